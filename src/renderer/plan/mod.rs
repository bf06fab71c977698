//! The scene-adaptive plan: what a given scene needs from the G-buffer and
//! the frame, decided from the scene and the context before anything is
//! allocated, so that nothing the scene does not use costs memory or time.
//!
//! Starting from the layout in [`RenderOptions::layout`] (the *full* layout,
//! by default [`GBufferLayout::recommended`]) the plan
//! - leaves out the `emissive` attachment when no material the G-buffer
//!   draws emits: the background it would otherwise carry is single-sampled
//!   anyway, so the lighting pass reads it from the background's own texture,
//!   and the pass that copies the background into every sample goes too
//!   (except with `average`, which blends background samples into edge
//!   pixels through it, unless the background is black);
//! - leaves out the `specular` attachment when every such material writes
//!   the same value into it (F0 and metallic): the lighting pass gets that
//!   value as a uniform, rounded as the attachment would have stored it
//!   (not with `average`, whose edge pixels blend in the cleared background
//!   samples);
//! - narrows an FP32 `position` to FP16 when the scene fits it: every view
//!   coordinate below 65504, half-float spacing at the farthest one no
//!   coarser than the scene's detail and than a quarter of the resolve's
//!   closeness window at this resolution (it never widens what the layout gives);
//! - marks every attachment multisampled or not for the method;
//! - lists the passes that run (no transparent pass without alpha-blended
//!   objects, no FXAA unless asked for, no decal pass without a hook) and
//!   the shader permutations they compile;
//! - estimates the G-buffer's bytes and applies the memory budget
//!   ([`MemoryBudget`](crate::gbuffer::MemoryBudget)): over it, the sample count steps down to the highest
//!   offered count that fits (or to single-sample), with a warning, or the
//!   plan is refused when the budget is strict.
//!
//! [`Renderer`](crate::renderer::Renderer) builds its G-buffer from the plan
//! unless [`RenderOptions::adaptive`] is off; `render --explain [--json]`
//! prints it.

mod decide;
mod needs;
mod parts;
mod report;

use crate::Result;
use crate::gbuffer::{GBufferLayout, gbuffer_bytes};
pub use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::technique;
use crate::scene::Scene;
use decide::{
    Decisions, decide_emissive, decide_passes, decide_position, decide_samples, decide_specular,
    permutations, planned_attachments,
};
pub use needs::{PlanContext, SceneNeeds, SpecularResponse};
pub use parts::{LeftOut, Permutation, PlannedAttachment};

/// The plan for one scene, context and set of options (see the
/// [module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The scene's name.
    pub scene: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The method asked for.
    pub requested_aa: AaMode,
    /// The method the frame runs: the one asked for, or `none` when the
    /// budget left no multisampled count.
    pub aa: AaMode,
    /// The sample count asked for.
    pub requested_samples: u32,
    /// The real samples per pixel of the G-buffer (1: single-sample).
    pub samples: u32,
    /// Whether the plan adapted the layout to the scene
    /// ([`RenderOptions::adaptive`]); otherwise it is the full layout.
    pub adaptive: bool,
    /// The G-buffer layout the frame uses.
    pub layout: GBufferLayout,
    /// Its attachments, depth last, with whether each is multisampled.
    pub attachments: Vec<PlannedAttachment>,
    /// The passes that run, in frame order.
    pub passes: Vec<Pass>,
    /// What this scene does without, with why.
    pub left_out: Vec<LeftOut>,
    /// Why things that could have been left out were kept.
    pub kept: Vec<LeftOut>,
    /// The specular value the lighting passes use when the layout has no
    /// `specular` attachment (F0 rgb, metallic), as the attachment would
    /// have stored it.
    pub constant_specular: Option<[f32; 4]>,
    /// The programs the frame compiles and their defines.
    pub permutations: Vec<Permutation>,
    /// Bytes of the planned G-buffer: single-sample textures, plus their
    /// multisampled twins when multisampling, plus what the method keeps
    /// beside them (`gbaa`'s edge buffers; `sparse`'s lists, pool and
    /// multisampled pre-pass depth).
    pub gbuffer_bytes: u64,
    /// The same for FreeSpace Open's layout at the same size and sample count.
    pub full_gbuffer_bytes: u64,
    /// Of `gbuffer_bytes`, what the resolve's second layer keeps (0 with
    /// one layer): its G-buffer, the first layer's copy, its coverage,
    /// depth and selection, the lit copies and the stencil mask.
    pub second_layer_bytes: u64,
    /// The memory budget in bytes.
    pub budget_bytes: u64,
    /// Where the budget came from.
    pub budget_source: String,
    /// Budget warnings (a stepped-down sample count), one line each.
    pub warnings: Vec<String>,
}

