//! Buffer objects and vertex arrays.

use super::counters::{self, Kind};
use super::{check_error, label_object};
use crate::{Error, Result};
use glow::HasContext;

/// A buffer object.
#[derive(Debug)]
pub struct Buffer {
    /// The GL name.
    pub(crate) raw: glow::Buffer,
    /// The target it was created for, e.g. `ARRAY_BUFFER`.
    pub target: u32,
    /// Size in bytes.
    pub size: usize,
}

impl Buffer {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Buffer::destroy`] frees it.
    pub fn raw(&self) -> glow::Buffer {
        self.raw
    }

    /// Create a buffer of `target` holding `data` (`usage` e.g. `STATIC_DRAW`).
    pub fn with_data(
        gl: &glow::Context,
        label: &str,
        target: u32,
        data: &[u8],
        usage: u32,
    ) -> Result<Self> {
        let raw = unsafe { gl.create_buffer() }.map_err(|reason| Error::Create {
            what: format!("buffer `{label}`"),
            reason,
        })?;
        counters::created(Kind::Buffer);
        let buffer = Buffer {
            raw,
            target,
            size: data.len(),
        };
        let previous = bound_buffer(gl, target);
        unsafe {
            gl.bind_buffer(target, Some(raw));
            gl.buffer_data_u8_slice(target, data, usage);
            gl.bind_buffer(target, previous);
        }
        if let Err(e) = check_error(
            gl,
            &format!("allocating buffer `{label}` ({} bytes)", data.len()),
        ) {
            buffer.destroy(gl);
            return Err(e);
        }
        label_object(gl, glow::BUFFER, raw.0.get(), label);
        Ok(buffer)
    }

    /// Create an uninitialised buffer of `size` bytes.
    pub fn with_size(
        gl: &glow::Context,
        label: &str,
        target: u32,
        size: usize,
        usage: u32,
    ) -> Result<Self> {
        let raw = unsafe { gl.create_buffer() }.map_err(|reason| Error::Create {
            what: format!("buffer `{label}`"),
            reason,
        })?;
        counters::created(Kind::Buffer);
        let buffer = Buffer { raw, target, size };
        let previous = bound_buffer(gl, target);
        unsafe {
            gl.bind_buffer(target, Some(raw));
            gl.buffer_data_size(target, size as i32, usage);
            gl.bind_buffer(target, previous);
        }
        if let Err(e) = check_error(gl, &format!("allocating buffer `{label}` ({size} bytes)")) {
            buffer.destroy(gl);
            return Err(e);
        }
        label_object(gl, glow::BUFFER, raw.0.get(), label);
        Ok(buffer)
    }

    /// Free the buffer.
    pub fn destroy(self, gl: &glow::Context) {
        unsafe { gl.delete_buffer(self.raw) };
        counters::destroyed(Kind::Buffer);
    }
}

/// A vertex array object (core profile draws need one bound, even an empty one).
#[derive(Debug)]
pub struct VertexArray {
    /// The GL name.
    pub(crate) raw: glow::VertexArray,
}

impl VertexArray {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`VertexArray::destroy`] frees it.
    pub fn raw(&self) -> glow::VertexArray {
        self.raw
    }

    /// Create an empty vertex array.
    pub fn new(gl: &glow::Context, label: &str) -> Result<Self> {
        let raw = unsafe { gl.create_vertex_array() }.map_err(|reason| Error::Create {
            what: format!("vertex array `{label}`"),
            reason,
        })?;
        counters::created(Kind::VertexArray);
        // The host's vertex array stays bound.
        let previous = unsafe { gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING) };
        unsafe { gl.bind_vertex_array(Some(raw)) };
        label_object(gl, glow::VERTEX_ARRAY, raw.0.get(), label);
        unsafe {
            gl.bind_vertex_array(
                std::num::NonZeroU32::new(previous as u32).map(glow::NativeVertexArray),
            )
        };
        Ok(VertexArray { raw })
    }

    /// Bind it.
    pub fn bind(&self, gl: &glow::Context) {
        unsafe { gl.bind_vertex_array(Some(self.raw)) };
    }

    /// Free the vertex array (not the buffers it refers to).
    pub fn destroy(self, gl: &glow::Context) {
        unsafe { gl.delete_vertex_array(self.raw) };
        counters::destroyed(Kind::VertexArray);
    }
}

/// The buffer bound to `target` now, so that creating one leaves the host's
/// binding (and, for `GL_ELEMENT_ARRAY_BUFFER`, its vertex array's) as it was.
fn bound_buffer(gl: &glow::Context, target: u32) -> Option<glow::Buffer> {
    let query = match target {
        glow::ARRAY_BUFFER => glow::ARRAY_BUFFER_BINDING,
        glow::ELEMENT_ARRAY_BUFFER => glow::ELEMENT_ARRAY_BUFFER_BINDING,
        glow::UNIFORM_BUFFER => glow::UNIFORM_BUFFER_BINDING,
        glow::SHADER_STORAGE_BUFFER => glow::SHADER_STORAGE_BUFFER_BINDING,
        glow::ATOMIC_COUNTER_BUFFER => glow::ATOMIC_COUNTER_BUFFER_BINDING,
        glow::PIXEL_PACK_BUFFER => glow::PIXEL_PACK_BUFFER_BINDING,
        glow::PIXEL_UNPACK_BUFFER => glow::PIXEL_UNPACK_BUFFER_BINDING,
        glow::COPY_READ_BUFFER => glow::COPY_READ_BUFFER_BINDING,
        glow::COPY_WRITE_BUFFER => glow::COPY_WRITE_BUFFER_BINDING,
        _ => return None,
    };
    let raw = unsafe { gl.get_parameter_i32(query) };
    std::num::NonZeroU32::new(raw as u32).map(glow::NativeBuffer)
}
