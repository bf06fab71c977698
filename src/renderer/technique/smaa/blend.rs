//! SMAA's third pass (`smaa_blend.frag`): each pixel mixed with its
//! neighbours across its edges by the weights, into the output image; see
//! [`super`].

use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use crate::renderer::pass::shared::{draw_fullscreen, fullscreen_program};
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The pass's body.
pub(crate) const SMAA_BLEND_FRAG: &str = include_str!("smaa_blend.frag");

/// The neighbourhood-blending program.
#[derive(Debug)]
pub(crate) struct SmaaBlendPass {
    program: Program,
}

impl SmaaBlendPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "smaa blend",
            "smaa_blend.frag",
            SMAA_BLEND_FRAG,
            &[],
            "o_color",
        )?;
        Ok(SmaaBlendPass { program })
    }

    /// Blend `image` by `weights` into `target`.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: &ColorTarget,
        vao: &VertexArray,
        image: &Texture2d,
        weights: &Texture2d,
    ) -> Result<()> {
        target.begin_fullscreen(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(image.raw()));
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, Some(weights.raw()));
        }
        let p = &self.program;
        p.bind(gl);
        p.set_i32(gl, "u_image", 0);
        p.set_i32(gl, "u_weights", 1);
        draw_fullscreen(gl, vao);
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.active_texture(glow::TEXTURE0);
        }
        Ok(check_error(gl, "the SMAA blending pass")?)
    }
}

impl GlObject for SmaaBlendPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
