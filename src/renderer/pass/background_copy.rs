//! The background copy pass (`background_copy.frag`): the
//! single-sampled background written into every sample of the G-buffer's
//! emissive attachment (multisampled or not), as FreeSpace Open does; a blit
//! cannot write a multisampled target.

use super::shared::{begin_fullscreen, draw_fullscreen, fullscreen_program};
use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use glow::HasContext;

/// The copy shader's body.
pub(crate) const BACKGROUND_COPY_FRAG: &str = include_str!("background_copy.frag");

/// The copy program.
#[derive(Debug)]
pub(crate) struct BackgroundCopyPass {
    program: Program,
}

/// Where the copy goes: a G-buffer framebuffer and its emissive attachment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CopyTarget<'a> {
    /// The framebuffer (the multisampled twin's, or the single-sample G-buffer's).
    pub(crate) fbo: glow::Framebuffer,
    /// Its size.
    pub(crate) width: u32,
    /// Its size.
    pub(crate) height: u32,
    /// The emissive attachment's colour attachment number.
    pub(crate) emissive: u32,
    /// The framebuffer's own draw-buffer mapping, put back afterwards.
    pub(crate) draw_buffers: &'a [Option<u32>],
}

impl BackgroundCopyPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "background copy",
            "background_copy.frag",
            BACKGROUND_COPY_FRAG,
            &[],
            "o_emissive",
        )?;
        Ok(BackgroundCopyPass { program })
    }

    /// Copy `background` into the emissive attachment of `target`. The
    /// framebuffer's draw buffers are pointed at the emissive attachment
    /// alone for the copy, then restored.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: CopyTarget<'_>,
        vao: &VertexArray,
        background: &Texture2d,
    ) -> Result<()> {
        begin_fullscreen(gl, target.fbo, target.width, target.height);
        unsafe {
            gl.enable(glow::MULTISAMPLE);
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0 + target.emissive]);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(background.raw()));
        }
        self.program.bind(gl);
        self.program.set_i32(gl, "u_background", 0);
        draw_fullscreen(gl, vao);
        let mapping: Vec<u32> = target
            .draw_buffers
            .iter()
            .map(|b| b.map_or(glow::NONE, |i| glow::COLOR_ATTACHMENT0 + i))
            .collect();
        unsafe { gl.draw_buffers(&mapping) };
        Ok(check_error(gl, "the background copy pass")?)
    }
}

impl GlObject for BackgroundCopyPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
