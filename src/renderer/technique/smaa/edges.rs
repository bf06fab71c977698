//! SMAA's first pass (`smaa_edges.frag`): the edges of the tonemapped
//! image, left (`.r`) and top (`.g`) boundary of each pixel, into the RG8
//! edge target; see [`super`].

use super::options::{SmaaEdges, SmaaOptions};
use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use crate::renderer::pass::shared::{draw_fullscreen, fullscreen_program};
use crate::renderer::targets::ColorTarget;
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

/// How the edge pass turns a depth texel into a view distance: the depth
/// to NDC z (`ndc = depth · scale + offset`: standard depth −1..1 or
/// `GL_ZERO_TO_ONE`), then the inverse projection's z and w rows at
/// x = y = 0 (`z = a·ndc + b`, `w = c·ndc + d`; the distance is `−z / w`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DepthInput {
    /// `scale`, `offset`.
    pub(crate) to_ndc: [f32; 2],
    /// `a`, `b`, `c`, `d`.
    pub(crate) unproject: [f32; 4],
}

impl DepthInput {
    /// For `projection` with the clip control `zero_to_one`.
    pub(crate) fn new(projection: &glam::Mat4, zero_to_one: bool) -> DepthInput {
        let inverse = projection.inverse();
        // Row r, column c of a column-major glam matrix: col(c)[r].
        let at = |r: usize, c: usize| inverse.col(c)[r];
        DepthInput {
            to_ndc: if zero_to_one { [1.0, 0.0] } else { [2.0, -1.0] },
            unproject: [at(2, 2), at(2, 3), at(3, 2), at(3, 3)],
        }
    }
}
