//! The C types: the status every call returns, the option values as
//! typedefs and constants, `DmsaaOptions`, and the opaque handle.

// The entry points these types' docs link to; rustdoc alone needs them.
#[cfg(doc)]
use crate::{
    dmsaa_begin_frame, dmsaa_begin_second_layer, dmsaa_begin_second_layer_own_target,
    dmsaa_destroy, dmsaa_finish_second_layer, dmsaa_framebuffer, dmsaa_last_error,
    dmsaa_options_default, dmsaa_resolve, dmsaa_retrofit_new, dmsaa_samples,
    dmsaa_second_layer_selection,
};
use deferred_msaa::DepthMode;
use deferred_msaa::foreign::ForeignRetrofit;
use std::ffi::{c_char, c_void};

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
    /// `dmsaa_begin_second_layer`, `dmsaa_resolve` between the two or
    /// without `dmsaa_begin_frame` since the last `dmsaa_resolve` (or
    /// `dmsaa_refresh`).
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
    /// Two lit layers (or the forward target's samples) would be mixed in a
    /// floating-point output with `DMSAA_LAYER_MIX_AUTO`: GL state cannot
    /// tell the output's tonemap, which decides the domain. Declare
    /// `layer_mix` (`DMSAA_LAYER_MIX_CURVE`, `_TONEMAPPED` or `_LINEAR`; the
    /// message says which fits which tonemap). Returned by
    /// `dmsaa_begin_second_layer` and `dmsaa_begin_forward`, having done
    /// nothing.
    LayerMixUndeclared = 10,
    /// The multisampled twins were not cleared between
    /// [`dmsaa_begin_frame`](crate::dmsaa_begin_frame) and
    /// [`dmsaa_resolve`](crate::dmsaa_resolve) (the host clears its
    /// G-buffer through another framebuffer, or before
    /// `dmsaa_begin_frame`, and declared no clear values): much of their
    /// depth still holds the value `dmsaa_begin_frame` put there. Returned
    /// by `dmsaa_resolve`, having resolved nothing: by the first frame's
    /// at once, by a later frame's at the next `dmsaa_resolve`. Clear
    /// through `dmsaa_begin_frame`'s framebuffer after the call, or set
    /// `clear_twins` and the clear values.
    TwinsNotCleared = 11,
}

/// The GL loader a host already has: returns the address of the GL entry
/// point `name` (a NUL-terminated ASCII string), or null where it has none.
/// `user_data` is what the host gave [`dmsaa_retrofit_new`]. An
/// `eglGetProcAddress`, `glXGetProcAddress` or `SDL_GL_GetProcAddress` is
/// wrapped in a one-line function of this type.
pub type DmsaaGetProcAddress =
    Option<unsafe extern "C" fn(name: *const c_char, user_data: *mut c_void) -> *const c_void>;

/// How the reference sample of a pixel is chosen
/// (`DMSAA_METHOD_AVERAGE` … `DMSAA_METHOD_UPPER_MEDIAN`).
pub type DmsaaMethod = u32;
/// Every sample weighs 1, as a hardware resolve.
pub const DMSAA_METHOD_AVERAGE: DmsaaMethod = 0;
/// Reference: the nearest sample.
pub const DMSAA_METHOD_FRONT: DmsaaMethod = 1;
/// Reference: the median sample by depth, the two middle ones of an even
/// count taking turns pixel by pixel (the default).
pub const DMSAA_METHOD_MEDIAN: DmsaaMethod = 2;
/// Reference: the farthest sample.
pub const DMSAA_METHOD_BACK: DmsaaMethod = 3;
/// Reference: the farther of the two middle samples by depth on every
/// pixel (FreeSpace Open's median).
pub const DMSAA_METHOD_UPPER_MEDIAN: DmsaaMethod = 4;

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
/// Inferred (the default) where GL state can tell: in linear light for an
/// sRGB output the host writes with `GL_FRAMEBUFFER_SRGB` on; as sRGB-encoded
/// display values (`DMSAA_LAYER_MIX_SRGB_ENCODED`) for any other 8-bit
/// (or other unorm) output, framebuffer 0 included. A floating-point output's tonemap decides
/// its domain and GL cannot see it: the first call that mixes into it returns
/// `DMSAA_STATUS_LAYER_MIX_UNDECLARED`, naming the declarations to choose from.
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

/// The stencil value [`dmsaa_second_layer_selection`]'s texture holds at the
/// pixels that have a second layer (0 elsewhere).
pub const DMSAA_SECOND_LAYER_SELECTED: u8 = 1;
// A literal, for the header; the same as the core's.
const _: () =
    assert!(DMSAA_SECOND_LAYER_SELECTED == deferred_msaa::second_layer::SECOND_LAYER_SELECTED);

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
    /// With two layers, 1: the host's lit target shows `lit_clear_color`
    /// where its lighting writes nothing (a sky left to its `glClear`), and
    /// [`dmsaa_begin_second_layer_own_target`]'s target starts cleared to
    /// it. 0 (default): that target starts as a copy of the output's lit
    /// first layer (a pixel the second lighting leaves unwritten mixes to
    /// the first layer's value); never the host's last `glClearColor`.
    pub has_lit_clear: u8,
    /// With `has_lit_clear`: the lit target's clear colour (RGBA, as
    /// `glClearColor` takes it).
    pub lit_clear_color: [f32; 4],
}

/// A host G-buffer retrofitted with MSAA: the multisampled twins, the
/// resolve's programs and the GL function table loaded through the host's
/// loader (a [`ForeignRetrofit`]). It never owns a GL context. Opaque; made by
/// [`dmsaa_retrofit_new`], freed by [`dmsaa_destroy`].
pub struct DmsaaRetrofit {
    /// The retrofit and the function table loaded through the host's
    /// loader: the core's entry point for hosts that name GL objects by
    /// number.
    pub(crate) msaa: ForeignRetrofit,
    pub(crate) depth_mode: DepthMode,
    pub(crate) world_space: bool,
    /// The second layer's phase as the calls so far left it, to tell a
    /// call out of order from a bad argument.
    pub(crate) phase: Phase,
    /// Between `dmsaa_begin_forward` and `dmsaa_finish_forward`, for this
    /// output (0: default).
    pub(crate) forward: Option<u32>,
    /// A panic happened on this handle: its state may be half-changed.
    pub(crate) poisoned: bool,
}

/// Where a frame with two layers is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// Before this frame's resolve (or with one layer).
    Idle,
    /// Resolved: the second lighting may begin.
    Resolved,
    /// Between begin and finish, lighting into this output (0: default).
    Lighting(u32),
}
