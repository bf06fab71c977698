//! What a host's framebuffer holds, read back from GL: every attachment's
//! image, internal format (as the host asked for it and as the driver
//! made it), size and samples, and the draw-buffer mapping. The retrofit
//! builds its twins from it; the second layer copies the host's images by it.

use crate::gl::format::{ComponentType, FormatProperties, internal_format_name};
use crate::gl::{Attachment, Format, HostImage, SetupState, TextureRef, check_error};
use crate::{Error, Result};
use glow::HasContext;

/// The image a host attachment points at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HostImageKind {
    /// Level 0 of a `GL_TEXTURE_2D`.
    Texture2d(glow::Texture),
    /// Layer `layer`, level 0, of a `GL_TEXTURE_2D_ARRAY`
    /// (`glFramebufferTextureLayer`).
    TextureLayer {
        /// The array texture.
        texture: glow::Texture,
        /// The layer.
        layer: u32,
    },
    /// A single-sample renderbuffer.
    Renderbuffer(glow::Renderbuffer),
}

/// One attachment of the host's framebuffer, as introspected.
#[derive(Clone, Debug, PartialEq)]
pub struct HostAttachment {
    /// Attachment point.
    pub point: Attachment,
    /// The host's image.
    pub image: HostImageKind,
    /// Its format, found from the internal format or, for unsized ones
    /// (`GL_RGBA`, `GL_DEPTH_COMPONENT`), from what the driver made of it.
    pub format: Format,
    /// The internal format as the host asked for it, e.g. `GL_RGBA`.
    pub requested_format: String,
    /// Width of the image.
    pub width: u32,
    /// Height of the image.
    pub height: u32,
}

impl HostAttachment {
    /// A description for the framebuffer wrapper: the format and size, and
    /// the texture where the image is a whole 2D texture.
    pub(crate) fn texture_ref(&self) -> TextureRef {
        let (raw, target) = match self.image {
            HostImageKind::Texture2d(t) => (t, glow::TEXTURE_2D),
            HostImageKind::TextureLayer { texture, .. } => (texture, glow::TEXTURE_2D_ARRAY),
            // Never bound as a texture: `host_image` attaches it.
            HostImageKind::Renderbuffer(rb) => (glow::NativeTexture(rb.0), glow::RENDERBUFFER),
        };
        TextureRef {
            raw,
            target,
            format: self.format,
            width: self.width,
            height: self.height,
            samples: 1,
        }
    }

    /// How the framebuffer wrapper must attach it, when not as a 2D texture.
    pub(crate) fn host_image(&self) -> Option<HostImage> {
        match self.image {
            HostImageKind::Texture2d(_) => None,
            HostImageKind::TextureLayer { texture, layer } => {
                Some(HostImage::TextureLayer { texture, layer })
            }
            HostImageKind::Renderbuffer(rb) => Some(HostImage::Renderbuffer(rb)),
        }
    }

    /// The GL object's name, to tell whether two points share it.
    fn object_name(&self) -> u32 {
        match self.image {
            HostImageKind::Texture2d(t) | HostImageKind::TextureLayer { texture: t, .. } => {
                t.0.get()
            }
            HostImageKind::Renderbuffer(rb) => rb.0.get(),
        }
    }
}

/// What a host framebuffer holds.
#[derive(Clone, Debug, PartialEq)]
pub struct HostFramebuffer {
    /// The host's FBO.
    pub fbo: glow::Framebuffer,
    /// Colour attachments, by ascending attachment number.
    pub colors: Vec<HostAttachment>,
    /// The depth (or depth-stencil) attachment.
    pub depth: HostAttachment,
    /// Draw buffer `i` → colour attachment number (`None` for `GL_NONE`).
    pub draw_buffers: Vec<Option<u32>>,
    /// Colour attachments no draw buffer maps (a `GL_NONE` hole): the
    /// geometry pass cannot write them, so they are neither twinned nor
    /// resolved and keep what the host put there.
    pub undrawn: Vec<Attachment>,
}

