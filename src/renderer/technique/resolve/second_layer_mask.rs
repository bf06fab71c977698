//! The second layer's stencil mask (`second_layer_mask.frag`):
//! the renderer, as a host of the retrofit, lights its second layer only
//! where the layer's coverage is above 0, by a stencil test on the HDR
//! target.

use crate::Result;
use crate::gl::{GlObject, Handle, Program, TextureRef, VertexArray, check_error};
use crate::renderer::pass::shared::{
    LightTarget, StencilSelect, begin_fullscreen, draw_fullscreen, fullscreen_program,
};
use glow::HasContext;

/// The mask pass's fragment shader.
pub const SECOND_LAYER_MASK_FRAG: &str = include_str!("second_layer_mask.frag");

/// The stencil value of pixels the second layer covers.
pub(crate) const COVERED: u8 = 1;

/// Marks covered pixels in a stencil attachment.
#[derive(Debug)]
pub(crate) struct SecondLayerMaskPass {
    program: Program,
}

impl GlObject for SecondLayerMaskPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}

impl SecondLayerMaskPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "second layer mask",
            "second_layer_mask.frag",
            SECOND_LAYER_MASK_FRAG,
            &[],
            "o_color",
        )?;
        Ok(SecondLayerMaskPass { program })
    }

    /// Clear `target`'s stencil and write [`COVERED`] where `coverage` is
    /// above 0; the light target that lights only those pixels.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        coverage: TextureRef,
    ) -> Result<LightTarget> {
        begin_fullscreen(gl, target.fbo, target.width, target.height);
        unsafe {
            gl.color_mask(false, false, false, false);
            gl.stencil_mask(0xFF);
            gl.clear_stencil(0);
            gl.clear(glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::ALWAYS, i32::from(COVERED), 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
        }
        self.program.bind(gl);
        coverage.bind(gl, 0);
        self.program.set_i32(gl, "u_coverage", 0);
        draw_fullscreen(gl, vao);
        unsafe {
            gl.color_mask(true, true, true, true);
            gl.disable(glow::STENCIL_TEST);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        check_error(gl, "the second layer's mask pass")?;
        Ok(LightTarget {
            stencil: StencilSelect::Equal(COVERED),
            ..target
        })
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}
