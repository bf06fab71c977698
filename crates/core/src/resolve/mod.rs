//! The depth-aware resolve: a full-screen pass that reads every sample of a
//! multisampled G-buffer and writes a single-sample one (its math:
//! docs/resolve.md in the repository, "The math").
//!
//! The math lives in two places only: `resolve.frag` and its CPU
//! reference, [`cpu`]. This module builds the shader permutations (the sample
//! count, attachment set and options are compile-time defines, cached by a
//! typed key) and runs the pass.

pub mod cpu;
mod settings;
mod stencil;

pub use settings::{
    DEFAULT_NORMAL_THRESHOLD, DepthProjection, NormalEncoding, Region, ResolveMethod, ResolveRule,
    ResolveSettings, Selection, SelectionFlag, Window,
};
pub(crate) use stencil::StencilPass;
pub use stencil::{STENCIL_COPY_FRAG, StencilCopy};

use crate::gl::format::SampleKind;
use crate::gl::{
    ColorAttachment, FULLSCREEN_VERT, Framebuffer, Program, SavedState, ShaderSource, ShaderStage,
    TextureRef, VertexArray, check_error, preamble,
};
use crate::{Error, Result};
use glow::HasContext;
use std::collections::HashMap;

/// The resolve's fragment shader body; it needs [`COMPLEX_GLSL`] in front
/// of it (see [`resolve_fragment_source`]).
pub const RESOLVE_FRAG: &str = include_str!("resolve.frag");

/// The shared definitions of a complex pixel and of the selective-AA
/// selection test, as a [`ShaderSource`] part (`complex.glsl`, no `main`):
///
/// - `bool dmsaa_same_surface(bool bg_i, float key_i, bool bg_0, float key_0)`
///   and its `vec4` key overload: sample `i` is the same surface as sample 0
///   (both background, or geometry with equal keys); a pixel is complex when
///   some sample is not;
/// - `bool dmsaa_same_surface_within(bool bg_i, float key_i, bool bg_0, float key_0, float tolerance)`:
///   the same with keys `tolerance` × the nearer key apart counting as equal;
/// - `bool dmsaa_outside_rect(vec2 c, vec4 rect)`, `bool dmsaa_outside_ellipse(vec2 c, vec4 ellipse)`:
///   a pixel centre outside a [`Region`] (its [`Region::window_uniform`] numbers);
/// - `bool dmsaa_within_depth(bool bg, float key, float max_depth)`: a sample
///   near enough for [`Selection::max_depth`].
///
/// The CPU reference (`resolve::cpu`) is the only other copy.
pub const COMPLEX_GLSL: &str = include_str!("complex.glsl");

/// The name [`COMPLEX_GLSL`] goes by in shader messages.
pub const COMPLEX_GLSL_NAME: &str = "complex.glsl";

/// The resolve's fragment stage: `header`, then [`COMPLEX_GLSL`] and
/// [`RESOLVE_FRAG`] as two parts (so messages name the right file).
pub fn resolve_fragment_source(header: &str) -> ShaderSource {
    ShaderSource::with_header(header)
        .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
        .part("resolve.frag", RESOLVE_FRAG)
}

/// The most colour attachments one resolve handles (GL 3.2 guarantees 8 draw buffers).
pub const MAX_ATTACHMENTS: usize = 8;

/// A colour input of the resolve by position: slot `k` is the `k`-th
/// texture of [`ResolveInputs::colors`] and goes to the target's draw
/// buffer `k`. A host names its attachments by [`ColorAttachment`] instead;
/// the retrofit maps one to the other.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ResolveSlot(pub usize);