/// How a framebuffer of ours attaches the host images that are not whole
/// 2D textures ([`Framebuffer::with_host_images`]).
pub(crate) type HostImages = Vec<(Attachment, HostImage)>;

impl HostFramebuffer {
    /// Width and height (all attachments agree).
    pub fn size(&self) -> (u32, u32) {
        (self.depth.width, self.depth.height)
    }

    /// The host's images as a framebuffer of ours attaches them: colour
    /// `k` at `Color(k)` (in host colour order), depth at its own point,
    /// and how those that are not whole 2D textures are attached.
    pub(crate) fn images(&self) -> (Vec<(Attachment, TextureRef)>, HostImages) {
        let mut attachments = Vec::with_capacity(self.colors.len() + 1);
        let mut images = Vec::new();
        for (point, a) in self
            .colors
            .iter()
            .enumerate()
            .map(|(k, a)| (Attachment::Color(k as u32), a))
            .chain([(self.depth.point, &self.depth)])
        {
            attachments.push((point, a.texture_ref()));
            images.extend(a.host_image().map(|image| (point, image)));
        }
        (attachments, images)
    }
}

fn attachment_param(gl: &glow::Context, point: u32, pname: u32) -> i32 {
    unsafe { gl.get_framebuffer_attachment_parameter_i32(glow::FRAMEBUFFER, point, pname) }
}

/// The properties the driver reports for the image at `point`.
fn attachment_properties(gl: &glow::Context, point: u32) -> Option<FormatProperties> {
    let p = |pname| attachment_param(gl, point, pname).max(0) as u32;
    let component = ComponentType::from_gl(p(glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE))?;
    let srgb = p(glow::FRAMEBUFFER_ATTACHMENT_COLOR_ENCODING) == glow::SRGB;
    Some(FormatProperties {
        component,
        rgba_bits: [
            p(glow::FRAMEBUFFER_ATTACHMENT_RED_SIZE),
            p(glow::FRAMEBUFFER_ATTACHMENT_GREEN_SIZE),
            p(glow::FRAMEBUFFER_ATTACHMENT_BLUE_SIZE),
            p(glow::FRAMEBUFFER_ATTACHMENT_ALPHA_SIZE),
        ],
        depth_bits: p(glow::FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE),
        stencil_bits: p(glow::FRAMEBUFFER_ATTACHMENT_STENCIL_SIZE),
        srgb,
    })
}

/// The texture target a texture name was created with, found by binding
/// it: binding to any other target is `GL_INVALID_OPERATION`.
fn texture_target(gl: &glow::Context, texture: glow::Texture) -> Option<u32> {
    const CANDIDATES: [u32; 6] = [
        glow::TEXTURE_2D,
        glow::TEXTURE_2D_ARRAY,
        glow::TEXTURE_2D_MULTISAMPLE,
        glow::TEXTURE_CUBE_MAP,
        glow::TEXTURE_RECTANGLE,
        glow::TEXTURE_3D,
    ];
    CANDIDATES.into_iter().find(|&target| unsafe {
        gl.bind_texture(target, Some(texture));
        let ok = gl.get_error() == glow::NO_ERROR;
        gl.bind_texture(target, None);
        ok
    })
}

fn target_name(target: u32) -> &'static str {
    match target {
        glow::TEXTURE_2D => "GL_TEXTURE_2D",
        glow::TEXTURE_2D_ARRAY => "GL_TEXTURE_2D_ARRAY",
        glow::TEXTURE_2D_MULTISAMPLE => "GL_TEXTURE_2D_MULTISAMPLE",
        glow::TEXTURE_CUBE_MAP => "GL_TEXTURE_CUBE_MAP",
        glow::TEXTURE_RECTANGLE => "GL_TEXTURE_RECTANGLE",
        glow::TEXTURE_3D => "GL_TEXTURE_3D",
        _ => "an unknown texture target",
    }
}

