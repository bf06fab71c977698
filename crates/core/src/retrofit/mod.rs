//! The integration: multisampled twins of a host engine's G-buffer,
//! resolved back into the host's own textures.
//!
//! ```text
//! each frame:     let fbo = msaa.begin_frame(&gl)?;                              // checks, prepares the twins
//! geometry pass:  gl.bind_framebuffer(FRAMEBUFFER, Some(fbo));                   // instead of the host's, then its clear
//! after it:       msaa.resolve(&gl, &params)?;                                    // writes the host's textures
//! ```
//! The host's model and lighting shaders do not change: the twins have the
//! same formats, attachment points and draw-buffer mapping as the host's FBO.

mod checks;
mod layers;
mod options;
mod rebuild;
mod stencil_copy;
mod twins;

use crate::clear_check::{ClearCheck, SENTINEL_DEPTH};
use crate::forward::ForwardTarget;
use crate::frame::Frame;
use crate::gbuffer::{MemoryBudget, MultisampleTwin, TwinSpec, budget_twins};
use crate::gl::{
    Attachment, ColorAttachment, Format, Framebuffer, GlObject, Handle, Made, Owned, SavedState,
    SetupState, TextureRef, check_error, destroy_object,
};
pub use crate::host::{HostAttachment, HostFramebuffer, HostImageKind, introspect};
use crate::profile::StepProfile;
use crate::resolve::cpu::{CpuCamera, CpuKeySource, CpuResolve};
use crate::resolve::{
    ExtraOutputs, KeySource, NormalEncoding, ResolveInputs, ResolveParams, ResolveRule,
    ResolveSlot, Resolver, StencilCopy,
};
pub use crate::second_layer::FirstLayerRestore;
use crate::second_layer::SecondLayer;
use crate::{Error, Result};
use checks::{check_stencil_copy_point, clear_host_errors, not_resolved, settle};
use glow::HasContext;
pub use options::{NormalAttachment, PositionSpace, RetrofitOptions, TwinClear};
use stencil_copy::StencilCopyTargets;
use twins::{clear_twin_depth, clear_twins, twin_format, unsigned_normalised};

/// A host G-buffer retrofitted with MSAA: multisampled twins to draw into and
/// a resolve that writes the host's original textures.
#[derive(Debug)]
pub struct MsaaRetrofit {
    host: HostFramebuffer,
    options: RetrofitOptions,
    twin: MultisampleTwin,
    target: Framebuffer,
    rules: Vec<ResolveRule>,
    key: KeySource,
    resolver: Resolver,
    /// What the budget did (a stepped-down sample count), one line each.
    warnings: Vec<String>,
    /// The stencil copy, for a depth-stencil host.
    stencil: Option<StencilCopyTargets>,
    /// The normal attachment's slot, for the second layer's clusters.
    normal: Option<(ResolveSlot, NormalEncoding)>,
    /// The second layer, with two layers.
    second: Option<SecondLayer>,
    /// The last profiled frame's steps ([`MsaaRetrofit::set_profiling`]).
    profile: StepProfile,
    /// The forward target, once asked for ([`MsaaRetrofit::begin_forward`]).
    forward: Option<ForwardTarget>,
    /// `begin_frame` was called since the last `resolve` (or `refresh`).
    frame_begun: bool,
    /// Whether a `refresh` made new twins since the last `resolve`.
    refreshed: bool,
    /// The check that the twins were cleared, where the host declared no
    /// clear values (`begin_frame` then clears the depth to a sentinel).
    clear_check: Option<ClearCheck>,
}

/// What [`MsaaRetrofit::build`] makes from the host's framebuffer.
struct Built {
    host: HostFramebuffer,
    twin: MultisampleTwin,
    target: Framebuffer,
    rules: Vec<ResolveRule>,
    key: KeySource,
    warnings: Vec<String>,
    stencil: Option<StencilCopyTargets>,
    normal: Option<(ResolveSlot, NormalEncoding)>,
    second: Option<SecondLayer>,
}

impl Built {
    fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for Built {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.twin.handles(out);
        self.target.handles(out);
        self.stencil.handles(out);
        self.second.handles(out);
    }
}

