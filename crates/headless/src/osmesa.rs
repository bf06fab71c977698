//! The OSMesa backend: Mesa's off-screen renderer, `libOSMesa.so.8`.
//!
//! OSMesa insists on a colour buffer in client memory to make a context
//! current; each context owns a small one (16×16 RGBA8) for its whole life.
//! Nothing is rendered into it: all rendering goes to framebuffer objects.

use std::cell::UnsafeCell;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::sync::{Mutex, OnceLock};

use crate::loader::{open, symbol};
use crate::{Error, Result};

type OsMesaCtx = *mut c_void;

// From Mesa's include/GL/osmesa.h.
const OSMESA_RGBA: c_int = 0x1908; // GL_RGBA
const OSMESA_FORMAT: c_int = 0x22;
const OSMESA_DEPTH_BITS: c_int = 0x30;
const OSMESA_STENCIL_BITS: c_int = 0x31;
const OSMESA_ACCUM_BITS: c_int = 0x32;
const OSMESA_PROFILE: c_int = 0x33;
const OSMESA_CORE_PROFILE: c_int = 0x34;
const OSMESA_COMPAT_PROFILE: c_int = 0x35;
const OSMESA_CONTEXT_MAJOR_VERSION: c_int = 0x36;
const OSMESA_CONTEXT_MINOR_VERSION: c_int = 0x37;
const GL_UNSIGNED_BYTE: u32 = 0x1401;

/// Side of the owned colour buffer, in pixels.
const BUFFER_SIDE: c_int = 16;
const BUFFER_PIXELS: usize = (BUFFER_SIDE * BUFFER_SIDE) as usize;

const BACKEND: &str = "osmesa";
const LIBRARY_NAME: &str = "libOSMesa.so.8";
const INSTALL_HINT: &str = "install the Debian package libosmesa6";

type FnCreateContextAttribs = unsafe extern "C" fn(*const c_int, OsMesaCtx) -> OsMesaCtx;
type FnDestroyContext = unsafe extern "C" fn(OsMesaCtx);
type FnMakeCurrent = unsafe extern "C" fn(OsMesaCtx, *mut c_void, u32, c_int, c_int) -> u8;
type FnGetCurrentContext = unsafe extern "C" fn() -> OsMesaCtx;
type FnGetColorBuffer =
    unsafe extern "C" fn(OsMesaCtx, *mut c_int, *mut c_int, *mut c_int, *mut *mut c_void) -> u8;
type FnGetProcAddress = unsafe extern "C" fn(*const c_char) -> *const c_void;

/// The loaded library; lives in a static for the rest of the process.
pub(crate) struct OsMesaLib {
    create_context_attribs: FnCreateContextAttribs,
    destroy_context: FnDestroyContext,
    make_current: FnMakeCurrent,
    get_current_context: FnGetCurrentContext,
    get_color_buffer: FnGetColorBuffer,
    get_proc_address: FnGetProcAddress,
    _lib: libloading::Library,
}

static LIBRARY: OnceLock<std::result::Result<OsMesaLib, String>> = OnceLock::new();

/// Serialises context creation and destruction: cheap, and it keeps OSMesa's
/// lazily built global state out of any race.
static LIFECYCLE: Mutex<()> = Mutex::new(());

/// Loads `libOSMesa.so.8` once per process.
pub(crate) fn library() -> Result<&'static OsMesaLib> {
    LIBRARY
        .get_or_init(|| OsMesaLib::load(LIBRARY_NAME))
        .as_ref()
        .map_err(|reason| Error::BackendUnavailable {
            backend: BACKEND,
            reason: reason.clone(),
        })
}

