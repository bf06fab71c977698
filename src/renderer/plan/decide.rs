//! The plan's decisions, one function each: what the layout leaves out or
//! narrows (emission, specular response, FP16 positions), the sample count
//! under the memory budget, the passes and the shader permutations.

use super::needs::PlanContext;
use super::needs::{SceneNeeds, SpecularResponse};
use super::parts::{LeftOut, Permutation, PlannedAttachment};
use crate::gbuffer::{GBufferLayout, HALF_MAX, choose_samples, fmt_bytes, gbuffer_bytes};
use crate::gl::Format;
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::pass::lighting::lighting_defines;
use crate::renderer::technique;
use crate::resolve::{KeySource, ResolveMethod, ResolveSlot, Window};
use crate::{Error, Result};

/// How fine FP16 positions must be against the resolve's closeness window:
/// at most this fraction of its inner edge (in pixel footprints).
pub(super) const WINDOW_FRACTION: f64 = 0.25;

/// Round `v` as a texture of `format` stores it (unsigned normalised 8-bit
/// or half float; other formats keep it).
pub(super) fn stored_as(format: Format, v: f32) -> f32 {
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
pub(super) fn half_spacing(m: f64) -> f64 {
    if m < 2f64.powi(-14) {
        2f64.powi(-24)
    } else {
        2f64.powi(m.log2().floor() as i32 - 10)
    }
}

/// What the plan left out and kept, with why, in the order decided.
#[derive(Default)]
pub(super) struct Decisions {
    pub(super) left_out: Vec<LeftOut>,
    pub(super) kept: Vec<LeftOut>,
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
pub(super) fn blends_background(aa: AaMode) -> bool {
    matches!(aa, AaMode::Resolve(s) if s.method == ResolveMethod::Average)
}

/// Emission: the `emissive` attachment goes when no material emits (and
/// `average` does not need it for the background).
pub(super) fn decide_emissive(
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
pub(super) fn decide_specular(
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
pub(super) fn decide_position(
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
pub(super) struct Budgeted {
    /// The method asked for, or `none` when no multisampled count fits.
    pub(super) aa: AaMode,
    /// The real samples per pixel of the G-buffer.
    pub(super) samples: u32,
    /// A stepped-down sample count, or a single-sample G-buffer over budget.
    pub(super) warnings: Vec<String>,
}

/// Apply the memory budget: a multisampled method steps its count down to
/// the highest offered count that fits (or to `none`); a single-sample one
/// keeps its method and warns when over.
pub(super) fn decide_samples(
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
pub(super) fn planned_attachments(
    layout: &GBufferLayout,
    multisampled: bool,
) -> Vec<PlannedAttachment> {
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
pub(super) fn decide_passes(
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
pub(super) fn remove(layout: &mut GBufferLayout, name: &str) {
    let key_name = layout.key_attachment().map(|a| a.name.clone());
    layout.colors.retain(|a| a.name != name);
    if let Some(key) = key_name {
        layout.key = layout
            .index_of(&key)
            .map_or(KeySource::Depth, |k| KeySource::Position(ResolveSlot(k)));
    }
}

/// Whether FP16 positions hold the scene: `Ok` with the numbers, or `Err` with why not.
pub(super) fn fp16_fits(
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
pub(super) fn permutations(layout: &GBufferLayout, aa: AaMode, samples: u32) -> Vec<Permutation> {
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
    use crate::gl::Format;

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
