//! Timing one step of the frame with the renderer's GPU timer.

use crate::Result;
use crate::gl::GpuTimer;

/// Run `f` between a timer's begin and end; the milliseconds it took.
pub(crate) fn timed(
    gl: &glow::Context,
    timer: &mut GpuTimer,
    f: impl FnOnce() -> Result<()>,
) -> Result<f64> {
    timer.begin(gl);
    let result = f();
    let ms = timer.end(gl);
    result.map(|()| ms)
}