impl Plan {
    /// The plan for `scene` on a context described by `context`.
    pub fn for_scene(
        scene: &Scene,
        context: &PlanContext,
        options: &RenderOptions,
    ) -> Result<Plan> {
        Plan::for_needs(&SceneNeeds::of(scene), context, options)
    }

    /// The plan from what the scene needs (see [`SceneNeeds::of`]): the
    /// layout's attachments one decision at a time, then the sample count
    /// under the budget, the attachments, the passes and the bytes.
    pub fn for_needs(
        needs: &SceneNeeds,
        context: &PlanContext,
        options: &RenderOptions,
    ) -> Result<Plan> {
        options.validate()?;
        let mut decisions = Decisions::default();
        let mut layout = options.layout.clone();
        decide_emissive(needs, options, &mut layout, &mut decisions)?;
        let constant_specular = decide_specular(needs, options, &mut layout, &mut decisions)?;
        decide_position(needs, options, &mut layout, &mut decisions);
        layout.validate()?;

        let (budget_bytes, budget_source) = options.memory_budget.resolve(context.driver_memory);
        let (width, height) = (options.width, options.height);
        let budgeted = decide_samples(options, context, &layout, budget_bytes)?;
        let (aa, samples) = (budgeted.aa, budgeted.samples);
        let multisampled = aa.is_multisampled();
        let twin = multisampled.then_some(samples);
        let attachments = planned_attachments(&layout, multisampled);
        let passes = decide_passes(needs, options, &layout, aa, &mut decisions);

        // What a method allocates beside the layout's textures and twins.
        let extra_bytes = technique::planned_memory(&RenderOptions {
            aa,
            layout: layout.clone(),
            ..options.clone()
        });
        let permutations = permutations(&layout, aa, samples);
        // `sparse` stands in for the multisampled layout at its count.
        let full_twin = if aa.takes_samples() && !aa.is_multisampled() {
            Some(options.samples)
        } else {
            twin
        };
        Ok(Plan {
            scene: needs.name.clone(),
            width,
            height,
            requested_aa: options.aa,
            aa,
            requested_samples: options.samples,
            samples,
            adaptive: options.adaptive,
            gbuffer_bytes: gbuffer_bytes(&layout, width, height, twin) + extra_bytes,
            second_layer_bytes: technique::second_layer_bytes(&RenderOptions {
                aa,
                layout: layout.clone(),
                ..options.clone()
            }),
            full_gbuffer_bytes: gbuffer_bytes(
                &GBufferLayout::freespace_open(),
                width,
                height,
                full_twin,
            ),
            layout,
            attachments,
            passes,
            left_out: decisions.left_out,
            kept: decisions.kept,
            constant_specular,
            permutations,
            budget_bytes,
            budget_source,
            warnings: budgeted.warnings,
        })
    }

    /// Whether `pass` runs.
    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }

    /// The options the frame really runs with: `options` with the plan's
    /// layout, sample count and method.
    pub fn apply(&self, options: &RenderOptions) -> RenderOptions {
        RenderOptions {
            layout: self.layout.clone(),
            samples: if self.aa.is_multisampled() {
                self.samples
            } else {
                options.samples
            },
            aa: self.aa,
            ..options.clone()
        }
    }

    /// Record whether a decal hook is installed (the decal pass runs then).
    pub(crate) fn set_decals(&mut self, on: bool) {
        let name = Pass::Decals.name();
        self.passes.retain(|p| *p != Pass::Decals);
        self.left_out.retain(|l| l.name != name);
        if on {
            let at = self
                .passes
                .iter()
                .position(|p| {
                    matches!(
                        p,
                        Pass::Lighting | Pass::ComplexMask | Pass::PerSampleLighting
                    )
                })
                .unwrap_or(self.passes.len());
            self.passes.insert(at, Pass::Decals);
        } else {
            self.left_out.push(LeftOut {
                name: name.into(),
                why: "no decal hook is installed".into(),
            });
        }
    }
}
