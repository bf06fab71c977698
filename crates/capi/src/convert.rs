//! What a C caller passes, checked and converted: the options into
//! `RetrofitOptions`, matrices, and the second layer's identity.

use crate::call::Failure;
use crate::types::*;
use deferred_msaa::foreign::ForeignRetrofit;
use deferred_msaa::gbuffer::MemoryBudget;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::{
    ColorAttachment, DepthMode, FirstLayerRestore, LayerMix, NormalAttachment, PositionSpace,
    RetrofitOptions, TwinClear,
};
use std::ffi::CStr;
use std::num::NonZeroU32;

pub(crate) fn flag(name: &str, value: u8) -> Result<bool, Failure> {
    match value {
        0 => Ok(false),
        1 => Ok(true),
        v => Err(Failure::invalid(format!(
            "DmsaaOptions.{name} is {v}; a flag is 0 or 1"
        ))),
    }
}

pub(crate) fn attachment(name: &str, value: i32) -> Result<Option<ColorAttachment>, Failure> {
    match value {
        DMSAA_NO_ATTACHMENT => Ok(None),
        v if v >= 0 => Ok(Some(ColorAttachment(v as u32))),
        v => Err(Failure::invalid(format!(
            "DmsaaOptions.{name} is {v}; expected a colour attachment number (0 for \
             GL_COLOR_ATTACHMENT0, ...) or DMSAA_NO_ATTACHMENT (-1)"
        ))),
    }
}

/// One of an enumeration's values, or an error naming the field and what
/// it accepts.
pub(crate) fn pick<T: Clone>(name: &str, value: u32, choices: &[(&str, T)]) -> Result<T, Failure> {
    choices
        .get(value as usize)
        .map(|(_, v)| v.clone())
        .ok_or_else(|| {
            let names: Vec<String> = choices
                .iter()
                .enumerate()
                .map(|(i, (n, _))| format!("{n} ({i})"))
                .collect();
            Failure::invalid(format!(
                "DmsaaOptions.{name} is {value}; expected one of {}",
                names.join(", ")
            ))
        })
}

/// What [`DmsaaOptions`] asks for: the Rust options, the depth mode and
/// whether positions are world-space.
#[derive(Debug)]
pub(crate) struct Converted {
    pub(crate) options: RetrofitOptions,
    pub(crate) depth_mode: DepthMode,
    pub(crate) world_space: bool,
}

