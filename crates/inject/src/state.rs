//! What the library keeps per GL context, and what each watched call does:
//! find the G-buffer, bind the retrofit's framebuffer in its place, resolve
//! when the program leaves it.
//!
//! The G-buffer, without a profile: a complete single-sample framebuffer
//! with at least two colour textures and a depth attachment, drawn into,
//! two or more of whose colour textures are bound at once for a draw into
//! another framebuffer (a lighting pass reads them together; a bloom
//! program's blur and composite read one at a time). With a profile, a
//! drawn framebuffer matching its signature. Anything less sure leaves the
//! program untouched and says so once.

use crate::check;
use crate::hooks::{self, Api, real_type};
use crate::profile::Profile;
use crate::replay::{self, DrawCall, RecordedDraw, Recording};
use deferred_msaa_capi as capi;
use glow::HasContext;
use std::collections::{HashMap, HashSet};
use std::ffi::{CStr, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Mutex, OnceLock};

const GL_FRAMEBUFFER: u32 = 0x8D40;
const GL_READ_FRAMEBUFFER: u32 = 0x8CA8;
const GL_DRAW_FRAMEBUFFER: u32 = 0x8CA9;
const GL_DRAW_FRAMEBUFFER_BINDING: u32 = 0x8CA6;
const GL_READ_FRAMEBUFFER_BINDING: u32 = 0x8CAA;
const GL_TEXTURE0: u32 = 0x84C0;
const GL_TEXTURE_2D: u32 = 0x0DE1;

/// How the run is set up: from the environment `deferred-msaa inject` sets.
pub(crate) struct Settings {
    /// `DMSAA_INJECT_CHECK=1`: the state and error checks around every call.
    pub(crate) check: bool,
    /// `DMSAA_INJECT_PROFILE`: the profile, read.
    pub(crate) profile: Option<Profile>,
    /// `DMSAA_INJECT_LEARN`: where to write a first profile (and retrofit
    /// nothing).
    pub(crate) learn: Option<std::path::PathBuf>,
    /// Why the retrofit is off from the start (a profile that did not
    /// load).
    pub(crate) off: Option<String>,
}

/// The run's settings, read once.
pub(crate) fn settings() -> &'static Settings {
    static SETTINGS: OnceLock<Settings> = OnceLock::new();
    SETTINGS.get_or_init(|| {
        let check = std::env::var("DMSAA_INJECT_CHECK").is_ok_and(|v| v == "1");
        let learn = std::env::var_os("DMSAA_INJECT_LEARN").map(Into::into);
        let (profile, off) = match std::env::var_os("DMSAA_INJECT_PROFILE") {
            None => (None, None),
            Some(path) => match Profile::load(std::path::Path::new(&path)) {
                Ok(p) => (Some(p), None),
                Err(e) => (None, Some(e.to_string())),
            },
        };
        if check {
            // SAFETY: a plain extern "C" function with no arguments.
            unsafe { libc::atexit(print_check_totals) };
        }
        Settings {
            check,
            profile,
            learn,
            off,
        }
    })
}

/// Say `message` on stderr, once per run for each `key`.
pub(crate) fn say_once(key: &str, message: &str) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said
        .get_or_insert_with(HashSet::new)
        .insert(key.to_string())
    {
        eprintln!("deferred-msaa inject: {message}");
    }
}

extern "C" fn print_check_totals() {
    let t = check::TOTALS.lock().unwrap_or_else(|e| e.into_inner());
    let resolves = RESOLVES.load(std::sync::atomic::Ordering::Relaxed);
    let calls: Vec<String> = t
        .by_call
        .iter()
        .map(|(call, n)| format!("{call} {n}"))
        .collect();
    eprintln!(
        "deferred-msaa inject: check: {} calls into the library, {} GL state values compared around each, \
         {} changed, {} GL errors left by the library, {} left pending by the program; {} frames resolved \
         (calls: {})",
        t.calls,
        t.values,
        t.changed,
        t.errors,
        t.program_errors,
        resolves,
        calls.join(", ")
    );
}

/// Frames resolved over the run, every context.
static RESOLVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

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
    pub(crate) depth: bool,
    /// Drawn into since it was inspected.
    pub(crate) drawn: bool,
    /// Its attachments changed since it was inspected.
    pub(crate) stale: bool,
}

impl Framebuffer {
    /// The heuristic's shape of a G-buffer.
    fn looks_like_gbuffer(&self) -> bool {
        self.complete && self.samples == 0 && self.colour_textures.len() >= 2 && self.depth
    }

