//! Thin owned wrappers over glow.
//!
//! Every GL object is a plain struct holding its glow handle; it is freed
//! explicitly with `destroy(self, gl)`, never on drop, because the library
//! runs inside the host's context and cannot know whether that context is
//! current when a value goes out of scope. Live-object counters
//! ([`live_objects`]) let tests prove that nothing leaks.
//!
//! The chores every pass repeats live here once: [`RenderTarget`] (textures
//! and their framebuffer), [`Made`] (what a failed constructor made is
//! destroyed), [`FullscreenPass`] and [`ShaderSource`] (parts with `#line`
//! numbering, so compile errors name a part's file and line).

mod buffer;
mod caps;
mod counters;
mod debug;
pub mod format;
mod framebuffer;
mod functions;
mod made;
mod pass;
mod program;
mod query;
mod samples;
mod source;
mod state;
mod target;
mod texture;

pub use buffer::{Buffer, VertexArray};
pub(crate) use caps::output_points;
pub use caps::{Capabilities, ExtraFns, sample_positions};
pub use counters::{LiveObjects, live_objects};
pub use debug::{install_debug_log, label_object};
pub use format::Format;
pub use framebuffer::{
    Attachment, ColorAttachment, Framebuffer, HostImage, framebuffer_status_name,
};
pub use functions::{
    CONDITIONAL_FUNCTIONS, REQUIRED_FUNCTIONS, first_missing_conditional_function,
    first_missing_function,
};
pub use made::{GlObject, Handle, Made, Owned, destroy_object};
pub use pass::{FullscreenPass, draw_fullscreen_triangle};
pub use program::{Program, ShaderStage, preamble};
pub use query::{GpuTimer, SamplesPassedQuery, TimerKind};
pub use source::{HEADER_NAME, ShaderSource};
pub use state::{DrawBufferState, Guard, Restore, SavedState, SetupState, load_state_functions};
pub use target::{RenderTarget, TargetTexture};
pub use texture::{Texture2d, Texture2dArray, Texture2dMultisample, TextureRef};

use crate::{Error, Result};

/// The full-screen triangle's vertex shader body (no vertex attributes:
/// `gl_VertexID` places the three corners).
pub const FULLSCREEN_VERT: &str = include_str!("fullscreen.vert");
use glow::HasContext;

/// The name of a `glGetError` code.
pub fn error_name(code: u32) -> &'static str {
    match code {
        glow::INVALID_ENUM => "GL_INVALID_ENUM",
        glow::INVALID_VALUE => "GL_INVALID_VALUE",
        glow::INVALID_OPERATION => "GL_INVALID_OPERATION",
        glow::INVALID_FRAMEBUFFER_OPERATION => "GL_INVALID_FRAMEBUFFER_OPERATION",
        glow::OUT_OF_MEMORY => "GL_OUT_OF_MEMORY",
        glow::STACK_OVERFLOW => "GL_STACK_OVERFLOW",
        glow::STACK_UNDERFLOW => "GL_STACK_UNDERFLOW",
        _ => "unknown GL error",
    }
}

/// Drain `glGetError`; the first error found becomes an [`Error::Gl`] naming `stage`.
pub fn check_error(gl: &glow::Context, stage: &str) -> Result<()> {
    let mut first = None;
    // A context may queue several flags; drain them all so the next check starts clean.
    for _ in 0..16 {
        let code = unsafe { gl.get_error() };
        if code == glow::NO_ERROR {
            break;
        }
        first.get_or_insert(code);
    }
    match first {
        None => Ok(()),
        Some(code) => Err(Error::Gl {
            stage: stage.to_string(),
            code,
            code_name: error_name(code),
        }),
    }
}
