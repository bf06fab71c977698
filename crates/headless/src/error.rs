//! The headless layer's error type.

/// Result alias of the headless layer.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong while making a headless context.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A context backend could not be loaded or initialised.
    #[error("{backend} backend unavailable: {reason}")]
    BackendUnavailable {
        /// `egl` or `osmesa`.
        backend: &'static str,
        /// What failed, and what to install or try instead.
        reason: String,
    },

    /// The context offers less than the OpenGL 3.2 core floor.
    #[error(
        "OpenGL {found} is below the supported floor: OpenGL 3.2 core profile and GLSL 1.50 are required"
    )]
    GlVersionTooLow {
        /// The version string the driver reported.
        found: String,
    },

    /// The driver refused to create or bind a context or display.
    #[error("could not create {what}: {reason}")]
    Create {
        /// The kind of object.
        what: String,
        /// The driver's words.
        reason: String,
    },

    /// A version or backend request outside what is accepted.
    #[error("{0}")]
    InvalidArgument(String),
}

impl Error {
    /// Shorthand for an [`Error::InvalidArgument`].
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::InvalidArgument(message.into())
    }
}
