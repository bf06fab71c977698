//! # deferred-msaa
//!
//! Depth-aware multi-sample anti-aliasing for OpenGL 3.2+ deferred renderers.
#![warn(missing_docs)]

pub mod cli;
pub mod compare;
pub mod context;
pub mod gl;
pub mod dump;
pub mod error;
pub mod gbuffer;
pub mod readback;
pub mod renderer;
pub mod resolve;
pub mod retrofit;
pub mod scene;

pub use error::{Error, Result};
