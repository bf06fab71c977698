//! GPU timing: `GL_TIME_ELAPSED` queries where the context has them,
//! otherwise `glFinish`-bracketed wall time.

use super::counters::{self, Kind};
use crate::{Error, Result};
use glow::HasContext;
use std::time::Instant;

/// How a measurement was taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum TimerKind {
    /// `GL_TIME_ELAPSED` query (GL 3.3 or ARB_timer_query).
    GlTimeElapsed,
    /// Wall-clock time between two `glFinish` calls.
    FinishWallClock,
}

impl TimerKind {
    /// The name written into reports.
    pub fn name(self) -> &'static str {
        match self {
            TimerKind::GlTimeElapsed => "gl-time-elapsed",
            TimerKind::FinishWallClock => "finish-wall-clock",
        }
    }
}

/// Measures one stretch of GL work at a time.
#[derive(Debug)]
pub struct GpuTimer {
    pub(crate) query: Option<glow::Query>,
    started: Option<Instant>,
    kind: TimerKind,
}

impl GpuTimer {
    /// A timer with a query object where the context has a trustworthy one,
    /// else (or with `force_wall_clock`) `glFinish`-bracketed wall time.
    /// Software rasterisers get wall time: llvmpipe restarts `GL_TIME_ELAPSED`
    /// at every tile a thread rasterises, so its query spans only the last tiles.
    pub fn new(gl: &glow::Context, force_wall_clock: bool) -> Result<Self> {
        let v = gl.version();
        let renderer = unsafe { gl.get_parameter_string(glow::RENDERER) }.to_ascii_lowercase();
        let software = ["llvmpipe", "softpipe", "swrast", "swr"]
            .iter()
            .any(|s| renderer.contains(s));
        let has_query = !software
            && ((v.major, v.minor) >= (3, 3)
                || gl.supported_extensions().contains("GL_ARB_timer_query"));
        if has_query && !force_wall_clock {
            let query = unsafe { gl.create_query() }.map_err(|reason| Error::Create {
                what: "timer query".into(),
                reason,
            })?;
            counters::created(Kind::Query);
            Ok(GpuTimer {
                query: Some(query),
                started: None,
                kind: TimerKind::GlTimeElapsed,
            })
        } else {
            Ok(GpuTimer {
                query: None,
                started: None,
                kind: TimerKind::FinishWallClock,
            })
        }
    }

    /// How this timer measures.
    pub fn kind(&self) -> TimerKind {
        self.kind
    }

    /// Start measuring.
    pub fn begin(&mut self, gl: &glow::Context) {
        match self.query {
            Some(q) => unsafe { gl.begin_query(glow::TIME_ELAPSED, q) },
            None => {
                unsafe { gl.finish() };
                self.started = Some(Instant::now());
            }
        }
    }

    /// Stop measuring and return the milliseconds spent (waits for the result).
    pub fn end(&mut self, gl: &glow::Context) -> f64 {
        match self.query {
            Some(q) => unsafe {
                gl.end_query(glow::TIME_ELAPSED);
                let ns = gl.get_query_parameter_u64(q, glow::QUERY_RESULT);
                ns as f64 / 1.0e6
            },
            None => {
                unsafe { gl.finish() };
                self.started
                    .take()
                    .map_or(0.0, |t| t.elapsed().as_secs_f64() * 1000.0)
            }
        }
    }

    /// Free the query object.
    pub fn destroy(self, gl: &glow::Context) {
        if let Some(q) = self.query {
            unsafe { gl.delete_query(q) };
            counters::destroyed(Kind::Query);
        }
    }
}

/// A `GL_SAMPLES_PASSED` occlusion query: counts the samples a stretch of
/// drawing lets through.
#[derive(Debug)]
pub struct SamplesPassedQuery {
    pub(crate) raw: glow::Query,
}

impl SamplesPassedQuery {
    /// Create the query object.
    pub fn new(gl: &glow::Context) -> Result<Self> {
        let raw = unsafe { gl.create_query() }.map_err(|reason| Error::Create {
            what: "samples-passed query".into(),
            reason,
        })?;
        counters::created(Kind::Query);
        Ok(SamplesPassedQuery { raw })
    }

    /// Start counting.
    pub fn begin(&self, gl: &glow::Context) {
        unsafe { gl.begin_query(glow::SAMPLES_PASSED, self.raw) };
    }

    /// Stop counting.
    pub fn end(&self, gl: &glow::Context) {
        unsafe { gl.end_query(glow::SAMPLES_PASSED) };
    }

    /// The count of the last begin/end pair (waits for the GPU).
    pub fn result(&self, gl: &glow::Context) -> u64 {
        u64::from(unsafe { gl.get_query_parameter_u32(self.raw, glow::QUERY_RESULT) })
    }

    /// Free the query object.
    pub fn destroy(self, gl: &glow::Context) {
        unsafe { gl.delete_query(self.raw) };
        counters::destroyed(Kind::Query);
    }
}
