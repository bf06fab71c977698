//! Changing a renderer's options: what a new size, layout, sample count or
//! method rebuilds, and what it keeps ([`Renderer::set_options`]).

use super::Renderer;
use super::depth::{self};
use super::options::RenderOptions;
use super::pass::geometry::GeometryPass;
use super::pass::lighting::LightingPass;
use super::pass::slots::GBufferSlots;
use super::plan::{Pass, Plan, PlanContext};
use super::resources::{Frame, attach_gbuffer_textures, free_textures};
use super::targets::Targets;
use super::technique::smaa::SmaaPasses;
use super::technique::smaa::options::SmaaEdges;
use super::technique::smaa::targets::SmaaTargets;
use crate::gbuffer::GBuffer;
use crate::gl::Made;
use crate::retrofit::{FirstLayerRestore, MsaaRetrofit, RetrofitOptions};
use crate::{Error, Result};

impl Renderer {
    /// Change size, sample count, anti-aliasing method, FXAA, SMAA or layout at run
    /// time, re-creating only what changed:
    /// - a new size re-allocates the G-buffer's textures on the same
    ///   framebuffer and lets the retrofit re-read it ([`MsaaRetrofit::set_samples`],
    ///   which rebuilds from the host's framebuffer), then the other targets;
    /// - a new sample count rebuilds the multisampled twins only;
    /// - switching between `none` and a multisampled method creates or frees
    ///   the retrofit;
    /// - a new resolve method or window changes nothing on the GPU;
    /// - the first switch to `per-sample` or `complex` builds their programs
    ///   (kept from then on); `complex`'s stencil mask and coverage flags are
    ///   allocated by the next frame (they follow the twins and targets, and
    ///   are freed on every change);
    /// - a new layout builds a new G-buffer and retrofit;
    /// - a new depth mode changes nothing on the GPU (it is decided again
    ///   with a new layout too, see [`DepthMode::Auto`](crate::renderer::DepthMode::Auto)).
    ///
    /// The precision check runs again before allocating; new findings are
    /// logged. New objects are made before old ones are freed: on error the
    /// renderer keeps rendering with its previous options.
    pub fn set_options(&mut self, gl: &glow::Context, requested: &RenderOptions) -> Result<()> {
        requested.validate()?;
        super::technique::sparse_check_support(gl, &requested.aa)?;
        let plan_context = if requested.layout == self.requested.layout {
            self.plan_context.clone()
        } else {
            PlanContext::query(gl, &requested.layout)
        };
        let mut plan = Plan::for_needs(&self.needs, &plan_context, requested)?;
        plan.set_decals(self.decal_hook.is_some());
        let active = plan.apply(requested);
        let options = &active;
        // The technique's programs first: they are kept either way.
        self.prepare_technique(gl, Some(options))?;
        if options.smaa.is_some() && self.passes.smaa.is_none() {
            self.passes.smaa = Some(SmaaPasses::new(gl)?);
        }
        let depth_mode =
            depth::resolve_mode(gl, options.depth_mode, &self.clip, options.layout.depth)?;
        let mut warnings = depth::warnings(&options.layout, &self.camera, depth_mode, self.extent);
        warnings.extend(plan.warnings.iter().cloned());
        if warnings != self.warnings {
            for w in &warnings {
                log::warn!("scene `{}` ({depth_mode} depth): {w}", self.scene_name);
            }
        }
        if options.layout != self.options.layout {
            self.rebuild_frame(gl, options)?;
        } else if (options.width, options.height) != (self.options.width, self.options.height) {
            self.resize(gl, options)?;
        } else {
            self.update_in_place(gl, options)?;
        }
        self.options = options.clone();
        self.requested = requested.clone();
        self.plan = plan;
        self.plan_context = plan_context;
        self.depth_mode = depth_mode;
        self.warnings = warnings;
        // Technique targets refer to the twins and targets that may have
        // changed; the next frame allocates them again.
        self.techniques.options_changed(gl, &self.options.aa);
        Ok(())
    }

