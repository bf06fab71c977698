//! Headless OpenGL contexts.
//!
//! A [`HeadlessContext`] owns a native OpenGL context with no window and no
//! default framebuffer worth rendering to, and hands out a [`glow::Context`]
//! for it. All real rendering goes to framebuffer objects.
//!
//! Two backends, both loaded at run time so that the crate builds and starts
//! on a machine that has neither:
//!
//! - [`Backend::Egl`]: `libEGL.so.1` on an `EGL_PLATFORM_SURFACELESS_MESA`
//!   display (falling back to `EGL_PLATFORM_DEVICE_EXT`), with a context
//!   made current without any surface (`EGL_KHR_surfaceless_context`).
//! - [`Backend::OsMesa`]: Mesa's off-screen renderer, `libOSMesa.so.8`.
//!
//! Every context is checked against the crate's floor, OpenGL 3.2 core with
//! GLSL 1.50; anything less is [`Error::GlVersionTooLow`].
//!
//! # Threads
//!
//! A context is current on at most one thread at a time. Creating one makes it
//! current on the calling thread. [`HeadlessContext`] is `Send` but not `Sync`:
//! to move one to another thread, call [`HeadlessContext::release_current`] on
//! the thread where it is current, move it, then call
//! [`HeadlessContext::make_current`] on the new thread. Several contexts may
//! live at once, on one thread or on many, for either backend or both.

#![warn(missing_docs)]

mod egl;
mod error;
mod loader;
mod osmesa;
mod request;

pub use error::{Error, Result};
pub use request::{ContextRequest, GlVersion};
use request::{glow_parses_version, parse_major_minor, read_gl_string};

use std::cell::Cell;
use std::ffi::{CStr, CString, c_void};
use std::fmt;
use std::marker::PhantomData;
use std::mem::ManuallyDrop;
use std::str::FromStr;

use glow::HasContext;

/// A way of getting a headless OpenGL context.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Backend {
    /// EGL on a surfaceless (or device) display, from `libEGL.so.1`
    /// (Debian packages `libegl1` and `libegl-mesa0`).
    #[default]
    Egl,
    /// Mesa's off-screen renderer, from `libOSMesa.so.8`
    /// (Debian package `libosmesa6`).
    OsMesa,
}

impl Backend {
    /// Every backend, in order of preference.
    pub const fn all() -> [Backend; 2] {
        [Backend::Egl, Backend::OsMesa]
    }

    /// The backend's name as the command line spells it: `egl` or `osmesa`.
    pub const fn name(self) -> &'static str {
        match self {
            Backend::Egl => "egl",
            Backend::OsMesa => "osmesa",
        }
    }

    /// Loads the backend's system library (once per process; it stays loaded)
    /// without creating a context.
    ///
    /// Returns [`Error::BackendUnavailable`], naming the Debian package to
    /// install, when the library is missing or lacks an entry point the
    /// backend needs. A success does not promise that context creation will
    /// succeed, only that the library is there.
    pub fn check_library(self) -> Result<()> {
        match self {
            Backend::Egl => egl::library().map(|_| ()),
            Backend::OsMesa => osmesa::library().map(|_| ()),
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = Error;

    /// Parses `egl` or `osmesa` (ASCII case-insensitive, surrounding
    /// whitespace ignored).
    fn from_str(s: &str) -> Result<Self> {
        let wanted = s.trim();
        Backend::all()
            .into_iter()
            .find(|b| b.name().eq_ignore_ascii_case(wanted))
            .ok_or_else(|| {
                Error::invalid(format!(
                    "unknown backend `{wanted}`: expected `egl` or `osmesa`"
                ))
            })
    }
}

/// The native half of a context.
enum Native {
    Egl(egl::EglContext),
    OsMesa(osmesa::OsMesaContext),
}

impl Native {
    fn make_current(&self) -> Result<()> {
        match self {
            Native::Egl(c) => c.make_current(),
            Native::OsMesa(c) => c.make_current(),
        }
    }

    fn release_current(&self) -> Result<()> {
        match self {
            Native::Egl(c) => c.release_current(),
            Native::OsMesa(c) => c.release_current(),
        }
    }

    fn get_proc_address(&self, name: &CStr) -> *const c_void {
        match self {
            Native::Egl(c) => c.get_proc_address(name),
            Native::OsMesa(c) => c.get_proc_address(name),
        }
    }

    /// Runs `f` with this context current on the calling thread, then puts
    /// back whatever was current before. `None` when it could not be made
    /// current (it is current on another thread).
    fn with_current(&self, f: impl FnOnce()) -> Option<()> {
        match self {
            Native::Egl(c) => c.with_current(f),
            Native::OsMesa(c) => c.with_current(f),
        }
    }
}

/// A headless OpenGL 3.2+ core context and its [`glow::Context`].
///
/// Dropping it releases it (if current on the calling thread) and destroys it;
/// for EGL, the display is terminated when the last context on it goes.
pub struct HeadlessContext {
    // Dropped by hand in `Drop`, before the native context goes: glow unsets
    // a debug callback on drop, which needs the context alive and current.
    gl: ManuallyDrop<glow::Context>,
    native: Native,
    backend: Backend,
    version: GlVersion,
    // Whether `gl_mut` was ever called: only then can glow hold a debug
    // callback, and only then does dropping `gl` make GL calls.
    gl_mut_used: bool,
    // Not `Sync`: a context is used from one thread at a time.
    _not_sync: PhantomData<Cell<()>>,
}

// SAFETY: EGL and OSMesa contexts may be made current on any thread, one
// thread at a time; the type is not `Sync`, so `&self` methods never run on
// two threads at once. The native handles are plain pointers owned by this
// value; the loaded libraries stay loaded for the life of the process.
unsafe impl Send for HeadlessContext {}

impl fmt::Debug for HeadlessContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HeadlessContext")
            .field("backend", &self.backend)
            .field("version", &self.version)
            .finish_non_exhaustive()
    }
}

