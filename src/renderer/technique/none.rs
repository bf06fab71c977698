//! Method `none` ([`AaMode::None`]): the G-buffer pass draws straight into
//! the single-sample G-buffer and every step is the frame's default.

use super::Technique;
use crate::renderer::AaMode;
use std::any::Any;

/// No anti-aliasing.
#[derive(Debug)]
pub(crate) struct NoAntialiasing;

impl Technique for NoAntialiasing {
    fn renders(&self, aa: &AaMode) -> bool {
        *aa == AaMode::None
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, _gl: &glow::Context) {}
}
