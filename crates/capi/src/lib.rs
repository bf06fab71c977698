//! # deferred-msaa-capi
//!
//! The `deferred-msaa` retrofit for C and C++ engines: a C ABI over
//! [`deferred_msaa::MsaaRetrofit`], [`deferred_msaa::RetrofitOptions`] and
//! [`deferred_msaa::Frame`], built as a static and a shared library, with
//! the header `include/deferred_msaa.h` generated from these declarations by
//! cbindgen (the crate's `tests/header.rs` fails when the committed header
//! is stale).
//!
//! ```c
//! DmsaaOptions options = dmsaa_options_default();
//! DmsaaRetrofit *msaa = NULL;
//! if (dmsaa_retrofit_new(load, NULL, gBuffer, &options, &msaa) != DMSAA_STATUS_OK)
//!     fprintf(stderr, "%s\n", dmsaa_last_error());
//! // every frame:
//! GLuint fbo; dmsaa_framebuffer(msaa, &fbo);
//! glBindFramebuffer(GL_FRAMEBUFFER, fbo);        // instead of gBuffer
//! /* ... the geometry pass ... */
//! dmsaa_resolve(msaa, projection, NULL);         // into gBuffer's own textures
//! /* ... the lighting pass ... */
//! dmsaa_destroy(msaa);                           // at shutdown
//! ```
//!
//! Every entry point catches panics and reports them as
//! [`DmsaaStatus::Panic`]; null pointers, options out of range and calls out
//! of order return a status, with the calling thread's message in
//! [`dmsaa_last_error`]. docs/capi.md in the repository describes the whole
//! API.
#![warn(missing_docs)]
// Every entry point checks its pointers before it reads them; the C caller
// guarantees only what the header says.
#![allow(clippy::missing_safety_doc)]

use deferred_msaa::foreign::ForeignRetrofit;
use deferred_msaa::gbuffer::MemoryBudget;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::{
    ColorAttachment, DepthMode, Error, FirstLayerRestore, Frame, LayerMix, NormalAttachment,
    PositionSpace, RetrofitOptions, TwinClear,
};
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_void};
use std::num::NonZeroU32;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// What every fallible call returns. Any value other than
/// `DMSAA_STATUS_OK` leaves a one-line message in [`dmsaa_last_error`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DmsaaStatus {
    /// Success.
    Ok = 0,
    /// A pointer argument that must not be null was null.
    NullPointer = 1,
    /// An argument or an option is out of range (the message names it and
    /// what is accepted), or the projection is not a GL perspective matrix.
    InvalidArgument = 2,
    /// A call out of order: `dmsaa_begin_second_layer` before this frame's
    /// `dmsaa_resolve` or twice, `dmsaa_finish_second_layer` without
    /// `dmsaa_begin_second_layer`, `dmsaa_resolve` between the two.
    OutOfOrder = 3,
    /// The host framebuffer cannot be retrofitted as it is (no depth
    /// attachment, an already multisampled attachment, a rule or key naming
    /// an attachment it lacks): the message names the attachment.
    UnsuitableFramebuffer = 4,
    /// The context lacks what is asked for: a GL version or extension, a
    /// sample count or a multisampled format; or the loader returns null
    /// for a GL function the library calls (the message names it).
    Unsupported = 5,
    /// The twins would take more memory than the options' budget allows.
    MemoryBudget = 6,
    /// The driver failed: a GL error, an object that could not be made, an
    /// incomplete framebuffer, a shader that did not compile or link (those
    /// two carry the driver's log on the lines after the first).
    Gl = 7,
    /// A panic inside the library, caught at the boundary. The handle it
    /// happened on refuses every call but `dmsaa_destroy` from then on.
    Panic = 8,
    /// The host's second lighting drew nothing where pixels have a second
    /// layer (a depth or stencil test left on from the first lighting
    /// rejected it): the message says how to set it up instead. Returned
    /// by `dmsaa_finish_second_layer`, or, where the result was not ready
    /// then, by the next `dmsaa_resolve` (which has still resolved its
    /// frame).
    SecondLighting = 9,
}

/// The GL loader a host already has: returns the address of the GL entry
/// point `name` (a NUL-terminated ASCII string), or null where it has none.
/// `user_data` is what the host gave [`dmsaa_retrofit_new`]. An
/// `eglGetProcAddress`, `glXGetProcAddress` or `SDL_GL_GetProcAddress` is
/// wrapped in a one-line function of this type.
pub type DmsaaGetProcAddress =
    Option<unsafe extern "C" fn(name: *const c_char, user_data: *mut c_void) -> *const c_void>;

/// How the reference sample of a pixel is chosen
/// (`DMSAA_METHOD_AVERAGE` … `DMSAA_METHOD_BACK`).
pub type DmsaaMethod = u32;
/// Every sample weighs 1, as a hardware resolve.
pub const DMSAA_METHOD_AVERAGE: DmsaaMethod = 0;
/// Reference: the nearest sample.
pub const DMSAA_METHOD_FRONT: DmsaaMethod = 1;
/// Reference: the median sample by depth (the default).
pub const DMSAA_METHOD_MEDIAN: DmsaaMethod = 2;
/// Reference: the farthest sample.
pub const DMSAA_METHOD_BACK: DmsaaMethod = 3;

/// The closeness window (`DMSAA_WINDOW_HARD`, `DMSAA_WINDOW_SMOOTH`).
pub type DmsaaWindow = u32;
/// Weight 1 within `window_c` pixel footprints, else 0.
pub const DMSAA_WINDOW_HARD: DmsaaWindow = 0;
/// Weight falling smoothly from `window_c_in` to `window_c` (the default).
pub const DMSAA_WINDOW_SMOOTH: DmsaaWindow = 1;

/// How a normal attachment stores a normal (`DMSAA_NORMAL_XYZ` …).
pub type DmsaaNormalEncoding = u32;
/// xyz as they are (a float or snorm attachment; the default).
pub const DMSAA_NORMAL_XYZ: DmsaaNormalEncoding = 0;
/// xyz packed as `n * 0.5 + 0.5` (an RGBA8 attachment).
pub const DMSAA_NORMAL_UNORM: DmsaaNormalEncoding = 1;
/// Octahedral, x and y in `[-1, 1]`.
pub const DMSAA_NORMAL_OCTAHEDRAL: DmsaaNormalEncoding = 2;
/// Octahedral packed into `[0, 1]`.
pub const DMSAA_NORMAL_OCTAHEDRAL_UNORM: DmsaaNormalEncoding = 3;

/// The rule by which one colour attachment's samples become one value.
pub type DmsaaRule = u32;
/// The format's default: blend, select for integer formats.
pub const DMSAA_RULE_DEFAULT: DmsaaRule = 0;
/// Weighted mean.
pub const DMSAA_RULE_BLEND: DmsaaRule = 1;
/// Normalised weighted sum of xyz (normals), w blended.
pub const DMSAA_RULE_BLEND_NORMAL: DmsaaRule = 2;
/// Weighted mean in the tonemapped domain `x / (1 + max3(x))`.
pub const DMSAA_RULE_BLEND_HDR: DmsaaRule = 3;
/// The reference sample's value, never blended.
pub const DMSAA_RULE_SELECT: DmsaaRule = 4;

/// How a depth-stencil host's stencil is written back after the resolve.
pub type DmsaaStencilCopy = u32;
/// The best the driver offers (the default).
pub const DMSAA_STENCIL_AUTO: DmsaaStencilCopy = 0;
/// One pass, with `GL_ARB_shader_stencil_export`.
pub const DMSAA_STENCIL_EXPORT: DmsaaStencilCopy = 1;
/// Eight passes, with `GL_ARB_stencil_texturing` alone.
pub const DMSAA_STENCIL_BIT_PASSES: DmsaaStencilCopy = 2;
/// `glBlitFramebuffer`: the sample the driver picks.
pub const DMSAA_STENCIL_BLIT: DmsaaStencilCopy = 3;

