//! What the harness reads back and how it builds the hosts' programs: a
//! read-back plane ([`Plane`]) with its channels' encoding and what the
//! resolve must leave in it, the texture and framebuffer reads, and
//! program linking with fixed attribute and output locations.

use glow::HasContext;
use image::RgbaImage;

/// How one channel of a read-back plane is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// `GL_UNSIGNED_BYTE` of a normalised format.
    Unorm8,
    /// `GL_SHORT` of a signed normalised format.
    Snorm16,
    /// `GL_HALF_FLOAT`.
    F16,
    /// `GL_FLOAT`.
    F32,
    /// `GL_UNSIGNED_BYTE` of an integer format (or stencil).
    U8,
    /// `GL_UNSIGNED_INT` of an integer format.
    U32,
}

impl Channel {
    /// Bytes per channel.
    pub fn size(self) -> usize {
        match self {
            Channel::Unorm8 | Channel::U8 => 1,
            Channel::Snorm16 | Channel::F16 => 2,
            Channel::F32 | Channel::U32 => 4,
        }
    }

    /// The GL pixel type to read it with.
    pub fn gl_type(self) -> u32 {
        match self {
            Channel::Unorm8 | Channel::U8 => glow::UNSIGNED_BYTE,
            Channel::Snorm16 => glow::SHORT,
            Channel::F16 => glow::HALF_FLOAT,
            Channel::F32 => glow::FLOAT,
            Channel::U32 => glow::UNSIGNED_INT,
        }
    }

    fn decode(self, b: &[u8]) -> f64 {
        match self {
            Channel::Unorm8 => b[0] as f64 / 255.0,
            Channel::Snorm16 => (i16::from_ne_bytes([b[0], b[1]]) as f64 / 32767.0).max(-1.0),
            Channel::F16 => half::f16::from_ne_bytes([b[0], b[1]]).to_f64(),
            Channel::F32 => f32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Channel::U8 => b[0] as f64,
            Channel::U32 => u32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f64,
        }
    }

    /// The slack allowed when a resolved value is compared with a range of
    /// no-MSAA values: one step of the format (rounding on both sides).
    pub fn slack(self, v: f64) -> f64 {
        match self {
            Channel::Unorm8 => 1.0 / 255.0,
            Channel::Snorm16 => 1.0 / 32767.0,
            Channel::F16 => v.abs().max(1e-3) / 1024.0,
            Channel::F32 => v.abs().max(1e-6) * 1e-5,
            Channel::U8 | Channel::U32 => 0.0,
        }
    }
}

/// What a plane must hold after the resolve, compared with the host's own
/// no-MSAA render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Check {
    /// The host writes one value over each face (a flat colour, an id, a
    /// flat normal, the stencil reference): bit for bit equal inside faces.
    /// These planes also say which face a pixel belongs to.
    Constant,
    /// Varies over a face (position, depth): inside faces, within the range
    /// of the no-MSAA render's 3x3 neighbourhood (one format step of slack).
    Smooth,
    /// Not written by the geometry pass: bit for bit equal everywhere.
    Untouched,
}

/// One attachment read back in its own format.
#[derive(Clone, Debug)]
pub struct Plane {
    /// The attachment and its format, for messages.
    pub name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The channel encoding.
    pub channel: Channel,
    /// Channels per pixel.
    pub channels: usize,
    /// The bytes as GL returned them (rows bottom to top, packed).
    pub raw: Vec<u8>,
    /// What the resolve must leave in it.
    pub check: Check,
}

impl Plane {
    fn bytes_per_pixel(&self) -> usize {
        self.channel.size() * self.channels
    }

    /// The bytes of pixel `(x, y)` (GL's origin: bottom left).
    pub fn texel(&self, x: u32, y: u32) -> &[u8] {
        let n = self.bytes_per_pixel();
        let i = (y * self.width + x) as usize * n;
        &self.raw[i..i + n]
    }

    /// The decoded channels of pixel `(x, y)`.
    pub fn values(&self, x: u32, y: u32) -> Vec<f64> {
        let s = self.channel.size();
        self.texel(x, y)
            .chunks_exact(s)
            .map(|c| self.channel.decode(c))
            .collect()
    }
}

/// A description of how to read one attachment.
pub struct Read<'a> {
    /// Plane name (attachment and format), e.g. `"GL_COLOR_ATTACHMENT0 (GL_RGBA16F)"`.
    pub name: &'a str,
    /// The pixel format to read with (`GL_RGBA`, `GL_RED_INTEGER`, `GL_DEPTH_COMPONENT`, …).
    pub format: u32,
    /// Channels in that format.
    pub channels: usize,
    /// Their encoding.
    pub channel: Channel,
    /// What the resolve must leave in it.
    pub check: Check,
}

fn pack_scope<T>(gl: &glow::Context, f: impl FnOnce() -> T) -> T {
    unsafe {
        let pack = gl.get_parameter_i32(glow::PACK_ALIGNMENT);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        let out = f();
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, pack);
        out
    }
}

/// `glGetTexImage` of level 0 of a 2D texture, leaving the active unit's binding as it was.
pub fn read_texture(
    gl: &glow::Context,
    texture: glow::Texture,
    width: u32,
    height: u32,
    r: Read,
) -> Plane {
    read_texture_layers(gl, glow::TEXTURE_2D, texture, width, height, 1, 0, r)
}

