//! The two-line integration: multisampled twins of a host engine's G-buffer,
//! resolved back into the host's own textures.
//!
//! ```text
//! geometry pass:  gl.bind_framebuffer(FRAMEBUFFER, Some(msaa.framebuffer()));   // instead of the host's
//! after it:       msaa.resolve(&gl, &params)?;                                    // writes the host's textures
//! ```
//! The host's model and lighting shaders do not change: the twins have the
//! same formats, attachment points and draw-buffer mapping as the host's FBO.

use crate::forward::ForwardTarget;
use crate::frame::Frame;
use crate::gbuffer::{MemoryBudget, MultisampleTwin, TwinSpec, budget_twins};
use crate::gl::Texture2d;
use crate::gl::{
    Attachment, ColorAttachment, Format, Framebuffer, GlObject, Handle, HostImage, Made, Owned,
    SavedState, SetupState, TextureRef, check_error, destroy_object,
};
pub use crate::host::{HostAttachment, HostFramebuffer, HostImageKind, introspect};
use crate::profile::StepProfile;
use crate::resolve::cpu::{CpuKeySource, CpuResolve};
use crate::resolve::{
    ExtraOutputs, KeySource, NormalEncoding, ResolveInputs, ResolveParams, ResolveRule,
    ResolveSettings, ResolveSlot, Resolver, StencilCopy, StencilPass,
};
use crate::second_layer::{LayerMix, SecondLayer};
use crate::{Error, Result};
use glow::HasContext;

/// How a host G-buffer is multisampled and resolved: everything that does
/// not change from frame to frame, given once. The programs it needs are
/// compiled when the retrofit is made; [`MsaaRetrofit::set_options`]
/// changes it and rebuilds what must be rebuilt.
#[derive(Clone, Debug, PartialEq)]
pub struct RetrofitOptions {
    /// Requested samples per pixel (the driver's real count is used:
    /// [`MsaaRetrofit::samples`]).
    pub samples: u32,
    /// Rules for colour attachments by attachment number; the others take
    /// their format's default ([`ResolveRule::default_for`]: blend, select for
    /// integers).
    pub rules: Vec<(ColorAttachment, ResolveRule)>,
    /// The colour attachment holding view-space position, whose `-z` is
    /// the depth key; `None` (the default) linearises the depth attachment
    /// with each frame's projection instead.
    pub position_attachment: Option<ColorAttachment>,
    /// What space [`RetrofitOptions::position_attachment`] holds
    /// positions in; with [`PositionSpace::World`] each frame passes its
    /// view matrix ([`Frame::with_view`]).
    pub position_space: PositionSpace,
    /// Method, window, fast path and selective anti-aliasing.
    pub resolve: ResolveSettings,
    /// How a depth-stencil host's stencil is written back after the
    /// resolve ([`StencilCopy`]: by default the reference sample's value).
    pub stencil: StencilCopy,
    /// A limit on the twins' memory: over it, the sample count steps down
    /// (with a line in [`MsaaRetrofit::warnings`]) or, strict, the retrofit
    /// refuses with [`Error::MemoryBudget`].
    pub memory_budget: Option<MemoryBudget>,
    /// The colour attachment holding normals, and how: samples whose
    /// normals differ are different surfaces even when close in depth, in
    /// the one-layer resolve as in both of two layers (`None`: by depth
    /// alone). A host whose normals are packed (`n * 0.5 + 0.5` in an
    /// unsigned normalised format) should name it with
    /// [`NormalEncoding::Unorm`]: without the test a crease pixel blends two
    /// packed normals into one that lights like neither face.
    pub normal_attachment: Option<NormalAttachment>,
    /// How [`MsaaRetrofit::finish_second_layer`] mixes the two lit layers.
    pub layer_mix: LayerMix,
    /// What [`MsaaRetrofit::finish_second_layer`] puts back of the first
    /// layer in the host's G-buffer ([`FirstLayerRestore`]; by default
    /// everything). The lit image is the same whichever is chosen.
    pub restore_first_layer: FirstLayerRestore,
    /// With two layers: count, with `GL_SAMPLES_PASSED` occlusion queries,
    /// what the host's first and second lighting draw, and return
    /// [`Error::SecondLighting`] where the first drew and the second drew
    /// nothing (its own depth or stencil test rejected it) though pixels
    /// have a second layer (default `true`). The queries are active from
    /// the end of `resolve` to the start of `begin_second_layer` and from
    /// its end to the start of `finish_second_layer`; a host that runs
    /// occlusion queries of its own there, or whose second lighting draws
    /// no fragments while something between `resolve` and its first
    /// lighting does (a compute-shader lighting after a fragment SSAO
    /// pass), turns it off.
    pub check_second_lighting: bool,
    /// What [`MsaaRetrofit::begin_frame`] clears the multisampled twins to
    /// (`None`, the default: it clears nothing, and the host clears its
    /// G-buffer through [`MsaaRetrofit::framebuffer`] as it cleared its own
    /// framebuffer). A host that clears its G-buffer's textures through
    /// another framebuffer, or per attachment with values of its own,
    /// never clears the twins: it declares its clear values here and calls
    /// `begin_frame` each frame.
    pub twin_clear: Option<TwinClear>,
    /// With two layers: colour attachments the second layer need not
    /// carry, because the host's lighting does not read them or reads the
    /// same value for both surfaces (an object ID, velocity, a decal mask).
    /// They are not resolved for the second layer (fewer draw buffers and
    /// less work), and during the second lighting the host's image holds
    /// the first layer's value there. Default: none.
    pub second_layer_omits: Vec<ColorAttachment>,
}