impl OsMesaLib {
    fn load(name: &str) -> std::result::Result<OsMesaLib, String> {
        let lib = open(&[name], INSTALL_HINT)?;
        // SAFETY (every `symbol` call): the types are osmesa.h's prototypes
        // (GLenum = u32, GLsizei = int, GLboolean = u8).
        let loaded = unsafe {
            (|| {
                Ok::<_, String>(OsMesaLib {
                    create_context_attribs: symbol(&lib, "OSMesaCreateContextAttribs")?,
                    destroy_context: symbol(&lib, "OSMesaDestroyContext")?,
                    make_current: symbol(&lib, "OSMesaMakeCurrent")?,
                    get_current_context: symbol(&lib, "OSMesaGetCurrentContext")?,
                    get_color_buffer: symbol(&lib, "OSMesaGetColorBuffer")?,
                    get_proc_address: symbol(&lib, "OSMesaGetProcAddress")?,
                    _lib: lib,
                })
            })()
        };
        loaded.map_err(|missing| {
            format!("{name} lacks an entry point: {missing} (Mesa 11.2 or newer is needed); {INSTALL_HINT}")
        })
    }
}

/// An OSMesa context and the colour buffer it is made current with.
pub(crate) struct OsMesaContext {
    lib: &'static OsMesaLib,
    context: OsMesaCtx,
    // Written by Mesa through a raw pointer, never read here.
    buffer: Box<UnsafeCell<[u32; BUFFER_PIXELS]>>,
}

impl OsMesaContext {
    /// Creates a context as `req` asks and makes it current.
    pub(crate) fn create(req: &crate::request::ContextRequest) -> Result<OsMesaContext> {
        let lib = library()?;
        let attribs = [
            OSMESA_FORMAT,
            OSMESA_RGBA,
            OSMESA_DEPTH_BITS,
            0,
            OSMESA_STENCIL_BITS,
            0,
            OSMESA_ACCUM_BITS,
            0,
            OSMESA_PROFILE,
            OSMESA_CORE_PROFILE,
            OSMESA_CONTEXT_MAJOR_VERSION,
            c_int::from(req.major),
            OSMESA_CONTEXT_MINOR_VERSION,
            c_int::from(req.minor),
            0,
        ];
        let context = {
            let _guard = LIFECYCLE.lock().unwrap_or_else(|p| p.into_inner());
            // SAFETY: zero-terminated attribute list; no share context.
            unsafe { (lib.create_context_attribs)(attribs.as_ptr(), std::ptr::null_mut()) }
        };
        if context.is_null() {
            if let Some(too_low) = crate::request::too_low_from_probe(probe_version(lib)) {
                return Err(too_low);
            }
            return Err(Error::Create {
                what: format!("OSMesa OpenGL {}.{} core context", req.major, req.minor),
                reason: "OSMesaCreateContextAttribs returned no context (the driver refused the version or profile)".into(),
            });
        }
        let ctx = OsMesaContext {
            lib,
            context,
            buffer: Box::new(UnsafeCell::new([0; BUFFER_PIXELS])),
        };
        ctx.make_current()?;
        Ok(ctx)
    }

    pub(crate) fn make_current(&self) -> Result<()> {
        // SAFETY: our context and our buffer, which outlives the context.
        let ok = unsafe {
            (self.lib.make_current)(
                self.context,
                self.buffer.get().cast(),
                GL_UNSIGNED_BYTE,
                BUFFER_SIDE,
                BUFFER_SIDE,
            )
        };
        if ok != 0 {
            Ok(())
        } else {
            Err(Error::Create {
                what: "a current OSMesa context (OSMesaMakeCurrent)".into(),
                reason: "OSMesaMakeCurrent failed".into(),
            })
        }
    }

    fn is_current(&self) -> bool {
        // SAFETY: plain query.
        unsafe { (self.lib.get_current_context)() == self.context }
    }

    pub(crate) fn release_current(&self) -> Result<()> {
        if !self.is_current() {
            return Ok(());
        }
        // SAFETY: a null context with a null buffer releases the current one.
        let ok =
            unsafe { (self.lib.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0) };
        if ok != 0 {
            Ok(())
        } else {
            Err(Error::Create {
                what: "a released OSMesa context (OSMesaMakeCurrent with no context)".into(),
                reason: "OSMesaMakeCurrent failed".into(),
            })
        }
    }