pub(crate) fn introspect_point(
    gl: &glow::Context,
    point: Attachment,
) -> Result<Option<HostAttachment>> {
    let name = point.name();
    let e = point.gl_enum();
    let refuse = |reason: String| Error::Retrofit {
        attachment: name.clone(),
        reason,
    };
    let kind = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE) as u32;
    let raw = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME) as u32;
    let (image, internal, width, height) = match kind {
        glow::NONE => return Ok(None),
        glow::TEXTURE => {
            let level = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_TEXTURE_LEVEL);
            let layered = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_LAYERED);
            let layer = attachment_param(gl, e, glow::FRAMEBUFFER_ATTACHMENT_TEXTURE_LAYER);
            let _ = check_error(gl, "reading attachment parameters");
            let texture = std::num::NonZeroU32::new(raw)
                .map(glow::NativeTexture)
                .ok_or_else(|| refuse("the driver reports texture 0".into()))?;
            if layered != 0 {
                return Err(refuse(format!(
                    "texture {raw} is attached layered (glFramebufferTexture on an array); \
                     attach one layer with glFramebufferTextureLayer instead"
                )));
            }
            if level != 0 {
                return Err(refuse(format!(
                    "texture {raw} is attached at mip level {level}; only level 0 can be retrofitted"
                )));
            }
            if !unsafe { gl.is_texture(texture) } {
                return Err(refuse(format!(
                    "texture {raw} was deleted (glIsTexture is false) and is still attached; \
                     attach a texture that exists"
                )));
            }
            let target = texture_target(gl, texture);
            let image = match target {
                Some(glow::TEXTURE_2D) => HostImageKind::Texture2d(texture),
                Some(glow::TEXTURE_2D_ARRAY) => HostImageKind::TextureLayer {
                    texture,
                    layer: layer.max(0) as u32,
                },
                Some(glow::TEXTURE_2D_MULTISAMPLE) => {
                    return Err(refuse(format!(
                        "texture {raw} is already a GL_TEXTURE_2D_MULTISAMPLE; the retrofit \
                         makes the multisampled twins itself, so give it single-sample textures"
                    )));
                }
                other => {
                    return Err(refuse(format!(
                        "texture {raw} is a {}; only GL_TEXTURE_2D and layers of a \
                         GL_TEXTURE_2D_ARRAY can be retrofitted",
                        other.map_or("texture of an unknown target", target_name)
                    )));
                }
            };
            let target = target.unwrap_or(glow::TEXTURE_2D);
            let (internal, w, h) = unsafe {
                gl.bind_texture(target, Some(texture));
                let v = (
                    gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_INTERNAL_FORMAT),
                    gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_WIDTH),
                    gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_HEIGHT),
                );
                gl.bind_texture(target, None);
                v
            };
            (image, internal as u32, w, h)
        }
        glow::RENDERBUFFER => {
            let rb = std::num::NonZeroU32::new(raw)
                .map(glow::NativeRenderbuffer)
                .ok_or_else(|| refuse("the driver reports renderbuffer 0".into()))?;
            if !unsafe { gl.is_renderbuffer(rb) } {
                return Err(refuse(format!(
                    "renderbuffer {raw} was deleted (glIsRenderbuffer is false) and is still \
                     attached; attach a renderbuffer that exists"
                )));
            }
            let (internal, w, h, samples) = unsafe {
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                let p = |pname| gl.get_renderbuffer_parameter_i32(glow::RENDERBUFFER, pname);
                let v = (
                    p(glow::RENDERBUFFER_INTERNAL_FORMAT),
                    p(glow::RENDERBUFFER_WIDTH),
                    p(glow::RENDERBUFFER_HEIGHT),
                    p(glow::RENDERBUFFER_SAMPLES),
                );
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
                v
            };
            if samples > 1 {
                return Err(refuse(format!(
                    "renderbuffer {raw} is already multisampled ({samples}x); the retrofit \
                     makes the multisampled twins itself, so give it single-sample images"
                )));
            }
            (HostImageKind::Renderbuffer(rb), internal as u32, w, h)
        }
        glow::FRAMEBUFFER_DEFAULT => {
            return Err(refuse(
                "it is the default framebuffer's; the retrofit needs the host's own FBO".into(),
            ));
        }
        other => return Err(refuse(format!("unexpected object type 0x{other:04X}"))),
    };
    let requested_format = internal_format_name(internal);
    let format = match Format::from_internal_format(internal) {
        Some(f) => Some(f),
        None => attachment_properties(gl, e).and_then(|p| Format::from_properties(&p)),
    };
    let _ = check_error(gl, "reading attachment properties");
    let format = format.ok_or_else(|| Error::UnsupportedFormat {
        attachment: name.clone(),
        format: requested_format.clone(),
        reason: "no multisampled twin can hold it; use a sized colour format such as \
                 GL_RGBA8, GL_RGBA16F, GL_RGBA32F, an snorm, unorm or integer format, or a \
                 GL_DEPTH_COMPONENT*/GL_DEPTH24_STENCIL8 depth format"
            .into(),
    })?;
    Ok(Some(HostAttachment {
        point,
        image,
        format,
        requested_format,
        width: width.max(0) as u32,
        height: height.max(0) as u32,
    }))
}