impl MsaaRetrofit {
    /// Introspect `host_fbo`, build its multisampled twins under
    /// `options` and compile the resolve's programs.
    ///
    /// Errors: [`Error::Retrofit`] or [`Error::UnsupportedFormat`] naming
    /// the attachment the host framebuffer cannot be retrofitted for,
    /// [`Error::MemoryBudget`] when a strict budget (or any budget, with no
    /// multisampled count that fits) refuses, and the GL layer's errors.
    pub fn new(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Self> {
        clear_host_errors(gl);
        let host = SetupState::capture(gl).guard(gl);
        let result = Self::create(gl, host_fbo, options);
        drop(host);
        match (result, check_error(gl, "making the retrofit")) {
            // An error no step checked: the retrofit is not handed out, and
            // what it made is freed.
            (Ok(retrofit), Err(e)) => {
                retrofit.destroy(gl);
                let _ = check_error(gl, "freeing a retrofit that left a GL error");
                Err(e)
            }
            (result, _) => result,
        }
    }

    fn create(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Self> {
        let (resolver, clear_check, built) = Made::build(gl, |made| {
            let resolver = made.keep(Resolver::new(gl)?);
            let clear_check = made.keep(ClearCheck::new(gl)?);
            Ok::<_, Error>((resolver, clear_check, Self::build(gl, host_fbo, options)?))
        })?;
        let mut retrofit = Owned::new(
            gl,
            MsaaRetrofit {
                host: built.host,
                options: options.clone(),
                twin: built.twin,
                target: built.target,
                rules: built.rules,
                key: built.key,
                resolver,
                warnings: built.warnings,
                stencil: built.stencil,
                normal: built.normal,
                second: built.second,
                profile: StepProfile::default(),
                forward: None,
                frame_begun: false,
                refreshed: false,
                clear_check: Some(clear_check),
            },
        );
        retrofit.prepare(gl)?;
        Ok(retrofit.into_inner())
    }

    /// The sample count `budget` allows for twins of `host`'s attachments.
    fn budgeted(
        gl: &glow::Context,
        host: &HostFramebuffer,
        requested: u32,
        budget: &MemoryBudget,
    ) -> Result<(u32, Option<String>)> {
        let mut formats: Vec<Format> = host.colors.iter().map(|a| a.format).collect();
        formats.push(host.depth.format);
        let (w, h) = host.size();
        budget_twins(gl, &formats, w, h, requested, budget)
    }

    /// What the memory budget did, one line each (empty without one, or
    /// when the requested count fit).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The options in force.
    pub fn options(&self) -> &RetrofitOptions {
        &self.options
    }

    fn build(
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<Built> {
        let host = introspect(gl, host_fbo)?;
        let mut rules = Vec::with_capacity(host.colors.len());
        for a in &host.colors {
            let Attachment::Color(i) = a.point else {
                continue;
            };
            let rule = options
                .rules
                .iter()
                .find(|(n, _)| *n == ColorAttachment(i))
                .map_or(ResolveRule::default_for(a.format), |(_, r)| *r);
            if ResolveRule::default_for(a.format) == ResolveRule::Select
                && rule != ResolveRule::Select
            {
                return Err(Error::UnsupportedFormat {
                    attachment: a.point.name(),
                    format: a.requested_format.clone(),
                    reason: format!(
                        "integer values can only be selected, not resolved by `{rule}`"
                    ),
                });
            }
            if rule == ResolveRule::BlendNormal && unsigned_normalised(a.format) {
                return Err(Error::UnsupportedFormat {
                    attachment: a.point.name(),
                    format: a.requested_format.clone(),
                    reason: "`blend-normal` renormalises the stored vector, and an unsigned normalised format holds no negative component: for normals packed as n*0.5+0.5 use `blend` or `select` and name the attachment in RetrofitOptions::normal_attachment with NormalEncoding::Unorm, so that samples of different normals are not blended".into(),
                });
            }
            rules.push(rule);
        }
        for (n, _) in &options.rules {
            if !host.colors.iter().any(|a| a.point == Attachment::from(*n)) {
                return Err(Error::Retrofit {
                    attachment: n.name(),
                    reason: not_resolved(&host, Attachment::from(*n), "a rule is given for it"),
                });
            }
        }
        let key = match options.position_attachment {
            None => KeySource::Depth,
            Some(n) => {
                let k = host
                    .colors
                    .iter()
                    .position(|a| a.point == Attachment::from(n))
                    .ok_or_else(|| Error::Retrofit {
                        attachment: n.name(),
                        reason: not_resolved(
                            &host,
                            Attachment::from(n),
                            "named as the position attachment",
                        ),
                    })?;
                if ResolveRule::default_for(host.colors[k].format) == ResolveRule::Select {
                    return Err(Error::UnsupportedFormat {
                        attachment: n.name(),
                        format: host.colors[k].requested_format.clone(),
                        reason: "the depth key needs a floating-point position".into(),
                    });
                }
                match options.position_space {
                    PositionSpace::View => KeySource::Position(ResolveSlot(k)),
                    PositionSpace::World => KeySource::WorldPosition(ResolveSlot(k)),
                }
            }
        };
        let normal = match options.normal_attachment {
            None => None,
            Some(n) => {
                let k = host
                    .colors
                    .iter()
                    .position(|a| a.point == Attachment::from(n.attachment))
                    .ok_or_else(|| Error::Retrofit {
                        attachment: n.attachment.name(),
                        reason: not_resolved(
                            &host,
                            Attachment::from(n.attachment),
                            "named as the normal attachment",
                        ),
                    })?;
                if ResolveRule::default_for(host.colors[k].format) == ResolveRule::Select {
                    return Err(Error::UnsupportedFormat {
                        attachment: n.attachment.name(),
                        format: host.colors[k].requested_format.clone(),
                        reason: "the normal test needs a float or normalised normal attachment"
                            .into(),
                    });
                }
                let signed = matches!(n.encoding, NormalEncoding::Xyz | NormalEncoding::Octahedral);
                if signed && unsigned_normalised(host.colors[k].format) {
                    return Err(Error::UnsupportedFormat {
                        attachment: n.attachment.name(),
                        format: host.colors[k].requested_format.clone(),
                        reason: format!(
                            "the normal attachment's NormalEncoding::{:?} is for signed components, but an unsigned normalised format holds no negative one: normals packed into [0, 1] are NormalEncoding::Unorm (octahedral ones OctahedralUnorm)",
                            n.encoding
                        ),
                    });
                }
                Some((ResolveSlot(k), n.encoding))
            }
        };
        // A copy by blit reads no reference index: it needs no output.
        if host.depth.format.has_stencil() && options.stencil.on(gl)? != StencilCopy::Blit {
            check_stencil_copy_point(gl, &host)?;
        }
        let mut samples = options.samples;
        let mut warnings = Vec::new();
        if let Some(budget) = &options.memory_budget {
            let (fits, warning) = Self::budgeted(gl, &host, options.samples, budget)?;
            samples = fits;
            warnings.extend(warning);
        }
        let mut specs: Vec<TwinSpec> = Vec::with_capacity(host.colors.len() + 1);
        for a in &host.colors {
            specs.push(TwinSpec {
                point: a.point,
                format: twin_format(gl, a, samples)?,
                name: a.point.name(),
            });
        }
        specs.push(TwinSpec {
            point: host.depth.point,
            format: host.depth.format,
            name: host.depth.point.name(),
        });
        let (w, h) = host.size();
        let (twin, stencil, target, second) = Made::build(gl, |made| {
            let twin = made.keep(MultisampleTwin::new(
                gl,
                &specs,
                &host.draw_buffers,
                w,
                h,
                samples,
            )?);
            // The resolve writes output k into the host's k-th colour texture.
            let (mut attachments, images) = host.images();
            let mut draw: Vec<Option<u32>> = (0..host.colors.len() as u32).map(Some).collect();
            let stencil = if host.depth.format.has_stencil() {
                Some(made.keep(StencilCopyTargets::new(gl, &host, options.stencil)?))
            } else {
                None
            };
            let second = if options.resolve.layers == 2 {
                // The seed sample, where the stencil copy reads indices.
                let with_reference = stencil.as_ref().is_some_and(|s| s.reference.is_some());
                let mut omitted = Vec::with_capacity(options.second_layer_omits.len());
                for n in &options.second_layer_omits {
                    let point = Attachment::from(*n);
                    let k = host
                        .colors
                        .iter()
                        .position(|a| a.point == point)
                        .ok_or_else(|| Error::Retrofit {
                            attachment: n.name(),
                            reason: not_resolved(
                                &host,
                                point,
                                "named in RetrofitOptions::second_layer_omits",
                            ),
                        })?;
                    omitted.push(k);
                }
                Some(made.keep(SecondLayer::new(
                    gl,
                    &host,
                    &options.layer_mix,
                    with_reference,
                    options.check_second_lighting,
                    &omitted,
                )?))
            } else {
                None
            };
            // After the colours: the outside flag for the second layer, then
            // the reference index for the stencil copy (the program key's
            // order of extra outputs).
            let mut next = host.colors.len() as u32;
            if let Some(flag) = second.as_ref().and_then(SecondLayer::flag) {
                attachments.push((Attachment::Color(next), TextureRef::from(flag)));
                draw.push(Some(next));
                next += 1;
            }
            if let Some(reference) = stencil.as_ref().and_then(|s| s.reference.as_ref()) {
                attachments.push((Attachment::Color(next), TextureRef::from(reference)));
                draw.push(Some(next));
            }
            let target = made.keep(Framebuffer::with_host_images(
                gl,
                "resolve target (host images)",
                &attachments,
                &images,
                &draw,
            )?);
            Ok::<_, Error>((twin, stencil, target, second))
        })?;
        Ok(Built {
            stencil,
            host,
            twin,
            target,
            rules,
            key,
            warnings,
            normal,
            second,
        })
    }

    /// Compile the programs the options' resolve uses.
    fn prepare(&mut self, gl: &glow::Context) -> Result<()> {
        let extra = self.extra_outputs();
        self.run_resolver(gl, None, None, extra)?;
        self.run_second_layer(gl, None, &mut StepProfile::default())?
    }

    /// The second layer's resolve under `params` (or, without, only its
    /// compilation); nothing with one layer.
    /// The second layer's resolve (or, without `params`, its programs);
    /// inside, the last frame's check of the second lighting, when it was
    /// left to this frame.
    fn run_second_layer(
        &mut self,
        gl: &glow::Context,
        params: Option<&ResolveParams>,
        profile: &mut StepProfile,
    ) -> Result<Result<()>> {
        let Some(second) = &self.second else {
            return Ok(Ok(()));
        };
        let (depth, colors, points) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            attachments: &points,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
            normal: self.normal,
        };
        match params {
            None => {
                for (pass, target) in second.passes() {
                    self.resolver.prepare_second_layer(
                        gl,
                        &inputs,
                        target,
                        &self.options.resolve,
                        second.has_reference(),
                        pass,
                    )?;
                }
                Ok(Ok(()))
            }
            Some(params) => {
                let selected = profile.time(gl, "second layer: selection", || {
                    let mut state = SavedState::capture(gl, 1);
                    // The selection sets the stencil function.
                    state.keep_stencil_func(gl)?;
                    let _state = state.guard(gl);
                    second.select(gl, params.projection.clear_depth as f32)
                });
                profile.time(gl, "second layer: resolve", || {
                    let selected = selected?;
                    // One draw, or several where the context's draw buffers
                    // cannot take every colour and the extras at once.
                    for (pass, target) in second.passes() {
                        self.resolver.run_second_layer(
                            gl,
                            &inputs,
                            target,
                            params,
                            second.has_reference(),
                            selected,
                            pass,
                        )?;
                    }
                    Ok::<_, Error>(())
                })?;
                // The last frame's check, if it was left pending, comes
                // back here: returned once this frame is resolved whole.
                match &mut self.second {
                    Some(second) => profile.time(gl, "second layer: count", || {
                        let state = SavedState::capture(gl, 1);
                        let counted = second.count_selected(gl);
                        state.restore(gl);
                        Ok(counted)
                    }),
                    None => Ok(Ok(())),
                }
            }
        }
    }

    /// The resolver on the twins: a resolve into `target` (the host's
    /// images when `None`) under `params`, or, without `params`, only the
    /// compilation of what such a resolve uses.
    fn run_resolver(
        &mut self,
        gl: &glow::Context,
        target: Option<&Framebuffer>,
        params: Option<&ResolveParams>,
        extra: ExtraOutputs,
    ) -> Result<()> {
        let (depth, colors, points) = self.inputs()?;
        let inputs = ResolveInputs {
            depth,
            colors: &colors,
            attachments: &points,
            rules: &self.rules,
            key: self.key,
            samples: self.twin.samples,
            normal: self.normal,
        };
        let target = target.unwrap_or(&self.target);
        match params {
            None => self
                .resolver
                .prepare(gl, &inputs, target, &self.options.resolve, extra),
            Some(params) => self.resolver.run(gl, &inputs, target, params, extra),
        }
    }

    /// The resolve's outputs beyond the host's attachments: the reference
    /// index, when the host's stencil is copied.
    fn extra_outputs(&self) -> ExtraOutputs {
        ExtraOutputs {
            complex: false,
            // The second layer's resolve runs where the first left a sample out.
            outside: self.second.as_ref().is_some_and(|s| s.flag().is_some()),
            reference: self.stencil.as_ref().is_some_and(|s| s.reference.is_some()),
        }
    }

    /// How the host's stencil is copied back (`None` without a stencil).
    pub fn stencil_copy(&self) -> Option<StencilCopy> {
        self.stencil.as_ref().map(|s| s.pass.method())
    }

    /// The multisampled framebuffer: bind it instead of the host's for the geometry pass.
    pub fn framebuffer(&self) -> glow::Framebuffer {
        self.twin.fbo.raw()
    }

    /// The start of a frame, required before each frame's geometry pass:
    /// check that the multisampled framebuffer and its twins still exist (a
    /// render-target wrapper that deletes what it wraps when dropped
    /// deletes them, and the frame after would resolve stale samples),
    /// prepare the twins, and return [`MsaaRetrofit::framebuffer`] to bind
    /// for the geometry pass. The host's GL state is as it was.
    ///
    /// With [`RetrofitOptions::twin_clear`] declared, the twins are cleared
    /// to its values. Without, their depth is cleared to a sentinel value
    /// that the host's own clear of the framebuffer replaces, and
    /// [`MsaaRetrofit::resolve`] returns [`Error::TwinsNotCleared`] for a
    /// frame in which much of it is left (nothing cleared the twins after
    /// this call: the host clears its G-buffer through another
    /// framebuffer, or before `begin_frame`), instead of resolving a black
    /// or stale frame.
    ///
    /// Errors: [`Error::Retrofit`] naming the deleted object (then
    /// [`MsaaRetrofit::refresh`] makes new twins), and the GL layer's.
    pub fn begin_frame(&mut self, gl: &glow::Context) -> Result<glow::Framebuffer> {
        clear_host_errors(gl);
        self.check_twins(gl)?;
        let host = SetupState::capture(gl).guard(gl);
        match &self.options.twin_clear {
            Some(clear) => clear_twins(gl, &self.host, &self.twin, clear),
            None => clear_twin_depth(gl, &self.twin, SENTINEL_DEPTH),
        }
        drop(host);
        let result = settle(
            gl,
            "clearing the multisampled twins",
            Ok(self.twin.fbo.raw()),
        );
        self.frame_begun = result.is_ok();
        result
    }

    /// The multisampled framebuffer and textures exist: nobody else deleted
    /// them.
    fn check_twins(&self, gl: &glow::Context) -> Result<()> {
        let deleted = |what: String| Error::Retrofit {
            attachment: "the multisampled twins".into(),
            reason: format!(
                "{what} was deleted by someone other than the retrofit, which owns it (a render-target wrapper that deletes what it wraps when dropped?); wrap it without taking ownership, and call refresh to make new twins"
            ),
        };
        if !unsafe { gl.is_framebuffer(self.twin.fbo.raw()) } {
            return Err(deleted(format!(
                "the multisampled framebuffer {} (MsaaRetrofit::framebuffer)",
                self.twin.fbo.raw().0
            )));
        }
        for (t, spec) in self.twin.textures.iter().zip(&self.twin.specs) {
            if !unsafe { gl.is_texture(t.raw()) } {
                return Err(deleted(format!(
                    "the multisampled twin texture {} of {}",
                    t.raw().0,
                    spec.point.name()
                )));
            }
        }
        Ok(())
    }

    /// The real sample count.
    pub fn samples(&self) -> u32 {
        self.twin.samples
    }

    /// What was found in the host's framebuffer.
    pub fn host(&self) -> &HostFramebuffer {
        &self.host
    }

    /// The multisampled twins (for techniques that read samples directly).
    pub fn twin(&self) -> &MultisampleTwin {
        &self.twin
    }

    /// The resolve rule of each host colour attachment, in attachment order.
    pub fn rules(&self) -> &[ResolveRule] {
        &self.rules
    }

    /// Where the depth key comes from (a slot among the host's colour
    /// attachments, in attachment order).
    pub fn key(&self) -> KeySource {
        self.key
    }

    /// The resolve's inputs: depth, and the twins in host colour order with
    /// the attachment each stands for.
    pub fn inputs(&self) -> Result<(TextureRef, Vec<TextureRef>, Vec<ColorAttachment>)> {
        let depth = self
            .twin
            .depth()
            .map(TextureRef::from)
            .ok_or_else(|| Error::Retrofit {
                attachment: self.host.depth.point.name(),
                reason: "its multisampled twin is missing".into(),
            })?;
        let mut colors = Vec::with_capacity(self.host.colors.len());
        let mut points = Vec::with_capacity(self.host.colors.len());
        for a in &self.host.colors {
            let (Some(twin), Attachment::Color(n)) = (self.twin.texture(a.point), a.point) else {
                return Err(Error::Retrofit {
                    attachment: a.point.name(),
                    reason: "its multisampled twin is missing".into(),
                });
            };
            colors.push(TextureRef::from(twin));
            points.push(ColorAttachment(n));
        }
        Ok((depth, colors, points))
    }

    /// The CPU reference of this retrofit's resolve of `frame`: the same
    /// settings, rules, depth key, normal test, clear depth and pixel
    /// footprint, for tools that analyse the resolve sample by sample (the
    /// samples are [`MsaaRetrofit::inputs`] read back). A world-space key
    /// needs the frame's view ([`Frame::with_view`]).
    pub fn cpu_reference(&self, frame: &Frame) -> Result<CpuResolve> {
        let params = self.params(frame)?;
        let key_source = match self.key {
            KeySource::Depth => CpuKeySource::Depth(params.projection),
            KeySource::Position(slot) => CpuKeySource::Position(slot.0),
            KeySource::WorldPosition(slot) => CpuKeySource::WorldPosition {
                attachment: slot.0,
                view_row: params.view_row.ok_or_else(|| {
                    Error::invalid(
                        "the depth key is a world-space position, so the CPU reference needs \
                         the view matrix (Frame::with_view)",
                    )
                })?,
            },
        };
        Ok(CpuResolve {
            settings: params.settings,
            rules: self.rules.clone(),
            key_source,
            clear_depth: params.projection.clear_depth,
            footprint: params.footprint(),
            normal: self.normal.map(|(slot, encoding)| (slot.0, encoding)),
            camera: CpuCamera::of(&params),
        })
    }

    /// The low-level parameters of a resolve of this frame.
    fn params(&self, frame: &Frame) -> Result<ResolveParams> {
        let (projection, fov_y) = frame.depth_terms()?;
        Ok(ResolveParams {
            settings: self.options.resolve,
            projection,
            fov_y,
            height_px: self.host.size().1,
            view_row: frame.view_row(),
        })
    }

    /// Resolve the twins into the host's textures: call it after the
    /// geometry pass, before the host's lighting reads its G-buffer.
    ///
    /// Errors: [`Error::InvalidArgument`] between `begin_second_layer` and
    /// `finish_second_layer` or for a projection that is not a GL
    /// perspective; [`Error::Retrofit`] when the host re-allocated, deleted
    /// or replaced an attachment since the retrofit read it (call
    /// [`MsaaRetrofit::refresh`]); [`Error::HostGl`] for an error the
    /// host's calls left pending; [`Error::FrameNotBegun`] without
    /// [`MsaaRetrofit::begin_frame`] since the last resolve (or refresh);
    /// [`Error::TwinsNotCleared`] where nothing cleared the twins after it
    /// (nothing is resolved; see `begin_frame`); [`Error::Gl`].
    pub fn resolve(&mut self, gl: &glow::Context, frame: &Frame) -> Result<()> {
        if self.second.as_ref().is_some_and(|s| s.lighting) {
            return Err(Error::invalid(
                "resolve was called between begin_second_layer and finish_second_layer",
            ));
        }
        let params = self.params(frame)?;
        crate::resolve::check_view(self.key, params.view_row)?;
        self.check_twins(gl)?;
        // An error the host's calls left pending (a geometry pass that
        // failed to bind its framebuffer, say) means the twins may not hold
        // the frame it drew: returned, with nothing resolved.
        if let Err(Error::Gl {
            code, code_name, ..
        }) = check_error(gl, "the host's GL calls")
        {
            return Err(Error::HostGl { code, code_name });
        }
        crate::host::check_unchanged(gl, &self.host)?;
        if !self.frame_begun {
            return Err(Error::FrameNotBegun {
                since: if self.refreshed { " or refresh" } else { "" },
            });
        }
        // The frame is this call's from here, resolved or refused.
        self.frame_begun = false;
        self.refreshed = false;
        let extra = self.extra_outputs();
        if let Some(second) = &mut self.second {
            second.end_first_lighting(gl);
        }
        // A frame begins: its profile replaces the last one's.
        let mut profile = std::mem::take(&mut self.profile);
        profile.clear();
        let result = self
            .check_cleared(gl, &mut profile)
            .and_then(|()| self.resolve_profiled(gl, &params, extra, &mut profile));
        self.profile = profile;
        settle(gl, "resolving", result)
    }

    /// Where the host declared no clear values: check that it cleared the
    /// twins after `begin_frame` (the sentinel's pixels counted).
    fn check_cleared(&mut self, gl: &glow::Context, profile: &mut StepProfile) -> Result<()> {
        if self.options.twin_clear.is_some() {
            return Ok(());
        }
        let (Some(check), Some(depth)) = (&mut self.clear_check, self.twin.depth()) else {
            return Ok(());
        };
        let target = &self.target;
        profile.time(gl, "clear check", || check.check(gl, depth, target))
    }

    fn resolve_profiled(
        &mut self,
        gl: &glow::Context,
        params: &ResolveParams,
        extra: ExtraOutputs,
        profile: &mut StepProfile,
    ) -> Result<()> {
        profile.time(gl, "resolve", || {
            self.run_resolver(gl, None, Some(params), extra)
        })?;
        if let (Some(s), Some(depth)) = (&self.stencil, self.twin.depth()) {
            profile.time(gl, "stencil copy", || {
                s.pass
                    .run(gl, depth, &self.twin.fbo, s.reference.as_ref(), &s.target)
            })?;
        }
        if self.second.as_ref().is_some_and(|s| s.lighting) {
            return Err(Error::invalid(
                "resolve was called between begin_second_layer and finish_second_layer",
            ));
        }
        let last_check = self.run_second_layer(gl, Some(params), profile)?;
        if let Some(second) = &mut self.second {
            second.resolved = true;
        }
        last_check
    }

    /// Time each of the retrofit's steps from the next frame on (between
    /// two `glFinish` calls, which slow the frame: for finding where time
    /// goes, not for frame times), or stop. [`MsaaRetrofit::profile`] has
    /// the steps of the frame since the last `resolve`.
    pub fn set_profiling(&mut self, on: bool) {
        self.profile.set_enabled(on);
    }

    /// The steps timed since the last `resolve` while profiling: the
    /// resolve, the stencil copy, the second layer's selection and resolve,
    /// and each copy and the mix of `begin_second_layer` and
    /// `finish_second_layer`. Empty when not profiling.
    pub fn profile(&self) -> &StepProfile {
        &self.profile
    }

    /// The profile, for a host to time its own passes into it
    /// ([`StepProfile::time`]).
    pub fn profile_mut(&mut self) -> &mut StepProfile {
        &mut self.profile
    }

    /// Resolve into another target (its colour `k` receives host attachment
    /// `k`; with `complex_output`, draw buffer `colors.len()` gets the
    /// complex-pixel mask): for tools that inspect the resolve. Its
    /// programs are compiled on first use.
    pub fn resolve_into(
        &mut self,
        gl: &glow::Context,
        target: &Framebuffer,
        frame: &Frame,
        complex_output: bool,
    ) -> Result<()> {
        let params = self.params(frame)?;
        self.run_resolver(gl, Some(target), Some(&params), complex_output.into())
    }

    /// Free everything this crate created (never the host's objects).
    pub fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

/// What [`MsaaRetrofit::destroy`] frees, for a [`Made`](crate::gl::Made) guard.
impl GlObject for MsaaRetrofit {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.twin.handles(out);
        self.target.handles(out);
        self.stencil.handles(out);
        self.second.handles(out);
        self.resolver.handles(out);
        self.forward.handles(out);
        self.clear_check.handles(out);
    }
}