/// The values a host clears its G-buffer to, for
/// [`MsaaRetrofit::begin_frame`] to clear the multisampled twins to
/// ([`RetrofitOptions::twin_clear`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TwinClear {
    /// Per colour attachment, its clear value (`glClearBufferfv`'s; an
    /// integer attachment takes the values as integers); an attachment not
    /// listed is cleared to 0.
    pub colors: Vec<(ColorAttachment, [f32; 4])>,
    /// The depth clear value (1 for standard depth, 0 for reversed-Z).
    pub depth: f32,
    /// The stencil clear value, for a depth-stencil host.
    pub stencil: i32,
}

impl Default for TwinClear {
    /// Colours 0, depth 1, stencil 0.
    fn default() -> Self {
        TwinClear {
            colors: Vec::new(),
            depth: 1.0,
            stencil: 0,
        }
    }
}

/// What of the host's G-buffer [`MsaaRetrofit::finish_second_layer`] puts
/// back as the first layer had it ([`RetrofitOptions::restore_first_layer`]).
/// [`MsaaRetrofit::begin_second_layer`] copies that much aside and `finish`
/// copies it back; what is not put back holds the second layer afterwards
/// (where a pixel has none, what the second layer's resolve left there).
///
/// Which a host may choose depends on what its passes after lighting read
/// before the next geometry pass overwrites the G-buffer: any colour
/// attachment (screen-space reflections or ambient occlusion, picking from
/// an ID attachment, a debug view): [`FirstLayerRestore::Everything`].
/// Only depth or stencil (transparent objects or particles drawn into the
/// lit image with depth testing, a stencil-masked outline):
/// [`FirstLayerRestore::DepthAndStencil`]. Nothing (the lit image goes
/// straight to tonemapping and post filters that read only colour):
/// [`FirstLayerRestore::Nothing`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FirstLayerRestore {
    /// Colours, depth and stencil (default): the G-buffer afterwards is
    /// bit for bit the one `resolve` wrote.
    #[default]
    Everything,
    /// Depth and stencil only: one copy each way instead of one per
    /// attachment; the colour attachments hold the second layer afterwards.
    DepthAndStencil,
    /// Nothing: no copies; colours, depth and stencil hold the second layer
    /// afterwards.
    Nothing,
}

impl FirstLayerRestore {
    /// Whether the depth and stencil come back.
    pub fn restores_depth(self) -> bool {
        self != FirstLayerRestore::Nothing
    }

    /// Whether the colour attachments come back.
    pub fn restores_colors(self) -> bool {
        self == FirstLayerRestore::Everything
    }
}

/// A host's normal attachment and its encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NormalAttachment {
    /// The attachment.
    pub attachment: ColorAttachment,
    /// How it stores a normal.
    pub encoding: NormalEncoding,
}

impl Default for RetrofitOptions {
    fn default() -> Self {
        RetrofitOptions {
            samples: 4,
            rules: Vec::new(),
            position_attachment: None,
            position_space: PositionSpace::View,
            resolve: ResolveSettings::default(),
            stencil: StencilCopy::Auto,
            memory_budget: None,
            normal_attachment: None,
            layer_mix: LayerMix::Auto,
            restore_first_layer: FirstLayerRestore::Everything,
            check_second_lighting: true,
            twin_clear: None,
            second_layer_omits: Vec::new(),
        }
    }
}

/// The space of a host's position attachment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PositionSpace {
    /// View space: the key is `−z`, as it is.
    #[default]
    View,
    /// World space (the most-copied deferred tutorial's layout): the key is
    /// view space's `−z`, from each frame's view matrix.
    World,
}

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

