//! # deferred-msaa-lab
//!
//! The lab on top of [`deferred_msaa`], the core a host engine links: a demo
//! deferred renderer written as a host of the retrofit ([`renderer`]) with
//! its scene-adaptive plan ([`renderer::plan`]), built-in scenes and glTF loading
//! ([`scene`]), the image measures ([`compare`]), the error-against-time
//! benchmark ([`bench`](mod@bench)), the per-sample dump ([`dump`]) and the
//! `deferred-msaa` command line ([`cli`]). Headless contexts come from
//! [`deferred_msaa_headless`], re-exported as [`context`].
//!
//! The core's modules are re-exported under their own names, so that the
//! lab, its tests and its tools name one path for each thing; a host needs
//! none of this crate.
#![warn(missing_docs)]

pub mod bench;
pub mod cli;
pub mod compare;
pub mod dump;
pub mod error;
pub mod renderer;
pub mod scene;

pub use deferred_msaa::{frame, gbuffer, gl, readback, resolve, retrofit, second_layer};
pub use deferred_msaa_headless as context;
pub use error::{Error, Result};
