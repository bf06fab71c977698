//! The check that the host cleared the multisampled twins in each frame.
//!
//! A host that clears its G-buffer through another framebuffer (one that
//! shares its textures, `glClearBuffer*` per attachment) clears its own
//! single-sample textures, never the twins: its geometry pass then draws
//! against last frame's depth, or a fresh twin's, and the lit frame is
//! black or stale while every call returns OK. So, where the host declared
//! no clear values ([`RetrofitOptions::twin_clear`](crate::RetrofitOptions::twin_clear)),
//! `begin_frame` clears the twins' depth to a sentinel no host clears to
//! and no screen-facing geometry lands on, and `resolve` counts, with a
//! `GL_SAMPLES_PASSED` query around a pass of its own over every fourth
//! pixel in x and y, the pixels whose depth still holds it. A frame in which more than
//! [`UNCLEARED_FRACTION`] of the pixels do was not cleared after
//! `begin_frame`, and is not resolved. The first check waits for its
//! count, so a host set up wrongly hears of it on its first frame; after a
//! cleared frame, counts are read at the next `resolve`, so that no frame
//! stalls on the GPU (a host that stops clearing then hears of it a frame
//! late, and of every frame after at once, until one is cleared).

use crate::gl::{
    Format, Framebuffer, FullscreenPass, GlObject, Handle, Made, SamplesPassedQuery, SavedState,
    ShaderSource, Texture2dMultisample, VertexArray,
};
use crate::{Error, Result};
use glow::HasContext;

/// The pass's fragment shader.
const CLEAR_CHECK_FRAG: &str = include_str!("clear_check.frag");

/// The depth `begin_frame` clears the twins to: 0x5EA1C3 / (2^24 - 1),
/// exact in 24-bit depth, far from the values hosts clear to (0, 1) and
/// from round ones a flat plane would sit at.
pub(crate) const SENTINEL_DEPTH: f32 = 6_201_795.0 / 16_777_215.0;

/// The check reads every `STEP`-th pixel in x and y (a 1/16 sample of the
/// frame): the share it judges is a share of the frame, not a few pixels.
const STEP: u32 = 4;

/// The share of a frame's pixels still at the sentinel above which the
/// frame was not cleared: geometry that happens to land on the sentinel
/// covers a line of pixels, not a part of the screen like this.
pub(crate) const UNCLEARED_FRACTION: u64 = 32;

/// Half a step of `format`'s depth: the sentinel reads back within it.
fn tolerance(format: Format) -> f32 {
    let p = format.properties();
    match p.component {
        crate::gl::format::ComponentType::Unorm if p.depth_bits < 24 => {
            0.5 / ((1u64 << p.depth_bits) - 1) as f32
        }
        _ => 1.0 / 16_777_216.0,
    }
}

/// The check's pass and query.
#[derive(Debug)]
pub(crate) struct ClearCheck {
    pass: FullscreenPass,
    vao: VertexArray,
    query: SamplesPassedQuery,
    /// A count issued and not read yet.
    pending: bool,
    /// A count was read once: from then on counts are not waited for.
    waited: bool,
}

impl GlObject for ClearCheck {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.pass.handles(out);
        self.vao.handles(out);
        self.query.handles(out);
    }
}

impl ClearCheck {
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            let pass = made.keep(FullscreenPass::new(
                gl,
                "uncleared-twin check",
                &ShaderSource::new().part("clear_check.frag", CLEAR_CHECK_FRAG),
                &[],
            )?);
            let vao = made.keep(VertexArray::new(gl, "uncleared-twin check triangle")?);
            let query = made.keep(SamplesPassedQuery::new(gl)?);
            Ok(ClearCheck {
                pass,
                vao,
                query,
                pending: false,
                waited: false,
            })
        })
    }

    /// A new set of twins: the next check waits for its count again.
    pub(crate) fn reset(&mut self) {
        self.pending = false;
        self.waited = false;
    }

    /// Check the last frame's count if one is pending, then count this
    /// frame's pixels of `depth` at the sentinel, drawing into `target`
    /// (the resolve's, the twins' size) with every write off. The count is
    /// judged now on the first frame, else at the next call.
    pub(crate) fn check(
        &mut self,
        gl: &glow::Context,
        depth: &Texture2dMultisample,
        target: &Framebuffer,
    ) -> Result<()> {
        let (w, h) = (target.width.div_ceil(STEP), target.height.div_ceil(STEP));
        let total = u64::from(w) * u64::from(h);
        if self.pending {
            self.pending = false;
            if let Err(e) = judge(self.query.result(gl), total, true) {
                // A host that stopped clearing: its next frames are judged
                // at once again, until one is cleared.
                self.waited = false;
                return Err(e);
            }
        }
        self.query.begin(gl);
        // The crate's calls leave no error behind them, so one here is the
        // query's: the host has an occlusion query of its own active.
        if unsafe { gl.get_error() } != glow::NO_ERROR {
            log::warn!(
                "an occlusion query of the host's is active during resolve: this frame's check that the twins were cleared is skipped"
            );
            return Ok(());
        }
        {
            let state = SavedState::capture(gl, 1).guard(gl);
            let program = self.pass.begin(gl, target);
            unsafe {
                gl.viewport(0, 0, w as i32, h as i32);
                gl.depth_mask(false);
                gl.color_mask(false, false, false, false);
                gl.active_texture(glow::TEXTURE0);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(depth.raw()));
            }
            program.set_i32(gl, "u_depth", 0);
            program.set_f32(gl, "u_sentinel", SENTINEL_DEPTH);
            program.set_f32(gl, "u_tolerance", tolerance(depth.format));
            program.set_i32(gl, "u_step", STEP as i32);
            self.pass.draw(gl, &self.vao);
            drop(state);
        }
        self.query.end(gl);
        if self.waited {
            self.pending = true;
            return Ok(());
        }
        let result = judge(self.query.result(gl), total, false);
        self.waited = result.is_ok();
        result
    }
}

/// The error for a frame with `left` of `total` pixels at the sentinel.
fn judge(left: u64, total: u64, last_frame: bool) -> Result<()> {
    if left * UNCLEARED_FRACTION <= total {
        return Ok(());
    }
    Err(Error::TwinsNotCleared {
        pixels: left,
        total,
        last_frame,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sentinel_is_exact_in_24_bit_depth_and_far_from_hosts_clears() {
        let step = SENTINEL_DEPTH * 16_777_215.0;
        assert!((step - step.round()).abs() < 0.01, "{step}");
        const { assert!(SENTINEL_DEPTH > 0.1 && SENTINEL_DEPTH < 0.9) };
        // Sixteen-bit depth stores it within the tolerance it is read with.
        let d16 = (SENTINEL_DEPTH * 65_535.0).round() / 65_535.0;
        assert!((d16 - SENTINEL_DEPTH).abs() <= tolerance(Format::Depth16));
        assert!(tolerance(Format::Depth24Stencil8) < 1e-7);
    }

    #[test]
    fn a_frame_is_uncleared_only_past_its_share_of_pixels() {
        assert!(judge(0, 1000, false).is_ok());
        assert!(judge(1000 / UNCLEARED_FRACTION, 1000, false).is_ok());
        let err = judge(900, 1000, true).unwrap_err().to_string();
        assert!(err.contains("900 of 1000"), "{err}");
        assert!(err.contains("twin_clear"), "{err}");
    }
}
