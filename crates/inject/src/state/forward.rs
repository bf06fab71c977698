//! What the program draws forward after its lighting (light cubes, glass,
//! particles), into the lit target the lighting drew into: drawn into the
//! retrofit's multisampled forward target instead and averaged into the
//! lit target, as an in-source retrofit's `dmsaa_begin_forward` and
//! `dmsaa_finish_forward` do. The forward target begins at the first draw
//! into the lit target after the lighting pass ended (a depth blit into
//! it before stays the program's), stands in for the lit target at each
//! bind of it for drawing, and is finished at the first bind that leaves
//! it (or reads the lit target), at a blit into the lit target, and at the
//! swap. A profile turns it off with `forward = false`.

use super::context::{Context, Forward, GL_DRAW_FRAMEBUFFER, GL_READ_FRAMEBUFFER};
use super::run::{say_once, settings};
use deferred_msaa_capi as capi;

const GL_FRAMEBUFFER: u32 = 0x8D40;

impl Context {
    /// The lighting pass into `output` ended: what is drawn into it from
    /// now on this frame is forward.
    pub(super) fn lighting_ended(&mut self, output: u32) {
        let on = settings()
            .profile
            .as_ref()
            .and_then(|p| p.retrofit.as_ref())
            .and_then(|r| r.forward)
            .unwrap_or(true);
        if on && self.retrofit.is_some() && !self.off && !self.forward_refused {
            self.forward = Some(Forward { output, fbo: None });
        }
    }

    /// Before a draw into the program's draw framebuffer `d`: the forward
    /// target begun where `d` is the lit target after the lighting.
    pub(super) fn forward_draw(&mut self, d: u32) {
        let Some(f) = self.forward else {
            return;
        };
        if f.fbo.is_some() || d != f.output || self.twin_bound {
            return;
        }
        let Some(handle) = self.retrofit.as_ref().map(|r| r.handle) else {
            return;
        };
        let mut fbo = 0u32;
        // SAFETY: a live handle and a writable u32; this context current.
        let status = self.checked("dmsaa_begin_forward", |_| unsafe {
            capi::dmsaa_begin_forward(handle, f.output, &mut fbo)
        });
        if status != capi::DmsaaStatus::Ok || fbo == 0 {
            // The forward target is the library's default, not the
            // program's ask: without it the retrofit goes on, and its
            // forward draws stay single-sampled, said once.
            self.forward = None;
            self.forward_refused = true;
            // SAFETY: the C API's message, a C string valid until its next call.
            let message = unsafe { std::ffi::CStr::from_ptr(capi::dmsaa_last_error()) }
                .to_string_lossy()
                .into_owned();
            say_once(
                "forward",
                &format!(
                    "dmsaa_begin_forward failed ({message}); what the program draws after its lighting stays \
                     single-sampled for the rest of the run (declare [retrofit] layer_mix in a profile, or \
                     forward = false)"
                ),
            );
            return;
        }
        super::context::real_bind(GL_DRAW_FRAMEBUFFER, fbo);
        self.forward = Some(Forward {
            output: f.output,
            fbo: Some(fbo),
        });
    }

    /// At a bind of `name` to `target`: `true` where the forward target
    /// was bound in its place (a bind of the lit target for drawing while
    /// the forward target is begun); otherwise a begun forward target that
    /// the bind leaves (or whose lit target it reads) is finished first.
    pub(super) fn forward_bind(&mut self, target: u32, name: u32) -> bool {
        let Some(Forward {
            output,
            fbo: Some(fbo),
        }) = self.forward
        else {
            return false;
        };
        let draw = target == GL_FRAMEBUFFER || target == GL_DRAW_FRAMEBUFFER;
        let read = target == GL_FRAMEBUFFER || target == GL_READ_FRAMEBUFFER;
        if draw && name == output {
            // (A read binding that comes with it is the caller's.)
            super::context::real_bind(GL_DRAW_FRAMEBUFFER, fbo);
            self.draw_fbo = name;
            return true;
        }
        if draw || (read && name == output) {
            self.finish_forward();
        }
        false
    }

    /// Average the forward target into the lit target (which the library
    /// binds where the forward target was); the next draw into the lit
    /// target this frame begins it again.
    pub(super) fn finish_forward(&mut self) {
        let Some(Forward {
            output,
            fbo: Some(_),
        }) = self.forward
        else {
            return;
        };
        self.forward = Some(Forward { output, fbo: None });
        let Some(handle) = self.retrofit.as_ref().map(|r| r.handle) else {
            return;
        };
        // The lit target bound where the program sees it bound, as the
        // library would bind it in the forward target's place.
        if self.draw_fbo == output {
            super::context::real_bind(GL_DRAW_FRAMEBUFFER, output);
        }
        // SAFETY: a live handle; this context current.
        let status = self.checked("dmsaa_finish_forward", |_| unsafe {
            capi::dmsaa_finish_forward(handle, output)
        });
        if status != capi::DmsaaStatus::Ok {
            self.forward = None;
            self.fail("dmsaa_finish_forward");
        }
    }

    /// Before the program reads or blits into the framebuffer it has bound
    /// for drawing: a begun forward target finished, so that the lit
    /// target is bound and whole.
    pub(super) fn forward_before_blit(&mut self) {
        if self
            .forward
            .is_some_and(|f| f.fbo.is_some() && self.draw_fbo == f.output)
        {
            self.finish_forward();
        }
    }

    /// The frame's end: a begun forward target finished, and the next frame
    /// starts with none.
    pub(super) fn forward_frame_ends(&mut self) {
        self.finish_forward();
        self.forward = None;
    }
}
