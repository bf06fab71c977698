//! A clear made through a framebuffer of the program's own that shares the
//! G-buffer's textures (an engine's "clear" framebuffer) clears the
//! G-buffer's textures, not the retrofit's framebuffer standing in for it:
//! it is replayed there, attachment by attachment, with the values GL
//! used (the clear colour, depth and stencil the program set for
//! `glClear`; each `glClearBuffer*` call's own values, on the attachment
//! it reached; the same masks and scissor apply), and the draw framebuffer
//! put back.

use super::context::Context;
use deferred_msaa_capi as capi;
use glow::HasContext;
use std::num::NonZeroU32;

/// The object attached at `attachment` of the framebuffer bound at
/// `target`: (type, name).
///
/// # Safety
///
/// A query of the current context.
unsafe fn attached(gl: &glow::Context, target: u32, attachment: u32) -> (u32, u32) {
    // SAFETY: the caller's.
    unsafe {
        (
            gl.get_framebuffer_attachment_parameter_i32(
                target,
                attachment,
                glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE,
            ) as u32,
            gl.get_framebuffer_attachment_parameter_i32(
                target,
                attachment,
                glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME,
            ) as u32,
        )
    }
}

/// A `glClearBuffer*` call as the program made it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClearBuffer {
    /// `GL_COLOR`, `GL_DEPTH`, `GL_STENCIL` or `GL_DEPTH_STENCIL`.
    pub(crate) buffer: u32,
    /// The draw buffer (for `GL_COLOR`; 0 otherwise).
    pub(crate) drawbuffer: i32,
    /// The values it cleared to.
    pub(crate) value: ClearValue,
}

/// The values of a `glClearBuffer*` call, by its kind.
#[derive(Clone, Copy, Debug)]
pub(crate) enum ClearValue {
    /// `glClearBufferfv`: four colour values, or the depth first.
    Float([f32; 4]),
    /// `glClearBufferiv`: four colour values, or the stencil first.
    Int([i32; 4]),
    /// `glClearBufferuiv`: four colour values.
    Uint([u32; 4]),
    /// `glClearBufferfi`: depth and stencil.
    DepthStencil(f32, i32),
}

/// `call`'s clear made on the bound draw framebuffer, a colour one at draw
/// buffer `i`.
///
/// # Safety
///
/// A framebuffer of the library's bound for drawing.
unsafe fn clear_bound(gl: &glow::Context, call: &ClearBuffer, i: u32) {
    // SAFETY: the caller's.
    unsafe {
        match (call.buffer, call.value) {
            (glow::COLOR, ClearValue::Float(v)) => gl.clear_buffer_f32_slice(glow::COLOR, i, &v),
            (glow::COLOR, ClearValue::Int(v)) => gl.clear_buffer_i32_slice(glow::COLOR, i, &v),
            (glow::COLOR, ClearValue::Uint(v)) => gl.clear_buffer_u32_slice(glow::COLOR, i, &v),
            (glow::DEPTH, ClearValue::Float(v)) => {
                gl.clear_buffer_f32_slice(glow::DEPTH, 0, &v[..1])
            }
            (glow::STENCIL, ClearValue::Int(v)) => {
                gl.clear_buffer_i32_slice(glow::STENCIL, 0, &v[..1])
            }
            (glow::DEPTH_STENCIL, ClearValue::DepthStencil(depth, stencil)) => {
                gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, depth, stencil)
            }
            _ => {}
        }
    }
}

impl Context {
    /// Where the bound draw framebuffer is not the G-buffer but shares a
    /// colour texture with it: the G-buffer, that framebuffer, and the
    /// twin to replay a clear on (the retrofit made now if it is not yet:
    /// the G-buffer's next bind would make it, after this clear).
    fn sharing_gbuffer(&mut self) -> Option<(u32, u32, u32)> {
        let d = self.draw_fbo;
        if d == 0 || self.twin_bound || self.off || self.learning() {
            return None;
        }
        // The cleared framebuffer read as it is now; with a signature, the
        // G-buffer may be found by it (the program clears before it binds).
        let cleared = self.inspect();
        if self.gbuffer.is_none() {
            let textures: Vec<u32> = cleared.colour_textures.iter().map(|&(_, t)| t).collect();
            self.match_signature_at_clear(d, &textures);
        }
        let g = self.gbuffer?;
        if d == g {
            return None;
        }
        // The G-buffer's textures.
        let ours: Vec<u32> = self
            .framebuffers
            .get(&g)
            .map(|f| f.colour_textures.iter().map(|&(_, t)| t).collect())
            .unwrap_or_default();
        if !cleared
            .colour_textures
            .iter()
            .any(|(_, t)| ours.contains(t))
        {
            return None;
        }
        let twin = self.twin()?;
        Some((g, d, twin))
    }

