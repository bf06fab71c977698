//! The real entry points, found past this library: glibc's own `dlsym`,
//! the get-proc-addresses the program's loader asked for, the context
//! current on a thread, and the C API's loader.

use std::ffi::{CStr, c_char, c_void};
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

    pub(crate) fn set(&self, address: *mut c_void) {
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
pub(crate) type GetProcAddress = unsafe extern "C" fn(*const c_char) -> *mut c_void;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;

unsafe extern "C" {
    fn dlvsym(handle: *mut c_void, symbol: *const c_char, version: *const c_char) -> *mut c_void;
}

static REAL_DLSYM: Slot = Slot::new();
pub(crate) static GLX_GET_PROC_ADDRESS: Slot = Slot::new();
pub(crate) static EGL_GET_PROC_ADDRESS: Slot = Slot::new();
pub(crate) static GLX_GET_CURRENT_CONTEXT: Slot = Slot::new();
pub(crate) static EGL_GET_CURRENT_CONTEXT: Slot = Slot::new();

/// glibc's own `dlsym`: the versions it has carried it under (2.34 moved
/// it into libc; 2.2.5 and 2.17 are the x86-64 and AArch64 baselines).
pub(crate) fn real_dlsym() -> Option<Dlsym> {
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

/// The definition of `name` (NUL-terminated) after this library's: the
/// one a program linked with libGL would have called.
pub(crate) fn next_definition(name: impl AsRef<[u8]>) -> *mut c_void {
    match (real_dlsym(), CStr::from_bytes_with_nul(name.as_ref())) {
        // SAFETY: a C string; RTLD_NEXT from this library.
        (Some(real), Ok(name)) => unsafe { real(libc::RTLD_NEXT, name.as_ptr()) },
        _ => std::ptr::null_mut(),
    }
}

/// Fill `slot` with the definition of `name` past this library where the
/// program's loader was not seen (a program linked with libGL looks
/// nothing up). Past it, not the global one: this library defines the
/// get-proc-addresses itself.
fn fill_from_global(slot: &Slot, name: &CStr) {
    if slot.get().is_none() {
        slot.set(next_definition(name.to_bytes_with_nul()));
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