/// Where the per-sample depth key comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum KeySource {
    /// `z = −position.z` of the colour input in this slot (view-space position).
    Position(ResolveSlot),
    /// `z = −(view · position).z` of the colour input in this slot
    /// (world-space position; the view matrix comes with each frame).
    WorldPosition(ResolveSlot),
    /// The depth attachment, linearised with the projection.
    Depth,
}

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
fn all_bits(n: usize) -> u8 {
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
    fn of(selection: &Selection, inputs: &ResolveInputs<'_>) -> Result<Self> {
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

/// What a resolve writes besides the resolved attachments and depth, to
/// the draw buffers after the attachments', in this order. `true` and
/// `false` convert to the complex-pixel mask alone, or nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ExtraOutputs {
    /// 1.0 where the pixel took the slow path, else 0.0 (a float target).
    pub complex: bool,
    /// 1.0 where a sample lies outside the pixel's cluster (its weight is
    /// 0: the pixel may have a second layer), else 0.0 (a float target).
    pub outside: bool,
    /// The index of the pixel's reference sample (0 where it took one
    /// sample), to an unsigned-integer target: how the host's stencil is
    /// copied from the reference sample.
    pub reference: bool,
}

impl From<bool> for ExtraOutputs {
    fn from(complex: bool) -> Self {
        ExtraOutputs {
            complex,
            outside: false,
            reference: false,
        }
    }
}

/// The inputs of one resolve.
#[derive(Clone, Debug)]
pub struct ResolveInputs<'a> {
    /// The multisampled depth texture (or its per-sample layer array).
    pub depth: TextureRef,
    /// The multisampled colour textures, in slot order (slot `k` is written
    /// to the target's draw buffer `k`).
    pub colors: &'a [TextureRef],
    /// The attachment each colour input stands for, in the same order: how
    /// [`SelectionFlag::attachment`] finds its slot.
    pub attachments: &'a [ColorAttachment],
    /// One rule per colour texture.
    pub rules: &'a [ResolveRule],
    /// Where the depth key comes from.
    pub key: KeySource,
    /// Sample count; for layer arrays, the number of layers.
    pub samples: u32,
    /// The colour input holding normals and their encoding: clusters split
    /// by normal too, with one layer or two ([`ResolveSettings::normal_threshold`]).
    pub normal: Option<(ResolveSlot, NormalEncoding)>,
}

impl ResolveInputs<'_> {
    /// The slot holding `attachment`, if it is an input.
    pub fn slot_of(&self, attachment: ColorAttachment) -> Option<ResolveSlot> {
        self.attachments
            .iter()
            .position(|a| *a == attachment)
            .map(ResolveSlot)
    }

    fn attachment_list(&self) -> String {
        let names: Vec<String> = self.attachments.iter().map(|a| a.name()).collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    }
}

/// The camera facts the closeness window needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolveParams {
    /// Method, window and options.
    pub settings: ResolveSettings,
    /// Depth linearisation and the clear depth.
    pub projection: DepthProjection,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Height of the framebuffer in pixels.
    pub height_px: u32,
    /// The view matrix's third row `(m[2], m[6], m[10], m[14])` of a
    /// column-major view matrix: needed, and only used, when the key is a
    /// [`KeySource::WorldPosition`].
    pub view_row: Option<[f64; 4]>,
}

impl ResolveParams {
    /// `tan(fov_y / height_px)`: a pixel's view-space size at distance 1.
    pub fn footprint(&self) -> f64 {
        (self.fov_y / self.height_px.max(1) as f64).tan()
    }
}

/// Compiles, caches and runs resolve programs.
#[derive(Debug)]
pub struct Resolver {
    programs: HashMap<ResolveProgramKey, Program>,
    vao: VertexArray,
}

/// How one resolve draw runs beside its program: the stage its GL errors
/// are reported as, and the stencil value it is limited to (an early test
/// on the target's stencil).
#[derive(Clone, Copy, Debug)]
struct DrawRun<'s> {
    stage: &'s str,
    stencil: Option<u8>,
}

impl Resolver {
    /// Create the pass (programs are built on first use).
    pub fn new(gl: &glow::Context) -> Result<Self> {
        Ok(Resolver {
            programs: HashMap::new(),
            vao: VertexArray::new(gl, "resolve full-screen triangle")?,
        })
    }

    /// The program for `key`, built on first use.
    pub(crate) fn program(
        &mut self,
        gl: &glow::Context,
        key: &ResolveProgramKey,
    ) -> Result<&Program> {
        match self.programs.entry(key.clone()) {
            std::collections::hash_map::Entry::Occupied(e) => Ok(e.into_mut()),
            std::collections::hash_map::Entry::Vacant(v) => Ok(v.insert(build_program(gl, key)?)),
        }
    }

    /// Number of cached programs.
    pub fn cached_programs(&self) -> usize {
        self.programs.len()
    }

