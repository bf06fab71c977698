//! The targets of method `complex`: the HDR target with a stencil mask of
//! its complex pixels, and the multisampled coverage flags.

use crate::Result;
use crate::gl::{
    Attachment, Format, Framebuffer, GlObject, Handle, Made, Texture2d, Texture2dMultisample,
    TextureRef,
};
use crate::renderer::targets::ColorTarget;
use crate::retrofit::MsaaRetrofit;

/// The targets of [`AaMode::Complex`](crate::renderer::AaMode::Complex), sized like
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
