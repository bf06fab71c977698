//! `deferred-msaa inject`'s preloaded library: MSAA for a deferred OpenGL
//! program that is not changed, through the same C API a host would call.
//!
//! Loaded with `LD_PRELOAD` (the `deferred-msaa inject` command sets it),
//! it defines `dlsym`, so that the program's GL loader (GLFW, SDL, glad
//! through them) gets this library's `glXGetProcAddress(ARB)` and
//! `eglGetProcAddress`; those hand back wrappers for about twenty GL
//! functions and the real entry points for the rest. From those calls the
//! library finds the G-buffer, binds the retrofit's multisampled framebuffer
//! in its place and resolves into it when the program leaves it
//! (docs/inject.md says how, and the contract). The retrofit itself
//! is `deferred-msaa-capi`'s, given the real entry points.
//!
//! The environment it reads: `DMSAA_INJECT_PROFILE` (a [`profile`] file),
//! `DMSAA_INJECT_CHECK=1` (the GL state and error checks around every call
//! into the library, summed up on stderr at exit), `DMSAA_INJECT_LEARN`
//! (write a first profile there from one observed frame; retrofit nothing).

mod camera;
mod check;
mod hooks;
pub mod profile;
mod real;
mod replay;
mod state;

use std::ffi::{CStr, c_char};

/// Check the profile at `path` as the preloaded library will read it: 0
/// when it is valid; otherwise 1, with a one-line message (NUL-terminated,
/// cut to `capacity`) in `message`. `deferred-msaa inject` calls it before
/// starting the program, so that a bad profile is refused up front.
///
/// # Safety
///
/// `path` is a C string; `message` is writable for `capacity` bytes (or
/// null with `capacity` 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_inject_check_profile(
    path: *const c_char,
    message: *mut c_char,
    capacity: usize,
) -> i32 {
    let result = if path.is_null() {
        Err("no profile path given".to_string())
    } else {
        // SAFETY: the caller's contract.
        let path = unsafe { CStr::from_ptr(path) }
            .to_string_lossy()
            .into_owned();
        profile::Profile::load(std::path::Path::new(&path))
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    match result {
        Ok(()) => 0,
        Err(text) => {
            if !message.is_null() && capacity > 0 {
                let n = text.len().min(capacity - 1);
                // SAFETY: `n + 1 <= capacity` bytes, the caller's buffer.
                unsafe {
                    std::ptr::copy_nonoverlapping(text.as_ptr(), message.cast::<u8>(), n);
                    *message.add(n) = 0;
                }
            }
            1
        }
    }
}
