//! The renderer's own single-sample targets besides the G-buffer: the
//! background, the HDR target (alone for lighting, with the resolved depth
//! for transparent objects), the tonemapped LDR image and the FXAA output
//! (the targets a technique adds are its own, in its folder).

use crate::Result;
use crate::gl::destroy_object;
use crate::gl::{Attachment, Format, Framebuffer, GlObject, Handle, Made, Texture2d, TextureRef};
use crate::renderer::pass::shared::begin_fullscreen;

/// A texture and a framebuffer with it as colour attachment 0.
#[derive(Debug)]
pub(crate) struct ColorTarget {
    /// The texture.
    pub(crate) texture: Texture2d,
    /// The framebuffer.
    pub(crate) fbo: Framebuffer,
}

impl ColorTarget {
    /// Read the RGBA8 texture back, row 0 at the top (`what` names it in errors).
    pub(crate) fn read_rgba8(&self, gl: &glow::Context, what: &str) -> Result<image::RgbaImage> {
        let (w, h) = (self.fbo.width, self.fbo.height);
        let data = self.fbo.read_u8(gl, glow::RGBA, 4, what)?;
        image::RgbaImage::from_raw(w, h, data).ok_or_else(|| {
            crate::Error::invalid(format!("{what}'s buffer does not hold {w}x{h} pixels"))
        })
    }

    /// Start a full-screen pass into it ([`begin_fullscreen`]).
    pub(crate) fn begin_fullscreen(&self, gl: &glow::Context) {
        begin_fullscreen(gl, self.fbo.raw(), self.texture.width, self.texture.height);
    }

    /// Allocate a `format` texture of `width`×`height` and its framebuffer.
    pub(crate) fn new(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let texture = made.keep(Texture2d::new(gl, label, format, width, height)?);
            let fbo = Framebuffer::new(
                gl,
                label,
                &[(Attachment::Color(0), TextureRef::from(&texture))],
                &[Some(0)],
            )?;
            Ok(ColorTarget { texture, fbo })
        })
    }

    /// Free the framebuffer and the texture.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
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
        Made::build(gl, |made| {
            let background = made.keep(ColorTarget::new(gl, "background", Format::Rgba16f, w, h)?);
            let hdr = made.keep(ColorTarget::new(gl, "hdr", Format::Rgba16f, w, h)?);
            let depth = TextureRef::from(depth);
            let hdr_with_depth = made.keep(Framebuffer::new(
                gl,
                "hdr with resolved depth",
                &[
                    (Attachment::Color(0), TextureRef::from(&hdr.texture)),
                    (Attachment::for_depth_format(depth.format), depth),
                ],
                &[Some(0)],
            )?);
            let ldr = made.keep(Self::ldr_target(gl, "ldr", w, h)?);
            let fxaa = if fxaa {
                Some(Self::ldr_target(gl, "fxaa", w, h)?)
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

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for Targets {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.background.handles(out);
        self.hdr_with_depth.handles(out);
        self.hdr.handles(out);
        self.ldr.handles(out);
        self.fxaa.handles(out);
    }
}
