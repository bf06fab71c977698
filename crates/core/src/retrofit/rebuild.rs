//! Changing a retrofit after it is made: new options, a new sample count,
//! or the host's framebuffer re-read after it re-allocated its textures.

use super::checks::{clear_host_errors, settle};
use super::options::RetrofitOptions;
use super::{Built, MsaaRetrofit};
use crate::Result;
use crate::gl::{Owned, SetupState, destroy_object};

impl MsaaRetrofit {
    /// Change the options. Only what they change is rebuilt: the twins
    /// when the sample count, budget, rules, key, stencil copy, layer
    /// count, normal attachment or layer mix change (the host draws into
    /// the new twins); the programs whenever the resolve's permutation
    /// changes. On error the retrofit keeps working with the options it had.
    pub fn set_options(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        clear_host_errors(gl);
        let host = SetupState::capture(gl).guard(gl);
        let result = self.change_options(gl, options);
        drop(host);
        settle(gl, "changing the options", result)
    }

    fn change_options(&mut self, gl: &glow::Context, options: &RetrofitOptions) -> Result<()> {
        let twins_change = options.samples != self.options.samples
            || options.memory_budget != self.options.memory_budget
            || options.rules != self.options.rules
            || options.position_attachment != self.options.position_attachment
            || options.position_space != self.options.position_space
            || options.stencil != self.options.stencil
            || options.normal_attachment != self.options.normal_attachment
            || options.layer_mix != self.options.layer_mix
            || options.check_second_lighting != self.options.check_second_lighting
            || options.second_layer_omits != self.options.second_layer_omits
            || options.resolve.layers != self.options.resolve.layers;
        if twins_change {
            return self.rebuild(gl, self.host.fbo, options);
        }
        let previous = self.options.clone();
        self.options = options.clone();
        if let Err(e) = self.prepare(gl) {
            self.options = previous;
            return Err(e);
        }
        Ok(())
    }

    /// Re-read the host framebuffer (after the host resized or re-allocated
    /// its textures) and rebuild the twins. The old twins are freed only once
    /// the new ones exist, so a failure leaves the retrofit working as before.
    ///
    /// Errors: those of [`MsaaRetrofit::new`]; [`Error::InvalidArgument`](crate::Error::InvalidArgument)
    /// when the host's framebuffer itself was deleted (then
    /// [`MsaaRetrofit::refresh_with`] takes its new one).
    pub fn refresh(&mut self, gl: &glow::Context) -> Result<()> {
        let options = self.options.clone();
        self.rebuild(gl, self.host.fbo, &options)
    }

    /// [`MsaaRetrofit::refresh`] for a host that made its G-buffer anew
    /// under another framebuffer name (deleted the old one and generated a
    /// new one, on a resize, say): the retrofit reads `host_fbo` from now
    /// on and rebuilds its twins, second layer and forward target for it,
    /// keeping its options and compiled programs. On error the retrofit is
    /// as it was.
    ///
    /// Errors: those of [`MsaaRetrofit::new`] for `host_fbo`.
    pub fn refresh_with(&mut self, gl: &glow::Context, host_fbo: glow::Framebuffer) -> Result<()> {
        let options = self.options.clone();
        self.rebuild(gl, host_fbo, &options)
    }

    /// Change the sample count: [`MsaaRetrofit::set_options`] with only
    /// `samples` changed.
    pub fn set_samples(&mut self, gl: &glow::Context, samples: u32) -> Result<()> {
        let options = RetrofitOptions {
            samples,
            ..self.options.clone()
        };
        self.rebuild(gl, self.host.fbo, &options)
    }

    fn rebuild(
        &mut self,
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<()> {
        clear_host_errors(gl);
        if host_fbo == self.host.fbo {
            crate::host::check_alive(gl, host_fbo)?;
        }
        let host = SetupState::capture(gl).guard(gl);
        let result = self.rebuild_within(gl, host_fbo, options);
        drop(host);
        settle(gl, "rebuilding the twins", result)
    }

    /// Put `built` in place of what the retrofit was built with; that is
    /// returned.
    fn swap_built(&mut self, built: Built) -> Built {
        use std::mem::replace;
        Built {
            host: replace(&mut self.host, built.host),
            twin: replace(&mut self.twin, built.twin),
            target: replace(&mut self.target, built.target),
            rules: replace(&mut self.rules, built.rules),
            key: replace(&mut self.key, built.key),
            warnings: replace(&mut self.warnings, built.warnings),
            stencil: replace(&mut self.stencil, built.stencil),
            normal: replace(&mut self.normal, built.normal),
            second: replace(&mut self.second, built.second),
        }
    }

    fn rebuild_within(
        &mut self,
        gl: &glow::Context,
        host_fbo: glow::Framebuffer,
        options: &RetrofitOptions,
    ) -> Result<()> {
        let built = Self::build(gl, host_fbo, options)?;
        // Freed when this returns, or if the compilation panics; taken back
        // if it fails.
        let old = Owned::new(gl, self.swap_built(built));
        let old_options = std::mem::replace(&mut self.options, options.clone());
        match self.prepare(gl) {
            Ok(()) => {
                drop(old);
                // New twins: a frame begins on them with begin_frame, and
                // their first check waits for its count.
                self.frame_begun = false;
                self.refreshed = true;
                if let Some(check) = &mut self.clear_check {
                    check.reset();
                }
                // The forward target attaches the old twins' depth.
                if let Some(forward) = self.forward.take() {
                    destroy_object(gl, forward);
                }
                Ok(())
            }
            Err(e) => {
                // Put the working twins back.
                self.swap_built(old.into_inner()).destroy(gl);
                self.options = old_options;
                Err(e)
            }
        }
    }
}
