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

use std::ffi::{CStr, c_char, c_ulong, c_void};
use std::sync::atomic::{AtomicUsize, Ordering};

/// One function address, filled once it is known (0: not yet).
pub(crate) struct Slot(AtomicUsize);

impl Slot {
    /// An empty slot.
    pub(crate) const fn new() -> Self {
        Slot(AtomicUsize::new(0))
    }

    /// The address, if known.
    pub(crate) fn get(&self) -> Option<usize> {
        match self.0.load(Ordering::Acquire) {
            0 => None,
            p => Some(p),
        }
    }

    fn set(&self, address: *mut c_void) {
        if !address.is_null() {
            self.0.store(address as usize, Ordering::Release);
        }
    }
}

/// The windowing API a context belongs to, and so the loader its entry
/// points come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Api {
    /// `glXGetProcAddress(ARB)`.
    Glx,
    /// `eglGetProcAddress`.
    Egl,
}

type Dlsym = unsafe extern "C" fn(*mut c_void, *const c_char) -> *mut c_void;
type GetProcAddress = unsafe extern "C" fn(*const c_char) -> *mut c_void;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;

unsafe extern "C" {
    fn dlvsym(handle: *mut c_void, symbol: *const c_char, version: *const c_char) -> *mut c_void;
}

static REAL_DLSYM: Slot = Slot::new();
static GLX_GET_PROC_ADDRESS: Slot = Slot::new();
static EGL_GET_PROC_ADDRESS: Slot = Slot::new();
static GLX_GET_CURRENT_CONTEXT: Slot = Slot::new();
static EGL_GET_CURRENT_CONTEXT: Slot = Slot::new();

