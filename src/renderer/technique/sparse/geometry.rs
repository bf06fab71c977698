//! The passes of [`AaMode::Sparse`](crate::renderer::AaMode::Sparse) that
//! build the linked lists: the multisampled depth pre-pass
//! (`sparse_depth.frag`), the set-up pass that empties the lists and writes
//! sample 0's depth into the G-buffer (`sparse_setup.frag`), and the
//! G-buffer pass that writes one block per visible fragment
//! (`geometry.frag` unchanged, wrapped by `sparse_geometry.frag`). The
//! pre-pass and the G-buffer pass share `geometry.vert`, so a visible
//! fragment's depth is bitwise the one the pre-pass stored and the depth
//! test EQUAL finds it.

use super::shader::{EXTENSIONS, SPARSE_FRAG, apply_region};
use super::targets::SparseTargets;
use crate::Result;
use crate::gl::{
    FullscreenPass, GlObject, Handle, Made, Program, ShaderSource, ShaderStage, TextureRef,
    VertexArray, check_error,
};
use crate::renderer::mesh::{
    AttribLocations, BASE_TEXTURE_UNIT, EMISSIVE_TEXTURE_UNIT, GpuScene, set_culling,
};
use crate::renderer::pass::geometry::GEOMETRY_VERT;
use crate::renderer::pass::geometry::model_wrapped;
use crate::renderer::pass::shared::{begin_fullscreen, bind_target, draw_fullscreen};
use crate::resolve::{COMPLEX_GLSL, COMPLEX_GLSL_NAME, Region};
use glam::{DMat4, Mat4};
use glow::HasContext;

/// The pre-pass's fragment shader (the alpha test only).
pub(crate) const SPARSE_DEPTH_FRAG: &str = include_str!("sparse_depth.frag");
/// The set-up pass's body (after `sparse.frag`).
pub(crate) const SPARSE_SETUP_FRAG: &str = include_str!("sparse_setup.frag");
/// The G-buffer pass's wrapper (after `geometry.frag` and `sparse.frag`).
pub(crate) const SPARSE_GEOMETRY_FRAG: &str = include_str!("sparse_geometry.frag");

/// A model program and where it reads its attributes.
#[derive(Debug)]
struct ModelProgram {
    program: Program,
    locations: AttribLocations,
}

impl ModelProgram {
    /// `geometry.vert` and `fragment`, the vertex stage with the fragment
    /// stage's header.
    fn build(gl: &glow::Context, label: &str, fragment: &ShaderSource) -> Result<Self> {
        let vertex = fragment.header_only().part("geometry.vert", GEOMETRY_VERT);
        let program = Program::from_sources(
            gl,
            label,
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, fragment),
            ],
            // geometry.frag's outputs: the framebuffer has no colour
            // attachment, so what they get is dropped.
            &[
                ("o_color", 0),
                ("o_position", 1),
                ("o_normal", 2),
                ("o_specular", 3),
                ("o_emissive", 4),
            ],
        )?;
        let locations = AttribLocations::of(gl, &program);
        Ok(ModelProgram { program, locations })
    }
}

impl GlObject for ModelProgram {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}

/// What the list-building passes draw with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BuildParams<'a> {
    /// World to view.
    pub(crate) view: &'a DMat4,
    /// The projection of the frame's depth mode.
    pub(crate) projection: &'a Mat4,
    /// LESS, or GREATER with reversed-Z.
    pub(crate) nearer_func: u32,
    /// 1.0, or 0.0 with reversed-Z.
    pub(crate) clear_depth: f32,
    /// The anti-aliased region.
    pub(crate) region: Option<Region>,
    /// The view distance beyond which fragments are not anti-aliased.
    pub(crate) max_depth: f32,
}

/// The three list-building programs.
#[derive(Debug)]
pub(crate) struct SparseBuildPasses {
    depth: ModelProgram,
    setup: Program,
    geometry: ModelProgram,
}

