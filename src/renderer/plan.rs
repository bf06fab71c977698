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

use crate::gbuffer::{
    DriverMemory, GBufferLayout, HALF_MAX, choose_samples, fmt_bytes, gbuffer_bytes,
};
use crate::gl::{Capabilities, Format};
pub use crate::renderer::frame_pass::Pass;
use crate::renderer::shaders::lighting_defines;
use crate::renderer::technique;
use crate::renderer::{AaMode, RenderOptions};
use crate::resolve::{KeySource, ResolveMethod, ResolveSlot, Window};
use crate::scene::{AlphaMode, Background, Scene};
use crate::{Error, Result};

/// F0 of a dielectric, as `geometry.frag` writes it for metallic 0.
const DIELECTRIC_F0: f32 = 0.04;

/// How fine FP16 positions must be against the resolve's closeness window:
/// at most this fraction of its inner edge (in pixel footprints).
const WINDOW_FRACTION: f64 = 0.25;

/// What the plan reads from a scene, computed once (the renderer keeps it
/// for [`Renderer::set_options`](crate::renderer::Renderer::set_options)).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneNeeds {
    /// The scene's name.
    pub name: String,
    /// Materials drawn into the G-buffer that emit light.
    pub emitters: Vec<String>,
    /// What those materials write into the specular attachment.
    pub specular: SpecularResponse,
    /// Objects drawn by the forward transparent pass (alpha-blended).
    pub transparent_objects: usize,
    /// The largest view-space coordinate (|x|, |y| or |z|) of the scene's
    /// bounds as its camera sees them; `None` for an empty or non-finite scene.
    pub max_coordinate: Option<f64>,
    /// The smallest detail that must stay apart: 1/1000 of the bounds' radius
    /// (as in the renderer's precision check).
    pub detail: Option<f64>,
    /// The camera's vertical field of view, radians.
    pub fov_y: f64,
    /// Whether the background shows anything (it is not plain black).
    pub background_visible: bool,
}

/// The value the G-buffer's materials write into the specular attachment.
#[derive(Clone, Debug, PartialEq)]
pub enum SpecularResponse {
    /// Every material writes this (F0 rgb, metallic), in full precision.
    Uniform([f32; 4]),
    /// The materials differ; why, in words.
    Varying(String),
}

/// What `geometry.frag` writes into the specular attachment for a material,
/// when it is one value (no base-colour texture feeds a metallic F0).
fn specular_of(m: &crate::scene::Material) -> std::result::Result<[f32; 4], String> {
    let metallic = m.metallic.clamp(0.0, 1.0);
    if metallic == 0.0 {
        return Ok([DIELECTRIC_F0, DIELECTRIC_F0, DIELECTRIC_F0, 0.0]);
    }
    if m.base_color_texture.is_some() {
        return Err(format!(
            "material `{}` is metallic with a base-colour texture: its F0 varies per texel",
            m.name
        ));
    }
    // mix(vec3(0.04), base.rgb, metallic), as the shader computes it.
    let f0 = |c: f32| DIELECTRIC_F0 * (1.0 - metallic) + c * metallic;
    Ok([
        f0(m.base_color[0]),
        f0(m.base_color[1]),
        f0(m.base_color[2]),
        metallic,
    ])
}

