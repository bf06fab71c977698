//! The host's lit target, as the second layer's mix and the forward target
//! read and write it: a framebuffer of the host's (its first draw buffer's
//! image) or the default framebuffer, and what the host's writes into it
//! mean.
//!
//! GL state cannot tell whether a value in an sRGB-capable image was
//! encoded by GL: the window's back buffer of a program that never enables
//! `GL_FRAMEBUFFER_SRGB` reports `GL_SRGB` encoding on Mesa, yet holds the
//! values the program wrote. What counts is whether the host's lighting
//! wrote through the encoding, which is `GL_FRAMEBUFFER_SRGB` as the host
//! left it: with it off, the crate reads and writes the image's bits as
//! they are, exactly as for a plain `RGBA8` target.

use crate::gl::{Attachment, Format, Framebuffer, HostImage, TextureRef};
use crate::host::{HostAttachment, introspect_point};
use crate::{Error, Result};
use glow::HasContext;

/// The lit target of a host (see the module).
#[derive(Debug)]
pub(crate) struct LitOutput {
    /// The host's framebuffer (`None`: the default framebuffer).
    pub(crate) host: Option<glow::Framebuffer>,
    /// Its first draw buffer's image, for a framebuffer of the host's.
    pub(crate) image: Option<HostAttachment>,
    /// The image's format (for the default framebuffer, as far as the
    /// driver says).
    pub(crate) format: Format,
    /// The host's writes went through the sRGB encoding
    /// (`GL_FRAMEBUFFER_SRGB` on, into an sRGB image).
    pub(crate) srgb_writes: bool,
}

impl LitOutput {
    /// Read what `host` (bound by the caller's state, which the caller
    /// saves) lights into, and check it is `size`. `framebuffer_srgb` is
    /// `GL_FRAMEBUFFER_SRGB` as the host left it.
    pub(crate) fn inspect(
        gl: &glow::Context,
        host: Option<glow::Framebuffer>,
        framebuffer_srgb: bool,
        size: (u32, u32),
    ) -> Result<Self> {
        let (image, format) = match host {
            Some(fbo) => {
                let image = output_image(gl, fbo)?;
                if (image.width, image.height) != size {
                    return Err(Error::Retrofit {
                        attachment: image.point.name(),
                        reason: format!(
                            "the lit output is {}x{}, the G-buffer {}x{}: the crate mixes them pixel for pixel",
                            image.width, image.height, size.0, size.1
                        ),
                    });
                }
                let format = image.format;
                (Some(image), format)
            }
            None => (None, default_framebuffer_format(gl)),
        };
        Ok(LitOutput {
            host,
            image,
            format,
            srgb_writes: framebuffer_srgb && format.is_srgb(),
        })
    }

    /// Whether this is the same target, written the same way.
    pub(crate) fn same(&self, host: Option<glow::Framebuffer>, framebuffer_srgb: bool) -> bool {
        self.host == host && self.srgb_writes == (framebuffer_srgb && self.format.is_srgb())
    }

    /// The format of the crate's copies of the lit image: the image's own
    /// where the host's writes were encoded (the copies then read decoded,
    /// in linear light), else its bits as plain unorm.
    pub(crate) fn copy_format(&self) -> Format {
        if self.srgb_writes {
            self.format
        } else {
            self.format.without_srgb()
        }
    }

    /// A framebuffer of the host's image alone at colour 0, and `extra`
    /// attachments (`None` for the default framebuffer).
    pub(crate) fn framebuffer(
        &self,
        gl: &glow::Context,
        label: &str,
        extra: &[(Attachment, TextureRef)],
    ) -> Result<Option<Framebuffer>> {
        let Some(image) = &self.image else {
            return Ok(None);
        };
        let images: Vec<(Attachment, HostImage)> = image
            .host_image()
            .map(|i| (Attachment::Color(0), i))
            .into_iter()
            .collect();
        let mut attachments = vec![(Attachment::Color(0), image.texture_ref())];
        attachments.extend_from_slice(extra);
        Framebuffer::with_host_images(gl, label, &attachments, &images, &[Some(0)]).map(Some)
    }
}

/// Bind `target` (or the default framebuffer, for `None`) for reading its
/// lit colour; the caller saves the host's state.
pub(crate) fn bind_for_reading(gl: &glow::Context, target: Option<&Framebuffer>) {
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, target.map(Framebuffer::raw));
        if target.is_some() {
            gl.read_buffer(glow::COLOR_ATTACHMENT0);
        }
    }
}

/// The image a host framebuffer lights into: its first draw buffer's.
fn output_image(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<HostAttachment> {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        let draw = gl.get_parameter_i32(glow::DRAW_BUFFER0) as u32;
        let point = match draw.checked_sub(glow::COLOR_ATTACHMENT0) {
            Some(k) if k < 32 => Attachment::Color(k),
            _ => {
                return Err(Error::Retrofit {
                    attachment: "GL_DRAW_BUFFER0".into(),
                    reason:
                        "the lit output's first draw buffer is GL_NONE; the crate mixes into it"
                            .into(),
                });
            }
        };
        introspect_point(gl, point)?.ok_or_else(|| Error::Retrofit {
            attachment: point.name(),
            reason: "the lit output's first draw buffer has nothing attached".into(),
        })
    }
}

/// The default framebuffer's colour format, as far as the driver says.
fn default_framebuffer_format(gl: &glow::Context) -> Format {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        let draw = gl.get_parameter_i32(glow::DRAW_BUFFER) as u32;
        let point = if draw == glow::FRONT || draw == glow::FRONT_LEFT {
            glow::FRONT_LEFT
        } else {
            glow::BACK_LEFT
        };
        let p = |pname| {
            gl.get_framebuffer_attachment_parameter_i32(glow::FRAMEBUFFER, point, pname)
                .max(0) as u32
        };
        let srgb = p(glow::FRAMEBUFFER_ATTACHMENT_COLOR_ENCODING) == glow::SRGB;
        let float = p(glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE) == glow::FLOAT;
        let _ = gl.get_error();
        match (float, srgb) {
            (true, _) => Format::Rgba16f,
            (false, true) => Format::Srgb8Alpha8,
            (false, false) => Format::Rgba8,
        }
    }
}
