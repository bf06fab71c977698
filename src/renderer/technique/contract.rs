//! What passes between the renderer's frame and a technique: the
//! [`Technique`] trait and the steps of the frame it is handed.

use crate::Result;
use crate::frame::Frame as ResolveFrame;
use crate::gbuffer::GBuffer;
use crate::gl::{GpuTimer, Texture2d, VertexArray};
use crate::renderer::mesh::GpuScene;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::pass::background_copy::{BackgroundCopyPass, CopyTarget};
use crate::renderer::pass::geometry::{GeometryPass, GeometryTarget};
use crate::renderer::pass::lighting::{LightBatch, LightingPass, StandIns};
use crate::renderer::pass::shared::{LightTarget, StencilSelect};
use crate::renderer::pass::slots::GBufferSlots;
use crate::renderer::targets::{ColorTarget, Targets};
use crate::renderer::timing::timed;
use crate::retrofit::MsaaRetrofit;
use glam::{DMat4, Mat4};
use std::any::Any;

/// A technique whose state [`Renderer::technique`](crate::renderer::Renderer::technique)
/// lends out: [`Gbaa`](super::Gbaa), [`Complex`](super::Complex), [`Sparse`](super::Sparse) or [`Taa`](super::Taa).
pub trait TechniqueState: std::any::Any + sealed::Sealed {}

pub(crate) mod sealed {
    /// Only this crate's techniques are [`TechniqueState`](super::TechniqueState)s:
    /// each implements it beside its `TechniqueState`.
    pub trait Sealed {}
}

/// The camera of the frame about to be rendered, as
/// [`Technique::begin_frame`] sees it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameCamera<'a> {
    /// The camera's view.
    pub(crate) view: &'a DMat4,
    /// The projection in the frame's depth mode, unjittered.
    pub(crate) projection: &'a Mat4,
    /// The image size.
    pub(crate) size: (u32, u32),
    /// Whether clip-space z maps to depth 0..1 as it is (reversed-Z's
    /// clip control) rather than from −1..1.
    pub(crate) zero_to_one: bool,
}

/// What a technique builds against.
#[derive(Clone, Copy)]
pub(crate) struct Setup<'a> {
    /// The options the frame runs with (the plan applied).
    pub(crate) options: &'a RenderOptions,
    /// The attachment numbers of the G-buffer.
    pub(crate) slots: GBufferSlots,
    /// The G-buffer's colour attachments; a technique's own outputs take
    /// the next draw buffers.
    pub(crate) colors: u32,
}

/// The frame's size- and layout-dependent objects, lent to a technique.
#[derive(Clone, Copy)]
pub(crate) struct FrameParts<'a> {
    /// The method the frame runs, with its options.
    pub(crate) aa: AaMode,
    /// The host's single-sample G-buffer.
    pub(crate) gbuffer: &'a GBuffer,
    /// The retrofit, for the methods with multisampled twins.
    pub(crate) retrofit: Option<&'a MsaaRetrofit>,
    /// The background, HDR and LDR targets.
    pub(crate) targets: &'a Targets,
}

/// The framebuffer the G-buffer pass draws into and its draw buffers.
#[derive(Clone, Debug)]
pub(crate) struct GBufferTarget {
    /// The framebuffer.
    pub(crate) fbo: glow::Framebuffer,
    /// Its draw buffers (the background copy writes the emissive one).
    pub(crate) draw_buffers: Vec<Option<u32>>,
}

impl GBufferTarget {
    /// The retrofit's multisampled twin when there is one (the first of the
    /// two integration lines), else the G-buffer itself.
    pub(crate) fn of_frame(frame: &FrameParts<'_>) -> Self {
        match frame.retrofit {
            Some(r) => GBufferTarget {
                fbo: r.framebuffer(),
                draw_buffers: r.host().draw_buffers.clone(),
            },
            None => GBufferTarget {
                fbo: frame.gbuffer.fbo.raw(),
                draw_buffers: (0..frame.gbuffer.colors.len() as u32).map(Some).collect(),
            },
        }
    }
}

