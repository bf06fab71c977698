//! The real entry points, below both the hooks and the state: glibc's own
//! `dlsym`, the get-proc-addresses the program's loader asked for, the
//! context current on a thread, the C API's loader ([`loader`]), and the
//! watched GL functions' one list with their real types and slots
//! ([`watched`]). The hooks fill the slots and hand out wrappers; the state
//! calls the real functions for the library's own work. Nothing here
//! names either.

mod loader;
mod watched;

pub(crate) use loader::{
    Api, EGL_GET_CURRENT_CONTEXT, EGL_GET_PROC_ADDRESS, GLX_GET_CURRENT_CONTEXT,
    GLX_GET_PROC_ADDRESS, GetProcAddress, Slot, current_context, library_loader, load_real,
    next_definition, real_dlsym,
};
pub(crate) use watched::{real, real_type, watched_functions};
