//! A sequence run through the C API: each call made, the host's GL state
//! compared around it, and what a failure must look like.

use deferred_msaa::MsaaRetrofit;
use deferred_msaa_capi as c;
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_testkit::projection;
use glow::HasContext;
use std::ffi::{CStr, c_char, c_void};

use super::host::*;
use super::sequence::*;
use crate::common::gl_state::GlState;

thread_local! {
    /// Calls by name: how many returned OK, how many another status.
    static STATS: std::cell::RefCell<std::collections::BTreeMap<String, (u64, u64)>> =
        Default::default();
}

/// How many library calls were checked on this thread since the last
/// time this was asked.
pub fn take_call_count() -> u64 {
    STATS.with(|s| {
        let s = std::mem::take(&mut *s.borrow_mut());
        s.values().map(|(ok, other)| ok + other).sum()
    })
}

/// The calls made on this thread since the last call, by name: OK and
/// other statuses, one line.
pub fn take_stats() -> String {
    STATS.with(|s| {
        let s = std::mem::take(&mut *s.borrow_mut());
        s.iter()
            .map(|(name, (ok, other))| format!("{name} {ok} OK / {other} not"))
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// Whether a failed `dmsaa_retrofit_new` was refused by the C layer's own
/// checks, which come before any GL call (null pointers, options out of
/// range, a zero framebuffer): every refusal after those is GL's.
pub(super) fn before_gl(status: c::DmsaaStatus, message: &str) -> bool {
    status == c::DmsaaStatus::NullPointer
        || (status == c::DmsaaStatus::InvalidArgument
            && !message.contains("is not a framebuffer object"))
}

/// What the loader is given as user data.
pub(super) struct Loader<'a> {
    pub(super) context: &'a HeadlessContext,
    pub(super) missing: Option<&'static str>,
}

unsafe extern "C" fn load(name: *const c_char, user: *mut c_void) -> *const c_void {
    // SAFETY: `user` is the `Loader` the fuzzer passed with this function,
    // alive for the call; `name` is the library's NUL-terminated name.
    let (loader, name) = unsafe { (&*(user as *const Loader<'_>), CStr::from_ptr(name)) };
    let name = name.to_str().unwrap_or("");
    if loader.missing == Some(name) {
        return std::ptr::null();
    }
    loader.context.get_proc_address(name)
}

/// What the fuzzer knows of a live handle.
pub(super) struct Handle {
    pub(super) raw: *mut c::DmsaaRetrofit,
    pub(super) options: c::DmsaaOptions,
    /// The framebuffer it was made for.
    pub(super) fbo: u32,
}

/// The calling thread's `dmsaa_last_error()`.
pub fn last_message() -> String {
    last_error()
}

pub(super) fn last_error() -> String {
    // SAFETY: the library's NUL-terminated message.
    unsafe { CStr::from_ptr(c::dmsaa_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// The projection (and view) a handle with `options` is given.
pub(super) fn matrices(kind: Projection, options: &c::DmsaaOptions) -> ([f32; 16], [f32; 16]) {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let m = match kind {
        Projection::Orthographic => {
            let mut m = [0.0; 16];
            m[0] = 1.0;
            m[5] = 1.0;
            m[10] = -1.0;
            m[15] = 1.0;
            m
        }
        Projection::NaN => [f64::NAN; 16],
        _ if options.depth_mode == c::DMSAA_DEPTH_REVERSED_Z => {
            projection::perspective_reversed(1.0, aspect, 0.1, Some(100.0))
        }
        _ => projection::perspective(1.0, aspect, 0.1, Some(100.0)),
    };
    let mut view = [0f32; 16];
    for i in 0..4 {
        view[i * 5] = 1.0;
    }
    (projection::to_f32(&m), view)
}

/// One sequence's run: the handles, the host, the failures found.
pub(super) struct Run<'a> {
    pub(super) gl: &'a glow::Context,
    pub(super) context: &'a HeadlessContext,
    pub(super) host: Host,
    pub(super) slots: [Option<Handle>; 2],
    /// The Rust API's handles, for a sequence of [`Api::Rust`].
    pub(super) retrofits: [Option<(MsaaRetrofit, c::DmsaaOptions)>; 2],
    pub(super) api: Api,
    /// A Rust API call is under way: its message is its error's, checked by
    /// [`Run::call_rust`], not `dmsaa_last_error`.
    pub(super) in_rust_call: bool,
    pub(super) failures: Vec<String>,
}

impl Run<'_> {
    pub(super) fn handle(&self, which: Which) -> *mut c::DmsaaRetrofit {
        match which {
            Which::Slot(k) => self.slots[k]
                .as_ref()
                .map_or(std::ptr::null_mut(), |h| h.raw),
            Which::Null => std::ptr::null_mut(),
        }
    }

    pub(super) fn fail(&mut self, index: usize, what: String) {
        self.failures.push(format!("call {index}: {what}"));
    }

    /// Run one library call with the checks around it; its status.
    pub(super) fn call(
        &mut self,
        index: usize,
        name: &str,
        f: impl FnOnce(&mut Self) -> c::DmsaaStatus,
    ) -> c::DmsaaStatus {
        let gl = self.gl;
        // The host's own GL calls must be clean, or the check after is moot.
        let pending = unsafe { gl.get_error() };
        if pending != glow::NO_ERROR {
            self.fail(
                index,
                format!("the fuzzer's host left GL error 0x{pending:04X}"),
            );
            while unsafe { gl.get_error() } != glow::NO_ERROR {}
        }
        let before = GlState::capture(gl);
        let status = f(self);
        // A Rust call's outcome, by its own words.
        let outcome = match (self.in_rust_call, status) {
            (false, status) => format!("{status:?}"),
            (true, c::DmsaaStatus::Ok) => "Ok".into(),
            (true, c::DmsaaStatus::Panic) => "a panic".into(),
            (true, _) => "Err".into(),
        };
        STATS.with(|s| {
            let mut s = s.borrow_mut();
            let entry = s.entry(name.to_string()).or_default();
            if status == c::DmsaaStatus::Ok {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        });
        let error = unsafe { gl.get_error() };
        if error != glow::NO_ERROR {
            self.fail(
                index,
                format!("{name} returned {outcome} and left GL error 0x{error:04X}"),
            );
            while unsafe { gl.get_error() } != glow::NO_ERROR {}
        }
        let after = GlState::capture(gl);
        for d in before.differences(&after) {
            self.fail(index, format!("{name} ({outcome}) changed {d}"));
        }
        if self.in_rust_call {
            return status;
        }
        if status == c::DmsaaStatus::Panic {
            self.fail(index, format!("{name} panicked: {}", last_error()));
        }
        if std::env::var_os("DEFERRED_MSAA_VERBOSE").is_some() {
            let message = if status == c::DmsaaStatus::Ok {
                String::new()
            } else {
                last_error()
            };
            eprintln!("call {index}: {name}: {status:?} {message}");
        }
        if status != c::DmsaaStatus::Ok {
            let message = last_error();
            let driver_log = status == c::DmsaaStatus::Gl
                && (message.contains("failed to compile") || message.contains("failed to link"));
            if message.trim().is_empty() || (message.contains('\n') && !driver_log) {
                self.fail(
                    index,
                    format!("{name} returned {status:?} with the message {message:?}"),
                );
            }
        }
        status
    }

    pub(super) fn new_handle(
        &mut self,
        index: usize,
        fbo: Fbo,
        options: &Options,
        missing: Option<usize>,
    ) {
        let Some(slot) = self.slots.iter().position(Option::is_none) else {
            return;
        };
        let c_options = options.apply();
        let names = loader_names();
        let missing = missing.map(|k| names[k % names.len()]);
        // A conditional function is called (and so needed) only where the
        // context offers it.
        let needed = missing.filter(|name| {
            deferred_msaa_lab::gl::REQUIRED_FUNCTIONS.contains(name)
                || deferred_msaa_lab::gl::first_missing_conditional_function(self.gl, |n| {
                    if n == *name {
                        std::ptr::null()
                    } else {
                        self.context.get_proc_address(n)
                    }
                })
                .is_some()
        });
        let loader = Loader {
            context: self.context,
            missing,
        };
        let host_fbo = self.host.fbo_arg(fbo);
        let live = c::dmsaa_live_objects();
        let mut out: *mut c::DmsaaRetrofit = std::ptr::NonNull::dangling().as_ptr();
        let status = self.call(index, "dmsaa_retrofit_new", |_| unsafe {
            c::dmsaa_retrofit_new(
                Some(load),
                &loader as *const Loader<'_> as *mut c_void,
                host_fbo,
                &c_options,
                &mut out,
            )
        });
        if status == c::DmsaaStatus::Ok {
            if out.is_null() {
                self.fail(
                    index,
                    "dmsaa_retrofit_new returned OK and a null handle".into(),
                );
                return;
            }
            if let Some(name) = needed {
                self.fail(
                    index,
                    format!("dmsaa_retrofit_new succeeded without {name}"),
                );
            }
            self.slots[slot] = Some(Handle {
                raw: out,
                options: c_options,
                fbo: host_fbo,
            });
            return;
        }
        if !out.is_null() {
            self.fail(
                index,
                format!("a failed dmsaa_retrofit_new ({status:?}) left *out set"),
            );
        }
        if c::dmsaa_live_objects() != live {
            self.fail(
                index,
                format!(
                    "a failed dmsaa_retrofit_new ({status:?}) left {} GL objects",
                    c::dmsaa_live_objects() - live
                ),
            );
        }
        if let Some(name) = needed {
            let message = last_error();
            if !before_gl(status, &message)
                && (status != c::DmsaaStatus::Unsupported || !message.contains(name))
            {
                self.fail(
                    index,
                    format!("a loader without {name}: {status:?}, {message:?}"),
                );
            }
        }
        if fbo == Fbo::NotAFramebuffer
            && missing.is_none()
            && !before_gl(status, &last_error())
            && !last_error().contains("is not a framebuffer object")
        {
            self.fail(
                index,
                format!(
                    "a name that is no framebuffer was refused as: {}",
                    last_error()
                ),
            );
        }
    }

    /// The host puts its G-buffer back; `which`'s handle must refresh and
    /// resolve a uniform draw into the values the host's own clear gives.
    pub(super) fn recover(&mut self, index: usize, which: Which) {
        let gl = self.gl;
        self.host.put_back(gl);
        let Which::Slot(k) = which else {
            return;
        };
        let Some((options, fbo)) = self.slots[k].as_ref().map(|h| (h.options, h.fbo)) else {
            return;
        };
        let raw = self.handle(which);
        if fbo != self.host.fbo.0.get() {
            // The host made its framebuffer again under another name: the
            // handle refuses, saying its framebuffer is gone.
            let status = self.call(index, "dmsaa_refresh (framebuffer gone)", |_| unsafe {
                c::dmsaa_refresh(raw)
            });
            if status != c::DmsaaStatus::InvalidArgument
                || !last_error().contains("no longer a framebuffer object")
            {
                self.fail(
                    index,
                    format!(
                        "dmsaa_refresh with the framebuffer deleted: {status:?}: {}",
                        last_error()
                    ),
                );
            }
            return;
        }
        let status = self.call(index, "dmsaa_refresh (recovery)", |_| unsafe {
            c::dmsaa_refresh(raw)
        });
        if status != c::DmsaaStatus::Ok {
            self.fail(
                index,
                format!(
                    "no recovery: with the G-buffer put back, dmsaa_refresh returned {status:?}: {}",
                    last_error()
                ),
            );
            return;
        }
        let expected = self.expected_frame();
        self.draw(index, which);
        let (projection, view) = matrices(Projection::Perspective, &options);
        let status = self.call(index, "dmsaa_resolve (recovery)", |_| unsafe {
            c::dmsaa_resolve(raw, projection.as_ptr(), view.as_ptr())
        });
        if status != c::DmsaaStatus::Ok {
            self.fail(
                index,
                format!(
                    "no recovery: after dmsaa_refresh, dmsaa_resolve returned {status:?}: {}",
                    last_error()
                ),
            );
            return;
        }
        self.check_frame(index, &expected);
    }

    /// The host's own clear of its G-buffer, read back: what a resolve of
    /// the uniform draw must give. The images are cleared to something
    /// else after, so that the resolve must write them.
    pub(super) fn expected_frame(&mut self) -> Vec<Vec<f32>> {
        let gl = self.gl;
        unsafe {
            reset(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.host.fbo));
            Host::clear(gl, self.host.colors);
        }
        let expected = self.host.read(gl);
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.host.fbo));
            for k in 0..self.host.colors {
                gl.clear_buffer_f32_slice(glow::COLOR, k as u32, &[0.0; 4]);
            }
            gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, 1.0, 0);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
        expected
    }

    /// Every attachment and the depth bit for bit as `expected`.
    pub(super) fn check_frame(&mut self, index: usize, expected: &[Vec<f32>]) {
        let got = self.host.read(self.gl);
        for (k, (g, e)) in got.iter().zip(expected).enumerate() {
            if let Some(p) = g
                .iter()
                .zip(e)
                .position(|(a, b)| a.to_bits() != b.to_bits())
            {
                let what = if k < self.host.colors {
                    format!("colour attachment {k}")
                } else {
                    "depth".to_string()
                };
                self.fail(
                    index,
                    format!(
                        "no recovery: the resolved {what} is {} at value {p}, the host's own {}",
                        g[p], e[p]
                    ),
                );
                return;
            }
        }
    }

    /// The host's frame into `which`'s framebuffer, begun as every frame
    /// is: a uniform value per attachment.
    pub(super) fn draw(&mut self, index: usize, which: Which) {
        let raw = self.handle(which);
        let mut fbo = 0u32;
        let status = self.call(index, "dmsaa_begin_frame", |_| unsafe {
            c::dmsaa_begin_frame(raw, &mut fbo)
        });
        if status != c::DmsaaStatus::Ok {
            return;
        }
        let Some(fbo) = std::num::NonZeroU32::new(fbo).map(glow::NativeFramebuffer) else {
            self.fail(index, "dmsaa_begin_frame gave 0".into());
            return;
        };
        self.draw_into(fbo);
    }

    /// The uniform draw into a multisampled framebuffer.
    pub(super) fn draw_into(&mut self, fbo: glow::Framebuffer) {
        let gl = self.gl;
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            let draw_buffers = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).max(1) as u32;
            for i in 0..draw_buffers {
                gl.color_mask_draw_buffer(i, true, true, true, true);
            }
            gl.color_mask(true, true, true, true);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::RASTERIZER_DISCARD);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            Host::clear(gl, self.host.colors);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    pub(super) fn step(&mut self, index: usize, op: &Op) {
        let gl = self.gl;
        if self.api == Api::Rust && self.step_rust(index, op) {
            return;
        }
        match op {
            Op::New {
                fbo,
                options,
                missing,
            } => self.new_handle(index, *fbo, options, *missing),
            Op::Destroy(which) => {
                let raw = self.handle(*which);
                self.call(index, "dmsaa_destroy", |_| {
                    unsafe { c::dmsaa_destroy(raw) };
                    c::DmsaaStatus::Ok
                });
                if let Which::Slot(k) = which {
                    self.slots[*k] = None;
                }
            }
            Op::Getters(which) => {
                let raw = self.handle(*which);
                let mut value = 0u32;
                type Getter =
                    unsafe extern "C" fn(*mut c::DmsaaRetrofit, *mut u32) -> c::DmsaaStatus;
                let getters: [(&str, Getter); 3] = [
                    ("dmsaa_framebuffer", c::dmsaa_framebuffer),
                    ("dmsaa_samples", c::dmsaa_samples),
                    (
                        "dmsaa_second_layer_selection",
                        c::dmsaa_second_layer_selection,
                    ),
                ];
                for (name, f) in getters {
                    let status = self.call(index, name, |_| unsafe { f(raw, &mut value) });
                    if raw.is_null() != (status == c::DmsaaStatus::NullPointer) {
                        self.fail(index, format!("{name} on {which:?}: {status:?}"));
                    }
                }
            }
            Op::Resolve(which, kind, with_view) => {
                let raw = self.handle(*which);
                let options = match which {
                    Which::Slot(k) => self.slots[*k]
                        .as_ref()
                        .map_or_else(|| c::dmsaa_options_default(), |h| h.options),
                    Which::Null => c::dmsaa_options_default(),
                };
                let (projection, view) = matrices(*kind, &options);
                let p = if *kind == Projection::Null {
                    std::ptr::null()
                } else {
                    projection.as_ptr()
                };
                let v = if *with_view {
                    view.as_ptr()
                } else {
                    std::ptr::null()
                };
                self.call(index, "dmsaa_resolve", |_| unsafe {
                    c::dmsaa_resolve(raw, p, v)
                });
            }
            Op::Begin(which, output, null_run) => {
                let raw = self.handle(*which);
                let output = self.host.fbo_arg(*output);
                let mut run = false;
                let run_ptr: *mut bool = if *null_run {
                    std::ptr::null_mut()
                } else {
                    &mut run
                };
                self.call(index, "dmsaa_begin_second_layer", |_| unsafe {
                    c::dmsaa_begin_second_layer(raw, output, run_ptr)
                });
            }
            Op::Finish(which, output) => {
                let raw = self.handle(*which);
                let output = self.host.fbo_arg(*output);
                self.call(index, "dmsaa_finish_second_layer", |_| unsafe {
                    c::dmsaa_finish_second_layer(raw, output)
                });
            }
            Op::SetOptions(which, options) => {
                let raw = self.handle(*which);
                let c_options = options.apply();
                let status = self.call(index, "dmsaa_set_options", |_| unsafe {
                    c::dmsaa_set_options(raw, &c_options)
                });
                if let (c::DmsaaStatus::Ok, Which::Slot(k)) = (status, which) {
                    if let Some(h) = self.slots[*k].as_mut() {
                        h.options = c_options;
                    }
                }
            }
            Op::Refresh(which) => {
                let raw = self.handle(*which);
                self.call(index, "dmsaa_refresh", |_| unsafe { c::dmsaa_refresh(raw) });
            }
            Op::Draw(which) => self.draw(index, *which),
            Op::Dirty(seed) => {
                dirty(gl, &self.host, *seed);
                // A host may leave state GL refuses (a deleted name bound):
                // not the library's concern.
                while unsafe { gl.get_error() } != glow::NO_ERROR {}
            }
            Op::Set(setting) => unsafe {
                match *setting {
                    Setting::BlendOnlyOn(i) => {
                        gl.disable(glow::BLEND);
                        gl.enable_draw_buffer(glow::BLEND, i);
                    }
                    Setting::MaskOff(i) => gl.color_mask_draw_buffer(i, false, false, false, false),
                    Setting::StencilReferences(front, back) => {
                        gl.stencil_func_separate(glow::FRONT, glow::EQUAL, front, 0xFF);
                        gl.stencil_func_separate(glow::BACK, glow::GEQUAL, back, 0x7F);
                    }
                    Setting::DefaultFramebuffer => gl.bind_framebuffer(glow::FRAMEBUFFER, None),
                    Setting::Viewport(i) => {
                        if crate::common::gl_state::has_viewport_arrays(gl) {
                            let k = i as i32;
                            gl.viewport_f32_slice(i, 1, &[[1.0 + k as f32, 2.0, 7.5, 9.0]]);
                            gl.scissor_slice(i, 1, &[[k, 3, 5, 6]]);
                            gl.disable(glow::SCISSOR_TEST);
                            gl.enable_draw_buffer(glow::SCISSOR_TEST, i);
                        }
                    }
                }
            },
            Op::Reallocate(k) => {
                let k = (*k).min(self.host.colors);
                self.host.specify(gl, k, OTHER_SIZE);
            }
            Op::Delete(k) => {
                let k = (*k).min(self.host.colors);
                self.host.delete(gl, k);
            }
            Op::PutBack => self.host.put_back(gl),
            Op::Recreate => self.host.recreate(gl),
            Op::Recover(which) => self.recover(index, *which),
            Op::Frame(which) => {
                self.draw(index, *which);
                self.step(index, &Op::Resolve(*which, Projection::Perspective, true));
                let raw = self.handle(*which);
                let output = self.host.light_fbo.0.get();
                let mut run = false;
                let status = self.call(index, "dmsaa_begin_second_layer", |_| unsafe {
                    c::dmsaa_begin_second_layer(raw, output, &mut run)
                });
                if status == c::DmsaaStatus::Ok && run {
                    self.step(index, &Op::Finish(*which, Fbo::Light));
                }
            }
        }
    }
}
