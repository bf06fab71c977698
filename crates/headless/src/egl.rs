//! The EGL backend: a surfaceless (or device) display, no surface at all.
//!
//! `libEGL.so.1` is opened at run time with `libloading` and the entry points
//! are called directly, so that every failure — including error codes no
//! wrapper knows, such as `EGL_BAD_DEVICE_EXT` — becomes a `crate::Error`
//! rather than a panic. The enum values come from `khronos-egl`, plus the
//! extension ones below.
//!
//! One display is shared by every EGL context of the process. It is
//! initialised when the first context is created and terminated when the last
//! one is dropped (a reference count under a mutex), so contexts may come and
//! go on any number of threads.

use std::ffi::{CStr, c_char, c_void};
use std::sync::{Mutex, MutexGuard, OnceLock};

use khronos_egl as k;

use crate::loader::{open, symbol};
use crate::{Error, Result};

type EglBoolean = u32;
type EglInt = i32;
type EglEnum = u32;
type EglAttrib = isize;
type EglDisplay = *mut c_void;
type EglConfig = *mut c_void;
type EglCtx = *mut c_void;
type EglSurface = *mut c_void;
type EglDevice = *mut c_void;

const EGL_TRUE: EglBoolean = 1;
const EGL_SUCCESS: EglInt = 0x3000;
const EGL_PLATFORM_SURFACELESS_MESA: EglEnum = 0x31DD;
const EGL_PLATFORM_DEVICE_EXT: EglEnum = 0x313F;
const EGL_CONTEXT_FLAGS_KHR: EglInt = 0x30FC;
const EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR: EglInt = 0x0001;
const EGL_DRAW: EglInt = 0x3059;
const EGL_READ: EglInt = 0x305A;
const EGL_BAD_DEVICE_EXT: EglInt = 0x322B;

const BACKEND: &str = "egl";
const INSTALL_HINT: &str = "install the Debian packages libegl1 and libegl-mesa0";

type FnGetError = unsafe extern "system" fn() -> EglInt;
type FnQueryString = unsafe extern "system" fn(EglDisplay, EglInt) -> *const c_char;
type FnGetProcAddress = unsafe extern "system" fn(*const c_char) -> *const c_void;
type FnGetPlatformDisplay =
    unsafe extern "system" fn(EglEnum, *mut c_void, *const EglAttrib) -> EglDisplay;
type FnGetPlatformDisplayExt =
    unsafe extern "system" fn(EglEnum, *mut c_void, *const EglInt) -> EglDisplay;
type FnInitialize = unsafe extern "system" fn(EglDisplay, *mut EglInt, *mut EglInt) -> EglBoolean;
type FnTerminate = unsafe extern "system" fn(EglDisplay) -> EglBoolean;
type FnBindApi = unsafe extern "system" fn(EglEnum) -> EglBoolean;
type FnChooseConfig = unsafe extern "system" fn(
    EglDisplay,
    *const EglInt,
    *mut EglConfig,
    EglInt,
    *mut EglInt,
) -> EglBoolean;
type FnCreateContext =
    unsafe extern "system" fn(EglDisplay, EglConfig, EglCtx, *const EglInt) -> EglCtx;
type FnDestroyContext = unsafe extern "system" fn(EglDisplay, EglCtx) -> EglBoolean;
type FnMakeCurrent =
    unsafe extern "system" fn(EglDisplay, EglSurface, EglSurface, EglCtx) -> EglBoolean;
type FnGetCurrentContext = unsafe extern "system" fn() -> EglCtx;
type FnGetCurrentDisplay = unsafe extern "system" fn() -> EglDisplay;
type FnGetCurrentSurface = unsafe extern "system" fn(EglInt) -> EglSurface;
type FnQueryDevicesExt =
    unsafe extern "system" fn(EglInt, *mut EglDevice, *mut EglInt) -> EglBoolean;

