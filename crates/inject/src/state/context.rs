//! One GL context's view of the program, the framebuffers it inspected,
//! its retrofit, and the calls into the C API that every part makes.

use super::run::{say_once, settings};
use crate::check;
use crate::profile::Profile;
use crate::real::{Api, load_real, real, real_type};
use crate::replay::Recording;
use deferred_msaa_capi as capi;
use std::collections::HashMap;
use std::ffi::CStr;

pub(super) const GL_READ_FRAMEBUFFER: u32 = 0x8CA8;
pub(super) const GL_DRAW_FRAMEBUFFER: u32 = 0x8CA9;

/// What the inspection of a framebuffer found.
#[derive(Clone, Debug, Default)]
pub(crate) struct Framebuffer {
    pub(crate) complete: bool,
    pub(crate) samples: i32,
    /// Colour attachment number → texture name, for texture attachments.
    pub(crate) colour_textures: Vec<(u32, u32)>,
    /// Colour attachments of any kind.
    pub(crate) colour_attachments: u32,
    /// Each colour attachment's component type and size (`float16`…).
    pub(crate) formats: Vec<String>,
    /// Colour attachment number → its channels (1 to 4).
    pub(crate) channels: Vec<(u32, u32)>,
    pub(crate) depth: bool,
    /// Two or more colour attachments are layers of one texture
    /// (`glFramebufferTextureLayer` on an array texture).
    pub(crate) layered: bool,
    /// Drawn into since it was inspected.
    pub(crate) drawn: bool,
    /// Its attachments changed since it was inspected.
    pub(crate) stale: bool,
}

impl Framebuffer {
    /// The heuristic's shape of a G-buffer.
    pub(super) fn looks_like_gbuffer(&self) -> bool {
        self.complete && self.samples == 0 && self.colour_textures.len() >= 2 && self.depth
    }

    pub(super) fn describe(&self) -> String {
        format!(
            "{} colour textures ({}){}",
            self.colour_textures.len(),
            self.formats.join(", "),
            if self.depth { " + depth" } else { "" }
        )
    }
}

/// The retrofit made for a context's G-buffer.
/// The forward target of one frame (the state of `state/forward.rs`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Forward {
    /// The program's lit target (0: the default framebuffer).
    pub(super) output: u32,
    /// The forward target, once begun.
    pub(super) fbo: Option<u32>,
}

/// What a matrix uniform the library follows holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MatrixRole {
    /// The projection.
    Projection,
    /// The view.
    View,
    /// Their product (`viewProjection`), taken apart.
    ViewProjection,
}

pub(super) struct Retrofit {
    pub(super) handle: *mut capi::DmsaaRetrofit,
    pub(super) world_space: bool,
    pub(super) layers: u32,
    /// Whether the G-buffer was read back after its first resolve.
    pub(super) looked: bool,
    /// Whether `dmsaa_begin_frame` began the frame being drawn (at the
    /// first hand-out of the twin or replayed clear after a resolve).
    pub(super) begun: bool,
}

// SAFETY: the handle is used only under the state's lock, with the
// context it was made on current (the state is kept per context).
unsafe impl Send for Retrofit {}

/// A pass the program drew in one frame (for `--learn`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Pass {
    pub(crate) framebuffer: u32,
    pub(crate) program: u32,
    pub(crate) draws: u32,
}