impl SceneNeeds {
    /// Read `scene`.
    pub fn of(scene: &Scene) -> Self {
        let mut emitters: Vec<String> = Vec::new();
        let mut specular: Option<(String, [f32; 4])> = None;
        let mut varying: Option<String> = None;
        let mut transparent_objects = 0;
        for object in &scene.objects {
            let Some(m) = scene.materials.get(object.material) else {
                continue;
            };
            if m.alpha_mode == AlphaMode::Blend {
                transparent_objects += 1;
                continue;
            }
            if m.is_emissive() && !emitters.contains(&m.name) {
                emitters.push(m.name.clone());
            }
            if varying.is_some() {
                continue;
            }
            match (specular_of(m), &specular) {
                (Err(why), _) => varying = Some(why),
                (Ok(v), None) => specular = Some((m.name.clone(), v)),
                (Ok(v), Some((first, w))) if v != *w => {
                    varying = Some(format!(
                        "materials `{first}` and `{}` differ (F0 {:.3}, metallic {:.2} against F0 {:.3}, metallic {:.2})",
                        m.name, w[0], w[3], v[0], v[3]
                    ));
                }
                (Ok(_), Some(_)) => {}
            }
        }
        let specular = match (varying, specular) {
            (Some(why), _) => SpecularResponse::Varying(why),
            (None, Some((_, v))) => SpecularResponse::Uniform(v),
            // Nothing is drawn into the G-buffer: any constant will do.
            (None, None) => {
                SpecularResponse::Uniform([DIELECTRIC_F0, DIELECTRIC_F0, DIELECTRIC_F0, 0.0])
            }
        };
        let (max_coordinate, detail) = if scene.bounds.is_empty() {
            (None, None)
        } else {
            let view = scene.camera.view.as_dmat4();
            let max = scene
                .bounds
                .corners()
                .iter()
                .map(|c| view.transform_point3(c.as_dvec3()).abs().max_element())
                .fold(0.0f64, f64::max);
            let radius = (scene.bounds.max.as_dvec3() - scene.bounds.min.as_dvec3()).length() * 0.5;
            let detail = radius * 1e-3;
            let ok = max.is_finite() && detail.is_finite() && detail > 0.0;
            (ok.then_some(max), ok.then_some(detail))
        };
        SceneNeeds {
            name: scene.name.clone(),
            emitters,
            specular,
            transparent_objects,
            max_coordinate,
            detail,
            fov_y: f64::from(scene.camera.fov_y),
            background_visible: scene.background != Background::Black,
        }
    }
}

/// What the plan needs to know about the context.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanContext {
    /// Sample counts a multisampled texture of every format the plan may
    /// pick really gets, ascending (llvmpipe: `[4]`).
    pub sample_counts: Vec<u32>,
    /// Free video memory, where the driver reports it.
    pub driver_memory: Option<DriverMemory>,
}

impl PlanContext {
    /// Query the current context for a plan starting from `layout`: the
    /// sample counts every one of its formats (and FP16 positions) gets.
    pub fn query(gl: &glow::Context, layout: &GBufferLayout) -> Self {
        let mut formats: Vec<Format> = layout.colors.iter().map(|a| a.format).collect();
        formats.push(layout.depth);
        formats.push(Format::Rgba16f);
        formats.dedup();
        let mut counts: Option<Vec<u32>> = None;
        let mut seen: Vec<Format> = Vec::new();
        for f in formats {
            if seen.contains(&f) {
                continue;
            }
            seen.push(f);
            let offered = Capabilities::sample_counts_for(gl, f);
            counts = Some(match counts {
                None => offered,
                Some(c) => c.into_iter().filter(|n| offered.contains(n)).collect(),
            });
        }
        PlanContext {
            sample_counts: counts.unwrap_or_default(),
            driver_memory: DriverMemory::query(gl),
        }
    }
}

/// One attachment of the planned G-buffer.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PlannedAttachment {
    /// `color`, `position`, …, `depth`.
    pub name: String,
    /// Its internal format.
    pub format: Format,
    /// Whether the method needs it multisampled (a twin with the plan's
    /// sample count beside the single-sample texture).
    pub multisampled: bool,
}

/// Something the scene does not need, and why.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct LeftOut {
    /// An attachment, a pass, or a format (`position RGBA32F`).
    pub name: String,
    /// Why this scene does without it.
    pub why: String,
}

/// One shader program the frame compiles, with its `#define`s.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Permutation {
    /// The program.
    pub program: String,
    /// Its defines, `NAME` or `NAME=VALUE`.
    pub defines: Vec<String>,
}

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

/// Round `v` as a texture of `format` stores it (unsigned normalised 8-bit
/// or half float; other formats keep it).
fn stored_as(format: Format, v: f32) -> f32 {
    match format {
        Format::R8 | Format::Rg8 | Format::Rgba8 => (v.clamp(0.0, 1.0) * 255.0).round() / 255.0,
        Format::R16f | Format::Rg16f | Format::Rgba16f => {
            let spacing = half_spacing(f64::from(v.abs())) as f32;
            (v / spacing).round() * spacing
        }
        _ => v,
    }
}