impl HeadlessContext {
    /// Creates an OpenGL 3.2 core context (the driver may give a newer one)
    /// and makes it current on the calling thread.
    pub fn new(backend: Backend) -> Result<Self> {
        HeadlessContext::with_request(backend, &ContextRequest::default())
    }

    /// Creates a context as `req` asks and makes it current on the calling
    /// thread.
    ///
    /// Errors: [`Error::InvalidArgument`] for a request below 3.2,
    /// [`Error::BackendUnavailable`] when the backend's library or a display
    /// is missing, [`Error::GlVersionTooLow`] when the driver offers less
    /// than OpenGL 3.2 / GLSL 1.50, [`Error::Create`] when the driver refuses
    /// the context.
    pub fn with_request(backend: Backend, req: &ContextRequest) -> Result<Self> {
        req.validate()?;
        let native = match backend {
            Backend::Egl => Native::Egl(egl::EglContext::create(req)?),
            Backend::OsMesa => Native::OsMesa(osmesa::OsMesaContext::create(req)?),
        };
        // The native context is current now. Check the version before glow
        // sees it: glow panics on a missing or unparsable GL_VERSION.
        let loader = |name: &CStr| native.get_proc_address(name);
        let raw_version = read_gl_string(&loader, glow::VERSION).ok_or_else(|| Error::Create {
            what: format!("{backend} OpenGL context"),
            reason: "glGetString(GL_VERSION) returned nothing; the context is not usable".into(),
        })?;
        match parse_major_minor(&raw_version) {
            Some(v) if v >= (3, 2) && glow_parses_version(&raw_version) => {}
            Some(v) if v < (3, 2) => return Err(Error::GlVersionTooLow { found: raw_version }),
            _ => {
                return Err(Error::Create {
                    what: format!("{backend} OpenGL context"),
                    reason: format!("unrecognised GL_VERSION string `{raw_version}`"),
                });
            }
        }

        // Read through the raw path, not glow's, which panics on a null or
        // non-UTF-8 string.
        let string = |name| read_gl_string(&loader, name).unwrap_or_default();
        let version = GlVersion::from_strings(
            raw_version.clone(),
            string(glow::SHADING_LANGUAGE_VERSION),
            string(glow::RENDERER),
            string(glow::VENDOR),
        );
        // SAFETY: the context is current on this thread and the loader
        // returns its entry points.
        let gl = unsafe { glow::Context::from_loader_function_cstr(loader) };
        if !version.at_least(3, 2) || !version.glsl_at_least(1, 50) {
            let found = if version.at_least(3, 2) {
                format!(
                    "{} with GLSL {}",
                    version.version_string, version.glsl_string
                )
            } else {
                version.version_string.clone()
            };
            return Err(Error::GlVersionTooLow { found });
        }
        if req.debug && backend == Backend::OsMesa && gl.supports_debug() {
            // SAFETY: current context; DEBUG_OUTPUT exists with KHR_debug.
            unsafe { gl.enable(glow::DEBUG_OUTPUT) };
        }
        log::debug!("{backend} context: {version}");

        Ok(HeadlessContext {
            gl: ManuallyDrop::new(gl),
            native,
            backend,
            version,
            gl_mut_used: false,
            _not_sync: PhantomData,
        })
    }

    /// The backend that created this context.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The GL function table. Calls through it reach this context only while
    /// it is current on the calling thread.
    pub fn gl(&self) -> &glow::Context {
        &self.gl
    }

    /// The GL function table, mutably (for `debug_message_callback`). Make
    /// the context current first.
    pub fn gl_mut(&mut self) -> &mut glow::Context {
        self.gl_mut_used = true;
        &mut self.gl
    }

    /// Makes this context current on the calling thread.
    ///
    /// Fails (with [`Error::Create`]) when it is current on another thread:
    /// call [`HeadlessContext::release_current`] there first.
    pub fn make_current(&self) -> Result<()> {
        self.native.make_current()
    }

