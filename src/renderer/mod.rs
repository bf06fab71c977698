//! A small deferred renderer that mirrors FreeSpace Open's frame
//! (docs/freespace-open.md), for demos, tests and benchmarks.
//!
//! It is written as a *host* of the retrofit: it owns an ordinary
//! single-sample [`GBuffer`] like any engine, and multisampling comes only
//! through [`MsaaRetrofit`] on that G-buffer's framebuffer — the two-line
//! integration. With [`AaMode::None`] the G-buffer pass draws straight into
//! the G-buffer; with [`AaMode::Resolve`] it draws into the retrofit's
//! multisampled twin, which [`MsaaRetrofit::resolve`] then writes back into
//! the G-buffer's own textures. Nothing else changes: the model shaders and
//! the lighting shader are the same either way.
//!
//! # The frame ([`Renderer::render`])
//!
//! 1. **Clear** the G-buffer pass's framebuffer (colour 0, depth to the
//!    clear depth: 1.0, or 0.0 with reversed-Z).
//! 2. **Background**, drawn single-sampled into its own RGBA16F texture
//!    (`background.frag`), then **copied** into the emissive attachment of
//!    that framebuffer by a full-screen pass that writes every sample
//!    (`background_copy.frag`; a blit cannot write a multisampled target).
//! 3. **G-buffer pass** (`geometry.vert` + `geometry.frag`): opaque and
//!    alpha-tested objects; depth test LESS with standard GL depth (−1..1),
//!    or GREATER with reversed-Z ([`DepthMode`]).
//! 4. **Resolve** ([`MsaaRetrofit::resolve`]) into the G-buffer's textures,
//!    when multisampling.
//! 5. **Decal hook** ([`Renderer::set_decal_hook`]) with the resolved
//!    G-buffer bound.
//! 6. **Lighting** (`lighting.frag`): per pixel, from the resolved G-buffer,
//!    into an RGBA16F HDR target; background pixels (depth = clear depth)
//!    get their emissive value only. With [`AaMode::PerSample`] the lighting
//!    pass (`lighting_per_sample.frag`, which calls `lighting.frag`'s
//!    shading with its light batches) lights every sample of the
//!    multisampled twins instead, each into a radiance layer of its own,
//!    the batches added as this pass adds them, and `sample_average.frag`
//!    averages the samples as the tonemap will see them. With
//!    [`AaMode::Complex`] (whose G-buffer pass also records coverage flags,
//!    `geometry_coverage.frag`) a detection pass (`complex_mask.frag`)
//!    marks complex pixels in a stencil mask on the HDR target, then
//!    stencil-masked passes of `lighting_per_sample.frag` light simple
//!    pixels once, from sample 0, and complex pixels per sample, averaged
//!    by `sample_average.frag`.
//! 7. **Transparent objects** (`transparent.frag`), forward, single-sampled,
//!    alpha-blended, depth-tested against the resolved depth without writing it.
//! 8. **Tonemap** (`tonemap.frag`) into an RGBA8 sRGB-encoded image.
//! 9. **FXAA** (`fxaa.frag`), optional, into a second RGBA8 image; or
//!    **SMAA 1x** ([`SmaaOptions`]: `smaa_edges.frag`, `smaa_weights.frag`,
//!    `smaa_blend.frag`), optional, through its edge and weight targets
//!    into another.
//!
//! With [`AaMode::Sparse`] steps 2 (the copy) to 4 become a multisampled
//! depth pre-pass, a set-up pass and a G-buffer pass that writes per-pixel
//! lists of blocks, and step 6 lights the lists (`sparse*.frag`; see
//! [`SparseOptions`]).
//!
//! With [`AaMode::Gbaa`] step 3 also writes two edge buffers (its program
//! adds a geometry stage, `gbaa_geometry.geom`, and wraps `geometry.frag`
//! in `gbaa_geometry.frag`), step 8 tonemaps into an sRGB texture, and a
//! post pass (`gbaa.frag`) blends across the edges into the RGBA8 image
//! before FXAA.
//!
//! Each pass sets all the GL state it relies on.
//!
//! # Depth
//!
//! [`DepthMode::Auto`] (the default) renders with reversed-Z — near → 1,
//! far → 0, `glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)`, cleared to 0.0 —
//! when the context has `glClipControl` and the layout's depth is floating
//! point, and with GL's standard depth otherwise. The clip control is set
//! for the frame and put back as the host had it afterwards, as are the
//! depth function and the clear depth. Before allocating, the layout is
//! checked against the scene's depth range ([`Renderer::warnings`]).