/// What copies a depth-stencil host's stencil back: the resolve's reference
/// index per pixel, a framebuffer of the host's depth-stencil image alone
/// (the pass reads the index, so it must not be attached where it writes),
/// and the pass.
#[derive(Debug)]
struct StencilCopyTargets {
    /// The resolve's reference-sample index, for a copy that reads it
    /// (`None` for [`StencilCopy::Blit`], which needs none).
    reference: Option<Texture2d>,
    target: Framebuffer,
    pass: StencilPass,
}

impl GlObject for StencilCopyTargets {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.reference.handles(out);
        self.target.handles(out);
        self.pass.handles(out);
    }
}

impl StencilCopyTargets {
    fn new(gl: &glow::Context, host: &HostFramebuffer, method: StencilCopy) -> Result<Self> {
        let method = method.on(gl)?;
        let (w, h) = host.size();
        Made::build(gl, |made| {
            let reference = if method == StencilCopy::Blit {
                None
            } else {
                Some(made.keep(Texture2d::new(
                    gl,
                    "resolve reference sample",
                    Format::R8ui,
                    w,
                    h,
                )?))
            };
            let depth = &host.depth;
            let images: Vec<(Attachment, HostImage)> = depth
                .host_image()
                .map(|i| (depth.point, i))
                .into_iter()
                .collect();
            let target = made.keep(Framebuffer::with_host_images(
                gl,
                "stencil copy target (host depth-stencil)",
                &[(depth.point, depth.texture_ref())],
                &images,
                &[],
            )?);
            let pass = StencilPass::new(gl, method)?;
            Ok(StencilCopyTargets {
                reference,
                target,
                pass,
            })
        })
    }
}

/// The format of a colour attachment's multisampled twin: the host's own
/// where the driver multisamples it, else its stand-in
/// ([`Format::multisample_stand_in`]).
/// Whether `format` stores unsigned normalised components (`GL_RGBA8`,
/// `GL_RGB10_A2`, ...): no negative value, so a normal in it is packed.
fn unsigned_normalised(format: Format) -> bool {
    matches!(
        format.properties().component,
        crate::gl::format::ComponentType::Unorm
    )
}

fn twin_format(gl: &glow::Context, a: &HostAttachment, samples: u32) -> Result<Format> {
    if multisamples(gl, a.format, samples)? {
        return Ok(a.format);
    }
    let wider = a.format.multisample_stand_in();
    if let Some(wider) = wider {
        if multisamples(gl, wider, samples)? {
            log::info!(
                "{}: {} cannot be multisampled here; its twin is {wider}",
                a.point.name(),
                a.requested_format
            );
            return Ok(wider);
        }
    }
    Err(Error::UnsupportedFormat {
        attachment: a.point.name(),
        format: a.requested_format.clone(),
        reason: format!(
            "the driver cannot render to a multisampled texture of it{}",
            wider
                .map(|w| format!(" nor of its stand-in GL_{w}"))
                .unwrap_or_default()
        ),
    })
}

/// Whether a `samples`x multisample texture of `format` can be made and
/// rendered to: a 1x1 probe, freed at once. A count the format supports
/// at others is the count's error, not the format's.
fn multisamples(gl: &glow::Context, format: Format, samples: u32) -> Result<bool> {
    let _ = check_error(gl, "before probing a multisample format");
    let texture =
        match crate::gl::Texture2dMultisample::new(gl, "format probe", format, 1, 1, samples) {
            Ok(t) => t,
            Err(e @ Error::UnsupportedSampleCount { .. }) => {
                let _ = check_error(gl, "probing a multisample format");
                return match &e {
                    Error::UnsupportedSampleCount { supported, .. } if !supported.is_empty() => {
                        Err(e)
                    }
                    _ => Ok(false),
                };
            }
            Err(Error::Gl { .. }) => return Ok(false),
            Err(e) => return Err(e),
        };
    let point = if format.is_depth() {
        Attachment::for_depth_format(format)
    } else {
        Attachment::Color(0)
    };
    let draw: &[Option<u32>] = if format.is_depth() { &[] } else { &[Some(0)] };
    let fbo = Framebuffer::new(
        gl,
        "format probe",
        &[(point, TextureRef::from(&texture))],
        draw,
    );
    let complete = fbo.is_ok();
    if let Ok(f) = fbo {
        f.destroy(gl);
    }
    texture.destroy(gl);
    let _ = check_error(gl, "probing a multisample format");
    Ok(complete)
}

/// The colour attachment points (and draw buffers) a framebuffer of this
/// context may use: the smaller of `GL_MAX_COLOR_ATTACHMENTS` and
/// `GL_MAX_DRAW_BUFFERS`.
pub(crate) fn output_points(gl: &glow::Context) -> u32 {
    let (attachments, draw) = unsafe {
        (
            glow::HasContext::get_parameter_i32(gl, glow::MAX_COLOR_ATTACHMENTS),
            glow::HasContext::get_parameter_i32(gl, glow::MAX_DRAW_BUFFERS),
        )
    };
    attachments.min(draw).max(1) as u32
}

