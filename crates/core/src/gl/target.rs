//! An owned render target: textures made for a list of attachment points
//! and formats, and the framebuffer that holds them, freed by one `destroy`.

use super::{
    Attachment, Format, Framebuffer, GlObject, Handle, Made, Texture2d, Texture2dMultisample,
    TextureRef, destroy_object,
};
use crate::{Error, Result};

/// One of a [`RenderTarget`]'s textures.
#[derive(Debug)]
pub enum TargetTexture {
    /// A single-sample texture.
    Single(Texture2d),
    /// A multisampled texture.
    Multisample(Texture2dMultisample),
}

impl TargetTexture {
    /// A borrowed view, for binding and attaching.
    pub fn as_ref(&self) -> TextureRef {
        match self {
            TargetTexture::Single(t) => TextureRef::from(t),
            TargetTexture::Multisample(t) => TextureRef::from(t),
        }
    }
}

impl GlObject for TargetTexture {
    fn handles(&self, out: &mut Vec<Handle>) {
        match self {
            TargetTexture::Single(t) => t.handles(out),
            TargetTexture::Multisample(t) => t.handles(out),
        }
    }
}

/// Textures for `(attachment, format)` pairs and a framebuffer holding them.
///
/// Each texture is labelled `{label} {attachment}`; the framebuffer `label`.
#[derive(Debug)]
pub struct RenderTarget {
    fbo: Framebuffer,
    textures: Vec<(Attachment, TargetTexture)>,
}

impl RenderTarget {
    /// Single-sample textures of `width`×`height`, colour attachment `i`
    /// mapped to fragment output `draw_buffers[i]`. On failure nothing is
    /// left allocated.
    pub fn new(
        gl: &glow::Context,
        label: &str,
        width: u32,
        height: u32,
        attachments: &[(Attachment, Format)],
        draw_buffers: &[Option<u32>],
    ) -> Result<Self> {
        Self::build(gl, label, attachments, draw_buffers, |point, format| {
            let name = format!("{label} {}", point.name());
            Ok(TargetTexture::Single(Texture2d::new(
                gl, &name, format, width, height,
            )?))
        })
    }

    /// [`RenderTarget::new`] with `samples`-sample textures; the driver's
    /// real count must agree across attachments.
    pub fn multisample(
        gl: &glow::Context,
        label: &str,
        width: u32,
        height: u32,
        samples: u32,
        attachments: &[(Attachment, Format)],
        draw_buffers: &[Option<u32>],
    ) -> Result<Self> {
        let mut real: Option<u32> = None;
        Self::build(gl, label, attachments, draw_buffers, |point, format| {
            let name = format!("{label} {}", point.name());
            let t = Texture2dMultisample::new(gl, &name, format, width, height, samples)?;
            let first = *real.get_or_insert(t.samples);
            if t.samples != first {
                let e = Error::UnsupportedSampleCount {
                    requested: samples,
                    format: format!(
                        "{format} (the driver gave {} samples to it but {first} to the others)",
                        t.samples
                    ),
                    supported: vec![first],
                };
                t.destroy(gl);
                return Err(e);
            }
            Ok(TargetTexture::Multisample(t))
        })
    }

    fn build(
        gl: &glow::Context,
        label: &str,
        attachments: &[(Attachment, Format)],
        draw_buffers: &[Option<u32>],
        mut texture: impl FnMut(Attachment, Format) -> Result<TargetTexture>,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let mut textures = Vec::with_capacity(attachments.len());
            for &(point, format) in attachments {
                textures.push((point, made.keep(texture(point, format)?)));
            }
            let refs: Vec<(Attachment, TextureRef)> =
                textures.iter().map(|(p, t)| (*p, t.as_ref())).collect();
            let fbo = Framebuffer::new(gl, label, &refs, draw_buffers)?;
            Ok(RenderTarget { fbo, textures })
        })
    }

    /// The framebuffer.
    pub fn fbo(&self) -> &Framebuffer {
        &self.fbo
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.fbo.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.fbo.height
    }

    /// The real sample count (1 when single-sampled).
    pub fn samples(&self) -> u32 {
        self.fbo.samples
    }

    /// The texture at `point`.
    pub fn get(&self, point: Attachment) -> Option<&TargetTexture> {
        self.textures
            .iter()
            .find(|(p, _)| *p == point)
            .map(|(_, t)| t)
    }

    /// The single-sample texture at `point`.
    pub fn texture(&self, point: Attachment) -> Option<&Texture2d> {
        match self.get(point)? {
            TargetTexture::Single(t) => Some(t),
            TargetTexture::Multisample(_) => None,
        }
    }

    /// The multisampled texture at `point`.
    pub fn multisample_texture(&self, point: Attachment) -> Option<&Texture2dMultisample> {
        match self.get(point)? {
            TargetTexture::Multisample(t) => Some(t),
            TargetTexture::Single(_) => None,
        }
    }

    /// Free the framebuffer, then the textures.
    pub fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for RenderTarget {
    fn handles(&self, out: &mut Vec<Handle>) {
        for (_, t) in &self.textures {
            t.handles(out);
        }
        self.fbo.handles(out);
    }
}