    fn describe(&self) -> String {
        format!(
            "{} colour textures ({}){}",
            self.colour_textures.len(),
            self.formats.join(", "),
            if self.depth { " + depth" } else { "" }
        )
    }
}

/// The retrofit made for a context's G-buffer.
struct Retrofit {
    handle: *mut capi::DmsaaRetrofit,
    world_space: bool,
    layers: u32,
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
    api: Api,
    gl: Option<glow::Context>,
    /// The framebuffers bound for drawing and reading, as the program
    /// sees them (the G-buffer, never the twin).
    draw_fbo: u32,
    read_fbo: u32,
    program: u32,
    active_unit: u32,
    unit_textures: HashMap<u32, u32>,
    /// (program, location) → "projection" or "view".
    matrix_uniforms: HashMap<(u32, i32), bool>,
    /// (program, location) → uniform name, for `--learn`.
    pub(crate) uniform_names: HashMap<(u32, i32), String>,
    pub(crate) matrices_set: Vec<String>,
    projection: Option<[f32; 16]>,
    view: Option<[f32; 16]>,
    pub(crate) framebuffers: HashMap<u32, Framebuffer>,
    pub(crate) gbuffer: Option<u32>,
    retrofit: Option<Retrofit>,
    needs_refresh: bool,
    twin_bound: bool,
    twin_drawn: bool,
    off: bool,
    frames: u64,
    pub(crate) passes: Vec<Pass>,
    pub(crate) last_frame: Vec<Pass>,
    /// With two layers: the draws after this frame's resolve.
    recording: Option<Recording>,
}

