//! The lab's error type: the core's and the headless layer's errors, and
//! what only the lab can meet (scenes, files, images).

use std::path::PathBuf;

/// Result alias used throughout the lab.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the lab: the renderer, scenes, the bench,
/// the CLI.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An error of the core (GL objects, the resolve, the retrofit).
    #[error(transparent)]
    Core(#[from] deferred_msaa::Error),

    /// A headless context could not be made.
    #[error(transparent)]
    Context(#[from] deferred_msaa_headless::Error),

    /// A scene could not be loaded.
    #[error("{}: {reason}", path.display())]
    Scene {
        /// The file, or `builtin:NAME`.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },

    /// A size, count or option outside what is accepted.
    #[error("{0}")]
    InvalidArgument(String),

    /// A G-buffer layout or plan that cannot work.
    #[error("invalid G-buffer layout: {0}")]
    Layout(String),

    /// A bar's width could not be measured (the bench's bar width error).
    #[error(transparent)]
    BarWidth(#[from] crate::bench::bar_width::BarWidthError),

    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },

    /// An image could not be encoded or decoded.
    #[error("{}: {source}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// The codec error.
        source: image::ImageError,
    },
}

impl Error {
    /// Shorthand for an [`Error::InvalidArgument`].
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::InvalidArgument(message.into())
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// The core's error inside, if this is one.
    pub fn core(&self) -> Option<&deferred_msaa::Error> {
        match self {
            Error::Core(e) => Some(e),
            _ => None,
        }
    }
}