impl SparseBuildPasses {
    /// Build the programs (the caller has checked the extensions).
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            let depth = made.keep(ModelProgram::build(
                gl,
                "sparse depth pre-pass",
                &ShaderSource::new().part("sparse_depth.frag", SPARSE_DEPTH_FRAG),
            )?);
            let setup = ShaderSource::new()
                .extensions(EXTENSIONS)
                .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
                .part("sparse.frag", SPARSE_FRAG)
                .part("sparse_setup.frag", SPARSE_SETUP_FRAG);
            let setup = made
                .keep(FullscreenPass::new(gl, "sparse set-up", &setup, &[])?)
                .into_program();
            let geometry = model_wrapped(
                ShaderSource::new().extensions(EXTENSIONS),
                &[
                    (COMPLEX_GLSL_NAME, COMPLEX_GLSL),
                    ("sparse.frag", SPARSE_FRAG),
                    ("sparse_geometry.frag", SPARSE_GEOMETRY_FRAG),
                ],
            );
            let geometry = made.keep(ModelProgram::build(gl, "sparse geometry", &geometry)?);
            Ok(SparseBuildPasses {
                depth,
                setup,
                geometry,
            })
        })
    }

    /// The depth pre-pass: clear depth and stencil, then every opaque and
    /// alpha-tested object, depth only.
    pub(crate) fn draw_depth(
        &self,
        gl: &glow::Context,
        targets: &SparseTargets,
        scene: &GpuScene,
        params: &BuildParams<'_>,
    ) -> Result<()> {
        bind_target(gl, targets.fbo.raw(), targets.width, targets.height);
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.enable(glow::MULTISAMPLE);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.clear_depth_f64(f64::from(params.clear_depth));
            gl.clear_stencil(0);
            gl.clear(glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(params.nearer_func);
        }
        let m = &self.depth;
        m.program.bind(gl);
        m.program
            .set_mat4(gl, "u_projection", &params.projection.to_cols_array());
        m.program
            .set_i32(gl, "u_base_texture", BASE_TEXTURE_UNIT as i32);
        for item in &scene.gbuffer_items {
            let (model_view, normal) = item.matrices(params.view);
            m.program.set_mat4(gl, "u_model_view", &model_view);
            m.program.set_mat4(gl, "u_normal_matrix", &normal);
            scene.bind_material(gl, &m.program, &item.material);
            set_culling(gl, &item.material);
            scene.meshes[item.mesh].draw(gl, m.locations);
        }
        unsafe { gl.bind_vertex_array(None) };
        Ok(check_error(gl, "the sparse depth pre-pass")?)
    }

    /// The set-up pass into the G-buffer's framebuffer `gbuffer_fbo`
    /// (`width`×`height`): empty every list and write sample 0's depth.
    pub(crate) fn draw_setup(
        &self,
        gl: &glow::Context,
        targets: &SparseTargets,
        gbuffer_fbo: glow::Framebuffer,
        vao: &VertexArray,
    ) -> Result<()> {
        begin_fullscreen(gl, gbuffer_fbo, targets.width, targets.height);
        unsafe {
            gl.color_mask(false, false, false, false);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::ALWAYS);
            gl.depth_mask(true);
        }
        TextureRef::from(&targets.depth).bind(gl, 0);
        let p = &self.setup;
        p.bind(gl);
        p.set_i32(gl, "u_depth", 0);
        p.set_u32(gl, "u_width", targets.width);
        targets.bind_buffers(gl);
        draw_fullscreen(gl, vao);
        unsafe {
            // The G-buffer pass's atomics must see the zeroed heads.
            gl.memory_barrier(glow::SHADER_STORAGE_BARRIER_BIT);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(false);
            gl.disable(glow::DEPTH_TEST);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
        }
        Ok(check_error(gl, "the sparse set-up pass")?)
    }

    /// The G-buffer pass: every opaque and alpha-tested object again, at the
    /// pre-pass depth (EQUAL, not written), each sample claimed once through
    /// the stencil; one block per visible fragment.
    pub(crate) fn draw_blocks(
        &self,
        gl: &glow::Context,
        targets: &SparseTargets,
        scene: &GpuScene,
        params: &BuildParams<'_>,
    ) -> Result<()> {
        targets.reset_counters(gl);
        bind_target(gl, targets.fbo.raw(), targets.width, targets.height);
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.enable(glow::MULTISAMPLE);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::EQUAL);
            gl.depth_mask(false);
            // A sample whose stencil is still 0 is unclaimed; the fragment
            // that passes the depth test there claims it (0 -> 1).
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::EQUAL, 0, 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::INCR);
            gl.stencil_mask(0xFF);
        }
        let m = &self.geometry;
        let p = &m.program;
        p.bind(gl);
        p.set_mat4(gl, "u_projection", &params.projection.to_cols_array());
        p.set_i32(gl, "u_base_texture", BASE_TEXTURE_UNIT as i32);
        p.set_i32(gl, "u_emissive_texture", EMISSIVE_TEXTURE_UNIT as i32);
        p.set_u32(gl, "u_width", targets.width);
        p.set_u32(gl, "u_pool_capacity", targets.pool_capacity);
        p.set_f32(gl, "u_max_depth", params.max_depth);
        apply_region(gl, p, &params.region, targets.height);
        targets.bind_buffers(gl);
        for item in &scene.gbuffer_items {
            let (model_view, normal) = item.matrices(params.view);
            p.set_mat4(gl, "u_model_view", &model_view);
            p.set_mat4(gl, "u_normal_matrix", &normal);
            p.set_i32(gl, "u_object_antialias", i32::from(item.antialias));
            scene.bind_material(gl, p, &item.material);
            set_culling(gl, &item.material);
            scene.meshes[item.mesh].draw(gl, m.locations);
        }
        unsafe {
            gl.bind_vertex_array(None);
            gl.disable(glow::STENCIL_TEST);
            gl.depth_func(params.nearer_func);
            // The lighting pass reads the blocks; the counters may be read back.
            gl.memory_barrier(
                glow::SHADER_STORAGE_BARRIER_BIT
                    | glow::BUFFER_UPDATE_BARRIER_BIT
                    | glow::ATOMIC_COUNTER_BARRIER_BIT,
            );
        }
        Ok(check_error(gl, "the sparse G-buffer pass")?)
    }

    /// Free the programs.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.depth.program.destroy(gl);
        self.setup.destroy(gl);
        self.geometry.program.destroy(gl);
    }
}
