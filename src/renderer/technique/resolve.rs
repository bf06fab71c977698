//! The resolve methods (`average`, `front`, `median`, `back`;
//! [`AaMode::Resolve`]): the G-buffer pass draws into the retrofit's
//! multisampled twins, which [`MsaaRetrofit::resolve`] writes back into the
//! G-buffer; lighting is per pixel.

use super::{ComplexPixelsInput, Technique, resolve_twins};
use crate::Result;
use crate::frame::Frame as ResolveFrame;
use crate::gl::GpuTimer;
use crate::renderer::{AaMode, slow_path};
use crate::retrofit::MsaaRetrofit;
use std::any::Any;

/// The depth-aware resolve of the multisampled G-buffer.
#[derive(Debug)]
pub(crate) struct Resolve;

impl Technique for Resolve {
    fn renders(&self, aa: &AaMode) -> bool {
        matches!(aa, AaMode::Resolve(_))
    }

    fn after_geometry(
        &self,
        gl: &glow::Context,
        retrofit: Option<&mut MsaaRetrofit>,
        resolve_frame: &ResolveFrame,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        resolve_twins(gl, retrofit, resolve_frame, timer)
    }

    /// The pixels the resolve took its slow path on, found by running the
    /// last frame's resolve again into a scratch mask.
    fn complex_pixels(
        &self,
        gl: &glow::Context,
        input: ComplexPixelsInput<'_>,
    ) -> Result<Option<image::GrayImage>> {
        let Some(retrofit) = input.retrofit else {
            return Ok(None);
        };
        slow_path::slow_path_mask(gl, retrofit, &input.resolve_frame).map(Some)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, _gl: &glow::Context) {}
}