    /// A new layout: a new G-buffer, retrofit and targets (and a new model
    /// program when the attachment numbers moved).
    fn rebuild_frame(&mut self, gl: &glow::Context, options: &RenderOptions) -> Result<()> {
        let slots = GBufferSlots::of(&options.layout)?;
        // The model and lighting programs follow the attachment set.
        let (frame, geometry, lighting) = Made::build(gl, |made| {
            let frame = made.keep(Frame::new(gl, options, self.opt_out_flag)?);
            let geometry = if slots != self.passes.geometry.slots() {
                Some(made.keep(GeometryPass::new(gl, slots)?))
            } else {
                None
            };
            let lighting = if slots != self.passes.lighting.slots() {
                Some(made.keep(LightingPass::new(gl, slots)?))
            } else {
                None
            };
            Ok::<_, Error>((frame, geometry, lighting))
        })?;
        std::mem::replace(&mut self.frame, frame).destroy(gl);
        if let Some(g) = geometry {
            std::mem::replace(&mut self.passes.geometry, g).destroy(gl);
        }
        if let Some(l) = lighting {
            std::mem::replace(&mut self.passes.lighting, l).destroy(gl);
        }
        Ok(())
    }

    /// A new size with the same layout.
    fn resize(&mut self, gl: &glow::Context, options: &RenderOptions) -> Result<()> {
        let (colors, depth, targets, smaa) = Made::build(gl, |made| {
            let (colors, depth) =
                GBuffer::allocate_textures(gl, &options.layout, options.width, options.height)?;
            let (colors, depth) = (made.keep(colors), made.keep(depth));
            let targets = made.keep(Targets::new(gl, &depth, options.fxaa)?);
            let smaa = if options.smaa.is_some() {
                Some(made.keep(SmaaTargets::new(gl, options.width, options.height)?))
            } else {
                None
            };
            Ok::<_, Error>((colors, depth, targets, smaa))
        })?;
        let gb = &mut self.frame.gbuffer;
        if let Err(e) = attach_gbuffer_textures(gl, &mut gb.fbo, &colors, &depth) {
            let _ = attach_gbuffer_textures(gl, &mut gb.fbo, &gb.colors, &gb.depth);
            targets.destroy(gl);
            if let Some(t) = smaa {
                t.destroy(gl);
            }
            free_textures(gl, colors, Some(depth));
            return Err(e);
        }
        let old_colors = std::mem::replace(&mut gb.colors, colors);
        let old_depth = std::mem::replace(&mut gb.depth, depth);
        let old_size = (gb.width, gb.height);
        (gb.width, gb.height) = (options.width, options.height);
        if let Err(e) = self.update_retrofit(gl, options, true) {
            // Put the old textures back: the retrofit still matches them.
            let gb = &mut self.frame.gbuffer;
            let colors = std::mem::replace(&mut gb.colors, old_colors);
            let depth = std::mem::replace(&mut gb.depth, old_depth);
            (gb.width, gb.height) = old_size;
            let _ = attach_gbuffer_textures(gl, &mut gb.fbo, &gb.colors, &gb.depth);
            targets.destroy(gl);
            if let Some(t) = smaa {
                t.destroy(gl);
            }
            free_textures(gl, colors, Some(depth));
            return Err(e);
        }
        free_textures(gl, old_colors, Some(old_depth));
        std::mem::replace(&mut self.frame.targets, targets).destroy(gl);
        if let Some(t) = std::mem::replace(&mut self.frame.smaa, smaa) {
            t.destroy(gl);
        }
        Ok(())
    }