/// The G-buffer pass's inputs, after the clear and the background.
pub(crate) struct GeometryStep<'a> {
    /// Where it draws.
    pub(crate) target: GeometryTarget,
    /// The draw buffers of `target`.
    pub(crate) draw_buffers: &'a [Option<u32>],
    /// The frame's objects.
    pub(crate) frame: FrameParts<'a>,
    /// The model program of the layout.
    pub(crate) model: &'a GeometryPass,
    /// The pass that copies the background into every sample.
    pub(crate) background_copy: &'a BackgroundCopyPass,
    /// The full-screen vertex array.
    pub(crate) fullscreen: &'a VertexArray,
    /// The layout's attachment numbers.
    pub(crate) slots: GBufferSlots,
    /// The scene's meshes.
    pub(crate) scene: &'a GpuScene,
    /// The camera's view.
    pub(crate) view: &'a DMat4,
    /// The projection in the frame's depth mode.
    pub(crate) projection: &'a Mat4,
    /// The depth function that lets the nearer fragment pass.
    pub(crate) nearer_func: u32,
    /// The depth the G-buffer is cleared to.
    pub(crate) clear_depth: f32,
}

impl GeometryStep<'_> {
    /// Copy the background into the target's emissive attachment. Without
    /// one the lighting pass reads the background texture itself.
    pub(crate) fn copy_background(&self, gl: &glow::Context) -> Result<()> {
        let Some(emissive) = self.slots.emissive else {
            return Ok(());
        };
        let copy = CopyTarget {
            fbo: self.target.fbo,
            width: self.target.width,
            height: self.target.height,
            emissive,
            draw_buffers: self.draw_buffers,
        };
        self.background_copy.draw(
            gl,
            copy,
            self.fullscreen,
            &self.frame.targets.background.texture,
        )
    }

    /// Draw the scene's opaque and alpha-tested objects with `model`.
    pub(crate) fn draw_models(&self, gl: &glow::Context, model: &GeometryPass) -> Result<()> {
        model.draw(
            gl,
            self.target,
            self.scene,
            self.view,
            self.projection,
            self.nearer_func,
        )
    }
}

/// The lighting step's inputs.
pub(crate) struct LightingStep<'a> {
    /// The frame's objects (the HDR target is `frame.targets.hdr`).
    pub(crate) frame: FrameParts<'a>,
    /// The per-pixel lighting program of the layout.
    pub(crate) lighting: &'a LightingPass,
    /// The full-screen vertex array.
    pub(crate) fullscreen: &'a VertexArray,
    /// The layout's attachment numbers.
    pub(crate) slots: GBufferSlots,
    /// The scene's lights in view space.
    pub(crate) batches: &'a [LightBatch],
    /// The depth background pixels keep.
    pub(crate) clear_depth: f32,
    /// What stands in for attachments the plan left out.
    pub(crate) stand_ins: StandIns<'a>,
    /// The projection in the frame's depth mode.
    pub(crate) projection: &'a Mat4,
    /// The size of a pixel at unit distance (`tan(fov_y / height)`).
    pub(crate) footprint: f32,
}

impl LightingStep<'_> {
    /// Light every pixel once from the resolved G-buffer.
    pub(crate) fn light_per_pixel(&self, gl: &glow::Context) -> Result<()> {
        let hdr = &self.frame.targets.hdr;
        self.light_per_pixel_into(
            gl,
            LightTarget {
                fbo: hdr.fbo.raw(),
                width: hdr.texture.width,
                height: hdr.texture.height,
                stencil: StencilSelect::All,
            },
        )
    }

    /// [`LightingStep::light_per_pixel`] into `target` (the HDR texture,
    /// perhaps with a stencil mask).
    pub(crate) fn light_per_pixel_into(
        &self,
        gl: &glow::Context,
        target: LightTarget,
    ) -> Result<()> {
        self.lighting.draw(
            gl,
            target,
            self.fullscreen,
            self.frame.gbuffer,
            self.slots,
            self.batches,
            self.clear_depth,
            self.stand_ins,
        )
    }

    /// The image size.
    pub(crate) fn size(&self) -> (u32, u32) {
        let hdr = &self.frame.targets.hdr.texture;
        (hdr.width, hdr.height)
    }

    /// The background's own texture.
    pub(crate) fn background(&self) -> &Texture2d {
        &self.frame.targets.background.texture
    }
}

/// What [`Technique::complex_pixels`] may read.
pub(crate) struct ComplexPixelsInput<'a> {
    /// The retrofit, for the methods with multisampled twins.
    pub(crate) retrofit: Option<&'a mut MsaaRetrofit>,
    /// The last frame's resolve input.
    pub(crate) resolve_frame: ResolveFrame,
    /// The image size.
    pub(crate) width: u32,
    /// The image size.
    pub(crate) height: u32,
}

/// One anti-aliasing technique: the steps of the renderer's frame that
/// differ by method. Programs are built by the first
/// [`prepare`](Technique::prepare) that needs them and kept; targets that
/// refer to the frame's are dropped by [`options_changed`](Technique::options_changed).
pub(crate) trait Technique: std::fmt::Debug {
    /// Build what a frame with `setup` needs: programs (and targets of its
    /// own) always; targets that refer to the frame's objects when `frame`
    /// is given (it is not while options are being changed).
    fn prepare(
        &mut self,
        _gl: &glow::Context,
        _setup: &Setup<'_>,
        _frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        Ok(())
    }

