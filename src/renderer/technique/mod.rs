//! The anti-aliasing techniques of the frame: one type per technique (the
//! four resolve methods of [`AaMode::Resolve`] share one), each in its own
//! module beside the passes it adds.
//!
//! The renderer runs one frame for every technique (see the
//! [renderer's documentation](super)) and asks the technique for the steps
//! that differ: where the G-buffer pass draws and what it draws
//! (`Technique::geometry_target`, `Technique::draw_gbuffer`), what runs
//! after it (`Technique::after_geometry`: the resolve, for the methods
//! with multisampled twins), how the HDR target is lit
//! (`Technique::light`) and what follows the tonemap
//! (`Technique::tonemap_target`, `Technique::post`). Everything a
//! technique builds or allocates it owns and frees in
//! `Technique::destroy`.
//!
//! What is known of a technique before anything is built (its method
//! names and how their options parse, whether it draws into the
//! multisampled twins, which passes the plan lists for it, ...) is its
//! `Kind`, a unit type beside it that the options, the plan, the bench and
//! the command line ask.
//!
//! Adding a technique: its [`AaMode`] variant (the public option that
//! names it, with its options), a module here with a type implementing
//! `Technique` and a unit type implementing `Kind`, and its line in
//! `KINDS`.
//!
//! The public types here are the techniques whose own state a renderer
//! lends out, through [`Renderer::technique`](super::Renderer::technique).

mod complex;
mod gbaa;
mod none;
mod per_sample;
mod resolve;
mod sparse;
mod taa;

use super::background_copy::{BackgroundCopyPass, CopyTarget};
use super::frame_pass::Pass;
use super::geometry::{GeometryPass, GeometryTarget};
use super::lighting::{LightBatch, LightingPass, StandIns};
use super::mesh::GpuScene;
use super::pass::{LightTarget, StencilSelect};
use super::targets::{ColorTarget, Targets};
use super::{AaMode, GBufferSlots, RenderOptions, timed};
use crate::Result;
use crate::frame::Frame as ResolveFrame;
use crate::gbuffer::GBuffer;
use crate::gl::{GpuTimer, Texture2d, VertexArray};
use crate::retrofit::MsaaRetrofit;
pub use complex::Complex;
pub use gbaa::Gbaa;
use glam::{DMat4, Mat4};
pub(crate) use per_sample::PerSample;
pub(crate) use resolve::second_layer_bytes;
pub use sparse::Sparse;
use std::any::Any;
pub use taa::Taa;

/// Every technique, once. Adding a technique is one line here.
pub(crate) static KINDS: [&dyn Kind; 7] = [
    &none::Kind,
    &resolve::Kind,
    &per_sample::Kind,
    &complex::Kind,
    &gbaa::Kind,
    &sparse::Kind,
    &taa::Kind,
];

/// What is known of a technique before anything is built: its method names
/// and how they parse, and the facts the options, the plan, the bench and
/// the command line ask of it. The defaults are `none`'s.
pub(crate) trait Kind: Sync {
    /// The method names it renders, as `--method` and bench entries spell them.
    fn methods(&self) -> &'static [&'static str];

    /// The technique's name: its one method's (`resolve` for the four
    /// resolve methods). Methods of one technique can share a renderer.
    fn name(&self) -> &'static str {
        self.methods()[0]
    }

    /// Whether it renders `aa`.
    fn renders(&self, aa: &AaMode) -> bool;

    /// The method name of `aa`, which it renders.
    fn method_name(&self, _aa: &AaMode) -> &'static str {
        self.name()
    }

    /// The mode for `method` (one of [`Kind::methods`]) with `options`, the
    /// parts of a method spec after its colons; errors are one line that
    /// names `spec`.
    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode>;

    /// The options [`Kind::parse`] takes, for error messages; `None`: none.
    fn options_help(&self) -> Option<&'static str> {
        None
    }

    /// Whether the G-buffer pass draws into the retrofit's multisampled twins.
    fn draws_into_twins(&self) -> bool {
        false
    }

    /// Whether it renders more than one sample per pixel, so that
    /// [`RenderOptions::samples`] applies.
    fn takes_samples(&self) -> bool {
        self.draws_into_twins()
    }

    /// Whether lighting lights samples of the twins rather than resolved pixels.
    fn lights_per_sample(&self) -> bool {
        false
    }

    /// Whether its G-buffer pass does more than `none`'s (the bench then
    /// counts its G-buffer time beyond `none`'s as anti-aliasing time).
    fn adds_geometry(&self) -> bool {
        false
    }

    /// Whether its lighting does more than `none`'s per-pixel pass (the
    /// bench then counts its lighting time beyond `none`'s likewise).
    fn adds_lighting(&self) -> bool {
        self.lights_per_sample()
    }

    /// Whether the G-buffer pass fills the G-buffer's attachments.
    fn fills_gbuffer(&self) -> bool {
        true
    }

    /// The plan's lighting passes for `aa`, in frame order.
    fn lighting_passes(&self, _aa: &AaMode) -> Vec<Pass> {
        vec![Pass::Lighting]
    }

    /// The plan's passes after the tonemap and before FXAA.
    fn post_passes(&self) -> Vec<Pass> {
        Vec::new()
    }

    /// The plan's name for its G-buffer program.
    fn geometry_program(&self) -> &'static str {
        "geometry"
    }

    /// The plan's names of the programs it compiles beside the G-buffer,
    /// resolve and lighting programs, in frame order.
    fn own_programs(&self) -> &'static [&'static str] {
        &[]
    }

    /// How many frames `aa` must render, from a fresh state, before its
    /// image is what a still camera settles on (a temporal method's
    /// history); the bench renders them before it measures a still frame.
    fn warmup_frames(&self, _aa: &AaMode) -> u32 {
        0
    }

    /// The technique, in an empty state (nothing is built before it is
    /// first used).
    fn build(&self) -> Box<dyn Technique>;
}

