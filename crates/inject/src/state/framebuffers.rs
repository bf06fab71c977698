//! The framebuffer binds the program makes and the attachments it changes,
//! followed so that the twin stands in for the G-buffer and goes when it
//! goes.

use super::context::{Context, GL_DRAW_FRAMEBUFFER, GL_READ_FRAMEBUFFER, real_bind};
use super::run::{say_once, seen, settings};
use deferred_msaa_capi as capi;

const GL_FRAMEBUFFER: u32 = 0x8D40;

impl Context {
    pub(super) fn bind_framebuffer(&mut self, target: u32, name: u32, real: &dyn Fn(u32, u32)) {
        // A pass ends at the first bind after it drew: the lighting's is
        // replayed, an earlier one's let go.
        if let Some(r) = self.recording.as_mut()
            && r.pass_drawn
        {
            if r.skip > 0 {
                r.skip -= 1;
                r.let_go();
            } else if r.passes_left > 0 {
                // The lighting goes on in its next pass.
                r.passes_left -= 1;
                r.pass_drawn = false;
            } else {
                self.second_layer();
            }
        }
        let draw = target == GL_FRAMEBUFFER || target == GL_DRAW_FRAMEBUFFER;
        let read = target == GL_FRAMEBUFFER || target == GL_READ_FRAMEBUFFER;
        if draw && name != 0 && self.gbuffer.is_none() {
            self.match_signature_at_bind(target, name, real);
        }
        if self.forward_bind(target, name) {
            // The forward target drawn in the lit target's place.
            if read {
                real(GL_READ_FRAMEBUFFER, name);
                self.read_fbo = name;
            }
            return;
        }
        let is_gbuffer = name != 0 && self.gbuffer == Some(name);
        if draw && is_gbuffer {
            if let Some(twin) = self.twin() {
                real(target, twin);
                self.twin_bound = true;
                self.draw_fbo = name;
                if read {
                    self.read_fbo = name;
                }
                return;
            }
        }
        real(target, name);
        let left_twin = draw && self.twin_bound;
        if draw {
            self.draw_fbo = name;
            self.twin_bound = false;
        }
        if read {
            self.read_fbo = name;
        }
        // The resolve at the first bind that leaves the twin after drawing,
        // or at a read of the G-buffer before that.
        if self.twin_drawn && (left_twin || (read && is_gbuffer)) {
            self.resolve();
        }
    }