    /// The options changed: free what refers to the old frame's objects;
    /// `active`: whether this technique renders the new options.
    fn options_changed(&mut self, _gl: &glow::Context, _active: bool) {}

    /// The frame begins with `camera`: the projection every pass of the
    /// frame draws with (`camera.projection` unless the technique jitters
    /// it). Called once per frame rendered, after [`Technique::prepare`].
    fn begin_frame(&mut self, camera: &FrameCamera<'_>) -> Mat4 {
        *camera.projection
    }

    /// Forget what earlier frames left behind (a temporal history), so
    /// that the next frame starts afresh.
    fn reset_history(&mut self) {}

    /// Where the G-buffer pass draws.
    fn geometry_target(&self, frame: &FrameParts<'_>) -> GBufferTarget {
        GBufferTarget::of_frame(frame)
    }

    /// Clear the technique's own G-buffer outputs, after the G-buffer's
    /// clear (which zeroes every draw buffer).
    fn clear_outputs(&self, _gl: &glow::Context) {}

    /// The G-buffer pass, after the clear and the background: the
    /// background copy, then the model program.
    fn draw_gbuffer(&self, gl: &glow::Context, step: &GeometryStep<'_>) -> Result<()> {
        step.copy_background(gl)?;
        step.draw_models(gl, step.model)
    }

    /// What runs between the G-buffer pass and the decal hook, timed; the
    /// milliseconds it took (0 when nothing runs, untimed).
    fn after_geometry(
        &self,
        _gl: &glow::Context,
        _retrofit: Option<&mut MsaaRetrofit>,
        _resolve_frame: &ResolveFrame,
        _timer: &mut GpuTimer,
    ) -> Result<f64> {
        Ok(0.0)
    }

    /// Light the HDR target (the renderer times it).
    fn light(&mut self, gl: &glow::Context, step: &LightingStep<'_>) -> Result<()> {
        step.light_per_pixel(gl)
    }

    /// After [`Technique::light`]: the resolve's second layer, lit by the
    /// same pass and mixed in, timed; the milliseconds it took (0 when
    /// there is none, untimed).
    fn second_lighting(
        &mut self,
        _gl: &glow::Context,
        _retrofit: Option<&mut MsaaRetrofit>,
        _step: &LightingStep<'_>,
        _timer: &mut GpuTimer,
    ) -> Result<f64> {
        Ok(0.0)
    }

    /// Where the tonemap writes: the LDR image unless a post pass follows.
    fn tonemap_target<'a>(&'a self, targets: &'a Targets) -> &'a ColorTarget {
        &targets.ldr
    }

    /// The pass after the tonemap and before FXAA, timed; the milliseconds
    /// it took (0 when there is none, untimed).
    fn post(
        &mut self,
        _gl: &glow::Context,
        _targets: &Targets,
        _fullscreen: &VertexArray,
        _timer: &mut GpuTimer,
    ) -> Result<f64> {
        Ok(0.0)
    }

    /// The bytes the technique allocates beside the G-buffer and its twins
    /// for `options`.
    fn memory(&self, _options: &RenderOptions) -> u64 {
        0
    }

    /// The real samples per pixel of the technique's own multisampled
    /// targets, when it has any (the twins' count is the retrofit's).
    fn samples(&self) -> Option<u32> {
        None
    }

    /// Which pixels the last frame treated as complex (255) or simple (0),
    /// row 0 at the top; `None` when the technique has no such notion.
    fn complex_pixels(
        &self,
        _gl: &glow::Context,
        _input: ComplexPixelsInput<'_>,
    ) -> Result<Option<image::GrayImage>> {
        Ok(None)
    }

    /// For [`Techniques::get`].
    fn as_any(&self) -> &dyn Any;

    /// Free every GL object the technique made.
    fn destroy(self: Box<Self>, gl: &glow::Context);
}

/// The resolve of the multisampled twins into the G-buffer's own textures
/// (the second integration line), timed; 0 without twins.
pub(crate) fn resolve_twins(
    gl: &glow::Context,
    retrofit: Option<&mut MsaaRetrofit>,
    resolve_frame: &ResolveFrame,
    timer: &mut GpuTimer,
) -> Result<f64> {
    match retrofit {
        Some(r) => timed(gl, timer, || Ok(r.resolve(gl, resolve_frame)?)),
        None => Ok(0.0),
    }
}
