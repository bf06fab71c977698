//! What the full-screen passes share: program building, the full-screen
//! state, and binding a target.

use crate::Result;
use crate::gl::{FullscreenPass, Program, ShaderSource, VertexArray, draw_fullscreen_triangle};
use glow::HasContext;

/// Build a full-screen program: `fullscreen.vert` and `frag_body`, with
/// `defines`, its one output `output` on draw buffer 0.
pub(crate) fn fullscreen_program(
    gl: &glow::Context,
    label: &str,
    frag_name: &str,
    frag_body: &str,
    defines: &[(String, String)],
    output: &str,
) -> Result<Program> {
    let fragment = ShaderSource::new()
        .defines(defines)
        .part(frag_name, frag_body);
    Ok(FullscreenPass::new(gl, label, &fragment, &[(output, 0)])?.into_program())
}

/// Bind `fbo` to `GL_FRAMEBUFFER` with a `width`×`height` viewport.
pub(crate) fn bind_target(gl: &glow::Context, fbo: glow::Framebuffer, width: u32, height: u32) {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.viewport(0, 0, width as i32, height as i32);
    }
}

/// The state of a full-screen pass: no depth test or write, no blending,
/// culling, scissor or stencil, all colour channels written, no sRGB
/// conversion on write.
pub(crate) fn fullscreen_state(gl: &glow::Context) {
    unsafe {
        gl.disable(glow::DEPTH_TEST);
        gl.depth_mask(false);
        gl.disable(glow::BLEND);
        gl.disable(glow::CULL_FACE);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::FRAMEBUFFER_SRGB);
        gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
        gl.color_mask(true, true, true, true);
    }
}

/// The start of a full-screen pass: bind `fbo` with a `width`×`height`
/// viewport ([`bind_target`]) and set [`fullscreen_state`].
pub(crate) fn begin_fullscreen(
    gl: &glow::Context,
    fbo: glow::Framebuffer,
    width: u32,
    height: u32,
) {
    bind_target(gl, fbo, width, height);
    fullscreen_state(gl);
}

/// Draw the full-screen triangle (an empty vertex array; positions come from `gl_VertexID`).
pub(crate) fn draw_fullscreen(gl: &glow::Context, vao: &VertexArray) {
    draw_fullscreen_triangle(gl, vao);
}

/// Which pixels a full-screen pass may write, by their stencil value (the
/// complex-pixel mask of method `complex`: 1 = complex, 0 = simple).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StencilSelect {
    /// No stencil test.
    All,
    /// Only pixels whose stencil value equals this one (stencil not written).
    Equal(u8),
}

/// Where a lighting pass draws: a framebuffer whose draw buffer 0 is the HDR
/// target, and which pixels it lights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightTarget {
    /// The framebuffer (the HDR target, or the HDR target with the stencil mask).
    pub(crate) fbo: glow::Framebuffer,
    /// Its width.
    pub(crate) width: u32,
    /// Its height.
    pub(crate) height: u32,
    /// The stencil test; anything but [`StencilSelect::All`] needs a
    /// framebuffer with a stencil attachment.
    pub(crate) stencil: StencilSelect,
}

impl LightTarget {
    /// [`begin_fullscreen`] on the framebuffer, then the stencil test.
    pub(crate) fn bind(&self, gl: &glow::Context) {
        begin_fullscreen(gl, self.fbo, self.width, self.height);
        if let StencilSelect::Equal(value) = self.stencil {
            unsafe {
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::EQUAL, i32::from(value), 0xFF);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
                gl.stencil_mask(0);
            }
        }
    }
}
