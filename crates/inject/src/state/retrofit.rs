//! The retrofit driven through the C API: made for the G-buffer, its
//! framebuffer (the twin) handed out to be bound in the G-buffer's place,
//! resolved, and with two layers the recorded lighting drawn again.

use super::context::{Context, Framebuffer, Retrofit};
use super::run::{RESOLVES, say_once, seen, settings};
use crate::real::{Api, library_loader};
use crate::replay::{self, Recording};
use deferred_msaa_capi as capi;
use glow::HasContext;
use std::ffi::c_void;

impl Context {
    /// The framebuffer to bind in the G-buffer's place this frame, making
    /// the retrofit first if it is not made yet.
    pub(super) fn twin(&mut self) -> Option<u32> {
        if self.off || self.learning() {
            return None;
        }
        let g = self.gbuffer?;
        if self.retrofit.is_none() {
            if !self.attachments_exist(g) {
                // The program is remaking its G-buffer (a resize deletes
                // the old textures before it attaches new ones): made at a
                // later bind, once its attachments are whole again.
                return None;
            }
            self.make(g)?;
        }
        let (handle, begun) = self.retrofit.as_ref().map(|r| (r.handle, r.begun))?;
        if self.needs_refresh {
            self.needs_refresh = false;
            // New twins: the frame begins on them.
            if let Some(r) = self.retrofit.as_mut() {
                r.begun = false;
            }
            // SAFETY: a live handle; this context current.
            let status = self.checked("dmsaa_refresh", |_| unsafe { capi::dmsaa_refresh(handle) });
            if status != capi::DmsaaStatus::Ok {
                self.fail("dmsaa_refresh");
                return None;
            }
        }
        let begun = begun && self.retrofit.as_ref().is_some_and(|r| r.begun);
        let mut twin = 0u32;
        // The frame's first use of the twins (a bind of the G-buffer or a
        // clear through a framebuffer sharing it) begins it: before the
        // program's clear reaches the twins.
        let (call, status) = if begun {
            // SAFETY: a live handle and a writable u32.
            (
                "dmsaa_framebuffer",
                self.checked("dmsaa_framebuffer", |_| unsafe {
                    capi::dmsaa_framebuffer(handle, &mut twin)
                }),
            )
        } else {
            // A new frame on the twins: the last one's forward draws are
            // over (a program with no swap shows its frames only here).
            self.forward_frame_ends();
            // SAFETY: as above, this context current.
            (
                "dmsaa_begin_frame",
                self.checked("dmsaa_begin_frame", |_| unsafe {
                    capi::dmsaa_begin_frame(handle, &mut twin)
                }),
            )
        };
        if status != capi::DmsaaStatus::Ok || twin == 0 {
            self.fail(call);
            return None;
        }
        if let Some(r) = self.retrofit.as_mut() {
            r.begun = true;
        }
        Some(twin)
    }

    /// Whether the colour textures framebuffer `g` was last seen with all
    /// still exist.
    fn attachments_exist(&mut self, g: u32) -> bool {
        let textures: Vec<u32> = self
            .framebuffers
            .get(&g)
            .map(|f| f.colour_textures.iter().map(|&(_, t)| t).collect())
            .unwrap_or_default();
        let gl = self.gl();
        textures.iter().all(|&t| {
            std::num::NonZeroU32::new(t)
                // SAFETY: a query of the current context.
                .is_some_and(|t| unsafe { gl.is_texture(glow::NativeTexture(t)) })
        })
    }

    /// Make the retrofit of framebuffer `g`: the kept one of a deleted
    /// G-buffer made anew for it (`dmsaa_refresh_with`), else a new one.
    fn make(&mut self, g: u32) -> Option<()> {
        if let Some(mut r) = self.orphan.take() {
            let handle = r.handle;
            // SAFETY: a live handle; this context current.
            let status = self.checked("dmsaa_refresh_with", |_| unsafe {
                capi::dmsaa_refresh_with(handle, g)
            });
            if status == capi::DmsaaStatus::Ok {
                r.begun = false;
                r.looked = true;
                self.retrofit = Some(r);
                return Some(());
            }
            // SAFETY: as above.
            self.checked("dmsaa_destroy", |_| {
                unsafe { capi::dmsaa_destroy(handle) };
                capi::DmsaaStatus::Ok
            });
        }
        self.make_new(g)
    }

