//! The depth-aware resolve: a full-screen pass that reads every sample of a
//! multisampled G-buffer and writes a single-sample one (DESIGN.md section 3).
//!
//! The math lives in two places only: `shaders_glsl/resolve.frag` and its CPU
//! reference, [`cpu`]. This module builds the shader permutations (the sample
//! count, attachment set and options are compile-time defines, cached by a
//! typed key) and runs the pass.

pub mod cpu;
mod settings;
pub mod tiles;

pub use settings::{
    DepthProjection, Region, ResolveMethod, ResolveRule, ResolveSettings, Selection, SelectionFlag,
    Window,
};
use tiles::{RESOLVE_TILES_VERT, TileMask};

use crate::gl::format::SampleKind;
use crate::gl::{
    Framebuffer, Program, ShaderStage, TextureRef, VertexArray, check_error, preamble,
};
use crate::{Error, Result};
use glow::HasContext;
use std::collections::HashMap;

/// The resolve's fragment shader body.
pub const RESOLVE_FRAG: &str = include_str!("../../shaders_glsl/resolve.frag");
/// The full-screen triangle's vertex shader body.
pub const FULLSCREEN_VERT: &str = include_str!("../../shaders_glsl/fullscreen.vert");

/// The most colour attachments one resolve handles (GL 3.2 guarantees 8 draw buffers).
pub const MAX_ATTACHMENTS: usize = 8;

/// Where the per-sample depth key comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum KeySource {
    /// `z = −position.z` of the colour attachment with this index.
    Position(usize),
    /// The depth attachment, linearised with the projection.
    Depth,
}

/// Everything that selects one compiled resolve program.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ResolveProgramKey {
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
    /// Write `gl_FragDepth`.
    pub write_depth: bool,
    /// Blend depth instead of selecting the reference's.
    pub blend_depth: bool,
    /// Write the complex-pixel mask to output `attachments.len()`.
    pub complex_output: bool,
    /// Which of the resolve's passes this program is.
    pub pass: ResolvePass,
    /// Selective anti-aliasing criteria compiled in.
    pub selection: SelectionKey,
}

/// The passes of a resolve ([`tiles`] explains the tiled schedule).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ResolvePass {
    /// The whole resolve over a full-screen triangle.
    Single,
    /// The tile classification, `tile_size` pixels square.
    ClassifyTiles {
        /// Tile edge in pixels.
        tile_size: u32,
    },
    /// Every pixel copies sample 0 (the slow tiles are drawn over it next).
    OneSample,
    /// The tiles with a slow pixel: the single-pass program on the tile grid.
    SlowTiles {
        /// Tile edge in pixels.
        tile_size: u32,
    },
}

/// The compiled-in shape of a [`Selection`] (its numbers are uniforms).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SelectionKey {
    /// `Some(true)` for an ellipse, `Some(false)` for a rectangle.
    pub region_ellipse: Option<bool>,
    /// A depth threshold is set.
    pub max_depth: bool,
    /// The flag's attachment and component.
    pub flag: Option<SelectionFlag>,
}