    /// The program key of the single-pass resolve of `inputs` into `target`
    /// under `settings`, after checking that they fit together.
    fn base_key(
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        settings: &ResolveSettings,
        extra: ExtraOutputs,
        second_layer_output: bool,
    ) -> Result<ResolveProgramKey> {
        settings.validate()?;
        if inputs.colors.len() != inputs.rules.len()
            || inputs.colors.len() != inputs.attachments.len()
        {
            return Err(Error::Layout(format!(
                "{} colour inputs but {} rules and {} attachment numbers",
                inputs.colors.len(),
                inputs.rules.len(),
                inputs.attachments.len()
            )));
        }
        if inputs.colors.len() > MAX_ATTACHMENTS {
            return Err(Error::Layout(format!(
                "{} colour attachments; the resolve handles at most {MAX_ATTACHMENTS}",
                inputs.colors.len()
            )));
        }
        let written = all_bits(inputs.colors.len());
        let mut attachments = Vec::with_capacity(inputs.colors.len());
        for ((tex, &rule), point) in inputs
            .colors
            .iter()
            .zip(inputs.rules)
            .zip(inputs.attachments)
        {
            let kind = tex.format.sample_kind();
            if kind != SampleKind::Float && rule != ResolveRule::Select {
                return Err(Error::UnsupportedFormat {
                    attachment: point.name(),
                    format: tex.format.name().into(),
                    reason: format!(
                        "integer formats can only be selected, not resolved by `{rule}`"
                    ),
                });
            }
            attachments.push((rule, kind));
        }
        if let KeySource::Position(slot) | KeySource::WorldPosition(slot) = inputs.key {
            if inputs.colors.get(slot.0).map(|t| t.format.sample_kind()) != Some(SampleKind::Float)
            {
                return Err(Error::Layout(format!(
                    "the depth key is in colour input {}, which is not a float input",
                    slot.0
                )));
            }
        }
        let normal = match inputs.normal {
            Some((slot, encoding)) => {
                let input = inputs.colors.get(slot.0).ok_or_else(|| {
                    Error::Layout(format!(
                        "the normals are in colour input {}, but there are {}",
                        slot.0,
                        inputs.colors.len()
                    ))
                })?;
                if input.format.sample_kind() != SampleKind::Float {
                    return Err(Error::UnsupportedFormat {
                        attachment: inputs
                            .attachments
                            .get(slot.0)
                            .map_or_else(|| format!("colour input {}", slot.0), |a| a.name()),
                        format: input.format.name().into(),
                        reason: "the normal test needs a float or normalised normal attachment"
                            .into(),
                    });
                }
                Some((slot, encoding))
            }
            None => None,
        };
        if second_layer_output && (extra.complex || extra.outside) {
            return Err(Error::invalid(
                "the second layer's resolve writes no complex mask or outside flag",
            ));
        }
        let s = settings;
        // The second layer's depth is a colour output; a depth-stencil
        // attachment of its target holds only the stencil that limits it.
        let write_depth = target.has_depth() && !second_layer_output;
        Ok(ResolveProgramKey {
            samples: inputs.samples,
            samples_as_layers: inputs.depth.target == glow::TEXTURE_2D_ARRAY,
            attachments,
            key: inputs.key,
            method: s.method,
            window: if s.method == ResolveMethod::Average {
                Window::Smooth
            } else {
                s.window
            },
            fast_path: s.fast_path,
            plane_uniformity: s.plane_uniformity && s.fast_path,
            position_uniformity: s.position_uniformity
                && s.fast_path
                && !matches!(inputs.key, KeySource::Depth),
            write_depth,
            blend_depth: s.blend_depth && (write_depth || second_layer_output),
            complex_output: extra.complex,
            outside_output: extra.outside,
            reference_output: extra.reference,
            selection: SelectionKey::of(&s.selection, inputs)?,
            majority_reference: s.layers == 2
                && normal.is_some()
                && s.method != ResolveMethod::Average,
            normal,
            second_layer_output,
            written,
            layer_extras: second_layer_output,
        })
    }

    /// Compile now every program that [`Resolver::run`] with these inputs,
    /// target and settings will use, so that no frame pays for a compile
    /// and a shader error surfaces at set-up.
    pub fn prepare(
        &mut self,
        gl: &glow::Context,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        settings: &ResolveSettings,
        extra: impl Into<ExtraOutputs>,
    ) -> Result<()> {
        let key = Self::base_key(inputs, target, settings, extra.into(), false)?;
        self.program(gl, &key)?;
        Ok(())
    }

    /// [`Resolver::prepare`] for [`Resolver::run_second_layer`].
    pub fn prepare_second_layer(
        &mut self,
        gl: &glow::Context,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        settings: &ResolveSettings,
        reference_output: bool,
        pass: LayerPass,
    ) -> Result<()> {
        let key = Self::second_layer_key(inputs, target, settings, reference_output, pass)?;
        self.program(gl, &key)?;
        Ok(())
    }

