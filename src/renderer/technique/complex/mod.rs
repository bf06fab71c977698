//! Method `complex` ([`AaMode::Complex`]): per-sample lighting on complex
//! pixels only. The G-buffer pass also records coverage flags where the
//! context has `gl_SampleMaskIn` (`geometry_coverage.frag`), a detection
//! pass (`complex_mask.frag`) marks complex pixels in a stencil mask on the
//! HDR target, and stencil-masked passes of `lighting_per_sample.frag`
//! light simple pixels once, from sample 0, into the HDR target, and complex
//! pixels per sample, into radiance layers with the same stencil, which
//! `sample_average.frag` averages into the HDR target.

mod coverage;
mod mask;
mod targets;

use super::contract::{
    ComplexPixelsInput, FrameParts, GBufferTarget, GeometryStep, LightingStep, Setup, Technique,
    TechniqueState, resolve_twins,
};
use super::per_sample::{per_sample_inputs, prepare_lighting};
use crate::frame::Frame as ResolveFrame;
use crate::gl::{GpuTimer, TextureRef};
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::AaMode;
use crate::renderer::pass::lighting_per_sample::{
    PerSampleLightingPass, SampleRadiance, prepare_radiance,
};
use crate::renderer::pass::shared::{LightTarget, StencilSelect};
use crate::renderer::pass::slots::GBufferSlots;
use crate::retrofit::MsaaRetrofit;
use crate::{Error, Result};
use coverage::CoverageGeometryPass;
use glow::HasContext;
use mask::{ComplexMaskPass, MaskTarget};
use std::any::Any;
use targets::ComplexTargets;

/// Per-sample lighting on complex pixels only ([`AaMode::Complex`]), as
/// [`Renderer::technique`](crate::renderer::Renderer::technique) lends it:
/// the last frame's complex pixels.
#[derive(Debug, Default)]
pub struct Complex {
    /// The programs, built when the method is first used and kept.
    lighting: Option<PerSampleLightingPass>,
    mask: Option<ComplexMaskPass>,
    /// The coverage-recording model program, or why the context cannot
    /// record coverage, for the layout's slots and coverage slot.
    coverage: Option<CoverageState>,
    /// The stencil mask and coverage flags, allocated by the first frame
    /// after a change of options (they refer to the twins and the HDR target).
    targets: Option<ComplexTargets>,
    /// Each sample's radiance, with the stencil mask of `targets`.
    radiance: Option<SampleRadiance>,
    /// Pixels the last frame's per-sample pass lit (`GL_SAMPLES_PASSED`).
    lit_pixels: Option<u64>,
    /// The last frame's image size.
    size: (u32, u32),
}

impl TechniqueState for Complex {}
impl super::contract::sealed::Sealed for Complex {}

/// [`Complex::coverage`]: built for these slots and coverage slot.
#[derive(Debug)]
struct CoverageState {
    slots: GBufferSlots,
    coverage_slot: u32,
    pass: std::result::Result<CoverageGeometryPass, String>,
}

impl Complex {
    /// The coverage-recording model program, when the context has one.
    fn coverage(&self) -> Option<&CoverageGeometryPass> {
        self.coverage.as_ref().and_then(|c| c.pass.as_ref().ok())
    }

    /// How many pixels the last frame lit per sample (the complex ones);
    /// `None` before the first frame after a change of options or without
    /// a query object.
    pub(crate) fn lit_pixels(&self) -> Option<u64> {
        self.lit_pixels
    }

    /// The fraction of pixels marked complex (and lit per sample) in the
    /// last frame, counted with a `GL_SAMPLES_PASSED` query around the
    /// per-sample lighting pass, which the stencil mask limits to those
    /// pixels. `None` before the first frame after
    /// [`Renderer::set_options`](crate::renderer::Renderer::set_options), or
    /// where the context gave no query object.
    pub fn fraction(&self) -> Option<f32> {
        let pixels = f64::from(self.size.0) * f64::from(self.size.1);
        self.lit_pixels.map(|n| (n as f64 / pixels.max(1.0)) as f32)
    }