/// Whether the host's framebuffer still holds what `host` read: each image
/// attached where it was, not deleted, at the size it had. A host that
/// re-allocates, deletes or replaces an attachment must call `refresh` (or
/// `refresh_with`, for a framebuffer made anew); a
/// pass over the old images would write part of an image of another size
/// or raise a GL error naming none of this. The host's bindings are left
/// as they were (the read framebuffer, the active unit's 2D and 2D-array
/// textures and the renderbuffer are put back).
///
/// Errors: [`Error::Retrofit`] naming the first attachment that changed and
/// how, or [`Error::InvalidArgument`] when the framebuffer is gone.
pub(crate) fn check_unchanged(gl: &glow::Context, host: &HostFramebuffer) -> Result<()> {
    check_alive(gl, host.fbo)?;
    let changed = |a: &HostAttachment, what: String| Error::Retrofit {
        attachment: a.point.name(),
        reason: format!(
            "{what} since the retrofit read it ({}x{}); call refresh after re-allocating the \
             G-buffer's images, or refresh_with with the new framebuffer where the host made \
             the G-buffer anew",
            a.width, a.height
        ),
    };
    let restore = unsafe {
        [
            (glow::READ_FRAMEBUFFER, glow::READ_FRAMEBUFFER_BINDING),
            (glow::TEXTURE_2D, glow::TEXTURE_BINDING_2D),
            (glow::TEXTURE_2D_ARRAY, glow::TEXTURE_BINDING_2D_ARRAY),
            (glow::RENDERBUFFER, glow::RENDERBUFFER_BINDING),
        ]
        .map(|(target, binding)| (target, gl.get_parameter_i32(binding)))
    };
    let result = (|| {
        for a in host.colors.iter().chain([&host.depth]) {
            let (size, attached) = unsafe {
                gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(host.fbo));
                // The depth-stencil point is read at depth, as introspection reads it.
                let point = match a.point {
                    Attachment::DepthStencil => glow::DEPTH_ATTACHMENT,
                    p => p.gl_enum(),
                };
                let attached = gl.get_framebuffer_attachment_parameter_i32(
                    glow::READ_FRAMEBUFFER,
                    point,
                    glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME,
                ) as u32;
                let size = match a.image {
                    HostImageKind::Texture2d(t)
                    | HostImageKind::TextureLayer { texture: t, .. }
                        if gl.is_texture(t) =>
                    {
                        let target = match a.image {
                            HostImageKind::TextureLayer { .. } => glow::TEXTURE_2D_ARRAY,
                            _ => glow::TEXTURE_2D,
                        };
                        gl.bind_texture(target, Some(t));
                        Some((
                            gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_WIDTH),
                            gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_HEIGHT),
                        ))
                    }
                    HostImageKind::Renderbuffer(rb) if gl.is_renderbuffer(rb) => {
                        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                        Some((
                            gl.get_renderbuffer_parameter_i32(
                                glow::RENDERBUFFER,
                                glow::RENDERBUFFER_WIDTH,
                            ),
                            gl.get_renderbuffer_parameter_i32(
                                glow::RENDERBUFFER,
                                glow::RENDERBUFFER_HEIGHT,
                            ),
                        ))
                    }
                    _ => None,
                };
                (size, attached)
            };
            let Some((w, h)) = size else {
                return Err(changed(a, "the host deleted its image".into()));
            };
            if attached != a.object_name() {
                return Err(changed(
                    a,
                    format!(
                        "another image ({attached}) is attached in place of {}",
                        a.object_name()
                    ),
                ));
            }
            if (w.max(0) as u32, h.max(0) as u32) != (a.width, a.height) {
                return Err(changed(a, format!("the host re-allocated it at {w}x{h}")));
            }
        }
        Ok(())
    })();
    unsafe {
        for (target, raw) in restore {
            let name = std::num::NonZeroU32::new(raw as u32);
            match target {
                glow::READ_FRAMEBUFFER => gl.bind_framebuffer(
                    target,
                    name.map(glow::NativeFramebuffer)
                        .filter(|&f| gl.is_framebuffer(f)),
                ),
                glow::RENDERBUFFER => gl.bind_renderbuffer(
                    target,
                    name.map(glow::NativeRenderbuffer)
                        .filter(|&r| gl.is_renderbuffer(r)),
                ),
                _ => gl.bind_texture(
                    target,
                    name.map(glow::NativeTexture).filter(|&t| gl.is_texture(t)),
                ),
            }
        }
    }
    result
}

