//! Method `taa` ([`AaMode::Taa`]): temporal anti-aliasing, one sample per
//! pixel on top of `none`'s frame. Each frame is drawn with its projection
//! shifted by a sub-pixel Halton (2, 3) offset (every pass: background,
//! G-buffer, lighting, transparent objects), the tonemap writes the
//! technique's own sRGB texture, and the resolve (`taa.frag`) blends it
//! with the history reprojected from the previous frame into the LDR image
//! and the next history. The history, the previous frame's view-projection
//! and the jitter index live here, so that a renderer given a new camera
//! each frame ([`Renderer::set_camera`](crate::renderer::Renderer::set_camera))
//! reprojects from the camera of the frame before.

pub(crate) mod options;
mod pass;

use super::contract::{FrameCamera, FrameParts, Setup, Technique, TechniqueState};
use crate::Error;
use crate::Result;
use crate::gl::Format;
use crate::gl::{GpuTimer, TextureRef, VertexArray};
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::targets::{ColorTarget, Targets};
use crate::renderer::timing::timed;
use glam::{DMat4, Mat4};
use options::TaaOptions;
use pass::{ResolveInputs, TaaPasses, TaaTargets, taa_bytes};
use std::any::Any;

/// Temporal anti-aliasing ([`AaMode::Taa`]), as
/// [`Renderer::technique`](crate::renderer::Renderer::technique) lends it:
/// its history and jitter state.
#[derive(Debug, Default)]
pub struct Taa {
    /// The options of the frames rendered.
    options: TaaOptions,
    /// The programs, built when the method is first used and kept.
    passes: Option<TaaPasses>,
    /// The histories and the frame the tonemap writes, allocated by the
    /// first frame after a change of options (they refer to the LDR image
    /// and the G-buffer's depth).
    targets: Option<TaaTargets>,
    /// The full-screen triangle of the reprojected-history view.
    fullscreen: Option<VertexArray>,
    /// Frames rendered since the last reset: the jitter index.
    frames: u64,
    /// This frame's unjittered view-projection and depth convention, once
    /// a frame has begun.
    current: Option<(DMat4, bool)>,
    /// The view-projection of the frame before, when there was one since
    /// the last reset and its history was written.
    previous: Option<DMat4>,
    /// Which history holds the last frame's result.
    latest: usize,
    /// Whether `history[latest]` holds a frame's result.
    has_history: bool,
    /// What the last resolve read: for [`Taa::read_reprojected`].
    last: Option<(usize, ResolveInputs)>,
}

impl TechniqueState for Taa {}
impl super::contract::sealed::Sealed for Taa {}

impl Taa {
    /// Frames rendered since the history was last reset (the next frame's
    /// jitter is [`TaaOptions::jitter`] of this).
    pub fn frames_since_reset(&self) -> u64 {
        self.frames
    }

    /// The sub-pixel offset, in pixels, the last frame was drawn with;
    /// `None` before the first.
    pub fn last_jitter(&self) -> Option<[f32; 2]> {
        self.frames
            .checked_sub(1)
            .map(|index| self.options.jitter(index))
    }

    /// What the last frame's resolve found of the history: the history as
    /// it read it, reprojected to the last frame's camera through the last
    /// frame's depth (Catmull-Rom filtered, before the neighbourhood clip
    /// and the blend), sRGB-encoded, row 0 at the top; alpha 255 where
    /// the pixel's surface was on screen in the previous frame, 0 where the
    /// history was reset (all 0 on the first frame after a reset). `None`
    /// before the first frame after
    /// [`Renderer::set_options`](crate::renderer::Renderer::set_options).
    pub fn read_reprojected(&self, gl: &glow::Context) -> Result<Option<image::RgbaImage>> {
        let (Some(passes), Some(targets), Some(vao), Some((from, inputs))) =
            (&self.passes, &self.targets, &self.fullscreen, &self.last)
        else {
            return Ok(None);
        };
        let (w, h) = (targets.depth.width, targets.depth.height);
        let scratch = ColorTarget::new(gl, "taa reprojected history", Format::Rgba8, w, h)?;
        let result = passes
            .draw(gl, vao, targets, *from, inputs, Some(&scratch))
            .and_then(|()| scratch.read_rgba8(gl, "the taa reprojected history"));
        scratch.destroy(gl);
        result.map(Some)
    }

    /// The history's texture as the last frame wrote it (`RGBA16F`,
    /// linear display values: the tonemapped image before its sRGB
    /// encoding); `None` before the first frame after a reset.
    pub fn history_texture(&self) -> Option<TextureRef> {
        let targets = self.targets.as_ref()?;
        self.has_history
            .then(|| TextureRef::from(&targets.history[self.latest]))
    }

    /// Forget the history: the next frame starts again from its own image
    /// and from the first jitter phase.
    fn reset(&mut self) {
        self.frames = 0;
        self.current = None;
        self.previous = None;
        self.has_history = false;
        self.last = None;
    }
}

