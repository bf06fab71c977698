//! # deferred-msaa
//!
//! Depth-aware multi-sample anti-aliasing for OpenGL 3.2+ deferred renderers.
#![warn(missing_docs)]

pub mod context;
pub mod error;
pub mod resolve;
pub mod scene;

pub use error::{Error, Result};