/// One GL context's view of the program, and its retrofit.
pub(crate) struct Context {
    pub(super) api: Api,
    pub(super) gl: Option<glow::Context>,
    /// The framebuffers bound for drawing and reading, as the program
    /// sees them (the G-buffer, never the twin).
    pub(super) draw_fbo: u32,
    pub(super) read_fbo: u32,
    pub(super) program: u32,
    pub(super) active_unit: u32,
    pub(super) unit_textures: HashMap<u32, u32>,
    /// The `GL_TEXTURE_2D_ARRAY` bound on each unit (a G-buffer of one
    /// array's layers is read through it; never replayed).
    pub(super) unit_arrays: HashMap<u32, u32>,
    /// (program, location) → "projection" or "view".
    pub(super) matrix_uniforms: HashMap<(u32, i32), MatrixRole>,
    /// (program, location) → uniform name, for `--learn`.
    pub(crate) uniform_names: HashMap<(u32, i32), String>,
    pub(crate) matrices_set: Vec<String>,
    /// `--learn`: each matrix uniform's last value (untransposed), by name.
    pub(crate) matrix_values: HashMap<String, [f32; 16]>,
    pub(super) projection: Option<[f32; 16]>,
    pub(super) view: Option<[f32; 16]>,
    /// `GL_UNIFORM_BUFFER` binding points: index → (buffer, start, size;
    /// 0 for the whole buffer).
    pub(crate) uniform_bindings: HashMap<u32, (u32, i64, i64)>,
    /// The projections and views written into each uniform buffer: buffer
    /// → (byte offset → which).
    pub(crate) block_matrices:
        HashMap<u32, std::collections::BTreeMap<u32, crate::camera::BlockMatrix>>,
    /// The camera block the writes showed, where the retrofit reads it.
    pub(super) found_block: Option<crate::profile::CameraBlock>,
    pub(crate) framebuffers: HashMap<u32, Framebuffer>,
    pub(crate) gbuffer: Option<u32>,
    /// Every framebuffer a later draw read two colour textures of, while
    /// no retrofit is made (without a profile): more than one is a choice
    /// left to a profile.
    pub(super) read_as_gbuffers: std::collections::HashSet<u32>,
    /// The G-buffer last deleted, as it was seen (for `--learn`).
    pub(crate) last_gbuffer: Option<Framebuffer>,
    /// How many times a G-buffer was deleted (for `--learn`: one made anew
    /// each frame, or one deleted at the program's end).
    pub(crate) gbuffers_deleted: u32,
    pub(super) retrofit: Option<Retrofit>,
    /// The retrofit of a G-buffer found by the profile's signature and
    /// deleted: kept for the next one the program makes
    /// (`dmsaa_refresh_with`), its programs compiled.
    pub(super) orphan: Option<Retrofit>,
    pub(super) needs_refresh: bool,
    pub(super) twin_bound: bool,
    pub(super) twin_drawn: bool,
    pub(super) off: bool,
    pub(super) frames: u64,
    /// Draw calls seen.
    pub(crate) draws: u64,
    pub(crate) passes: Vec<Pass>,
    pub(crate) last_frame: Vec<Pass>,
    /// The draws after this frame's resolve, up to the lighting's end.
    pub(super) recording: Option<Recording>,
    /// After the lighting: the forward target of the frame.
    pub(super) forward: Option<Forward>,
    /// The library refused the forward target once (a float lit target
    /// with no `layer_mix` declared): not asked for again.
    pub(super) forward_refused: bool,
}

impl Context {
    pub(super) fn new(api: Api) -> Self {
        let (projection, view) = settings()
            .profile
            .as_ref()
            .map(Profile::fixed_matrices)
            .unwrap_or((None, None));
        let off = if let Some(why) = &settings().off {
            say_once("profile", &format!("{why}; leaving the program untouched"));
            true
        } else {
            false
        };
        Context {
            api,
            gl: None,
            draw_fbo: 0,
            read_fbo: 0,
            program: 0,
            active_unit: 0,
            unit_textures: HashMap::new(),
            unit_arrays: HashMap::new(),
            matrix_uniforms: HashMap::new(),
            uniform_names: HashMap::new(),
            matrices_set: Vec::new(),
            matrix_values: HashMap::new(),
            projection,
            view,
            uniform_bindings: HashMap::new(),
            block_matrices: HashMap::new(),
            found_block: None,
            framebuffers: HashMap::new(),
            gbuffer: None,
            read_as_gbuffers: std::collections::HashSet::new(),
            last_gbuffer: None,
            gbuffers_deleted: 0,
            retrofit: None,
            orphan: None,
            needs_refresh: false,
            twin_bound: false,
            twin_drawn: false,
            off,
            frames: 0,
            draws: 0,
            passes: Vec::new(),
            last_frame: Vec::new(),
            recording: None,
            forward: None,
            forward_refused: false,
        }
    }