/// What the host's lit values mean, and so how the two lit layers are
/// mixed by the second layer's coverage (and the forward target's samples
/// averaged).
pub type DmsaaLayerMix = u32;
/// Inferred (the default): tonemapped for a floating-point output; in
/// linear light for an sRGB output the host writes with
/// `GL_FRAMEBUFFER_SRGB` on; as stored otherwise (a host whose 8-bit
/// output holds display values declares `DMSAA_LAYER_MIX_SRGB_ENCODED`).
pub const DMSAA_LAYER_MIX_AUTO: DmsaaLayerMix = 0;
/// Linear values (linear light, or any values to be mixed as they are):
/// `mix(first, second, a)` as the output stores them.
pub const DMSAA_LAYER_MIX_LINEAR: DmsaaLayerMix = 1;
/// In the domain `x / (1 + max3(x))`, mapped back.
pub const DMSAA_LAYER_MIX_TONEMAPPED: DmsaaLayerMix = 2;
/// In the domain of the host's own tonemap curve: `layer_mix_curve` is GLSL
/// defining `vec3 dmsaa_curve(vec3)` and `vec3 dmsaa_curve_inverse(vec3)`.
pub const DMSAA_LAYER_MIX_CURVE: DmsaaLayerMix = 3;
/// sRGB-encoded display values the host's shader wrote (or an sRGB image
/// written with `GL_FRAMEBUFFER_SRGB` off): decoded, mixed in linear light,
/// encoded again.
pub const DMSAA_LAYER_MIX_SRGB_ENCODED: DmsaaLayerMix = 4;

/// What `dmsaa_finish_second_layer` puts back of the first layer in the
/// host's G-buffer; what it does not put back holds the second layer.
pub type DmsaaRestore = u32;
/// Nothing: for a host that reads nothing of its G-buffer after lighting
/// until its next geometry pass (no copies).
pub const DMSAA_RESTORE_NOTHING: DmsaaRestore = 0;
/// Colours, depth and stencil (the default).
pub const DMSAA_RESTORE_EVERYTHING: DmsaaRestore = 1;
/// Depth and stencil only: for a host whose passes after lighting test
/// against them (transparent objects drawn with depth testing) but read
/// no colour attachment.
pub const DMSAA_RESTORE_DEPTH_AND_STENCIL: DmsaaRestore = 2;

/// How the host's depth buffer holds depth.
pub type DmsaaDepthMode = u32;
/// OpenGL's default: the near plane at 0, cleared to 1 (the default).
pub const DMSAA_DEPTH_STANDARD: DmsaaDepthMode = 0;
/// `glClipControl(..., GL_ZERO_TO_ONE)`, cleared to 1.
pub const DMSAA_DEPTH_ZERO_TO_ONE: DmsaaDepthMode = 1;
/// Reversed-Z: `GL_ZERO_TO_ONE`, the near plane at 1, cleared to 0.
pub const DMSAA_DEPTH_REVERSED_Z: DmsaaDepthMode = 2;

/// `position_attachment` / `normal_attachment`: none.
pub const DMSAA_NO_ATTACHMENT: i32 = -1;

/// How many colour attachments `DmsaaOptions.rules` covers (GL's
/// guaranteed minimum of `GL_MAX_COLOR_ATTACHMENTS`).
pub const DMSAA_MAX_RULES: usize = 8;

/// `memory_budget_bytes`: no budget.
pub const DMSAA_MEMORY_BUDGET_NONE: u64 = 0;
/// `memory_budget_bytes`: a share of the free video memory the driver
/// reports (or the crate's fixed default where it reports none).
pub const DMSAA_MEMORY_BUDGET_DRIVER: u64 = u64::MAX;

/// Everything that does not change from frame to frame, given once: the
/// C form of the Rust `RetrofitOptions`. Start from
/// [`dmsaa_options_default`] and change fields; flags are 0 or 1, and any
/// value out of range makes the call that is given it fail with
/// `DMSAA_STATUS_INVALID_ARGUMENT`, naming the field.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DmsaaOptions {
    /// Requested samples per pixel, at least 1 (default 4); the driver's
    /// real count is used ([`dmsaa_samples`]).
    pub samples: u32,
    /// Resolved layers per pixel: 1 (default) or 2 (the second layer:
    /// [`dmsaa_begin_second_layer`], [`dmsaa_finish_second_layer`]).
    pub layers: u32,
    /// The colour attachment number holding positions, whose view-space
    /// `-z` is the depth key; `DMSAA_NO_ATTACHMENT` (default) linearises
    /// the depth attachment with each frame's projection instead.
    pub position_attachment: i32,
    /// 1: the position attachment holds world-space positions, and each
    /// [`dmsaa_resolve`] passes the view matrix; 0 (default): view space.
    pub world_space_position: u8,
    /// The colour attachment number holding normals, for the normal test
    /// (one layer or two; name it for normals packed as `n*0.5+0.5`);
    /// `DMSAA_NO_ATTACHMENT` (default): by depth alone.
    pub normal_attachment: i32,
    /// How `normal_attachment` stores normals (`DMSAA_NORMAL_*`).
    pub normal_encoding: DmsaaNormalEncoding,
    /// With a normal attachment: samples close in depth are
    /// one surface only when the cosine between their normals is at least
    /// this, in `[-1, 1]` (default 0.95).
    pub normal_threshold: f64,
    /// `DMSAA_METHOD_*` (default median).
    pub method: DmsaaMethod,
    /// `DMSAA_WINDOW_*` (default smooth).
    pub window: DmsaaWindow,
    /// Outer window width in pixel footprints, above 0 (default 5).
    pub window_c: f64,
    /// Inner width of the smooth window, at least 0 and below `window_c`
    /// (default 2.5).
    pub window_c_in: f64,
    /// 1 (default): uniform pixels take one sample.
    pub fast_path: u8,
    /// 1: blend the depth attachment's value rather than select the
    /// reference's (default 0).
    pub blend_depth: u8,
    /// 1: with the fast path and a depth key, pixels whose depth samples lie
    /// on one plane count as uniform (default 0).
    pub plane_uniformity: u8,
    /// 1: with the fast path and a position key, pixels whose position
    /// samples are all equal count as uniform (default 0).
    pub position_uniformity: u8,
    /// The rule of colour attachment `k` (`DMSAA_RULE_*`); attachments the
    /// host framebuffer lacks must stay `DMSAA_RULE_DEFAULT`.
    pub rules: [DmsaaRule; DMSAA_MAX_RULES],
    /// `DMSAA_STENCIL_*` (default auto).
    pub stencil_copy: DmsaaStencilCopy,
    /// `DMSAA_LAYER_MIX_*` (default auto).
    pub layer_mix: DmsaaLayerMix,
    /// With `DMSAA_LAYER_MIX_CURVE`: the curve's GLSL, NUL-terminated UTF-8,
    /// copied by the call that reads the options; otherwise ignored.
    pub layer_mix_curve: *const c_char,
    /// `DMSAA_RESTORE_*` (default everything): what
    /// `dmsaa_finish_second_layer` puts back of the first layer in the
    /// host's G-buffer. The lit image is the same whichever is chosen.
    pub restore_first_layer: DmsaaRestore,
    /// 1 (default): with two layers, count what the first and second
    /// lighting draw (occlusion queries between `dmsaa_resolve` and
    /// `dmsaa_begin_second_layer`, and between it and
    /// `dmsaa_finish_second_layer`) and return
    /// `DMSAA_STATUS_SECOND_LIGHTING` where the second drew nothing. 0 for a
    /// host that runs occlusion queries of its own there, or whose second
    /// lighting draws no fragments while something before its first
    /// lighting does.
    pub check_second_lighting: u8,
    /// 1: [`dmsaa_begin_frame`] clears the multisampled twins to
    /// `clear_colors` (per colour attachment number, `glClearBufferfv`'s
    /// values; integer attachments take them as integers), `clear_depth` and
    /// `clear_stencil`, for a host that clears its G-buffer through another
    /// framebuffer or per attachment with its own values. 0 (default): the
    /// host clears through [`dmsaa_framebuffer`]'s framebuffer.
    pub clear_twins: u8,
    /// With `clear_twins`: each colour attachment's clear value (default 0).
    pub clear_colors: [[f32; 4]; DMSAA_MAX_RULES],
    /// With `clear_twins`: the depth clear value (default 1).
    pub clear_depth: f32,
    /// With `clear_twins`: the stencil clear value (default 0).
    pub clear_stencil: i32,
    /// With two layers: the colour attachments the second layer need not
    /// carry, as a bit mask (bit n: `GL_COLOR_ATTACHMENTn`; default 0):
    /// attachments the host's lighting does not read or reads the same for
    /// both surfaces (an object ID, velocity). Not resolved for the second
    /// layer; the host's image keeps the first layer's value there during
    /// the second lighting.
    pub second_layer_omits: u32,
    /// A limit on the twins' memory in bytes: `DMSAA_MEMORY_BUDGET_NONE`
    /// (default), `DMSAA_MEMORY_BUDGET_DRIVER`, or a number of bytes. Over
    /// it, the sample count steps down (or, strict, the call fails).
    pub memory_budget_bytes: u64,
    /// 1: over the budget, fail with `DMSAA_STATUS_MEMORY_BUDGET` rather
    /// than step down (default 0).
    pub memory_budget_strict: u8,
    /// `DMSAA_DEPTH_*` (default standard): how the host stores depth.
    pub depth_mode: DmsaaDepthMode,
}