mod background;
mod background_copy;
mod complex_mask;
mod depth;
pub mod frame_pass;
mod fxaa;
pub(crate) mod gbaa;
mod gbaa_geometry;
mod geometry;
mod geometry_coverage;
mod lighting;
mod lighting_per_sample;
mod mesh;
mod options;
mod pass;
pub mod plan;
mod second_layer_mask;
mod slow_path;
mod smaa;
mod smaa_blend;
mod smaa_edges;
pub mod smaa_tables;
mod smaa_weights;
mod sparse;
mod taa;
mod targets;
pub mod technique;
mod tonemap;

/// The demo renderer's tonemap curve and its inverse as GLSL, for
/// [`LayerMix::Curve`](deferred_msaa::LayerMix::Curve): the declaration of
/// its lit values it makes by default ([`RenderOptions::layer_mix`]).
pub fn tonemap_curve() -> String {
    tonemap::layer_mix_curve()
}
mod transparent;

use crate::frame::{DepthMode as ResolveDepthMode, Frame as ResolveFrame};
use crate::gbuffer::{GBuffer, GBufferLayout};
use crate::gl::ColorAttachment;
use crate::gl::destroy_object;
use crate::gl::{
    Attachment, Capabilities, Framebuffer, GlObject, GpuTimer, Handle, Made, Texture2d, TextureRef,
    TimerKind, VertexArray, check_error, framebuffer_status_name,
};
use crate::resolve::SelectionFlag;
use crate::retrofit::{FirstLayerRestore, MsaaRetrofit, RetrofitOptions};
use crate::scene::{Background, Camera, Light, Scene};
use crate::{Error, Result};
use background::BackgroundPass;
use background_copy::BackgroundCopyPass;
pub use depth::DepthMode;
use depth::{ClipControl, SceneExtent};
use fxaa::FxaaPass;
use geometry::{GeometryPass, GeometryTarget};
use glam::Mat4;
use glow::HasContext;
use lighting::{LightingPass, StandIns, light_batches};
use lighting_per_sample::PerSampleLightingPass;
use mesh::GpuScene;
pub use options::{AaMode, RenderOptions};
use plan::{Pass, Plan, PlanContext, SceneNeeds};
use smaa::{DepthInput, SmaaPasses, SmaaTargets};
pub use smaa::{SmaaEdges, SmaaFilter, SmaaOptions, SmaaOutput, SmaaPreset};
pub use sparse::{
    DEFAULT_POOL_BLOCKS_PER_PIXEL, MASK_OVERFLOW, MASK_SINGLE, MAX_SPARSE_SAMPLES, SparseMemory,
    SparseOptions, SparseStats,
};
use std::ffi::c_void;
pub use taa::{MAX_TAA_PHASES, TaaOptions};
use targets::Targets;
use technique::{
    ComplexPixelsInput, FrameCamera, FrameParts, GeometryStep, LightingStep, Setup, Techniques,
};
use tonemap::TonemapPass;
use transparent::TransparentPass;

/// The sources of the renderer's model and lighting shaders, for a host (or
/// a test) that builds the very same programs around its own G-buffer.
pub mod shaders {
    pub use super::geometry::{GEOMETRY_FRAG, GEOMETRY_VERT};
    pub use super::lighting::{AMBIENT, LIGHTING_FRAG, LIGHTS_PER_BATCH, lighting_defines};
}

/// The colour attachment numbers of the attachments the renderer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GBufferSlots {
    pub(crate) color: u32,
    pub(crate) position: u32,
    pub(crate) normal: u32,
    /// `None`: the layout has none (the scene-adaptive plan left it out).
    pub(crate) specular: Option<u32>,
    /// `None`: the layout has none (the scene-adaptive plan left it out).
    pub(crate) emissive: Option<u32>,
}