impl Context {
    fn new(api: Api) -> Self {
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
            matrix_uniforms: HashMap::new(),
            uniform_names: HashMap::new(),
            matrices_set: Vec::new(),
            projection,
            view,
            framebuffers: HashMap::new(),
            gbuffer: None,
            retrofit: None,
            needs_refresh: false,
            twin_bound: false,
            twin_drawn: false,
            off,
            frames: 0,
            passes: Vec::new(),
            last_frame: Vec::new(),
            recording: None,
        }
    }

    /// The context's real GL, for the library's own queries.
    fn gl(&mut self) -> &glow::Context {
        let api = self.api;
        self.gl.get_or_insert_with(|| {
            // SAFETY: this context is current; the loader gives its real
            // entry points.
            unsafe {
                glow::Context::from_loader_function_cstr(|name: &CStr| hooks::load_real(api, name))
            }
        })
    }

    fn learning(&self) -> bool {
        settings().learn.is_some()
    }

    /// `call` into the library; in `--check` mode with the state read
    /// before and after and the errors it leaves counted.
    fn checked(
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
    fn fail(&mut self, call: &str) {
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
    fn give_up(&mut self) {
        self.off = true;
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

    /// The framebuffer to bind in the G-buffer's place this frame, making
    /// the retrofit first if it is not made yet.
    fn twin(&mut self) -> Option<u32> {
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
        let handle = self.retrofit.as_ref()?.handle;
        if self.needs_refresh {
            self.needs_refresh = false;
            // SAFETY: a live handle; this context current.
            let status = self.checked("dmsaa_refresh", |_| unsafe { capi::dmsaa_refresh(handle) });
            if status != capi::DmsaaStatus::Ok {
                self.fail("dmsaa_refresh");
                return None;
            }
        }
        let mut twin = 0u32;
        // SAFETY: a live handle and a writable u32.
        let status = self.checked("dmsaa_framebuffer", |_| unsafe {
            capi::dmsaa_framebuffer(handle, &mut twin)
        });
        if status != capi::DmsaaStatus::Ok || twin == 0 {
            self.fail("dmsaa_framebuffer");
            return None;
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

    /// Make the retrofit of framebuffer `g`.
    fn make(&mut self, g: u32) -> Option<()> {
        let profile = settings().profile.as_ref();
        let options = match profile {
            Some(p) => p.options("the profile").ok()?,
            None => capi::dmsaa_options_default(),
        };
        let world_space = options.world_space_position == 1;
        if self.projection.is_none() {
            say_once(
                "projection",
                &format!(
                    "found the G-buffer (framebuffer {g}) but no projection matrix: no uniform named {:?} was set; \
                     leaving the program untouched (a profile names the uniform or gives the matrix)",
                    profile
                        .and_then(|p| p.projection_uniform())
                        .unwrap_or("projection")
                ),
            );
            self.off = true;
            return None;
        }
        if world_space && self.view.is_none() {
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
            capi::dmsaa_retrofit_new(Some(hooks::library_loader), user, g, &options, &mut handle)
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
        say_once(
            "made",
            &format!(
                "retrofitting framebuffer {g} ({shape}) with {samples}x MSAA, {} layer(s), {}",
                options.layers,
                if profile.is_some() {
                    "options from the profile"
                } else {
                    "default options"
                }
            ),
        );
        self.retrofit = Some(Retrofit {
            handle,
            world_space,
            layers: options.layers,
        });
        Some(())
    }

    fn resolve(&mut self) {
        self.twin_drawn = false;
        let Some(r) = self.retrofit.as_ref() else {
            return;
        };
        let (handle, world_space, layers) = (r.handle, r.world_space, r.layers);
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
            if layers == 2 {
                let pass = settings()
                    .profile
                    .as_ref()
                    .and_then(|p| p.lighting.as_ref())
                    .map_or(1, |l| l.pass);
                self.recording = Some(Recording {
                    skip: pass.saturating_sub(1),
                    ..Recording::default()
                });
            }
        } else {
            self.fail("dmsaa_resolve");
        }
    }

    fn bind_framebuffer(&mut self, target: u32, name: u32, real: &dyn Fn(u32, u32)) {
        // A pass ends at the first bind after it drew: the lighting's is
        // replayed, an earlier one's let go.
        if let Some(r) = self.recording.as_mut()
            && !r.draws.is_empty()
        {
            if r.skip > 0 {
                r.skip -= 1;
                r.draws.clear();
                r.target = None;
            } else {
                self.second_layer();
            }
        }
        let draw = target == GL_FRAMEBUFFER || target == GL_DRAW_FRAMEBUFFER;
        let read = target == GL_FRAMEBUFFER || target == GL_READ_FRAMEBUFFER;
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

    /// Before a draw call: the twin is drawn; otherwise the framebuffer
    /// drawn into is inspected, and the G-buffer looked for.
    fn before_draw(&mut self, call: DrawCall) {
        if self.twin_bound {
            self.twin_drawn = true;
            return;
        }
        let d = self.draw_fbo;
        if self
            .recording
            .as_ref()
            .is_some_and(|r| r.target.is_none_or(|t| t == d))
        {
            // SAFETY: a query of the current context.
            let vertex_array =
                unsafe { self.gl().get_parameter_i32(glow::VERTEX_ARRAY_BINDING) } as u32;
            let mut textures: Vec<(u32, u32)> = self
                .unit_textures
                .iter()
                .filter(|(_, t)| **t != 0)
                .map(|(u, t)| (*u, *t))
                .collect();
            textures.sort_unstable();
            let program = self.program;
            if let Some(r) = self.recording.as_mut() {
                r.target = Some(d);
                r.draws.push(RecordedDraw {
                    call,
                    program,
                    vertex_array,
                    textures,
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
                f.drawn = true;
            }
        }
        if self.gbuffer.is_none() {
            self.find_gbuffer(d);
        }
    }

    /// The bound draw framebuffer's attachments, read from GL.
    fn inspect(&mut self) -> Framebuffer {
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
                if kind == glow::TEXTURE {
                    let texture = param(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME) as u32;
                    f.colour_textures.push((k, texture));
                }
            }
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
    fn matches_profile(profile: &Profile, f: &Framebuffer) -> bool {
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
            if let Some(f) = self.framebuffers.get(&draw)
                && Self::matches_profile(p, f)
            {
                self.gbuffer = Some(draw);
            }
            return;
        }
        let bound: HashSet<u32> = self
            .unit_textures
            .values()
            .copied()
            .filter(|&t| t != 0)
            .collect();
        if bound.len() < 2 {
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
        match found.as_slice() {
            [] => {}
            [g] => self.gbuffer = Some(*g),
            many => {
                say_once(
                    "ambiguous",
                    &format!(
                        "framebuffers {many:?} all look like G-buffers; leaving the program untouched (a profile names which)"
                    ),
                );
                self.off = true;
            }
        }
    }

    /// At a swap: the last resort's resolve, the frame's passes kept for
    /// `--learn`, and the one line for a program left alone.
    fn end_frame(&mut self) {
        if self.twin_drawn {
            self.resolve();
        }
        if self
            .recording
            .as_ref()
            .is_some_and(|r| !r.draws.is_empty() && r.skip == 0)
        {
            self.second_layer();
        }
        self.recording = None;
        self.frames += 1;
        self.last_frame = std::mem::take(&mut self.passes);
        if self.learning() {
            crate::learn::after_frame(self);
            return;
        }
        if self.frames == 2 && self.gbuffer.is_none() && !self.off {
            let unsure: Vec<u32> = self
                .framebuffers
                .iter()
                .filter(|(_, f)| f.drawn && f.looks_like_gbuffer())
                .map(|(n, _)| *n)
                .collect();
            let message = if unsure.is_empty() {
                "no G-buffer found (no complete single-sample framebuffer with two or more colour textures and \
                 depth was drawn into); leaving the program untouched"
                    .to_string()
            } else {
                format!(
                    "framebuffer(s) {unsure:?} have the shape of a G-buffer, but no later pass read two of their \
                     colour textures together; not sure it is one, so leaving the program untouched (a profile \
                     can name it)"
                )
            };
            say_once("none", &message);
        }
    }

    /// The second layer: the recorded lighting drawn again into the
    /// retrofit's own target, the two layers mixed into the program's lit
    /// target, and the state the replay changed put back.
    fn second_layer(&mut self) {
        let Some(recording) = self.recording.take() else {
            return;
        };
        let Some(handle) = self.retrofit.as_ref().map(|r| r.handle) else {
            return;
        };
        let output = recording.target.unwrap_or(0);
        let draws = recording.draws;
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
                // SAFETY: the retrofit's framebuffer, bound for the replay.
                unsafe {
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(glow::NativeFramebuffer(own)))
                };
                replay::draw(gl, &draws);
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
        }
    }

    fn delete_framebuffers(&mut self, names: &[u32]) {
        for name in names {
            self.framebuffers.remove(name);
            if self.gbuffer == Some(*name) {
                // GL unbinds a deleted framebuffer: the twin goes too.
                if self.twin_bound {
                    real_bind(GL_DRAW_FRAMEBUFFER, 0);
                    if self.read_fbo == *name {
                        real_bind(GL_READ_FRAMEBUFFER, 0);
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
                // A new G-buffer is looked for as at the start.
                self.gbuffer = None;
            }
        }
    }

    /// Before an attachment of framebuffer `name` changes through direct
    /// state access (the twin, bound or not, is not touched).
    fn named_attachment_changes(&mut self, name: u32) {
        if let Some(f) = self.framebuffers.get_mut(&name) {
            f.stale = true;
        }
        if name != 0 && self.gbuffer == Some(name) {
            self.needs_refresh = true;
        }
    }

    /// Before an attachment of the framebuffer bound at `target` changes.
    fn attachment_changes(&mut self, target: u32) {
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

/// The real `glBindFramebuffer`, for the library's own binds.
fn real_bind(target: u32, name: u32) {
    if let Some(p) = hooks::real::glBindFramebuffer.get() {
        // SAFETY: the driver's glBindFramebuffer.
        unsafe { std::mem::transmute::<usize, real_type::glBindFramebuffer>(p)(target, name) };
    }
}

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
    if INSIDE.with(|i| i.replace(true)) {
        return None;
    }
    let _inside = Inside;
    let (api, id) = hooks::current_context()?;
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

/// What each watched GL function does around its real call (the wrappers
/// in [`crate::hooks`] call these).
#[allow(non_snake_case)]
pub(crate) mod handlers {
    use super::*;
    use std::ffi::{c_char, c_ulong};

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
        // A blit from the G-buffer reads it: resolved first.
        with_context(|cx| {
            if cx.twin_drawn && read != 0 && cx.gbuffer == Some(read) {
                cx.resolve();
            }
        });
        unsafe {
            real(
                read, draw, sx0, sy0, sx1, sy1, dx0, dy0, dx1, dy1, mask, filter,
            )
        }
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
                if projection == Some(&*name) {
                    cx.matrix_uniforms.insert((program, location), true);
                } else if view == Some(&*name) {
                    cx.matrix_uniforms.insert((program, location), false);
                }
                if cx.learning() {
                    cx.uniform_names
                        .insert((program, location), name.to_string());
                }
            });
        }
        location
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
        with_context(|cx| {
            let key = (cx.program, location);
            if cx.learning()
                && let Some(name) = cx.uniform_names.get(&key)
                && !cx.matrices_set.contains(name)
            {
                let name = name.clone();
                cx.matrices_set.push(name);
            }
            let Some(&is_projection) = cx.matrix_uniforms.get(&key) else {
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
            if is_projection {
                cx.projection = Some(m);
            } else {
                cx.view = Some(m);
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
        unsafe { real(mask) }
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
        {
            map.remove(&(context as usize));
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
}
