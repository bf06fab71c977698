//! A per-step profile of the retrofit's passes: each step timed on the
//! wall clock between two `glFinish` calls. The finishes stall the
//! pipeline, so a profiled frame is slower than a plain one and only the
//! steps' shares mean anything; profiling is off unless asked for
//! ([`crate::MsaaRetrofit::set_profiling`]), and costs nothing then.

use glow::HasContext;
use std::time::Instant;

/// The steps of the last profiled frame, in the order they ran.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepProfile {
    enabled: bool,
    steps: Vec<(&'static str, f64)>,
}

impl StepProfile {
    /// Whether steps are being timed.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// The timed steps: a name and milliseconds each, in the order they
    /// ran since the profile was last cleared.
    pub fn steps(&self) -> &[(&'static str, f64)] {
        &self.steps
    }

    /// Run `step`; when profiling, time it as `name` between two
    /// `glFinish` calls. A host may time its own passes into the same
    /// profile (its lighting between the second-layer calls, say).
    pub fn time<T>(
        &mut self,
        gl: &glow::Context,
        name: &'static str,
        step: impl FnOnce() -> T,
    ) -> T {
        if !self.enabled {
            return step();
        }
        unsafe { gl.finish() };
        let start = Instant::now();
        let result = step();
        unsafe { gl.finish() };
        self.steps.push((name, start.elapsed().as_secs_f64() * 1e3));
        result
    }

    /// Turn timing on or off; either way the steps recorded so far go.
    pub(crate) fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
        self.steps.clear();
    }

    /// Forget the steps recorded so far (a new frame begins).
    pub(crate) fn clear(&mut self) {
        self.steps.clear();
    }
}