/// `glGetTexImage` of a whole 2D array texture, keeping layer `layer`.
#[allow(clippy::too_many_arguments)]
pub fn read_texture_layers(
    gl: &glow::Context,
    target: u32,
    texture: glow::Texture,
    width: u32,
    height: u32,
    layers: u32,
    layer: u32,
    r: Read,
) -> Plane {
    let per_layer = (width * height) as usize * r.channels * r.channel.size();
    let mut raw = vec![0u8; per_layer * layers as usize];
    pack_scope(gl, || unsafe {
        let binding = match target {
            glow::TEXTURE_2D_ARRAY => glow::TEXTURE_BINDING_2D_ARRAY,
            _ => glow::TEXTURE_BINDING_2D,
        };
        let previous = gl.get_parameter_i32(binding) as u32;
        gl.bind_texture(target, Some(texture));
        gl.get_tex_image(
            target,
            0,
            r.format,
            r.channel.gl_type(),
            glow::PixelPackData::Slice(Some(&mut raw)),
        );
        gl.bind_texture(
            target,
            std::num::NonZeroU32::new(previous).map(glow::NativeTexture),
        );
    });
    assert_eq!(
        unsafe { gl.get_error() },
        glow::NO_ERROR,
        "reading {}",
        r.name
    );
    let start = per_layer * layer as usize;
    Plane {
        name: r.name.to_string(),
        width,
        height,
        channel: r.channel,
        channels: r.channels,
        raw: raw[start..start + per_layer].to_vec(),
        check: r.check,
    }
}

/// `glReadPixels` of a framebuffer: colour attachment `read_buffer`, or
/// (with `None`) its depth or stencil, as `r.format` says. The read
/// framebuffer binding is left as it was.
pub fn read_framebuffer(
    gl: &glow::Context,
    fbo: glow::Framebuffer,
    read_buffer: Option<u32>,
    width: u32,
    height: u32,
    r: Read,
) -> Plane {
    let mut raw = vec![0u8; (width * height) as usize * r.channels * r.channel.size()];
    pack_scope(gl, || unsafe {
        let previous = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING) as u32;
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
        let previous_buffer = gl.get_parameter_i32(glow::READ_BUFFER) as u32;
        if let Some(b) = read_buffer {
            gl.read_buffer(b);
        }
        gl.read_pixels(
            0,
            0,
            width as i32,
            height as i32,
            r.format,
            r.channel.gl_type(),
            glow::PixelPackData::Slice(Some(&mut raw)),
        );
        gl.read_buffer(previous_buffer);
        gl.bind_framebuffer(
            glow::READ_FRAMEBUFFER,
            std::num::NonZeroU32::new(previous).map(glow::NativeFramebuffer),
        );
    });
    assert_eq!(
        unsafe { gl.get_error() },
        glow::NO_ERROR,
        "reading {}",
        r.name
    );
    Plane {
        name: r.name.to_string(),
        width,
        height,
        channel: r.channel,
        channels: r.channels,
        raw,
        check: r.check,
    }
}

/// An 8-bit RGBA image of a framebuffer's colour attachment 0, top row first.
pub fn read_image(
    gl: &glow::Context,
    fbo: glow::Framebuffer,
    width: u32,
    height: u32,
) -> RgbaImage {
    let plane = read_framebuffer(
        gl,
        fbo,
        Some(glow::COLOR_ATTACHMENT0),
        width,
        height,
        Read {
            name: "output",
            format: glow::RGBA,
            channels: 4,
            channel: Channel::Unorm8,
            check: Check::Smooth,
        },
    );
    RgbaImage::from_fn(width, height, |x, y| {
        let t = plane.texel(x, height - 1 - y);
        image::Rgba([t[0], t[1], t[2], 255])
    })
}

/// The engine's own shader helper: compile and link, panicking with the log.
pub fn program(gl: &glow::Context, label: &str, vertex: &str, fragment: &str) -> glow::Program {
    program_with_locations(gl, label, vertex, fragment, &[], &[])
}

/// [`program`] for GLSL 1.50 shaders without layout qualifiers: attribute
/// and fragment-output locations bound before linking, as GL 3.2 engines do.
pub fn program_with_locations(
    gl: &glow::Context,
    label: &str,
    vertex: &str,
    fragment: &str,
    attributes: &[(u32, &str)],
    outputs: &[(u32, &str)],
) -> glow::Program {
    unsafe {
        let program = gl.create_program().expect("program");
        let mut shaders = Vec::new();
        for (stage, source) in [
            (glow::VERTEX_SHADER, vertex),
            (glow::FRAGMENT_SHADER, fragment),
        ] {
            let shader = gl.create_shader(stage).expect("shader");
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            assert!(
                gl.get_shader_compile_status(shader),
                "{label}: {}",
                gl.get_shader_info_log(shader)
            );
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        for &(location, name) in attributes {
            gl.bind_attrib_location(program, location, name);
        }
        for &(location, name) in outputs {
            gl.bind_frag_data_location(program, location, name);
        }
        gl.link_program(program);
        assert!(
            gl.get_program_link_status(program),
            "{label}: {}",
            gl.get_program_info_log(program)
        );
        for s in shaders {
            gl.detach_shader(program, s);
            gl.delete_shader(s);
        }
        program
    }
}