/// Clear `twin`'s images to `clear`'s values: each colour attachment of
/// `host` at the draw buffer the host maps to it, by its sample kind, then
/// depth and stencil. The caller keeps the host's state.
fn clear_twins(
    gl: &glow::Context,
    host: &HostFramebuffer,
    twin: &MultisampleTwin,
    clear: &TwinClear,
) {
    use crate::gl::format::SampleKind;
    unsafe {
        twin.fbo.bind(gl);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::RASTERIZER_DISCARD);
        gl.color_mask(true, true, true, true);
        gl.depth_mask(true);
        gl.stencil_mask(0xFF);
        for a in &host.colors {
            let Attachment::Color(n) = a.point else {
                continue;
            };
            let Some(buffer) = host.draw_buffers.iter().position(|b| *b == Some(n)) else {
                continue;
            };
            let value = clear
                .colors
                .iter()
                .find(|(c, _)| Attachment::from(*c) == a.point)
                .map_or([0.0; 4], |(_, v)| *v);
            let buffer = buffer as u32;
            match a.format.sample_kind() {
                SampleKind::Float => gl.clear_buffer_f32_slice(glow::COLOR, buffer, &value),
                SampleKind::Uint => gl.clear_buffer_u32_slice(
                    glow::COLOR,
                    buffer,
                    &value.map(|v| v.max(0.0) as u32),
                ),
                SampleKind::Int => {
                    gl.clear_buffer_i32_slice(glow::COLOR, buffer, &value.map(|v| v as i32))
                }
            }
        }
        if host.depth.format.has_stencil() {
            gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, clear.depth, clear.stencil);
        } else {
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[clear.depth]);
        }
    }
}

/// Why an attachment an option names is not one the retrofit resolves:
/// attached but in none of the draw buffers, or nothing attached at all.
fn not_resolved(host: &HostFramebuffer, point: Attachment, what: &str) -> String {
    if host.undrawn.contains(&point) {
        format!(
            "{what}, but it is in none of the host framebuffer's draw buffers (glDrawBuffers): the geometry pass cannot write it, so the retrofit neither twins nor resolves it; add it to the draw buffers, or give the option no attachment there"
        )
    } else {
        format!("{what}, but nothing is attached there")
    }
}

/// The resolve writes a depth-stencil host's reference-sample index as one
/// more colour output after the host's drawn colours: a host that uses
/// every point leaves none for it, which must be refused here, in one line,
/// rather than fail later as a GL error on a point the context lacks.
fn check_stencil_copy_point(gl: &glow::Context, host: &HostFramebuffer) -> Result<()> {
    let points = output_points(gl);
    let needed = host.colors.len() as u32 + 1;
    if needed <= points {
        return Ok(());
    }
    Err(Error::Retrofit {
        attachment: host.depth.point.name(),
        reason: format!(
            "the stencil copy's reference sample needs a colour output after the {} drawn colour \
             attachments, and this context has {points} (GL_MAX_COLOR_ATTACHMENTS, \
             GL_MAX_DRAW_BUFFERS); copy the stencil by blit (StencilCopy::Blit, DMSAA_STENCIL_BLIT: the sample the driver picks, no index needed), draw one colour attachment fewer, or attach {} without its stencil",
            host.colors.len(),
            host.depth.requested_format
        ),
    })
}

/// Before a public call's GL calls: an error the host left pending is not
/// the call's; it is logged and cleared, so that [`settle`] sees the call's
/// own.
fn clear_host_errors(gl: &glow::Context) {
    if let Err(e) = check_error(gl, "the host's GL calls before this call") {
        log::warn!("{e}");
    }
}

/// The end of a public call, after the host's state is back: any GL error
/// the call's own GL calls left pending is drained, so that none is left for
/// the host whatever the result; after a call that succeeded it is the
/// call's error (one no step of the call checked, which the misuse fuzzer
/// has not met).
fn settle<T>(gl: &glow::Context, stage: &str, result: Result<T>) -> Result<T> {
    let pending = check_error(gl, stage);
    let value = result?;
    pending.map(|()| value)
}

