//! The FXAA-style post filter (`fxaa.frag`): luma-based edge
//! smoothing of the tonemapped image into a second RGBA8 target.

use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use crate::renderer::pass::shared::{draw_fullscreen, fullscreen_program};
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The filter's body.
pub(crate) const FXAA_FRAG: &str = include_str!("fxaa.frag");

/// The filter program.
#[derive(Debug)]
pub(crate) struct FxaaPass {
    program: Program,
}

impl FxaaPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(gl, "fxaa", "fxaa.frag", FXAA_FRAG, &[], "o_color")?;
        Ok(FxaaPass { program })
    }

    /// Filter `ldr` (linearly filtered, clamped) into `target`.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: &ColorTarget,
        vao: &VertexArray,
        ldr: &Texture2d,
    ) -> Result<()> {
        target.begin_fullscreen(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(ldr.raw()));
        }
        let p = &self.program;
        p.bind(gl);
        p.set_i32(gl, "u_ldr", 0);
        p.set_vec2(
            gl,
            "u_texel",
            [1.0 / ldr.width as f32, 1.0 / ldr.height as f32],
        );
        draw_fullscreen(gl, vao);
        Ok(check_error(gl, "the FXAA pass")?)
    }
}

impl GlObject for FxaaPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
