//! The renderer's own single-sample targets besides the G-buffer: the
//! background, the HDR target (alone for lighting, with the resolved depth
//! for transparent objects), the tonemapped LDR image and the FXAA output.

use crate::Result;
use crate::gl::{Attachment, Format, Framebuffer, Texture2d, TextureRef};

/// A texture and a framebuffer with it as colour attachment 0.
#[derive(Debug)]
pub(crate) struct ColorTarget {
    /// The texture.
    pub(crate) texture: Texture2d,
    /// The framebuffer.
    pub(crate) fbo: Framebuffer,
}

impl ColorTarget {
    /// Allocate a `format` texture of `width`×`height` and its framebuffer.
    pub(crate) fn new(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let texture = Texture2d::new(gl, label, format, width, height)?;
        match Framebuffer::new(
            gl,
            label,
            &[(Attachment::Color(0), TextureRef::from(&texture))],
            &[Some(0)],
        ) {
            Ok(fbo) => Ok(ColorTarget { texture, fbo }),
            Err(e) => {
                texture.destroy(gl);
                Err(e)
            }
        }
    }

    /// Free the framebuffer and the texture.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.texture.destroy(gl);
    }
}

/// Every size-dependent target except the G-buffer.
#[derive(Debug)]
pub(crate) struct Targets {
    /// The background, drawn single-sampled (RGBA16F).
    pub(crate) background: ColorTarget,
    /// The HDR target the lighting pass writes (RGBA16F).
    pub(crate) hdr: ColorTarget,
    /// The HDR texture with the G-buffer's resolved depth, for transparent objects.
    pub(crate) hdr_with_depth: Framebuffer,
    /// The tonemapped image (RGBA8, sRGB-encoded values, linear filtering for FXAA).
    pub(crate) ldr: ColorTarget,
    /// The FXAA output (RGBA8), when FXAA is on.
    pub(crate) fxaa: Option<ColorTarget>,
}

impl Targets {
    /// Allocate the targets for a G-buffer whose depth texture is `depth`
    /// (their size is its size; the HDR target gets it attached).
    pub(crate) fn new(gl: &glow::Context, depth: &Texture2d, fxaa: bool) -> Result<Self> {
        let (w, h) = (depth.width, depth.height);
        let background = ColorTarget::new(gl, "background", Format::Rgba16f, w, h)?;
        let hdr = match ColorTarget::new(gl, "hdr", Format::Rgba16f, w, h) {
            Ok(t) => t,
            Err(e) => {
                background.destroy(gl);
                return Err(e);
            }
        };
        let depth = TextureRef::from(depth);
        let hdr_with_depth = match Framebuffer::new(
            gl,
            "hdr with resolved depth",
            &[
                (Attachment::Color(0), TextureRef::from(&hdr.texture)),
                (Attachment::for_depth_format(depth.format), depth),
            ],
            &[Some(0)],
        ) {
            Ok(f) => f,
            Err(e) => {
                background.destroy(gl);
                hdr.destroy(gl);
                return Err(e);
            }
        };
        let ldr = match Self::ldr_target(gl, "ldr", w, h) {
            Ok(t) => t,
            Err(e) => {
                background.destroy(gl);
                hdr.destroy(gl);
                hdr_with_depth.destroy(gl);
                return Err(e);
            }
        };
        let fxaa = if fxaa {
            match Self::ldr_target(gl, "fxaa", w, h) {
                Ok(t) => Some(t),
                Err(e) => {
                    background.destroy(gl);
                    hdr.destroy(gl);
                    hdr_with_depth.destroy(gl);
                    ldr.destroy(gl);
                    return Err(e);
                }
            }
        } else {
            None
        };
        Ok(Targets {
            background,
            hdr,
            hdr_with_depth,
            ldr,
            fxaa,
        })
    }

    /// An RGBA8 target with linear filtering (the FXAA pass samples between texels).
    pub(crate) fn ldr_target(
        gl: &glow::Context,
        label: &str,
        width: u32,
        height: u32,
    ) -> Result<ColorTarget> {
        let target = ColorTarget::new(gl, label, Format::Rgba8, width, height)?;
        target.texture.set_filter(gl, glow::LINEAR);
        Ok(target)
    }

    /// The last target of the frame: FXAA's output, or the tonemapped image.
    pub(crate) fn final_target(&self) -> &ColorTarget {
        self.fxaa.as_ref().unwrap_or(&self.ldr)
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.background.destroy(gl);
        self.hdr_with_depth.destroy(gl);
        self.hdr.destroy(gl);
        self.ldr.destroy(gl);
        if let Some(t) = self.fxaa {
            t.destroy(gl);
        }
    }
}
