//! The resolve pass of method `taa` (`taa.frag`): temporal anti-aliasing,
//! [`AaMode::Taa`](crate::renderer::AaMode::Taa), with its targets. Its
//! options and jitter sequence are in [`options`](super::options); the
//! technique that drives it frame by frame is [`Taa`](super::Taa).

use crate::Result;
use crate::gl::{
    Attachment, Format, Framebuffer, FullscreenPass, GlObject, Handle, Made, Program, ShaderSource,
    Texture2d, TextureRef, VertexArray, check_error,
};
use crate::renderer::pass::shared::draw_fullscreen;
use crate::renderer::pass::tonemap::TONEMAP_FRAG;
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The pass's body.
pub(crate) const TAA_FRAG: &str = include_str!("taa.frag");

/// Format of the history: linear display values, which an 8-bit target
/// would quantise out of the blend (a step of 1/255 times the blend factor
/// rounds to nothing).
pub(crate) const HISTORY_FORMAT: Format = Format::Rgba16f;
/// Format of the frame the tonemap writes for the pass: sRGB-encoded, so
/// that fetches decode to linear display values.
pub(crate) const CURRENT_FORMAT: Format = Format::Srgb8Alpha8;

/// The half-size of the variance clipping box, in standard deviations of
/// the neighbourhood (Salvi's variance clipping; 1 is the usual choice).
pub(crate) const GAMMA: f32 = 1.0;

/// The least weight of this frame while the camera is still, as a share
/// of `alpha` (0.015 at the default 0.1): a still camera averages many
/// jitter phases, a running mean until it holds that many.
pub(crate) const STILL_ALPHA_SHARE: f32 = 0.15;

/// The bytes `taa` allocates beside the G-buffer at `width`×`height`: two
/// histories and the tonemapped frame it reads.
pub(crate) fn taa_bytes(width: u32, height: u32) -> u64 {
    u64::from(2 * HISTORY_FORMAT.bytes_per_texel() + CURRENT_FORMAT.bytes_per_texel())
        * u64::from(width)
        * u64::from(height)
}

/// What one resolve reads besides its targets.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ResolveInputs {
    /// This frame's unjittered NDC to the previous frame's clip space.
    pub(crate) reproject: [f32; 16],
    /// Whether a history exists (not the first frame after a reset).
    pub(crate) has_history: bool,
    /// Whether the camera (its unjittered view-projection) is the last
    /// frame's: nothing was uncovered, and the history is not clipped.
    pub(crate) camera_still: bool,
    /// Whether NDC z is the depth value itself (reversed-Z's clip control).
    pub(crate) zero_to_one: bool,
    /// The weight of this frame.
    pub(crate) alpha: f32,
}

/// The two programs: the resolve, and the reprojected history alone.
#[derive(Debug)]
pub(crate) struct TaaPasses {
    resolve: Program,
    reprojected: Program,
}