/// A host G-buffer retrofitted with MSAA: the multisampled twins, the
/// resolve's programs and the GL function table loaded through the host's
/// loader (a [`ForeignRetrofit`]). It never owns a GL context. Opaque; made by
/// [`dmsaa_retrofit_new`], freed by [`dmsaa_destroy`].
pub struct DmsaaRetrofit {
    /// The retrofit and the function table loaded through the host's
    /// loader: the core's entry point for hosts that name GL objects by
    /// number.
    msaa: ForeignRetrofit,
    depth_mode: DepthMode,
    world_space: bool,
    /// The second layer's phase as the calls so far left it, to tell a
    /// call out of order from a bad argument.
    phase: Phase,
    /// Between `dmsaa_begin_forward` and `dmsaa_finish_forward`, for this
    /// output (0: default).
    forward: Option<u32>,
    /// A panic happened on this handle: its state may be half-changed.
    poisoned: bool,
}

/// Where a frame with two layers is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Before this frame's resolve (or with one layer).
    Idle,
    /// Resolved: the second lighting may begin.
    Resolved,
    /// Between begin and finish, lighting into this output (0: default).
    Lighting(u32),
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// What an entry point fails with: its status and message.
#[derive(Debug)]
struct Failure {
    status: DmsaaStatus,
    message: String,
}

impl Failure {
    fn new(status: DmsaaStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }

    fn null(function: &str, argument: &str) -> Self {
        Failure::new(
            DmsaaStatus::NullPointer,
            format!("{function}: `{argument}` is null"),
        )
    }

    fn invalid(message: impl Into<String>) -> Self {
        Failure::new(DmsaaStatus::InvalidArgument, message)
    }

    /// The Rust error's message, under the status of its kind.
    fn from_error(error: &Error) -> Self {
        let status = match error {
            Error::InvalidArgument(_) => DmsaaStatus::InvalidArgument,
            Error::Retrofit { .. } | Error::Layout(_) => DmsaaStatus::UnsuitableFramebuffer,
            Error::Unsupported { .. }
            | Error::UnsupportedSampleCount { .. }
            | Error::UnsupportedFormat { .. } => DmsaaStatus::Unsupported,
            Error::MemoryBudget { .. } => DmsaaStatus::MemoryBudget,
            Error::SecondLighting(_) => DmsaaStatus::SecondLighting,
            _ => DmsaaStatus::Gl,
        };
        Failure::new(status, error.to_string())
    }
}

impl From<Error> for Failure {
    fn from(error: Error) -> Self {
        Failure::from_error(&error)
    }
}

fn set_last_error(message: &str) {
    // An interior NUL cannot be given to C; it never occurs in the crate's
    // messages, but a driver log could hold one.
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Run one entry point's body: a panic becomes `DMSAA_STATUS_PANIC`, a
/// failure sets the thread's message.
fn entry(function: &str, body: impl FnOnce() -> Result<(), Failure>) -> DmsaaStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => DmsaaStatus::Ok,
        Ok(Err(failure)) => {
            set_last_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            set_last_error(&format!(
                "{function}: internal error (a panic: {}); please report it",
                what.lines().next().unwrap_or("")
            ));
            DmsaaStatus::Panic
        }
    }
}

/// The handle behind `retrofit`, checked: not null, not poisoned, not
/// destroyed. A panic while it is borrowed poisons it.
fn with_handle<T>(
    function: &str,
    retrofit: *mut DmsaaRetrofit,
    body: impl FnOnce(&mut DmsaaRetrofit) -> Result<T, Failure>,
) -> Result<T, Failure> {
    // SAFETY: the header requires a handle from `dmsaa_retrofit_new` not
    // yet destroyed, or null, which is refused here.
    let Some(handle) = (unsafe { retrofit.as_mut() }) else {
        return Err(Failure::null(function, "retrofit"));
    };
    if handle.poisoned {
        return Err(Failure::new(
            DmsaaStatus::Panic,
            format!(
                "{function}: this retrofit had an internal error earlier; destroy it and make a new one"
            ),
        ));
    }
    handle.poisoned = true;
    // The core's guards put the host's state back while a panic unwinds;
    // a GL error left on the way is drained before the panic goes on to
    // `entry`, so that none is left for the host.
    let result = match catch_unwind(AssertUnwindSafe(|| body(&mut *handle))) {
        Ok(result) => result,
        Err(payload) => {
            let _ = deferred_msaa::gl::check_error(handle.msaa.parts_mut().0, "a panic");
            std::panic::resume_unwind(payload)
        }
    };
    handle.poisoned = false;
    result
}

fn flag(name: &str, value: u8) -> Result<bool, Failure> {
    match value {
        0 => Ok(false),
        1 => Ok(true),
        v => Err(Failure::invalid(format!(
            "DmsaaOptions.{name} is {v}; a flag is 0 or 1"
        ))),
    }
}

fn attachment(name: &str, value: i32) -> Result<Option<ColorAttachment>, Failure> {
    match value {
        DMSAA_NO_ATTACHMENT => Ok(None),
        v if v >= 0 => Ok(Some(ColorAttachment(v as u32))),
        v => Err(Failure::invalid(format!(
            "DmsaaOptions.{name} is {v}; expected a colour attachment number (0 for \
             GL_COLOR_ATTACHMENT0, ...) or DMSAA_NO_ATTACHMENT (-1)"
        ))),
    }
}

