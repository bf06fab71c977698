//! Method `per-sample` ([`AaMode::PerSample`]): the G-buffer is resolved
//! for the decal hook and transparent objects, but lighting reads every
//! sample of the multisampled twins into a radiance layer of its own
//! (`lighting_per_sample.frag`) and averages the samples as the tonemap
//! will see them (`sample_average.frag`).

use super::contract::{
    ComplexPixelsInput, FrameParts, LightingStep, Setup, Technique, resolve_twins,
};
use crate::frame::Frame as ResolveFrame;
use crate::gl::GpuTimer;
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::AaMode;
use crate::renderer::pass::lighting_per_sample::{
    PerSampleLightingPass, SampleInputs, SampleRadiance, prepare_radiance,
};
use crate::renderer::pass::shared::{LightTarget, StencilSelect};
use crate::renderer::pass::slots::GBufferSlots;
use crate::retrofit::MsaaRetrofit;
use crate::{Error, Result};
use std::any::Any;

/// Per-sample lighting of every pixel.
#[derive(Debug, Default)]
pub(crate) struct PerSample {
    /// Built when the method is first used, and kept.
    lighting: Option<PerSampleLightingPass>,
    /// Each sample's radiance, allocated by the first frame after a change
    /// of options.
    radiance: Option<SampleRadiance>,
    /// Pixels the last frame's lighting pass lit (`GL_SAMPLES_PASSED`).
    lit_pixels: Option<u64>,
}

impl PerSample {
    /// How many pixels the last frame's per-sample lighting lit; `None`
    /// before the first frame after a change of options or without a
    /// query object.
    pub(crate) fn lit_pixels(&self) -> Option<u64> {
        self.lit_pixels
    }
}

/// Build (or, when the attachment numbers moved, rebuild) the per-sample
/// lighting program in `slot`.
pub(super) fn prepare_lighting(
    slot: &mut Option<PerSampleLightingPass>,
    gl: &glow::Context,
    slots: GBufferSlots,
) -> Result<()> {
    if slot.as_ref().map(PerSampleLightingPass::slots) != Some(slots) {
        let pass = PerSampleLightingPass::new(gl, slots)?;
        if let Some(old) = slot.replace(pass) {
            old.destroy(gl);
        }
    }
    Ok(())
}

/// The per-sample lighting program and the twins it reads.
pub(super) fn per_sample_inputs<'a>(
    lighting: Option<&'a PerSampleLightingPass>,
    frame: &FrameParts<'_>,
    slots: GBufferSlots,
) -> Result<(&'a PerSampleLightingPass, SampleInputs)> {
    let pass = lighting.ok_or_else(|| {
        Error::invalid("the per-sample lighting program is missing (not prepared)")
    })?;
    let retrofit = frame.retrofit.ok_or_else(|| {
        Error::invalid("per-sample lighting needs the multisampled G-buffer, which is missing")
    })?;
    Ok((pass, SampleInputs::of(retrofit, slots)?))
}

impl Technique for PerSample {
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        prepare_lighting(&mut self.lighting, gl, setup.slots)?;
        if let Some(frame) = frame {
            // A new frame: nothing is lit yet.
            self.lit_pixels = None;
            let samples = frame.retrofit.map_or(1, MsaaRetrofit::samples);
            prepare_radiance(
                &mut self.radiance,
                gl,
                &frame.targets.hdr.texture,
                samples,
                None,
            )?;
        }
        Ok(())
    }

    fn options_changed(&mut self, gl: &glow::Context, _active: bool) {
        if let Some(r) = self.radiance.take() {
            r.destroy(gl);
        }
        self.lit_pixels = None;
    }

    /// The resolved G-buffer serves the decal hook and transparent objects.
    fn after_geometry(
        &self,
        gl: &glow::Context,
        retrofit: Option<&mut MsaaRetrofit>,
        resolve_frame: &ResolveFrame,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        resolve_twins(gl, retrofit, resolve_frame, timer)
    }

    fn light(&mut self, gl: &glow::Context, step: &LightingStep<'_>) -> Result<()> {
        let (pass, inputs) = per_sample_inputs(self.lighting.as_ref(), &step.frame, step.slots)?;
        let radiance = self.radiance.as_ref().ok_or_else(|| {
            Error::invalid("method `per-sample` has no per-sample radiance (not prepared)")
        })?;
        let (width, height) = step.size();
        let hdr = LightTarget {
            fbo: step.frame.targets.hdr.fbo.raw(),
            width,
            height,
            stencil: StencilSelect::All,
        };
        self.lit_pixels = pass.draw(
            gl,
            hdr,
            radiance,
            StencilSelect::All,
            step.fullscreen,
            &inputs,
            step.batches,
            step.clear_depth,
            true,
            step.stand_ins,
        )?;
        Ok(())
    }

    /// Every pixel: each is lit per sample.
    fn complex_pixels(
        &self,
        _gl: &glow::Context,
        input: ComplexPixelsInput<'_>,
    ) -> Result<Option<image::GrayImage>> {
        Ok(Some(image::GrayImage::from_pixel(
            input.width,
            input.height,
            image::Luma([255]),
        )))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, gl: &glow::Context) {
        if let Some(p) = self.lighting {
            p.destroy(gl);
        }
        if let Some(r) = self.radiance {
            r.destroy(gl);
        }
    }
}

/// What is known of `per-sample` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["per-sample"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        *aa == AaMode::PerSample
    }

    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        super::kind::no_options(method, options, spec)?;
        Ok(AaMode::PerSample)
    }

    fn draws_into_twins(&self) -> bool {
        true
    }

    fn lights_per_sample(&self) -> bool {
        true
    }

    fn lighting_passes(&self, _aa: &AaMode) -> Vec<Pass> {
        vec![Pass::PerSampleLighting]
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(PerSample::default())
    }
}