impl GBufferSlots {
    fn of(layout: &GBufferLayout) -> Result<Self> {
        let find = |name: &str| {
            layout.index_of(name).map(|k| k as u32).ok_or_else(|| {
                Error::Layout(format!(
                    "the renderer writes an attachment named `{name}`, which this layout lacks (it has: {})",
                    layout
                        .colors
                        .iter()
                        .map(|a| a.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
        };
        Ok(GBufferSlots {
            color: find("color")?,
            position: find("position")?,
            normal: find("normal")?,
            specular: layout.index_of("specular").map(|k| k as u32),
            emissive: layout.index_of("emissive").map(|k| k as u32),
        })
    }

    /// The model shader's outputs the layout has, with their attachment numbers.
    pub(crate) fn outputs(&self) -> Vec<(&'static str, u32)> {
        let mut outputs = vec![
            ("o_color", self.color),
            ("o_position", self.position),
            ("o_normal", self.normal),
        ];
        outputs.extend(self.specular.map(|k| ("o_specular", k)));
        outputs.extend(self.emissive.map(|k| ("o_emissive", k)));
        outputs
    }

    /// The defines the model and lighting shaders are compiled with for
    /// this attachment set: `GBUFFER_NO_SPECULAR`, `GBUFFER_NO_EMISSIVE`
    /// (none for the full layout).
    pub(crate) fn defines(&self) -> Vec<(String, String)> {
        let mut d = Vec::new();
        if self.specular.is_none() {
            d.push(("GBUFFER_NO_SPECULAR".to_string(), "1".to_string()));
        }
        if self.emissive.is_none() {
            d.push(("GBUFFER_NO_EMISSIVE".to_string(), "1".to_string()));
        }
        d
    }
}

/// Where one frame's time went, in milliseconds, measured pass by pass with
/// [`GpuTimer`] (`total_ms` is the sum).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrameTimings {
    /// The whole frame.
    pub total_ms: f64,
    /// Clear, background, background copy and the G-buffer pass.
    pub geometry_ms: f64,
    /// The resolve (0 without multisampling).
    pub resolve_ms: f64,
    /// The decal hook (0 without one).
    pub decal_ms: f64,
    /// Deferred lighting; with [`AaMode::PerSample`] the per-sample
    /// lighting, with [`AaMode::Complex`] the complex-pixel detection and
    /// both lighting passes.
    pub lighting_ms: f64,
    /// The resolve's second layer (with two layers): the retrofit's copies
    /// around the second lighting, its mask, the second lighting and the
    /// mix (the second layer's resolve is in `resolve_ms`).
    pub second_layer_ms: f64,
    /// Forward transparent objects.
    pub transparent_ms: f64,
    /// Tonemapping.
    pub tonemap_ms: f64,
    /// The FXAA pass (0 when off).
    pub fxaa_ms: f64,
    /// The post pass between the tonemap and FXAA: [`AaMode::Gbaa`]'s
    /// blend across edges (its G-buffer pass is in `geometry_ms`) or
    /// [`AaMode::Taa`]'s resolve; 0 with other modes.
    pub post_ms: f64,
    /// SMAA's three passes (0 when off): the sum of the next three.
    pub smaa_ms: f64,
    /// SMAA's edge pass.
    pub smaa_edges_ms: f64,
    /// SMAA's blending-weight pass.
    pub smaa_weights_ms: f64,
    /// SMAA's neighbourhood-blending pass.
    pub smaa_blend_ms: f64,
    /// How the times were measured.
    pub timer: TimerKind,
}

/// A decal hook; see [`Renderer::set_decal_hook`].
pub type DecalHook = Box<dyn FnMut(&glow::Context, &DecalTarget<'_>)>;

/// What a decal hook is given: the resolved G-buffer and the matrices the
/// frame's G-buffer pass drew with, so that decals land on the surfaces
/// they decorate.
#[derive(Debug, Clone, Copy)]
pub struct DecalTarget<'a> {
    /// The resolved single-sample G-buffer; its framebuffer is bound.
    pub gbuffer: &'a GBuffer,
    /// World to view: the camera's view matrix.
    pub view: Mat4,
    /// View to clip: [`Renderer::projection`], moved by the frame's
    /// sub-pixel jitter under [`AaMode::Taa`] (a decal drawn unjittered
    /// there would swim against the jittered geometry under it).
    pub projection: Mat4,
}

/// Programs, the full-screen vertex array and the timer: built once.
#[derive(Debug)]
struct Passes {
    background: BackgroundPass,
    background_copy: BackgroundCopyPass,
    geometry: GeometryPass,
    lighting: LightingPass,
    transparent: TransparentPass,
    tonemap: TonemapPass,
    fxaa: FxaaPass,
    /// SMAA's programs and tables, built when SMAA is first asked for.
    smaa: Option<SmaaPasses>,
    fullscreen: VertexArray,
    timer: GpuTimer,
}

impl GlObject for Passes {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.background.handles(out);
        self.background_copy.handles(out);
        self.geometry.handles(out);
        self.lighting.handles(out);
        self.transparent.handles(out);
        self.tonemap.handles(out);
        self.fxaa.handles(out);
        self.smaa.handles(out);
        self.fullscreen.handles(out);
        self.timer.handles(out);
    }
}

impl Passes {
    fn new(gl: &glow::Context, slots: GBufferSlots, smaa: bool) -> Result<Self> {
        Made::build(gl, |made| {
            Ok(Passes {
                background: made.keep(BackgroundPass::new(gl)?),
                background_copy: made.keep(BackgroundCopyPass::new(gl)?),
                geometry: made.keep(GeometryPass::new(gl, slots)?),
                lighting: made.keep(LightingPass::new(gl, slots)?),
                transparent: made.keep(TransparentPass::new(gl)?),
                tonemap: made.keep(TonemapPass::new(gl)?),
                fxaa: made.keep(FxaaPass::new(gl)?),
                smaa: if smaa {
                    Some(made.keep(SmaaPasses::new(gl)?))
                } else {
                    None
                },
                fullscreen: made.keep(VertexArray::new(gl, "renderer full-screen triangle")?),
                timer: made.keep(GpuTimer::new(gl, false)?),
            })
        })
    }

    fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

/// The size- and layout-dependent resources: the host G-buffer, the
/// retrofit on it, and the other targets.
#[derive(Debug)]
struct Frame {
    gbuffer: GBuffer,
    retrofit: Option<MsaaRetrofit>,
    targets: Targets,
}

impl GlObject for Frame {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.gbuffer.handles(out);
        self.retrofit.handles(out);
        self.targets.handles(out);
    }
}

impl Frame {
    fn new(
        gl: &glow::Context,
        options: &RenderOptions,
        opt_out_flag: Option<SelectionFlag>,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let gbuffer = made.keep(GBuffer::new(
                gl,
                &options.layout,
                options.width,
                options.height,
            )?);
            let retrofit = if options.aa.is_multisampled() {
                Some(made.keep(MsaaRetrofit::new(
                    gl,
                    gbuffer.fbo.raw(),
                    &options.retrofit_options(opt_out_flag),
                )?))
            } else {
                None
            };
            let targets = made.keep(Targets::new(
                gl,
                &gbuffer.depth,
                options.fxaa,
                options.smaa.is_some(),
            )?);
            Ok(Frame {
                gbuffer,
                retrofit,
                targets,
            })
        })
    }

    fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

fn free_textures(gl: &glow::Context, colors: Vec<Texture2d>, depth: Option<Texture2d>) {
    for t in colors {
        t.destroy(gl);
    }
    if let Some(t) = depth {
        t.destroy(gl);
    }
}

/// Attach `colors` (colour `k` at `GL_COLOR_ATTACHMENTk`) and `depth` to the
/// existing framebuffer `fbo`, as an engine does when it re-allocates its
/// G-buffer on resize, and check completeness.
fn attach_gbuffer_textures(
    gl: &glow::Context,
    fbo: &mut Framebuffer,
    colors: &[Texture2d],
    depth: &Texture2d,
) -> Result<()> {
    let mut attachments: Vec<(Attachment, TextureRef)> = colors
        .iter()
        .enumerate()
        .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
        .collect();
    attachments.push((
        Attachment::for_depth_format(depth.format),
        TextureRef::from(depth),
    ));
    let status = unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo.raw()));
        for (point, texture) in &attachments {
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                point.gl_enum(),
                glow::TEXTURE_2D,
                Some(texture.raw()),
                0,
            );
        }
        let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        status
    };
    check_error(
        gl,
        &format!("re-attaching the textures of framebuffer `{}`", fbo.label),
    )?;
    if status != glow::FRAMEBUFFER_COMPLETE {
        return Err(deferred_msaa::Error::FramebufferIncomplete {
            label: fbo.label.clone(),
            status: framebuffer_status_name(status),
        }
        .into());
    }
    fbo.width = depth.width;
    fbo.height = depth.height;
    fbo.attachments = attachments;
    Ok(())
}

