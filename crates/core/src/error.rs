//! The core's error type.
//!
//! Every variant carries enough context to act on: the stage, the object or
//! attachment name, the driver's own words. `Display` is a single line for
//! everything a user can cause (bad input, unsupported capabilities); shader
//! build failures add the driver log and the numbered source lines around
//! the offending ones, because that is what a shader author needs.

/// Result alias used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in `deferred-msaa`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A feature needs a newer GL version or an extension the context lacks.
    #[error("{feature} needs {requires}, which this context ({found}) does not offer")]
    Unsupported {
        /// What was asked for.
        feature: String,
        /// The version or extension it needs.
        requires: String,
        /// What the context has.
        found: String,
    },

    /// A sample count the driver does not offer for a format.
    #[error(
        "{requested}x MSAA is not supported for {format}; the driver offers {}",
        fmt_counts(supported)
    )]
    UnsupportedSampleCount {
        /// The count that was asked for.
        requested: u32,
        /// The internal format's name.
        format: String,
        /// The counts the driver offers for it.
        supported: Vec<u32>,
    },

    /// An internal format the crate cannot use for this purpose.
    #[error("attachment `{attachment}`: format {format} is not supported ({reason})")]
    UnsupportedFormat {
        /// The attachment it was declared for.
        attachment: String,
        /// The format's name (or its GL enum in hex when unknown).
        format: String,
        /// Why, and what is supported instead.
        reason: String,
    },

    /// A GL object could not be created.
    #[error("could not create {what}: {reason}")]
    Create {
        /// The kind of object and its label.
        what: String,
        /// The driver's words.
        reason: String,
    },

    /// A framebuffer is not complete.
    #[error("framebuffer `{label}` is incomplete: {status}")]
    FramebufferIncomplete {
        /// The framebuffer's debug label.
        label: String,
        /// The status enum's name, e.g. `GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE`.
        status: &'static str,
    },

    /// A shader stage failed to compile.
    #[error("{stage} shader `{name}` failed to compile:\n{log}\n{excerpt}")]
    ShaderCompile {
        /// `vertex`, `geometry`, `fragment` or `compute`.
        stage: &'static str,
        /// The shader's file name or label.
        name: String,
        /// The driver's info log.
        log: String,
        /// The offending source lines with their numbers.
        excerpt: String,
    },

    /// A program failed to link.
    #[error("program `{name}` failed to link:\n{log}")]
    ProgramLink {
        /// The program's label.
        name: String,
        /// The driver's info log.
        log: String,
    },

    /// `glGetError` reported an error after a stage.
    #[error("GL error {code_name} (0x{code:04X}) during {stage}")]
    Gl {
        /// What was being done.
        stage: String,
        /// The raw error code.
        code: u32,
        /// Its name, e.g. `GL_OUT_OF_MEMORY`.
        code_name: &'static str,
    },

    /// A host framebuffer cannot be retrofitted as it is.
    #[error("cannot retrofit host framebuffer, attachment `{attachment}`: {reason}")]
    Retrofit {
        /// The attachment point, e.g. `GL_COLOR_ATTACHMENT2` or `GL_DEPTH_ATTACHMENT`.
        attachment: String,
        /// Why, and what is needed instead.
        reason: String,
    },

    /// A G-buffer would take more memory than its budget allows
    /// ([`MemoryBudget`](crate::gbuffer::MemoryBudget)), and no lower sample
    /// count fits or stepping down was refused (strict).
    #[error(
        "the G-buffer needs {} at {samples}x, over the memory budget of {}; allow more memory, fewer samples or a smaller size",
        crate::gbuffer::fmt_bytes(*needed),
        crate::gbuffer::fmt_bytes(*budget)
    )]
    MemoryBudget {
        /// Bytes the G-buffer would take at `samples`.
        needed: u64,
        /// The budget in bytes.
        budget: u64,
        /// The sample count asked for (as the driver rounds it).
        samples: u32,
    },

    /// A G-buffer layout that cannot work.
    #[error("invalid G-buffer layout: {0}")]
    Layout(String),

    /// A size, count or option outside what is accepted.
    #[error("{0}")]
    InvalidArgument(String),

    /// The host's own GL calls before a call of the crate left an error
    /// pending: the crate did nothing with the frame, which may not be the
    /// one the host meant to draw.
    #[error(
        "the host's GL calls before the resolve left {code_name} (0x{code:04X}) pending, so the multisampled twins may not hold the frame it drew (a geometry pass that failed to bind its framebuffer, say): nothing was resolved; find the failing call with glGetError or KHR_debug"
    )]
    HostGl {
        /// The raw error code.
        code: u32,
        /// Its name, e.g. `GL_INVALID_OPERATION`.
        code_name: &'static str,
    },

    /// The host's second lighting (two layers) did not light the second
    /// layer: what it drew, and how to set it up instead.
    #[error("{0}")]
    SecondLighting(String),

    /// `resolve` without `begin_frame` since the last `resolve` (or since
    /// `refresh`): the crate cannot know the twins were cleared for this
    /// frame.
    #[error(
        "resolve was called without begin_frame since the last resolve{since}: call MsaaRetrofit::begin_frame (C dmsaa_begin_frame) at the start of every frame, before the geometry pass clears and draws into the framebuffer it returns; nothing was resolved"
    )]
    FrameNotBegun {
        /// `""`, or `" or refresh"` where new twins were made since.
        since: &'static str,
    },

    /// The multisampled twins were not cleared between `begin_frame` and
    /// `resolve`: their depth still holds the value `begin_frame` put
    /// there over much of the frame.
    #[error(
        "{pixels} of {total} pixels of the multisampled G-buffer were not cleared between begin_frame and resolve{when} (their depth still holds the value begin_frame put there), so the geometry pass drew against stale depth and the frame would be black or stale; {}: clear through the framebuffer begin_frame returns (MsaaRetrofit::framebuffer, dmsaa_begin_frame's) after begin_frame, as the host cleared its own G-buffer, or declare the host's clear values in RetrofitOptions::twin_clear (C: DmsaaOptions::clear_twins = 1 with clear_colors, clear_depth and clear_stencil) for begin_frame to clear to; docs/hosts.md, \"Clears and wrappers\"",
        if *last_frame { "this frame was not resolved" } else { "nothing was resolved" },
        when = if *last_frame { " in the last frame" } else { "" }
    )]
    TwinsNotCleared {
        /// Pixels whose depth still held the sentinel.
        pixels: u64,
        /// Pixels of the frame.
        total: u64,
        /// Whether the count is the last frame's (read a frame late so that
        /// no frame waits on the GPU).
        last_frame: bool,
    },

    /// Two lit layers (or the forward target's samples) would be mixed in
    /// a floating-point output with [`LayerMix::Auto`](crate::LayerMix::Auto):
    /// the right domain is the host's tonemap, which GL state cannot tell.
    #[error(
        "the lit output is {format}, whose tonemap GL state cannot tell, so LayerMix::Auto does not know how to mix it: declare `layer_mix` (C `DmsaaOptions::layer_mix`): LayerMix::Curve with the host's tonemap and its inverse (DMSAA_LAYER_MIX_CURVE; for a linear tonemap that clamps, `clamp(x * exposure, 0, 1)` and `y / exposure`), LayerMix::Tonemapped for a Reinhard-like tonemap (DMSAA_LAYER_MIX_TONEMAPPED), or LayerMix::Linear where the values reach the screen as they are, never clamped (DMSAA_LAYER_MIX_LINEAR); docs/hosts.md, \"Per engine style\""
    )]
    LayerMixUndeclared {
        /// The output's format, e.g. `RGBA16F`.
        format: &'static str,
    },
}

fn fmt_counts(counts: &[u32]) -> String {
    if counts.is_empty() {
        return "no multisampling".to_string();
    }
    let list: Vec<String> = counts.iter().map(|c| format!("{c}x")).collect();
    list.join(", ")
}

impl Error {
    /// Shorthand for an [`Error::InvalidArgument`].
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::InvalidArgument(message.into())
    }
}
