//! The G-buffer pass (`geometry.vert` + `geometry.frag`):
//! opaque and alpha-tested objects into the G-buffer. Program and state are
//! the same with and without MSAA; only the bound framebuffer differs (the
//! retrofit's multisampled twin, or the single-sample G-buffer).

use super::shared::bind_target;
use super::slots::GBufferSlots;
use crate::Result;
use crate::gl::{GlObject, Handle, Program, ShaderSource, ShaderStage, check_error};
use crate::renderer::mesh::{
    AttribLocations, BASE_TEXTURE_UNIT, EMISSIVE_TEXTURE_UNIT, GpuScene, set_culling,
};
use glam::{DMat4, Mat4};
use glow::HasContext;

/// The model vertex shader's body (`geometry.vert`, shared
/// with the transparent pass): attributes `a_position`, `a_normal`, `a_uv`;
/// uniforms `u_model_view`, `u_normal_matrix`, `u_projection`. Compiled
/// after [`preamble`](crate::gl::preamble) with no extensions or defines.
pub const GEOMETRY_VERT: &str = include_str!("geometry.vert");
/// The model fragment shader's body (`geometry.frag`): outputs
/// `o_color`, `o_position`, `o_normal`, `o_specular`, `o_emissive`, bound by
/// name to the layout's attachment numbers; material uniforms as set by the
/// renderer. Compiled after [`preamble`](crate::gl::preamble) with no
/// extensions, with and without MSAA alike; a layout the scene-adaptive
/// plan trimmed adds `GBUFFER_NO_SPECULAR` / `GBUFFER_NO_EMISSIVE`, which
/// drop those outputs (the full layout: no defines).
pub const GEOMETRY_FRAG: &str = include_str!("geometry.frag");

/// The model program, its outputs bound to the layout's attachment numbers.
#[derive(Debug)]
pub(crate) struct GeometryPass {
    program: Program,
    slots: GBufferSlots,
    locations: AttribLocations,
}

/// Where a G-buffer pass draws.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GeometryTarget {
    /// The framebuffer.
    pub(crate) fbo: glow::Framebuffer,
    /// Its width.
    pub(crate) width: u32,
    /// Its height.
    pub(crate) height: u32,
}

impl GeometryPass {
    /// Build the program with `o_color`, `o_position`, … bound to `slots`.
    pub(crate) fn new(gl: &glow::Context, slots: GBufferSlots) -> Result<Self> {
        Self::with_fragment(
            gl,
            "geometry",
            slots,
            &[],
            ("geometry.frag", GEOMETRY_FRAG),
            &[],
        )
    }

    /// A program like the model program with another fragment shader
    /// (`frag_name`, `frag_body`, compiled with `extensions`) that writes the
    /// same outputs and `extra_outputs` (name, draw buffer).
    pub(crate) fn with_fragment(
        gl: &glow::Context,
        label: &str,
        slots: GBufferSlots,
        extensions: &[&str],
        (frag_name, frag_body): (&str, &str),
        extra_outputs: &[(&str, u32)],
    ) -> Result<Self> {
        let fragment = Self::header(slots, extensions).part(frag_name, frag_body);
        Self::with_fragment_source(gl, label, slots, &fragment, extra_outputs)
    }

    /// The header of the model program's stages for `slots`: its defines
    /// after `extensions`.
    pub(crate) fn header(slots: GBufferSlots, extensions: &[&str]) -> ShaderSource {
        ShaderSource::new()
            .extensions(extensions)
            .defines(&slots.defines())
    }