/// The spacing of half floats around magnitude `m`.
fn half_spacing(m: f64) -> f64 {
    if m < 2f64.powi(-14) {
        2f64.powi(-24)
    } else {
        2f64.powi(m.log2().floor() as i32 - 10)
    }
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

    /// The plan as JSON (`render --explain --json`; keys as docs/plan.md lists them).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "scene": self.scene,
            "width": self.width,
            "height": self.height,
            "method": self.aa.name(),
            "requested_method": self.requested_aa.name(),
            "samples": self.samples,
            "requested_samples": self.requested_samples,
            "adaptive": self.adaptive,
            "attachments": self.attachments.iter().map(|a| serde_json::json!({
                "name": a.name,
                "format": a.format.name(),
                "multisampled": a.multisampled,
            })).collect::<Vec<_>>(),
            "passes": self.passes.iter().map(|p| p.name()).collect::<Vec<_>>(),
            "left_out": self.left_out,
            "kept": self.kept,
            "constant_specular": self.constant_specular,
            "permutations": self.permutations,
            "gbuffer_bytes": self.gbuffer_bytes,
            "full_gbuffer_bytes": self.full_gbuffer_bytes,
            "second_layer_bytes": self.second_layer_bytes,
            "budget_bytes": self.budget_bytes,
            "budget_source": self.budget_source,
            "warnings": self.warnings,
        })
    }

    /// The plan in words (`render --explain`).
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut t = String::new();
        let method = if self.aa == self.requested_aa {
            self.aa.name().to_string()
        } else {
            format!("{} (asked: {})", self.aa.name(), self.requested_aa.name())
        };
        let _ = writeln!(
            t,
            "plan for `{}` at {}x{}, {method}, {}x{}",
            self.scene,
            self.width,
            self.height,
            self.samples,
            if self.adaptive { "" } else { ", full layout" }
        );
        let _ = writeln!(t, "attachments:");
        for a in &self.attachments {
            let _ = writeln!(
                t,
                "  {:<10} {:<20} {}",
                a.name,
                a.format.name(),
                if a.multisampled {
                    format!("multisampled {}x", self.samples)
                } else {
                    "single-sample".into()
                }
            );
        }
        let names: Vec<&str> = self.passes.iter().map(|p| p.name()).collect();
        let _ = writeln!(t, "passes: {}", names.join(" → "));
        if !self.left_out.is_empty() {
            let _ = writeln!(t, "left out:");
            for l in &self.left_out {
                let _ = writeln!(t, "  {}: {}", l.name, l.why);
            }
        }
        if !self.kept.is_empty() {
            let _ = writeln!(t, "kept:");
            for l in &self.kept {
                let _ = writeln!(t, "  {}: {}", l.name, l.why);
            }
        }
        let _ = writeln!(t, "shaders:");
        for p in &self.permutations {
            let _ = writeln!(
                t,
                "  {}: {}",
                p.program,
                if p.defines.is_empty() {
                    "(no defines)".to_string()
                } else {
                    p.defines.join(" ")
                }
            );
        }
        let _ = writeln!(
            t,
            "G-buffer: {} ({:.0}% of FreeSpace Open's layout at this size and count, {}); budget {} ({})",
            fmt_bytes(self.gbuffer_bytes),
            100.0 * self.gbuffer_bytes as f64 / self.full_gbuffer_bytes.max(1) as f64,
            fmt_bytes(self.full_gbuffer_bytes),
            fmt_bytes(self.budget_bytes),
            self.budget_source
        );
        if let (AaMode::Resolve(settings), true) = (self.aa, self.second_layer_bytes > 0) {
            let _ = writeln!(
                t,
                "second layer: {} of it (its G-buffer and the first layer's copy, coverage, depth, selection, two lit copies, the stencil mask); clusters split by depth window and by normal (cosine below {})",
                fmt_bytes(self.second_layer_bytes),
                settings.normal_threshold
            );
        }
        for w in &self.warnings {
            let _ = writeln!(t, "warning: {w}");
        }
        t
    }
}

/// What the plan left out and kept, with why, in the order decided.
#[derive(Default)]
struct Decisions {
    left_out: Vec<LeftOut>,
    kept: Vec<LeftOut>,
}

impl Decisions {
    fn leave_out(&mut self, name: &str, why: impl Into<String>) {
        self.left_out.push(LeftOut {
            name: name.to_string(),
            why: why.into(),
        });
    }

    fn keep(&mut self, name: &str, why: impl Into<String>) {
        self.kept.push(LeftOut {
            name: name.to_string(),
            why: why.into(),
        });
    }
}

/// Whether `aa` blends background samples into edge pixels (`average`, as
/// a hardware resolve does). The depth-aware resolves never do, so there
/// the emissive attachment only carries the background to background
/// pixels, which its own texture does as well.
fn blends_background(aa: AaMode) -> bool {
    matches!(aa, AaMode::Resolve(s) if s.method == ResolveMethod::Average)
}

