//! A [`HostSpec`](super::HostSpec) built with raw GL calls the way a host
//! writes them ([`RandomHost`]), and what its attachments hold.

use super::formats::*;
use super::spec::*;
use glow::HasContext;

/// How a shader writes and reads an attachment, as the driver made it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueKind {
    /// Unsigned normalised (and sRGB): `vec4` in [0, 1].
    Unorm,
    /// Signed normalised: `vec4` in [-1, 1].
    Snorm,
    /// Floating point (`unsigned` for `GL_R11F_G11F_B10F`).
    Float {
        /// Whether the format stores no sign.
        unsigned: bool,
    },
    /// Signed integer: `ivec4`.
    Int,
    /// Unsigned integer: `uvec4`.
    Uint,
}

impl ValueKind {
    /// Integer formats, which the resolve selects one sample of.
    pub fn is_integer(self) -> bool {
        matches!(self, ValueKind::Int | ValueKind::Uint)
    }
}

/// The GL objects of one image.
#[derive(Clone, Copy, Debug)]
pub(super) enum Image {
    Texture(glow::Texture),
    Renderbuffer(glow::Renderbuffer),
}

/// A random host's objects, built from its [`HostSpec`] with raw GL.
#[derive(Debug)]
pub struct RandomHost {
    /// What it was built from.
    pub spec: HostSpec,
    /// Its framebuffer.
    pub fbo: glow::Framebuffer,
    /// Width now.
    pub width: u32,
    /// Height now.
    pub height: u32,
    /// How each colour attachment (in spec order) is written.
    pub kinds: Vec<ValueKind>,
    images: Vec<Image>,
    depth_image: Option<Image>,
}

/// Why a random host could not be built: a host bug, not a case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HostIncomplete(pub String);

pub(super) fn status_name(status: u32) -> String {
    deferred_msaa::gl::framebuffer_status_name(status).to_string()
}

