//! The ways in: `dlsym` and the GL loaders' get-proc-address functions,
//! which hand the program this library's wrappers for the few GL
//! functions it watches, and the real entry points for everything else.
//!
//! GLFW (and SDL, and glad through either) `dlopen` libGL or libEGL and
//! look up `glXGetProcAddressARB` or `eglGetProcAddress` with `dlsym` on
//! that handle, so a preloaded definition of those names is never
//! reached; a preloaded `dlsym` is. The real `dlsym` comes from
//! `dlvsym(RTLD_NEXT, "dlsym", <glibc version>)`, which does not go
//! through this one, so nothing here recurses. A program linked with
//! libEGL or libGL that calls the get-proc-address by name (a small C
//! engine's own loader) reaches this library's definitions of those
//! names instead, which look the real ones up past it.
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
    GetProcAddress, Slot, next_definition, real_dlsym,
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
    // Any lookup: a program that reaches GL some way the library does not
    // follow still hears why it was left alone, at its exit.
    crate::state::handlers::watch_exit();
    match bytes {
        b"OSMesaGetProcAddress" => {
            crate::state::handlers::saw_other_loader("OSMesaGetProcAddress");
            found
        }
        b"glXGetProcAddress" | b"glXGetProcAddressARB" => {
            // A global lookup finds this library's own definition first.
            let found = past_own(
                found,
                glXGetProcAddressARB as *mut c_void,
                c"glXGetProcAddressARB",
            );
            GLX_GET_PROC_ADDRESS.set(found);
            // SAFETY: the same handle, a C string literal.
            GLX_GET_CURRENT_CONTEXT.set(unsafe { real(handle, c"glXGetCurrentContext".as_ptr()) });
            glx_get_proc_address as *mut c_void
        }
        b"eglGetProcAddress" => {
            let found = past_own(
                found,
                eglGetProcAddress as *mut c_void,
                c"eglGetProcAddress",
            );
            EGL_GET_PROC_ADDRESS.set(found);
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

/// `found`, or where it is this library's `own` definition of `name`, the
/// definition past this library.
fn past_own(found: *mut c_void, own: *mut c_void, name: &CStr) -> *mut c_void {
    if found != own {
        return found;
    }
    next_definition(name.to_bytes_with_nul())
}

/// The real get-proc-address `name` (past this library) and the
/// get-current-context beside it, filled at a linked program's first
/// lookup, and the exit watched as a `dlsym` of them does.
fn fill_linked(loader: &Slot, name: &CStr, current: &Slot, current_name: &CStr) {
    if loader.get().is_none() {
        loader.set(next_definition(name.to_bytes_with_nul()));
        current.set(next_definition(current_name.to_bytes_with_nul()));
        crate::state::handlers::watch_exit();
    }
}

/// `eglGetProcAddress` for a program linked with libEGL.
///
/// # Safety
///
/// `eglGetProcAddress`'s contract.
#[unsafe(no_mangle)]
#[allow(non_snake_case)]
pub unsafe extern "C" fn eglGetProcAddress(name: *const c_char) -> *mut c_void {
    fill_linked(
        &EGL_GET_PROC_ADDRESS,
        c"eglGetProcAddress",
        &EGL_GET_CURRENT_CONTEXT,
        c"eglGetCurrentContext",
    );
    hooked_lookup(&EGL_GET_PROC_ADDRESS, name)
}

/// `glXGetProcAddressARB` for a program linked with libGL.
///
/// # Safety
///
/// `glXGetProcAddressARB`'s contract.
#[unsafe(no_mangle)]
#[allow(non_snake_case)]
pub unsafe extern "C" fn glXGetProcAddressARB(name: *const c_char) -> *mut c_void {
    fill_linked(
        &GLX_GET_PROC_ADDRESS,
        c"glXGetProcAddressARB",
        &GLX_GET_CURRENT_CONTEXT,
        c"glXGetCurrentContext",
    );
    hooked_lookup(&GLX_GET_PROC_ADDRESS, name)
}

/// `glXGetProcAddress`, the same as `glXGetProcAddressARB`.
///
/// # Safety
///
/// `glXGetProcAddress`'s contract.
#[unsafe(no_mangle)]
#[allow(non_snake_case)]
pub unsafe extern "C" fn glXGetProcAddress(name: *const c_char) -> *mut c_void {
    // SAFETY: the same contract.
    unsafe { glXGetProcAddressARB(name) }
}
