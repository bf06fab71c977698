//! SMAA's second pass (`smaa_weights.frag`): from the edges, the areas each
//! pixel takes across its top and left edges and gives, into the RGBA8
//! weight target; see [`super`] and [`super::tables`].

use super::options::SmaaPreset;
use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use crate::renderer::pass::shared::{draw_fullscreen, fullscreen_program};
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The pass's body.
pub(crate) const SMAA_WEIGHTS_FRAG: &str = include_str!("smaa_weights.frag");

/// The blending-weight program.
#[derive(Debug)]
pub(crate) struct SmaaWeightsPass {
    program: Program,
}

impl SmaaWeightsPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "smaa weights",
            "smaa_weights.frag",
            SMAA_WEIGHTS_FRAG,
            &[],
            "o_weights",
        )?;
        Ok(SmaaWeightsPass { program })
    }

    /// Clear `target` and weigh the edges of `edges` into it, with the
    /// preset's search steps, diagonal steps and corner rounding.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        preset: SmaaPreset,
        target: &ColorTarget,
        vao: &VertexArray,
        edges: &Texture2d,
        area: &Texture2d,
        search: &Texture2d,
        diagonal: &Texture2d,
    ) -> Result<()> {
        target.begin_fullscreen(gl);
        unsafe {
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            for (unit, texture) in [edges, area, search, diagonal].into_iter().enumerate() {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(texture.raw()));
            }
        }
        let p = &self.program;
        p.bind(gl);
        p.set_i32(gl, "u_edges", 0);
        p.set_i32(gl, "u_area", 1);
        p.set_i32(gl, "u_search", 2);
        p.set_i32(gl, "u_diagonal", 3);
        p.set_i32(
            gl,
            "u_diagonal_steps",
            preset.diagonal_steps().map_or(0, |n| n as i32),
        );
        p.set_i32(gl, "u_search_steps", preset.search_steps() as i32);
        let corner = preset.corner_rounding();
        p.set_i32(gl, "u_corners", i32::from(corner.is_some()));
        p.set_f32(gl, "u_corner", corner.map_or(1.0, |c| c as f32 / 100.0));
        draw_fullscreen(gl, vao);
        unsafe {
            for unit in (0..4).rev() {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, None);
            }
        }
        Ok(check_error(gl, "the SMAA blending-weight pass")?)
    }
}

impl GlObject for SmaaWeightsPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