/// One of an enumeration's values, or an error naming the field and what
/// it accepts.
fn pick<T: Clone>(name: &str, value: u32, choices: &[(&str, T)]) -> Result<T, Failure> {
    choices
        .get(value as usize)
        .map(|(_, v)| v.clone())
        .ok_or_else(|| {
            let names: Vec<String> = choices
                .iter()
                .enumerate()
                .map(|(i, (n, _))| format!("{n} ({i})"))
                .collect();
            Failure::invalid(format!(
                "DmsaaOptions.{name} is {value}; expected one of {}",
                names.join(", ")
            ))
        })
}

/// What [`DmsaaOptions`] asks for: the Rust options, the depth mode and
/// whether positions are world-space.
#[derive(Debug)]
struct Converted {
    options: RetrofitOptions,
    depth_mode: DepthMode,
    world_space: bool,
}

fn convert(o: &DmsaaOptions) -> Result<Converted, Failure> {
    if o.samples == 0 {
        return Err(Failure::invalid(
            "DmsaaOptions.samples is 0; it is at least 1",
        ));
    }
    let mut options = RetrofitOptions {
        samples: o.samples,
        ..RetrofitOptions::default()
    };
    options.resolve.layers = o.layers;
    options.position_attachment = attachment("position_attachment", o.position_attachment)?;
    let world_space = flag("world_space_position", o.world_space_position)?;
    options.position_space = if world_space {
        PositionSpace::World
    } else {
        PositionSpace::View
    };
    let encoding = pick(
        "normal_encoding",
        o.normal_encoding,
        &[
            ("DMSAA_NORMAL_XYZ", NormalEncoding::Xyz),
            ("DMSAA_NORMAL_UNORM", NormalEncoding::Unorm),
            ("DMSAA_NORMAL_OCTAHEDRAL", NormalEncoding::Octahedral),
            (
                "DMSAA_NORMAL_OCTAHEDRAL_UNORM",
                NormalEncoding::OctahedralUnorm,
            ),
        ],
    )?;
    options.normal_attachment =
        attachment("normal_attachment", o.normal_attachment)?.map(|attachment| NormalAttachment {
            attachment,
            encoding,
        });
    options.resolve.normal_threshold = o.normal_threshold;
    options.resolve.method = pick(
        "method",
        o.method,
        &[
            ("DMSAA_METHOD_AVERAGE", ResolveMethod::Average),
            ("DMSAA_METHOD_FRONT", ResolveMethod::Front),
            ("DMSAA_METHOD_MEDIAN", ResolveMethod::Median),
            ("DMSAA_METHOD_BACK", ResolveMethod::Back),
        ],
    )?;
    options.resolve.window = pick(
        "window",
        o.window,
        &[
            ("DMSAA_WINDOW_HARD", Window::Hard),
            ("DMSAA_WINDOW_SMOOTH", Window::Smooth),
        ],
    )?;
    options.resolve.c = o.window_c;
    options.resolve.c_in = o.window_c_in;
    options.resolve.fast_path = flag("fast_path", o.fast_path)?;
    options.resolve.blend_depth = flag("blend_depth", o.blend_depth)?;
    options.resolve.plane_uniformity = flag("plane_uniformity", o.plane_uniformity)?;
    options.resolve.position_uniformity = flag("position_uniformity", o.position_uniformity)?;
    // The numbers the resolve checks itself are checked now, so that a bad
    // option fails here with the Rust message rather than later.
    options.resolve.validate()?;
    for (k, &rule) in o.rules.iter().enumerate() {
        let rule = pick(
            &format!("rules[{k}]"),
            rule,
            &[
                ("DMSAA_RULE_DEFAULT", None),
                ("DMSAA_RULE_BLEND", Some(ResolveRule::Blend)),
                ("DMSAA_RULE_BLEND_NORMAL", Some(ResolveRule::BlendNormal)),
                ("DMSAA_RULE_BLEND_HDR", Some(ResolveRule::BlendHdr)),
                ("DMSAA_RULE_SELECT", Some(ResolveRule::Select)),
            ],
        )?;
        if let Some(rule) = rule {
            options.rules.push((ColorAttachment(k as u32), rule));
        }
    }
    options.stencil = pick(
        "stencil_copy",
        o.stencil_copy,
        &[
            ("DMSAA_STENCIL_AUTO", StencilCopy::Auto),
            ("DMSAA_STENCIL_EXPORT", StencilCopy::Export),
            ("DMSAA_STENCIL_BIT_PASSES", StencilCopy::BitPasses),
            ("DMSAA_STENCIL_BLIT", StencilCopy::Blit),
        ],
    )?;
    options.layer_mix = match o.layer_mix {
        DMSAA_LAYER_MIX_CURVE => {
            if o.layer_mix_curve.is_null() {
                return Err(Failure::null("DmsaaOptions", "layer_mix_curve"));
            }
            // SAFETY: the header requires a NUL-terminated string here.
            let text = unsafe { CStr::from_ptr(o.layer_mix_curve) };
            let text = text
                .to_str()
                .map_err(|_| Failure::invalid("DmsaaOptions.layer_mix_curve is not UTF-8 text"))?;
            LayerMix::Curve(text.to_owned())
        }
        other => pick(
            "layer_mix",
            other,
            &[
                ("DMSAA_LAYER_MIX_AUTO", LayerMix::Auto),
                ("DMSAA_LAYER_MIX_LINEAR", LayerMix::Linear),
                ("DMSAA_LAYER_MIX_TONEMAPPED", LayerMix::Tonemapped),
                // Taken above, with its text; listed for the message.
                ("DMSAA_LAYER_MIX_CURVE", LayerMix::Auto),
                ("DMSAA_LAYER_MIX_SRGB_ENCODED", LayerMix::SrgbEncoded),
            ],
        )?,
    };
    options.restore_first_layer = pick(
        "restore_first_layer",
        o.restore_first_layer,
        &[
            ("DMSAA_RESTORE_NOTHING", FirstLayerRestore::Nothing),
            ("DMSAA_RESTORE_EVERYTHING", FirstLayerRestore::Everything),
            (
                "DMSAA_RESTORE_DEPTH_AND_STENCIL",
                FirstLayerRestore::DepthAndStencil,
            ),
        ],
    )?;
    options.check_second_lighting = flag("check_second_lighting", o.check_second_lighting)?;
    options.second_layer_omits = (0..32)
        .filter(|n| o.second_layer_omits & (1 << n) != 0)
        .map(ColorAttachment)
        .collect();
    options.twin_clear = flag("clear_twins", o.clear_twins)?.then(|| TwinClear {
        colors: o
            .clear_colors
            .iter()
            .enumerate()
            .map(|(n, v)| (ColorAttachment(n as u32), *v))
            .collect(),
        depth: o.clear_depth,
        stencil: o.clear_stencil,
    });
    let strict = flag("memory_budget_strict", o.memory_budget_strict)?;
    options.memory_budget = match o.memory_budget_bytes {
        DMSAA_MEMORY_BUDGET_NONE => None,
        DMSAA_MEMORY_BUDGET_DRIVER => Some(MemoryBudget {
            bytes: None,
            strict,
        }),
        bytes => Some(MemoryBudget {
            bytes: Some(bytes),
            strict,
        }),
    };
    let depth_mode = pick(
        "depth_mode",
        o.depth_mode,
        &[
            ("DMSAA_DEPTH_STANDARD", DepthMode::Standard),
            ("DMSAA_DEPTH_ZERO_TO_ONE", DepthMode::ZeroToOne),
            ("DMSAA_DEPTH_REVERSED_Z", DepthMode::ReversedZ),
        ],
    )?;
    Ok(Converted {
        options,
        depth_mode,
        world_space,
    })
}