impl SelectionKey {
    /// The shape of `selection`.
    pub fn of(selection: &Selection) -> Self {
        SelectionKey {
            region_ellipse: selection
                .region
                .map(|r| matches!(r, Region::Ellipse { .. })),
            max_depth: selection.max_depth.is_some(),
            flag: selection.flag,
        }
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
        if let KeySource::Position(k) = self.key {
            def("KEY_SAMPLER", format!("u_att{k}"));
            def("KEY_INDEX", k.to_string());
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
            if let (true, Some(k)) = (self.plane_uniformity, first_blended) {
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
        match self.pass {
            ResolvePass::Single => {}
            ResolvePass::ClassifyTiles { tile_size } => {
                def("PASS_CLASSIFY_TILES", "1".into());
                def("TILE_SIZE", tile_size.to_string());
            }
            ResolvePass::OneSample => def("PASS_ONE_SAMPLE", "1".into()),
            ResolvePass::SlowTiles { tile_size } => def("TILE_SIZE", tile_size.to_string()),
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
        if let Some(f) = sel.flag {
            def("SELECT_FLAG_SAMPLER", format!("u_att{}", f.attachment));
            let component = ["x", "y", "z", "w"][usize::from(f.component.min(3))];
            def("SELECT_FLAG_COMPONENT", component.into());
        }
        d
    }

    /// The vertex shader this pass draws with.
    fn vertex_shader(&self) -> (&'static str, &'static str) {
        match self.pass {
            ResolvePass::Single | ResolvePass::ClassifyTiles { .. } | ResolvePass::OneSample => {
                ("fullscreen.vert", FULLSCREEN_VERT)
            }
            ResolvePass::SlowTiles { .. } => ("resolve_tiles.vert", RESOLVE_TILES_VERT),
        }
    }
}

/// The inputs of one resolve.
#[derive(Clone, Debug)]
pub struct ResolveInputs<'a> {
    /// The multisampled depth texture (or its per-sample layer array).
    pub depth: TextureRef,
    /// The multisampled colour textures, in output order.
    pub colors: &'a [TextureRef],
    /// One rule per colour texture.
    pub rules: &'a [ResolveRule],
    /// Where the depth key comes from.
    pub key: KeySource,
    /// Sample count; for layer arrays, the number of layers.
    pub samples: u32,
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
    schedule: Schedule,
    tiles: Option<TileMask>,
}

/// How a resolve finds the pixels that take one sample (uniform pixels on
/// the fast path, pixels outside a selective-AA selection). Every schedule
/// gives the same values; they differ in speed, by GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Schedule {
    /// One full-screen pass; a per-pixel branch skips the slow path (the
    /// default). Where branches are real (GPUs take them 32–64 pixels at a
    /// time) uniform regions skip it.
    OnePass,
    /// Classify tiles of this many pixels ([`tiles::TILE_SIZE`] is the size
    /// measured), copy sample 0 everywhere, then draw only the slow tiles
    /// with the full program ([`tiles`]): for a rasteriser that runs both
    /// sides of every branch, as llvmpipe does, but never visits a tile it
    /// is not given. Measured on llvmpipe (README, "What the resolve
    /// costs") it wins only where slow tiles are few, by less than the
    /// noise, and loses 2x where they are many, because classifying costs
    /// about what the slow path saves there.
    Tiles(u32),
}

impl Resolver {
    /// Create the pass (programs are built on first use), with the
    /// one-pass schedule ([`Schedule`]).
    pub fn new(gl: &glow::Context) -> Result<Self> {
        Ok(Resolver {
            programs: HashMap::new(),
            vao: VertexArray::new(gl, "resolve full-screen triangle")?,
            schedule: Schedule::OnePass,
            tiles: None,
        })
    }

    /// Choose how one-sample pixels are found (see [`Schedule`]).
    pub fn set_schedule(&mut self, schedule: Schedule) -> Result<()> {
        if schedule == Schedule::Tiles(0) {
            return Err(Error::invalid("a resolve tile must be at least 1 pixel"));
        }
        self.schedule = schedule;
        Ok(())
    }

    /// The schedule in use.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    /// The program for `key`, built on first use.
    pub fn program(&mut self, gl: &glow::Context, key: &ResolveProgramKey) -> Result<&Program> {
        match self.programs.entry(key.clone()) {
            std::collections::hash_map::Entry::Occupied(e) => Ok(e.into_mut()),
            std::collections::hash_map::Entry::Vacant(v) => Ok(v.insert(build_program(gl, key)?)),
        }
    }

    /// Number of cached programs.
    pub fn cached_programs(&self) -> usize {
        self.programs.len()
    }

