//! The check that the host's second lighting drew: a lighting pass left
//! with its depth or stencil test on against what its first run wrote (the
//! most-copied tutorial lights a full-screen quad into framebuffer 0 with
//! its depth test on) is rejected at every pixel, and the mix would then be
//! the first layer alone with every call returning OK.
//!
//! Three `GL_SAMPLES_PASSED` queries: one around a pass of the crate's own
//! that counts the pixels with a second layer (coverage above 0), one
//! around the host's first lighting (from the end of `resolve` to the start
//! of `begin_second_layer`), one around its second lighting (from the end of
//! `begin_second_layer` to the start of `finish_second_layer`). A frame
//! where pixels were selected and the first lighting drew but the second
//! passed no sample is an error. A lighting that draws no fragments at all
//! (a compute pass, clears, copies) passes none either time and is not
//! judged. The first check waits for its result, so a host set up wrongly
//! hears of it on its first frame; later checks read a result only once
//! the GPU has it, and otherwise at the next `resolve`, so that no frame
//! stalls on it.

use crate::gl::{GlObject, Handle, SamplesPassedQuery};
use crate::{Error, Result};
use glow::HasContext;

/// Where the check is in its frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Nothing counted since the last result.
    Idle,
    /// The selected pixels are counted; the host's first lighting is
    /// being counted.
    FirstLighting,
    /// Both counts ended; the second lighting is not begun.
    Lit,
    /// The host's second lighting is being counted.
    SecondLighting,
    /// Every count ended; the second lighting's result is not read yet.
    Pending,
}

/// The three queries and where they are (see the module).
#[derive(Debug)]
pub(crate) struct LightingCheck {
    selected: SamplesPassedQuery,
    first: SamplesPassedQuery,
    second: SamplesPassedQuery,
    stage: Stage,
    /// A result was read once: from then on results are not waited for.
    waited: bool,
}

impl GlObject for LightingCheck {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.selected.handles(out);
        self.first.handles(out);
        self.second.handles(out);
    }
}

/// Begin `query`; `false` (and the error it raised cleared) where the host
/// has an occlusion query of its own active, which GL allows one of.
fn try_begin(gl: &glow::Context, query: &SamplesPassedQuery) -> bool {
    query.begin(gl);
    // The crate's calls leave no error behind them, so one here is this
    // call's: another occlusion query is active.
    unsafe { gl.get_error() == glow::NO_ERROR }
}

impl LightingCheck {
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        crate::gl::Made::build(gl, |made| {
            Ok(LightingCheck {
                selected: made.keep(SamplesPassedQuery::new(gl)?),
                first: made.keep(SamplesPassedQuery::new(gl)?),
                second: made.keep(SamplesPassedQuery::new(gl)?),
                stage: Stage::Idle,
                waited: false,
            })
        })
    }

    /// Count the pixels `draw` lets through (the crate's pass over the
    /// second layer's coverage), then begin counting the host's first
    /// lighting; a result still pending from the last frame is checked
    /// first (waiting for it: it is a frame old).
    pub(crate) fn count_selected(&mut self, gl: &glow::Context, draw: impl FnOnce()) -> Result<()> {
        self.end_first(gl);
        let last = self.settle(gl, true);
        self.stage = Stage::Idle;
        if try_begin(gl, &self.selected) {
            draw();
            self.selected.end(gl);
            if try_begin(gl, &self.first) {
                self.stage = Stage::FirstLighting;
            }
        }
        last
    }

    /// Stop counting the host's first lighting (the start of
    /// `begin_second_layer`, before the crate draws anything, or of any
    /// other call that draws: the count is the host's alone).
    pub(crate) fn end_first(&mut self, gl: &glow::Context) {
        if self.stage == Stage::FirstLighting {
            self.first.end(gl);
            self.stage = Stage::Lit;
        }
    }

    /// The host's second lighting starts (the end of `begin_second_layer`).
    pub(crate) fn lighting_begins(&mut self, gl: &glow::Context) {
        self.end_first(gl);
        if self.stage == Stage::Lit {
            self.stage = if try_begin(gl, &self.second) {
                Stage::SecondLighting
            } else {
                Stage::Idle
            };
        }
    }

    /// The host's second lighting ended (the start of
    /// `finish_second_layer`): its count is checked, now if the result is
    /// there (or this is the first check), else at the next `resolve`.
    pub(crate) fn lighting_ends(&mut self, gl: &glow::Context) -> Result<()> {
        if self.stage != Stage::SecondLighting {
            return Ok(());
        }
        self.second.end(gl);
        self.stage = Stage::Pending;
        let wait = !self.waited;
        self.settle(gl, wait)
    }

    /// A frame that began a count but will not light again (an error
    /// between): the count is dropped.
    pub(crate) fn abandon(&mut self, gl: &glow::Context) {
        self.end_first(gl);
        if self.stage == Stage::SecondLighting {
            self.second.end(gl);
        }
        self.stage = Stage::Idle;
    }

    /// Read a pending result when it is there, or when `wait`.
    fn settle(&mut self, gl: &glow::Context, wait: bool) -> Result<()> {
        if self.stage != Stage::Pending {
            return Ok(());
        }
        let available = wait
            || unsafe { gl.get_query_parameter_u32(self.second.raw, glow::QUERY_RESULT_AVAILABLE) }
                != 0;
        if !available {
            return Ok(());
        }
        self.stage = Stage::Idle;
        self.waited = true;
        let selected = self.selected.result(gl);
        let first = self.first.result(gl);
        let second = self.second.result(gl);
        if selected > 0 && first > 0 && second == 0 {
            return Err(Error::SecondLighting(format!(
                "the host's second lighting drew no sample into its target, where its first lighting drew {first} and {selected} pixels have a second layer: \
                 a depth or stencil test left on from the first lighting rejected it (the first lighting wrote depth or stencil \
                 into the lit target). Clear the lit target's depth and stencil before the second lighting as before the first \
                 (repeat the lighting pass's own glClear), disable those tests in the lighting pass, or light into \
                 begin_second_layer_own_target's framebuffer (dmsaa_begin_second_layer_own_target), which the crate prepares"
            )));
        }
        Ok(())
    }
}