    /// After `glClearBuffer*` into the bound draw framebuffer: where it is
    /// not the G-buffer but shares attachments with it, the same clear of
    /// the same attachment, with the same value, on the twin.
    pub(super) fn after_clear_buffer(&mut self, call: ClearBuffer) {
        if let Some(shared) = self.sharing_gbuffer() {
            self.replay_clear(shared, call);
        }
    }

    /// `call`, made through framebuffer `d` sharing G-buffer `g`'s
    /// textures, made again on the twin `twin`: on the attachment it
    /// reached, with its value.
    fn replay_clear(&mut self, (g, d, twin): (u32, u32, u32), call: ClearBuffer) {
        let mut replayed = false;
        self.checked(
            "a clear through a framebuffer sharing the G-buffer's, replayed",
            |gl| {
                // SAFETY: queries of the current context; the library's own
                // framebuffer bound for the replay, the program's put back.
                unsafe {
                    let fbo = |n: u32| NonZeroU32::new(n).map(glow::NativeFramebuffer);
                    let read_fbo = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING) as u32;
                    // The object the call cleared, and the G-buffer's
                    // attachment point that holds it.
                    let point = match call.buffer {
                        glow::COLOR => {
                            let b = gl.get_parameter_i32(
                                glow::DRAW_BUFFER0 + call.drawbuffer.max(0) as u32,
                            ) as u32;
                            if !(glow::COLOR_ATTACHMENT0..glow::COLOR_ATTACHMENT0 + 8).contains(&b)
                            {
                                return capi::DmsaaStatus::Ok;
                            }
                            let object = attached(gl, glow::DRAW_FRAMEBUFFER, b);
                            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo(g));
                            let found = (0..8).map(|k| glow::COLOR_ATTACHMENT0 + k).find(|&a| {
                                object.0 != glow::NONE
                                    && attached(gl, glow::READ_FRAMEBUFFER, a) == object
                            });
                            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo(read_fbo));
                            match found {
                                Some(a) => a,
                                None => return capi::DmsaaStatus::Ok,
                            }
                        }
                        glow::DEPTH | glow::DEPTH_STENCIL | glow::STENCIL => {
                            let a = if call.buffer == glow::STENCIL {
                                glow::STENCIL_ATTACHMENT
                            } else {
                                glow::DEPTH_ATTACHMENT
                            };
                            let object = attached(gl, glow::DRAW_FRAMEBUFFER, a);
                            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo(g));
                            let shares = object.0 != glow::NONE
                                && attached(gl, glow::READ_FRAMEBUFFER, a) == object;
                            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo(read_fbo));
                            if !shares {
                                return capi::DmsaaStatus::Ok;
                            }
                            a
                        }
                        _ => return capi::DmsaaStatus::Ok,
                    };
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, fbo(twin));
                    if call.buffer == glow::COLOR {
                        let max = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(0, 8) as u32;
                        let slot = (0..max).find(|&i| {
                            gl.get_parameter_i32(glow::DRAW_BUFFER0 + i) as u32 == point
                        });
                        if let Some(i) = slot {
                            clear_bound(gl, &call, i);
                            replayed = true;
                        }
                    } else {
                        clear_bound(gl, &call, 0);
                        replayed = true;
                    }
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, fbo(d));
                }
                capi::DmsaaStatus::Ok
            },
        );
        if replayed {
            self.twin_drawn = true;
        }
    }

    /// After `glClearNamedFramebuffer*` of framebuffer `f` (direct state
    /// access: nothing bound): the G-buffer cleared by name is the same
    /// clear on the twin, at the same draw buffer (the twin's mirror the
    /// G-buffer's); a framebuffer sharing its textures is replayed as
    /// [`Context::after_clear_buffer`] replays a clear through it.
    pub(super) fn after_clear_named(&mut self, f: u32, call: ClearBuffer) {
        let Some(g) = self.gbuffer else {
            return;
        };
        if f == 0 || self.off || self.learning() {
            return;
        }
        // The framebuffer cleared, bound for drawing as the program would
        // have bound it to clear it the old way; the program's bindings put
        // back after.
        // SAFETY: a query of the current context.
        let real_draw =
            unsafe { self.gl().get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) } as u32;
        let (draw_fbo, twin_bound) = (self.draw_fbo, self.twin_bound);
        if f == g {
            let Some(twin) = self.twin() else {
                return;
            };
            super::context::real_bind(glow::DRAW_FRAMEBUFFER, twin);
            self.checked("a clear of the G-buffer by name, replayed", |gl| {
                // SAFETY: the twin bound for drawing; its draw buffers are
                // the G-buffer's.
                unsafe { clear_bound(gl, &call, call.drawbuffer.max(0) as u32) };
                capi::DmsaaStatus::Ok
            });
            self.twin_drawn = true;
        } else {
            super::context::real_bind(glow::DRAW_FRAMEBUFFER, f);
            self.draw_fbo = f;
            self.twin_bound = false;
            self.after_clear_buffer(call);
            (self.draw_fbo, self.twin_bound) = (draw_fbo, twin_bound);
        }
        super::context::real_bind(glow::DRAW_FRAMEBUFFER, real_draw);
    }

    /// A colour clear made while the lighting is recorded, before its
    /// pass's first draw: made again on the own target at the replay, where
    /// its framebuffer is the lit target.
    pub(super) fn record_clear(&mut self, mask: u32) {
        if mask & glow::COLOR_BUFFER_BIT == 0
            || self.recording.as_ref().is_none_or(|r| r.pass_drawn)
        {
            return;
        }
        let mut colour = [0f32; 4];
        // SAFETY: a query of the current context.
        unsafe {
            self.gl()
                .get_parameter_f32_slice(glow::COLOR_CLEAR_VALUE, &mut colour)
        };
        let d = self.draw_fbo;
        if let Some(r) = self.recording.as_mut() {
            let before = r.draws.len();
            r.clears.push((before, d, colour));
        }
    }

    /// After `glClear(mask)` into the bound draw framebuffer: the calls it
    /// made, one per attachment (each draw buffer's colour with the clear
    /// colour, the depth and stencil with their clear values), each
    /// replayed as a `glClearBuffer*` call through that framebuffer is.
    pub(super) fn after_clear(&mut self, mask: u32) {
        let Some(shared) = self.sharing_gbuffer() else {
            return;
        };
        let mut calls: Vec<ClearBuffer> = Vec::new();
        // SAFETY: queries of the current context.
        unsafe {
            let gl = self.gl();
            if mask & glow::COLOR_BUFFER_BIT != 0 {
                let mut colour = [0f32; 4];
                gl.get_parameter_f32_slice(glow::COLOR_CLEAR_VALUE, &mut colour);
                let max = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(0, 8) as u32;
                for i in 0..max {
                    let b = gl.get_parameter_i32(glow::DRAW_BUFFER0 + i) as u32;
                    if (glow::COLOR_ATTACHMENT0..glow::COLOR_ATTACHMENT0 + 8).contains(&b) {
                        calls.push(ClearBuffer {
                            buffer: glow::COLOR,
                            drawbuffer: i as i32,
                            value: ClearValue::Float(colour),
                        });
                    }
                }
            }
            let mut depth = [0f32; 1];
            gl.get_parameter_f32_slice(glow::DEPTH_CLEAR_VALUE, &mut depth);
            let stencil = gl.get_parameter_i32(glow::STENCIL_CLEAR_VALUE);
            match (
                mask & glow::DEPTH_BUFFER_BIT != 0,
                mask & glow::STENCIL_BUFFER_BIT != 0,
            ) {
                (true, true) => calls.push(ClearBuffer {
                    buffer: glow::DEPTH_STENCIL,
                    drawbuffer: 0,
                    value: ClearValue::DepthStencil(depth[0], stencil),
                }),
                (true, false) => calls.push(ClearBuffer {
                    buffer: glow::DEPTH,
                    drawbuffer: 0,
                    value: ClearValue::Float([depth[0], 0.0, 0.0, 0.0]),
                }),
                (false, true) => calls.push(ClearBuffer {
                    buffer: glow::STENCIL,
                    drawbuffer: 0,
                    value: ClearValue::Int([stencil, 0, 0, 0]),
                }),
                (false, false) => {}
            }
        }
        for call in calls {
            self.replay_clear(shared, call);
        }
    }
}
