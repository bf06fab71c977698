//! The G-buffer found from the draws: the framebuffers drawn into are
//! inspected, and at the end of a frame the one line for a program left
//! alone (or `--learn`'s profile).
//!
//! The G-buffer, without a profile: a complete single-sample framebuffer
//! with at least two colour textures and a depth attachment, drawn into,
//! two or more of whose colour textures are bound at once for a draw into
//! another framebuffer (a lighting pass reads them together; a bloom
//! program's blur and composite read one at a time). With a profile, a
//! drawn framebuffer matching its signature. Anything less sure leaves the
//! program untouched and says so once.

use super::context::{Context, Framebuffer, GL_DRAW_FRAMEBUFFER, Pass};
use super::run::{FRAMES, left_alone, say_once, seen, settings};
use crate::profile::Profile;
use crate::replay::{DrawCall, DrawState, RecordedDraw};
use glow::HasContext;
use std::collections::HashSet;

impl Context {
    /// Before a draw call: the twin is drawn; otherwise the framebuffer
    /// drawn into is inspected, and the G-buffer looked for.
    pub(super) fn before_draw(&mut self, call: DrawCall) {
        self.draws += 1;
        seen(|s| s.draws += 1);
        if self.twin_bound {
            self.twin_drawn = true;
            return;
        }
        let d = self.draw_fbo;
        self.forward_draw(d);
        if self
            .recording
            .as_ref()
            .is_some_and(|r| r.multi_pass || r.target.is_none_or(|t| t == d))
        {
            // SAFETY: a query of the current context.
            let vertex_array =
                unsafe { self.gl().get_parameter_i32(glow::VERTEX_ARRAY_BINDING) } as u32;
            let mut textures: Vec<(u32, u32, u32)> = self
                .unit_textures
                .iter()
                .map(|(u, t)| (*u, glow::TEXTURE_2D, *t))
                .chain(
                    self.unit_arrays
                        .iter()
                        .map(|(u, t)| (*u, glow::TEXTURE_2D_ARRAY, *t)),
                )
                .filter(|&(_, _, t)| t != 0)
                .collect();
            textures.sort_unstable();
            let program = self.program;
            let state = DrawState::read(self.gl());
            if let Some(r) = self.recording.as_mut() {
                r.target = Some(d);
                r.pass_drawn = true;
                let uniforms = std::mem::take(&mut r.uniforms);
                let buffers = std::mem::take(&mut r.buffers);
                r.draws.push(RecordedDraw {
                    call,
                    program,
                    vertex_array,
                    textures,
                    uniforms,
                    buffers,
                    framebuffer: d,
                    state,
                });
            }
        }
        if self.learning() {
            match self.passes.last_mut() {
                Some(p) if p.framebuffer == d && p.program == self.program => p.draws += 1,
                _ => self.passes.push(Pass {
                    framebuffer: d,
                    program: self.program,
                    draws: 1,
                }),
            }
        }
        if self.off {
            return;
        }
        if d != 0 {
            let fresh = self.framebuffers.get(&d).is_none_or(|f| f.stale);
            if fresh {
                let info = self.inspect();
                self.framebuffers.insert(d, info);
            }
            if let Some(f) = self.framebuffers.get_mut(&d) {
                if !f.drawn {
                    seen(|s| {
                        if f.looks_like_gbuffer() {
                            s.candidates.insert(d);
                        }
                    });
                }
                f.drawn = true;
            }
        }
        // Until the retrofit is made, every framebuffer read as a G-buffer
        // is counted: a second one (a mirror's view beside the camera's)
        // makes the choice the program's, not the first read's.
        if self.gbuffer.is_none() || self.retrofit.is_none() {
            self.find_gbuffer(d);
        }
    }