    /// Resolve `inputs` into `target`, whose colour attachment `k` (draw buffer
    /// `k`) receives input `k`, whose depth attachment (if any) receives the
    /// resolved depth, and whose draw buffer `colors.len()` receives the
    /// complex-pixel mask when `complex_output` is set.
    pub fn run(
        &mut self,
        gl: &glow::Context,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        complex_output: bool,
    ) -> Result<()> {
        params.settings.validate()?;
        // An error the host left pending is not the resolve's: report it apart.
        if let Err(e) = check_error(gl, "the host's GL calls before the resolve") {
            log::warn!("{e}");
        }
        if inputs.colors.len() != inputs.rules.len() {
            return Err(Error::Layout(format!(
                "{} colour inputs but {} rules",
                inputs.colors.len(),
                inputs.rules.len()
            )));
        }
        if inputs.colors.len() > MAX_ATTACHMENTS {
            return Err(Error::Layout(format!(
                "{} colour attachments; the resolve handles at most {MAX_ATTACHMENTS}",
                inputs.colors.len()
            )));
        }
        let mut attachments = Vec::with_capacity(inputs.colors.len());
        for (tex, &rule) in inputs.colors.iter().zip(inputs.rules) {
            let kind = tex.format.sample_kind();
            if kind != SampleKind::Float && rule != ResolveRule::Select {
                return Err(Error::UnsupportedFormat {
                    attachment: format!("{} input", tex.format),
                    format: tex.format.name().into(),
                    reason: format!(
                        "integer formats can only be selected, not resolved by `{rule}`"
                    ),
                });
            }
            attachments.push((rule, kind));
        }
        let s = params.settings;
        if let Some(flag) = s.selection.flag {
            match inputs.colors.get(flag.attachment) {
                None => {
                    return Err(Error::invalid(format!(
                        "the selective-AA flag is in colour attachment {}, but the resolve has {} colour attachments",
                        flag.attachment,
                        inputs.colors.len()
                    )));
                }
                Some(tex) if tex.format.sample_kind() != SampleKind::Float => {
                    return Err(Error::UnsupportedFormat {
                        attachment: format!("colour attachment {}", flag.attachment),
                        format: tex.format.name().into(),
                        reason: "the selective-AA flag must be in a float or normalised format"
                            .into(),
                    });
                }
                Some(_) => {}
            }
        }
        let write_depth = target.attachments.iter().any(|(_, t)| t.format.is_depth());
        let base = ResolveProgramKey {
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
            write_depth,
            blend_depth: s.blend_depth && write_depth,
            complex_output,
            pass: ResolvePass::Single,
            selection: SelectionKey::of(&s.selection),
        };
        // Splitting pays off only when some pixels may take one sample.
        let splits = s.fast_path || s.selection.is_active();
        let schedule = if splits {
            self.schedule
        } else {
            Schedule::OnePass
        };
        let state = SavedState::capture(gl);
        let result = match schedule {
            Schedule::OnePass => self.draw(gl, &base, inputs, target, params, None),
            Schedule::Tiles(tile_size) => {
                self.run_tiled(gl, base, inputs, target, params, tile_size)
            }
        };
        unsafe {
            for k in 0..=inputs.colors.len() as u32 + 1 {
                gl.active_texture(glow::TEXTURE0 + k);
                gl.bind_texture(inputs.depth.target, None);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
                gl.bind_texture(glow::TEXTURE_2D, None);
            }
        }
        state.restore(gl);
        result?;
        check_error(gl, "the resolve pass")
    }

    /// The tiled schedule: classify, then one-sample tiles, then slow tiles.
    fn run_tiled(
        &mut self,
        gl: &glow::Context,
        base: ResolveProgramKey,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        tile_size: u32,
    ) -> Result<()> {
        let size = (target.width, target.height);
        let stale = self
            .tiles
            .as_ref()
            .is_some_and(|t| t.target != size || t.tile_size != tile_size);
        if stale {
            if let Some(old) = self.tiles.take() {
                old.destroy(gl);
            }
        }
        if self.tiles.is_none() {
            self.tiles = Some(TileMask::new(gl, size.0, size.1, tile_size)?);
        }
        let Some(mask) = self.tiles.take() else {
            return Err(Error::invalid("the resolve tile mask is missing"));
        };
        let result = (|| {
            let classify = ResolveProgramKey {
                pass: ResolvePass::ClassifyTiles { tile_size },
                write_depth: false,
                blend_depth: false,
                complex_output: false,
                ..base.clone()
            };
            self.draw(gl, &classify, inputs, mask.framebuffer(), params, None)?;
            // Sample 0 everywhere, over a full-screen triangle: cheaper than
            // drawing the one-sample tiles apart, whose two triangles each
            // would make a rasteriser shade the blocks on their shared
            // diagonal twice. The slow tiles are then drawn over it.
            let one = ResolveProgramKey {
                pass: ResolvePass::OneSample,
                ..base.clone()
            };
            self.draw(gl, &one, inputs, target, params, None)?;
            let slow = ResolveProgramKey {
                pass: ResolvePass::SlowTiles { tile_size },
                ..base
            };
            self.draw(gl, &slow, inputs, target, params, Some(&mask))
        })();
        self.tiles = Some(mask);
        result
    }

