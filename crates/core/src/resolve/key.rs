//! What selects one compiled resolve program: its key, the defines it
//! prepends to `resolve.frag`, and the draws a second layer takes.

use super::inputs::{KeySource, ResolveInputs, ResolveSlot};
use super::settings::{NormalEncoding, Region, ResolveMethod, ResolveRule, Selection, Window};
use crate::gl::format::SampleKind;
use crate::{Error, Result};

/// Everything that selects one compiled resolve program.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct ResolveProgramKey {
    /// Real sample count.
    pub samples: u32,
    /// Inputs are `sampler2DArray`s with one layer per sample (test harness).
    pub samples_as_layers: bool,
    /// Per colour attachment: its rule and how shaders read it.
    pub attachments: Vec<(ResolveRule, SampleKind)>,
    /// Key source.
    pub key: KeySource,
    /// Reference choice.
    pub method: ResolveMethod,
    /// Window (normalised to `Smooth` for `Average`, which ignores it).
    pub window: Window,
    /// Uniform-pixel fast path.
    pub fast_path: bool,
    /// The opt-in plane test of [`ResolveSettings::plane_uniformity`] (with the fast path).
    pub plane_uniformity: bool,
    /// The opt-in test of [`ResolveSettings::position_uniformity`] (with the
    /// fast path and a position key).
    pub position_uniformity: bool,
    /// Write `gl_FragDepth`.
    pub write_depth: bool,
    /// Blend depth instead of selecting the reference's.
    pub blend_depth: bool,
    /// Write the complex-pixel mask to output `attachments.len()`.
    pub complex_output: bool,
    /// Write the outside flag (1.0 where a sample is outside the first
    /// layer's cluster) after the complex mask.
    pub outside_output: bool,
    /// Write the reference sample's index to the output after those.
    pub reference_output: bool,
    /// Selective anti-aliasing criteria compiled in.
    pub selection: SelectionKey,
    /// The normal attachment's slot and encoding, whose test splits
    /// clusters (one layer or two).
    pub normal: Option<(ResolveSlot, NormalEncoding)>,
    /// Two layers with a normal attachment (and a method with a reference):
    /// the reference moves to the orientation most samples within its depth
    /// window share, in both layers' passes.
    pub majority_reference: bool,
    /// Write the second layer and its coverage instead of the first.
    pub second_layer_output: bool,
    /// The colour attachments written (bit k: attachment k), to
    /// consecutive outputs in attachment order; the others are resolved
    /// for nothing but the compiler drops them.
    pub written: u8,
    /// With `second_layer_output`: the coverage, depth (and reference)
    /// outputs are written after the colours.
    pub layer_extras: bool,
}

/// Which outputs one draw of the second layer's resolve writes. A host
/// whose colours and the second layer's own outputs (coverage, depth, the
/// seed sample) together need more draw buffers than the context has gets
/// its second layer in several draws: the first writes the extras and as
/// many colours as fit, the others the remaining colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LayerPass {
    /// The colour inputs written (bit k: input k), to consecutive draw
    /// buffers in input order.
    pub colors: u8,
    /// The coverage, the depth and, with a reference output, the seed
    /// sample, to the draw buffers after the colours.
    pub extras: bool,
}

impl LayerPass {
    /// Every one of `n` colours and the extras: one draw.
    pub fn all(n: usize) -> LayerPass {
        LayerPass {
            colors: all_bits(n),
            extras: true,
        }
    }
}

/// The mask of attachments `0..n`.
pub(super) fn all_bits(n: usize) -> u8 {
    if n >= 8 { u8::MAX } else { (1u8 << n) - 1 }
}

/// The compiled-in shape of a [`Selection`] (its numbers are uniforms).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct SelectionKey {
    /// `Some(true)` for an ellipse, `Some(false)` for a rectangle.
    pub region_ellipse: Option<bool>,
    /// A depth threshold is set.
    pub max_depth: bool,
    /// The flag's input slot and component.
    pub flag: Option<(ResolveSlot, u8)>,
}