/// Emission: the `emissive` attachment goes when no material emits (and
/// `average` does not need it for the background).
fn decide_emissive(
    needs: &SceneNeeds,
    options: &RenderOptions,
    layout: &mut GBufferLayout,
    decisions: &mut Decisions,
) -> Result<()> {
    if layout.index_of("emissive").is_none() {
        return match needs.emitters.first() {
            Some(m) => Err(Error::Layout(format!(
                "material `{m}` of scene `{}` emits but the layout has no `emissive` attachment",
                needs.name
            ))),
            None => Ok(()),
        };
    }
    if !options.adaptive {
        decisions.keep("emissive", "the full layout was asked for");
    } else if let Some(m) = needs.emitters.first() {
        decisions.keep("emissive", format!("material `{m}` emits"));
    } else if blends_background(options.aa) && needs.background_visible {
        decisions.keep(
            "emissive",
            "method `average` blends background samples into edge pixels: the emissive \
             attachment carries the background there",
        );
    } else {
        remove(layout, "emissive");
        decisions.leave_out(
            "emissive",
            "no material emits; the background it would carry is single-sampled, \
             so the lighting pass reads it from the background's own texture",
        );
    }
    Ok(())
}

/// Specular response: the `specular` attachment becomes a uniform of the
/// lighting pass when every material writes one value. The value the
/// lighting passes then use, as the attachment would have stored it.
fn decide_specular(
    needs: &SceneNeeds,
    options: &RenderOptions,
    layout: &mut GBufferLayout,
    decisions: &mut Decisions,
) -> Result<Option<[f32; 4]>> {
    let specular_format = options.layout.attachment("specular").map(|a| a.format);
    let constant = match &needs.specular {
        SpecularResponse::Uniform(v) => Some(v.map(|c| match specular_format {
            Some(f) => stored_as(f, c),
            None => c,
        })),
        SpecularResponse::Varying(_) => None,
    };
    let Some(_) = specular_format else {
        // No attachment: the constant, or the scene cannot be drawn.
        return match (&needs.specular, constant) {
            (_, Some(v)) => Ok(Some(v)),
            (SpecularResponse::Varying(why), _) => Err(Error::Layout(format!(
                "scene `{}` needs a `specular` attachment, which the layout lacks: {why}",
                needs.name
            ))),
            (SpecularResponse::Uniform(_), None) => Ok(None),
        };
    };
    match (&needs.specular, constant) {
        (_, Some(v)) if options.adaptive && !blends_background(options.aa) => {
            remove(layout, "specular");
            decisions.leave_out(
                "specular",
                format!(
                    "every material writes the same specular response (F0 ({:.4}, {:.4}, {:.4}), metallic {:.4}): a uniform of the lighting pass",
                    v[0], v[1], v[2], v[3]
                ),
            );
            Ok(Some(v))
        }
        (SpecularResponse::Varying(why), _) => {
            decisions.keep("specular", why.clone());
            Ok(None)
        }
        _ if options.adaptive => {
            decisions.keep(
                "specular",
                "method `average` blends the cleared background samples into edge pixels' \
                 specular value, which a constant cannot stand for",
            );
            Ok(None)
        }
        _ => {
            decisions.keep("specular", "the full layout was asked for");
            Ok(None)
        }
    }
}

/// Position precision: an FP32 `position` narrows to FP16 when the scene
/// fits it. Without a resolve the default resolve's window still decides,
/// so that every method of a scene gets one layout.
fn decide_position(
    needs: &SceneNeeds,
    options: &RenderOptions,
    layout: &mut GBufferLayout,
    decisions: &mut Decisions,
) {
    let Some(k) = layout.index_of("position") else {
        return;
    };
    if layout.colors[k].format != Format::Rgba32f || !options.adaptive {
        return;
    }
    let settings = Some(options.aa.settings().unwrap_or_default());
    match fp16_fits(needs, settings, options.height) {
        Ok(why) => {
            layout.colors[k].format = Format::Rgba16f;
            decisions.leave_out("position RGBA32F", format!("FP16 holds this scene: {why}"));
        }
        Err(why) => decisions.keep("position RGBA32F", why),
    }
}

/// The method and sample count under the memory budget.
struct Budgeted {
    /// The method asked for, or `none` when no multisampled count fits.
    aa: AaMode,
    /// The real samples per pixel of the G-buffer.
    samples: u32,
    /// A stepped-down sample count, or a single-sample G-buffer over budget.
    warnings: Vec<String>,
}