/// The second layer's lighting output, checked when `begin_second_layer`
/// is given it (`finish_second_layer` takes begin's alone): a name
/// that is no framebuffer, or a framebuffer GL calls incomplete (the
/// default framebuffer of a surfaceless context, say), is refused saying
/// so, rather than as the GL error a copy from it raises. The read binding
/// is put back.
fn check_output(gl: &glow::Context, output: Option<glow::Framebuffer>) -> Result<()> {
    use glow::HasContext;
    let name = || {
        output.map_or("the default framebuffer (0)".to_string(), |f| {
            format!("framebuffer {}", f.0)
        })
    };
    if let Some(f) = output {
        if !unsafe { gl.is_framebuffer(f) } {
            return Err(Error::invalid(format!(
                "the lighting output, {}, is not a framebuffer object (glIsFramebuffer is false)",
                name()
            )));
        }
    }
    let status = unsafe {
        let read = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING);
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, output);
        let status = gl.check_framebuffer_status(glow::READ_FRAMEBUFFER);
        gl.bind_framebuffer(
            glow::READ_FRAMEBUFFER,
            std::num::NonZeroU32::new(read as u32)
                .map(glow::NativeFramebuffer)
                .filter(|&f| gl.is_framebuffer(f)),
        );
        status
    };
    if status != glow::FRAMEBUFFER_COMPLETE {
        return Err(Error::invalid(format!(
            "the lighting output, {}, is incomplete ({}): the second layer reads the lit image \
             from it",
            name(),
            crate::gl::framebuffer_status_name(status)
        )));
    }
    Ok(())
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
        let (resolver, built) = Made::build(gl, |made| {
            let resolver = made.keep(Resolver::new(gl)?);
            Ok::<_, Error>((resolver, Self::build(gl, host_fbo, options)?))
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

    /// The start of a frame: check that the multisampled framebuffer and
    /// its twins still exist (a render-target wrapper that deletes what it
    /// wraps when dropped deletes them, and the frame after would resolve
    /// stale samples), clear the twins to
    /// [`RetrofitOptions::twin_clear`]'s values where the host declared
    /// them, and return [`MsaaRetrofit::framebuffer`] to bind for the
    /// geometry pass. The host's GL state is as it was.
    ///
    /// Errors: [`Error::Retrofit`] naming the deleted object (then
    /// [`MsaaRetrofit::refresh`] makes new twins), and the GL layer's.
    pub fn begin_frame(&mut self, gl: &glow::Context) -> Result<glow::Framebuffer> {
        clear_host_errors(gl);
        self.check_twins(gl)?;
        if let Some(clear) = &self.options.twin_clear {
            let host = SetupState::capture(gl).guard(gl);
            clear_twins(gl, &self.host, &self.twin, clear);
            drop(host);
        }
        settle(
            gl,
            "clearing the multisampled twins",
            Ok(self.twin.fbo.raw()),
        )
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
    /// [`MsaaRetrofit::refresh`]); [`Error::Gl`].
    pub fn resolve(&mut self, gl: &glow::Context, frame: &Frame) -> Result<()> {
        if self.second.as_ref().is_some_and(|s| s.lighting) {
            return Err(Error::invalid(
                "resolve was called between begin_second_layer and finish_second_layer",
            ));
        }
        let params = self.params(frame)?;
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
        let extra = self.extra_outputs();
        if let Some(second) = &mut self.second {
            second.end_first_lighting(gl);
        }
        // A frame begins: its profile replaces the last one's.
        let mut profile = std::mem::take(&mut self.profile);
        profile.clear();
        let result = self.resolve_profiled(gl, &params, extra, &mut profile);
        self.profile = profile;
        settle(gl, "resolving", result)
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

    /// With two layers ([`ResolveSettings::layers`] = 2), after the host lit
    /// the first layer into `output` (its framebuffer; `None` for the
    /// default framebuffer; the lit colour is its first draw buffer's, the
    /// G-buffer's size): keep that lit image, and put the second layer into
    /// the host's G-buffer textures and depth (the stencil stays the first
    /// layer's). The host then runs its lighting again, unchanged, and calls
    /// [`MsaaRetrofit::finish_second_layer`]. `false`, and nothing done, with
    /// one layer.
    ///
    /// Where a pixel has no second cluster the second layer holds the clear
    /// depth (and colours nothing reads), so a lighting pass that skips
    /// background (by a depth test or its own test of the depth value)
    /// skips it; its output there is not used.
    pub fn begin_second_layer(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<bool> {
        Ok(self.begin_second(gl, output, false)?.is_some())
    }

    /// [`MsaaRetrofit::begin_second_layer`], for a host that lights the
    /// second layer into the crate's own target instead of `output`: the
    /// framebuffer returned, of `output`'s format and the G-buffer's size,
    /// whose colour is cleared to the host's clear colour
    /// (`glClearColor`), whose depth is cleared to the host's clear depth
    /// (`glClearDepth`), and whose stencil is
    /// [`SECOND_LAYER_SELECTED`](crate::second_layer::SECOND_LAYER_SELECTED)
    /// exactly where a pixel has a second layer (every pixel, where no
    /// selection could be made). The host binds it in place of `output`
    /// for its second lighting, changing nothing else; with
    /// `glStencilFunc(GL_EQUAL, SECOND_LAYER_SELECTED, 0xFF)` and stencil
    /// writes off it lights only the pixels the mix reads. It must not
    /// clear the stencil. This is the route for a host lighting into the
    /// default framebuffer, to which no stencil texture attaches; and its
    /// depth test cannot reject the second lighting as the first lighting's
    /// depth in `output` would. `None`, and nothing done, with one layer.
    /// [`MsaaRetrofit::finish_second_layer`] takes the same `output`.
    pub fn begin_second_layer_own_target(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<Option<glow::Framebuffer>> {
        Ok(self.begin_second(gl, output, true)?.flatten())
    }

    /// Both begins: `Some` when the host is to light again, holding the
    /// crate's own target with `own_target`.
    fn begin_second(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        own_target: bool,
    ) -> Result<Option<Option<glow::Framebuffer>>> {
        let Some(second) = &mut self.second else {
            return Ok(None);
        };
        second.end_first_lighting(gl);
        if self.forward.as_ref().is_some_and(|f| f.drawing) {
            return Err(Error::invalid(
                "begin_second_layer between begin_forward and finish_forward: light both layers before the forward pass",
            ));
        }
        clear_host_errors(gl);
        crate::host::check_unchanged(gl, &self.host)?;
        check_output(gl, output)?;
        let host = SetupState::capture(gl).guard(gl);
        let profile = &mut self.profile;
        let mut result = second.begin(
            gl,
            output,
            self.options.restore_first_layer,
            own_target,
            profile,
        );
        // The host's stencil, for its lighting's tests: the second
        // cluster's seed sample's (the first layer's comes back in finish).
        if let (Ok(_), Some(s), Some(depth), Some(reference)) = (
            &result,
            &self.stencil,
            self.twin.depth(),
            second.reference(),
        ) {
            if let Err(e) = profile.time(gl, "second layer: seed stencil", || {
                s.pass
                    .run(gl, depth, &self.twin.fbo, Some(reference), &s.target)
            }) {
                result = Err(e);
            }
        }
        drop(host);
        match result {
            Ok(own) => {
                // Counted from here to finish: the host's second lighting.
                second.lighting_begins(gl);
                settle(gl, "beginning the second layer", Ok(Some(own)))
            }
            Err(e) => {
                second.abandon_check(gl);
                settle(gl, "beginning the second layer", Err(e))
            }
        }
    }

    /// After the host lit the second layer into `output` (the one given to
    /// [`MsaaRetrofit::begin_second_layer`]): write
    /// `mix(first, second, α)` into it ([`RetrofitOptions::layer_mix`]; the
    /// first layer exactly where `α` is 0) and put the first layer back into
    /// the host's G-buffer textures and depth (as much of it as
    /// [`RetrofitOptions::restore_first_layer`] said at `begin`). The
    /// host's GL state is as it was.
    pub fn finish_second_layer(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<()> {
        let Some(second) = &mut self.second else {
            return Err(Error::invalid(
                "finish_second_layer needs two layers (ResolveSettings::layers = 2)",
            ));
        };
        clear_host_errors(gl);
        if let Err(e) = crate::host::check_unchanged(gl, &self.host) {
            // The first layer has no images left to go back into: the
            // frame is over, and `refresh` reads the new G-buffer.
            second.lighting = false;
            return Err(e);
        }
        let mut host = SetupState::capture(gl);
        // The mix tests the selection's stencil.
        host.keep_stencil_func(gl)?;
        let host = host.guard(gl);
        let result = second.finish(gl, output, &mut self.profile);
        drop(host);
        settle(gl, "finishing the second layer", result)
    }

    /// MSAA for what the host draws forward after lighting (light cubes,
    /// transparent objects, particles): after the lighting (and, with two
    /// layers, after [`MsaaRetrofit::finish_second_layer`]), copy the lit
    /// image of `output` (the host's framebuffer, its first draw buffer's
    /// image; `None` for the default framebuffer) into every sample of a
    /// multisampled colour target, attached with the G-buffer twins'
    /// multisampled depth (and stencil) as the geometry pass left them, and
    /// return that framebuffer. The host binds it in place of `output`,
    /// draws its forward objects unchanged (its own depth test, blending
    /// and stencil state; the depth is its own depth convention, as drawn),
    /// and calls [`MsaaRetrofit::finish_forward`]. The target is made on
    /// the first call for an output and kept; a host that writes `output`
    /// through `GL_FRAMEBUFFER_SRGB` should leave it on as it lit.
    ///
    /// What the forward objects write into depth and stencil goes into the
    /// twins' depth, which the next geometry pass clears; `output`'s own
    /// depth is not changed.
    pub fn begin_forward(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<glow::Framebuffer> {
        if self.second.as_ref().is_some_and(|s| s.lighting) {
            return Err(Error::invalid(
                "begin_forward between begin_second_layer and finish_second_layer: finish the second layer first",
            ));
        }
        if self.forward.as_ref().is_some_and(|f| f.drawing) {
            return Err(Error::invalid(
                "begin_forward was called twice: call finish_forward after the forward objects",
            ));
        }
        if let Some(second) = &mut self.second {
            second.end_first_lighting(gl);
        }
        clear_host_errors(gl);
        let host = SetupState::capture(gl).guard(gl);
        let framebuffer_srgb = unsafe { gl.is_enabled(glow::FRAMEBUFFER_SRGB) };
        let result = self
            .forward_for(gl, output, framebuffer_srgb)
            .and_then(|()| {
                let forward = self
                    .forward
                    .as_mut()
                    .ok_or_else(|| Error::invalid("the forward target was not made"))?;
                self.profile.time(gl, "forward: fill", || forward.begin(gl))
            });
        drop(host);
        settle(gl, "beginning the forward target", result)
    }

    /// The forward target for `output`, made again when the output, the
    /// way the host writes it or the layer mix changed.
    fn forward_for(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
        framebuffer_srgb: bool,
    ) -> Result<()> {
        if self
            .forward
            .as_ref()
            .is_some_and(|f| f.serves(output, framebuffer_srgb, &self.options.layer_mix))
        {
            return Ok(());
        }
        if let Some(old) = self.forward.take() {
            destroy_object(gl, old);
        }
        let lit =
            crate::lit_output::LitOutput::inspect(gl, output, framebuffer_srgb, self.host.size())?;
        self.forward = Some(ForwardTarget::new(
            gl,
            lit,
            &self.twin,
            &self.options.layer_mix,
        )?);
        Ok(())
    }

    /// After the host drew its forward objects into
    /// [`MsaaRetrofit::begin_forward`]'s framebuffer: average each pixel's
    /// samples into `output`'s lit image (in the domain of
    /// [`RetrofitOptions::layer_mix`]), leaving every pixel no forward
    /// object touched bit for bit as it was. The host's GL state is as it
    /// was.
    pub fn finish_forward(
        &mut self,
        gl: &glow::Context,
        output: Option<glow::Framebuffer>,
    ) -> Result<()> {
        let Some(forward) = self.forward.as_mut().filter(|f| f.drawing) else {
            return Err(Error::invalid("finish_forward without begin_forward"));
        };
        if forward.output() != output {
            forward.drawing = false;
            return Err(Error::invalid(
                "finish_forward was given another output than begin_forward",
            ));
        }
        clear_host_errors(gl);
        let host = SetupState::capture(gl).guard(gl);
        let result = self
            .profile
            .time(gl, "forward: resolve", || forward.finish(gl));
        drop(host);
        settle(gl, "resolving the forward target", result)
    }

    /// The bytes the forward target allocates (0 before the first
    /// [`MsaaRetrofit::begin_forward`]).
    pub fn forward_bytes(&self) -> u64 {
        self.forward.as_ref().map_or(0, ForwardTarget::bytes)
    }

    /// The second layer's coverage `α = n2 / (n1 + n2)` per pixel (R16F, in
    /// red; 0 where a pixel has one cluster), as of the last resolve; `None`
    /// with one layer.
    pub fn second_layer_coverage(&self) -> Option<TextureRef> {
        self.second.as_ref().map(|s| TextureRef::from(s.coverage()))
    }

    /// The pixels of the last resolve that have a second cluster, as a
    /// stencil: a `DEPTH24_STENCIL8` texture whose stencil is
    /// [`SECOND_LAYER_SELECTED`](crate::second_layer::SECOND_LAYER_SELECTED)
    /// exactly where the coverage is above 0 and 0 elsewhere (its depth is
    /// not defined: test the stencil only, and do not write it). A host
    /// may attach it as the depth-stencil attachment of the framebuffer its
    /// second lighting draws into and light only those pixels
    /// (`glStencilFunc(GL_EQUAL, 1, 0xFF)`), instead of a mask of its own;
    /// the mix keeps the first layer's lit value everywhere else. `None`
    /// with one layer, or where the first resolve had no draw buffer left
    /// for the flag the selection is made from.
    pub fn second_layer_selection(&self) -> Option<TextureRef> {
        self.second
            .as_ref()
            .and_then(SecondLayer::selection)
            .map(TextureRef::from)
    }

    /// The second layer's G-buffer as of the last resolve: its colour
    /// textures in host colour order (the host's formats; meaningful where
    /// the coverage is above 0) and its depth-buffer values (R32F, the
    /// clear depth where the coverage is 0); `None` with one layer. For
    /// hosts that light it with a pass of their own.
    pub fn second_layer_gbuffer(&self) -> Option<(Vec<TextureRef>, TextureRef)> {
        self.second.as_ref().map(|s| {
            let (colors, depth) = s.gbuffer();
            (
                colors.iter().map(TextureRef::from).collect(),
                TextureRef::from(depth),
            )
        })
    }

    /// The bytes the second layer allocates (0 with one layer): its
    /// G-buffer, the first layer's copy kept during the second lighting,
    /// the coverage, and the two lit copies once an output was given.
    pub fn second_layer_bytes(&self) -> u64 {
        self.second.as_ref().map_or(0, SecondLayer::bytes)
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

    /// Change the options. Only what they change is rebuilt: the twins
    /// when the sample count, budget, rules, key, stencil copy, layer
    /// count, normal attachment or layer mix change (the host draws into
    /// the new twins); the programs whenever the resolve's permutation
    /// changes. On error the retrofit keeps working with the options it had.
    pub fn set_options(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        clear_host_errors(gl);
        let host = SetupState::capture(gl).guard(gl);
        let result = self.change_options(gl, options);
        drop(host);
        settle(gl, "changing the options", result)
    }

    fn change_options(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let twins_change = options.samples != self.options.samples
            || options.memory_budget != self.options.memory_budget
            || options.rules != self.options.rules
            || options.position_attachment != self.options.position_attachment
            || options.position_space != self.options.position_space
            || options.stencil != self.options.stencil
            || options.normal_attachment != self.options.normal_attachment
            || options.layer_mix != self.options.layer_mix
            || options.check_second_lighting != self.options.check_second_lighting
            || options.second_layer_omits != self.options.second_layer_omits
            || options.resolve.layers != self.options.resolve.layers;
        if twins_change {
            return self.rebuild(gl, options);
        }
        let previous = self.options.clone();
        self.options = options.clone();
        if let Err(e) = self.prepare(gl) {
            self.options = previous;
            return Err(e);
        }
        Ok(())
    }

    /// Re-read the host framebuffer (after the host resized or re-allocated
    /// its textures) and rebuild the twins. The old twins are freed only once
    /// the new ones exist, so a failure leaves the retrofit working as before.
    pub fn refresh(&mut self, gl: &glow::Context) -> Result<()> {
        let options = self.options.clone();
        self.rebuild(gl, &options)
    }

    /// Change the sample count: [`MsaaRetrofit::set_options`] with only
    /// `samples` changed.
    pub fn set_samples(&mut self, gl: &glow::Context, samples: u32) -> Result<()> {
        let options = RetrofitOptions {
            samples,
            ..self.options.clone()
        };
        self.rebuild(gl, &options)
    }

    fn rebuild(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        clear_host_errors(gl);
        crate::host::check_alive(gl, self.host.fbo)?;
        let host = SetupState::capture(gl).guard(gl);
        let result = self.rebuild_within(gl, options);
        drop(host);
        settle(gl, "rebuilding the twins", result)
    }

    /// Put `built` in place of what the retrofit was built with; that is
    /// returned.
    fn swap_built(&mut self, built: Built) -> Built {
        use std::mem::replace;
        Built {
            host: replace(&mut self.host, built.host),
            twin: replace(&mut self.twin, built.twin),
            target: replace(&mut self.target, built.target),
            rules: replace(&mut self.rules, built.rules),
            key: replace(&mut self.key, built.key),
            warnings: replace(&mut self.warnings, built.warnings),
            stencil: replace(&mut self.stencil, built.stencil),
            normal: replace(&mut self.normal, built.normal),
            second: replace(&mut self.second, built.second),
        }
    }

    fn rebuild_within(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let built = Self::build(gl, self.host.fbo, options)?;
        // Freed when this returns, or if the compilation panics; taken back
        // if it fails.
        let old = Owned::new(gl, self.swap_built(built));
        let old_options = std::mem::replace(&mut self.options, options.clone());
        match self.prepare(gl) {
            Ok(()) => {
                drop(old);
                // The forward target attaches the old twins' depth.
                if let Some(forward) = self.forward.take() {
                    destroy_object(gl, forward);
                }
                Ok(())
            }
            Err(e) => {
                // Put the working twins back.
                self.swap_built(old.into_inner()).destroy(gl);
                self.options = old_options;
                Err(e)
            }
        }
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
    }
}
