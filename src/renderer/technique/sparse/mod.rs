//! Method `sparse` ([`AaMode::Sparse`]): the G-buffer pass becomes a
//! multisampled depth pre-pass, a set-up pass and a pass that writes
//! per-pixel lists of G-buffer blocks, and lighting lights the lists
//! (`sparse*.frag`, each beside its module here: `geometry`, `lighting`;
//! the design is documented on [`SparseOptions`]).

mod geometry;
mod lighting;
pub(crate) mod options;
mod shader;
pub(crate) mod state;
pub(crate) mod targets;

use super::contract::{FrameParts, GeometryStep, LightingStep, Setup, Technique, TechniqueState};
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::pass::shared::{LightTarget, StencilSelect};
use crate::{Error, Result};
use options::{SparseOptions, SparseStats};
pub(crate) use state::check_support;
use state::{BuildParams, LightParams, SparseState};
use std::any::Any;
use targets::SparseMemory;

/// The multisampled G-buffer as per-pixel linked lists of blocks
/// ([`AaMode::Sparse`]), as
/// [`Renderer::technique`](crate::renderer::Renderer::technique) lends it:
/// its memory, counters and one-sample pixels.
#[derive(Debug, Default)]
pub struct Sparse {
    /// The programs (kept once built) and the targets (they follow the
    /// options, and go when another method is chosen).
    state: SparseState,
}

impl TechniqueState for Sparse {}
impl super::contract::sealed::Sealed for Sparse {}

impl Sparse {
    /// The GPU memory it has allocated, by part, once allocated.
    /// [`SparseMemory::total`] is what the bench reports as its G-buffer bytes.
    pub fn allocated(&self) -> Option<SparseMemory> {
        self.state.memory()
    }

    /// What the last frame's G-buffer pass counted: the pool's use and the
    /// pixels that fell back to one sample because it ran out, read back
    /// from the atomic counters (this waits for the frame). `None` before
    /// the first frame.
    pub fn stats(&self, gl: &glow::Context) -> Result<Option<SparseStats>> {
        self.state.stats(gl)
    }

    /// The last frame's one-sample pixels, read back from the heads (row 0
    /// at the top): [`MASK_OVERFLOW`] where the pool ran out,
    /// [`MASK_SINGLE`] where a visible fragment is not anti-aliased (object
    /// flag or depth limit), 0 elsewhere (pixels outside
    /// [`SparseOptions::region`] are not marked: the region alone decides
    /// them). `None` before the first frame.
    ///
    /// [`MASK_OVERFLOW`]: crate::renderer::MASK_OVERFLOW
    /// [`MASK_SINGLE`]: crate::renderer::MASK_SINGLE
    /// [`SparseOptions::region`]: crate::renderer::SparseOptions::region
    pub fn read_mask(&self, gl: &glow::Context) -> Result<Option<image::GrayImage>> {
        self.state.read_mask(gl)
    }
}

impl Technique for Sparse {
    /// Its targets depend on the options alone, so they are allocated
    /// while options change too.
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        _frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        self.state.prepare(gl, setup.options)
    }

    fn options_changed(&mut self, gl: &glow::Context, active: bool) {
        if !active {
            self.state.release(gl);
        }
    }

    /// The lists instead of the G-buffer's colours (which stay cleared; the
    /// set-up pass writes its depth); no background copy.
    fn draw_gbuffer(&self, gl: &glow::Context, step: &GeometryStep<'_>) -> Result<()> {
        let AaMode::Sparse(o) = step.frame.aa else {
            return Ok(());
        };
        let build = BuildParams {
            view: step.view,
            projection: step.projection,
            nearer_func: step.nearer_func,
            clear_depth: step.clear_depth,
            region: o.region,
            max_depth: o.max_depth.unwrap_or(f32::MAX),
        };
        self.state.build_lists(
            gl,
            step.scene,
            step.frame.gbuffer.fbo.raw(),
            step.fullscreen,
            &build,
        )
    }

    fn light(&mut self, gl: &glow::Context, step: &LightingStep<'_>) -> Result<()> {
        let AaMode::Sparse(o) = step.frame.aa else {
            return Ok(());
        };
        let (width, height) = step.size();
        let hdr = LightTarget {
            fbo: step.frame.targets.hdr.fbo.raw(),
            width,
            height,
            stencil: StencilSelect::All,
        };
        let params = LightParams {
            background: step.background(),
            projection: step.projection,
            region: o.region,
        };
        self.state
            .light(gl, hdr, step.fullscreen, step.batches, &params)
    }

    /// The lists, the pool and the multisampled pre-pass depth.
    fn memory(&self, options: &RenderOptions) -> u64 {
        match options.aa {
            AaMode::Sparse(o) => SparseMemory::planned(
                &o,
                options.width,
                options.height,
                options.samples.max(1),
                options.layout.depth,
            )
            .total(),
            _ => 0,
        }
    }

    fn samples(&self) -> Option<u32> {
        self.state.samples()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, gl: &glow::Context) {
        self.state.destroy(gl);
    }
}

/// What is known of `sparse` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["sparse"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        matches!(aa, AaMode::Sparse(_))
    }

    /// `:pool=N`: the block pool's size.
    fn parse(&self, _method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        let mut sparse = SparseOptions::default();
        for option in options {
            match option.split_once('=') {
                Some(("pool", v)) => {
                    let blocks = v.trim().parse::<u32>().map_err(|_| {
                        Error::invalid(format!(
                            "method `{spec}`: `pool={v}` is not a number of blocks"
                        ))
                    })?;
                    sparse.pool_blocks = Some(blocks);
                }
                _ => {
                    return Err(Error::invalid(format!(
                        "method `{spec}`: unknown option `:{option}` (sparse takes :pool=N)"
                    )));
                }
            }
        }
        Ok(AaMode::Sparse(sparse))
    }

    fn options_help(&self) -> Option<&'static str> {
        Some("sparse's :pool=N")
    }

    fn takes_samples(&self) -> bool {
        true
    }

    fn adds_geometry(&self) -> bool {
        true
    }

    fn adds_lighting(&self) -> bool {
        true
    }

    fn fills_gbuffer(&self) -> bool {
        false
    }

    fn lighting_passes(&self, _aa: &AaMode) -> Vec<Pass> {
        vec![Pass::SparseDepth, Pass::SparseLists, Pass::SparseLighting]
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(Sparse::default())
    }
}

/// The fragment shader of the lighting pass exactly as compiled
/// ([`Renderer::sparse_lighting_program_source`](crate::renderer::Renderer::sparse_lighting_program_source)).
pub(crate) fn lighting_program_source() -> String {
    lighting::SparseLightingPass::source()
}
