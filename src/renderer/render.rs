//! The frame: [`Renderer::render`] runs the passes in order, asking the
//! technique that renders the current method for the steps that differ.

use super::depth;
use super::options::RenderOptions;
use super::pass::geometry::{GeometryPass, GeometryTarget};
use super::pass::lighting::{StandIns, light_batches};
use super::pass::slots::GBufferSlots;
use super::plan::Pass;
use super::resources::{Frame, Passes};
use super::technique::smaa::edges::DepthInput;
use super::technique::{FrameCamera, FrameParts, GeometryStep, LightingStep, Setup};
use super::timing::timed;
use super::{DecalTarget, FrameTimings, Renderer};
use crate::gl::check_error;
use crate::{Error, Result};
use glow::HasContext;

impl Renderer {
    /// Render one frame (see the [module documentation](super) for the passes).
    ///
    /// The clip control the depth mode needs is set for the frame; the
    /// host's clip control, depth function and clear depth are put back
    /// afterwards, on error too.
    pub fn render(&mut self, gl: &glow::Context) -> Result<FrameTimings> {
        let saved = self.clip.enter(gl, self.depth_mode);
        let result = self.render_passes(gl);
        self.clip.leave(gl, saved);
        result
    }

    fn render_passes(&mut self, gl: &glow::Context) -> Result<FrameTimings> {
        let (width, height) = (self.options.width, self.options.height);
        let aa = self.options.aa;
        let depth_mode = self.depth_mode;
        let clear_depth = depth_mode.clear_depth();
        let view = self.camera.view.as_dmat4();
        let resolve_frame = self.resolve_frame();
        let batches = light_batches(&self.lights, &view);
        let footprint = (self.camera.fov_y / height as f32).tan();
        let slots = self.passes.geometry.slots();
        let runs_transparent = self.plan.runs(Pass::Transparent);
        self.align_first_layer_restore(gl)?;
        let specular_constant = self
            .plan
            .constant_specular
            .unwrap_or([0.04, 0.04, 0.04, 0.0]);
        // The way into a frame with twins: the geometry pass's clear
        // reaches them after it (MsaaRetrofit::begin_frame).
        if let Some(retrofit) = self.frame.retrofit.as_mut() {
            retrofit.begin_frame(gl)?;
        }
        let frame = FrameParts {
            aa,
            gbuffer: &self.frame.gbuffer,
            retrofit: self.frame.retrofit.as_ref(),
            targets: &self.frame.targets,
        };
        let setup = Setup {
            options: &self.options,
            slots,
            colors: self.frame.gbuffer.colors.len() as u32,
        };
        let technique = self.techniques.active_mut(&aa);
        technique.prepare(gl, &setup, Some(frame))?;
        // Every pass of the frame draws with the projection the technique
        // gives (`taa` jitters it).
        let projection = technique.begin_frame(&FrameCamera {
            view: &view,
            projection: &depth::projection(&self.camera, width as f32 / height as f32, depth_mode),
            size: (width, height),
            zero_to_one: depth_mode.is_reversed(),
        });
        let Passes {
            background,
            background_copy,
            geometry,
            lighting,
            transparent,
            tonemap,
            fxaa,
            smaa,
            fullscreen,
            timer,
        } = &mut self.passes;
        let mut t = FrameTimings {
            total_ms: 0.0,
            geometry_ms: 0.0,
            resolve_ms: 0.0,
            decal_ms: 0.0,
            lighting_ms: 0.0,
            second_layer_ms: 0.0,
            transparent_ms: 0.0,
            tonemap_ms: 0.0,
            fxaa_ms: 0.0,
            post_ms: 0.0,
            smaa_ms: 0.0,
            smaa_edges_ms: 0.0,
            smaa_weights_ms: 0.0,
            smaa_blend_ms: 0.0,
            timer: timer.kind(),
        };

        let gbuffer_target = technique.geometry_target(&frame);
        let target = GeometryTarget {
            fbo: gbuffer_target.fbo,
            width,
            height,
        };
        let step = GeometryStep {
            target,
            draw_buffers: &gbuffer_target.draw_buffers,
            frame,
            model: geometry,
            background_copy,
            fullscreen,
            slots,
            scene: &self.scene,
            view: &view,
            projection: &projection,
            nearer_func: depth_mode.nearer_func(),
            clear_depth,
        };
        t.geometry_ms = timed(gl, timer, || {
            GeometryPass::clear(gl, target, clear_depth);
            technique.clear_outputs(gl);
            background.draw(
                gl,
                &frame.targets.background,
                fullscreen,
                &self.background,
                &view,
                &projection,
            )?;
            technique.draw_gbuffer(gl, &step)
        })?;

        t.resolve_ms =
            technique.after_geometry(gl, self.frame.retrofit.as_mut(), &resolve_frame, timer)?;

        let Frame {
            gbuffer,
            retrofit,
            targets,
            smaa: smaa_targets,
        } = &mut self.frame;
        let (gbuffer, targets) = (&*gbuffer, &*targets);
        if let Some(hook) = self.decal_hook.as_mut() {
            let decal_target = DecalTarget {
                gbuffer,
                view: self.camera.view,
                projection,
            };
            t.decal_ms = timed(gl, timer, || {
                gbuffer.fbo.bind(gl);
                hook(gl, &decal_target);
                Ok(check_error(gl, "the decal hook")?)
            })?;
        }

        // One step per lighting call: the second lends the retrofit apart.
        macro_rules! lighting_step {
            ($retrofit:expr) => {
                LightingStep {
                    frame: FrameParts {
                        aa,
                        gbuffer,
                        retrofit: $retrofit,
                        targets,
                    },
                    lighting,
                    fullscreen,
                    slots,
                    batches: &batches,
                    clear_depth,
                    stand_ins: StandIns {
                        background: &targets.background.texture,
                        specular: specular_constant,
                    },
                    projection: &projection,
                    footprint,
                }
            };
        }
        let step = lighting_step!(retrofit.as_ref());
        t.lighting_ms = timed(gl, timer, || technique.light(gl, &step))?;
        // The retrofit is lent mutably for its second-layer calls, so this
        // step does not lend it again.
        let step = lighting_step!(None);
        t.second_layer_ms = technique.second_lighting(gl, retrofit.as_mut(), &step, timer)?;
        if runs_transparent {
            let forward_msaa = self.options.forward_msaa;
            t.transparent_ms = timed(gl, timer, || {
                let lit = targets.hdr.fbo.raw();
                // With forward MSAA, into the retrofit's multisampled
                // forward target, resolved back into the HDR image.
                let target = match (forward_msaa, retrofit.as_mut()) {
                    (true, Some(r)) => r.begin_forward(gl, Some(lit))?,
                    (true, None) => {
                        return Err(Error::invalid(
                            "forward MSAA needs the retrofit's multisampled G-buffer, and this method has none",
                        ));
                    }
                    (false, _) => targets.hdr_with_depth.raw(),
                };
                transparent.draw(
                    gl,
                    (target, width, height),
                    &self.scene,
                    &view,
                    &projection,
                    &batches,
                    depth_mode.nearer_func(),
                )?;
                match (forward_msaa, retrofit.as_mut()) {
                    (true, Some(r)) => Ok(r.finish_forward(gl, Some(lit))?),
                    _ => Ok(()),
                }
            })?;
        }
        let tonemapped = technique.tonemap_target(targets);
        t.tonemap_ms = timed(gl, timer, || {
            tonemap.draw(gl, tonemapped, fullscreen, &targets.hdr.texture)
        })?;
        t.post_ms = technique.post(gl, targets, fullscreen, timer)?;
        if let Some(out) = targets.fxaa.as_ref() {
            t.fxaa_ms = timed(gl, timer, || {
                fxaa.draw(gl, out, fullscreen, &targets.ldr.texture)
            })?;
        }
        if let (Some(options), Some(passes), Some(out)) =
            (self.options.smaa, smaa.as_ref(), smaa_targets.as_ref())
        {
            let depth_input = DepthInput::new(&projection, depth_mode.is_reversed());
            let times = passes.draw(
                gl,
                &options,
                out,
                fullscreen,
                &targets.ldr.texture,
                &gbuffer.depth,
                depth_input,
                timer,
            )?;
            t.smaa_edges_ms = times.edges_ms;
            t.smaa_weights_ms = times.weights_ms;
            t.smaa_blend_ms = times.blend_ms;
            t.smaa_ms = times.edges_ms + times.weights_ms + times.blend_ms;
        }
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.bind_vertex_array(None);
            gl.use_program(None);
        }
        t.total_ms = t.geometry_ms
            + t.resolve_ms
            + t.decal_ms
            + t.lighting_ms
            + t.second_layer_ms
            + t.transparent_ms
            + t.tonemap_ms
            + t.post_ms
            + t.fxaa_ms
            + t.smaa_ms;
        Ok(t)
    }

    /// Let the technique of `options` (default: the current ones) build its
    /// programs and the targets that do not refer to the frame's objects.
    pub(super) fn prepare_technique(
        &mut self,
        gl: &glow::Context,
        options: Option<&RenderOptions>,
    ) -> Result<()> {
        let options = options.unwrap_or(&self.options);
        let setup = Setup {
            options,
            slots: GBufferSlots::of(&options.layout)?,
            colors: options.layout.colors.len() as u32,
        };
        self.techniques
            .active_mut(&options.aa)
            .prepare(gl, &setup, None)
    }
}