/// The kind of the technique that renders `aa`.
pub(crate) fn kind_of(aa: &AaMode) -> &'static dyn Kind {
    // Every AaMode has its kind: the registry's own tests check it.
    KINDS
        .iter()
        .copied()
        .find(|k| k.renders(aa))
        .unwrap_or_else(|| unreachable!("no technique renders {aa:?}"))
}

/// The kind whose methods include `method`.
pub(crate) fn kind_named(method: &str) -> Option<&'static dyn Kind> {
    KINDS
        .iter()
        .copied()
        .find(|k| k.methods().contains(&method))
}

/// Every method name, in the registry's order.
pub(crate) fn method_names() -> Vec<&'static str> {
    KINDS
        .iter()
        .flat_map(|k| k.methods().iter().copied())
        .collect()
}

/// The error for options given to a method that takes none.
pub(crate) fn no_options(method: &str, options: &[&str], spec: &str) -> Result<()> {
    match options.first() {
        None => Ok(()),
        Some(o) => Err(crate::Error::invalid(format!(
            "method `{spec}`: `{method}` takes no options (got `:{o}`)"
        ))),
    }
}

/// A technique whose state [`Renderer::technique`](super::Renderer::technique)
/// lends out: [`Gbaa`], [`Complex`], [`Sparse`] or [`Taa`].
pub trait TechniqueState: std::any::Any + sealed::Sealed {}

mod sealed {
    /// Only this crate's techniques are [`TechniqueState`](super::TechniqueState)s.
    pub trait Sealed {}
    impl Sealed for super::Gbaa {}
    impl Sealed for super::Complex {}
    impl Sealed for super::Sparse {}
    impl Sealed for super::Taa {}
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

/// The registry's techniques, with their state.
pub(crate) struct Techniques {
    all: Vec<(&'static dyn Kind, Box<dyn Technique>)>,
}

impl std::fmt::Debug for Techniques {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.all.iter().map(|(_, t)| t))
            .finish()
    }
}

impl Techniques {
    /// Every technique, nothing built yet.
    pub(crate) fn new() -> Self {
        Techniques {
            all: KINDS.iter().map(|&k| (k, k.build())).collect(),
        }
    }

    /// The technique that renders `aa`.
    pub(crate) fn active(&self, aa: &AaMode) -> &dyn Technique {
        let position = self.position(aa);
        &*self.all[position].1
    }

    /// The technique that renders `aa`, to prepare or draw with.
    pub(crate) fn active_mut(&mut self, aa: &AaMode) -> &mut dyn Technique {
        let position = self.position(aa);
        &mut *self.all[position].1
    }

    fn position(&self, aa: &AaMode) -> usize {
        // Every AaMode has its technique: the registry's own tests check it.
        self.all
            .iter()
            .position(|(k, _)| k.renders(aa))
            .unwrap_or_else(|| unreachable!("no technique renders {aa:?}"))
    }

    /// The technique of type `T` when it is the one that renders `aa`.
    pub(crate) fn get<T: Any>(&self, aa: &AaMode) -> Option<&T> {
        self.active(aa).as_any().downcast_ref::<T>()
    }

    /// Tell every technique that the options changed to ones `aa` renders.
    pub(crate) fn options_changed(&mut self, gl: &glow::Context, aa: &AaMode) {
        for (k, t) in &mut self.all {
            t.options_changed(gl, k.renders(aa));
        }
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        for (_, t) in self.all {
            t.destroy(gl);
        }
    }
}

/// The bytes the technique that renders `options.aa` allocates beside the
/// G-buffer and its twins, before anything is built (for the plan).
pub(crate) fn planned_memory(options: &RenderOptions) -> u64 {
    // An empty technique holds no GL object, so it is dropped, not destroyed.
    kind_of(&options.aa).build().memory(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolve::{ResolveMethod, ResolveSettings};

    #[test]
    fn every_method_has_one_technique() {
        let modes = [
            AaMode::None,
            AaMode::Resolve(ResolveSettings::default()),
            AaMode::Resolve(ResolveSettings {
                method: ResolveMethod::Average,
                ..ResolveSettings::default()
            }),
            AaMode::PerSample,
            AaMode::Complex,
            AaMode::Gbaa,
            AaMode::Sparse(Default::default()),
            AaMode::Taa(Default::default()),
        ];
        for aa in modes {
            assert_eq!(KINDS.iter().filter(|k| k.renders(&aa)).count(), 1, "{aa:?}");
            // A mode's method name parses back to a mode of the same kind.
            let name = kind_of(&aa).method_name(&aa);
            let kind = kind_named(name).expect("a method name of the registry");
            assert_eq!(kind.name(), kind_of(&aa).name(), "{aa:?}");
            let parsed = kind
                .parse(name, &[], name)
                .expect("a bare method name parses");
            assert_eq!(kind_of(&parsed).name(), kind.name());
        }
        let mut names = method_names();
        let all = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), all, "a method name belongs to one technique");
    }
}
