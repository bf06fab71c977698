//! The watched GL functions: their one list, and the types and slots of
//! their real entry points, which both the wrappers and the handlers use.

use super::loader::Slot;

/// The watched GL functions with their arguments, handed to the macro
/// `$then`: the real entry points and the wrappers are made from one list.
macro_rules! watched_functions {
    ($then:ident) => {
        $then! {
            glBindFramebuffer(target: u32, framebuffer: u32);
            glDeleteFramebuffers(count: i32, framebuffers: *const u32);
            glFramebufferTexture(target: u32, attachment: u32, texture: u32, level: i32);
            glFramebufferTexture2D(target: u32, attachment: u32, textarget: u32, texture: u32, level: i32);
            glFramebufferTextureLayer(target: u32, attachment: u32, texture: u32, level: i32, layer: i32);
            glFramebufferRenderbuffer(target: u32, attachment: u32, rbtarget: u32, renderbuffer: u32);
            glNamedFramebufferTexture(framebuffer: u32, attachment: u32, texture: u32, level: i32);
            glNamedFramebufferRenderbuffer(framebuffer: u32, attachment: u32, rbtarget: u32, renderbuffer: u32);
            glBlitFramebuffer(sx0: i32, sy0: i32, sx1: i32, sy1: i32, dx0: i32, dy0: i32, dx1: i32, dy1: i32, mask: u32, filter: u32);
            glBlitNamedFramebuffer(read: u32, draw: u32, sx0: i32, sy0: i32, sx1: i32, sy1: i32, dx0: i32, dy0: i32, dx1: i32, dy1: i32, mask: u32, filter: u32);
            glBindTextureUnit(unit: u32, texture: u32);
            glActiveTexture(unit: u32);
            glBindTexture(target: u32, texture: u32);
            glUseProgram(program: u32);
            glGetUniformLocation(program: u32, name: *const c_char) -> i32;
            glUniformMatrix4fv(location: i32, count: i32, transpose: u8, value: *const f32);
            glBindBufferBase(target: u32, index: u32, buffer: u32);
            glBindBufferRange(target: u32, index: u32, buffer: u32, offset: isize, size: isize);
            glBufferSubData(target: u32, offset: isize, size: isize, data: *const c_void);
            glBufferData(target: u32, size: isize, data: *const c_void, usage: u32);
            glNamedBufferSubData(buffer: u32, offset: isize, size: isize, data: *const c_void);
            glUniform1f(location: i32, v0: f32);
            glUniform2f(location: i32, v0: f32, v1: f32);
            glUniform3f(location: i32, v0: f32, v1: f32, v2: f32);
            glUniform4f(location: i32, v0: f32, v1: f32, v2: f32, v3: f32);
            glUniform1i(location: i32, v0: i32);
            glUniform2i(location: i32, v0: i32, v1: i32);
            glUniform3i(location: i32, v0: i32, v1: i32, v2: i32);
            glUniform4i(location: i32, v0: i32, v1: i32, v2: i32, v3: i32);
            glUniform1fv(location: i32, count: i32, value: *const f32);
            glUniform2fv(location: i32, count: i32, value: *const f32);
            glUniform3fv(location: i32, count: i32, value: *const f32);
            glUniform4fv(location: i32, count: i32, value: *const f32);
            glUniform1iv(location: i32, count: i32, value: *const i32);
            glUniform2iv(location: i32, count: i32, value: *const i32);
            glUniform3iv(location: i32, count: i32, value: *const i32);
            glUniform4iv(location: i32, count: i32, value: *const i32);
            glGetIntegerv(pname: u32, data: *mut i32);
            glClear(mask: u32);
            glClearBufferfv(buffer: u32, drawbuffer: i32, value: *const f32);
            glClearBufferiv(buffer: u32, drawbuffer: i32, value: *const i32);
            glClearBufferuiv(buffer: u32, drawbuffer: i32, value: *const u32);
            glClearBufferfi(buffer: u32, drawbuffer: i32, depth: f32, stencil: i32);
            glClearNamedFramebufferfv(framebuffer: u32, buffer: u32, drawbuffer: i32, value: *const f32);
            glClearNamedFramebufferiv(framebuffer: u32, buffer: u32, drawbuffer: i32, value: *const i32);
            glClearNamedFramebufferuiv(framebuffer: u32, buffer: u32, drawbuffer: i32, value: *const u32);
            glClearNamedFramebufferfi(framebuffer: u32, buffer: u32, drawbuffer: i32, depth: f32, stencil: i32);
            glDrawArrays(mode: u32, first: i32, count: i32);
            glDrawArraysInstanced(mode: u32, first: i32, count: i32, instances: i32);
            glDrawElements(mode: u32, count: i32, kind: u32, indices: *const c_void);
            glDrawElementsInstanced(mode: u32, count: i32, kind: u32, indices: *const c_void, instances: i32);
            glDrawElementsBaseVertex(mode: u32, count: i32, kind: u32, indices: *const c_void, base: i32);
            glDrawRangeElements(mode: u32, start: u32, end: u32, count: i32, kind: u32, indices: *const c_void);
            glXSwapBuffers(display: *mut c_void, drawable: c_ulong);
            glXDestroyContext(display: *mut c_void, context: *mut c_void);
            eglDestroyContext(display: *mut c_void, context: *mut c_void) -> u32;
            eglSwapBuffers(display: *mut c_void, surface: *mut c_void) -> u32;
        }
    };
}
pub(crate) use watched_functions;

/// Declares the watched functions' real types and slots.
macro_rules! declare_real_entry_points {
    ($( $name:ident ( $($arg:ident : $ty:ty),* ) $(-> $ret:ty)? ; )*) => {
        /// The real entry points' types.
        #[allow(non_camel_case_types)]
        pub(crate) mod real_type {
            use std::ffi::{c_char, c_ulong, c_void};
            $( pub(crate) type $name = unsafe extern "system" fn($($ty),*) $(-> $ret)?; )*
        }

        /// The real entry points, as the program asked for them.
        #[allow(non_upper_case_globals)]
        pub(crate) mod real {
            use super::Slot;
            $( pub(crate) static $name: Slot = Slot::new(); )*
        }
    };
}

watched_functions!(declare_real_entry_points);