    /// Releases this context from the calling thread, leaving no context of
    /// this backend current there. Does nothing when this context is not the
    /// one current on the calling thread.
    pub fn release_current(&self) -> Result<()> {
        self.native.release_current()
    }

    /// Looks up a GL entry point by name (for functions glow lacks, e.g.
    /// `glGetMultisamplefv`, `glClipControl`); null if absent.
    ///
    /// The pointer is valid only with this context current. A non-null
    /// pointer does not prove the driver implements the function (EGL through
    /// libglvnd and OSMesa hand out dispatch stubs for any `gl*` name): check
    /// the version or the extension first.
    pub fn get_proc_address(&self, name: &str) -> *const c_void {
        match CString::new(name) {
            Ok(name) => self.native.get_proc_address(&name),
            Err(_) => std::ptr::null(),
        }
    }

    /// The version and identity strings read after creation.
    pub fn version(&self) -> GlVersion {
        self.version.clone()
    }
}

impl Drop for HeadlessContext {
    fn drop(&mut self) {
        // SAFETY: `gl` is taken exactly once, here, and never used again.
        let gl = unsafe { ManuallyDrop::take(&mut self.gl) };
        if !self.gl_mut_used {
            // glow's drop makes no GL call unless a debug callback was set,
            // which needs `gl_mut`.
            drop(gl);
        } else {
            let mut gl = Some(gl);
            let made_current = self.native.with_current(|| drop(gl.take()));
            if made_current.is_none() {
                log::warn!(
                    "dropping a {} context that is current on another thread; \
                     its glow function table is leaked rather than unset there",
                    self.backend
                );
                std::mem::forget(gl);
            }
        }
        // `native` drops next: it releases and destroys the context.
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::request::too_low_from_probe;

    #[test]
    fn parses_version_strings() {
        assert_eq!(
            parse_major_minor("4.5 (Core Profile) Mesa 22.3.6"),
            Some((4, 5))
        );
        assert_eq!(
            parse_major_minor("3.2 (Core Profile) Mesa 22.3.6"),
            Some((3, 2))
        );
        assert_eq!(parse_major_minor("4.50"), Some((4, 50)));
        assert_eq!(parse_major_minor("1.50"), Some((1, 50)));
        assert_eq!(parse_major_minor("OpenGL ES 3.2 Mesa 22.3.6"), Some((3, 2)));
        assert_eq!(parse_major_minor("OpenGL ES GLSL ES 3.20"), Some((3, 20)));
        assert_eq!(parse_major_minor("4.6.0 NVIDIA 535.104.05"), Some((4, 6)));
        assert_eq!(parse_major_minor(""), None);
        assert_eq!(parse_major_minor("garbage"), None);
        assert_eq!(parse_major_minor("4"), None);
    }

    #[test]
    fn glow_parse_precheck() {
        assert!(glow_parses_version("4.5 (Core Profile) Mesa 22.3.6"));
        assert!(glow_parses_version("3.2 Mesa"));
        assert!(glow_parses_version("4.6.0 NVIDIA 535.104.05"));
        assert!(glow_parses_version("OpenGL ES 3.2 Mesa 22.3.6"));
        assert!(!glow_parses_version("version 4.5"));
        assert!(!glow_parses_version("4"));
        assert!(!glow_parses_version(""));
    }

    #[test]
    fn version_comparisons() {
        let v = GlVersion::from_strings(
            "3.2 (Core Profile) Mesa 22.3.6".into(),
            "1.50".into(),
            "llvmpipe".into(),
            "Mesa".into(),
        );
        assert_eq!(
            (v.major, v.minor, v.glsl_major, v.glsl_minor),
            (3, 2, 1, 50)
        );
        assert!(v.at_least(3, 2));
        assert!(v.at_least(3, 1));
        assert!(v.at_least(2, 9));
        assert!(!v.at_least(3, 3));
        assert!(!v.at_least(4, 0));
        assert!(v.glsl_at_least(1, 50));
        assert!(!v.glsl_at_least(3, 30));
    }

    #[test]
    fn probe_reports_low_versions_only() {
        assert!(matches!(
            too_low_from_probe(Some("3.1 Mesa 22.3.6".into())),
            Some(Error::GlVersionTooLow { found }) if found == "3.1 Mesa 22.3.6"
        ));
        assert!(too_low_from_probe(Some("4.5 (Compatibility Profile) Mesa".into())).is_none());
        assert!(too_low_from_probe(None).is_none());
    }

    #[test]
    fn request_floor() {
        assert!(ContextRequest::default().validate().is_ok());
        let low = ContextRequest {
            major: 3,
            minor: 1,
            debug: false,
        };
        assert!(matches!(low.validate(), Err(Error::InvalidArgument(_))));
        let high = ContextRequest {
            major: 4,
            minor: 0,
            debug: true,
        };
        assert!(high.validate().is_ok());
    }
}