/// The loaded library and its entry points. Lives in a static for the rest of
/// the process (never unloaded: unloading Mesa's EGL at exit is known to
/// crash).
pub(crate) struct EglLib {
    get_error: FnGetError,
    query_string: FnQueryString,
    get_proc_address: FnGetProcAddress,
    get_platform_display: Option<FnGetPlatformDisplay>,
    get_platform_display_ext: Option<FnGetPlatformDisplayExt>,
    query_devices_ext: Option<FnQueryDevicesExt>,
    initialize: FnInitialize,
    terminate: FnTerminate,
    bind_api: FnBindApi,
    choose_config: FnChooseConfig,
    create_context: FnCreateContext,
    destroy_context: FnDestroyContext,
    make_current: FnMakeCurrent,
    get_current_context: FnGetCurrentContext,
    get_current_display: FnGetCurrentDisplay,
    get_current_surface: FnGetCurrentSurface,
    client_extensions: String,
    _lib: libloading::Library,
}

static LIBRARY: OnceLock<std::result::Result<EglLib, String>> = OnceLock::new();

/// Loads `libEGL.so.1` once per process.
pub(crate) fn library() -> Result<&'static EglLib> {
    LIBRARY
        .get_or_init(|| EglLib::load(&["libEGL.so.1", "libEGL.so"]))
        .as_ref()
        .map_err(|reason| Error::BackendUnavailable {
            backend: BACKEND,
            reason: reason.clone(),
        })
}

/// Looks up an extension entry point through `eglGetProcAddress`.
///
/// # Safety
/// `T` must be the entry point's true function pointer type.
unsafe fn proc_address<T: Copy>(get: FnGetProcAddress, name: &CStr) -> Option<T> {
    debug_assert_eq!(size_of::<T>(), size_of::<*const c_void>());
    // SAFETY: `name` is NUL-terminated; `eglGetProcAddress` may be called
    // before any display exists.
    let p = unsafe { get(name.as_ptr()) };
    if p.is_null() {
        None
    } else {
        // SAFETY: forwarded to the caller; a non-null pointer is a function.
        Some(unsafe { std::mem::transmute_copy::<*const c_void, T>(&p) })
    }
}

impl EglLib {
    fn load(names: &[&str]) -> std::result::Result<EglLib, String> {
        let lib = open(names, INSTALL_HINT)?;
        Self::from_library(lib)
            .map_err(|missing| format!("libEGL lacks an entry point: {missing}; {INSTALL_HINT}"))
    }

    fn from_library(lib: libloading::Library) -> std::result::Result<EglLib, String> {
        // SAFETY (every `symbol` call): the types are the EGL 1.4/1.5
        // prototypes of the named functions.
        unsafe {
            let get_proc_address: FnGetProcAddress = symbol(&lib, "eglGetProcAddress")?;
            let query_string: FnQueryString = symbol(&lib, "eglQueryString")?;
            let get_error: FnGetError = symbol(&lib, "eglGetError")?;
            // EGL_NO_DISPLAY: the client extensions (EGL_EXT_client_extensions);
            // null when the library has none, which leaves no platform to use.
            let ext = query_string(std::ptr::null_mut(), k::EXTENSIONS);
            let client_extensions = if ext.is_null() {
                // Clear the EGL_BAD_DISPLAY that the query set.
                get_error();
                String::new()
            } else {
                CStr::from_ptr(ext).to_string_lossy().into_owned()
            };
            Ok(EglLib {
                get_error,
                query_string,
                get_proc_address,
                get_platform_display: symbol(&lib, "eglGetPlatformDisplay").ok(),
                get_platform_display_ext: proc_address(
                    get_proc_address,
                    c"eglGetPlatformDisplayEXT",
                ),
                query_devices_ext: proc_address(get_proc_address, c"eglQueryDevicesEXT"),
                initialize: symbol(&lib, "eglInitialize")?,
                terminate: symbol(&lib, "eglTerminate")?,
                bind_api: symbol(&lib, "eglBindAPI")?,
                choose_config: symbol(&lib, "eglChooseConfig")?,
                create_context: symbol(&lib, "eglCreateContext")?,
                destroy_context: symbol(&lib, "eglDestroyContext")?,
                make_current: symbol(&lib, "eglMakeCurrent")?,
                get_current_context: symbol(&lib, "eglGetCurrentContext")?,
                get_current_display: symbol(&lib, "eglGetCurrentDisplay")?,
                get_current_surface: symbol(&lib, "eglGetCurrentSurface")?,
                client_extensions,
                _lib: lib,
            })
        }
    }

