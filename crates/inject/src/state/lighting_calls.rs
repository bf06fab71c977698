//! What the lighting's recording keeps of the calls between its draws for
//! their replay (`crate::replay`): uniform values, and uniform buffers'
//! bindings and writes, each for the draw it comes before.

use super::context::Context;
use crate::replay::{BufferChange, UniformCall, UniformValue};
use glow::HasContext;
use std::ffi::c_void;

/// `count` elements of `n` components at `value`, copied (none from a
/// null pointer or a count below 1, GL's errors).
///
/// # Safety
///
/// `value` points at `count * n` values, as GL reads them.
pub(super) unsafe fn copied<T: Copy>(value: *const T, count: i32, n: usize) -> Option<Vec<T>> {
    if value.is_null() || count < 1 {
        return None;
    }
    // SAFETY: the caller's.
    Some(unsafe { std::slice::from_raw_parts(value, count as usize * n) }.to_vec())
}

impl Context {
    /// A uniform call, on the program bound now.
    pub(super) fn record_uniform(&mut self, location: i32, value: UniformValue) {
        let program = self.program;
        if let Some(r) = self.recording.as_mut().filter(|_| location >= 0) {
            r.uniforms.push(UniformCall {
                program,
                location,
                value,
            });
        }
    }

    /// A `GL_UNIFORM_BUFFER` binding point bound (`size` 0: the whole
    /// buffer).
    pub(super) fn record_binding(&mut self, index: u32, buffer: u32, offset: isize, size: isize) {
        self.uniform_buffer_bound(index, buffer, offset, size);
        if let Some(r) = self.recording.as_mut() {
            r.buffers.push(BufferChange::Bind {
                index,
                buffer,
                offset: offset as i32,
                size: size as i32,
            });
        }
    }

    /// `size` bytes at `data` written at `offset` into buffer `named`
    /// (`glNamedBufferSubData`), or with `None` into the buffer bound at
    /// `GL_UNIFORM_BUFFER` (`glBufferSubData`): kept for the replay, and
    /// looked at for a camera until a retrofit is made.
    ///
    /// # Safety
    ///
    /// `data` is null or holds `size` bytes.
    pub(super) unsafe fn record_buffer_data(
        &mut self,
        named: Option<u32>,
        offset: isize,
        size: isize,
        data: *const c_void,
    ) {
        let looking = self.retrofit.is_none() || self.learning();
        if (self.recording.is_none() && !looking) || data.is_null() || size <= 0 {
            return;
        }
        let buffer = match named {
            Some(b) => b,
            // SAFETY: a query of the current context.
            None => (unsafe { self.gl().get_parameter_i32(glow::UNIFORM_BUFFER_BINDING) }) as u32,
        };
        // SAFETY: the caller's.
        let bytes = unsafe { std::slice::from_raw_parts(data.cast::<u8>(), size as usize) };
        if looking {
            self.uniform_buffer_written(buffer, offset, bytes);
        }
        if let Some(r) = self.recording.as_mut() {
            r.buffers.push(BufferChange::Data {
                buffer,
                offset: offset as i32,
                bytes: bytes.to_vec(),
            });
        }
    }
}