impl SelectionKey {
    /// The shape of `selection`, its flag found among `inputs`.
    pub(super) fn of(selection: &Selection, inputs: &ResolveInputs<'_>) -> Result<Self> {
        let flag = match selection.flag {
            None => None,
            Some(f) => {
                let slot = inputs.slot_of(f.attachment).ok_or_else(|| Error::Retrofit {
                    attachment: f.attachment.name(),
                    reason: format!(
                        "named as the selective-AA flag, but the resolve's colour inputs are {}",
                        inputs.attachment_list()
                    ),
                })?;
                let format = inputs.colors[slot.0].format;
                if format.sample_kind() != SampleKind::Float {
                    return Err(Error::UnsupportedFormat {
                        attachment: f.attachment.name(),
                        format: format.name().into(),
                        reason: "the selective-AA flag must be in a float or normalised format"
                            .into(),
                    });
                }
                Some((slot, f.component))
            }
        };
        Ok(SelectionKey {
            region_ellipse: selection
                .region
                .map(|r| matches!(r, Region::Ellipse { .. })),
            max_depth: selection.max_depth.is_some(),
            flag,
        })
    }
}

impl ResolveProgramKey {
    /// The `#define` block for this permutation.
    pub fn defines(&self) -> Vec<(String, String)> {
        let mut d: Vec<(String, String)> = Vec::new();
        let mut def = |k: &str, v: String| d.push((k.to_string(), v));
        def("NUM_SAMPLES", self.samples.to_string());
        def("NUM_ATTACHMENTS", self.attachments.len().to_string());
        if self.samples_as_layers {
            def("SAMPLES_AS_LAYERS", "1".into());
        }
        for (k, (rule, kind)) in self.attachments.iter().enumerate() {
            let prefix = match kind {
                SampleKind::Float => "",
                SampleKind::Uint => "u",
                SampleKind::Int => "i",
            };
            let sampler = if self.samples_as_layers {
                "sampler2DArray"
            } else {
                "sampler2DMS"
            };
            def(&format!("ATT{k}_SAMPLER"), format!("{prefix}{sampler}"));
            def(&format!("ATT{k}_VEC"), format!("{prefix}vec4"));
            let rule = match rule {
                ResolveRule::Blend => "RULE_BLEND",
                ResolveRule::BlendNormal => "RULE_BLEND_NORMAL",
                ResolveRule::BlendHdr => "RULE_BLEND_HDR",
                ResolveRule::Select => "RULE_SELECT",
            };
            def(&format!("ATT{k}_RULE"), rule.into());
        }
        let key_index = match self.key {
            KeySource::Position(ResolveSlot(k)) | KeySource::WorldPosition(ResolveSlot(k)) => {
                def("KEY_SAMPLER", format!("u_att{k}"));
                def("KEY_INDEX", k.to_string());
                Some(k)
            }
            KeySource::Depth => None,
        };
        // The per-attachment code: one call of resolve.frag's template per
        // attachment, in order.
        let (mut declarations, mut begins, mut steps, mut ends, mut zeros) = (
            String::new(),
            String::new(),
            String::new(),
            String::new(),
            String::new(),
        );
        for (k, (rule, _)) in self.attachments.iter().enumerate() {
            let args = format!("s0_{k}, ref_{k}, acc_{k}, ATT{k}_RULE");
            // An attachment another draw writes is a plain variable here.
            let storage = if self.written & (1 << k) != 0 {
                "out "
            } else {
                ""
            };
            declarations.push_str(&format!(
                "uniform ATT{k}_SAMPLER u_att{k}; {storage}ATT{k}_VEC o_att{k}; "
            ));
            zeros.push_str(&format!(
                "o_att{k} = has_second ? o_att{k} : ATT{k}_VEC(0); "
            ));
            if key_index == Some(k) {
                begins.push_str(&format!("KEY_BEGIN({args}) "));
                steps.push_str(&format!("KEY_STEP(acc_{k}, ATT{k}_RULE) "));
                ends.push_str(&format!("KEY_END(o_att{k}, {args}) "));
            } else if *rule == ResolveRule::Select {
                ends.push_str(&format!("SELECT_END(o_att{k}, u_att{k}) "));
            } else {
                begins.push_str(&format!("BLEND_BEGIN(u_att{k}, {args}) "));
                steps.push_str(&format!("BLEND_STEP(u_att{k}, {args}) "));
                ends.push_str(&format!("BLEND_END(o_att{k}, {args}) "));
            }
        }
        def("ATTACHMENT_DECLARATIONS", declarations);
        def("ATTACHMENT_BEGINS", begins);
        def("ATTACHMENT_STEPS", steps);
        def("ATTACHMENT_ENDS", ends);
        def("ATTACHMENT_ZEROS", zeros);
        if matches!(self.key, KeySource::WorldPosition(_)) {
            def("KEY_WORLD", "1".into());
        }
        let method = match self.method {
            ResolveMethod::Average => "METHOD_AVERAGE",
            ResolveMethod::Front => "METHOD_FRONT",
            ResolveMethod::Median => "METHOD_MEDIAN",
            ResolveMethod::Back => "METHOD_BACK",
            ResolveMethod::UpperMedian => "METHOD_UPPER_MEDIAN",
        };
        def("METHOD", method.into());
        if self.window == Window::Hard {
            def("WINDOW_HARD", "1".into());
        }
        if self.fast_path {
            def("FAST_PATH", "1".into());
            // The plane test compares the first blended attachment's samples;
            // without one it never fires (as in the CPU reference).
            let first_blended = self
                .attachments
                .iter()
                .position(|(rule, _)| *rule != ResolveRule::Select);
            if self.position_uniformity {
                def("POSITION_UNIFORMITY", "1".into());
            } else if let (true, Some(k)) = (self.plane_uniformity, first_blended) {
                def("PLANE_UNIFORMITY", "1".into());
                def("PLANE_SAMPLER", format!("u_att{k}"));
            }
        }
        if self.write_depth {
            def("WRITE_DEPTH", "1".into());
        }
        if self.blend_depth {
            def("BLEND_DEPTH", "1".into());
        }
        if self.complex_output {
            def("COMPLEX_OUTPUT", "1".into());
        }
        if self.outside_output {
            def("OUTSIDE_OUTPUT", "1".into());
        }
        if self.reference_output {
            def("REFERENCE_OUTPUT", "1".into());
        }
        let sel = self.selection;
        if let Some(ellipse) = sel.region_ellipse {
            let shape = if ellipse {
                "REGION_ELLIPSE"
            } else {
                "REGION_RECT"
            };
            def("SELECT_REGION", shape.into());
        }
        if sel.max_depth {
            def("SELECT_MAX_DEPTH", "1".into());
        }
        if let Some((ResolveSlot(slot), component)) = sel.flag {
            def("SELECT_FLAG_SAMPLER", format!("u_att{slot}"));
            let component = ["x", "y", "z", "w"][usize::from(component.min(3))];
            def("SELECT_FLAG_COMPONENT", component.into());
        }
        if let Some((ResolveSlot(slot), encoding)) = self.normal {
            def("CLUSTER_NORMALS", "1".into());
            def("NORMAL_SAMPLER", format!("u_att{slot}"));
            let encoding = match encoding {
                NormalEncoding::Xyz => "NORMAL_XYZ",
                NormalEncoding::Unorm => "NORMAL_UNORM",
                NormalEncoding::Octahedral => "NORMAL_OCTAHEDRAL",
                NormalEncoding::OctahedralUnorm => "NORMAL_OCTAHEDRAL_UNORM",
            };
            def("NORMAL_ENCODING", encoding.into());
        }
        if self.majority_reference {
            def("MAJORITY_REFERENCE", "1".into());
        }
        if self.second_layer_output {
            def("SECOND_LAYER_OUTPUT", "1".into());
            if !self.layer_extras {
                def("SECOND_LAYER_COLOURS_ONLY", "1".into());
            }
        }
        d
    }
}