impl RandomHost {
    /// Build it; a framebuffer the driver calls incomplete, or a GL error
    /// while building it, is the host's own bug ([`HostIncomplete`],
    /// nothing left allocated). The host's bindings go back to 0.
    pub fn build(gl: &glow::Context, spec: &HostSpec) -> Result<RandomHost, HostIncomplete> {
        unsafe {
            let _ = gl.get_error();
            let fbo = gl.create_framebuffer().map_err(HostIncomplete)?;
            let mut host = RandomHost {
                spec: spec.clone(),
                fbo,
                width: spec.width,
                height: spec.height,
                kinds: Vec::new(),
                images: Vec::new(),
                depth_image: None,
            };
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            for c in &spec.colors {
                let (w, h) = c.size.unwrap_or((spec.width, spec.height));
                let image = allocate(gl, c.format, c.storage, w, h);
                attach(gl, glow::COLOR_ATTACHMENT0 + c.point, &image, c.storage);
                host.images.push(image);
            }
            if let Some(d) = &spec.depth {
                let image = allocate(gl, d.format, d.storage, spec.width, spec.height);
                let points: &[u32] = match d.point {
                    DepthPoint::Depth => &[glow::DEPTH_ATTACHMENT],
                    DepthPoint::DepthStencil => &[glow::DEPTH_STENCIL_ATTACHMENT],
                    DepthPoint::Both => &[glow::DEPTH_ATTACHMENT, glow::STENCIL_ATTACHMENT],
                    DepthPoint::Stencil => &[glow::STENCIL_ATTACHMENT],
                };
                for &p in points {
                    attach(gl, p, &image, d.storage);
                }
                host.depth_image = Some(image);
            }
            let buffers: Vec<u32> = spec
                .draw_buffers
                .iter()
                .map(|b| b.map_or(glow::NONE, |n| glow::COLOR_ATTACHMENT0 + n))
                .collect();
            gl.draw_buffers(&buffers);
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            let error = gl.get_error();
            let problem = if error != glow::NO_ERROR {
                Some(format!("GL error 0x{error:04X} while building"))
            } else if status != glow::FRAMEBUFFER_COMPLETE {
                Some(status_name(status))
            } else {
                None
            };
            if let Some(p) = problem {
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                host.destroy(gl);
                let _ = gl.get_error();
                return Err(HostIncomplete(p));
            }
            host.kinds = spec
                .colors
                .iter()
                .map(|c| value_kind(gl, glow::COLOR_ATTACHMENT0 + c.point, c.format))
                .collect();
            host.fill_undrawn(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            let error = gl.get_error();
            if error != glow::NO_ERROR {
                host.destroy(gl);
                return Err(HostIncomplete(format!(
                    "GL error 0x{error:04X} while clearing"
                )));
            }
            Ok(host)
        }
    }

    /// Give attachments no draw buffer maps a value of their own, so that
    /// a resolve that wrote them would show: each in turn becomes draw
    /// buffer 0 for one clear, then the host's list is put back.
    unsafe fn fill_undrawn(&self, gl: &glow::Context) {
        unsafe {
            for (c, kind) in self.spec.colors.iter().zip(&self.kinds) {
                if self.spec.draw_buffers.contains(&Some(c.point)) {
                    continue;
                }
                gl.draw_buffers(&[glow::COLOR_ATTACHMENT0 + c.point]);
                let v = 3 + c.point;
                match kind {
                    ValueKind::Int => gl.clear_buffer_i32_slice(glow::COLOR, 0, &[v as i32; 4]),
                    ValueKind::Uint => gl.clear_buffer_u32_slice(glow::COLOR, 0, &[v; 4]),
                    _ => gl.clear_buffer_f32_slice(glow::COLOR, 0, &[v as f32 / 16.0; 4]),
                }
            }
            let buffers: Vec<u32> = self
                .spec
                .draw_buffers
                .iter()
                .map(|b| b.map_or(glow::NONE, |n| glow::COLOR_ATTACHMENT0 + n))
                .collect();
            gl.draw_buffers(&buffers);
        }
    }

    /// Re-specify every image at `width` x `height`, in place (the same
    /// texture and renderbuffer names), as an engine does on a window
    /// resize; the framebuffer is left as it is.
    pub fn resize(&mut self, gl: &glow::Context, width: u32, height: u32) {
        unsafe {
            for (c, image) in self.spec.colors.iter().zip(&self.images) {
                respecify(gl, c.format, c.storage, image, width, height);
            }
            if let (Some(d), Some(image)) = (&self.spec.depth, &self.depth_image) {
                respecify(gl, d.format, d.storage, image, width, height);
            }
            self.width = width;
            self.height = height;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            self.fill_undrawn(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    /// Delete everything the host made.
    pub fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            for image in self.images.iter().chain(&self.depth_image) {
                match *image {
                    Image::Texture(t) => gl.delete_texture(t),
                    Image::Renderbuffer(r) => gl.delete_renderbuffer(r),
                }
            }
        }
    }
}

pub(super) fn value_kind(gl: &glow::Context, point: u32, format: HostFormat) -> ValueKind {
    let ty = unsafe {
        gl.get_framebuffer_attachment_parameter_i32(
            glow::FRAMEBUFFER,
            point,
            glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE,
        )
    } as u32;
    match ty {
        glow::INT => ValueKind::Int,
        glow::UNSIGNED_INT => ValueKind::Uint,
        glow::SIGNED_NORMALIZED => ValueKind::Snorm,
        glow::FLOAT => ValueKind::Float {
            unsigned: matches!(format.internal, glow::R11F_G11F_B10F | glow::RGB9_E5),
        },
        _ => ValueKind::Unorm,
    }
}

unsafe fn tex_image(gl: &glow::Context, target: u32, format: HostFormat, w: u32, h: u32) {
    unsafe {
        gl.tex_image_2d(
            target,
            0,
            format.internal as i32,
            w as i32,
            h as i32,
            0,
            format.pixel,
            format.ty,
            glow::PixelUnpackData::Slice(None),
        );
    }
}

unsafe fn array_image(gl: &glow::Context, target: u32, format: HostFormat, w: u32, h: u32, d: u32) {
    unsafe {
        gl.tex_image_3d(
            target,
            0,
            format.internal as i32,
            w as i32,
            h as i32,
            d as i32,
            0,
            format.pixel,
            format.ty,
            glow::PixelUnpackData::Slice(None),
        );
    }
}

pub(super) fn layers_of(storage: Storage) -> u32 {
    match storage {
        Storage::Layer { layers, .. } => layers,
        Storage::Texture3dLayer => 2,
        _ => 1,
    }
}

unsafe fn respecify(
    gl: &glow::Context,
    format: HostFormat,
    storage: Storage,
    image: &Image,
    w: u32,
    h: u32,
) {
    unsafe {
        match (*image, storage) {
            (Image::Renderbuffer(rb), Storage::MultisampledRenderbuffer) => {
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage_multisample(
                    glow::RENDERBUFFER,
                    4,
                    format.internal,
                    w as i32,
                    h as i32,
                );
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
            }
            (Image::Renderbuffer(rb), _) => {
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage(glow::RENDERBUFFER, format.internal, w as i32, h as i32);
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
            }
            (Image::Texture(t), s) => {
                let target = texture_target(s);
                gl.bind_texture(target, Some(t));
                match s {
                    Storage::Layer { .. } | Storage::Texture3dLayer | Storage::Layered => {
                        array_image(gl, target, format, w, h, layers_of(s))
                    }
                    Storage::MipLevel1 => {
                        tex_image(gl, target, format, 2 * w, 2 * h);
                        gl.tex_image_2d(
                            target,
                            1,
                            format.internal as i32,
                            w as i32,
                            h as i32,
                            0,
                            format.pixel,
                            format.ty,
                            glow::PixelUnpackData::Slice(None),
                        );
                        // Levels 0 and 1 make the whole chain: a level
                        // other than the base one is attachable only from
                        // a mipmap-complete texture.
                        gl.tex_parameter_i32(target, glow::TEXTURE_MAX_LEVEL, 1);
                    }
                    Storage::CubeFace => {
                        for face in 0..6 {
                            tex_image(gl, glow::TEXTURE_CUBE_MAP_POSITIVE_X + face, format, w, h);
                        }
                    }
                    Storage::MultisampledTexture => gl.tex_image_2d_multisample(
                        target,
                        4,
                        format.internal as i32,
                        w as i32,
                        h as i32,
                        true,
                    ),
                    _ => tex_image(gl, target, format, w, h),
                }
                if s != Storage::MultisampledTexture {
                    // Tutorials set nearest filtering; mipmaps are not made.
                    gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
                    gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
                }
                gl.bind_texture(target, None);
            }
        }
    }
}

pub(super) fn texture_target(storage: Storage) -> u32 {
    match storage {
        Storage::Layer { .. } | Storage::Layered => glow::TEXTURE_2D_ARRAY,
        Storage::CubeFace => glow::TEXTURE_CUBE_MAP,
        Storage::Rectangle => glow::TEXTURE_RECTANGLE,
        Storage::Texture3dLayer => glow::TEXTURE_3D,
        Storage::MultisampledTexture => glow::TEXTURE_2D_MULTISAMPLE,
        _ => glow::TEXTURE_2D,
    }
}

unsafe fn allocate(
    gl: &glow::Context,
    format: HostFormat,
    storage: Storage,
    w: u32,
    h: u32,
) -> Image {
    unsafe {
        let image = match storage {
            Storage::Renderbuffer | Storage::MultisampledRenderbuffer => {
                Image::Renderbuffer(gl.create_renderbuffer().expect("a renderbuffer name"))
            }
            _ => Image::Texture(gl.create_texture().expect("a texture name")),
        };
        respecify(gl, format, storage, &image, w, h);
        image
    }
}

unsafe fn attach(gl: &glow::Context, point: u32, image: &Image, storage: Storage) {
    unsafe {
        match (*image, storage) {
            (Image::Renderbuffer(rb), _) => {
                gl.framebuffer_renderbuffer(glow::FRAMEBUFFER, point, glow::RENDERBUFFER, Some(rb))
            }
            (Image::Texture(t), Storage::Layer { layer, .. }) => {
                gl.framebuffer_texture_layer(glow::FRAMEBUFFER, point, Some(t), 0, layer as i32)
            }
            (Image::Texture(t), Storage::Texture3dLayer) => {
                gl.framebuffer_texture_layer(glow::FRAMEBUFFER, point, Some(t), 0, 1)
            }
            (Image::Texture(t), Storage::Layered) => {
                gl.framebuffer_texture(glow::FRAMEBUFFER, point, Some(t), 0)
            }
            (Image::Texture(t), Storage::MipLevel1) => {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(t), 1)
            }
            (Image::Texture(t), Storage::CubeFace) => gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                point,
                glow::TEXTURE_CUBE_MAP_POSITIVE_X,
                Some(t),
                0,
            ),
            (Image::Texture(t), s) => {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, texture_target(s), Some(t), 0)
            }
        }
    }
}