/// glibc's own `dlsym`: the versions it has carried it under (2.34 moved
/// it into libc; 2.2.5 and 2.17 are the x86-64 and AArch64 baselines).
fn real_dlsym() -> Option<Dlsym> {
    if REAL_DLSYM.get().is_none() {
        for version in [c"GLIBC_2.34", c"GLIBC_2.2.5", c"GLIBC_2.17"] {
            // SAFETY: plain C strings; dlvsym is not this library's dlsym.
            let found = unsafe { dlvsym(libc::RTLD_NEXT, c"dlsym".as_ptr(), version.as_ptr()) };
            if !found.is_null() {
                REAL_DLSYM.set(found);
                break;
            }
        }
    }
    // SAFETY: the address glibc gave for `dlsym`, of this type.
    REAL_DLSYM
        .get()
        .map(|p| unsafe { std::mem::transmute::<usize, Dlsym>(p) })
}

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
            // SAFETY: the same handle, a C string literal.
            GLX_GET_CURRENT_CONTEXT.set(unsafe { real(handle, c"glXGetCurrentContext".as_ptr()) });
            glx_get_proc_address as *mut c_void
        }
        b"eglGetProcAddress" => {
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

/// The definition of `name` (NUL-terminated) after this library's: the
/// one a program linked with libGL would have called.
fn next_definition(name: &str) -> *mut c_void {
    match (real_dlsym(), CStr::from_bytes_with_nul(name.as_bytes())) {
        // SAFETY: a C string; RTLD_NEXT from this library.
        (Some(real), Ok(name)) => unsafe { real(libc::RTLD_NEXT, name.as_ptr()) },
        _ => std::ptr::null_mut(),
    }
}

/// Fill `slot` with the global definition of `name` where the program's
/// loader was not seen (a program linked with libGL looks nothing up).
fn fill_from_global(slot: &Slot, name: &CStr) {
    if slot.get().is_none()
        && let Some(real) = real_dlsym()
    {
        // SAFETY: a C string; the global scope.
        slot.set(unsafe { real(libc::RTLD_DEFAULT, name.as_ptr()) });
    }
}

/// The context current on this thread, and its API; EGL first (GLFW
/// loads GLX beside an EGL context).
pub(crate) fn current_context() -> Option<(Api, usize)> {
    fill_from_global(&EGL_GET_CURRENT_CONTEXT, c"eglGetCurrentContext");
    fill_from_global(&GLX_GET_CURRENT_CONTEXT, c"glXGetCurrentContext");
    for (api, slot) in [
        (Api::Egl, &EGL_GET_CURRENT_CONTEXT),
        (Api::Glx, &GLX_GET_CURRENT_CONTEXT),
    ] {
        if let Some(p) = slot.get() {
            // SAFETY: the address dlsym gave for get-current-context.
            let get = unsafe { std::mem::transmute::<usize, GetCurrentContext>(p) };
            // SAFETY: no arguments; callable on any thread.
            let context = unsafe { get() };
            if !context.is_null() {
                return Some((api, context as usize));
            }
        }
    }
    None
}

/// The real entry point `name` of `api`'s contexts (never a wrapper).
pub(crate) fn load_real(api: Api, name: &CStr) -> *const c_void {
    let slot = match api {
        Api::Glx => {
            fill_from_global(&GLX_GET_PROC_ADDRESS, c"glXGetProcAddressARB");
            &GLX_GET_PROC_ADDRESS
        }
        Api::Egl => {
            fill_from_global(&EGL_GET_PROC_ADDRESS, c"eglGetProcAddress");
            &EGL_GET_PROC_ADDRESS
        }
    };
    match slot.get() {
        // SAFETY: the address dlsym gave for a get-proc-address; a C string.
        Some(p) => unsafe { std::mem::transmute::<usize, GetProcAddress>(p)(name.as_ptr()) },
        None => std::ptr::null(),
    }
}

/// The C API's loader: `user_data` is 0 for GLX, 1 for EGL.
pub(crate) unsafe extern "C" fn library_loader(
    name: *const c_char,
    user_data: *mut c_void,
) -> *const c_void {
    if name.is_null() {
        return std::ptr::null();
    }
    let api = if user_data.is_null() {
        Api::Glx
    } else {
        Api::Egl
    };
    // SAFETY: the C API gives a C string.
    load_real(api, unsafe { CStr::from_ptr(name) })
}

/// Declares the watched GL functions: the real address's slot and type,
/// and the wrapper that calls `crate::state::handlers::<name>` with the
/// real function first.
macro_rules! watched {
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

        /// What the program calls instead: handed out by the get-proc-addresses
        /// and `dlsym`, and exported under the function's own name for a
        /// program linked with libGL or libEGL (the preload comes first).
        #[allow(non_snake_case)]
        mod wrapper {
            use super::*;
            $(
                /// The watched function: the handler around the real one.
                ///
                /// # Safety
                ///
                /// The GL function's own contract.
                #[unsafe(no_mangle)]
                #[allow(clippy::too_many_arguments)]
                pub unsafe extern "system" fn $name($($arg: $ty),*) $(-> $ret)? {
                    // Handed out: the slot was filled first. Called by its
                    // exported name: the next definition (libGL's, libEGL's).
                    if real::$name.get().is_none() {
                        real::$name.set(next_definition(concat!(stringify!($name), "\0")));
                    }
                    let Some(address) = real::$name.get() else {
                        return Default::default();
                    };
                    // SAFETY: the driver's address for this function.
                    let real = unsafe { std::mem::transmute::<usize, real_type::$name>(address) };
                    crate::state::handlers::$name(real, $($arg),*)
                }
            )*
        }

        /// The slot and the wrapper of the watched function `name`.
        fn wrapper_for(name: &[u8]) -> Option<(&'static Slot, usize)> {
            $(
                if name == stringify!($name).as_bytes() {
                    return Some((&real::$name, wrapper::$name as *const () as usize));
                }
            )*
            None
        }
    };
}

watched! {
    glBindFramebuffer(target: u32, framebuffer: u32);
    glDeleteFramebuffers(count: i32, framebuffers: *const u32);
    glFramebufferTexture(target: u32, attachment: u32, texture: u32, level: i32);
    glFramebufferTexture2D(target: u32, attachment: u32, textarget: u32, texture: u32, level: i32);
    glFramebufferRenderbuffer(target: u32, attachment: u32, rbtarget: u32, renderbuffer: u32);
    glNamedFramebufferTexture(framebuffer: u32, attachment: u32, texture: u32, level: i32);
    glNamedFramebufferRenderbuffer(framebuffer: u32, attachment: u32, rbtarget: u32, renderbuffer: u32);
    glBlitNamedFramebuffer(read: u32, draw: u32, sx0: i32, sy0: i32, sx1: i32, sy1: i32, dx0: i32, dy0: i32, dx1: i32, dy1: i32, mask: u32, filter: u32);
    glBindTextureUnit(unit: u32, texture: u32);
    glActiveTexture(unit: u32);
    glBindTexture(target: u32, texture: u32);
    glUseProgram(program: u32);
    glGetUniformLocation(program: u32, name: *const c_char) -> i32;
    glUniformMatrix4fv(location: i32, count: i32, transpose: u8, value: *const f32);
    glGetIntegerv(pname: u32, data: *mut i32);
    glClear(mask: u32);
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