/// Run `f` between a timer's begin and end; the milliseconds it took.
pub(crate) fn timed(
    gl: &glow::Context,
    timer: &mut GpuTimer,
    f: impl FnOnce() -> Result<()>,
) -> Result<f64> {
    timer.begin(gl);
    let result = f();
    let ms = timer.end(gl);
    result.map(|()| ms)
}

/// The demo deferred renderer; see the [module documentation](self).
pub struct Renderer {
    /// The selective-AA flag of objects that opted out of anti-aliasing,
    /// when the scene has any.
    opt_out_flag: Option<SelectionFlag>,
    /// The options the frame runs with: those asked for with the plan's
    /// layout, sample count and method.
    options: RenderOptions,
    /// The options as asked for ([`Renderer::options`]).
    requested: RenderOptions,
    plan: Plan,
    needs: SceneNeeds,
    plan_context: PlanContext,
    /// `options.depth_mode` as decided for this context and layout (never `Auto`).
    depth_mode: DepthMode,
    clip: ClipControl,
    scene_name: String,
    extent: Option<SceneExtent>,
    warnings: Vec<String>,
    camera: Camera,
    background: Background,
    lights: Vec<Light>,
    scene: GpuScene,
    passes: Passes,
    frame: Frame,
    decal_hook: Option<DecalHook>,
    /// Whether the G-buffer holds the first layer again after the frame
    /// ([`Renderer::set_keep_gbuffer`]).
    keep_gbuffer: bool,
    /// Every anti-aliasing technique with what it has built; the one that
    /// renders `options.aa` runs the frame's method-specific steps.
    techniques: Techniques,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("options", &self.options)
            .field("depth_mode", &self.depth_mode)
            .field("samples", &self.samples())
            .field("objects", &self.scene.meshes.len())
            .field("lights", &self.lights.len())
            .field("decal_hook", &self.decal_hook.is_some())
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Build every program, upload the scene's meshes and textures (once),
    /// and allocate the targets for `options`.
    ///
    /// `loader` looks up GL entry points glow does not wrap (`glClipControl`,
    /// for reversed-Z; `glIsEnabledi` and `glGetBooleani_v`, which the
    /// retrofit's saved state needs: [`load_state_functions`](deferred_msaa::gl::load_state_functions))
    /// for the current context: the host's
    /// `eglGetProcAddress` or equivalent, e.g.
    /// `|name| ctx.get_proc_address(name)` with a
    /// [`HeadlessContext`](crate::context::HeadlessContext).
    ///
    /// Before allocating, the scene-adaptive [`Plan`] picks the layout and
    /// applies the memory budget, and the layout is checked against how far
    /// the scene reaches from the camera; each finding is logged with
    /// `log::warn!` and kept ([`Renderer::warnings`]). Errors: invalid
    /// options, a layout the scene cannot do without,
    /// [`Error::MemoryBudget`](deferred_msaa::Error::MemoryBudget) with a strict budget, and
    /// [`Error::Unsupported`](deferred_msaa::Error::Unsupported) for [`DepthMode::Reversed`] on a context
    /// without `glClipControl`.
    pub fn new(
        gl: &glow::Context,
        loader: impl Fn(&str) -> *const c_void,
        scene: &Scene,
        requested: &RenderOptions,
    ) -> Result<Self> {
        requested.validate()?;
        deferred_msaa::gl::load_state_functions(&loader)?;
        sparse::check_support(gl, &requested.aa)?;
        let needs = SceneNeeds::of(scene);
        let plan_context = PlanContext::query(gl, &requested.layout);
        let plan = Plan::for_needs(&needs, &plan_context, requested)?;
        let active = plan.apply(requested);
        let options = &active;
        let slots = GBufferSlots::of(&options.layout)?;
        let clip = ClipControl::load(&loader, Capabilities::query(gl).clip_control);
        let depth_mode = depth::resolve_mode(gl, options.depth_mode, &clip, options.layout.depth)?;
        let extent = SceneExtent::of(scene);
        let mut warnings = depth::warnings(&options.layout, &scene.camera, depth_mode, extent);
        warnings.extend(plan.warnings.iter().cloned());
        for w in &warnings {
            log::warn!("scene `{}` ({depth_mode} depth): {w}", scene.name);
        }
        let (passes, gpu_scene, frame, opt_out_flag) = Made::build(gl, |made| {
            let passes = made.keep(Passes::new(gl, slots, options.smaa.is_some())?);
            let gpu_scene = made.keep(GpuScene::new(gl, scene)?);
            // Objects that opted out of anti-aliasing (`Object::antialias`, a
            // glTF `extras` field) write 0 into `color.a`: the resolve reads it
            // as its selective-AA flag unless the options name another.
            let opt_out_flag = gpu_scene
                .gbuffer_items
                .iter()
                .any(|i| !i.antialias)
                .then_some(SelectionFlag {
                    attachment: ColorAttachment(slots.color),
                    component: 3,
                });
            let frame = made.keep(Frame::new(gl, options, opt_out_flag)?);
            Ok::<_, Error>((passes, gpu_scene, frame, opt_out_flag))
        })?;
        let mut renderer = Renderer {
            opt_out_flag,
            options: options.clone(),
            requested: requested.clone(),
            plan,
            needs,
            plan_context,
            depth_mode,
            clip,
            scene_name: scene.name.clone(),
            extent,
            warnings,
            camera: scene.camera,
            background: scene.background,
            lights: scene.lights.clone(),
            scene: gpu_scene,
            passes,
            frame,
            decal_hook: None,
            keep_gbuffer: true,
            techniques: Techniques::new(),
        };
        if let Err(e) = renderer.prepare_technique(gl, None) {
            renderer.destroy(gl);
            return Err(e);
        }
        Ok(renderer)
    }

