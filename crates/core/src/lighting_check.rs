//! The check that the host's second lighting drew: a lighting pass left
//! with its depth or stencil test on against what its first run wrote (the
//! most-copied tutorial lights a full-screen quad into framebuffer 0 with
//! its depth test on) is rejected at every pixel, and the mix would then be
//! the first layer alone with every call returning OK.
//!
//! Two `GL_SAMPLES_PASSED` queries: one around a pass of the crate's own
//! that counts the pixels with a second layer (coverage above 0), one
//! around the host's second lighting, from the end of
//! `begin_second_layer` to the start of `finish_second_layer`. A frame
//! whose lighting passed no sample where pixels were selected is an error.
//! The first check waits for its result, so a host set up wrongly hears of
//! it on its first frame; later checks read a result only once the GPU has
//! it, and otherwise at the next `resolve`, so that no frame stalls on it.

use crate::gl::{GlObject, Handle, SamplesPassedQuery};
use crate::{Error, Result};
use glow::HasContext;

/// Where the check is in its frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Nothing counted since the last result.
    Idle,
    /// The selected pixels are counted; the lighting is not yet.
    Selected,
    /// The host's second lighting is being counted.
    Lighting,
    /// Both counts ended; the lighting's result is not read yet.
    Pending,
}

/// The two queries and where they are (see the module).
#[derive(Debug)]
pub(crate) struct LightingCheck {
    selected: SamplesPassedQuery,
    lit: SamplesPassedQuery,
    stage: Stage,
    /// A result was read once: from then on results are not waited for.
    waited: bool,
}

impl GlObject for LightingCheck {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.selected.handles(out);
        self.lit.handles(out);
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
        let selected = SamplesPassedQuery::new(gl)?;
        let lit = match SamplesPassedQuery::new(gl) {
            Ok(q) => q,
            Err(e) => {
                selected.destroy(gl);
                return Err(e);
            }
        };
        Ok(LightingCheck {
            selected,
            lit,
            stage: Stage::Idle,
            waited: false,
        })
    }

    /// Count the pixels `draw` lets through (the crate's pass over the
    /// second layer's coverage), for this frame's check; a result still
    /// pending from the last frame is checked first.
    pub(crate) fn count_selected(&mut self, gl: &glow::Context, draw: impl FnOnce()) -> Result<()> {
        let last = self.settle(gl, true);
        if try_begin(gl, &self.selected) {
            draw();
            self.selected.end(gl);
            self.stage = Stage::Selected;
        } else {
            self.stage = Stage::Idle;
        }
        last
    }

    /// The host's second lighting starts (the end of `begin_second_layer`).
    pub(crate) fn lighting_begins(&mut self, gl: &glow::Context) {
        if self.stage == Stage::Selected {
            self.stage = if try_begin(gl, &self.lit) {
                Stage::Lighting
            } else {
                Stage::Idle
            };
        }
    }

    /// The host's second lighting ended (the start of
    /// `finish_second_layer`): its count is checked, now if the result is
    /// there (or this is the first check), else at the next `resolve`.
    pub(crate) fn lighting_ends(&mut self, gl: &glow::Context) -> Result<()> {
        if self.stage != Stage::Lighting {
            return Ok(());
        }
        self.lit.end(gl);
        self.stage = Stage::Pending;
        let wait = !self.waited;
        self.settle(gl, wait)
    }

    /// A frame that began the count but will not light (an error between):
    /// the count is dropped.
    pub(crate) fn abandon(&mut self, gl: &glow::Context) {
        if self.stage == Stage::Lighting {
            self.lit.end(gl);
        }
        self.stage = Stage::Idle;
    }

    /// Read a pending result when it is there, or when `wait`.
    fn settle(&mut self, gl: &glow::Context, wait: bool) -> Result<()> {
        if self.stage != Stage::Pending {
            self.stage = Stage::Idle;
            return Ok(());
        }
        let available = wait
            || unsafe { gl.get_query_parameter_u32(self.lit.raw, glow::QUERY_RESULT_AVAILABLE) }
                != 0;
        if !available {
            return Ok(());
        }
        self.stage = Stage::Idle;
        self.waited = true;
        let selected = self.selected.result(gl);
        let lit = self.lit.result(gl);
        if selected > 0 && lit == 0 {
            return Err(Error::SecondLighting(format!(
                "the host's second lighting drew no sample into its target, where {selected} pixels have a second layer: \
                 a depth or stencil test left on from the first lighting rejected it (the first lighting wrote depth or stencil \
                 into the lit target). Clear the lit target's depth and stencil before the second lighting as before the first \
                 (repeat the lighting pass's own glClear), disable those tests in the lighting pass, or light into \
                 begin_second_layer_own_target's framebuffer (dmsaa_begin_second_layer_own_target), which the crate clears"
            )));
        }
        Ok(())
    }
}
