//! 2D, 2D-multisample and 2D-array textures.

use super::counters::{self, Kind};
use super::{Format, check_error, label_object};
use crate::{Error, Result};
use glow::HasContext;

fn validate_size(gl: &glow::Context, what: &str, width: u32, height: u32) -> Result<()> {
    let max = unsafe { gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE) }.max(1) as u32;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(Error::invalid(format!(
            "{what}: size {width}x{height} is outside what the driver offers (1x1 to {max}x{max})"
        )));
    }
    Ok(())
}

fn new_texture(gl: &glow::Context, what: &str) -> Result<glow::Texture> {
    let raw = unsafe { gl.create_texture() }.map_err(|reason| Error::Create {
        what: what.to_string(),
        reason,
    })?;
    counters::created(Kind::Texture);
    Ok(raw)
}

fn delete_texture(gl: &glow::Context, raw: glow::Texture) {
    unsafe { gl.delete_texture(raw) };
    counters::destroyed(Kind::Texture);
}

/// The host state a texture allocation touches, put back afterwards: the
/// binding of the target on the active unit, the unpack alignment and row
/// length, and the pixel-unpack buffer (with one bound, the upload would
/// read the host's buffer instead of `data`).
struct AllocationState {
    target: u32,
    binding: i32,
    alignment: i32,
    row_length: i32,
    unpack_buffer: i32,
}

impl AllocationState {
    fn capture(gl: &glow::Context, target: u32) -> Self {
        let binding = match target {
            glow::TEXTURE_2D_ARRAY => glow::TEXTURE_BINDING_2D_ARRAY,
            glow::TEXTURE_2D_MULTISAMPLE => glow::TEXTURE_BINDING_2D_MULTISAMPLE,
            _ => glow::TEXTURE_BINDING_2D,
        };
        unsafe {
            let state = AllocationState {
                target,
                binding: gl.get_parameter_i32(binding),
                alignment: gl.get_parameter_i32(glow::UNPACK_ALIGNMENT),
                row_length: gl.get_parameter_i32(glow::UNPACK_ROW_LENGTH),
                unpack_buffer: gl.get_parameter_i32(glow::PIXEL_UNPACK_BUFFER_BINDING),
            };
            gl.bind_buffer(glow::PIXEL_UNPACK_BUFFER, None);
            gl.pixel_store_i32(glow::UNPACK_ROW_LENGTH, 0);
            state
        }
    }

    fn restore(self, gl: &glow::Context) {
        unsafe {
            gl.bind_texture(self.target, super::state::live_texture(gl, self.binding));
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, self.alignment);
            gl.pixel_store_i32(glow::UNPACK_ROW_LENGTH, self.row_length);
            gl.bind_buffer(
                glow::PIXEL_UNPACK_BUFFER,
                std::num::NonZeroU32::new(self.unpack_buffer as u32).map(glow::NativeBuffer),
            );
        }
    }
}

/// Create a `TEXTURE_2D` (or, with `layers`, a `TEXTURE_2D_ARRAY`) with
/// nearest filtering and clamped edges, upload `data`, check for errors and
/// label it. On failure nothing is left allocated.
fn allocate(
    gl: &glow::Context,
    label: &str,
    format: Format,
    width: u32,
    height: u32,
    layers: Option<u32>,
    data: Option<&[u8]>,
) -> Result<glow::Texture> {
    validate_size(gl, label, width, height)?;
    let raw = new_texture(gl, label)?;
    let target = if layers.is_some() {
        glow::TEXTURE_2D_ARRAY
    } else {
        glow::TEXTURE_2D
    };
    let host = AllocationState::capture(gl, target);
    unsafe {
        gl.bind_texture(target, Some(raw));
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
        let (internal, pf, pt) = (
            format.internal_format() as i32,
            format.pixel_format(),
            format.pixel_type(),
        );
        match layers {
            Some(n) => gl.tex_image_3d(
                target,
                0,
                internal,
                width as i32,
                height as i32,
                n as i32,
                0,
                pf,
                pt,
                glow::PixelUnpackData::Slice(data),
            ),
            None => gl.tex_image_2d(
                target,
                0,
                internal,
                width as i32,
                height as i32,
                0,
                pf,
                pt,
                glow::PixelUnpackData::Slice(data),
            ),
        }
        gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
        gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
        gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE as i32);
        gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE as i32);
    }
    host.restore(gl);
    let stage = format!("allocating texture `{label}` ({format}, {width}x{height})");
    if let Err(e) = check_error(gl, &stage) {
        delete_texture(gl, raw);
        return Err(e);
    }
    label_object(gl, glow::TEXTURE, raw.0.get(), label);
    Ok(raw)
}

/// A single-sample 2D texture.
#[derive(Debug)]
pub struct Texture2d {
    /// The GL name.
    pub(crate) raw: glow::Texture,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Internal format.
    pub format: Format,
}