/// Apply the memory budget: a multisampled method steps its count down to
/// the highest offered count that fits (or to `none`); a single-sample one
/// keeps its method and warns when over.
fn decide_samples(
    options: &RenderOptions,
    context: &PlanContext,
    layout: &GBufferLayout,
    budget_bytes: u64,
) -> Result<Budgeted> {
    let (width, height) = (options.width, options.height);
    let mut warnings = Vec::new();
    if options.aa.is_multisampled() {
        let choice = choose_samples(
            options.samples,
            &context.sample_counts,
            budget_bytes,
            options.memory_budget.strict,
            true,
            |n| gbuffer_bytes(layout, width, height, (n > 1).then_some(n)),
        )?;
        warnings.extend(choice.warning(budget_bytes));
        let (aa, samples) = if choice.samples > 1 {
            (options.aa, choice.samples)
        } else {
            (AaMode::None, 1)
        };
        return Ok(Budgeted {
            aa,
            samples,
            warnings,
        });
    }
    let bytes = gbuffer_bytes(layout, width, height, None);
    if bytes > budget_bytes {
        if options.memory_budget.strict {
            return Err(deferred_msaa::Error::MemoryBudget {
                needed: bytes,
                budget: budget_bytes,
                samples: 1,
            }
            .into());
        }
        warnings.push(format!(
            "memory budget: the single-sample G-buffer needs {}, over the budget of {}; there is no lower sample count to step down to",
            fmt_bytes(bytes),
            fmt_bytes(budget_bytes)
        ));
    }
    // Single-sample methods (`none`, `gbaa`, `sparse`) keep their method.
    Ok(Budgeted {
        aa: options.aa,
        samples: 1,
        warnings,
    })
}

/// The layout's attachments, depth last, each multisampled or not.
fn planned_attachments(layout: &GBufferLayout, multisampled: bool) -> Vec<PlannedAttachment> {
    let colors = layout.colors.iter().map(|a| (a.name.clone(), a.format));
    colors
        .chain(std::iter::once(("depth".to_string(), layout.depth)))
        .map(|(name, format)| PlannedAttachment {
            name,
            format,
            multisampled,
        })
        .collect()
}

/// The passes that run for `aa`, in frame order; those that do not are
/// left out with why.
fn decide_passes(
    needs: &SceneNeeds,
    options: &RenderOptions,
    layout: &GBufferLayout,
    aa: AaMode,
    decisions: &mut Decisions,
) -> Vec<Pass> {
    let mut passes = vec![Pass::Clear, Pass::Background];
    let kind = technique::kind_of(&aa);
    // `sparse` builds block lists instead of filling the G-buffer.
    if kind.fills_gbuffer() {
        if layout.index_of("emissive").is_some() {
            passes.push(Pass::BackgroundCopy);
        } else {
            decisions.leave_out(
                Pass::BackgroundCopy.name(),
                "no emissive attachment to copy the background into",
            );
        }
        passes.push(Pass::Geometry);
    }
    if aa.is_multisampled() {
        passes.push(Pass::Resolve);
    }
    decisions.leave_out(Pass::Decals.name(), "no decal hook is installed");
    passes.extend(kind.lighting_passes(&aa));
    if needs.transparent_objects > 0 {
        passes.push(Pass::Transparent);
    } else {
        decisions.leave_out(Pass::Transparent.name(), "no alpha-blended object");
    }
    passes.push(Pass::Tonemap);
    passes.extend(kind.post_passes());
    if options.fxaa {
        passes.push(Pass::Fxaa);
    } else {
        decisions.leave_out(Pass::Fxaa.name(), "not asked for");
    }
    if options.smaa.is_some() {
        passes.push(Pass::Smaa);
    } else {
        decisions.leave_out(Pass::Smaa.name(), "not asked for");
    }
    passes
}

/// Remove the attachment `name` from `layout`, keeping the key on the same
/// attachment.
fn remove(layout: &mut GBufferLayout, name: &str) {
    let key_name = layout.key_attachment().map(|a| a.name.clone());
    layout.colors.retain(|a| a.name != name);
    if let Some(key) = key_name {
        layout.key = layout
            .index_of(&key)
            .map_or(KeySource::Depth, |k| KeySource::Position(ResolveSlot(k)));
    }
}

