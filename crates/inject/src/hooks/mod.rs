//! The ways in: `dlsym` and the GL loaders' get-proc-address functions,
//! which hand the program this library's wrappers for the few GL
//! functions it watches, and the real entry points for everything else.
//!
//! GLFW (and SDL, and glad through either) `dlopen` libGL or libEGL and
//! look up `glXGetProcAddressARB` or `eglGetProcAddress` with `dlsym` on
//! that handle, so a preloaded definition of those names is never
//! reached; a preloaded `dlsym` is. The real `dlsym` comes from
//! `dlvsym(RTLD_NEXT, "dlsym", <glibc version>)`, which does not go
//! through this one, so nothing here recurses.
//!
//! Each wrapper fetches the real entry point from its [`Slot`] (filled
//! when the program asked for the function, so a wrapper is only ever
//! handed out for a function the driver has) and calls the handler of
//! the same name in [`crate::state::handlers`].
//!
//! The parts, one-way: [`crate::real`] (below this module and the state)
//! finds the real entry points and holds the watched functions' slots,
//! [`wrappers`] stands in for them; this file hands out the wrappers.

mod wrappers;

use crate::real::{
    EGL_GET_CURRENT_CONTEXT, EGL_GET_PROC_ADDRESS, GLX_GET_CURRENT_CONTEXT, GLX_GET_PROC_ADDRESS,
    GetProcAddress, Slot, real_dlsym,
};
use std::ffi::{CStr, c_char, c_void};
use wrappers::wrapper_for;

/// The preloaded `dlsym`: the real lookup, then this library's function in
/// place of a get-proc-address or a watched GL function.
///
/// # Safety
///
/// `dlsym`'s contract. One difference a program may see: a lookup with
/// `RTLD_NEXT` is made from this library, so it starts after it rather
/// than after the caller.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dlsym(handle: *mut c_void, name: *const c_char) -> *mut c_void {
    let Some(real) = real_dlsym() else {
        return std::ptr::null_mut();
    };
    // SAFETY: forwarded as given.
    let found = unsafe { real(handle, name) };
    if found.is_null() || name.is_null() {
        return found;
    }
    // SAFETY: a non-null name `dlsym` was given is a C string.
    let bytes = unsafe { CStr::from_ptr(name) }.to_bytes();
    match bytes {
        b"glXGetProcAddress" | b"glXGetProcAddressARB" => {
            GLX_GET_PROC_ADDRESS.set(found);
            crate::state::handlers::watch_exit();
            // SAFETY: the same handle, a C string literal.
            GLX_GET_CURRENT_CONTEXT.set(unsafe { real(handle, c"glXGetCurrentContext".as_ptr()) });
            glx_get_proc_address as *mut c_void
        }
        b"eglGetProcAddress" => {
            EGL_GET_PROC_ADDRESS.set(found);
            crate::state::handlers::watch_exit();
            // SAFETY: as above.
            EGL_GET_CURRENT_CONTEXT.set(unsafe { real(handle, c"eglGetCurrentContext".as_ptr()) });
            egl_get_proc_address as *mut c_void
        }
        _ => match wrapper_for(bytes) {
            Some((slot, wrapper)) => {
                slot.set(found);
                wrapper as *mut c_void
            }
            None => found,
        },
    }
}

/// What a get-proc-address returns to the program: the wrapper of a
/// watched function (its real address kept), else the real address.
fn hooked_lookup(real: &Slot, name: *const c_char) -> *mut c_void {
    let Some(real) = real.get() else {
        return std::ptr::null_mut();
    };
    // SAFETY: the address dlsym gave for a get-proc-address.
    let real = unsafe { std::mem::transmute::<usize, GetProcAddress>(real) };
    // SAFETY: forwarded as given.
    let found = unsafe { real(name) };
    if found.is_null() || name.is_null() {
        return found;
    }
    // SAFETY: a non-null name given to a get-proc-address is a C string.
    match wrapper_for(unsafe { CStr::from_ptr(name) }.to_bytes()) {
        Some((slot, wrapper)) => {
            slot.set(found);
            wrapper as *mut c_void
        }
        None => found,
    }
}

unsafe extern "C" fn glx_get_proc_address(name: *const c_char) -> *mut c_void {
    hooked_lookup(&GLX_GET_PROC_ADDRESS, name)
}

unsafe extern "C" fn egl_get_proc_address(name: *const c_char) -> *mut c_void {
    hooked_lookup(&EGL_GET_PROC_ADDRESS, name)
}