    /// Make a new retrofit of framebuffer `g`.
    fn make_new(&mut self, g: u32) -> Option<()> {
        let profile = settings().profile.as_ref();
        let mut options = match profile {
            Some(p) => p.options("the profile").ok()?,
            None => capi::dmsaa_options_default(),
        };
        // A two-channel attachment holds an encoded normal (octahedral,
        // spheremap) or a motion vector far more often than a colour, and
        // an encoding's samples do not blend into a value of it: where no
        // profile states its rule, one sample's value is taken.
        let stated: Vec<u32> = profile
            .map(|p| {
                p.attachments
                    .iter()
                    .filter(|a| a.rule.is_some())
                    .map(|a| a.index)
                    .collect()
            })
            .unwrap_or_default();
        let two_channels: Vec<u32> = self
            .framebuffers
            .get(&g)
            .map(|f| {
                f.channels
                    .iter()
                    .filter(|&&(k, n)| {
                        n == 2 && (k as usize) < capi::DMSAA_MAX_RULES && !stated.contains(&k)
                    })
                    .map(|&(k, _)| k)
                    .collect()
            })
            .unwrap_or_default();
        for &k in &two_channels {
            options.rules[k as usize] = capi::DMSAA_RULE_SELECT;
        }
        let world_space = options.world_space_position == 1;
        let mut block = self.camera_block();
        if self.projection.is_none() && block.is_none() {
            match self.find_camera_block(g) {
                Ok(found) => block = found,
                Err(()) => {
                    self.off = true;
                    return None;
                }
            }
        }
        if self.projection.is_none() && block.is_none() {
            say_once(
                "projection",
                &format!(
                    "found the G-buffer (framebuffer {g}) but no projection matrix: no uniform named {:?} was set, \
                     and no uniform block was written one with glBufferSubData or glBufferData; leaving the program \
                     untouched (a profile names the uniform or the block, or gives the matrix)",
                    profile
                        .and_then(|p| p.projection_uniform())
                        .unwrap_or("projection")
                ),
            );
            self.off = true;
            return None;
        }
        if world_space && self.view.is_none() && block.is_none_or(|b| b.view_offset.is_none()) {
            say_once(
                "view",
                "the profile declares world-space positions but no view matrix was seen; leaving the program untouched",
            );
            self.off = true;
            return None;
        }
        let user: *mut c_void = match self.api {
            Api::Glx => std::ptr::null_mut(),
            Api::Egl => std::ptr::dangling_mut::<u8>().cast(),
        };
        let mut handle = std::ptr::null_mut();
        // SAFETY: the loader gives this context's real entry points; the
        // options and the out pointer live across the call.
        let status = self.checked("dmsaa_retrofit_new", |_| unsafe {
            capi::dmsaa_retrofit_new(Some(library_loader), user, g, &options, &mut handle)
        });
        if status != capi::DmsaaStatus::Ok || handle.is_null() {
            self.fail("dmsaa_retrofit_new");
            return None;
        }
        let mut samples = 0;
        // SAFETY: a live handle and a writable u32.
        unsafe { capi::dmsaa_samples(handle, &mut samples) };
        let shape = self
            .framebuffers
            .get(&g)
            .map(Framebuffer::describe)
            .unwrap_or_default();
        // Frames before this one were the program's own where it drew into
        // this G-buffer (or one it deleted) before the retrofit was made.
        let drawn_before =
            self.framebuffers.get(&g).is_some_and(|f| f.drawn) || self.gbuffers_deleted > 0;
        let line = made_line(
            g,
            &shape,
            samples,
            options.layers,
            profile.is_some(),
            &two_channels,
            self.found_block,
            drawn_before,
        );
        say_once("made", &line);
        seen(|s| s.retrofitted = true);
        self.retrofit = Some(Retrofit {
            handle,
            world_space,
            layers: options.layers,
            looked: false,
            begun: false,
        });
        Some(())
    }