    /// The last EGL error on this thread, by name.
    fn error(&self) -> String {
        // SAFETY: no arguments; always callable.
        let code = unsafe { (self.get_error)() };
        error_name(code)
    }

    fn has_client_extension(&self, name: &str) -> bool {
        has_extension(&self.client_extensions, name)
    }

    /// `eglBindAPI(EGL_OPENGL_API)` on the calling thread: the current-context
    /// queries and a release with `EGL_NO_CONTEXT` act on the bound API.
    fn bind_opengl(&self) -> Result<()> {
        // SAFETY: plain call with a valid enum.
        if unsafe { (self.bind_api)(k::OPENGL_API) } == EGL_TRUE {
            Ok(())
        } else {
            Err(Error::BackendUnavailable {
                backend: BACKEND,
                reason: format!(
                    "eglBindAPI(EGL_OPENGL_API) failed ({}): this libEGL offers no desktop OpenGL; {INSTALL_HINT}",
                    self.error()
                ),
            })
        }
    }

    fn platform_display(
        &self,
        platform: EglEnum,
        native: *mut c_void,
    ) -> std::result::Result<EglDisplay, String> {
        // SAFETY: the attribute lists are EGL_NONE-terminated; `native` is
        // EGL_DEFAULT_DISPLAY or a device handle from eglQueryDevicesEXT.
        let display = unsafe {
            if let Some(get) = self.get_platform_display {
                get(platform, native, [k::ATTRIB_NONE as EglAttrib].as_ptr())
            } else if let Some(get) = self.get_platform_display_ext {
                get(platform, native, [k::NONE].as_ptr())
            } else {
                return Err(
                    "neither eglGetPlatformDisplay nor eglGetPlatformDisplayEXT exists".into(),
                );
            }
        };
        if display.is_null() {
            Err(format!("eglGetPlatformDisplay failed ({})", self.error()))
        } else {
            Ok(display)
        }
    }
}

fn has_extension(list: &str, name: &str) -> bool {
    list.split_ascii_whitespace().any(|e| e == name)
}

fn error_name(code: EglInt) -> String {
    let name = match code {
        EGL_SUCCESS => "EGL_SUCCESS",
        0x3001 => "EGL_NOT_INITIALIZED",
        0x3002 => "EGL_BAD_ACCESS",
        0x3003 => "EGL_BAD_ALLOC",
        0x3004 => "EGL_BAD_ATTRIBUTE",
        0x3005 => "EGL_BAD_CONFIG",
        0x3006 => "EGL_BAD_CONTEXT",
        0x3007 => "EGL_BAD_CURRENT_SURFACE",
        0x3008 => "EGL_BAD_DISPLAY",
        0x3009 => "EGL_BAD_MATCH",
        0x300A => "EGL_BAD_NATIVE_PIXMAP",
        0x300B => "EGL_BAD_NATIVE_WINDOW",
        0x300C => "EGL_BAD_PARAMETER",
        0x300D => "EGL_BAD_SURFACE",
        0x300E => "EGL_CONTEXT_LOST",
        EGL_BAD_DEVICE_EXT => "EGL_BAD_DEVICE_EXT",
        other => return format!("EGL error 0x{other:04X}"),
    };
    name.to_string()
}

/// The shared display, while at least one context uses it.
#[derive(Clone, Copy)]
struct OpenDisplay {
    raw: EglDisplay,
    platform: &'static str,
    major: EglInt,
    minor: EglInt,
    no_config: bool,
}

// SAFETY: an EGLDisplay handle is a process-wide token, valid on any thread.
unsafe impl Send for OpenDisplay {}

