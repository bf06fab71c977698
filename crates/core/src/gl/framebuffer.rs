//! Framebuffer objects, checked for completeness.

use super::counters::{self, Kind};
use super::state::live_framebuffer;
use super::{TextureRef, check_error, label_object};
use crate::{Error, Result};
use glow::HasContext;

/// The name of a `glCheckFramebufferStatus` value.
pub fn framebuffer_status_name(status: u32) -> &'static str {
    match status {
        glow::FRAMEBUFFER_COMPLETE => "GL_FRAMEBUFFER_COMPLETE",
        glow::FRAMEBUFFER_UNDEFINED => "GL_FRAMEBUFFER_UNDEFINED",
        glow::FRAMEBUFFER_INCOMPLETE_ATTACHMENT => "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT",
        glow::FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT => {
            "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT"
        }
        glow::FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER => "GL_FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER",
        glow::FRAMEBUFFER_INCOMPLETE_READ_BUFFER => "GL_FRAMEBUFFER_INCOMPLETE_READ_BUFFER",
        glow::FRAMEBUFFER_UNSUPPORTED => "GL_FRAMEBUFFER_UNSUPPORTED",
        glow::FRAMEBUFFER_INCOMPLETE_MULTISAMPLE => "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE",
        glow::FRAMEBUFFER_INCOMPLETE_LAYER_TARGETS => "GL_FRAMEBUFFER_INCOMPLETE_LAYER_TARGETS",
        _ => "unknown framebuffer status",
    }
}

/// Where a texture is attached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attachment {
    /// `GL_COLOR_ATTACHMENTi`.
    Color(u32),
    /// `GL_DEPTH_ATTACHMENT`.
    Depth,
    /// `GL_STENCIL_ATTACHMENT`.
    Stencil,
    /// `GL_DEPTH_STENCIL_ATTACHMENT`.
    DepthStencil,
}

impl Attachment {
    /// The GL enum.
    pub fn gl_enum(self) -> u32 {
        match self {
            Attachment::Color(i) => glow::COLOR_ATTACHMENT0 + i,
            Attachment::Depth => glow::DEPTH_ATTACHMENT,
            Attachment::Stencil => glow::STENCIL_ATTACHMENT,
            Attachment::DepthStencil => glow::DEPTH_STENCIL_ATTACHMENT,
        }
    }

    /// The GL name, e.g. `GL_COLOR_ATTACHMENT2`.
    pub fn name(self) -> String {
        match self {
            Attachment::Color(i) => format!("GL_COLOR_ATTACHMENT{i}"),
            Attachment::Depth => "GL_DEPTH_ATTACHMENT".into(),
            Attachment::Stencil => "GL_STENCIL_ATTACHMENT".into(),
            Attachment::DepthStencil => "GL_DEPTH_STENCIL_ATTACHMENT".into(),
        }
    }

    /// The attachment point a depth format belongs to.
    pub fn for_depth_format(format: super::Format) -> Attachment {
        if format.has_stencil() {
            Attachment::DepthStencil
        } else {
            Attachment::Depth
        }
    }
}

/// A colour attachment point by number: `ColorAttachment(2)` is
/// `GL_COLOR_ATTACHMENT2` of the host's framebuffer, whatever draw buffer
/// it is mapped to. (The resolve's own inputs are numbered apart, by
/// [`ResolveSlot`](crate::resolve::ResolveSlot).)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ColorAttachment(pub u32);

impl ColorAttachment {
    /// The GL name, e.g. `GL_COLOR_ATTACHMENT2`.
    pub fn name(self) -> String {
        Attachment::from(self).name()
    }
}

impl From<ColorAttachment> for Attachment {
    fn from(c: ColorAttachment) -> Self {
        Attachment::Color(c.0)
    }
}

impl std::fmt::Display for ColorAttachment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GL_COLOR_ATTACHMENT{}", self.0)
    }
}