    /// The last frame's complex-pixel mask, read back from its stencil
    /// buffer (row 0 at the top; 255 = complex, lit per sample; 0 = simple,
    /// lit once). `None` before the first frame after
    /// [`Renderer::set_options`](crate::renderer::Renderer::set_options).
    pub fn read_mask(&self, gl: &glow::Context) -> Result<Option<image::GrayImage>> {
        self.targets.as_ref().map(|c| c.read_mask(gl)).transpose()
    }

    /// Build the coverage program and the mask program for `slots` and a
    /// coverage slot after the `colors` attachments. Without
    /// `gl_SampleMaskIn` complex pixels are found by the discontinuity test
    /// alone, said in a `log::warn!` line.
    fn prepare_programs(
        &mut self,
        gl: &glow::Context,
        slots: GBufferSlots,
        colors: u32,
    ) -> Result<()> {
        let current = self
            .coverage
            .as_ref()
            .is_some_and(|c| c.slots == slots && c.coverage_slot == colors);
        if !current {
            let pass = CoverageGeometryPass::new(gl, slots, colors);
            if let Err(reason) = &pass {
                log::warn!(
                    "method `complex`: no coverage mask ({reason}); complex pixels are found by the depth, normal and colour discontinuity test alone"
                );
            }
            let state = CoverageState {
                slots,
                coverage_slot: colors,
                pass,
            };
            if let Some(CoverageState { pass: Ok(old), .. }) = self.coverage.replace(state) {
                old.destroy(gl);
            }
        }
        let with_coverage = self.coverage().is_some();
        if self.mask.as_ref().map(ComplexMaskPass::uses_coverage) != Some(with_coverage) {
            let mask = ComplexMaskPass::new(gl, with_coverage)?;
            if let Some(old) = self.mask.replace(mask) {
                old.destroy(gl);
            }
        }
        Ok(())
    }

    /// Allocate the stencil mask (and coverage flags, when the context
    /// records coverage) unless they are there and match.
    fn prepare_targets(&mut self, gl: &glow::Context, frame: FrameParts<'_>) -> Result<()> {
        let coverage_slot = self.coverage().map(CoverageGeometryPass::coverage_slot);
        let current = self
            .targets
            .as_ref()
            .is_some_and(|c| c.coverage.is_some() == coverage_slot.is_some());
        let retrofit = frame.retrofit.ok_or_else(|| {
            Error::invalid("method `complex` needs the multisampled G-buffer, which is missing")
        })?;
        if !current {
            // The layers refer to the old stencil.
            if let Some(r) = self.radiance.take() {
                r.destroy(gl);
            }
            let targets = ComplexTargets::new(
                gl,
                &frame.targets.hdr.texture,
                coverage_slot.map(|slot| (retrofit, slot)),
            )?;
            if let Some(old) = self.targets.replace(targets) {
                old.destroy(gl);
            }
        }
        let stencil = self.targets.as_ref().map(|t| &t.stencil);
        prepare_radiance(
            &mut self.radiance,
            gl,
            &frame.targets.hdr.texture,
            retrofit.samples(),
            stencil,
        )
    }

    fn free_targets(&mut self, gl: &glow::Context) {
        if let Some(r) = self.radiance.take() {
            r.destroy(gl);
        }
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
    }
}