struct DisplayState {
    users: usize,
    display: Option<OpenDisplay>,
}

static DISPLAY: Mutex<DisplayState> = Mutex::new(DisplayState {
    users: 0,
    display: None,
});

fn lock_display() -> MutexGuard<'static, DisplayState> {
    // The state is a counter and a handle; a panic elsewhere leaves it usable.
    DISPLAY
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// One context's share of the display; the last lease to go terminates it.
struct DisplayLease {
    lib: &'static EglLib,
    display: OpenDisplay,
}

impl DisplayLease {
    fn acquire(lib: &'static EglLib) -> Result<DisplayLease> {
        let mut state = lock_display();
        let display = match state.display {
            Some(d) => d,
            None => {
                let d = open_display(lib)?;
                state.display = Some(d);
                d
            }
        };
        state.users += 1;
        Ok(DisplayLease { lib, display })
    }
}

impl Drop for DisplayLease {
    fn drop(&mut self) {
        let mut state = lock_display();
        state.users = state.users.saturating_sub(1);
        if state.users > 0 {
            return;
        }
        if let Some(d) = state.display.take() {
            // SAFETY: no context of ours lives on this display any more.
            if unsafe { (self.lib.terminate)(d.raw) } != EGL_TRUE {
                log::warn!("eglTerminate failed: {}", self.lib.error());
            }
        }
    }
}

/// Initialises `raw` and checks that it can do what we need; terminates it
/// again when it cannot.
fn init_display(
    lib: &EglLib,
    raw: EglDisplay,
    platform: &'static str,
) -> std::result::Result<OpenDisplay, String> {
    let (mut major, mut minor) = (0, 0);
    // SAFETY: `raw` came from eglGetPlatformDisplay.
    if unsafe { (lib.initialize)(raw, &mut major, &mut minor) } != EGL_TRUE {
        return Err(format!("eglInitialize failed ({})", lib.error()));
    }
    // SAFETY: initialised display.
    let ext = unsafe { (lib.query_string)(raw, k::EXTENSIONS) };
    let extensions = if ext.is_null() {
        String::new()
    } else {
        // SAFETY: EGL returns a NUL-terminated static string.
        unsafe { CStr::from_ptr(ext) }
            .to_string_lossy()
            .into_owned()
    };
    let mut missing = Vec::new();
    if !has_extension(&extensions, "EGL_KHR_surfaceless_context") {
        missing.push("EGL_KHR_surfaceless_context");
    }
    if (major, minor) < (1, 5) && !has_extension(&extensions, "EGL_KHR_create_context") {
        missing.push("EGL_KHR_create_context (or EGL 1.5)");
    }
    if !missing.is_empty() {
        // SAFETY: we initialised it above and nothing else of ours uses it.
        unsafe { (lib.terminate)(raw) };
        return Err(format!(
            "EGL {major}.{minor} display lacks {}",
            missing.join(" and ")
        ));
    }
    Ok(OpenDisplay {
        raw,
        platform,
        major,
        minor,
        no_config: has_extension(&extensions, "EGL_KHR_no_config_context"),
    })
}

/// Picks a headless display: Mesa's surfaceless platform, else the first
/// device that works. Never `eglGetDisplay(EGL_DEFAULT_DISPLAY)`, which tries
/// X11.
fn open_display(lib: &EglLib) -> Result<OpenDisplay> {
    let mut reasons = Vec::new();
    if lib.has_client_extension("EGL_MESA_platform_surfaceless") {
        match lib
            .platform_display(EGL_PLATFORM_SURFACELESS_MESA, std::ptr::null_mut())
            .and_then(|raw| init_display(lib, raw, "surfaceless"))
        {
            Ok(d) => return Ok(d),
            Err(e) => reasons.push(format!("surfaceless platform: {e}")),
        }
    } else {
        reasons.push("no EGL_MESA_platform_surfaceless".to_string());
    }

    if lib.has_client_extension("EGL_EXT_platform_device") {
        match device_displays(lib) {
            Ok(devices) => {
                for (i, device) in devices.into_iter().enumerate() {
                    match lib
                        .platform_display(EGL_PLATFORM_DEVICE_EXT, device)
                        .and_then(|raw| init_display(lib, raw, "device"))
                    {
                        Ok(d) => return Ok(d),
                        Err(e) => reasons.push(format!("device {i}: {e}")),
                    }
                }
            }
            Err(e) => reasons.push(format!("device platform: {e}")),
        }
    } else {
        reasons.push("no EGL_EXT_platform_device".to_string());
    }

    Err(Error::BackendUnavailable {
        backend: BACKEND,
        reason: format!(
            "no headless EGL display ({}); {INSTALL_HINT}, or use the OSMesa backend",
            reasons.join("; ")
        ),
    })
}