    /// The profile whose signature finds the G-buffer, where there is one
    /// and the camera is known (a G-buffer found without it could not be
    /// resolved).
    fn signature_to_match(&self) -> Option<&'static crate::profile::Profile> {
        if self.off || self.learning() {
            return None;
        }
        let profile = settings()
            .profile
            .as_ref()
            .filter(|p| p.framebuffer.is_some())?;
        (self.projection.is_some() || self.camera_block().is_some()).then_some(profile)
    }

    /// With a profile's signature and the camera known: a framebuffer bound
    /// for drawing that has the signature is the G-buffer from this bind on
    /// (so a G-buffer made anew each frame, or a program that renders one
    /// frame, is retrofitted in the frame that makes it). `real` binds it
    /// first, for its attachments to be read.
    fn match_signature_at_bind(&mut self, target: u32, name: u32, real: &dyn Fn(u32, u32)) {
        let Some(profile) = self.signature_to_match() else {
            return;
        };
        let fresh = self.framebuffers.get(&name).is_none_or(|f| f.stale);
        if fresh {
            real(target, name);
            let info = self.inspect();
            self.framebuffers.insert(name, info);
        }
        if self
            .framebuffers
            .get(&name)
            .is_some_and(|f| Self::matches_profile(profile, f))
        {
            self.gbuffer = Some(name);
            seen(|s| s.found = Some(name));
        }
    }

    /// With a profile's signature and the camera known: at a clear through
    /// the bound draw framebuffer `cleared` (not the G-buffer, its colour
    /// textures `textures`), a framebuffer seen before that shares one of
    /// them and has the signature is the G-buffer from now on, so that a
    /// program clearing its G-buffer through another framebuffer before it
    /// binds it has that clear replayed in its first frame too. One whose
    /// attachments changed since it was seen is read again (bound for
    /// drawing for the query, `cleared` bound back after).
    pub(super) fn match_signature_at_clear(&mut self, cleared: u32, textures: &[u32]) {
        if self.gbuffer.is_some() {
            return;
        }
        let Some(profile) = self.signature_to_match() else {
            return;
        };
        let mut candidates: Vec<u32> = self
            .framebuffers
            .keys()
            .copied()
            .filter(|&f| f != cleared && f != 0)
            .collect();
        candidates.sort_unstable();
        for f in candidates {
            if self.framebuffers.get(&f).is_some_and(|info| info.stale) {
                real_bind(GL_DRAW_FRAMEBUFFER, f);
                let info = self.inspect();
                real_bind(GL_DRAW_FRAMEBUFFER, cleared);
                self.framebuffers.insert(f, info);
            }
            let Some(info) = self.framebuffers.get(&f) else {
                continue;
            };
            if info
                .colour_textures
                .iter()
                .any(|(_, t)| textures.contains(t))
                && Self::matches_profile(profile, info)
            {
                self.gbuffer = Some(f);
                seen(|s| s.found = Some(f));
                return;
            }
        }
    }

    pub(super) fn delete_framebuffers(&mut self, names: &[u32]) {
        for name in names {
            let seen_as = self.framebuffers.remove(name);
            self.read_as_gbuffers.remove(name);
            if self.gbuffer == Some(*name) {
                self.last_gbuffer = seen_as;
                self.gbuffers_deleted += 1;
                if self.retrofit.is_none() && !self.off && !self.learning() {
                    // Found, and deleted before it was bound again.
                    seen(|s| {
                        let times = s.made_and_deleted.map_or(0, |(_, n)| n);
                        s.made_and_deleted = Some((*name, times + 1));
                    });
                }
                // GL unbinds a deleted framebuffer: the twin goes too.
                if self.twin_bound {
                    real_bind(GL_DRAW_FRAMEBUFFER, 0);
                    if self.read_fbo == *name {
                        real_bind(GL_READ_FRAMEBUFFER, 0);
                    }
                    self.twin_bound = false;
                }
                self.twin_drawn = false;
                self.forward = None;
                let signature = settings()
                    .profile
                    .as_ref()
                    .is_some_and(|p| p.framebuffer.is_some());
                if let Some(r) = self.retrofit.take() {
                    if signature && self.orphan.is_none() {
                        // A program that makes its G-buffer anew (each
                        // frame, or at a resize under a new name): kept for
                        // the next one its signature finds.
                        self.orphan = Some(r);
                    } else {
                        // SAFETY: a handle the C API made, on its context.
                        self.checked("dmsaa_destroy", |_| {
                            unsafe { capi::dmsaa_destroy(r.handle) };
                            capi::DmsaaStatus::Ok
                        });
                    }
                }
                // A new G-buffer is looked for as at the start.
                self.gbuffer = None;
            }
        }
    }

    /// Before an attachment of framebuffer `name` changes through direct
    /// state access (the twin, bound or not, is not touched).
    pub(super) fn named_attachment_changes(&mut self, name: u32) {
        if let Some(f) = self.framebuffers.get_mut(&name) {
            f.stale = true;
        }
        if name != 0 && self.gbuffer == Some(name) {
            self.needs_refresh = true;
        }
    }

    /// Before an attachment of the framebuffer bound at `target` changes.
    pub(super) fn attachment_changes(&mut self, target: u32) {
        let bound = if target == GL_READ_FRAMEBUFFER {
            self.read_fbo
        } else {
            self.draw_fbo
        };
        if let Some(f) = self.framebuffers.get_mut(&bound) {
            f.stale = true;
        }
        if self.gbuffer != Some(bound) || bound == 0 {
            return;
        }
        // The twins are rebuilt from the G-buffer at its next bind.
        self.needs_refresh = true;
        if !self.twin_bound || target == GL_READ_FRAMEBUFFER {
            return;
        }
        if self.twin_drawn {
            // Drawn into the twin and not resolved: the frame's geometry
            // would be lost either way.
            say_once(
                "reattach",
                "the program changed its G-buffer's attachments after drawing into it; the retrofit is off for the rest of the run",
            );
            self.give_up();
            return;
        }
        // The change would go to the twin, bound in the G-buffer's place
        // (a program binds its G-buffer to reattach its textures after a
        // resize): the G-buffer goes back under it, and this frame's
        // drawing into it stays single-sampled.
        real_bind(GL_DRAW_FRAMEBUFFER, bound);
        if self.read_fbo == bound {
            real_bind(GL_READ_FRAMEBUFFER, bound);
        }
        self.twin_bound = false;
    }
}