/// The options a C caller passed, checked for null and converted.
fn read_options(function: &str, options: *const DmsaaOptions) -> Result<Converted, Failure> {
    // SAFETY: the header requires null or a valid `DmsaaOptions`.
    let options = unsafe { options.as_ref() }.ok_or_else(|| Failure::null(function, "options"))?;
    convert(options).map_err(|f| Failure::new(f.status, format!("{function}: {}", f.message)))
}

/// The default options: 4 samples, one layer, the depth key from the depth
/// buffer, the median method with the smooth window (c = 5, c_in = 2.5),
/// the fast path, each attachment's default rule, the first layer restored
/// after the second lighting, no memory budget, standard depth.
///
/// Threading: any thread; needs no GL context. Never fails.
#[unsafe(no_mangle)]
pub extern "C" fn dmsaa_options_default() -> DmsaaOptions {
    let rust = RetrofitOptions::default();
    let resolve = rust.resolve;
    DmsaaOptions {
        samples: rust.samples,
        layers: resolve.layers,
        position_attachment: DMSAA_NO_ATTACHMENT,
        world_space_position: 0,
        normal_attachment: DMSAA_NO_ATTACHMENT,
        normal_encoding: DMSAA_NORMAL_XYZ,
        normal_threshold: resolve.normal_threshold,
        method: DMSAA_METHOD_MEDIAN,
        window: DMSAA_WINDOW_SMOOTH,
        window_c: resolve.c,
        window_c_in: resolve.c_in,
        fast_path: u8::from(resolve.fast_path),
        blend_depth: u8::from(resolve.blend_depth),
        plane_uniformity: u8::from(resolve.plane_uniformity),
        position_uniformity: u8::from(resolve.position_uniformity),
        rules: [DMSAA_RULE_DEFAULT; DMSAA_MAX_RULES],
        stencil_copy: DMSAA_STENCIL_AUTO,
        layer_mix: DMSAA_LAYER_MIX_AUTO,
        layer_mix_curve: std::ptr::null(),
        restore_first_layer: match rust.restore_first_layer {
            FirstLayerRestore::Nothing => DMSAA_RESTORE_NOTHING,
            FirstLayerRestore::Everything => DMSAA_RESTORE_EVERYTHING,
            FirstLayerRestore::DepthAndStencil => DMSAA_RESTORE_DEPTH_AND_STENCIL,
        },
        check_second_lighting: u8::from(rust.check_second_lighting),
        clear_twins: 0,
        clear_colors: [[0.0; 4]; DMSAA_MAX_RULES],
        clear_depth: 1.0,
        clear_stencil: 0,
        second_layer_omits: 0,
        memory_budget_bytes: DMSAA_MEMORY_BUDGET_NONE,
        memory_budget_strict: 0,
        depth_mode: DMSAA_DEPTH_STANDARD,
    }
}

/// Retrofit the host's G-buffer framebuffer `host_fbo` with MSAA: read its
/// attachments, formats and draw buffers, make multisampled twins of them
/// and compile the resolve's programs.
///
/// `get_proc_address` (with `user_data`, passed back to it unchanged) loads
/// the GL entry points; the handle keeps the function table it loaded, never
/// a context. `options` is read during the call only. On success `*out`
/// holds the new handle, which the caller owns and frees with
/// [`dmsaa_destroy`]; on failure `*out` is set to null (when `out` is not
/// null) and nothing is left allocated.
///
/// Threading: the host's GL context must be current on the calling thread,
/// here and in every later call on the handle (the same context or one
/// sharing its objects). The GL state the host set (bindings, program,
/// viewport, enables, draw buffers...) is as it was when the call returns.
///
/// Every GL function the library calls is asked of the loader before
/// anything is made: one it returns null for is
/// `DMSAA_STATUS_UNSUPPORTED`, naming it.
///
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `get_proc_address`,
/// `options` or `out`; `DMSAA_STATUS_INVALID_ARGUMENT` for a `host_fbo` of
/// 0 (the default framebuffer has no textures to resolve into), a name that
/// is no framebuffer object, or options out of range;
/// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the framebuffer cannot be
/// retrofitted (no depth attachment, for one); `DMSAA_STATUS_UNSUPPORTED`
/// (a function the loader lacks, too), `DMSAA_STATUS_MEMORY_BUDGET`,
/// `DMSAA_STATUS_GL` as their names say. No GL error is left, and the host's
/// GL state is as it was, whatever the status.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_retrofit_new(
    get_proc_address: DmsaaGetProcAddress,
    user_data: *mut c_void,
    host_fbo: u32,
    options: *const DmsaaOptions,
    out: *mut *mut DmsaaRetrofit,
) -> DmsaaStatus {
    const F: &str = "dmsaa_retrofit_new";
    entry(F, || {
        if out.is_null() {
            return Err(Failure::null(F, "out"));
        }
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out = std::ptr::null_mut() };
        let Some(load) = get_proc_address else {
            return Err(Failure::null(F, "get_proc_address"));
        };
        let converted = read_options(F, options)?;
        let Some(fbo) = NonZeroU32::new(host_fbo) else {
            return Err(Failure::invalid(format!(
                "{F}: host_fbo is 0, the default framebuffer, which has no G-buffer textures to \
                 resolve into; pass the G-buffer framebuffer the geometry pass draws into"
            )));
        };
        let loader = |name: &str| match CString::new(name) {
            // SAFETY: the header requires a loader for the context current
            // on this thread, called with a NUL-terminated name.
            Ok(name) => unsafe { load(name.as_ptr(), user_data) },
            Err(_) => std::ptr::null(),
        };
        // SAFETY: the loader returns entry points of the context current
        // on this thread, as the header requires. Every function the
        // library calls is asked for first (`DMSAA_STATUS_UNSUPPORTED`
        // naming one the loader lacks), and a GL error left behind a panic
        // is drained.
        let msaa = unsafe { ForeignRetrofit::new(loader, fbo, &converted.options)? };
        let handle = Box::new(DmsaaRetrofit {
            msaa,
            depth_mode: converted.depth_mode,
            world_space: converted.world_space,
            phase: Phase::Idle,
            forward: None,
            poisoned: false,
        });
        // SAFETY: as above.
        unsafe { *out = Box::into_raw(handle) };
        Ok(())
    })
}

/// The multisampled framebuffer: bind it instead of the host's G-buffer
/// framebuffer for the geometry pass. It changes after
/// [`dmsaa_set_options`] or [`dmsaa_refresh`] rebuild the twins, so a host
/// asks for it each frame (the call is cheap: no GL call).
///
/// Ownership: the framebuffer belongs to the handle; do not delete it.
/// Threading: the calling thread's context need not be current.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_framebuffer(
    retrofit: *mut DmsaaRetrofit,
    out_fbo: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_framebuffer";
    entry(F, || {
        if out_fbo.is_null() {
            return Err(Failure::null(F, "out_fbo"));
        }
        let fbo = with_handle(F, retrofit, |h| Ok(h.msaa.framebuffer().get()))?;
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_fbo = fbo };
        Ok(())
    })
}

/// The start of a frame: check that the multisampled framebuffer and its
/// textures still exist (something that deletes them, such as a
/// render-target wrapper deleting what it wraps, makes every later frame
/// stale), clear the twins to the options' `clear_*` values where
/// `clear_twins` is 1, and give [`dmsaa_framebuffer`]'s framebuffer in
/// `*out_fbo`, to bind for the geometry pass.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`;
/// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming a deleted object (then
/// [`dmsaa_refresh`] makes new twins); `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_begin_frame(
    retrofit: *mut DmsaaRetrofit,
    out_fbo: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_begin_frame";
    entry(F, || {
        if out_fbo.is_null() {
            return Err(Failure::null(F, "out_fbo"));
        }
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_fbo = 0 };
        let fbo = with_handle(F, retrofit, |h| Ok(h.msaa.begin_frame()?.get()))?;
        // SAFETY: as above.
        unsafe { *out_fbo = fbo };
        Ok(())
    })
}