/// Whether the framebuffer a retrofit was made for still exists: a host
/// that deletes it and makes another (whose name GL does not promise to be
/// the same) gives that one to `refresh_with`.
///
/// Errors: [`Error::InvalidArgument`] saying so.
pub(crate) fn check_alive(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<()> {
    if unsafe { gl.is_framebuffer(fbo) } {
        return Ok(());
    }
    Err(Error::invalid(format!(
        "host framebuffer {} is no longer a framebuffer object (deleted since the retrofit read \
         it); give the host's new framebuffer to refresh_with (dmsaa_refresh_with)",
        fbo.0
    )))
}

/// Read a host framebuffer's attachments, formats, sizes and draw-buffer
/// mapping. The host's bindings are left as they were.
pub fn introspect(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<HostFramebuffer> {
    // Binding a name that is not a framebuffer is `GL_INVALID_OPERATION`
    // (and every query after it reads the host's own binding): say so.
    if !unsafe { gl.is_framebuffer(fbo) } {
        return Err(Error::invalid(format!(
            "host framebuffer {} is not a framebuffer object (glIsFramebuffer is false: never \
             bound since glGenFramebuffers, or deleted); pass the G-buffer framebuffer the \
             geometry pass draws into",
            fbo.0
        )));
    }
    let _host = SetupState::capture(gl).guard(gl);
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
    introspect_bound(gl, fbo)
}

fn introspect_bound(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<HostFramebuffer> {
    let max_colors =
        unsafe { gl.get_parameter_i32(glow::MAX_COLOR_ATTACHMENTS) }.clamp(1, 32) as u32;
    let max_draw = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) }.clamp(1, 32) as u32;
    let mut colors = Vec::new();
    for i in 0..max_colors {
        if let Some(a) = introspect_point(gl, Attachment::Color(i))? {
            colors.push(a);
        }
    }
    // Querying GL_DEPTH_STENCIL_ATTACHMENT is an error when depth and stencil
    // differ; read the depth point, and call it depth-stencil when the same
    // texture also sits at the stencil point.
    let depth = introspect_point(gl, Attachment::Depth)?.map(|mut a| {
        let stencil_name = attachment_param(
            gl,
            glow::STENCIL_ATTACHMENT,
            glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME,
        );
        if a.format.has_stencil() && stencil_name as u32 == a.object_name() {
            a.point = Attachment::DepthStencil;
        }
        a
    });
    let depth = depth.ok_or_else(|| Error::Retrofit {
        attachment: "GL_DEPTH_ATTACHMENT".into(),
        reason: if colors.is_empty() {
            // Engines that attach their textures on first bind: nothing yet.
            "the host framebuffer has nothing attached at all (no colour, no depth); make the retrofit once the engine has attached its G-buffer's images (some engines attach them on the framebuffer's first bind)".into()
        } else {
            "the host framebuffer has no depth attachment; the resolve needs per-sample depth".into()
        },
    })?;
    if !depth.format.is_depth() {
        return Err(Error::UnsupportedFormat {
            attachment: "GL_DEPTH_ATTACHMENT".into(),
            format: depth.format.name().into(),
            reason: "not a depth format".into(),
        });
    }
    if colors.is_empty() {
        return Err(Error::Retrofit {
            attachment: "GL_COLOR_ATTACHMENT0".into(),
            reason: "the host framebuffer has no colour attachments".into(),
        });
    }
    if colors.len() > crate::resolve::MAX_ATTACHMENTS {
        return Err(Error::Retrofit {
            attachment: colors[crate::resolve::MAX_ATTACHMENTS].point.name(),
            reason: format!(
                "at most {} colour attachments are supported",
                crate::resolve::MAX_ATTACHMENTS
            ),
        });
    }
    for a in &colors {
        if (a.width, a.height) != (depth.width, depth.height) {
            return Err(Error::Retrofit {
                attachment: a.point.name(),
                reason: format!(
                    "it is {}x{} but the depth attachment is {}x{}; all attachments must have one size",
                    a.width, a.height, depth.width, depth.height
                ),
            });
        }
        if a.format.is_depth() {
            return Err(Error::UnsupportedFormat {
                attachment: a.point.name(),
                format: a.format.name().into(),
                reason: "a depth format on a colour attachment".into(),
            });
        }
    }
    let mut draw_buffers = Vec::new();
    for i in 0..max_draw {
        let b = unsafe { gl.get_parameter_i32(glow::DRAW_BUFFER0 + i) } as u32;
        draw_buffers.push(
            (glow::COLOR_ATTACHMENT0..glow::COLOR_ATTACHMENT0 + 32)
                .contains(&b)
                .then(|| b - glow::COLOR_ATTACHMENT0),
        );
    }
    while draw_buffers.last() == Some(&None) {
        draw_buffers.pop();
    }
    check_error(gl, "introspecting the host framebuffer")?;
    // What no draw buffer reaches, the geometry pass cannot write: it keeps
    // what the host put there, so it is neither twinned nor resolved.
    let (colors, undrawn): (Vec<HostAttachment>, Vec<HostAttachment>) = colors
        .into_iter()
        .partition(|a| matches!(a.point, Attachment::Color(n) if draw_buffers.contains(&Some(n))));
    if colors.is_empty() {
        return Err(Error::Retrofit {
            attachment: undrawn
                .first()
                .map_or("GL_COLOR_ATTACHMENT0".into(), |a| a.point.name()),
            reason: "no colour attachment is in the host framebuffer's draw buffers".into(),
        });
    }
    Ok(HostFramebuffer {
        fbo,
        colors,
        depth,
        draw_buffers,
        undrawn: undrawn.into_iter().map(|a| a.point).collect(),
    })
}
