//! The forward transparent pass (`transparent.frag`, with the
//! model vertex shader `geometry.vert`): alpha-blended objects drawn
//! single-sampled into the HDR target after lighting, sorted back to front,
//! depth-tested against the resolved depth without writing it. The lights
//! and BRDF are lighting.frag's (compiled in front of transparent.frag).

use super::geometry::GEOMETRY_VERT;
use super::lighting::{LIGHTING_FRAG, LightBatch, lighting_defines, set_batch_blend};
use super::shared::bind_target;
use crate::Result;
use crate::gl::{GlObject, Handle, Program, ShaderSource, ShaderStage, check_error};
use crate::renderer::mesh::{
    AttribLocations, BASE_TEXTURE_UNIT, EMISSIVE_TEXTURE_UNIT, GpuScene, set_culling,
};
use glam::{DMat4, Mat4};
use glow::HasContext;

/// The transparent shader's body.
pub(crate) const TRANSPARENT_FRAG: &str = include_str!("transparent.frag");

/// The transparent program.
#[derive(Debug)]
pub(crate) struct TransparentPass {
    program: Program,
    locations: AttribLocations,
}

impl TransparentPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let mut defines = lighting_defines();
        defines.push(("LIGHTING_FUNCTIONS_ONLY".into(), "1".into()));
        let fragment = ShaderSource::new()
            .defines(&defines)
            .part("lighting.frag", LIGHTING_FRAG)
            .part("transparent.frag", TRANSPARENT_FRAG);
        let vertex = fragment.header_only().part("geometry.vert", GEOMETRY_VERT);
        let program = Program::from_sources(
            gl,
            "transparent",
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, &fragment),
            ],
            &[("o_color", 0)],
        )?;
        let locations = AttribLocations::of(gl, &program);
        Ok(TransparentPass { program, locations })
    }

    /// Draw the scene's transparent objects into `target` (the HDR colour
    /// with the resolved depth attached, or the retrofit's multisampled
    /// forward target, each at the frame's size), farthest first,
    /// depth-tested with `depth_func` (LESS, or GREATER for reversed-Z).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: (glow::Framebuffer, u32, u32),
        scene: &GpuScene,
        view: &DMat4,
        projection: &Mat4,
        batches: &[LightBatch],
        depth_func: u32,
    ) -> Result<()> {
        if scene.transparent_items.is_empty() {
            return Ok(());
        }
        let mut order: Vec<(f64, usize)> = scene
            .transparent_items
            .iter()
            .enumerate()
            .map(|(i, item)| (view.transform_point3(item.center).z, i))
            .collect();
        // View space looks down -z: the most negative z is the farthest.
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));

        bind_target(gl, target.0, target.1, target.2);
        unsafe {
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(depth_func);
            gl.depth_mask(false);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.color_mask(true, true, true, true);
        }
        let p = &self.program;
        p.bind(gl);
        p.set_mat4(gl, "u_projection", &projection.to_cols_array());
        p.set_i32(gl, "u_base_texture", BASE_TEXTURE_UNIT as i32);
        p.set_i32(gl, "u_emissive_texture", EMISSIVE_TEXTURE_UNIT as i32);
        for (_, i) in order {
            let item = &scene.transparent_items[i];
            let (model_view, normal) = item.matrices(view);
            p.set_mat4(gl, "u_model_view", &model_view);
            p.set_mat4(gl, "u_normal_matrix", &normal);
            scene.bind_material(gl, p, &item.material);
            set_culling(gl, &item.material);
            for (index, batch) in batches.iter().enumerate() {
                set_batch_blend(gl, index, true);
                batch.apply(gl, p, index == 0);
                scene.meshes[item.mesh].draw(gl, self.locations);
            }
        }
        unsafe {
            gl.bind_vertex_array(None);
            gl.depth_mask(true);
        }
        Ok(check_error(gl, "the transparent pass")?)
    }
}

impl GlObject for TransparentPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