impl Texture2d {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Texture2d::destroy`] frees it.
    pub fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Allocate storage (nearest filtering, clamped) and label it.
    pub fn new(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        Self::with_data(gl, label, format, width, height, None)
    }

    /// Allocate and upload `data` laid out as `format`'s pixel format and type.
    pub fn with_data(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
        data: Option<&[u8]>,
    ) -> Result<Self> {
        let raw = allocate(gl, label, format, width, height, None, data)?;
        Ok(Texture2d {
            raw,
            width,
            height,
            format,
        })
    }

    /// Set the minification and magnification filters.
    pub fn set_filter(&self, gl: &glow::Context, filter: u32) {
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, Some(self.raw));
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MIN_FILTER, filter as i32);
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MAG_FILTER, filter as i32);
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
    }

    /// Free the texture.
    pub fn destroy(self, gl: &glow::Context) {
        delete_texture(gl, self.raw);
    }
}

/// A `GL_TEXTURE_2D_MULTISAMPLE` texture (never a renderbuffer: the resolve must read it).
#[derive(Debug)]
pub struct Texture2dMultisample {
    /// The GL name.
    pub(crate) raw: glow::Texture,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Internal format.
    pub format: Format,
    /// The sample count the driver really allocated (read back with `GL_TEXTURE_SAMPLES`).
    pub samples: u32,
    /// The sample count that was asked for.
    pub requested_samples: u32,
}

impl Texture2dMultisample {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Texture2dMultisample::destroy`] frees it.
    pub fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Allocate with fixed sample locations, then read the real sample count back:
    /// drivers round requests (llvmpipe turns 1–3 into 4).
    pub fn new(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
        samples: u32,
    ) -> Result<Self> {
        validate_size(gl, label, width, height)?;
        if samples == 0 {
            return Err(Error::invalid(format!(
                "{label}: a sample count of 0 is not a count"
            )));
        }
        let raw = new_texture(gl, label)?;
        let host = AllocationState::capture(gl, glow::TEXTURE_2D_MULTISAMPLE);
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(raw));
            gl.tex_image_2d_multisample(
                glow::TEXTURE_2D_MULTISAMPLE,
                samples as i32,
                format.internal_format() as i32,
                width as i32,
                height as i32,
                true,
            );
        }
        let allocated = check_error(
            gl,
            &format!("allocating {samples}x multisample texture `{label}`"),
        );
        let real = unsafe {
            gl.get_tex_level_parameter_i32(glow::TEXTURE_2D_MULTISAMPLE, 0, glow::TEXTURE_SAMPLES)
        };
        host.restore(gl);
        if let Err(e) = allocated {
            delete_texture(gl, raw);
            return Err(match e {
                Error::Gl { code, .. } if code != glow::OUT_OF_MEMORY => {
                    Error::UnsupportedSampleCount {
                        requested: samples,
                        format: format.name().to_string(),
                        supported: super::samples::sample_counts_for(gl, format),
                    }
                }
                other => other,
            });
        }
        if real <= 0 {
            delete_texture(gl, raw);
            return Err(Error::UnsupportedSampleCount {
                requested: samples,
                format: format.name().to_string(),
                supported: super::samples::sample_counts_for(gl, format),
            });
        }
        label_object(gl, glow::TEXTURE, raw.0.get(), label);
        Ok(Texture2dMultisample {
            raw,
            width,
            height,
            format,
            samples: real as u32,
            requested_samples: samples,
        })
    }

    /// Bytes of storage: width × height × samples × bytes per sample.
    pub fn bytes(&self) -> u64 {
        self.width as u64
            * self.height as u64
            * self.samples as u64
            * self.format.bytes_per_texel() as u64
    }

    /// Free the texture.
    pub fn destroy(self, gl: &glow::Context) {
        delete_texture(gl, self.raw);
    }
}

/// A 2D array texture; the resolve's test harness stores one sample per layer.
#[derive(Debug)]
pub struct Texture2dArray {
    /// The GL name.
    pub(crate) raw: glow::Texture,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Number of layers.
    pub layers: u32,
    /// Internal format.
    pub format: Format,
}

impl Texture2dArray {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Texture2dArray::destroy`] frees it.
    pub fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Allocate and optionally upload all layers at once (`data` is layer-major).
    pub fn new(
        gl: &glow::Context,
        label: &str,
        format: Format,
        width: u32,
        height: u32,
        layers: u32,
        data: Option<&[u8]>,
    ) -> Result<Self> {
        let raw = allocate(gl, label, format, width, height, Some(layers), data)?;
        Ok(Texture2dArray {
            raw,
            width,
            height,
            layers,
            format,
        })
    }

    /// Free the texture.
    pub fn destroy(self, gl: &glow::Context) {
        delete_texture(gl, self.raw);
    }
}

/// A borrowed view of any texture, for attaching and binding.
#[derive(Clone, Copy, Debug)]
pub struct TextureRef {
    /// The GL name.
    pub raw: glow::Texture,
    /// `TEXTURE_2D`, `TEXTURE_2D_MULTISAMPLE` or `TEXTURE_2D_ARRAY`.
    pub target: u32,
    /// Internal format.
    pub format: Format,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Samples (1 for single-sample textures).
    pub samples: u32,
}

impl From<&Texture2d> for TextureRef {
    fn from(t: &Texture2d) -> Self {
        TextureRef {
            raw: t.raw,
            target: glow::TEXTURE_2D,
            format: t.format,
            width: t.width,
            height: t.height,
            samples: 1,
        }
    }
}

impl From<&Texture2dMultisample> for TextureRef {
    fn from(t: &Texture2dMultisample) -> Self {
        TextureRef {
            raw: t.raw,
            target: glow::TEXTURE_2D_MULTISAMPLE,
            format: t.format,
            width: t.width,
            height: t.height,
            samples: t.samples,
        }
    }
}

impl From<&Texture2dArray> for TextureRef {
    fn from(t: &Texture2dArray) -> Self {
        TextureRef {
            raw: t.raw,
            target: glow::TEXTURE_2D_ARRAY,
            format: t.format,
            width: t.width,
            height: t.height,
            samples: 1,
        }
    }
}

impl TextureRef {
    /// The GL handle (the same as the `raw` field).
    pub fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Bind to texture unit `unit`.
    pub fn bind(&self, gl: &glow::Context, unit: u32) {
        unsafe {
            gl.active_texture(glow::TEXTURE0 + unit);
            gl.bind_texture(self.target, Some(self.raw));
        }
    }
}
