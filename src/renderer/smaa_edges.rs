//! SMAA's first pass (`smaa_edges.frag`): the edges of the tonemapped
//! image, left (`.r`) and top (`.g`) boundary of each pixel, into the RG8
//! edge target; see [`super::smaa`].

use super::pass::{draw_fullscreen, fullscreen_program};
use super::smaa::{DepthInput, SmaaEdges, SmaaOptions};
use super::targets::ColorTarget;
use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use glow::HasContext;

/// The pass's body.
pub(crate) const SMAA_EDGES_FRAG: &str = include_str!("smaa_edges.frag");

/// The edge program.
#[derive(Debug)]
pub(crate) struct SmaaEdgesPass {
    program: Program,
}

impl SmaaEdgesPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "smaa edges",
            "smaa_edges.frag",
            SMAA_EDGES_FRAG,
            &[],
            "o_edges",
        )?;
        Ok(SmaaEdgesPass { program })
    }

    /// Clear `target` and mark the edges of `image` (or, with depth
    /// edges, of `depth`) in it.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        options: &SmaaOptions,
        target: &ColorTarget,
        vao: &VertexArray,
        image: &Texture2d,
        depth: &Texture2d,
        depth_input: DepthInput,
    ) -> Result<()> {
        target.begin_fullscreen(gl);
        unsafe {
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(image.raw()));
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, Some(depth.raw()));
        }
        let p = &self.program;
        p.bind(gl);
        p.set_i32(gl, "u_image", 0);
        p.set_i32(gl, "u_depth", 1);
        let mode = match options.edges {
            SmaaEdges::Luma => 0,
            SmaaEdges::Color => 1,
            SmaaEdges::Depth => 2,
        };
        p.set_i32(gl, "u_mode", mode);
        p.set_f32(gl, "u_threshold", options.preset.threshold());
        p.set_vec2(gl, "u_to_ndc", depth_input.to_ndc);
        p.set_vec4(gl, "u_unproject", depth_input.unproject);
        draw_fullscreen(gl, vao);
        unsafe {
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.active_texture(glow::TEXTURE0);
        }
        Ok(check_error(gl, "the SMAA edge pass")?)
    }
}

impl GlObject for SmaaEdgesPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
