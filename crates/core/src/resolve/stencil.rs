//! The host's stencil after a resolve: each pixel takes the stencil value
//! of the resolve's reference sample, read from the multisampled twin.
//!
//! The resolve writes its reference sample's index per pixel; this pass
//! reads the twin's depth-stencil texture as `GL_STENCIL_INDEX`
//! (`GL_ARB_stencil_texturing`, core in 4.3) at that sample and writes the
//! value into the host's depth-stencil image:
//!
//! - [`StencilCopy::Export`]: one pass, `gl_FragStencilRefARB`
//!   (`GL_ARB_shader_stencil_export`);
//! - [`StencilCopy::BitPasses`]: where the driver cannot export stencil from
//!   a shader, eight passes, one per bit, each writing its bit through the
//!   stencil write mask where the reference's value has it;
//! - [`StencilCopy::Blit`]: where the driver cannot read stencil in a
//!   shader either, `glBlitFramebuffer` of the stencil, whose sample the
//!   driver chooses (sample 0 on Mesa): exact on uniform pixels, one of the
//!   pixel's samples elsewhere.

use crate::gl::{
    Framebuffer, FullscreenPass, Made, SavedState, ShaderSource, Texture2d, Texture2dMultisample,
    TextureRef, VertexArray, check_error,
};
use crate::{Error, Result};
use glow::HasContext;

/// The pass's fragment shader body.
pub const STENCIL_COPY_FRAG: &str = include_str!("stencil_copy.frag");

/// How the host's stencil is written back after a resolve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum StencilCopy {
    /// The best the driver offers: `Export`, else `BitPasses`, else `Blit`.
    #[default]
    Auto,
    /// The reference sample's value, in one pass with
    /// `GL_ARB_shader_stencil_export` and `GL_ARB_stencil_texturing`.
    Export,
    /// The reference sample's value, in eight passes, with
    /// `GL_ARB_stencil_texturing` alone.
    BitPasses,
    /// `glBlitFramebuffer`: the sample the driver picks.
    Blit,
}

impl StencilCopy {
    /// What `self` becomes on this context: `Auto` resolved, and an error
    /// naming the missing extension for a method the driver lacks.
    pub fn on(self, gl: &glow::Context) -> Result<StencilCopy> {
        let v = gl.version();
        let ext = gl.supported_extensions();
        let texturing = (v.major, v.minor) >= (4, 3) || ext.contains("GL_ARB_stencil_texturing");
        let export = ext.contains("GL_ARB_shader_stencil_export");
        let found = format!("OpenGL {}.{}", v.major, v.minor);
        let missing = |feature: &str, requires: &str| Error::Unsupported {
            feature: format!("copying the host's stencil by {feature}"),
            requires: requires.into(),
            found: found.clone(),
        };
        match self {
            StencilCopy::Auto if texturing && export => Ok(StencilCopy::Export),
            StencilCopy::Auto if texturing => Ok(StencilCopy::BitPasses),
            StencilCopy::Auto | StencilCopy::Blit => Ok(StencilCopy::Blit),
            StencilCopy::Export if !(texturing && export) => Err(missing(
                "shader export",
                "GL_ARB_shader_stencil_export and GL_ARB_stencil_texturing (OpenGL 4.3)",
            )),
            StencilCopy::BitPasses if !texturing => Err(missing(
                "bit passes",
                "GL_ARB_stencil_texturing (OpenGL 4.3)",
            )),
            method => Ok(method),
        }
    }
}

/// The stencil pass of one retrofit.
#[derive(Debug)]
pub(crate) struct StencilPass {
    method: StencilCopy,
    program: Option<FullscreenPass>,
    vao: VertexArray,
}

/// What it owns: its program and vertex array.
impl crate::gl::GlObject for StencilPass {
    fn handles(&self, out: &mut Vec<crate::gl::Handle>) {
        self.program.handles(out);
        self.vao.handles(out);
    }
}