impl Technique for Taa {
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        if let AaMode::Taa(options) = setup.options.aa {
            if options != self.options {
                self.options = options;
                self.reset();
            }
        }
        if self.passes.is_none() {
            self.passes = Some(TaaPasses::new(gl)?);
        }
        if self.fullscreen.is_none() {
            self.fullscreen = Some(VertexArray::new(gl, "taa reprojected view triangle")?);
        }
        if let (None, Some(frame)) = (&self.targets, frame) {
            let depth = TextureRef::from(&frame.gbuffer.depth);
            self.targets = Some(TaaTargets::new(gl, &frame.targets.ldr.texture, depth)?);
            self.reset();
        }
        Ok(())
    }

    /// The targets refer to the LDR image and the depth, which may have
    /// been re-allocated: they go, and the history with them.
    fn options_changed(&mut self, gl: &glow::Context, _active: bool) {
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
        self.reset();
    }

    fn reset_history(&mut self) {
        self.reset();
    }

    /// Record this frame's camera and shift its projection by this frame's
    /// jitter: a translation in clip space of `2 · offset / size` (times w),
    /// which moves the whole image by `offset` pixels.
    fn begin_frame(&mut self, camera: &FrameCamera<'_>) -> Mat4 {
        let view_projection = camera.projection.as_dmat4() * *camera.view;
        if let Some((before, _)) = self.current.take() {
            // The frame before wrote its history only when it ran to its resolve.
            self.previous = self.has_history.then_some(before);
        }
        self.current = Some((view_projection, camera.zero_to_one));
        let [jx, jy] = self.options.jitter(self.frames);
        self.frames += 1;
        let (w, h) = camera.size;
        let shift = Mat4::from_translation(glam::Vec3::new(
            2.0 * jx / w.max(1) as f32,
            2.0 * jy / h.max(1) as f32,
            0.0,
        ));
        shift * *camera.projection
    }

    /// Its own sRGB texture, which the resolve reads.
    fn tonemap_target<'a>(&'a self, targets: &'a Targets) -> &'a ColorTarget {
        self.targets.as_ref().map_or(&targets.ldr, |t| &t.current)
    }

    /// The resolve into the LDR image and the next history.
    fn post(
        &mut self,
        gl: &glow::Context,
        _targets: &Targets,
        fullscreen: &VertexArray,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        let (Some(passes), Some(targets), Some((current, zero_to_one))) =
            (&self.passes, &self.targets, self.current)
        else {
            return Err(Error::invalid(
                "taa: the resolve ran before its targets and the frame's camera were set",
            ));
        };
        let reproject = match (self.has_history, self.previous) {
            (true, Some(previous)) => Some(previous * current.inverse()),
            _ => None,
        };
        let camera_still = self
            .previous
            .is_some_and(|previous| previous.abs_diff_eq(current, 1e-12));
        let inputs = ResolveInputs {
            reproject: reproject
                .unwrap_or(DMat4::IDENTITY)
                .as_mat4()
                .to_cols_array(),
            has_history: reproject.is_some(),
            camera_still,
            zero_to_one,
            alpha: self.options.alpha,
        };
        let from = self.latest;
        let ms = timed(gl, timer, || {
            passes.draw(gl, fullscreen, targets, from, &inputs, None)
        })?;
        self.latest = 1 - from;
        self.has_history = true;
        self.last = Some((from, inputs));
        Ok(ms)
    }

    /// The two histories and the frame the resolve reads.
    fn memory(&self, options: &RenderOptions) -> u64 {
        taa_bytes(options.width, options.height)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, gl: &glow::Context) {
        if let Some(t) = self.targets {
            t.destroy(gl);
        }
        if let Some(p) = self.passes {
            p.destroy(gl);
        }
        if let Some(v) = self.fullscreen {
            v.destroy(gl);
        }
    }
}

/// What is known of `taa` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["taa"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        matches!(aa, AaMode::Taa(_))
    }

    fn parse(&self, _method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        let mut taa = TaaOptions::default();
        for option in options {
            match option.split_once('=') {
                Some(("alpha", v)) => {
                    taa.alpha = v.trim().parse::<f32>().map_err(|_| {
                        Error::invalid(format!("method `{spec}`: `alpha={v}` is not a number"))
                    })?;
                }
                Some(("phases", v)) => {
                    taa.phases = v.trim().parse::<u32>().map_err(|_| {
                        Error::invalid(format!(
                            "method `{spec}`: `phases={v}` is not a number of phases"
                        ))
                    })?;
                }
                _ => {
                    return Err(Error::invalid(format!(
                        "method `{spec}`: unknown option `:{option}` (taa takes :alpha=F and :phases=N)"
                    )));
                }
            }
        }
        taa.validate()
            .map_err(|e| Error::invalid(format!("method `{spec}`: {e}")))?;
        Ok(AaMode::Taa(taa))
    }

    fn options_help(&self) -> Option<&'static str> {
        Some("taa's :alpha=F (0 < F <= 1) and :phases=N (2..=256)")
    }

    fn warmup_frames(&self, aa: &AaMode) -> u32 {
        match aa {
            AaMode::Taa(o) => o.warmup_frames(),
            _ => 0,
        }
    }

    fn post_passes(&self) -> Vec<Pass> {
        vec![Pass::TaaResolve]
    }

    fn own_programs(&self) -> &'static [&'static str] {
        &["taa"]
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(Taa::default())
    }
}