fn device_displays(lib: &EglLib) -> std::result::Result<Vec<EglDevice>, String> {
    let query = lib
        .query_devices_ext
        .ok_or("eglQueryDevicesEXT is missing")?;
    let mut count: EglInt = 0;
    // SAFETY: a null array asks for the count only.
    if unsafe { query(0, std::ptr::null_mut(), &mut count) } != EGL_TRUE {
        return Err(format!("eglQueryDevicesEXT failed ({})", lib.error()));
    }
    let mut devices = vec![std::ptr::null_mut(); usize::try_from(count).unwrap_or(0)];
    if devices.is_empty() {
        return Err("eglQueryDevicesEXT found no device".into());
    }
    let mut found: EglInt = 0;
    // SAFETY: `devices` holds `count` entries.
    if unsafe { query(count, devices.as_mut_ptr(), &mut found) } != EGL_TRUE {
        return Err(format!("eglQueryDevicesEXT failed ({})", lib.error()));
    }
    devices.truncate(usize::try_from(found).unwrap_or(0));
    Ok(devices)
}

/// An EGL context with no surface.
pub(crate) struct EglContext {
    lib: &'static EglLib,
    context: EglCtx,
    // Dropped after `Drop::drop` has destroyed the context.
    lease: DisplayLease,
}

impl EglContext {
    /// Creates a context as `req` asks and makes it current.
    pub(crate) fn create(req: &crate::request::ContextRequest) -> Result<EglContext> {
        let lib = library()?;
        let lease = DisplayLease::acquire(lib)?;
        lib.bind_opengl()?;
        let d = lease.display;
        let what = || {
            format!(
                "EGL OpenGL {}.{} core context ({} display)",
                req.major, req.minor, d.platform
            )
        };

        // EGL_SURFACE_TYPE must be given: its default, EGL_WINDOW_BIT,
        // matches nothing on a surfaceless display. 0 matches every config.
        let config_attribs = [
            k::SURFACE_TYPE,
            0,
            k::RENDERABLE_TYPE,
            k::OPENGL_BIT,
            k::NONE,
        ];
        let mut config: EglConfig = std::ptr::null_mut();
        let mut found: EglInt = 0;
        // SAFETY: room for one config; the list is EGL_NONE-terminated.
        let chose = unsafe {
            (lib.choose_config)(d.raw, config_attribs.as_ptr(), &mut config, 1, &mut found)
        };
        if chose != EGL_TRUE || found < 1 {
            let why = if chose != EGL_TRUE {
                format!("eglChooseConfig failed ({})", lib.error())
            } else {
                "no EGL config renders desktop OpenGL".to_string()
            };
            if d.no_config {
                log::debug!("{why}; using EGL_NO_CONFIG_KHR");
                config = std::ptr::null_mut();
            } else {
                return Err(Error::BackendUnavailable {
                    backend: BACKEND,
                    reason: format!("{why}; {INSTALL_HINT}"),
                });
            }
        }

        let mut attribs = vec![
            k::CONTEXT_MAJOR_VERSION,
            EglInt::from(req.major),
            k::CONTEXT_MINOR_VERSION,
            EglInt::from(req.minor),
            k::CONTEXT_OPENGL_PROFILE_MASK,
            k::CONTEXT_OPENGL_CORE_PROFILE_BIT,
        ];
        if req.debug {
            if (d.major, d.minor) >= (1, 5) {
                attribs.extend([k::CONTEXT_OPENGL_DEBUG, k::TRUE as EglInt]);
            } else {
                attribs.extend([EGL_CONTEXT_FLAGS_KHR, EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR]);
            }
        }
        attribs.push(k::NONE);

        // SAFETY: valid display and config; EGL_NONE-terminated list.
        let context =
            unsafe { (lib.create_context)(d.raw, config, std::ptr::null_mut(), attribs.as_ptr()) };
        if context.is_null() {
            let reason = lib.error();
            if let Some(too_low) =
                crate::request::too_low_from_probe(probe_version(lib, &d, config))
            {
                return Err(too_low);
            }
            return Err(Error::Create {
                what: what(),
                reason: format!("eglCreateContext failed ({reason})"),
            });
        }
        let ctx = EglContext {
            lib,
            context,
            lease,
        };
        ctx.make_current()?;
        Ok(ctx)
    }

