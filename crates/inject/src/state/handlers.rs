//! What each watched GL function does around its real call (the wrappers
//! in [`crate::hooks`] call these), on the current context's state.

// The handlers have the GL functions' own names.
#![allow(non_snake_case)]

use super::clears::{ClearBuffer, ClearValue};
use super::context::{Context, MatrixRole};
use super::lighting_calls::copied;
use super::run::{FRAMES, SEEN, left_alone, outcome_said, say_once, settings};
use crate::real::{current_context, real_type};
use crate::replay::{DrawCall, UniformValue};
use std::collections::HashMap;
use std::ffi::{CStr, c_char, c_ulong, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;

const GL_DRAW_FRAMEBUFFER_BINDING: u32 = 0x8CA6;
const GL_READ_FRAMEBUFFER_BINDING: u32 = 0x8CAA;
const GL_TEXTURE0: u32 = 0x84C0;
const GL_TEXTURE_2D: u32 = 0x0DE1;

static CONTEXTS: Mutex<Option<HashMap<usize, Context>>> = Mutex::new(None);

thread_local! {
    /// Whether this thread is inside [`with_context`] already (a driver
    /// calling an exported GL symbol of this library's while it works).
    static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Clears [`INSIDE`] on every way out.
struct Inside;

impl Drop for Inside {
    fn drop(&mut self) {
        INSIDE.with(|i| i.set(false));
    }
}

/// `f` on the current context's state, or `None` (the call passes through
/// untouched) where there is no current context, the call comes from inside
/// the library's own work on this thread, or the state is poisoned. Another
/// thread's call waits for the state (each context's state stays whole).
fn with_context<R>(f: impl FnOnce(&mut Context) -> R) -> Option<R> {
    watch_exit();
    if INSIDE.with(|i| i.replace(true)) {
        return None;
    }
    let _inside = Inside;
    let (api, id) = current_context()?;
    let mut guard = CONTEXTS.lock().ok()?;
    let context = guard
        .get_or_insert_with(HashMap::new)
        .entry(id)
        .or_insert_with(|| Context::new(api));
    match catch_unwind(AssertUnwindSafe(|| f(context))) {
        Ok(r) => Some(r),
        Err(_) => {
            say_once(
                "panic",
                "internal error; the retrofit is off for the rest of the run",
            );
            context.off = true;
            None
        }
    }
}

/// Have [`at_exit`] run when the program exits (once; from the first
/// `dlsym` or GL call that reaches the library).
pub(crate) fn watch_exit() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    // SAFETY: a plain extern "C" function with no arguments.
    ONCE.call_once(|| unsafe {
        libc::atexit(at_exit);
    });
}

/// The program looked up `name`, a get-proc-address the library does not
/// stand in for: said in the line of a run left alone.
pub(crate) fn saw_other_loader(name: &'static str) {
    super::run::seen(|s| s.other_loader = Some(name));
}

/// At exit: `--learn`'s profile if none was written yet; otherwise, for a
/// run that said nothing, the one line saying why the program was left
/// alone.
extern "C" fn at_exit() {
    if settings().learn.is_some() {
        // The contexts still alive (a destroyed one wrote at its end); the
        // state is not waited for at exit.
        if let Ok(guard) = CONTEXTS.try_lock()
            && let Some(map) = guard.as_ref()
            && let Some(cx) = map.values().max_by_key(|cx| cx.draws)
        {
            super::learn::at_end(cx, "at the program's exit");
        } else {
            super::learn::at_end_unseen();
        }
        return;
    }
    if outcome_said() {
        return;
    }
    let line = left_alone(
        &SEEN.lock().unwrap_or_else(|e| e.into_inner()),
        FRAMES.load(std::sync::atomic::Ordering::Relaxed),
        true,
    );
    say_once("exit", &line);
}

pub(crate) fn glBindFramebuffer(real: real_type::glBindFramebuffer, target: u32, name: u32) {
    // SAFETY (all handlers): the driver's function, with the program's
    // arguments or the library's own framebuffer name.
    let call = |t: u32, n: u32| unsafe { real(t, n) };
    if with_context(|cx| cx.bind_framebuffer(target, name, &call)).is_none() {
        call(target, name);
    }
}

pub(crate) fn glDeleteFramebuffers(
    real: real_type::glDeleteFramebuffers,
    count: i32,
    names: *const u32,
) {
    if count > 0 && !names.is_null() {
        // SAFETY: GL's contract: `count` names.
        let list = unsafe { std::slice::from_raw_parts(names, count as usize) };
        with_context(|cx| cx.delete_framebuffers(list));
    }
    unsafe { real(count, names) }
}

pub(crate) fn glFramebufferTexture(
    real: real_type::glFramebufferTexture,
    t: u32,
    a: u32,
    tex: u32,
    l: i32,
) {
    with_context(|cx| cx.attachment_changes(t));
    unsafe { real(t, a, tex, l) }
}

pub(crate) fn glFramebufferTexture2D(
    real: real_type::glFramebufferTexture2D,
    t: u32,
    a: u32,
    tt: u32,
    tex: u32,
    l: i32,
) {
    with_context(|cx| cx.attachment_changes(t));
    unsafe { real(t, a, tt, tex, l) }
}

pub(crate) fn glFramebufferTextureLayer(
    real: real_type::glFramebufferTextureLayer,
    t: u32,
    a: u32,
    tex: u32,
    l: i32,
    layer: i32,
) {
    with_context(|cx| cx.attachment_changes(t));
    unsafe { real(t, a, tex, l, layer) }
}

pub(crate) fn glFramebufferRenderbuffer(
    real: real_type::glFramebufferRenderbuffer,
    t: u32,
    a: u32,
    rt: u32,
    rb: u32,
) {
    with_context(|cx| cx.attachment_changes(t));
    unsafe { real(t, a, rt, rb) }
}

pub(crate) fn glNamedFramebufferTexture(
    real: real_type::glNamedFramebufferTexture,
    framebuffer: u32,
    a: u32,
    tex: u32,
    l: i32,
) {
    with_context(|cx| cx.named_attachment_changes(framebuffer));
    unsafe { real(framebuffer, a, tex, l) }
}

pub(crate) fn glNamedFramebufferRenderbuffer(
    real: real_type::glNamedFramebufferRenderbuffer,
    framebuffer: u32,
    a: u32,
    rt: u32,
    rb: u32,
) {
    with_context(|cx| cx.named_attachment_changes(framebuffer));
    unsafe { real(framebuffer, a, rt, rb) }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn glBlitNamedFramebuffer(
    real: real_type::glBlitNamedFramebuffer,
    read: u32,
    draw: u32,
    sx0: i32,
    sy0: i32,
    sx1: i32,
    sy1: i32,
    dx0: i32,
    dy0: i32,
    dx1: i32,
    dy1: i32,
    mask: u32,
    filter: u32,
) {
    // A blit from the G-buffer reads it: resolved first. One into (or
    // from) the lit target while the forward target stands in for it: the
    // forward target finished first.
    with_context(|cx| {
        if cx.twin_drawn && read != 0 && cx.gbuffer == Some(read) {
            cx.resolve();
        }
        if cx
            .forward
            .is_some_and(|f| f.fbo.is_some() && (f.output == draw || f.output == read))
        {
            cx.finish_forward();
        }
    });
    unsafe {
        real(
            read, draw, sx0, sy0, sx1, sy1, dx0, dy0, dx1, dy1, mask, filter,
        )
    }
}

/// A blit into the bound draw framebuffer: where the forward target stands
/// in for the lit target, finished first, so the blit reaches the lit
/// target itself (a multisampled target takes no blit in GL 3.2).
#[allow(clippy::too_many_arguments)]
pub(crate) fn glBlitFramebuffer(
    real: real_type::glBlitFramebuffer,
    sx0: i32,
    sy0: i32,
    sx1: i32,
    sy1: i32,
    dx0: i32,
    dy0: i32,
    dx1: i32,
    dy1: i32,
    mask: u32,
    filter: u32,
) {
    with_context(Context::forward_before_blit);
    unsafe { real(sx0, sy0, sx1, sy1, dx0, dy0, dx1, dy1, mask, filter) }
}

pub(crate) fn glBindTextureUnit(real: real_type::glBindTextureUnit, unit: u32, texture: u32) {
    unsafe { real(unit, texture) };
    with_context(|cx| {
        cx.unit_textures.insert(unit, texture);
    });
}

pub(crate) fn glActiveTexture(real: real_type::glActiveTexture, unit: u32) {
    unsafe { real(unit) };
    with_context(|cx| cx.active_unit = unit.wrapping_sub(GL_TEXTURE0));
}

pub(crate) fn glBindTexture(real: real_type::glBindTexture, target: u32, texture: u32) {
    unsafe { real(target, texture) };
    if target == GL_TEXTURE_2D {
        with_context(|cx| {
            cx.unit_textures.insert(cx.active_unit, texture);
        });
    } else if target == glow::TEXTURE_2D_ARRAY {
        with_context(|cx| {
            cx.unit_arrays.insert(cx.active_unit, texture);
        });
    }
}

pub(crate) fn glUseProgram(real: real_type::glUseProgram, program: u32) {
    unsafe { real(program) };
    with_context(|cx| cx.program = program);
}

pub(crate) fn glGetUniformLocation(
    real: real_type::glGetUniformLocation,
    program: u32,
    name: *const c_char,
) -> i32 {
    let location = unsafe { real(program, name) };
    if location >= 0 && !name.is_null() {
        // SAFETY: GL's contract: a C string.
        let name = unsafe { CStr::from_ptr(name) }.to_string_lossy();
        with_context(|cx| {
            let profile = settings().profile.as_ref();
            let projection = profile.map_or(Some("projection"), |p| p.projection_uniform());
            let view = profile.map_or(Some("view"), |p| p.view_uniform());
            let both = profile.and_then(|p| p.view_projection_uniform());
            let role = if projection == Some(&*name) {
                Some(MatrixRole::Projection)
            } else if view == Some(&*name) {
                Some(MatrixRole::View)
            } else if both == Some(&*name) {
                Some(MatrixRole::ViewProjection)
            } else {
                None
            };
            if let Some(role) = role {
                cx.matrix_uniforms.insert((program, location), role);
            }
            if cx.learning() {
                cx.uniform_names
                    .insert((program, location), name.to_string());
            }
        });
    }
    location
}

pub(crate) fn glBindBufferBase(
    real: real_type::glBindBufferBase,
    target: u32,
    index: u32,
    buffer: u32,
) {
    unsafe { real(target, index, buffer) };
    if target == glow::UNIFORM_BUFFER {
        with_context(|cx| cx.record_binding(index, buffer, 0, 0));
    }
}

pub(crate) fn glBindBufferRange(
    real: real_type::glBindBufferRange,
    target: u32,
    index: u32,
    buffer: u32,
    offset: isize,
    size: isize,
) {
    unsafe { real(target, index, buffer, offset, size) };
    if target == glow::UNIFORM_BUFFER {
        with_context(|cx| cx.record_binding(index, buffer, offset, size));
    }
}

pub(crate) fn glBufferSubData(
    real: real_type::glBufferSubData,
    target: u32,
    offset: isize,
    size: isize,
    data: *const c_void,
) {
    unsafe { real(target, offset, size, data) };
    if target == glow::UNIFORM_BUFFER {
        // SAFETY: GL read `size` bytes at `data`.
        with_context(|cx| unsafe { cx.record_buffer_data(None, offset, size, data) });
    }
}

/// New storage for the bound uniform buffer, with its values (a block
/// orphaned each frame): the values as a write of the whole buffer.
pub(crate) fn glBufferData(
    real: real_type::glBufferData,
    target: u32,
    size: isize,
    data: *const c_void,
    usage: u32,
) {
    unsafe { real(target, size, data, usage) };
    if target == glow::UNIFORM_BUFFER && !data.is_null() {
        // SAFETY: GL read `size` bytes at `data`.
        with_context(|cx| unsafe { cx.record_buffer_data(None, 0, size, data) });
    }
}

/// A write by name (GL 4.5 direct state access): any buffer, which a
/// uniform block may read (a light's values written before its draw).
pub(crate) fn glNamedBufferSubData(
    real: real_type::glNamedBufferSubData,
    buffer: u32,
    offset: isize,
    size: isize,
    data: *const c_void,
) {
    unsafe { real(buffer, offset, size, data) };
    if buffer != 0 {
        // SAFETY: GL read `size` bytes at `data`.
        with_context(|cx| unsafe { cx.record_buffer_data(Some(buffer), offset, size, data) });
    }
}

/// A uniform call made while the lighting is recorded.
fn record_uniform(location: i32, value: UniformValue) {
    with_context(|cx| cx.record_uniform(location, value));
}

macro_rules! uniform_scalars {
    ($($name:ident($($v:ident),+): $kind:ident, $ty:ty, $n:expr;)*) => {$(
        pub(crate) fn $name(real: real_type::$name, location: i32, $($v: $ty),+) {
            unsafe { real(location, $($v),+) };
            record_uniform(location, UniformValue::$kind($n, vec![$($v),+]));
        }
    )*};
}

uniform_scalars! {
    glUniform1f(v0): Float, f32, 1;
    glUniform2f(v0, v1): Float, f32, 2;
    glUniform3f(v0, v1, v2): Float, f32, 3;
    glUniform4f(v0, v1, v2, v3): Float, f32, 4;
    glUniform1i(v0): Int, i32, 1;
    glUniform2i(v0, v1): Int, i32, 2;
    glUniform3i(v0, v1, v2): Int, i32, 3;
    glUniform4i(v0, v1, v2, v3): Int, i32, 4;
}

macro_rules! uniform_vectors {
    ($($name:ident: $kind:ident, $ty:ty, $n:expr;)*) => {$(
        pub(crate) fn $name(real: real_type::$name, location: i32, count: i32, value: *const $ty) {
            unsafe { real(location, count, value) };
            // SAFETY: GL read `count` elements of $n components there.
            if let Some(values) = unsafe { copied(value, count, $n) } {
                record_uniform(location, UniformValue::$kind($n, values));
            }
        }
    )*};
}

uniform_vectors! {
    glUniform1fv: Float, f32, 1;
    glUniform2fv: Float, f32, 2;
    glUniform3fv: Float, f32, 3;
    glUniform4fv: Float, f32, 4;
    glUniform1iv: Int, i32, 1;
    glUniform2iv: Int, i32, 2;
    glUniform3iv: Int, i32, 3;
    glUniform4iv: Int, i32, 4;
}

pub(crate) fn glUniformMatrix4fv(
    real: real_type::glUniformMatrix4fv,
    location: i32,
    count: i32,
    transpose: u8,
    value: *const f32,
) {
    unsafe { real(location, count, transpose, value) };
    if count < 1 || value.is_null() {
        return;
    }
    // SAFETY: GL read `count` matrices there.
    if let Some(mut values) = unsafe { copied(value, count, 16) } {
        if transpose != 0 {
            for m in values.chunks_mut(16) {
                let t: Vec<f32> = m.to_vec();
                for c in 0..4 {
                    for r in 0..4 {
                        m[c * 4 + r] = t[r * 4 + c];
                    }
                }
            }
        }
        let first: Option<[f32; 16]> = values.get(..16).and_then(|m| m.try_into().ok());
        with_context(|cx| {
            // `--learn`: each matrix uniform's last value, by name.
            let key = (cx.program, location);
            if let (true, Some(name), Some(m)) = (cx.learning(), cx.uniform_names.get(&key), first)
            {
                let name = name.clone();
                cx.matrix_values.insert(name, m);
            }
        });
        record_uniform(location, UniformValue::Matrix4(values));
    }
    with_context(|cx| {
        let key = (cx.program, location);
        if cx.learning()
            && let Some(name) = cx.uniform_names.get(&key)
            && !cx.matrices_set.contains(name)
        {
            let name = name.clone();
            cx.matrices_set.push(name);
        }
        let Some(&role) = cx.matrix_uniforms.get(&key) else {
            return;
        };
        let mut m = [0f32; 16];
        // SAFETY: GL's contract: 16 floats per matrix.
        m.copy_from_slice(unsafe { std::slice::from_raw_parts(value, 16) });
        if transpose != 0 {
            let t = m;
            for c in 0..4 {
                for r in 0..4 {
                    m[c * 4 + r] = t[r * 4 + c];
                }
            }
        }
        match role {
            MatrixRole::Projection => cx.projection = Some(m),
            MatrixRole::View => cx.view = Some(m),
            MatrixRole::ViewProjection => {
                if let Some((projection, view)) = crate::camera::split_view_projection(&m) {
                    cx.projection = Some(projection);
                    cx.view = Some(view);
                }
            }
        }
    });
}

pub(crate) fn glGetIntegerv(real: real_type::glGetIntegerv, pname: u32, data: *mut i32) {
    unsafe { real(pname, data) };
    if data.is_null()
        || (pname != GL_DRAW_FRAMEBUFFER_BINDING && pname != GL_READ_FRAMEBUFFER_BINDING)
    {
        return;
    }
    // The program asks what it bound: the G-buffer, not the twin.
    with_context(|cx| {
        if cx.twin_bound
            && let Some(g) = cx.gbuffer
        {
            let seen = if pname == GL_DRAW_FRAMEBUFFER_BINDING {
                cx.draw_fbo
            } else {
                cx.read_fbo
            };
            if seen == g {
                // SAFETY: GL wrote one integer there.
                unsafe { *data = g as i32 };
            }
        }
    });
}

pub(crate) fn glClear(real: real_type::glClear, mask: u32) {
    with_context(|cx| {
        if cx.twin_bound {
            cx.twin_drawn = true;
        }
    });
    unsafe { real(mask) };
    with_context(|cx| {
        cx.record_clear(mask);
        cx.after_clear(mask);
    });
}

/// A `glClearBuffer*` call: through the twin it draws the frame; through
/// a framebuffer sharing the G-buffer's textures it is replayed on the
/// twin ([`Context::after_clear_buffer`]).
fn clear_buffer(call: ClearBuffer, real: impl FnOnce()) {
    with_context(|cx| {
        if cx.twin_bound {
            cx.twin_drawn = true;
        }
    });
    real();
    with_context(|cx| cx.after_clear_buffer(call));
}

/// The `glClearBuffer*v` and `glClearNamedFramebuffer*v` handlers: the
/// values read as GL reads them, the clear made, then replayed.
macro_rules! clear_vectors {
    ($($name:ident: $kind:ident, $ty:ty, $zero:expr;)*) => {$(
        pub(crate) fn $name(real: real_type::$name, buffer: u32, drawbuffer: i32, value: *const $ty) {
            // SAFETY: GL reads four values for a colour, one otherwise.
            let values = unsafe { read_values(value, buffer) };
            let value_read = ClearValue::$kind(values.map(|v| v.unwrap_or($zero)));
            clear_buffer(
                ClearBuffer { buffer, drawbuffer, value: value_read },
                || unsafe { real(buffer, drawbuffer, value) },
            );
        }
    )*};
    (named $($name:ident: $kind:ident, $ty:ty, $zero:expr;)*) => {$(
        pub(crate) fn $name(
            real: real_type::$name,
            framebuffer: u32,
            buffer: u32,
            drawbuffer: i32,
            value: *const $ty,
        ) {
            // SAFETY: GL reads four values for a colour, one otherwise.
            let values = unsafe { read_values(value, buffer) };
            let value_read = ClearValue::$kind(values.map(|v| v.unwrap_or($zero)));
            clear_named(
                framebuffer,
                ClearBuffer { buffer, drawbuffer, value: value_read },
                || unsafe { real(framebuffer, buffer, drawbuffer, value) },
            );
        }
    )*};
}

clear_vectors! {
    glClearBufferfv: Float, f32, 0.0;
    glClearBufferiv: Int, i32, 0;
    glClearBufferuiv: Uint, u32, 0;
}

pub(crate) fn glClearBufferfi(
    real: real_type::glClearBufferfi,
    buffer: u32,
    drawbuffer: i32,
    depth: f32,
    stencil: i32,
) {
    clear_buffer(
        ClearBuffer {
            buffer,
            drawbuffer,
            value: ClearValue::DepthStencil(depth, stencil),
        },
        || unsafe { real(buffer, drawbuffer, depth, stencil) },
    );
}

/// A `glClearNamedFramebuffer*` call (direct state access): of the
/// G-buffer itself, or of a framebuffer sharing its textures, replayed on
/// the twin ([`Context::after_clear_named`]).
fn clear_named(framebuffer: u32, call: ClearBuffer, real: impl FnOnce()) {
    real();
    with_context(|cx| cx.after_clear_named(framebuffer, call));
}

clear_vectors! {
    named
    glClearNamedFramebufferfv: Float, f32, 0.0;
    glClearNamedFramebufferiv: Int, i32, 0;
    glClearNamedFramebufferuiv: Uint, u32, 0;
}

pub(crate) fn glClearNamedFramebufferfi(
    real: real_type::glClearNamedFramebufferfi,
    framebuffer: u32,
    buffer: u32,
    drawbuffer: i32,
    depth: f32,
    stencil: i32,
) {
    clear_named(
        framebuffer,
        ClearBuffer {
            buffer,
            drawbuffer,
            value: ClearValue::DepthStencil(depth, stencil),
        },
        || unsafe { real(framebuffer, buffer, drawbuffer, depth, stencil) },
    );
}

/// The values a `glClearBuffer*v` call reads: four for `GL_COLOR`, one
/// otherwise (the rest `None`); none from a null pointer (GL's error).
///
/// # Safety
///
/// `value` is null or points at as many values as GL reads for `buffer`.
unsafe fn read_values<T: Copy>(value: *const T, buffer: u32) -> [Option<T>; 4] {
    let count = if buffer == glow::COLOR { 4 } else { 1 };
    let mut out = [None; 4];
    if value.is_null() {
        return out;
    }
    for (k, slot) in out.iter_mut().enumerate().take(count) {
        // SAFETY: the caller's.
        *slot = Some(unsafe { *value.add(k) });
    }
    out
}

pub(crate) fn glDrawArrays(real: real_type::glDrawArrays, mode: u32, first: i32, count: i32) {
    with_context(|cx| cx.before_draw(DrawCall::Arrays { mode, first, count }));
    unsafe { real(mode, first, count) }
}

pub(crate) fn glDrawArraysInstanced(
    real: real_type::glDrawArraysInstanced,
    m: u32,
    f: i32,
    c: i32,
    i: i32,
) {
    with_context(|cx| {
        cx.before_draw(DrawCall::ArraysInstanced {
            mode: m,
            first: f,
            count: c,
            instances: i,
        })
    });
    unsafe { real(m, f, c, i) }
}

pub(crate) fn glDrawElements(
    real: real_type::glDrawElements,
    m: u32,
    c: i32,
    k: u32,
    p: *const c_void,
) {
    with_context(|cx| {
        cx.before_draw(DrawCall::Elements {
            mode: m,
            count: c,
            kind: k,
            offset: p as usize,
        })
    });
    unsafe { real(m, c, k, p) }
}

pub(crate) fn glDrawElementsInstanced(
    real: real_type::glDrawElementsInstanced,
    m: u32,
    c: i32,
    k: u32,
    p: *const c_void,
    i: i32,
) {
    with_context(|cx| {
        cx.before_draw(DrawCall::ElementsInstanced {
            mode: m,
            count: c,
            kind: k,
            offset: p as usize,
            instances: i,
        })
    });
    unsafe { real(m, c, k, p, i) }
}

pub(crate) fn glDrawElementsBaseVertex(
    real: real_type::glDrawElementsBaseVertex,
    m: u32,
    c: i32,
    k: u32,
    p: *const c_void,
    b: i32,
) {
    with_context(|cx| {
        cx.before_draw(DrawCall::ElementsBaseVertex {
            mode: m,
            count: c,
            kind: k,
            offset: p as usize,
            base: b,
        })
    });
    unsafe { real(m, c, k, p, b) }
}

pub(crate) fn glDrawRangeElements(
    real: real_type::glDrawRangeElements,
    m: u32,
    s: u32,
    e: u32,
    c: i32,
    k: u32,
    p: *const c_void,
) {
    with_context(|cx| {
        cx.before_draw(DrawCall::Elements {
            mode: m,
            count: c,
            kind: k,
            offset: p as usize,
        })
    });
    unsafe { real(m, s, e, c, k, p) }
}

pub(crate) fn glXSwapBuffers(
    real: real_type::glXSwapBuffers,
    display: *mut c_void,
    drawable: c_ulong,
) {
    with_context(Context::end_frame);
    unsafe { real(display, drawable) }
}

/// A destroyed context's state is forgotten: its GL objects went with
/// it, and the retrofit's handle is left unfreed (`dmsaa_destroy` would
/// call GL without the context), a small allocation per context.
fn forget_context(context: *mut c_void) {
    if INSIDE.with(|i| i.get()) {
        return;
    }
    if let Ok(mut guard) = CONTEXTS.lock()
        && let Some(map) = guard.as_mut()
        && let Some(cx) = map.remove(&(context as usize))
        && settings().learn.is_some()
    {
        super::learn::at_end(&cx, "when its context was destroyed");
    }
}

pub(crate) fn glXDestroyContext(
    real: real_type::glXDestroyContext,
    display: *mut c_void,
    context: *mut c_void,
) {
    forget_context(context);
    unsafe { real(display, context) }
}

pub(crate) fn eglDestroyContext(
    real: real_type::eglDestroyContext,
    display: *mut c_void,
    context: *mut c_void,
) -> u32 {
    forget_context(context);
    unsafe { real(display, context) }
}

pub(crate) fn eglSwapBuffers(
    real: real_type::eglSwapBuffers,
    display: *mut c_void,
    surface: *mut c_void,
) -> u32 {
    with_context(Context::end_frame);
    unsafe { real(display, surface) }
}