    /// The options as given to [`Renderer::new`] or [`Renderer::set_options`].
    // The field `options` holds what the frame runs with (the plan applied).
    #[allow(clippy::misnamed_getters)]
    pub fn options(&self) -> &RenderOptions {
        &self.requested
    }

    /// The options the frame runs with: [`Renderer::options`] with the
    /// plan's layout, sample count and method (they differ where the plan
    /// trimmed the layout or the memory budget stepped the count down).
    pub fn effective_options(&self) -> &RenderOptions {
        &self.options
    }

    /// The scene-adaptive plan in effect (see [`plan`]).
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The G-buffer layout in use: the plan's (attachment `k` of
    /// [`Renderer::gbuffer`] is `layout().colors[k]`).
    pub fn layout(&self) -> &GBufferLayout {
        &self.options.layout
    }

    /// The scene camera the frame is rendered with.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Render the next frames from `camera` instead: nothing on the GPU
    /// changes, and a temporal method ([`AaMode::Taa`]) reprojects its
    /// history from the camera of the frame before. The precision check
    /// runs again for the new distances (new findings are logged,
    /// [`Renderer::warnings`]).
    pub fn set_camera(&mut self, camera: Camera) {
        if camera == self.camera {
            return;
        }
        self.camera = camera;
        let mut warnings =
            depth::warnings(&self.options.layout, &camera, self.depth_mode, self.extent);
        warnings.extend(self.plan.warnings.iter().cloned());
        if warnings != self.warnings {
            for w in warnings.iter().filter(|w| !self.warnings.contains(w)) {
                log::warn!(
                    "scene `{}` ({} depth): {w}",
                    self.scene_name,
                    self.depth_mode
                );
            }
        }
        self.warnings = warnings;
    }