    fn second_layer_key(
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        settings: &ResolveSettings,
        reference_output: bool,
        pass: LayerPass,
    ) -> Result<ResolveProgramKey> {
        if settings.layers != 2 {
            return Err(Error::invalid(format!(
                "a second layer needs ResolveSettings::layers = 2, not {}",
                settings.layers
            )));
        }
        let extra = ExtraOutputs {
            reference: reference_output && pass.extras,
            ..ExtraOutputs::default()
        };
        let mut key = Self::base_key(inputs, target, settings, extra, true)?;
        key.written &= pass.colors;
        key.layer_extras = pass.extras;
        Ok(key)
    }

    /// Resolve the second layer of `inputs` (the largest cluster of samples
    /// outside the first layer's; see the README's "second layer") into
    /// `target` (a depth-stencil attachment is used for `stencil` alone): colour attachment `k`
    /// receives input `k` (0 where a pixel has one cluster), colour
    /// attachment `colors.len()` the coverage `(n2 + j2) / N` (0 where a
    /// pixel has one cluster), `colors.len() + 1` the second cluster's
    /// depth-buffer value (a float target; the clear depth where there is
    /// none) and, with `reference_output`, `colors.len() + 2` the second
    /// cluster's seed sample (0 where there is none; an unsigned-integer
    /// target, as [`ExtraOutputs::reference`]). With `stencil`, only pixels
    /// whose stencil value in `target` equals it are resolved (an early
    /// test: the others keep what the target held). `pass` says which of
    /// these outputs this draw writes ([`LayerPass::all`]: every one, at
    /// the draw buffers above; otherwise the chosen colours at draw buffers
    /// `0..` in input order, then the extras). Needs
    /// `params.settings.layers == 2`. The host's GL state is kept, as
    /// [`Resolver::run`] keeps it.
    #[allow(clippy::too_many_arguments)]
    pub fn run_second_layer(
        &mut self,
        gl: &glow::Context,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        reference_output: bool,
        stencil: Option<u8>,
        pass: LayerPass,
    ) -> Result<()> {
        let key = Self::second_layer_key(inputs, target, &params.settings, reference_output, pass)?;
        let run = DrawRun {
            stage: "the second layer's resolve pass",
            stencil,
        };
        self.run_key(gl, key, inputs, target, params, run)
    }
    /// Resolve `inputs` into `target`, whose colour attachment `k` (draw buffer
    /// `k`) receives input `k`, whose depth attachment (if any) receives the
    /// resolved depth, and whose draw buffer `colors.len()` receives the
    /// complex-pixel mask when `complex_output` is set. Programs not yet
    /// built ([`Resolver::prepare`]) are built first. The host's GL state,
    /// texture bindings included, is as it was afterwards.
    pub fn run(
        &mut self,
        gl: &glow::Context,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        extra: impl Into<ExtraOutputs>,
    ) -> Result<()> {
        let base = Self::base_key(inputs, target, &params.settings, extra.into(), false)?;
        let run = DrawRun {
            stage: "the resolve pass",
            stencil: None,
        };
        self.run_key(gl, base, inputs, target, params, run)
    }

    fn run_key(
        &mut self,
        gl: &glow::Context,
        base: ResolveProgramKey,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        run: DrawRun<'_>,
    ) -> Result<()> {
        if matches!(inputs.key, KeySource::WorldPosition(_)) && params.view_row.is_none() {
            return Err(Error::invalid(
                "the depth key is a world-space position, so each frame needs the view matrix \
                 (Frame::with_view)",
            ));
        }
        // An error the host left pending is not the resolve's: report it apart.
        if let Err(e) = check_error(gl, "the host's GL calls before the resolve") {
            log::warn!("{e}");
        }
        // Units 0..=colors hold the inputs.
        let mut state = SavedState::capture(gl, inputs.colors.len() as u32 + 1);
        if run.stencil.is_some() {
            // The draw tests the target's stencil.
            state.keep_stencil_func(gl)?;
        }
        let state = state.guard(gl);
        let result = self.draw(gl, &base, inputs, target, params, run.stencil);
        drop(state);
        result?;
        check_error(gl, run.stage)
    }

