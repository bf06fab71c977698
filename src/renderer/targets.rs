//! The renderer's own single-sample targets besides the G-buffer: the
//! background, the HDR target (alone for lighting, with the resolved depth
//! for transparent objects), the tonemapped LDR image and the FXAA or SMAA
//! outputs;
//! and those of [`AaMode::Complex`](super::AaMode::Complex): the HDR target
//! with a stencil mask, and the coverage flags.

use super::pass::begin_fullscreen;
use super::smaa::SmaaTargets;
use crate::Result;
use crate::gl::destroy_object;
use crate::gl::{
    Attachment, Format, Framebuffer, GlObject, Handle, Made, Texture2d, Texture2dMultisample,
    TextureRef,
};
use crate::retrofit::MsaaRetrofit;

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
    /// SMAA's edges, weights and output, when SMAA is on.
    pub(crate) smaa: Option<SmaaTargets>,
}

impl Targets {
    /// Allocate the targets for a G-buffer whose depth texture is `depth`
    /// (their size is its size; the HDR target gets it attached).
    pub(crate) fn new(
        gl: &glow::Context,
        depth: &Texture2d,
        fxaa: bool,
        smaa: bool,
    ) -> Result<Self> {
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
            let smaa = if smaa {
                Some(made.keep(SmaaTargets::new(gl, w, h)?))
            } else {
                None
            };
            Ok(Targets {
                background,
                hdr,
                hdr_with_depth,
                ldr,
                fxaa,
                smaa,
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

    /// The last target of the frame: SMAA's or FXAA's output, or the
    /// tonemapped image.
    pub(crate) fn final_target(&self) -> &ColorTarget {
        match (&self.smaa, &self.fxaa) {
            (Some(smaa), _) => &smaa.out,
            (None, Some(fxaa)) => fxaa,
            (None, None) => &self.ldr,
        }
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
        self.smaa.handles(out);
    }
}

/// The targets of [`AaMode::Complex`](super::AaMode::Complex), sized like
/// the HDR target and the retrofit's twins they refer to.
#[derive(Debug)]
pub(crate) struct ComplexTargets {
    /// `DEPTH24_STENCIL8`, used only for its stencil: the complex-pixel mask.
    pub(crate) stencil: Texture2d,
    /// The HDR texture with `stencil` attached: the mask pass and both
    /// lighting passes draw here.
    pub(crate) hdr_with_stencil: Framebuffer,
    /// The coverage flags and the G-buffer pass's framebuffer, when the
    /// context records coverage.
    pub(crate) coverage: Option<CoverageTarget>,
}

/// The multisampled coverage flags and a framebuffer with the retrofit's
/// twins plus the flags, for the G-buffer pass of `complex`.
#[derive(Debug)]
pub(crate) struct CoverageTarget {
    /// `R8`, one flag per sample: 1 where a fragment with partial coverage wrote it.
    pub(crate) texture: Texture2dMultisample,
    /// The twins at their own attachment points, the flags at `coverage_slot`.
    pub(crate) fbo: Framebuffer,
    /// Its draw-buffer mapping: the twins' own, then the flags at `coverage_slot`.
    pub(crate) draw_buffers: Vec<Option<u32>>,
}

impl ComplexTargets {
    /// Allocate the stencil mask for `hdr` and, with `coverage` = `(retrofit,
    /// slot)`, the coverage flags (at the retrofit's sample count) and a
    /// framebuffer holding the retrofit's twins with the flags at colour
    /// attachment and draw buffer `slot`.
    pub(crate) fn new(
        gl: &glow::Context,
        hdr: &Texture2d,
        coverage: Option<(&MsaaRetrofit, u32)>,
    ) -> Result<Self> {
        let (w, h) = (hdr.width, hdr.height);
        Made::build(gl, |made| {
            let stencil = made.keep(Texture2d::new(
                gl,
                "complex-pixel stencil",
                Format::Depth24Stencil8,
                w,
                h,
            )?);
            let hdr_with_stencil = made.keep(Framebuffer::new(
                gl,
                "hdr with complex-pixel stencil",
                &[
                    (Attachment::Color(0), TextureRef::from(hdr)),
                    (Attachment::DepthStencil, TextureRef::from(&stencil)),
                ],
                &[Some(0)],
            )?);
            let coverage = match coverage {
                None => None,
                Some((retrofit, slot)) => Some(CoverageTarget::new(gl, retrofit, slot)?),
            };
            Ok(ComplexTargets {
                stencil,
                hdr_with_stencil,
                coverage,
            })
        })
    }

    /// Read the mask back (row 0 at the top): 255 for complex pixels, 0 for simple ones.
    pub(crate) fn read_mask(&self, gl: &glow::Context) -> Result<image::GrayImage> {
        let fbo = &self.hdr_with_stencil;
        let (w, h) = (fbo.width, fbo.height);
        let data = fbo.read_u8(gl, glow::STENCIL_INDEX, 1, "the complex-pixel stencil")?;
        let mask = data.iter().map(|&v| if v != 0 { 255 } else { 0 }).collect();
        image::GrayImage::from_raw(w, h, mask).ok_or_else(|| {
            crate::Error::invalid(format!(
                "the complex-pixel mask's buffer does not hold {w}x{h} pixels"
            ))
        })
    }

    /// Free everything (not the HDR texture nor the twins).
    pub(crate) fn destroy(self, gl: &glow::Context) {
        if let Some(c) = self.coverage {
            c.destroy(gl);
        }
        self.hdr_with_stencil.destroy(gl);
        self.stencil.destroy(gl);
    }
}

impl CoverageTarget {
    fn new(gl: &glow::Context, retrofit: &MsaaRetrofit, slot: u32) -> Result<Self> {
        let twin = retrofit.twin();
        Made::build(gl, |made| {
            let texture = made.keep(Texture2dMultisample::new(
                gl,
                "coverage flags",
                Format::R8,
                twin.width,
                twin.height,
                twin.samples,
            )?);
            let mut attachments = twin.fbo.attachments.clone();
            attachments.push((Attachment::Color(slot), TextureRef::from(&texture)));
            let mut draw_buffers = retrofit.host().draw_buffers.clone();
            if draw_buffers.len() <= slot as usize {
                draw_buffers.resize(slot as usize + 1, None);
            }
            draw_buffers[slot as usize] = Some(slot);
            let fbo = Framebuffer::new(
                gl,
                "multisampled G-buffer with coverage flags",
                &attachments,
                &draw_buffers,
            )?;
            Ok(CoverageTarget {
                texture,
                fbo,
                draw_buffers,
            })
        })
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.texture.destroy(gl);
    }
}

impl GlObject for ColorTarget {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.texture.handles(out);
        self.fbo.handles(out);
    }
}