    /// The context's real GL, for the library's own queries.
    pub(super) fn gl(&mut self) -> &glow::Context {
        let api = self.api;
        self.gl.get_or_insert_with(|| {
            // SAFETY: this context is current; the loader gives its real
            // entry points.
            unsafe { glow::Context::from_loader_function_cstr(|name: &CStr| load_real(api, name)) }
        })
    }

    pub(super) fn learning(&self) -> bool {
        settings().learn.is_some()
    }

    /// `call` into the library; in `--check` mode with the state read
    /// before and after and the errors it leaves counted.
    pub(super) fn checked(
        &mut self,
        call: &str,
        f: impl FnOnce(&glow::Context) -> capi::DmsaaStatus,
    ) -> capi::DmsaaStatus {
        let gl = self.gl();
        if !settings().check {
            return f(gl);
        }
        let pending = check::drain_errors(gl);
        let before = check::snapshot(gl);
        let status = f(gl);
        let after = check::snapshot(gl);
        let errors = check::drain_errors(gl);
        let changed = check::differences(&before, &after);
        for c in &changed {
            eprintln!("deferred-msaa inject: check: {call} changed {c}");
        }
        for e in &errors {
            eprintln!("deferred-msaa inject: check: {call} left GL error 0x{e:04x}");
        }
        if !pending.is_empty() {
            say_once(
                "pending",
                &format!(
                    "check: the program left GL error(s) {pending:04x?} pending before {call} (read, so cleared, by the check)"
                ),
            );
        }
        let mut t = check::TOTALS.lock().unwrap_or_else(|e| e.into_inner());
        t.calls += 1;
        t.values = before.len();
        t.changed += changed.len() as u64;
        t.errors += errors.len() as u64;
        t.program_errors += pending.len() as u64;
        *t.by_call.entry(call.to_string()).or_default() += 1;
        status
    }

    /// A library error: say it, free the retrofit, and leave the program
    /// alone for the rest of the run.
    pub(super) fn fail(&mut self, call: &str) {
        // SAFETY: the C API's message, a C string valid until its next call.
        let message = unsafe { CStr::from_ptr(capi::dmsaa_last_error()) }
            .to_string_lossy()
            .into_owned();
        say_once(
            "failed",
            &format!("{call} failed ({message}); the retrofit is off for the rest of the run"),
        );
        self.give_up();
    }

    /// Free the retrofit; a twin still bound is replaced by the G-buffer,
    /// so the program goes on drawing into its own framebuffer.
    pub(super) fn give_up(&mut self) {
        self.off = true;
        // A forward target bound in the lit target's place: the lit target
        // bound back, so the program goes on drawing into it.
        if let Some(Forward {
            output,
            fbo: Some(_),
        }) = self.forward.take()
            && self.draw_fbo == output
        {
            real_bind(GL_DRAW_FRAMEBUFFER, output);
        }
        if self.twin_bound {
            if let Some(g) = self.gbuffer {
                real_bind(GL_DRAW_FRAMEBUFFER, g);
                if self.read_fbo == g {
                    real_bind(GL_READ_FRAMEBUFFER, g);
                }
            }
            self.twin_bound = false;
        }
        self.twin_drawn = false;
        if let Some(r) = self.retrofit.take() {
            // SAFETY: a handle the C API made, on its context.
            self.checked("dmsaa_destroy", |_| {
                unsafe { capi::dmsaa_destroy(r.handle) };
                capi::DmsaaStatus::Ok
            });
        }
    }
}

/// The real `glBindFramebuffer`, for the library's own binds.
pub(super) fn real_bind(target: u32, name: u32) {
    if let Some(p) = real::glBindFramebuffer.get() {
        // SAFETY: the driver's glBindFramebuffer.
        unsafe { std::mem::transmute::<usize, real_type::glBindFramebuffer>(p)(target, name) };
    }
}