    /// One draw of the program for `key` into `target`, a full-screen triangle.
    fn draw(
        &mut self,
        gl: &glow::Context,
        key: &ResolveProgramKey,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        stencil: Option<u8>,
    ) -> Result<()> {
        let vao = self.vao.raw;
        let program = self.program(gl, key)?;
        let s = params.settings;
        unsafe {
            target.bind(gl);
            SavedState::prepare_fullscreen_pass(gl);
            // sRGB attachments: the twins' samples are read decoded, blended in
            // linear light and encoded again on the way into the host's
            // texture (a no-op for linear attachments).
            gl.enable(glow::FRAMEBUFFER_SRGB);
            if key.write_depth {
                gl.enable(glow::DEPTH_TEST);
                gl.depth_func(glow::ALWAYS);
                gl.depth_mask(true);
            } else {
                gl.disable(glow::DEPTH_TEST);
            }
            if let Some(value) = stencil {
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::EQUAL, i32::from(value), 0xFF);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
                gl.stencil_mask(0);
            }
            program.bind(gl);
            // Units as build_program set them: depth at 0, attachment k at 1 + k.
            inputs.depth.bind(gl, 0);
            for (k, tex) in inputs.colors.iter().enumerate() {
                tex.bind(gl, 1 + k as u32);
            }
            let proj = params.projection;
            program.set_f32(gl, "u_clear_depth", proj.clear_depth as f32);
            let to_ndc = if proj.zero_to_one {
                [1.0, 0.0]
            } else {
                [2.0, -1.0]
            };
            program.set_vec2(gl, "u_depth_to_ndc", to_ndc);
            program.set_vec2(gl, "u_projection", [proj.p22 as f32, proj.p23 as f32]);
            program.set_f32(gl, "u_footprint", params.footprint() as f32);
            program.set_f32(gl, "u_c", s.c as f32);
            program.set_f32(gl, "u_c_in", s.c_in as f32);
            if let Some(row) = params.view_row {
                program.set_vec4(gl, "u_view_row", row.map(|v| v as f32));
            }
            if let Some(region) = s.selection.region {
                let u = region.window_uniform(params.height_px);
                program.set_vec4(gl, "u_region", u.map(|v| v as f32));
            }
            if let Some(d) = s.selection.max_depth {
                program.set_f32(gl, "u_max_depth", d as f32);
            }
            if key.normal.is_some() {
                program.set_f32(gl, "u_normal_threshold", s.normal_threshold as f32);
            }
            gl.bind_vertex_array(Some(vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
        }
        Ok(())
    }

    /// Free the programs and the vertex array.
    pub fn destroy(self, gl: &glow::Context) {
        for (_, program) in self.programs {
            program.destroy(gl);
        }
        self.vao.destroy(gl);
    }
}

impl crate::gl::GlObject for Resolver {
    fn handles(&self, out: &mut Vec<crate::gl::Handle>) {
        for program in self.programs.values() {
            program.handles(out);
        }
        self.vao.handles(out);
    }
}

fn build_program(gl: &glow::Context, key: &ResolveProgramKey) -> Result<Program> {
    let mut frag_outputs: Vec<(String, u32)> = Vec::new();
    for k in (0..key.attachments.len()).filter(|&k| key.written & (1 << k) != 0) {
        let location = frag_outputs.len() as u32;
        frag_outputs.push((format!("o_att{k}"), location));
    }
    let mut next = frag_outputs.len() as u32;
    if key.complex_output {
        frag_outputs.push(("o_complex".into(), next));
        next += 1;
    }
    if key.outside_output {
        frag_outputs.push(("o_outside".into(), next));
        next += 1;
    }
    if key.second_layer_output && key.layer_extras {
        frag_outputs.push(("o_coverage".into(), next));
        frag_outputs.push(("o_layer_depth".into(), next + 1));
        next += 2;
    }
    if key.reference_output {
        frag_outputs.push(("o_reference".into(), next));
    }
    let frag_outputs: Vec<(&str, u32)> = frag_outputs
        .iter()
        .map(|(name, k)| (name.as_str(), *k))
        .collect();
    let label = format!(
        "resolve{} {}x {} {} ({} attachments)",
        if key.second_layer_output {
            " (second layer)"
        } else {
            ""
        },
        key.samples,
        key.method,
        key.window,
        key.attachments.len(),
    );
    let fragment = resolve_fragment_source(&preamble(&[], &key.defines()));
    let vertex = fragment
        .header_only()
        .part("fullscreen.vert", FULLSCREEN_VERT);
    let program = Program::from_sources(
        gl,
        &label,
        &[
            (ShaderStage::Vertex, &vertex),
            (ShaderStage::Fragment, &fragment),
        ],
        &frag_outputs,
    )?;
    // The samplers' units and +inf never change: set once here, not per
    // frame (a program keeps its uniforms).
    program.set_at_setup(gl, |p| {
        p.set_i32(gl, "u_depth", 0);
        for k in 0..key.attachments.len() {
            p.set_i32(gl, &format!("u_att{k}"), 1 + k as i32);
        }
        p.set_f32(gl, "u_infinity", f32::INFINITY);
    });
    Ok(program)
}