impl Technique for Complex {
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        if frame.is_some() {
            // A new frame: nothing is lit yet.
            self.lit_pixels = None;
        }
        prepare_lighting(&mut self.lighting, gl, setup.slots)?;
        self.prepare_programs(gl, setup.slots, setup.colors)?;
        match frame {
            Some(frame) => self.prepare_targets(gl, frame),
            None => Ok(()),
        }
    }

    fn options_changed(&mut self, gl: &glow::Context, _active: bool) {
        self.free_targets(gl);
        self.lit_pixels = None;
    }

    /// With coverage flags: the twins plus the flags.
    fn geometry_target(&self, frame: &FrameParts<'_>) -> GBufferTarget {
        let flags = match (self.coverage(), self.targets.as_ref()) {
            (Some(_), Some(t)) => t.coverage.as_ref(),
            _ => None,
        };
        match flags {
            Some(c) => GBufferTarget {
                fbo: c.fbo.raw(),
                draw_buffers: c.draw_buffers.clone(),
            },
            None => GBufferTarget::of_frame(frame),
        }
    }

    /// With coverage flags, the model shader wrapped to write them.
    fn draw_gbuffer(&self, gl: &glow::Context, step: &GeometryStep<'_>) -> Result<()> {
        step.copy_background(gl)?;
        let flags = self.targets.as_ref().and_then(|t| t.coverage.as_ref());
        match (self.coverage(), flags, step.frame.retrofit) {
            (Some(pass), Some(_), Some(r)) => step.draw_models(gl, pass.prepare(gl, r.samples())),
            _ => step.draw_models(gl, step.model),
        }
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
        let (Some(mask), Some(c), Some(radiance)) = (
            self.mask.as_ref(),
            self.targets.as_ref(),
            self.radiance.as_ref(),
        ) else {
            return Err(Error::invalid(
                "method `complex` has no mask pass, stencil target or per-sample radiance (not prepared)",
            ));
        };
        let (width, height) = step.size();
        self.size = (width, height);
        let mask_target = MaskTarget {
            fbo: c.hdr_with_stencil.raw(),
            width,
            height,
        };
        let flags = c.coverage.as_ref().map(|c| TextureRef::from(&c.texture));
        mask.draw(
            gl,
            mask_target,
            step.fullscreen,
            &inputs,
            flags,
            step.footprint,
        )?;
        let select = |value| LightTarget {
            fbo: c.hdr_with_stencil.raw(),
            width,
            height,
            stencil: StencilSelect::Equal(value),
        };
        // Simple pixels: once, from sample 0, as the one-sample lighting does.
        pass.light_samples(
            gl,
            select(mask::SIMPLE),
            step.fullscreen,
            &inputs,
            (0, 1),
            step.batches,
            step.clear_depth,
            step.stand_ins,
        )?;
        // Complex pixels: every sample, averaged.
        self.lit_pixels = pass.draw(
            gl,
            select(mask::COMPLEX),
            radiance,
            StencilSelect::Equal(mask::COMPLEX),
            step.fullscreen,
            &inputs,
            step.batches,
            step.clear_depth,
            true,
            step.stand_ins,
        )?;
        unsafe {
            gl.disable(glow::STENCIL_TEST);
            gl.stencil_mask(0xFF);
        }
        Ok(())
    }

    /// Its stencil mask.
    fn complex_pixels(
        &self,
        gl: &glow::Context,
        _input: ComplexPixelsInput<'_>,
    ) -> Result<Option<image::GrayImage>> {
        self.read_mask(gl)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(mut self: Box<Self>, gl: &glow::Context) {
        self.free_targets(gl);
        if let Some(p) = self.lighting {
            p.destroy(gl);
        }
        if let Some(p) = self.mask {
            p.destroy(gl);
        }
        if let Some(CoverageState { pass: Ok(p), .. }) = self.coverage {
            p.destroy(gl);
        }
    }
}

/// What is known of `complex` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["complex"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        *aa == AaMode::Complex
    }

    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        super::kind::no_options(method, options, spec)?;
        Ok(AaMode::Complex)
    }

    fn draws_into_twins(&self) -> bool {
        true
    }

    fn lights_per_sample(&self) -> bool {
        true
    }

    fn lighting_passes(&self, _aa: &AaMode) -> Vec<Pass> {
        vec![Pass::ComplexMask, Pass::PerSampleLighting]
    }

    fn geometry_program(&self) -> &'static str {
        "geometry (+ coverage where gl_SampleMaskIn exists)"
    }

    fn own_programs(&self) -> &'static [&'static str] {
        &["complex-mask"]
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(Complex::default())
    }
}