    /// Forget what earlier frames left to the next (the history of
    /// [`AaMode::Taa`]; nothing for the other methods): the next frame
    /// starts afresh, as after [`Renderer::new`]. [`Renderer::set_options`]
    /// does this itself (a new size or method invalidates the history); a
    /// caller that cuts to another shot calls it.
    pub fn reset_history(&mut self) {
        self.techniques.active_mut(&self.options.aa).reset_history();
    }

    /// The depth convention in effect: [`RenderOptions::depth_mode`] as
    /// decided for this context and layout, never [`DepthMode::Auto`].
    pub fn depth_mode(&self) -> DepthMode {
        self.depth_mode
    }

    /// The depth the G-buffer is cleared to and background pixels keep:
    /// 1.0, or 0.0 with reversed-Z.
    pub fn clear_depth(&self) -> f32 {
        self.depth_mode.clear_depth()
    }

    /// What the precision check found for the current layout and depth
    /// mode: FP16 positions overflowing, or depth too coarse for the scene's
    /// detail at its farthest distance (see
    /// [`precision_warnings`](crate::gbuffer::precision_warnings)). Empty
    /// when the layout holds the scene.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The real samples per pixel of the G-buffer pass (1 without multisampling).
    pub fn samples(&self) -> u32 {
        if let Some(n) = self.techniques.active(&self.options.aa).samples() {
            return n;
        }
        self.frame
            .retrofit
            .as_ref()
            .map_or(1, MsaaRetrofit::samples)
    }