    pub(crate) fn make_current(&self) -> Result<()> {
        self.lib.bind_opengl()?;
        // SAFETY: our display and context; no surface (surfaceless).
        let ok = unsafe {
            (self.lib.make_current)(
                self.lease.display.raw,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                self.context,
            )
        };
        if ok == EGL_TRUE {
            Ok(())
        } else {
            let error = self.lib.error();
            let hint = if error == "EGL_BAD_ACCESS" {
                " (it is current on another thread: release it there first)"
            } else {
                ""
            };
            Err(Error::Create {
                what: "a current EGL context (eglMakeCurrent)".into(),
                reason: format!("{error}{hint}"),
            })
        }
    }

    fn is_current(&self) -> bool {
        // SAFETY: plain query for the bound API (bound by the caller).
        unsafe { (self.lib.get_current_context)() == self.context }
    }

    pub(crate) fn release_current(&self) -> Result<()> {
        self.lib.bind_opengl()?;
        if !self.is_current() {
            return Ok(());
        }
        // SAFETY: releasing the calling thread's context of the bound API.
        let ok = unsafe {
            (self.lib.make_current)(
                self.lease.display.raw,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        if ok == EGL_TRUE {
            Ok(())
        } else {
            Err(Error::Create {
                what: "a released EGL context (eglMakeCurrent with EGL_NO_CONTEXT)".into(),
                reason: self.lib.error(),
            })
        }
    }

    pub(crate) fn get_proc_address(&self, name: &CStr) -> *const c_void {
        // SAFETY: NUL-terminated name.
        unsafe { (self.lib.get_proc_address)(name.as_ptr()) }
    }

    pub(crate) fn with_current(&self, f: impl FnOnce()) -> Option<()> {
        if self.lib.bind_opengl().is_err() {
            return None;
        }
        if self.is_current() {
            f();
            return Some(());
        }
        // SAFETY: plain queries.
        let (prev_display, prev_draw, prev_read, prev_context) = unsafe {
            (
                (self.lib.get_current_display)(),
                (self.lib.get_current_surface)(EGL_DRAW),
                (self.lib.get_current_surface)(EGL_READ),
                (self.lib.get_current_context)(),
            )
        };
        if self.make_current().is_err() {
            return None;
        }
        f();
        let (display, draw, read, context) = if prev_context.is_null() {
            (
                self.lease.display.raw,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        } else {
            (prev_display, prev_draw, prev_read, prev_context)
        };
        // SAFETY: restoring the handles EGL reported as current.
        if unsafe { (self.lib.make_current)(display, draw, read, context) } != EGL_TRUE {
            log::warn!(
                "could not restore the previously current EGL context: {}",
                self.lib.error()
            );
        }
        Some(())
    }
}

impl Drop for EglContext {
    fn drop(&mut self) {
        if let Err(e) = self.release_current() {
            log::warn!("{e}");
        }
        // SAFETY: our context on our display; if it is still current on
        // another thread, EGL defers its destruction until it is released.
        if unsafe { (self.lib.destroy_context)(self.lease.display.raw, self.context) } != EGL_TRUE {
            log::warn!("eglDestroyContext failed: {}", self.lib.error());
        }
        // `lease` drops next and terminates the display if we were last.
    }
}

/// Creates a plain context (no version, no profile), reads its `GL_VERSION`
/// and destroys it again: used to explain a refused core context.
fn probe_version(lib: &EglLib, d: &OpenDisplay, config: EglConfig) -> Option<String> {
    let attribs = [k::NONE];
    // SAFETY: valid display/config; EGL_NONE-terminated list.
    let context =
        unsafe { (lib.create_context)(d.raw, config, std::ptr::null_mut(), attribs.as_ptr()) };
    if context.is_null() {
        return None;
    }
    // SAFETY: surfaceless make-current of a context we just made; released
    // and destroyed before returning.
    unsafe {
        let prev_context = (lib.get_current_context)();
        let prev_display = (lib.get_current_display)();
        let prev_draw = (lib.get_current_surface)(EGL_DRAW);
        let prev_read = (lib.get_current_surface)(EGL_READ);
        let mut version = None;
        if (lib.make_current)(d.raw, std::ptr::null_mut(), std::ptr::null_mut(), context)
            == EGL_TRUE
        {
            let loader = |name: &CStr| (lib.get_proc_address)(name.as_ptr());
            version = crate::request::read_gl_string(&loader, glow::VERSION);
            if prev_context.is_null() {
                (lib.make_current)(
                    d.raw,
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                );
            } else {
                (lib.make_current)(prev_display, prev_draw, prev_read, prev_context);
            }
        }
        (lib.destroy_context)(d.raw, context);
        version
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_library_is_one_clear_line() {
        let Err(reason) = EglLib::load(&["libEGL-does-not-exist.so.1"]) else {
            panic!("a library that does not exist was loaded");
        };
        let e = Error::BackendUnavailable {
            backend: BACKEND,
            reason,
        };
        let text = e.to_string();
        assert!(!text.contains('\n'), "{text}");
        assert!(
            text.starts_with("egl backend unavailable: cannot load libEGL-does-not-exist.so.1"),
            "{text}"
        );
        assert!(
            text.contains("libegl1") && text.contains("libegl-mesa0"),
            "{text}"
        );
    }

    #[test]
    fn extension_lists_match_whole_names() {
        let list = "EGL_EXT_platform_base EGL_MESA_platform_surfaceless EGL_KHR_no_config_context";
        assert!(has_extension(list, "EGL_MESA_platform_surfaceless"));
        assert!(!has_extension(list, "EGL_MESA_platform"));
        assert!(!has_extension("", "EGL_EXT_platform_device"));
    }

    /// The fallback path: a display on the first device that works (Mesa
    /// offers a software device even with no GPU).
    #[test]
    fn device_platform_fallback() {
        let lib = match library() {
            Ok(lib) => lib,
            Err(e) => {
                eprintln!("skipped: {e}");
                return;
            }
        };
        if !lib.has_client_extension("EGL_EXT_platform_device") {
            eprintln!("skipped: no EGL_EXT_platform_device");
            return;
        }
        let devices = device_displays(lib).unwrap();
        assert!(!devices.is_empty());
        let opened = devices.iter().find_map(|&device| {
            lib.platform_display(EGL_PLATFORM_DEVICE_EXT, device)
                .and_then(|raw| init_display(lib, raw, "device"))
                .ok()
        });
        let d = opened.expect("no device display is usable");
        assert!((d.major, d.minor) >= (1, 4));
        // SAFETY: initialised above; a device display is never the shared one.
        unsafe { (lib.terminate)(d.raw) };
    }

    #[test]
    fn error_names() {
        assert_eq!(error_name(0x3009), "EGL_BAD_MATCH");
        assert_eq!(error_name(0x322B), "EGL_BAD_DEVICE_EXT");
        assert_eq!(error_name(0x1234), "EGL error 0x1234");
    }
}
