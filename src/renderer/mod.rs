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

mod depth;
pub mod frame_pass;
mod mesh;
mod options;
mod pass;
pub mod plan;
mod reconfigure;
mod render;
mod resources;
mod targets;
pub mod technique;
mod timing;

/// The demo renderer's tonemap curve and its inverse as GLSL, for
/// [`LayerMix::Curve`](deferred_msaa::LayerMix::Curve): the declaration of
/// its lit values it makes by default ([`RenderOptions::layer_mix`]).
pub fn tonemap_curve() -> String {
    pass::tonemap::layer_mix_curve()
}

use crate::frame::{DepthMode as ResolveDepthMode, Frame as ResolveFrame};
use crate::gbuffer::{GBuffer, GBufferLayout};
use crate::gl::{Capabilities, ColorAttachment, Made, TextureRef, TimerKind};
use crate::resolve::SelectionFlag;
use crate::retrofit::MsaaRetrofit;
use crate::scene::{Background, Camera, Light, Scene};
use crate::{Error, Result};
pub use depth::DepthMode;
use depth::{ClipControl, SceneExtent};
use glam::Mat4;
use mesh::GpuScene;
pub use options::{AaMode, RenderOptions};
use pass::geometry::GeometryPass;
use pass::lighting::LightingPass;
use pass::lighting_per_sample::PerSampleLightingPass;
use pass::slots::GBufferSlots;
use plan::{Plan, PlanContext, SceneNeeds};
use resources::{Frame, Passes};
use std::ffi::c_void;
pub use technique::smaa::tables as smaa_tables;
pub use technique::smaa::{SmaaEdges, SmaaFilter, SmaaOptions, SmaaOutput, SmaaPreset};
use technique::{ComplexPixelsInput, Techniques};
pub use technique::{
    DEFAULT_POOL_BLOCKS_PER_PIXEL, MASK_OVERFLOW, MASK_SINGLE, MAX_SPARSE_SAMPLES, MAX_TAA_PHASES,
    SparseMemory, SparseOptions, SparseStats, TaaOptions,
};

/// The sources of the renderer's model and lighting shaders, for a host (or
/// a test) that builds the very same programs around its own G-buffer.
pub mod shaders {
    pub use super::pass::geometry::{GEOMETRY_FRAG, GEOMETRY_VERT};
    pub use super::pass::lighting::{AMBIENT, LIGHTING_FRAG, LIGHTS_PER_BATCH, lighting_defines};
}

/// Where one frame's time went, in milliseconds, measured pass by pass with
/// [`GpuTimer`](crate::gl::GpuTimer) (`total_ms` is the sum).
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
        technique::sparse_check_support(gl, &requested.aa)?;
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
        self.frame.final_target().read_rgba8(gl, "the final image")
    }

    /// The final image's texture (RGBA8, sRGB-encoded values).
    pub fn final_texture(&self) -> TextureRef {
        TextureRef::from(&self.frame.final_target().texture)
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

    /// Whether this context can render with `aa`: [`Error::Unsupported`](deferred_msaa::Error::Unsupported),
    /// naming what is missing, when it cannot. Of the methods, only
    /// [`AaMode::Sparse`] needs more than OpenGL 3.2 (the others fall back
    /// where a feature is missing); [`Renderer::new`] and
    /// [`Renderer::set_options`] make the same check.
    pub fn check_support(gl: &glow::Context, aa: &AaMode) -> Result<()> {
        technique::sparse_check_support(gl, aa)
    }

    /// The fragment shader of [`AaMode::Sparse`]'s lighting pass exactly as
    /// compiled: `lighting.frag` (with `LIGHTING_FUNCTIONS_ONLY`),
    /// `tonemap.frag`'s curve, `complex.glsl` (the resolve's selection test),
    /// `sparse.frag`, then `sparse_lighting.frag`.
    pub fn sparse_lighting_program_source(&self) -> String {
        technique::sparse_lighting_source()
    }
}