    /// Same size and layout: the retrofit and the FXAA and SMAA targets may change.
    fn update_in_place(&mut self, gl: &glow::Context, options: &RenderOptions) -> Result<()> {
        let (w, h) = (options.width, options.height);
        let new_fxaa = if options.fxaa && self.frame.targets.fxaa.is_none() {
            Some(Targets::ldr_target(gl, "fxaa", w, h)?)
        } else {
            None
        };
        let new_smaa = if options.smaa.is_some() && self.frame.smaa.is_none() {
            match SmaaTargets::new(gl, w, h) {
                Ok(t) => Some(t),
                Err(e) => {
                    if let Some(t) = new_fxaa {
                        t.destroy(gl);
                    }
                    return Err(e);
                }
            }
        } else {
            None
        };
        if let Err(e) = self.update_retrofit(gl, options, false) {
            if let Some(t) = new_fxaa {
                t.destroy(gl);
            }
            if let Some(t) = new_smaa {
                t.destroy(gl);
            }
            return Err(e);
        }
        if new_smaa.is_some() {
            self.frame.smaa = new_smaa;
        } else if options.smaa.is_none() {
            if let Some(t) = self.frame.smaa.take() {
                t.destroy(gl);
            }
        }
        if new_fxaa.is_some() {
            self.frame.targets.fxaa = new_fxaa;
        } else if !options.fxaa {
            if let Some(t) = self.frame.targets.fxaa.take() {
                t.destroy(gl);
            }
        }
        Ok(())
    }

    /// Keep the G-buffer's first layer after each frame (`true`, the
    /// default) or not. With two layers the retrofit puts the host's
    /// second layer into the G-buffer for the second lighting; a caller that
    /// reads the G-buffer after [`Renderer::render`] ([`Renderer::gbuffer`],
    /// `dump`, the goldens) needs it back. One that reads only the lit image
    /// (the bench) may say `false`: the retrofit then copies back only what
    /// the frame's own passes after lighting read (the depth, which
    /// transparent objects are tested against and SMAA's depth edges read),
    /// or nothing ([`RetrofitOptions::restore_first_layer`]). The lit image
    /// is the same either way.
    pub fn set_keep_gbuffer(&mut self, gl: &glow::Context, keep: bool) -> Result<()> {
        self.keep_gbuffer = keep;
        self.align_first_layer_restore(gl)
    }

    /// What of the first layer the frame's G-buffer must hold again after
    /// the second lighting.
    fn first_layer_restore(&self) -> FirstLayerRestore {
        let smaa_reads_depth = self
            .options
            .smaa
            .is_some_and(|smaa| smaa.edges == SmaaEdges::Depth);
        if self.keep_gbuffer {
            FirstLayerRestore::Everything
        } else if self.plan.runs(Pass::Transparent) || smaa_reads_depth {
            FirstLayerRestore::DepthAndStencil
        } else {
            FirstLayerRestore::Nothing
        }
    }

    /// Set the retrofit's [`RetrofitOptions::restore_first_layer`] to what
    /// this frame needs, where it differs (a change of no twin: no rebuild).
    pub(super) fn align_first_layer_restore(&mut self, gl: &glow::Context) -> Result<()> {
        let restore = self.first_layer_restore();
        if let Some(r) = self.frame.retrofit.as_mut() {
            if r.options().restore_first_layer != restore {
                let options = RetrofitOptions {
                    restore_first_layer: restore,
                    ..r.options().clone()
                };
                r.set_options(gl, &options)?;
            }
        }
        Ok(())
    }

    /// Bring the retrofit in line with `options` (each branch is all or
    /// nothing). `host_changed`: the G-buffer's textures were re-allocated.
    fn update_retrofit(
        &mut self,
        gl: &glow::Context,
        options: &RenderOptions,
        host_changed: bool,
    ) -> Result<()> {
        let retrofit_options = RetrofitOptions {
            // Checked again each frame against the plan then in effect.
            restore_first_layer: self.first_layer_restore(),
            ..options.retrofit_options(self.opt_out_flag)
        };
        match (&mut self.frame.retrofit, options.aa.is_multisampled()) {
            (Some(r), true) => {
                if host_changed {
                    // Rebuilds the twins from the host framebuffer as it is now.
                    r.refresh(gl)?;
                }
                // Rebuilds only what the options change.
                r.set_options(gl, &retrofit_options)?;
            }
            (None, true) => {
                let r = MsaaRetrofit::new(gl, self.frame.gbuffer.fbo.raw(), &retrofit_options)?;
                self.frame.retrofit = Some(r);
            }
            (Some(_), false) => {
                if let Some(r) = self.frame.retrofit.take() {
                    r.destroy(gl);
                }
            }
            (None, false) => {}
        }
        Ok(())
    }
}