    /// The bound draw framebuffer's attachments, read from GL.
    pub(super) fn inspect(&mut self) -> Framebuffer {
        let gl = self.gl();
        let mut f = Framebuffer::default();
        // SAFETY: queries of the bound draw framebuffer, a user one.
        unsafe {
            f.complete =
                gl.check_framebuffer_status(GL_DRAW_FRAMEBUFFER) == glow::FRAMEBUFFER_COMPLETE;
            f.samples = gl.get_parameter_i32(glow::SAMPLES);
            let max = gl
                .get_parameter_i32(glow::MAX_COLOR_ATTACHMENTS)
                .clamp(0, 8) as u32;
            for k in 0..max {
                let attachment = glow::COLOR_ATTACHMENT0 + k;
                let param = |p| {
                    gl.get_framebuffer_attachment_parameter_i32(GL_DRAW_FRAMEBUFFER, attachment, p)
                };
                let kind = param(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE) as u32;
                if kind == glow::NONE {
                    continue;
                }
                f.colour_attachments += 1;
                let component = match param(glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE) as u32 {
                    glow::FLOAT => "float",
                    glow::INT => "int",
                    glow::UNSIGNED_INT => "uint",
                    glow::SIGNED_NORMALIZED => "snorm",
                    _ => "unorm",
                };
                let bits = param(glow::FRAMEBUFFER_ATTACHMENT_RED_SIZE);
                f.formats.push(format!("{component}{bits}"));
                let channels = [
                    glow::FRAMEBUFFER_ATTACHMENT_RED_SIZE,
                    glow::FRAMEBUFFER_ATTACHMENT_GREEN_SIZE,
                    glow::FRAMEBUFFER_ATTACHMENT_BLUE_SIZE,
                    glow::FRAMEBUFFER_ATTACHMENT_ALPHA_SIZE,
                ]
                .into_iter()
                .filter(|&p| param(p) > 0)
                .count() as u32;
                f.channels.push((k, channels));
                if kind == glow::TEXTURE {
                    let texture = param(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME) as u32;
                    f.colour_textures.push((k, texture));
                }
            }
            let mut names: Vec<u32> = f.colour_textures.iter().map(|&(_, t)| t).collect();
            names.sort_unstable();
            names.dedup();
            f.layered = names.len() < f.colour_textures.len();
            f.depth = gl.get_framebuffer_attachment_parameter_i32(
                GL_DRAW_FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE,
            ) as u32
                != glow::NONE;
        }
        f
    }

    /// Whether framebuffer `f` is the one the profile names.
    pub(super) fn matches_profile(profile: &Profile, f: &Framebuffer) -> bool {
        let Some(m) = &profile.framebuffer else {
            return false;
        };
        f.complete
            && f.samples == 0
            && f.colour_textures.len() as u32 == m.colour_textures
            && f.depth == m.depth
            && (m.formats.is_empty() || m.formats == f.formats)
    }

    /// Look for the G-buffer at a draw into framebuffer `draw`.
    fn find_gbuffer(&mut self, draw: u32) {
        let profile = settings().profile.as_ref();
        if let Some(p) = profile.filter(|p| p.framebuffer.is_some()) {
            if self.gbuffer.is_none()
                && let Some(f) = self.framebuffers.get(&draw)
                && Self::matches_profile(p, f)
            {
                self.gbuffer = Some(draw);
                seen(|s| s.found = Some(draw));
            }
            return;
        }
        let bound: HashSet<u32> = self
            .unit_textures
            .values()
            .chain(self.unit_arrays.values())
            .copied()
            .filter(|&t| t != 0)
            .collect();
        // Two colour attachments read together: two textures, or one
        // array texture whose layers they are.
        if bound.is_empty() {
            return;
        }
        let found: Vec<u32> = self
            .framebuffers
            .iter()
            .filter(|(name, f)| {
                **name != draw
                    && f.drawn
                    && f.looks_like_gbuffer()
                    && f.colour_textures
                        .iter()
                        .filter(|(_, t)| bound.contains(t))
                        .count()
                        >= 2
            })
            .map(|(name, _)| *name)
            .collect();
        self.read_as_gbuffers.extend(found.iter().copied());
        let mut all: Vec<u32> = self.read_as_gbuffers.iter().copied().collect();
        all.sort_unstable();
        match all.as_slice() {
            [] => {}
            [g] => {
                if self.gbuffer.is_none() {
                    self.gbuffer = Some(*g);
                    seen(|s| s.found = Some(*g));
                }
            }
            many => {
                say_once(
                    "ambiguous",
                    &format!(
                        "framebuffers {many:?} all look like G-buffers; leaving the program untouched (a profile names which)"
                    ),
                );
                self.gbuffer = None;
                self.off = true;
            }
        }
    }

    /// At a swap: the last resort's resolve, the frame's passes kept for
    /// `--learn`, and the one line for a program left alone.
    pub(super) fn end_frame(&mut self) {
        if self.draws == 0 {
            // A swap before the program drew anything (GLFW swaps once as
            // it makes a window): no frame of the program's.
            return;
        }
        if self.twin_drawn {
            self.resolve();
        }
        if self
            .recording
            .as_ref()
            .is_some_and(|r| r.pass_drawn && r.skip == 0 && r.passes_left == 0)
        {
            self.second_layer();
        }
        self.recording = None;
        self.forward_frame_ends();
        self.frames += 1;
        FRAMES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.last_frame = std::mem::take(&mut self.passes);
        if self.learning() {
            super::learn::after_frame(self);
            return;
        }
        // (A program whose G-buffer is made anew each frame has none between
        // frames: retrofitted, it is not left alone.)
        if self.frames == 2 && self.gbuffer.is_none() && !self.off && !seen(|s| s.retrofitted) {
            let frames = self.frames;
            say_once("none", &seen(|s| left_alone(s, frames, false)));
        }
    }
}