    /// One draw of the program for `key` into `target`; over the tile grid
    /// of `tiles` when given, else a full-screen triangle.
    fn draw(
        &mut self,
        gl: &glow::Context,
        key: &ResolveProgramKey,
        inputs: &ResolveInputs<'_>,
        target: &Framebuffer,
        params: &ResolveParams,
        tiles: Option<&TileMask>,
    ) -> Result<()> {
        let vao = self.vao.raw;
        let program = self.program(gl, key)?;
        let s = params.settings;
        unsafe {
            target.bind(gl);
            gl.disable(glow::BLEND);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::STENCIL_TEST);
            if key.write_depth {
                gl.enable(glow::DEPTH_TEST);
                gl.depth_func(glow::ALWAYS);
                gl.depth_mask(true);
            } else {
                gl.disable(glow::DEPTH_TEST);
            }
            gl.color_mask(true, true, true, true);
            program.bind(gl);
            inputs.depth.bind(gl, 0);
            program.set_i32(gl, "u_depth", 0);
            for (k, tex) in inputs.colors.iter().enumerate() {
                tex.bind(gl, 1 + k as u32);
                program.set_i32(gl, &format!("u_att{k}"), 1 + k as i32);
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
            program.set_f32(gl, "u_infinity", f32::INFINITY);
            if let Some(region) = s.selection.region {
                let u = region.window_uniform(params.height_px);
                program.set_vec4(gl, "u_region", u.map(|v| v as f32));
            }
            if let Some(d) = s.selection.max_depth {
                program.set_f32(gl, "u_max_depth", d as f32);
            }
            if let Some(loc) = program.uniform(gl, "u_size") {
                // The resolved pixels' extent (the inputs' size).
                let (w, h) = (inputs.depth.width as i32, inputs.depth.height as i32);
                gl.uniform_2_i32(Some(&loc), w, h);
            }
            gl.bind_vertex_array(Some(vao));
            match tiles {
                None => gl.draw_arrays(glow::TRIANGLES, 0, 3),
                Some(mask) => {
                    let unit = 1 + inputs.colors.len() as u32;
                    mask.texture().bind(gl, unit);
                    program.set_i32(gl, "u_tiles", unit as i32);
                    gl.draw_arrays(glow::TRIANGLES, 0, 6 * mask.tiles() as i32);
                }
            }
        }
        Ok(())
    }