    pub(crate) fn get_proc_address(&self, name: &CStr) -> *const c_void {
        // SAFETY: NUL-terminated name.
        unsafe { (self.lib.get_proc_address)(name.as_ptr()) }
    }

    pub(crate) fn with_current(&self, f: impl FnOnce()) -> Option<()> {
        if self.is_current() {
            f();
            return Some(());
        }
        // SAFETY: plain query.
        let previous = unsafe { (self.lib.get_current_context)() };
        self.make_current().ok()?;
        f();
        restore(self.lib, previous);
        Some(())
    }
}

/// Makes `previous` current again (with the colour buffer it had, assumed
/// `GL_UNSIGNED_BYTE` as all of ours are), or releases when it is null.
fn restore(lib: &OsMesaLib, previous: OsMesaCtx) {
    // SAFETY: `previous` was current on this thread a moment ago, so it is
    // alive; OSMesaGetColorBuffer reports the buffer it was bound to.
    let ok = unsafe {
        if previous.is_null() {
            (lib.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0)
        } else {
            let (mut w, mut h, mut format) = (0, 0, 0);
            let mut buffer = std::ptr::null_mut();
            if (lib.get_color_buffer)(previous, &mut w, &mut h, &mut format, &mut buffer) == 0
                || buffer.is_null()
            {
                (lib.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0);
                0
            } else {
                (lib.make_current)(previous, buffer, GL_UNSIGNED_BYTE, w, h)
            }
        }
    };
    if ok == 0 {
        log::warn!("could not restore the previously current OSMesa context");
    }
}

impl Drop for OsMesaContext {
    fn drop(&mut self) {
        if let Err(e) = self.release_current() {
            log::warn!("{e}");
        }
        let _guard = LIFECYCLE.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: our context, released above on this thread.
        unsafe { (self.lib.destroy_context)(self.context) };
        // `buffer` drops after the context that used it.
    }
}

/// Creates a compatibility context with no version asked, reads its
/// `GL_VERSION` and destroys it: used to explain a refused core context.
fn probe_version(lib: &OsMesaLib) -> Option<String> {
    let attribs = [
        OSMESA_FORMAT,
        OSMESA_RGBA,
        OSMESA_DEPTH_BITS,
        0,
        OSMESA_PROFILE,
        OSMESA_COMPAT_PROFILE,
        0,
    ];
    let _guard = LIFECYCLE.lock().unwrap_or_else(|p| p.into_inner());
    // SAFETY: zero-terminated list; the context is released and destroyed
    // before returning, while `buffer` is alive.
    unsafe {
        let context = (lib.create_context_attribs)(attribs.as_ptr(), std::ptr::null_mut());
        if context.is_null() {
            return None;
        }
        let previous = (lib.get_current_context)();
        let mut buffer = [0u32; BUFFER_PIXELS];
        let mut version = None;
        let made = (lib.make_current)(
            context,
            buffer.as_mut_ptr().cast(),
            GL_UNSIGNED_BYTE,
            BUFFER_SIDE,
            BUFFER_SIDE,
        );
        if made != 0 {
            let loader = |name: &CStr| (lib.get_proc_address)(name.as_ptr());
            version = crate::request::read_gl_string(&loader, glow::VERSION);
            restore(lib, previous);
        }
        (lib.destroy_context)(context);
        version
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_library_is_one_clear_line() {
        let Err(reason) = OsMesaLib::load("libOSMesa-does-not-exist.so.8") else {
            panic!("a library that does not exist was loaded");
        };
        let e = Error::BackendUnavailable {
            backend: BACKEND,
            reason,
        };
        let text = e.to_string();
        assert!(!text.contains('\n'), "{text}");
        assert!(
            text.starts_with(
                "osmesa backend unavailable: cannot load libOSMesa-does-not-exist.so.8"
            ),
            "{text}"
        );
        assert!(
            text.ends_with("install the Debian package libosmesa6"),
            "{text}"
        );
    }
}
