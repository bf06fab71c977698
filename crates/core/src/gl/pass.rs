//! A full-screen pass: a program whose vertex stage is `fullscreen.vert`,
//! drawn as one triangle from an empty vertex array.

use super::{
    FULLSCREEN_VERT, Framebuffer, GlObject, Handle, Program, SavedState, ShaderSource, ShaderStage,
    VertexArray,
};
use crate::Result;
use glow::HasContext;

/// A full-screen program. The vertex stage gets the fragment source's
/// header (version, extensions, defines) and `fullscreen.vert`.
#[derive(Debug)]
pub struct FullscreenPass {
    program: Program,
}

impl FullscreenPass {
    /// Build from the fragment stage's `fragment` with fragment outputs
    /// bound to `frag_outputs`' colour numbers.
    pub fn new(
        gl: &glow::Context,
        label: &str,
        fragment: &ShaderSource,
        frag_outputs: &[(&str, u32)],
    ) -> Result<Self> {
        let vertex = fragment
            .header_only()
            .part("fullscreen.vert", FULLSCREEN_VERT);
        let program = Program::from_sources(
            gl,
            label,
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, fragment),
            ],
            frag_outputs,
        )?;
        Ok(FullscreenPass { program })
    }

    /// The program, for its uniforms.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Bind `target` with its viewport, set the state of a full-screen pass
    /// ([`SavedState::prepare_fullscreen_pass`], no depth test) and bind the
    /// program. The caller saves and restores the host's state around it.
    pub fn begin(&self, gl: &glow::Context, target: &Framebuffer) -> &Program {
        target.bind(gl);
        SavedState::prepare_fullscreen_pass(gl);
        unsafe { gl.disable(glow::DEPTH_TEST) };
        self.program.bind(gl);
        &self.program
    }

    /// Draw the full-screen triangle with `vao` (empty: positions come from
    /// `gl_VertexID`) under the bound program.
    pub fn draw(&self, gl: &glow::Context, vao: &VertexArray) {
        draw_fullscreen_triangle(gl, vao);
    }

    /// The program alone, for a caller that keeps its own draw code.
    pub fn into_program(self) -> Program {
        self.program
    }

    /// Free the program.
    pub fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}

impl GlObject for FullscreenPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}

/// Bind `vao` and draw the three vertices of the full-screen triangle.
pub fn draw_fullscreen_triangle(gl: &glow::Context, vao: &VertexArray) {
    vao.bind(gl);
    unsafe { gl.draw_arrays(glow::TRIANGLES, 0, 3) };
}