    /// [`GeometryPass::with_fragment`] from a composed fragment source; the
    /// vertex stage gets its header and `geometry.vert`.
    pub(crate) fn with_fragment_source(
        gl: &glow::Context,
        label: &str,
        slots: GBufferSlots,
        fragment: &ShaderSource,
        extra_outputs: &[(&str, u32)],
    ) -> Result<Self> {
        let mut outputs = slots.outputs();
        outputs.extend_from_slice(extra_outputs);
        let vertex = fragment.header_only().part("geometry.vert", GEOMETRY_VERT);
        let program = Program::from_sources(
            gl,
            label,
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, fragment),
            ],
            &outputs,
        )?;
        let locations = AttribLocations::of(gl, &program);
        Ok(GeometryPass {
            program,
            slots,
            locations,
        })
    }

    /// The program (to set uniforms of its own, after binding it).
    pub(crate) fn program(&self) -> &Program {
        &self.program
    }

    /// The fragment shader's full source as compiled for `slots`.
    pub(crate) fn fragment_source(slots: GBufferSlots) -> String {
        Self::header(slots, &[])
            .part("geometry.frag", GEOMETRY_FRAG)
            .text()
    }

    /// The attachment numbers the outputs are bound to.
    pub(crate) fn slots(&self) -> GBufferSlots {
        self.slots
    }

    /// Clear `target` (colour 0, depth to `clear_depth`).
    pub(crate) fn clear(gl: &glow::Context, target: GeometryTarget, clear_depth: f32) {
        bind_target(gl, target.fbo, target.width, target.height);
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(f64::from(clear_depth));
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
        }
    }

    /// Draw the scene's opaque and alpha-tested objects into `target`
    /// (depth test `depth_func`: LESS, or GREATER for reversed-Z; depth
    /// written; back faces culled unless double-sided).
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: GeometryTarget,
        scene: &GpuScene,
        view: &DMat4,
        projection: &Mat4,
        depth_func: u32,
    ) -> Result<()> {
        unsafe { gl.enable(glow::MULTISAMPLE) };
        draw_models(
            gl,
            &self.program,
            self.locations,
            target,
            ModelDraw {
                scene,
                view,
                projection,
                depth_func,
            },
        );
        Ok(check_error(gl, "the G-buffer pass")?)
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}

impl GlObject for GeometryPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}

/// What a model program draws: the scene's opaque and alpha-tested objects
/// seen through `view` and `projection`, depth-tested with `depth_func`.
#[derive(Clone, Copy)]
pub(crate) struct ModelDraw<'a> {
    pub(crate) scene: &'a GpuScene,
    pub(crate) view: &'a DMat4,
    pub(crate) projection: &'a Mat4,
    pub(crate) depth_func: u32,
}

/// Draw every opaque and alpha-tested object with a model program built on
/// `geometry.vert`/`geometry.frag` (any extra uniform of the program is the
/// caller's to set, once it is bound): the G-buffer pass's state (depth
/// test, depth written, no blending, back faces culled unless
/// double-sided), the per-object matrices, material and anti-aliasing flag.
pub(crate) fn draw_models(
    gl: &glow::Context,
    program: &Program,
    locations: AttribLocations,
    target: GeometryTarget,
    draw: ModelDraw<'_>,
) {
    bind_target(gl, target.fbo, target.width, target.height);
    unsafe {
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(draw.depth_func);
        gl.depth_mask(true);
        gl.disable(glow::BLEND);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::FRAMEBUFFER_SRGB);
        gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
        gl.color_mask(true, true, true, true);
    }
    let p = program;
    p.bind(gl);
    p.set_mat4(gl, "u_projection", &draw.projection.to_cols_array());
    p.set_i32(gl, "u_base_texture", BASE_TEXTURE_UNIT as i32);
    p.set_i32(gl, "u_emissive_texture", EMISSIVE_TEXTURE_UNIT as i32);
    for item in &draw.scene.gbuffer_items {
        let (model_view, normal) = item.matrices(draw.view);
        p.set_mat4(gl, "u_model_view", &model_view);
        p.set_mat4(gl, "u_normal_matrix", &normal);
        draw.scene.bind_material(gl, p, &item.material);
        p.set_f32(gl, "u_no_antialias", if item.antialias { 0.0 } else { 1.0 });
        set_culling(gl, &item.material);
        draw.scene.meshes[item.mesh].draw(gl, locations);
    }
    unsafe { gl.bind_vertex_array(None) };
}

/// The model shader `geometry.frag` with its `main()` renamed `model_main`
/// (every wrapper that records more per fragment calls it), then `wrapper`
/// parts, after `header`'s version, extensions and defines. Each part keeps
/// its own line numbers ([`ShaderSource`]).
pub(crate) fn model_wrapped(header: ShaderSource, wrapper: &[(&str, &str)]) -> ShaderSource {
    let model = header.part_renaming_main("geometry.frag", GEOMETRY_FRAG, "model_main");
    wrapper
        .iter()
        .fold(model, |source, (name, text)| source.part(name, text))
}