impl StencilPass {
    /// Build the pass for `method` (already resolved by [`StencilCopy::on`]).
    pub(crate) fn new(gl: &glow::Context, method: StencilCopy) -> Result<Self> {
        Made::build(gl, |made| {
            let program = match method {
                StencilCopy::Export | StencilCopy::BitPasses => {
                    let mut source = ShaderSource::new();
                    if method == StencilCopy::Export {
                        source = source
                            .extension("GL_ARB_shader_stencil_export")
                            .define("STENCIL_EXPORT", "1");
                    }
                    Some(made.keep(FullscreenPass::new(
                        gl,
                        "stencil copy from the reference sample",
                        &source.part("stencil_copy.frag", STENCIL_COPY_FRAG),
                        &[],
                    )?))
                }
                _ => None,
            };
            let vao = VertexArray::new(gl, "stencil copy full-screen triangle")?;
            Ok(StencilPass {
                method,
                program,
                vao,
            })
        })
    }

    /// The method in use.
    pub(crate) fn method(&self) -> StencilCopy {
        self.method
    }

    /// Write `target`'s stencil (a framebuffer holding only the host's
    /// depth-stencil image) from `twin`, at the samples `reference` names;
    /// `twin_fbo` is the multisampled framebuffer, for the blit.
    pub(crate) fn run(
        &self,
        gl: &glow::Context,
        twin: &Texture2dMultisample,
        twin_fbo: &Framebuffer,
        reference: Option<&Texture2d>,
        target: &Framebuffer,
    ) -> Result<()> {
        if self.program.is_some() && reference.is_none() {
            return Err(crate::Error::invalid(
                "the stencil copy by shader needs the resolve's reference index",
            ));
        }
        let mut state = SavedState::capture(gl, 2);
        // The passes set the stencil function.
        state.keep_stencil_func(gl)?;
        let state = state.guard(gl);
        let result = match &self.program {
            None => unsafe {
                gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(twin_fbo.raw()));
                gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(target.raw()));
                SavedState::prepare_fullscreen_pass(gl);
                gl.stencil_mask(0xFF);
                let (w, h) = (target.width as i32, target.height as i32);
                gl.blit_framebuffer(
                    0,
                    0,
                    w,
                    h,
                    0,
                    0,
                    w,
                    h,
                    glow::STENCIL_BUFFER_BIT,
                    glow::NEAREST,
                );
                Ok(())
            },
            Some(pass) => unsafe {
                let program = pass.begin(gl, target);
                gl.depth_mask(false);
                gl.color_mask(false, false, false, false);
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::ALWAYS, 0xFF, 0xFF);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
                gl.active_texture(glow::TEXTURE0);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(twin.raw()));
                gl.tex_parameter_i32(
                    glow::TEXTURE_2D_MULTISAMPLE,
                    glow::DEPTH_STENCIL_TEXTURE_MODE,
                    glow::STENCIL_INDEX as i32,
                );
                program.set_i32(gl, "u_stencil", 0);
                if let Some(reference) = reference {
                    TextureRef::from(reference).bind(gl, 1);
                }
                program.set_i32(gl, "u_reference", 1);
                if self.method == StencilCopy::Export {
                    gl.stencil_mask(0xFF);
                    pass.draw(gl, &self.vao);
                } else {
                    // Clear, then set each bit where the reference's value has it.
                    gl.stencil_mask(0xFF);
                    gl.clear_stencil(0);
                    gl.clear(glow::STENCIL_BUFFER_BIT);
                    for bit in 0..8u32 {
                        gl.stencil_mask(1 << bit);
                        program.set_u32(gl, "u_bit", 1 << bit);
                        pass.draw(gl, &self.vao);
                    }
                }
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(twin.raw()));
                gl.tex_parameter_i32(
                    glow::TEXTURE_2D_MULTISAMPLE,
                    glow::DEPTH_STENCIL_TEXTURE_MODE,
                    glow::DEPTH_COMPONENT as i32,
                );
                Ok(())
            },
        };
        // The host's state, its stencil clear value included (the bit passes
        // clear with 0), comes back.
        drop(state);
        result.and_then(|()| check_error(gl, "copying the host's stencil"))
    }
}