    pub(super) fn resolve(&mut self) {
        self.twin_drawn = false;
        let Some(r) = self.retrofit.as_mut() else {
            return;
        };
        // The next frame begins at its first use of the twins.
        let begun = std::mem::replace(&mut r.begun, false);
        if !begun {
            // Nothing of this frame reached the twins: no resolve.
            return;
        }
        let r = &*r;
        let (handle, world_space) = (r.handle, r.world_space);
        if let Some(block) = self.camera_block()
            && !self.read_camera_block(block)
        {
            return;
        }
        let (Some(projection), view) = (self.projection, self.view) else {
            return;
        };
        let view_ptr = match (world_space, view.as_ref()) {
            (true, Some(v)) => v.as_ptr(),
            _ => std::ptr::null(),
        };
        // SAFETY: a live handle; 16 floats each, alive across the call.
        let status = self.checked("dmsaa_resolve", |_| unsafe {
            capi::dmsaa_resolve(handle, projection.as_ptr(), view_ptr)
        });
        if status == capi::DmsaaStatus::Ok {
            RESOLVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if let Some(r) = self.retrofit.as_mut().filter(|r| !r.looked) {
                r.looked = true;
                if let Some(g) = self.gbuffer {
                    self.look_at_resolved(g);
                }
            }
            // The lighting's draws are recorded: replayed with two layers,
            // and where they end, what follows is forward.
            let lighting = settings()
                .profile
                .as_ref()
                .and_then(|p| p.lighting.as_ref());
            let pass = lighting.map_or(1, |l| l.pass);
            let passes = lighting.and_then(|l| l.passes).unwrap_or(1).max(1);
            self.recording = Some(Recording {
                skip: pass.saturating_sub(1),
                passes_left: passes - 1,
                multi_pass: passes > 1,
                ..Recording::default()
            });
        } else {
            self.fail("dmsaa_resolve");
        }
    }

    /// The second layer: the recorded lighting drawn again into the
    /// retrofit's own target, the two layers mixed into the program's lit
    /// target, and the state the replay changed put back.
    pub(super) fn second_layer(&mut self) {
        let Some(recording) = self.recording.take() else {
            return;
        };
        let Some((handle, layers)) = self.retrofit.as_ref().map(|r| (r.handle, r.layers)) else {
            return;
        };
        let output = recording.target.unwrap_or(0);
        if layers < 2 {
            self.lighting_ended(output);
            return;
        }
        let draws = recording.draws;
        // The passes' colour clears, made again before the draws they came
        // before (the own target's depth and stencil are the library's).
        let clears = recording.clears;
        let mut failed = "the second layer";
        let status = self.checked(
            "the second layer (begin, the replayed lighting, finish)",
            |gl| {
                let mut own = 0u32;
                // SAFETY: a live handle, a writable u32; this context current.
                let status =
                    unsafe { capi::dmsaa_begin_second_layer_own_target(handle, output, &mut own) };
                if status != capi::DmsaaStatus::Ok {
                    failed = "dmsaa_begin_second_layer_own_target";
                    return status;
                }
                let Some(own) = std::num::NonZeroU32::new(own) else {
                    return status;
                };
                let saved = replay::save(gl, &draws);
                replay::draw(gl, &draws, &clears, output, own.get());
                // SAFETY: as above; the output given to begin.
                let status = unsafe { capi::dmsaa_finish_second_layer(handle, output) };
                replay::restore(gl, &saved);
                if status != capi::DmsaaStatus::Ok {
                    failed = "dmsaa_finish_second_layer";
                }
                status
            },
        );
        if status != capi::DmsaaStatus::Ok {
            self.fail(failed);
            return;
        }
        self.lighting_ended(output);
    }
}

/// The line that says a retrofit was made, and what of it the program did
/// not choose.
#[allow(clippy::too_many_arguments)]
fn made_line(
    g: u32,
    shape: &str,
    samples: u32,
    layers: u32,
    from_profile: bool,
    two_channels: &[u32],
    found_block: Option<crate::profile::CameraBlock>,
    drawn_before: bool,
) -> String {
    let mut line = format!(
        "retrofitting framebuffer {g} ({shape}) with {samples}x MSAA, {layers} layer(s), {}",
        if from_profile {
            "options from the profile"
        } else {
            "default options"
        }
    );
    if !two_channels.is_empty() {
        line += &format!(
            "; two-channel attachment(s) {two_channels:?} taken from one sample, not blended (an encoded normal \
             or a motion vector; a profile's `rule` says otherwise)"
        );
    }
    if let Some(b) = found_block {
        line += &format!(
            "; the camera from the uniform block at binding {} (projection at byte {}{}), found by its values",
            b.binding,
            b.offset,
            b.view_offset
                .map(|v| format!(", view at byte {v}"))
                .unwrap_or_default()
        );
    }
    line += if drawn_before {
        "; the frame(s) before this one are the program's own (the G-buffer is found in a frame that reads it, \
         or once its camera is known; a profile's [framebuffer] signature with a camera set before the G-buffer \
         is bound retrofits the first)"
    } else {
        "; from the program's first frame"
    };
    line
}