/// The real sample count of the twins (the driver may round the requested
/// count up, or the memory budget step it down).
///
/// Threading: the calling thread's context need not be current.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_samples`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_samples(
    retrofit: *mut DmsaaRetrofit,
    out_samples: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_samples";
    entry(F, || {
        if out_samples.is_null() {
            return Err(Failure::null(F, "out_samples"));
        }
        let samples = with_handle(F, retrofit, |h| Ok(h.msaa.samples()))?;
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_samples = samples };
        Ok(())
    })
}

/// The stencil value [`dmsaa_second_layer_selection`]'s texture holds at the
/// pixels that have a second layer (0 elsewhere).
pub const DMSAA_SECOND_LAYER_SELECTED: u8 = 1;
// A literal, for the header; the same as the core's.
const _: () =
    assert!(DMSAA_SECOND_LAYER_SELECTED == deferred_msaa::second_layer::SECOND_LAYER_SELECTED);

/// The pixels of the last resolve that have a second layer, as a stencil,
/// for a host to light only those in its second lighting: the name of a
/// `GL_TEXTURE_2D` of format `GL_DEPTH24_STENCIL8` whose stencil is
/// `DMSAA_SECOND_LAYER_SELECTED` exactly there and 0 elsewhere (its depth is
/// not defined, and a lighting pass that clears depth may clear it: the
/// library reads the stencil alone). Attach it as the `GL_DEPTH_STENCIL_ATTACHMENT` of the
/// framebuffer the second lighting draws into and test
/// `glStencilFunc(GL_EQUAL, DMSAA_SECOND_LAYER_SELECTED, 0xFF)` with a
/// stencil write mask of 0; [`dmsaa_finish_second_layer`] keeps the first
/// layer's lit value wherever the second lighting was masked off, so the
/// image is the same, for the cost of the selected pixels. Writes 0 with
/// one layer, or where the resolve had no draw buffer to spare for the
/// flag the selection is made from.
///
/// Ownership: the texture belongs to the handle; do not delete it or write
/// its stencil. It changes after [`dmsaa_set_options`] or
/// [`dmsaa_refresh`] rebuild the twins, so a host asks for it each frame
/// (the call is cheap: no GL call).
/// Threading: the calling thread's context need not be current.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_texture`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_second_layer_selection(
    retrofit: *mut DmsaaRetrofit,
    out_texture: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_second_layer_selection";
    entry(F, || {
        if out_texture.is_null() {
            return Err(Failure::null(F, "out_texture"));
        }
        let texture = with_handle(F, retrofit, |h| {
            Ok(h.msaa.second_layer_selection().map_or(0, NonZeroU32::get))
        })?;
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_texture = texture };
        Ok(())
    })
}

/// Sixteen floats from C.
fn matrix(function: &str, name: &str, m: *const f32) -> Result<[f32; 16], Failure> {
    if m.is_null() {
        return Err(Failure::null(function, name));
    }
    // SAFETY: the header requires 16 readable floats.
    Ok(unsafe { std::ptr::read_unaligned(m.cast::<[f32; 16]>()) })
}

/// Resolve the twins into the host's own G-buffer textures (and depth):
/// call it after the geometry pass, before the host's lighting reads its
/// G-buffer.
///
/// `projection`: the 16 floats of the geometry pass's projection matrix,
/// column-major (as `glUniformMatrix4fv` takes them untransposed), a GL
/// perspective projection. `view_or_null`: the view matrix likewise when
/// the options' position attachment holds world-space positions, else null
/// (it is then ignored). Both are read during the call only.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or
/// `projection`, or a null `view_or_null` with world-space positions;
/// `DMSAA_STATUS_INVALID_ARGUMENT` for a projection that is not a GL
/// perspective matrix; `DMSAA_STATUS_OUT_OF_ORDER` between
/// [`dmsaa_begin_second_layer`] and [`dmsaa_finish_second_layer`];
/// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the host re-allocated,
/// deleted or replaced an attachment since it was read (call
/// [`dmsaa_refresh`]); `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_resolve(
    retrofit: *mut DmsaaRetrofit,
    projection: *const f32,
    view_or_null: *const f32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_resolve";
    entry(F, || {
        with_handle(F, retrofit, |h| {
            let projection = matrix(F, "projection", projection)?;
            let mut frame = Frame::from_matrix(projection).with_depth_mode(h.depth_mode);
            if h.world_space {
                frame = frame.with_view(matrix(
                    F,
                    "view_or_null (the options' positions are world-space)",
                    view_or_null,
                )?);
            }
            let out_of_order = matches!(h.phase, Phase::Lighting(_));
            match h.msaa.resolve(&frame) {
                Ok(()) => {
                    h.phase = Phase::Resolved;
                    Ok(())
                }
                // The last frame's check: this frame is resolved.
                Err(e @ Error::SecondLighting(_)) => {
                    h.phase = Phase::Resolved;
                    Err(e.into())
                }
                Err(e) if out_of_order => Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string())),
                Err(e) => Err(e.into()),
            }
        })
    })
}

/// With two layers, after the host lit the first layer into `output_fbo`
/// (its framebuffer; 0 for the default framebuffer; the lit colour is its
/// first draw buffer's, the G-buffer's size): keep that lit image and put
/// the second layer into the host's G-buffer textures and depth. Then, when
/// `*run_lighting` is true, the host runs its lighting again, unchanged,
/// into the same `output_fbo`, and calls [`dmsaa_finish_second_layer`].
/// With one layer nothing is done and `*run_lighting` is false.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or
/// `run_lighting`; `DMSAA_STATUS_OUT_OF_ORDER` before this frame's
/// [`dmsaa_resolve`] or when already begun; `DMSAA_STATUS_INVALID_ARGUMENT`
/// for an output the second layer cannot use (no framebuffer, or
/// incomplete); `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the G-buffer
/// changed since it was read, as for [`dmsaa_resolve`]; `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_begin_second_layer(
    retrofit: *mut DmsaaRetrofit,
    output_fbo: u32,
    run_lighting: *mut bool,
) -> DmsaaStatus {
    const F: &str = "dmsaa_begin_second_layer";
    entry(F, || {
        if run_lighting.is_null() {
            return Err(Failure::null(F, "run_lighting"));
        }
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *run_lighting = false };
        let began = with_handle(F, retrofit, |h| {
            let out_of_order = h.phase != Phase::Resolved;
            let output = NonZeroU32::new(output_fbo);
            match h.msaa.begin_second_layer(output) {
                Ok(true) => {
                    h.phase = Phase::Lighting(output_fbo);
                    Ok(true)
                }
                Ok(false) => Ok(false),
                Err(e) if out_of_order => Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string())),
                Err(e) => Err(e.into()),
            }
        })?;
        // SAFETY: as above.
        unsafe { *run_lighting = began };
        Ok(())
    })
}