/// Whether FP16 positions hold the scene: `Ok` with the numbers, or `Err` with why not.
fn fp16_fits(
    needs: &SceneNeeds,
    settings: Option<crate::resolve::ResolveSettings>,
    height: u32,
) -> std::result::Result<String, String> {
    let (Some(max), Some(detail)) = (needs.max_coordinate, needs.detail) else {
        return Err("the scene's extent is unknown".into());
    };
    if max >= HALF_MAX {
        return Err(format!(
            "the scene reaches {max:.0} units from the camera, beyond FP16's {HALF_MAX}"
        ));
    }
    let spacing = half_spacing(max);
    if spacing > detail {
        return Err(format!(
            "FP16 spacing at {max:.1} units is {spacing:.4}, coarser than the scene's detail of {detail:.4}"
        ));
    }
    // The resolve's window in view units is (c_in or c) pixel footprints of
    // min(z_i, z_r); FP16 rounds by up to 2^-10 of z, so compare relatively.
    let window = settings.and_then(|s| match (s.method, s.window) {
        (ResolveMethod::Average, _) => None,
        (_, Window::Hard) => Some(s.c),
        (_, Window::Smooth) => Some(s.c_in),
    });
    if let Some(c) = window {
        let footprint = (needs.fov_y / f64::from(height.max(1))).tan();
        let allowed = WINDOW_FRACTION * c * footprint;
        let relative = 2f64.powi(-10);
        if relative > allowed {
            return Err(format!(
                "FP16 rounds depth keys by up to {relative:.5} of their distance, more than {WINDOW_FRACTION} of the resolve's {c} pixel-footprint window ({allowed:.5}) at {height} px"
            ));
        }
    }
    Ok(format!(
        "farthest coordinate {max:.1} units, spacing {spacing:.4} ≤ detail {detail:.4}"
    ))
}

/// The programs the frame compiles for `layout` and `aa`.
fn permutations(layout: &GBufferLayout, aa: AaMode, samples: u32) -> Vec<Permutation> {
    let defines = |d: Vec<(String, String)>| -> Vec<String> {
        d.into_iter()
            .map(|(k, v)| if v == "1" { k } else { format!("{k}={v}") })
            .collect()
    };
    let has = |name: &str| layout.index_of(name).is_some();
    let gbuffer: Vec<(String, String)> = [
        (!has("specular")).then(|| ("GBUFFER_NO_SPECULAR".to_string(), "1".to_string())),
        (!has("emissive")).then(|| ("GBUFFER_NO_EMISSIVE".to_string(), "1".to_string())),
    ]
    .into_iter()
    .flatten()
    .collect();
    let kind = technique::kind_of(&aa);
    let mut list = vec![Permutation {
        program: kind.geometry_program().into(),
        defines: defines(gbuffer.clone()),
    }];
    if let Some(s) = aa.settings().filter(|_| aa.is_multisampled()) {
        let mut d = vec![
            format!("NUM_SAMPLES={samples}"),
            format!("NUM_ATTACHMENTS={}", layout.colors.len()),
            format!("METHOD={}", s.method.name()),
        ];
        if s.window == Window::Hard && s.method != ResolveMethod::Average {
            d.push("WINDOW_HARD".into());
        }
        if s.fast_path {
            d.push("FAST_PATH".into());
        }
        d.push("WRITE_DEPTH".into());
        list.push(Permutation {
            program: "resolve".into(),
            defines: d,
        });
    }
    list.extend(kind.own_programs().iter().map(|&program| Permutation {
        program: program.into(),
        defines: Vec::new(),
    }));
    if aa.lights_per_sample() {
        list.push(Permutation {
            program: "lighting-per-sample".into(),
            defines: defines(gbuffer),
        });
    } else {
        list.push(Permutation {
            program: "lighting".into(),
            defines: defines(lighting_defines().into_iter().chain(gbuffer).collect()),
        });
    }
    list
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_values_round_like_the_attachment() {
        assert_eq!(stored_as(Format::Rgba8, 0.04), 10.0 / 255.0);
        assert_eq!(stored_as(Format::Rgba32f, 0.04), 0.04);
        // 0.04 in half float: 1311 / 32768.
        assert_eq!(stored_as(Format::Rgba16f, 0.04), 1311.0 / 32768.0);
        assert_eq!(half_spacing(1000.0), 0.5);
        assert_eq!(half_spacing(1.0), 2f64.powi(-10));
    }
}
