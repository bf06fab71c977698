//! The depth-aware resolve: a full-screen pass that reads every sample of a
//! multisampled G-buffer and writes a single-sample one (its math:
//! docs/resolve.md in the repository, "The math").
//!
//! The math lives in two places only: `resolve.frag` and its CPU
//! reference, [`cpu`]. This module builds the shader permutations (the sample
//! count, attachment set and options are compile-time defines, cached by a
//! typed key) and runs the pass.

pub mod cpu;
mod inputs;
mod key;
mod settings;
mod stencil;

pub use inputs::{ExtraOutputs, KeySource, MAX_ATTACHMENTS, ResolveInputs, ResolveSlot};
pub use key::LayerPass;
use key::all_bits;
pub(crate) use key::{ResolveProgramKey, SelectionKey};
pub use settings::{
    DEFAULT_NORMAL_THRESHOLD, DepthProjection, NormalEncoding, Region, ResolveMethod, ResolveRule,
    ResolveSettings, Selection, SelectionFlag, Window,
};
pub(crate) use stencil::StencilPass;
pub use stencil::{STENCIL_COPY_FRAG, StencilCopy};

use crate::gl::format::SampleKind;
use crate::gl::{
    FULLSCREEN_VERT, Framebuffer, Program, SavedState, ShaderSource, ShaderStage, VertexArray,
    check_error, preamble,
};
use crate::{Error, Result};
use glow::HasContext;
use std::collections::HashMap;

/// The resolve's fragment shader body; it needs [`COMPLEX_GLSL`] and
/// [`NORMALS_GLSL`] in front of it (see [`resolve_fragment_source`]).
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

/// How the resolve decodes a stored normal and tests two samples' normals
/// (`normals.glsl`), the part before [`CREASE_GLSL`].
pub const NORMALS_GLSL: &str = include_str!("normals.glsl");

/// The resolve's sample pattern and crease rule (`crease.glsl`), the part
/// between [`NORMALS_GLSL`] and [`RESOLVE_FRAG`].
pub const CREASE_GLSL: &str = include_str!("crease.glsl");

/// The resolve's fragment stage: `header`, then [`COMPLEX_GLSL`],
/// [`NORMALS_GLSL`], [`CREASE_GLSL`] and [`RESOLVE_FRAG`] as four parts (so
/// messages name the right file).
pub fn resolve_fragment_source(header: &str) -> ShaderSource {
    ShaderSource::with_header(header)
        .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
        .part("normals.glsl", NORMALS_GLSL)
        .part("crease.glsl", CREASE_GLSL)
        .part("resolve.frag", RESOLVE_FRAG)
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
            majority_reference: normal.is_some() && s.method != ResolveMethod::Average,
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
        check_view(inputs.key, params.view_row)?;
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
            program.set_f32(gl, "u_tan_half_fov_y", (params.fov_y / 2.0).tan() as f32);
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

/// A world-space key needs each frame's view matrix.
pub(crate) fn check_view(key: KeySource, view_row: Option<[f64; 4]>) -> Result<()> {
    if matches!(key, KeySource::WorldPosition(_)) && view_row.is_none() {
        return Err(Error::invalid(
            "the depth key is a world-space position, so each frame needs the view matrix \
             (Frame::with_view)",
        ));
    }
    Ok(())
}