/// [`dmsaa_begin_second_layer`], for a host that lights the second layer
/// into the library's own target instead of `output_fbo`: `*out_fbo` is a
/// framebuffer of `output_fbo`'s colour format and the G-buffer's size,
/// whose colour is cleared to the host's clear colour (`glClearColor`),
/// whose depth is cleared to the host's clear depth (`glClearDepth`), and
/// whose stencil is `DMSAA_SECOND_LAYER_SELECTED` exactly where a pixel has
/// a second layer (every pixel where no selection could be made). The host
/// binds it where it would bind `output_fbo` for its second lighting,
/// changing nothing else; with `glStencilFunc(GL_EQUAL,
/// DMSAA_SECOND_LAYER_SELECTED, 0xFF)` and `glStencilMask(0)` it lights only
/// the pixels the mix reads. It must not clear the stencil. This is the
/// route for a host lighting into the default framebuffer (0), to which no
/// texture attaches, and one whose lighting keeps its depth test on. Then
/// [`dmsaa_finish_second_layer`] with the same `output_fbo`. With one layer
/// nothing is done and `*out_fbo` is 0.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: those of [`dmsaa_begin_second_layer`], with `out_fbo` for
/// `run_lighting`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_begin_second_layer_own_target(
    retrofit: *mut DmsaaRetrofit,
    output_fbo: u32,
    out_fbo: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_begin_second_layer_own_target";
    entry(F, || {
        if out_fbo.is_null() {
            return Err(Failure::null(F, "out_fbo"));
        }
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_fbo = 0 };
        let target = with_handle(F, retrofit, |h| {
            let out_of_order = h.phase != Phase::Resolved;
            let output = NonZeroU32::new(output_fbo);
            match h.msaa.begin_second_layer_own_target(output) {
                Ok(Some(target)) => {
                    h.phase = Phase::Lighting(output_fbo);
                    Ok(target.get())
                }
                Ok(None) => Ok(0),
                Err(e) if out_of_order => Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string())),
                Err(e) => Err(e.into()),
            }
        })?;
        // SAFETY: as above.
        unsafe { *out_fbo = target };
        Ok(())
    })
}

/// MSAA for what the host draws forward after lighting (light cubes,
/// transparent objects, particles): after the lighting (with two layers,
/// after [`dmsaa_finish_second_layer`]), copy the lit image of
/// `output_fbo` (its first draw buffer's image; 0 for the default
/// framebuffer) into every sample of a multisampled colour target attached
/// with the G-buffer's multisampled depth and stencil as the geometry pass
/// drew them, and give that framebuffer in `*out_fbo`. The host binds it in
/// place of `output_fbo`, draws its forward objects unchanged (depth test,
/// blending, stencil as it likes), and calls [`dmsaa_finish_forward`].
/// `output_fbo`'s own depth is not changed; what the forward objects write
/// into depth goes into the multisampled depth, which the next geometry
/// pass clears.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`;
/// `DMSAA_STATUS_OUT_OF_ORDER` between the second layer's begin and finish
/// or when already begun; `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` for an
/// output of another size or without a colour draw buffer;
/// `DMSAA_STATUS_UNSUPPORTED`, `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_begin_forward(
    retrofit: *mut DmsaaRetrofit,
    output_fbo: u32,
    out_fbo: *mut u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_begin_forward";
    entry(F, || {
        if out_fbo.is_null() {
            return Err(Failure::null(F, "out_fbo"));
        }
        // SAFETY: checked non-null; the header requires a writable pointer.
        unsafe { *out_fbo = 0 };
        let target = with_handle(F, retrofit, |h| {
            let out_of_order = matches!(h.phase, Phase::Lighting(_)) || h.forward.is_some();
            let output = NonZeroU32::new(output_fbo);
            match h.msaa.begin_forward(output) {
                Ok(target) => {
                    h.forward = Some(output_fbo);
                    Ok(target.get())
                }
                Err(e) if out_of_order => Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string())),
                Err(e) => Err(e.into()),
            }
        })?;
        // SAFETY: as above.
        unsafe { *out_fbo = target };
        Ok(())
    })
}

/// After the host drew its forward objects into [`dmsaa_begin_forward`]'s
/// framebuffer: average each pixel's samples into `output_fbo`'s lit image
/// (the one given to begin), in the blend domain of the options'
/// `layer_mix`; a pixel no forward object touched keeps its value bit for
/// bit.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
/// `DMSAA_STATUS_OUT_OF_ORDER` without [`dmsaa_begin_forward`];
/// `DMSAA_STATUS_INVALID_ARGUMENT` for another output than begin's;
/// `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_finish_forward(
    retrofit: *mut DmsaaRetrofit,
    output_fbo: u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_finish_forward";
    entry(F, || {
        with_handle(F, retrofit, |h| {
            let begun = h.forward.take();
            let output = NonZeroU32::new(output_fbo);
            match h.msaa.finish_forward(output) {
                Ok(()) => Ok(()),
                Err(e) if begun.is_none() => {
                    Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string()))
                }
                Err(e) => Err(e.into()),
            }
        })
    })
}

/// After the host lit the second layer into `output_fbo` (the one given to
/// [`dmsaa_begin_second_layer`]): mix the two lit layers into it by the
/// second layer's coverage and put the first layer back into the host's
/// G-buffer (as much of it as the options' `restore_first_layer` says).
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
/// `DMSAA_STATUS_OUT_OF_ORDER` without a [`dmsaa_begin_second_layer`] that
/// returned `*run_lighting` true; `DMSAA_STATUS_INVALID_ARGUMENT` for
/// another output than begin's or with one layer; `DMSAA_STATUS_GL`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_finish_second_layer(
    retrofit: *mut DmsaaRetrofit,
    output_fbo: u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_finish_second_layer";
    entry(F, || {
        with_handle(F, retrofit, |h| {
            let phase = h.phase;
            let output = NonZeroU32::new(output_fbo);
            let result = h.msaa.finish_second_layer(output);
            match phase {
                // The Rust side leaves the phase when the output matches,
                // whatever the mix's result.
                Phase::Lighting(o) if o == output_fbo => h.phase = Phase::Idle,
                _ => {}
            }
            match result {
                Ok(()) => Ok(()),
                Err(e) if !matches!(phase, Phase::Lighting(_)) => {
                    Err(Failure::new(DmsaaStatus::OutOfOrder, e.to_string()))
                }
                Err(e) => Err(e.into()),
            }
        })
    })
}

/// What identifies the second layer's objects: they change when the twins
/// are rebuilt (a rebuilt second layer starts a frame afresh).
fn second_layer_identity(msaa: &ForeignRetrofit) -> Option<u32> {
    msaa.second_layer_coverage().map(NonZeroU32::get)
}

/// Change the options. Only what they change is rebuilt; when the twins
/// are, [`dmsaa_framebuffer`] returns the new multisampled framebuffer. On
/// error the handle keeps working with the options it had. `options` is
/// read during the call only.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `options`;
/// `DMSAA_STATUS_INVALID_ARGUMENT` for options out of range; those of
/// [`dmsaa_retrofit_new`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_set_options(
    retrofit: *mut DmsaaRetrofit,
    options: *const DmsaaOptions,
) -> DmsaaStatus {
    const F: &str = "dmsaa_set_options";
    entry(F, || {
        with_handle(F, retrofit, |h| {
            let converted = read_options(F, options)?;
            let before = second_layer_identity(&h.msaa);
            h.msaa.set_options(&converted.options)?;
            if second_layer_identity(&h.msaa) != before || before.is_none() {
                h.phase = Phase::Idle;
            }
            h.depth_mode = converted.depth_mode;
            h.world_space = converted.world_space;
            Ok(())
        })
    })
}

/// Re-read the host framebuffer after the host resized or re-allocated its
/// G-buffer textures, and rebuild the twins (ask [`dmsaa_framebuffer`]
/// again). On error the handle keeps working as before.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`; those of
/// [`dmsaa_retrofit_new`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_refresh(retrofit: *mut DmsaaRetrofit) -> DmsaaStatus {
    const F: &str = "dmsaa_refresh";
    entry(F, || {
        with_handle(F, retrofit, |h| {
            h.msaa.refresh()?;
            h.phase = Phase::Idle;
            Ok(())
        })
    })
}