/// An image that is not a whole single-level texture of the crate's
/// own: a layer of an array texture, or a renderbuffer (both are what host
/// engines attach).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HostImage {
    /// Layer `layer` (level 0) of the `GL_TEXTURE_2D_ARRAY` `texture`.
    TextureLayer {
        /// The array texture.
        texture: glow::Texture,
        /// The layer.
        layer: u32,
    },
    /// A single-sample renderbuffer.
    Renderbuffer(glow::Renderbuffer),
}

/// A framebuffer object with its attachments recorded.
#[derive(Debug)]
pub struct Framebuffer {
    /// The GL name.
    pub(crate) raw: glow::Framebuffer,
    /// Debug label, used in errors.
    pub label: String,
    /// Width of the attachments.
    pub width: u32,
    /// Height of the attachments.
    pub height: u32,
    /// Sample count of the attachments (1 when single-sampled).
    pub samples: u32,
    /// What is attached where. An attachment made from a [`HostImage`]
    /// is described here too, its `raw` and `target` naming the host's
    /// object only for what [`Framebuffer::host_images`] says.
    pub attachments: Vec<(Attachment, TextureRef)>,
    /// The attachments that are layers or renderbuffers.
    host_images: Vec<(Attachment, HostImage)>,
}

impl Framebuffer {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Framebuffer::destroy`] frees it.
    pub fn raw(&self) -> glow::Framebuffer {
        self.raw
    }

    /// Create a framebuffer, attach `attachments`, map colour attachment `i` to
    /// fragment output `draw_buffers[i]` (a `None` leaves the slot unmapped) and
    /// check completeness. On failure nothing is left allocated.
    pub fn new(
        gl: &glow::Context,
        label: &str,
        attachments: &[(Attachment, TextureRef)],
        draw_buffers: &[Option<u32>],
    ) -> Result<Self> {
        Self::with_host_images(gl, label, attachments, &[], draw_buffers)
    }

    /// [`Framebuffer::new`], where the attachments whose points appear in
    /// `host_images` attach that layer or renderbuffer instead (their
    /// `TextureRef` still gives the format and size).
    pub fn with_host_images(
        gl: &glow::Context,
        label: &str,
        attachments: &[(Attachment, TextureRef)],
        host_images: &[(Attachment, HostImage)],
        draw_buffers: &[Option<u32>],
    ) -> Result<Self> {
        let (width, height, samples) = match attachments.first() {
            Some((_, t)) => (t.width, t.height, t.samples),
            None => {
                return Err(Error::Layout(format!(
                    "framebuffer `{label}` has no attachments"
                )));
            }
        };
        let raw = unsafe { gl.create_framebuffer() }.map_err(|reason| Error::Create {
            what: format!("framebuffer `{label}`"),
            reason,
        })?;
        counters::created(Kind::Framebuffer);
        let fbo = Framebuffer {
            raw,
            label: label.to_string(),
            width,
            height,
            samples,
            attachments: attachments.to_vec(),
            host_images: host_images.to_vec(),
        };
        match fbo.configure(gl, draw_buffers) {
            Ok(()) => Ok(fbo),
            Err(e) => {
                fbo.destroy(gl);
                Err(e)
            }
        }
    }

    fn configure(&self, gl: &glow::Context, draw_buffers: &[Option<u32>]) -> Result<()> {
        // The host's bindings are put back: set-up may run inside its frame.
        let (draw, read) = unsafe {
            (
                gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING),
                gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING),
            )
        };
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.raw));
            for (point, tex) in &self.attachments {
                let host = self.host_images.iter().find(|(p, _)| p == point);
                if let Some((_, image)) = host {
                    match *image {
                        HostImage::TextureLayer { texture, layer } => gl.framebuffer_texture_layer(
                            glow::FRAMEBUFFER,
                            point.gl_enum(),
                            Some(texture),
                            0,
                            layer as i32,
                        ),
                        HostImage::Renderbuffer(rb) => gl.framebuffer_renderbuffer(
                            glow::FRAMEBUFFER,
                            point.gl_enum(),
                            glow::RENDERBUFFER,
                            Some(rb),
                        ),
                    }
                    continue;
                }
                match tex.target {
                    glow::TEXTURE_2D | glow::TEXTURE_2D_MULTISAMPLE => gl.framebuffer_texture_2d(
                        glow::FRAMEBUFFER,
                        point.gl_enum(),
                        tex.target,
                        Some(tex.raw),
                        0,
                    ),
                    _ => {
                        gl.framebuffer_texture(glow::FRAMEBUFFER, point.gl_enum(), Some(tex.raw), 0)
                    }
                }
            }
            let buffers: Vec<u32> = draw_buffers
                .iter()
                .map(|b| b.map_or(glow::NONE, |i| glow::COLOR_ATTACHMENT0 + i))
                .collect();
            if buffers.is_empty() {
                gl.draw_buffers(&[glow::NONE]);
                gl.read_buffer(glow::NONE);
            } else {
                gl.draw_buffers(&buffers);
            }
        }
        label_object(gl, glow::FRAMEBUFFER, self.raw.0.get(), &self.label);
        let status = unsafe { gl.check_framebuffer_status(glow::FRAMEBUFFER) };
        unsafe {
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, live_framebuffer(gl, draw));
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, live_framebuffer(gl, read));
        }
        check_error(gl, &format!("configuring framebuffer `{}`", self.label))?;
        if status != glow::FRAMEBUFFER_COMPLETE {
            return Err(Error::FramebufferIncomplete {
                label: self.label.clone(),
                status: framebuffer_status_name(status),
            });
        }
        Ok(())
    }

    /// Bind to `GL_FRAMEBUFFER` and set the viewport to its size.
    pub fn bind(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.raw));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// Read the whole framebuffer back as bytes, `channels` per pixel of
    /// `format` (`GL_RGBA`, `GL_RED`, `GL_STENCIL_INDEX`, …) from colour
    /// attachment 0 (or the stencil), rows top first as images are read.
    /// `what` names it in errors.
    pub fn read_u8(
        &self,
        gl: &glow::Context,
        format: u32,
        channels: usize,
        what: &str,
    ) -> Result<Vec<u8>> {
        let (w, h) = (self.width, self.height);
        let row = w as usize * channels;
        let mut data = vec![0u8; row * h as usize];
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.raw));
            if format != glow::STENCIL_INDEX && format != glow::DEPTH_COMPONENT {
                gl.read_buffer(glow::COLOR_ATTACHMENT0);
            }
            gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
            gl.pixel_store_i32(glow::PACK_ROW_LENGTH, 0);
            gl.read_pixels(
                0,
                0,
                w as i32,
                h as i32,
                format,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut data)),
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        check_error(gl, &format!("reading {what}"))?;
        // GL's rows run bottom-up.
        Ok(data
            .chunks_exact(row.max(1))
            .rev()
            .flatten()
            .copied()
            .collect())
    }

    /// The attachments that are layers or renderbuffers.
    pub fn host_images(&self) -> &[(Attachment, HostImage)] {
        &self.host_images
    }

    /// Whether a depth (or depth-stencil) image is attached.
    pub fn has_depth(&self) -> bool {
        self.attachments.iter().any(|(_, t)| t.format.is_depth())
    }

    /// The texture at an attachment point.
    pub fn texture(&self, point: Attachment) -> Option<TextureRef> {
        self.attachments
            .iter()
            .find(|(p, _)| *p == point)
            .map(|(_, t)| *t)
    }

    /// Free the framebuffer object (not its textures).
    pub fn destroy(self, gl: &glow::Context) {
        unsafe { gl.delete_framebuffer(self.raw) };
        counters::destroyed(Kind::Framebuffer);
    }
}
