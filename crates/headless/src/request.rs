//! What a context is asked for ([`ContextRequest`]) and the OpenGL version
//! it turns out to have ([`GlVersion`]), read the same way by every
//! backend.

use crate::{Error, Result};
use glow::HasContext;
use std::ffi::{CStr, c_void};
use std::fmt;

/// What to ask the driver for.
///
/// The profile is always core. The driver may return a newer version than
/// requested (Mesa's llvmpipe gives 4.5 core for any 3.2+ request).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ContextRequest {
    /// Requested OpenGL major version; at least 3.
    pub major: u8,
    /// Requested OpenGL minor version; with `major == 3`, at least 2.
    pub minor: u8,
    /// Ask for a debug context. EGL creates one (`EGL_CONTEXT_OPENGL_DEBUG`);
    /// OSMesa cannot, so there `GL_DEBUG_OUTPUT` is enabled instead when the
    /// context supports debug output.
    pub debug: bool,
}

impl Default for ContextRequest {
    /// OpenGL 3.2 core, no debug context.
    fn default() -> Self {
        ContextRequest {
            major: 3,
            minor: 2,
            debug: false,
        }
    }
}

impl ContextRequest {
    pub(crate) fn validate(&self) -> Result<()> {
        if (self.major, self.minor) < (3, 2) {
            return Err(Error::invalid(format!(
                "an OpenGL {}.{} context was requested; the crate needs at least a 3.2 core profile context",
                self.major, self.minor
            )));
        }
        Ok(())
    }
}

/// The version and identity strings of a context, read once after creation.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct GlVersion {
    /// OpenGL major version, from `GL_VERSION`.
    pub major: u32,
    /// OpenGL minor version, from `GL_VERSION`.
    pub minor: u32,
    /// GLSL major version, from `GL_SHADING_LANGUAGE_VERSION`.
    pub glsl_major: u32,
    /// GLSL minor version as written: `1.50` gives 50, `4.60` gives 60.
    pub glsl_minor: u32,
    /// `GL_VERSION` as the driver reported it.
    pub version_string: String,
    /// `GL_SHADING_LANGUAGE_VERSION` as the driver reported it.
    pub glsl_string: String,
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VENDOR`.
    pub vendor: String,
}

impl GlVersion {
    /// Reads and parses the version and identity strings of `gl`.
    ///
    /// `gl`'s context must be current on the calling thread (glow panics on a
    /// null string otherwise). Numbers that cannot be parsed read as 0.
    pub fn query(gl: &glow::Context) -> GlVersion {
        // SAFETY: plain queries; the caller guarantees the context is current.
        let (version_string, glsl_string, renderer, vendor) = unsafe {
            (
                gl.get_parameter_string(glow::VERSION),
                gl.get_parameter_string(glow::SHADING_LANGUAGE_VERSION),
                gl.get_parameter_string(glow::RENDERER),
                gl.get_parameter_string(glow::VENDOR),
            )
        };
        GlVersion::from_strings(version_string, glsl_string, renderer, vendor)
    }

    /// Builds a `GlVersion` from the four strings, parsing the numbers out of
    /// the first two (as [`GlVersion::query`] does).
    pub fn from_strings(
        version_string: String,
        glsl_string: String,
        renderer: String,
        vendor: String,
    ) -> GlVersion {
        let (major, minor) = parse_major_minor(&version_string).unwrap_or((0, 0));
        let (glsl_major, glsl_minor) = parse_major_minor(&glsl_string).unwrap_or((0, 0));
        GlVersion {
            major,
            minor,
            glsl_major,
            glsl_minor,
            version_string,
            glsl_string,
            renderer,
            vendor,
        }
    }

    /// Whether the OpenGL version is `major.minor` or newer.
    pub fn at_least(&self, major: u32, minor: u32) -> bool {
        (self.major, self.minor) >= (major, minor)
    }

    /// Whether the GLSL version is `major.minor` or newer, with `minor` as
    /// written (`glsl_at_least(1, 50)` for GLSL 1.50).
    pub fn glsl_at_least(&self, major: u32, minor: u32) -> bool {
        (self.glsl_major, self.glsl_minor) >= (major, minor)
    }
}

impl fmt::Display for GlVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "OpenGL {} (GLSL {}) on {} ({})",
            self.version_string, self.glsl_string, self.renderer, self.vendor
        )
    }
}

/// Finds the first `<digits>.<digits>` in a version string: `4.5 (Core
/// Profile) Mesa 22.3.6` gives (4, 5), `OpenGL ES GLSL ES 3.20` gives (3, 20).
pub(crate) fn parse_major_minor(s: &str) -> Option<(u32, u32)> {
    let start = s.find(|c: char| c.is_ascii_digit())?;
    let rest = &s[start..];
    let major_end = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    let major = rest[..major_end].parse().ok()?;
    let after = rest[major_end..].strip_prefix('.')?;
    let minor_end = after
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(after.len());
    let minor = after[..minor_end].parse().ok()?;
    Some((major, minor))
}

/// Whether glow's own `GL_VERSION` parser (which panics on failure) accepts
/// the string: the text before the first space must be
/// `<number>.<number>[...]`, unless an ` ES ` prefix comes first.
pub(crate) fn glow_parses_version(s: &str) -> bool {
    let s = match s.rfind(" ES ") {
        Some(pos) => &s[pos + 4..],
        None => s,
    };
    let token = s.split(' ').next().unwrap_or("");
    let mut parts = token.split('.');
    let major_ok = parts.next().is_some_and(|p| p.parse::<u32>().is_ok());
    let minor_ok = parts
        .next()
        .is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    major_ok && minor_ok
}

/// Reads a `glGetString` value through a loader, before any `glow::Context`
/// exists. `None` when the entry point or the string is missing.
pub(crate) fn read_gl_string(loader: &dyn Fn(&CStr) -> *const c_void, name: u32) -> Option<String> {
    type GetString = unsafe extern "system" fn(u32) -> *const u8;
    let ptr = loader(c"glGetString");
    if ptr.is_null() {
        return None;
    }
    // SAFETY: `glGetString` has this signature in every OpenGL version; a
    // context is current on this thread (the backends call this only then).
    unsafe {
        let get_string: GetString = std::mem::transmute::<*const c_void, GetString>(ptr);
        let s = get_string(name);
        if s.is_null() {
            None
        } else {
            Some(CStr::from_ptr(s.cast()).to_string_lossy().into_owned())
        }
    }
}

/// After a failed core-profile creation, a backend may create a plain context
/// and read its `GL_VERSION`: when that is below 3.2 the real reason is the
/// driver's version, not the request.
pub(crate) fn too_low_from_probe(probed_version: Option<String>) -> Option<Error> {
    let found = probed_version?;
    match parse_major_minor(&found) {
        Some(v) if v < (3, 2) => Some(Error::GlVersionTooLow { found }),
        _ => None,
    }
}