    /// Render one frame (see the [module documentation](self) for the passes).
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
            (self.options.smaa, smaa.as_ref(), targets.smaa.as_ref())
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
    fn prepare_technique(
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

    /// The state of the technique that renders the current method, when it
    /// is a `T` ([`technique::Gbaa`], [`technique::Complex`],
    /// [`technique::Sparse`]); `None` with other methods. For example
    /// `renderer.technique::<Gbaa>().and_then(Gbaa::edge_textures)`.
    pub fn technique<T: technique::TechniqueState>(&self) -> Option<&T> {
        self.techniques.get::<T>(&self.options.aa)
    }

    /// How many pixels the per-sample lighting pass lit in the last frame
    /// (`GL_SAMPLES_PASSED` around it): every pixel with
    /// [`AaMode::PerSample`], the complex ones with [`AaMode::Complex`].
    /// `None` with other modes, before the first frame after
    /// [`Renderer::set_options`], or without a query object.
    pub fn per_sample_pixels(&self) -> Option<u64> {
        match self
            .techniques
            .get::<technique::PerSample>(&self.options.aa)
        {
            Some(p) => p.lit_pixels(),
            None => self
                .techniques
                .get::<technique::Complex>(&self.options.aa)
                .and_then(technique::Complex::lit_pixels),
        }
    }

    /// Which pixels the method treated as complex in the last frame, row 0
    /// at the top (255 = complex, 0 = simple):
    /// - resolve methods: the pixels the resolve took its slow path on
    ///   (samples whose depth keys differ; every pixel with the fast path
    ///   off), found by running the last frame's resolve again with its
    ///   complex-pixel output into a scratch mask (the G-buffer is untouched);
    /// - [`AaMode::Complex`]: its stencil mask ([`technique::Complex::read_mask`]);
    /// - [`AaMode::PerSample`]: every pixel (each is lit per sample).
    ///
    /// `None` without multisampling or before the first frame after
    /// [`Renderer::set_options`] (`complex`).
    pub fn read_complex_pixels(&mut self, gl: &glow::Context) -> Result<Option<image::GrayImage>> {
        let input = ComplexPixelsInput {
            resolve_frame: self.resolve_frame(),
            retrofit: self.frame.retrofit.as_mut(),
            width: self.options.width,
            height: self.options.height,
        };
        self.techniques
            .active(&self.options.aa)
            .complex_pixels(gl, input)
    }

    /// The last frame's second-layer coverage `α` (`median:layers=2` and
    /// the other resolve methods with two layers) as 0..255, row 0 at the
    /// top: 0 where a pixel has one cluster of samples, else the second
    /// cluster's share of the two kept ones. `None` with one layer.
    pub fn read_second_layer_coverage(
        &mut self,
        gl: &glow::Context,
    ) -> Result<Option<image::GrayImage>> {
        let Some(coverage) = self
            .frame
            .retrofit
            .as_ref()
            .and_then(MsaaRetrofit::second_layer_coverage)
        else {
            return Ok(None);
        };
        let mut readback = crate::readback::Readback::new(gl)?;
        let read = readback.read(gl, coverage, 1);
        readback.destroy(gl);
        let read = read?;
        Ok(Some(image::GrayImage::from_fn(
            coverage.width,
            coverage.height,
            |x, y| image::Luma([(read.get(0, x, y)[0].clamp(0.0, 1.0) * 255.0).round() as u8]),
        )))
    }

    /// The fraction of pixels [`Renderer::read_complex_pixels`] marks.
    pub fn complex_pixel_fraction(&mut self, gl: &glow::Context) -> Result<Option<f64>> {
        Ok(self.read_complex_pixels(gl)?.map(|mask| {
            let marked = mask.pixels().filter(|p| p[0] != 0).count();
            marked as f64 / (mask.width() as f64 * mask.height() as f64).max(1.0)
        }))
    }

    /// Install (or remove, with `None`) the decal hook.
    ///
    /// It is called once per frame after the resolve (without multisampling:
    /// after the G-buffer pass) and before lighting, with the resolved
    /// single-sample G-buffer's framebuffer bound to `GL_FRAMEBUFFER` (so for
    /// both reading and drawing; all its colour attachments are draw
    /// buffers, colour `k` on draw buffer `k`) and the viewport covering it.
    /// The hook may read and write any attachment — draw decals into the
    /// colour, normal or emissive attachments, read positions — with
    /// whatever programs and state it needs, and need not restore GL state:
    /// every later pass sets what it uses. It must not delete or re-attach
    /// the G-buffer's objects, and must not begin a `GL_TIME_ELAPSED` query
    /// (it runs inside the renderer's own). A GL error it leaves fails the frame.
    /// Depth follows [`Renderer::depth_mode`]: with reversed-Z the clip
    /// control is `GL_ZERO_TO_ONE` during the hook, the nearer fragment
    /// passes GREATER and the background's depth is 0.0. Draw with the
    /// [`DecalTarget`]'s matrices: they are the frame's own, jitter
    /// included under [`AaMode::Taa`].
    ///
    /// With [`AaMode::PerSample`] and [`AaMode::Complex`] the hook still
    /// gets the resolved G-buffer (transparent objects are depth-tested
    /// against it), but lighting reads the multisampled samples, so what
    /// the hook draws is not lit.
    pub fn set_decal_hook(&mut self, hook: Option<DecalHook>) {
        self.plan.set_decals(hook.is_some());
        self.decal_hook = hook;
    }

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
    ///   with a new layout too, see [`DepthMode::Auto`]).
    ///
    /// The precision check runs again before allocating; new findings are
    /// logged. New objects are made before old ones are freed: on error the
    /// renderer keeps rendering with its previous options.
    pub fn set_options(&mut self, gl: &glow::Context, requested: &RenderOptions) -> Result<()> {
        requested.validate()?;
        sparse::check_support(gl, &requested.aa)?;
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
        let (colors, depth, targets) = Made::build(gl, |made| {
            let (colors, depth) =
                GBuffer::allocate_textures(gl, &options.layout, options.width, options.height)?;
            let (colors, depth) = (made.keep(colors), made.keep(depth));
            let targets = made.keep(Targets::new(
                gl,
                &depth,
                options.fxaa,
                options.smaa.is_some(),
            )?);
            Ok::<_, Error>((colors, depth, targets))
        })?;
        let gb = &mut self.frame.gbuffer;
        if let Err(e) = attach_gbuffer_textures(gl, &mut gb.fbo, &colors, &depth) {
            let _ = attach_gbuffer_textures(gl, &mut gb.fbo, &gb.colors, &gb.depth);
            targets.destroy(gl);
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
            free_textures(gl, colors, Some(depth));
            return Err(e);
        }
        free_textures(gl, old_colors, Some(old_depth));
        std::mem::replace(&mut self.frame.targets, targets).destroy(gl);
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
        let new_smaa = if options.smaa.is_some() && self.frame.targets.smaa.is_none() {
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
            self.frame.targets.smaa = new_smaa;
        } else if options.smaa.is_none() {
            if let Some(t) = self.frame.targets.smaa.take() {
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
    fn align_first_layer_restore(&mut self, gl: &glow::Context) -> Result<()> {
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

    /// The resolved single-sample G-buffer (the host G-buffer).
    pub fn gbuffer(&self) -> &GBuffer {
        &self.frame.gbuffer
    }

    /// The retrofit, when multisampling.
    pub fn retrofit(&self) -> Option<&MsaaRetrofit> {
        self.frame.retrofit.as_ref()
    }

    /// Profile the retrofit's steps from the next frame on, or stop
    /// ([`MsaaRetrofit::set_profiling`]); the renderer times its own
    /// second-layer passes into the same profile. Nothing with no retrofit.
    pub fn set_profiling(&mut self, on: bool) {
        if let Some(retrofit) = self.frame.retrofit.as_mut() {
            retrofit.set_profiling(on);
        }
    }

    /// The camera's projection at this size in the frame's depth mode:
    /// standard GL depth (−1..1, [`Camera::projection`]), or reversed-Z for
    /// `GL_ZERO_TO_ONE` (near → 1; far → 0, or 0 at infinity). With
    /// [`AaMode::Taa`] the frame's passes draw with it moved by the frame's
    /// sub-pixel jitter ([`technique::Taa::last_jitter`]).
    pub fn projection(&self) -> Mat4 {
        let aspect = self.options.width as f32 / self.options.height as f32;
        depth::projection(&self.camera, aspect, self.depth_mode)
    }

    /// What the resolve is given each frame: the projection in the frame's
    /// depth mode.
    pub fn resolve_frame(&self) -> ResolveFrame {
        let mode = if self.depth_mode.is_reversed() {
            ResolveDepthMode::ReversedZ
        } else {
            ResolveDepthMode::Standard
        };
        ResolveFrame::from(self.projection()).with_depth_mode(mode)
    }

    /// The lighting fragment shader exactly as compiled (preamble, defines
    /// and body). It does not depend on multisampling: the same source
    /// lights the G-buffer with and without MSAA (its defines follow only
    /// the attachment set of [`Renderer::layout`]).
    pub fn lighting_program_source(&self) -> String {
        LightingPass::source(self.passes.lighting.slots())
    }

    /// The fragment shader of [`AaMode::PerSample`] and [`AaMode::Complex`]'s
    /// per-sample lighting exactly as compiled: `lighting.frag` (its lights,
    /// BRDF and sample shading, with `LIGHTING_FUNCTIONS_ONLY`), then
    /// `lighting_per_sample.frag`'s reading of one sample. The per-pixel
    /// [`Renderer::lighting_program_source`] is not changed by these modes.
    pub fn per_sample_lighting_program_source(&self) -> String {
        PerSampleLightingPass::source(self.passes.geometry.slots())
    }

    /// The model fragment shader exactly as compiled; like the lighting
    /// source it does not change with MSAA.
    pub fn geometry_program_source(&self) -> String {
        GeometryPass::fragment_source(self.passes.geometry.slots())
    }

    /// Read the final image (after tonemapping and FXAA or SMAA); row 0 is the top.
    pub fn read_final(&self, gl: &glow::Context) -> Result<image::RgbaImage> {
        self.frame
            .targets
            .final_target()
            .read_rgba8(gl, "the final image")
    }

    /// The final image's texture (RGBA8, sRGB-encoded values).
    pub fn final_texture(&self) -> TextureRef {
        TextureRef::from(&self.frame.targets.final_target().texture)
    }

    /// The HDR target's texture (RGBA16F, linear radiance after lighting and
    /// transparent objects).
    pub fn hdr_texture(&self) -> TextureRef {
        TextureRef::from(&self.frame.targets.hdr.texture)
    }

    /// Free every GL object the renderer created.
    pub fn destroy(self, gl: &glow::Context) {
        self.passes.destroy(gl);
        self.scene.destroy(gl);
        self.frame.destroy(gl);
        self.techniques.destroy(gl);
    }
}