    /// Free the programs, the vertex array and the tile mask.
    pub fn destroy(self, gl: &glow::Context) {
        for (_, program) in self.programs {
            program.destroy(gl);
        }
        self.vao.destroy(gl);
        if let Some(t) = self.tiles {
            t.destroy(gl);
        }
    }
}

fn build_program(gl: &glow::Context, key: &ResolveProgramKey) -> Result<Program> {
    let mut frag_outputs: Vec<(String, u32)> = Vec::new();
    if matches!(key.pass, ResolvePass::ClassifyTiles { .. }) {
        frag_outputs.push(("o_tile".into(), 0));
    } else {
        for k in 0..key.attachments.len() {
            frag_outputs.push((format!("o_att{k}"), k as u32));
        }
        if key.complex_output {
            frag_outputs.push(("o_complex".into(), key.attachments.len() as u32));
        }
    }
    let frag_outputs: Vec<(&str, u32)> = frag_outputs
        .iter()
        .map(|(name, k)| (name.as_str(), *k))
        .collect();
    let label = format!(
        "resolve {}x {} {} ({} attachments, {:?})",
        key.samples,
        key.method,
        key.window,
        key.attachments.len(),
        key.pass
    );
    Program::build(
        gl,
        &label,
        &preamble(&[], &key.defines()),
        &[
            (
                ShaderStage::Vertex,
                key.vertex_shader().0,
                key.vertex_shader().1,
            ),
            (ShaderStage::Fragment, "resolve.frag", RESOLVE_FRAG),
        ],
        &frag_outputs,
    )
}

/// The host state a pass changes, put back afterwards: the crate runs inside
/// the host's context and must leave it as it found it.
pub(crate) struct SavedState {
    framebuffer: i32,
    program: i32,
    vertex_array: i32,
    active_texture: i32,
    viewport: [i32; 4],
    depth_test: bool,
    depth_func: i32,
    depth_mask: bool,
    blend: bool,
    cull: bool,
    scissor: bool,
    stencil: bool,
    color_mask: [bool; 4],
    /// Per face (front, back): stencil func, ref, value mask, fail/zfail/zpass
    /// ops, write mask.
    stencil_state: [[i32; 7]; 2],
}

impl SavedState {
    pub(crate) fn capture(gl: &glow::Context) -> Self {
        unsafe {
            let mut viewport = [0; 4];
            gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
            SavedState {
                framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING),
                program: gl.get_parameter_i32(glow::CURRENT_PROGRAM),
                vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING),
                active_texture: gl.get_parameter_i32(glow::ACTIVE_TEXTURE),
                viewport,
                depth_test: gl.is_enabled(glow::DEPTH_TEST),
                depth_func: gl.get_parameter_i32(glow::DEPTH_FUNC),
                depth_mask: gl.get_parameter_i32(glow::DEPTH_WRITEMASK) != 0,
                blend: gl.is_enabled(glow::BLEND),
                cull: gl.is_enabled(glow::CULL_FACE),
                scissor: gl.is_enabled(glow::SCISSOR_TEST),
                stencil: gl.is_enabled(glow::STENCIL_TEST),
                color_mask: {
                    let mut m = [0i32; 4];
                    gl.get_parameter_i32_slice(glow::COLOR_WRITEMASK, &mut m);
                    m.map(|c| c != 0)
                },
                stencil_state: [
                    [
                        glow::STENCIL_FUNC,
                        glow::STENCIL_REF,
                        glow::STENCIL_VALUE_MASK,
                        glow::STENCIL_FAIL,
                        glow::STENCIL_PASS_DEPTH_FAIL,
                        glow::STENCIL_PASS_DEPTH_PASS,
                        glow::STENCIL_WRITEMASK,
                    ]
                    .map(|p| gl.get_parameter_i32(p)),
                    [
                        glow::STENCIL_BACK_FUNC,
                        glow::STENCIL_BACK_REF,
                        glow::STENCIL_BACK_VALUE_MASK,
                        glow::STENCIL_BACK_FAIL,
                        glow::STENCIL_BACK_PASS_DEPTH_FAIL,
                        glow::STENCIL_BACK_PASS_DEPTH_PASS,
                        glow::STENCIL_BACK_WRITEMASK,
                    ]
                    .map(|p| gl.get_parameter_i32(p)),
                ],
            }
        }
    }

    pub(crate) fn restore(&self, gl: &glow::Context) {
        fn set(gl: &glow::Context, cap: u32, on: bool) {
            unsafe { if on { gl.enable(cap) } else { gl.disable(cap) } }
        }
        unsafe {
            gl.bind_framebuffer(
                glow::DRAW_FRAMEBUFFER,
                std::num::NonZeroU32::new(self.framebuffer as u32).map(glow::NativeFramebuffer),
            );
            gl.use_program(std::num::NonZeroU32::new(self.program as u32).map(glow::NativeProgram));
            gl.bind_vertex_array(
                std::num::NonZeroU32::new(self.vertex_array as u32).map(glow::NativeVertexArray),
            );
            gl.active_texture(self.active_texture as u32);
            gl.viewport(
                self.viewport[0],
                self.viewport[1],
                self.viewport[2],
                self.viewport[3],
            );
            gl.depth_func(self.depth_func as u32);
            gl.depth_mask(self.depth_mask);
            let [r, g, b, a] = self.color_mask;
            gl.color_mask(r, g, b, a);
            for (face, state) in [glow::FRONT, glow::BACK]
                .into_iter()
                .zip(self.stencil_state)
            {
                let [func, reference, mask, fail, zfail, zpass, write] = state;
                gl.stencil_func_separate(face, func as u32, reference, mask as u32);
                gl.stencil_op_separate(face, fail as u32, zfail as u32, zpass as u32);
                gl.stencil_mask_separate(face, write as u32);
            }
        }
        set(gl, glow::DEPTH_TEST, self.depth_test);
        set(gl, glow::BLEND, self.blend);
        set(gl, glow::CULL_FACE, self.cull);
        set(gl, glow::SCISSOR_TEST, self.scissor);
        set(gl, glow::STENCIL_TEST, self.stencil);
    }
}
