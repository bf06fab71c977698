//! Method `none` ([`AaMode::None`]): the G-buffer pass draws straight into
//! the single-sample G-buffer and every step is the frame's default.

use super::contract::Technique;
use super::kind::no_options;
use crate::Result;
use crate::renderer::options::AaMode;
use std::any::Any;

/// No anti-aliasing.
#[derive(Debug)]
pub(crate) struct NoAntialiasing;

impl Technique for NoAntialiasing {
    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, _gl: &glow::Context) {}
}

/// What is known of `none` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["none"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        *aa == AaMode::None
    }

    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        no_options(method, options, spec)?;
        Ok(AaMode::None)
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(NoAntialiasing)
    }
}