pub(crate) fn convert(o: &DmsaaOptions) -> Result<Converted, Failure> {
    if o.samples == 0 {
        return Err(Failure::invalid(
            "DmsaaOptions.samples is 0; it is at least 1",
        ));
    }
    let mut options = RetrofitOptions {
        samples: o.samples,
        ..RetrofitOptions::default()
    };
    options.resolve.layers = o.layers;
    options.position_attachment = attachment("position_attachment", o.position_attachment)?;
    let world_space = flag("world_space_position", o.world_space_position)?;
    options.position_space = if world_space {
        PositionSpace::World
    } else {
        PositionSpace::View
    };
    let encoding = pick(
        "normal_encoding",
        o.normal_encoding,
        &[
            ("DMSAA_NORMAL_XYZ", NormalEncoding::Xyz),
            ("DMSAA_NORMAL_UNORM", NormalEncoding::Unorm),
            ("DMSAA_NORMAL_OCTAHEDRAL", NormalEncoding::Octahedral),
            (
                "DMSAA_NORMAL_OCTAHEDRAL_UNORM",
                NormalEncoding::OctahedralUnorm,
            ),
        ],
    )?;
    options.normal_attachment =
        attachment("normal_attachment", o.normal_attachment)?.map(|attachment| NormalAttachment {
            attachment,
            encoding,
        });
    options.resolve.normal_threshold = o.normal_threshold;
    options.resolve.method = pick(
        "method",
        o.method,
        &[
            ("DMSAA_METHOD_AVERAGE", ResolveMethod::Average),
            ("DMSAA_METHOD_FRONT", ResolveMethod::Front),
            ("DMSAA_METHOD_MEDIAN", ResolveMethod::Median),
            ("DMSAA_METHOD_BACK", ResolveMethod::Back),
            ("DMSAA_METHOD_UPPER_MEDIAN", ResolveMethod::UpperMedian),
        ],
    )?;
    options.resolve.window = pick(
        "window",
        o.window,
        &[
            ("DMSAA_WINDOW_HARD", Window::Hard),
            ("DMSAA_WINDOW_SMOOTH", Window::Smooth),
        ],
    )?;
    options.resolve.c = o.window_c;
    options.resolve.c_in = o.window_c_in;
    options.resolve.fast_path = flag("fast_path", o.fast_path)?;
    options.resolve.blend_depth = flag("blend_depth", o.blend_depth)?;
    options.resolve.plane_uniformity = flag("plane_uniformity", o.plane_uniformity)?;
    options.resolve.position_uniformity = flag("position_uniformity", o.position_uniformity)?;
    // The numbers the resolve checks itself are checked now, so that a bad
    // option fails here with the Rust message rather than later.
    options.resolve.validate()?;
    for (k, &rule) in o.rules.iter().enumerate() {
        let rule = pick(
            &format!("rules[{k}]"),
            rule,
            &[
                ("DMSAA_RULE_DEFAULT", None),
                ("DMSAA_RULE_BLEND", Some(ResolveRule::Blend)),
                ("DMSAA_RULE_BLEND_NORMAL", Some(ResolveRule::BlendNormal)),
                ("DMSAA_RULE_BLEND_HDR", Some(ResolveRule::BlendHdr)),
                ("DMSAA_RULE_SELECT", Some(ResolveRule::Select)),
            ],
        )?;
        if let Some(rule) = rule {
            options.rules.push((ColorAttachment(k as u32), rule));
        }
    }
    options.stencil = pick(
        "stencil_copy",
        o.stencil_copy,
        &[
            ("DMSAA_STENCIL_AUTO", StencilCopy::Auto),
            ("DMSAA_STENCIL_EXPORT", StencilCopy::Export),
            ("DMSAA_STENCIL_BIT_PASSES", StencilCopy::BitPasses),
            ("DMSAA_STENCIL_BLIT", StencilCopy::Blit),
        ],
    )?;
    options.layer_mix = match o.layer_mix {
        DMSAA_LAYER_MIX_CURVE => {
            if o.layer_mix_curve.is_null() {
                return Err(Failure::null("DmsaaOptions", "layer_mix_curve"));
            }
            // SAFETY: the header requires a NUL-terminated string here.
            let text = unsafe { CStr::from_ptr(o.layer_mix_curve) };
            let text = text
                .to_str()
                .map_err(|_| Failure::invalid("DmsaaOptions.layer_mix_curve is not UTF-8 text"))?;
            LayerMix::Curve(text.to_owned())
        }
        other => pick(
            "layer_mix",
            other,
            &[
                ("DMSAA_LAYER_MIX_AUTO", LayerMix::Auto),
                ("DMSAA_LAYER_MIX_LINEAR", LayerMix::Linear),
                ("DMSAA_LAYER_MIX_TONEMAPPED", LayerMix::Tonemapped),
                // Taken above, with its text; listed for the message.
                ("DMSAA_LAYER_MIX_CURVE", LayerMix::Auto),
                ("DMSAA_LAYER_MIX_SRGB_ENCODED", LayerMix::SrgbEncoded),
            ],
        )?,
    };
    options.restore_first_layer = pick(
        "restore_first_layer",
        o.restore_first_layer,
        &[
            ("DMSAA_RESTORE_NOTHING", FirstLayerRestore::Nothing),
            ("DMSAA_RESTORE_EVERYTHING", FirstLayerRestore::Everything),
            (
                "DMSAA_RESTORE_DEPTH_AND_STENCIL",
                FirstLayerRestore::DepthAndStencil,
            ),
        ],
    )?;
    options.check_second_lighting = flag("check_second_lighting", o.check_second_lighting)?;
    options.second_layer_omits = (0..32)
        .filter(|n| o.second_layer_omits & (1 << n) != 0)
        .map(ColorAttachment)
        .collect();
    options.twin_clear = flag("clear_twins", o.clear_twins)?.then(|| TwinClear {
        colors: o
            .clear_colors
            .iter()
            .enumerate()
            .map(|(n, v)| (ColorAttachment(n as u32), *v))
            .collect(),
        depth: o.clear_depth,
        stencil: o.clear_stencil,
    });
    options.lit_clear = flag("has_lit_clear", o.has_lit_clear)?.then_some(o.lit_clear_color);
    let strict = flag("memory_budget_strict", o.memory_budget_strict)?;
    options.memory_budget = match o.memory_budget_bytes {
        DMSAA_MEMORY_BUDGET_NONE => None,
        DMSAA_MEMORY_BUDGET_DRIVER => Some(MemoryBudget {
            bytes: None,
            strict,
        }),
        bytes => Some(MemoryBudget {
            bytes: Some(bytes),
            strict,
        }),
    };
    let depth_mode = pick(
        "depth_mode",
        o.depth_mode,
        &[
            ("DMSAA_DEPTH_STANDARD", DepthMode::Standard),
            ("DMSAA_DEPTH_ZERO_TO_ONE", DepthMode::ZeroToOne),
            ("DMSAA_DEPTH_REVERSED_Z", DepthMode::ReversedZ),
        ],
    )?;
    Ok(Converted {
        options,
        depth_mode,
        world_space,
    })
}

/// The options a C caller passed, checked for null and converted.
pub(crate) fn read_options(
    function: &str,
    options: *const DmsaaOptions,
) -> Result<Converted, Failure> {
    // SAFETY: the header requires null or a valid `DmsaaOptions`.
    let options = unsafe { options.as_ref() }.ok_or_else(|| Failure::null(function, "options"))?;
    convert(options).map_err(|f| Failure::new(f.status, format!("{function}: {}", f.message)))
}

/// Sixteen floats from C.
pub(crate) fn matrix(function: &str, name: &str, m: *const f32) -> Result<[f32; 16], Failure> {
    if m.is_null() {
        return Err(Failure::null(function, name));
    }
    // SAFETY: the header requires 16 readable floats.
    Ok(unsafe { std::ptr::read_unaligned(m.cast::<[f32; 16]>()) })
}

/// What identifies the second layer's objects: they change when the twins
/// are rebuilt (a rebuilt second layer starts a frame afresh).
pub(crate) fn second_layer_identity(msaa: &ForeignRetrofit) -> Option<u32> {
    msaa.second_layer_coverage().map(NonZeroU32::get)
}