/// Free every GL object the handle made (never the host's) and the handle
/// itself; `retrofit` is invalid afterwards. Null is accepted and does
/// nothing. A handle that had an internal error is freed too.
///
/// Threading: the host's context current on the calling thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_destroy(retrofit: *mut DmsaaRetrofit) {
    if retrofit.is_null() {
        return;
    }
    let _ = entry("dmsaa_destroy", || {
        // SAFETY: the header requires a handle from `dmsaa_retrofit_new`,
        // destroyed once.
        let handle = unsafe { Box::from_raw(retrofit) };
        handle.msaa.destroy();
        Ok(())
    });
}

/// The message of the calling thread's last failed call: one line saying
/// what went wrong and, where it can, what to do (shader build failures,
/// which only a driver problem causes, add the driver's log on further
/// lines). An empty string before any failure. Successful calls leave it
/// as it was.
///
/// Ownership: the library's; valid until the calling thread's next failed
/// call. Threading: any thread; each has its own message.
#[unsafe(no_mangle)]
pub extern "C" fn dmsaa_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// How many GL objects (textures, framebuffers, programs, shaders,
/// buffers, vertex arrays, queries) the library has made and not yet freed
/// on the calling thread, over every handle: 0 once every handle made on
/// this thread is destroyed.
///
/// Threading: any thread; counts that thread's objects.
#[unsafe(no_mangle)]
pub extern "C" fn dmsaa_live_objects() -> i64 {
    deferred_msaa::gl::live_objects().total()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn last_error() -> String {
        // SAFETY: the library's own NUL-terminated message.
        unsafe { CStr::from_ptr(dmsaa_last_error()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_becomes_a_status_and_a_one_line_message() {
        let status = entry("dmsaa_test", || panic!("deliberately\nsecond line"));
        assert_eq!(status, DmsaaStatus::Panic);
        let message = last_error();
        assert!(
            message.starts_with("dmsaa_test: internal error"),
            "{message}"
        );
        assert!(
            message.contains("deliberately") && !message.contains('\n'),
            "{message}"
        );
    }

    #[test]
    fn the_defaults_are_the_rust_defaults() {
        let converted = convert(&dmsaa_options_default()).expect("the defaults are valid");
        assert_eq!(converted.options, RetrofitOptions::default());
        // Each layer mix constant is its own declaration (the list is
        // indexed by the constants' values).
        for (constant, want) in [
            (DMSAA_LAYER_MIX_AUTO, LayerMix::Auto),
            (DMSAA_LAYER_MIX_LINEAR, LayerMix::Linear),
            (DMSAA_LAYER_MIX_TONEMAPPED, LayerMix::Tonemapped),
            (DMSAA_LAYER_MIX_SRGB_ENCODED, LayerMix::SrgbEncoded),
        ] {
            let mut o = dmsaa_options_default();
            o.layer_mix = constant;
            assert_eq!(convert(&o).expect("valid").options.layer_mix, want);
        }
        assert_eq!(converted.depth_mode, DepthMode::Standard);
        assert!(!converted.world_space);
    }

    #[test]
    fn every_field_converts_and_out_of_range_values_are_named() {
        let mut o = dmsaa_options_default();
        o.layers = 2;
        o.position_attachment = 0;
        o.world_space_position = 1;
        o.normal_attachment = 1;
        o.normal_encoding = DMSAA_NORMAL_OCTAHEDRAL_UNORM;
        o.method = DMSAA_METHOD_FRONT;
        o.window = DMSAA_WINDOW_HARD;
        o.rules[1] = DMSAA_RULE_SELECT;
        o.stencil_copy = DMSAA_STENCIL_BLIT;
        o.layer_mix = DMSAA_LAYER_MIX_TONEMAPPED;
        o.restore_first_layer = DMSAA_RESTORE_DEPTH_AND_STENCIL;
        o.memory_budget_bytes = 1 << 20;
        o.memory_budget_strict = 1;
        o.depth_mode = DMSAA_DEPTH_REVERSED_Z;
        let c = convert(&o).expect("valid options");
        assert_eq!(c.options.resolve.layers, 2);
        assert_eq!(c.options.position_attachment, Some(ColorAttachment(0)));
        assert_eq!(c.options.position_space, PositionSpace::World);
        assert_eq!(
            c.options.normal_attachment,
            Some(NormalAttachment {
                attachment: ColorAttachment(1),
                encoding: NormalEncoding::OctahedralUnorm
            })
        );
        assert_eq!(c.options.resolve.method, ResolveMethod::Front);
        assert_eq!(c.options.resolve.window, Window::Hard);
        assert_eq!(
            c.options.rules,
            vec![(ColorAttachment(1), ResolveRule::Select)]
        );
        assert_eq!(c.options.stencil, StencilCopy::Blit);
        assert_eq!(c.options.layer_mix, LayerMix::Tonemapped);
        assert_eq!(
            c.options.restore_first_layer,
            FirstLayerRestore::DepthAndStencil
        );
        o.restore_first_layer = DMSAA_RESTORE_NOTHING;
        assert_eq!(
            convert(&o)
                .expect("valid options")
                .options
                .restore_first_layer,
            FirstLayerRestore::Nothing
        );
        assert_eq!(
            c.options.memory_budget,
            Some(MemoryBudget {
                bytes: Some(1 << 20),
                strict: true
            })
        );
        assert_eq!(c.depth_mode, DepthMode::ReversedZ);

        let curve = CString::new("vec3 dmsaa_curve(vec3 x) { return x; }").unwrap();
        let mut o = dmsaa_options_default();
        o.layer_mix = DMSAA_LAYER_MIX_CURVE;
        o.layer_mix_curve = curve.as_ptr();
        let c = convert(&o).expect("a curve mix");
        assert_eq!(
            c.options.layer_mix,
            LayerMix::Curve(curve.to_str().unwrap().into())
        );

        type Change = fn(&mut DmsaaOptions);
        let bad: [(&str, Change); 6] = [
            ("DmsaaOptions.stencil_copy is 4", |o| o.stencil_copy = 4),
            ("DmsaaOptions.rules[3] is 5", |o| o.rules[3] = 5),
            ("DmsaaOptions.depth_mode is 3", |o| o.depth_mode = 3),
            ("DmsaaOptions.restore_first_layer is 3", |o| {
                o.restore_first_layer = 3
            }),
            ("DmsaaOptions.normal_attachment is -2", |o| {
                o.normal_attachment = -2
            }),
            ("the normal threshold is a cosine", |o| {
                o.normal_threshold = 1.5
            }),
        ];
        for (expected, change) in bad {
            let mut o = dmsaa_options_default();
            change(&mut o);
            let Err(failure) = convert(&o) else {
                panic!("accepted: {expected}");
            };
            assert_eq!(failure.status, DmsaaStatus::InvalidArgument);
            assert!(failure.message.starts_with(expected), "{}", failure.message);
        }
    }

    #[test]
    fn null_pointers_are_refused_before_anything_is_read() {
        let mut out: *mut DmsaaRetrofit = std::ptr::NonNull::dangling().as_ptr();
        // SAFETY: every pointer is null or valid.
        let status = unsafe {
            dmsaa_retrofit_new(None, std::ptr::null_mut(), 1, std::ptr::null(), &mut out)
        };
        assert_eq!(status, DmsaaStatus::NullPointer);
        assert!(out.is_null(), "a failed call leaves *out null");
        assert_eq!(
            last_error(),
            "dmsaa_retrofit_new: `get_proc_address` is null"
        );
        let mut fbo = 0;
        // SAFETY: a null handle, which is refused.
        let status = unsafe { dmsaa_framebuffer(std::ptr::null_mut(), &mut fbo) };
        assert_eq!(status, DmsaaStatus::NullPointer);
        assert_eq!(last_error(), "dmsaa_framebuffer: `retrofit` is null");
    }
}