impl TaaPasses {
    /// Build both programs.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            let resolve = made.keep(Self::program(gl, false)?);
            let reprojected = made.keep(Self::program(gl, true)?);
            Ok(TaaPasses {
                resolve,
                reprojected,
            })
        })
    }

    /// `tonemap.frag`'s functions (for `srgb_encode`), then `taa.frag`.
    fn program(gl: &glow::Context, reprojected: bool) -> Result<Program> {
        let mut defines = vec![("TONEMAP_FUNCTIONS_ONLY".to_string(), "1".to_string())];
        if reprojected {
            defines.push(("TAA_REPROJECTED".into(), "1".into()));
        }
        let fragment = ShaderSource::new()
            .defines(&defines)
            .part("tonemap.frag", TONEMAP_FRAG)
            .part("taa.frag", TAA_FRAG);
        let (label, outputs): (&str, &[(&str, u32)]) = if reprojected {
            ("taa reprojected history", &[("o_color", 0)])
        } else {
            ("taa", &[("o_color", 0), ("o_history", 1)])
        };
        Ok(FullscreenPass::new(gl, label, &fragment, outputs)?.into_program())
    }

    /// Resolve: read `targets.current` and history `from`, write the LDR
    /// image and history `1 − from` (through `targets.fbos[1 − from]`);
    /// with `reprojected_into`, draw the reprojected history of `from`
    /// alone into that target instead.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        vao: &VertexArray,
        targets: &TaaTargets,
        from: usize,
        inputs: &ResolveInputs,
        reprojected_into: Option<&ColorTarget>,
    ) -> Result<()> {
        let (program, size) = match reprojected_into {
            Some(out) => {
                out.begin_fullscreen(gl);
                (&self.reprojected, (out.texture.width, out.texture.height))
            }
            None => {
                let fbo = &targets.fbos[1 - from];
                crate::renderer::pass::shared::begin_fullscreen(
                    gl,
                    fbo.raw(),
                    fbo.width,
                    fbo.height,
                );
                (&self.resolve, (fbo.width, fbo.height))
            }
        };
        debug_assert_eq!(size, (targets.depth.width, targets.depth.height));
        TextureRef::from(&targets.current.texture).bind(gl, 0);
        TextureRef::from(&targets.history[from]).bind(gl, 1);
        targets.depth.bind(gl, 2);
        let p = program;
        p.bind(gl);
        p.set_i32(gl, "u_current", 0);
        p.set_i32(gl, "u_history", 1);
        p.set_i32(gl, "u_depth", 2);
        p.set_mat4(gl, "u_reproject", &inputs.reproject);
        p.set_i32(gl, "u_has_history", i32::from(inputs.has_history));
        p.set_i32(gl, "u_zero_to_one", i32::from(inputs.zero_to_one));
        p.set_f32(gl, "u_alpha", inputs.alpha);
        p.set_f32(gl, "u_gamma", GAMMA);
        p.set_f32(gl, "u_alpha_still", inputs.alpha * STILL_ALPHA_SHARE);
        p.set_i32(gl, "u_camera_still", i32::from(inputs.camera_still));
        draw_fullscreen(gl, vao);
        unsafe { gl.active_texture(glow::TEXTURE0) };
        Ok(check_error(gl, "the taa resolve")?)
    }

    /// Free the programs.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.resolve.destroy(gl);
        self.reprojected.destroy(gl);
    }
}

impl GlObject for TaaPasses {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.resolve.handles(out);
        self.reprojected.handles(out);
    }
}

/// The size-dependent targets of `taa`.
#[derive(Debug)]
pub(crate) struct TaaTargets {
    /// The tonemapped frame ([`CURRENT_FORMAT`]), which the tonemap writes
    /// and the resolve reads.
    pub(crate) current: ColorTarget,
    /// The two histories ([`HISTORY_FORMAT`]): one is read while the other
    /// is written, and they swap every frame.
    pub(crate) history: [Texture2d; 2],
    /// `fbos[k]`: the renderer's LDR image at colour attachment 0 and
    /// `history[k]` at 1.
    pub(crate) fbos: [Framebuffer; 2],
    /// The G-buffer's depth texture (not owned).
    pub(crate) depth: TextureRef,
}

impl TaaTargets {
    /// Allocate for the LDR image `ldr` and the G-buffer depth `depth`
    /// (their size; neither is owned).
    pub(crate) fn new(gl: &glow::Context, ldr: &Texture2d, depth: TextureRef) -> Result<Self> {
        let (w, h) = (ldr.width, ldr.height);
        Made::build(gl, |made| {
            let current = made.keep(ColorTarget::new(gl, "taa frame", CURRENT_FORMAT, w, h)?);
            let history = [
                made.keep(Texture2d::new(gl, "taa history 0", HISTORY_FORMAT, w, h)?),
                made.keep(Texture2d::new(gl, "taa history 1", HISTORY_FORMAT, w, h)?),
            ];
            let fbo = |k: usize| {
                Framebuffer::new(
                    gl,
                    &format!("ldr with taa history {k}"),
                    &[
                        (Attachment::Color(0), TextureRef::from(ldr)),
                        (Attachment::Color(1), TextureRef::from(&history[k])),
                    ],
                    &[Some(0), Some(1)],
                )
            };
            let fbos = [made.keep(fbo(0)?), made.keep(fbo(1)?)];
            Ok(TaaTargets {
                current,
                history,
                fbos,
                depth,
            })
        })
    }

    /// Free what it owns (not the LDR image nor the depth).
    pub(crate) fn destroy(self, gl: &glow::Context) {
        let [f0, f1] = self.fbos;
        f0.destroy(gl);
        f1.destroy(gl);
        let [h0, h1] = self.history;
        h0.destroy(gl);
        h1.destroy(gl);
        self.current.destroy(gl);
    }
}

impl GlObject for TaaTargets {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.current.handles(out);
        for h in &self.history {
            h.handles(out);
        }
        for f in &self.fbos {
            f.handles(out);
        }
    }
}
