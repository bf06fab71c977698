/*
 * deferred_msaa.h: depth-aware MSAA for OpenGL 3.2+ deferred renderers,
 * the C interface of the deferred-msaa-capi library.
 *
 * Generated from crates/capi/src/lib.rs by cbindgen; do not edit (the
 * crate's tests fail when this file differs from the declarations).
 *
 * A host adds two calls to its frame: bind dmsaa_framebuffer's framebuffer
 * for its geometry pass instead of its G-buffer's, and call dmsaa_resolve
 * before its lighting, which then reads its own G-buffer textures,
 * anti-aliased. With two layers, dmsaa_begin_second_layer and
 * dmsaa_finish_second_layer bracket a second run of its lighting.
 *
 * Conventions for every function:
 * - Ownership: a DmsaaRetrofit is made by dmsaa_retrofit_new and owned by
 *   the caller until dmsaa_destroy. Pointer arguments are read (or, for
 *   out_* and run_lighting, written) during the call only; nothing the
 *   host passes is kept. The library never deletes the host's GL objects
 *   and changes none but by writing the G-buffer's images (the resolve,
 *   the second layer) and, with two layers, the lit output's colour.
 * - Threading: calls that touch GL need the host's GL context current on
 *   the calling thread (the handle holds the GL function table loaded
 *   through the host's loader, never a context). A handle is used from one
 *   thread at a time.
 * - GL state: every call leaves the state the host set as it was (bound
 *   framebuffers, program, textures and active unit, viewport, enables,
 *   blend, depth and stencil settings, draw buffers).
 * - Errors: every fallible call returns a DmsaaStatus; on anything but
 *   DMSAA_STATUS_OK, dmsaa_last_error() has a one-line message for the
 *   calling thread. A null pointer, an option out of range or a call out
 *   of order is an error status, never undefined behaviour, and no panic
 *   crosses the boundary.
 */

#ifndef DEFERRED_MSAA_H
#define DEFERRED_MSAA_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// `position_attachment` / `normal_attachment`: none.
#define DMSAA_NO_ATTACHMENT -1

// How many colour attachments `DmsaaOptions.rules` covers (GL's
// guaranteed minimum of `GL_MAX_COLOR_ATTACHMENTS`).
#define DMSAA_MAX_RULES 8

// `memory_budget_bytes`: no budget.
#define DMSAA_MEMORY_BUDGET_NONE 0

// `memory_budget_bytes`: a share of the free video memory the driver
// reports (or the crate's fixed default where it reports none).
#define DMSAA_MEMORY_BUDGET_DRIVER UINT64_MAX

// The stencil value [`dmsaa_second_layer_selection`]'s texture holds at the
// pixels that have a second layer (0 elsewhere).
#define DMSAA_SECOND_LAYER_SELECTED 1

// What every fallible call returns. Any value other than
// `DMSAA_STATUS_OK` leaves a one-line message in [`dmsaa_last_error`].
typedef enum {
  // Success.
  DMSAA_STATUS_OK = 0,
  // A pointer argument that must not be null was null.
  DMSAA_STATUS_NULL_POINTER = 1,
  // An argument or an option is out of range (the message names it and
  // what is accepted), or the projection is not a GL perspective matrix.
  DMSAA_STATUS_INVALID_ARGUMENT = 2,
  // A call out of order: `dmsaa_begin_second_layer` before this frame's
  // `dmsaa_resolve` or twice, `dmsaa_finish_second_layer` without
  // `dmsaa_begin_second_layer`, `dmsaa_resolve` between the two or
  // without `dmsaa_begin_frame` since the last `dmsaa_resolve` (or
  // `dmsaa_refresh`).
  DMSAA_STATUS_OUT_OF_ORDER = 3,
  // The host framebuffer cannot be retrofitted as it is (no depth
  // attachment, an already multisampled attachment, a rule or key naming
  // an attachment it lacks): the message names the attachment.
  DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER = 4,
  // The context lacks what is asked for: a GL version or extension, a
  // sample count or a multisampled format; or the loader returns null
  // for a GL function the library calls (the message names it).
  DMSAA_STATUS_UNSUPPORTED = 5,
  // The twins would take more memory than the options' budget allows.
  DMSAA_STATUS_MEMORY_BUDGET = 6,
  // The driver failed: a GL error, an object that could not be made, an
  // incomplete framebuffer, a shader that did not compile or link (those
  // two carry the driver's log on the lines after the first).
  DMSAA_STATUS_GL = 7,
  // A panic inside the library, caught at the boundary. The handle it
  // happened on refuses every call but `dmsaa_destroy` from then on.
  DMSAA_STATUS_PANIC = 8,
  // The host's second lighting drew nothing where pixels have a second
  // layer (a depth or stencil test left on from the first lighting
  // rejected it): the message says how to set it up instead. Returned
  // by `dmsaa_finish_second_layer`, or, where the result was not ready
  // then, by the next `dmsaa_resolve` (which has still resolved its
  // frame).
  DMSAA_STATUS_SECOND_LIGHTING = 9,
  // Two lit layers (or the forward target's samples) would be mixed in a
  // floating-point output with `DMSAA_LAYER_MIX_AUTO`: GL state cannot
  // tell the output's tonemap, which decides the domain. Declare
  // `layer_mix` (`DMSAA_LAYER_MIX_CURVE`, `_TONEMAPPED` or `_LINEAR`; the
  // message says which fits which tonemap). Returned by
  // `dmsaa_begin_second_layer` and `dmsaa_begin_forward`, having done
  // nothing.
  DMSAA_STATUS_LAYER_MIX_UNDECLARED = 10,
  // The multisampled twins were not cleared between
  // [`dmsaa_begin_frame`](crate::dmsaa_begin_frame) and
  // [`dmsaa_resolve`](crate::dmsaa_resolve) (the host clears its
  // G-buffer through another framebuffer, or before
  // `dmsaa_begin_frame`, and declared no clear values): much of their
  // depth still holds the value `dmsaa_begin_frame` put there. Returned
  // by `dmsaa_resolve`, having resolved nothing: by the first frame's
  // at once, by a later frame's at the next `dmsaa_resolve`. Clear
  // through `dmsaa_begin_frame`'s framebuffer after the call, or set
  // `clear_twins` and the clear values.
  DMSAA_STATUS_TWINS_NOT_CLEARED = 11,
} DmsaaStatus;

// A host G-buffer retrofitted with MSAA: the multisampled twins, the
// resolve's programs and the GL function table loaded through the host's
// loader (a [`ForeignRetrofit`]). It never owns a GL context. Opaque; made by
// [`dmsaa_retrofit_new`], freed by [`dmsaa_destroy`].
typedef struct DmsaaRetrofit DmsaaRetrofit;

// How a normal attachment stores a normal (`DMSAA_NORMAL_XYZ` …).
typedef uint32_t DmsaaNormalEncoding;

// How the reference sample of a pixel is chosen
// (`DMSAA_METHOD_AVERAGE` … `DMSAA_METHOD_UPPER_MEDIAN`).
typedef uint32_t DmsaaMethod;

// The closeness window (`DMSAA_WINDOW_HARD`, `DMSAA_WINDOW_SMOOTH`).
typedef uint32_t DmsaaWindow;

// The rule by which one colour attachment's samples become one value.
typedef uint32_t DmsaaRule;

// How a depth-stencil host's stencil is written back after the resolve.
typedef uint32_t DmsaaStencilCopy;

// What the host's lit values mean, and so how the two lit layers are
// mixed by the second layer's coverage (and the forward target's samples
// averaged).
typedef uint32_t DmsaaLayerMix;

// What `dmsaa_finish_second_layer` puts back of the first layer in the
// host's G-buffer; what it does not put back holds the second layer.
typedef uint32_t DmsaaRestore;

// How the host's depth buffer holds depth.
typedef uint32_t DmsaaDepthMode;

// Everything that does not change from frame to frame, given once: the
// C form of the Rust `RetrofitOptions`. Start from
// [`dmsaa_options_default`] and change fields; flags are 0 or 1, and any
// value out of range makes the call that is given it fail with
// `DMSAA_STATUS_INVALID_ARGUMENT`, naming the field.
typedef struct {
  // Requested samples per pixel, at least 1 (default 4); the driver's
  // real count is used ([`dmsaa_samples`]).
  uint32_t samples;
  // Resolved layers per pixel: 1 (default) or 2 (the second layer:
  // [`dmsaa_begin_second_layer`], [`dmsaa_finish_second_layer`]).
  uint32_t layers;
  // The colour attachment number holding positions, whose view-space
  // `-z` is the depth key; `DMSAA_NO_ATTACHMENT` (default) linearises
  // the depth attachment with each frame's projection instead.
  int32_t position_attachment;
  // 1: the position attachment holds world-space positions, and each
  // [`dmsaa_resolve`] passes the view matrix; 0 (default): view space.
  uint8_t world_space_position;
  // The colour attachment number holding normals, for the normal test
  // (one layer or two; name it for normals packed as `n*0.5+0.5`);
  // `DMSAA_NO_ATTACHMENT` (default): by depth alone.
  int32_t normal_attachment;
  // How `normal_attachment` stores normals (`DMSAA_NORMAL_*`).
  DmsaaNormalEncoding normal_encoding;
  // With a normal attachment: samples close in depth are
  // one surface only when the cosine between their normals is at least
  // this, in `[-1, 1]` (default 0.95).
  double normal_threshold;
  // `DMSAA_METHOD_*` (default median).
  DmsaaMethod method;
  // `DMSAA_WINDOW_*` (default smooth).
  DmsaaWindow window;
  // Outer window width in pixel footprints, above 0 (default 5).
  double window_c;
  // Inner width of the smooth window, at least 0 and below `window_c`
  // (default 2.5).
  double window_c_in;
  // 1 (default): uniform pixels take one sample.
  uint8_t fast_path;
  // 1: blend the depth attachment's value rather than select the
  // reference's (default 0).
  uint8_t blend_depth;
  // 1: with the fast path and a depth key, pixels whose depth samples lie
  // on one plane count as uniform (default 0).
  uint8_t plane_uniformity;
  // 1: with the fast path and a position key, pixels whose position
  // samples are all equal count as uniform (default 0).
  uint8_t position_uniformity;
  // The rule of colour attachment `k` (`DMSAA_RULE_*`); attachments the
  // host framebuffer lacks must stay `DMSAA_RULE_DEFAULT`.
  DmsaaRule rules[DMSAA_MAX_RULES];
  // `DMSAA_STENCIL_*` (default auto).
  DmsaaStencilCopy stencil_copy;
  // `DMSAA_LAYER_MIX_*` (default auto).
  DmsaaLayerMix layer_mix;
  // With `DMSAA_LAYER_MIX_CURVE`: the curve's GLSL, NUL-terminated UTF-8,
  // copied by the call that reads the options; otherwise ignored.
  const char *layer_mix_curve;
  // `DMSAA_RESTORE_*` (default everything): what
  // `dmsaa_finish_second_layer` puts back of the first layer in the
  // host's G-buffer. The lit image is the same whichever is chosen.
  DmsaaRestore restore_first_layer;
  // 1 (default): with two layers, count what the first and second
  // lighting draw (occlusion queries between `dmsaa_resolve` and
  // `dmsaa_begin_second_layer`, and between it and
  // `dmsaa_finish_second_layer`) and return
  // `DMSAA_STATUS_SECOND_LIGHTING` where the second drew nothing. 0 for a
  // host that runs occlusion queries of its own there, or whose second
  // lighting draws no fragments while something before its first
  // lighting does.
  uint8_t check_second_lighting;
  // 1: [`dmsaa_begin_frame`] clears the multisampled twins to
  // `clear_colors` (per colour attachment number, `glClearBufferfv`'s
  // values; integer attachments take them as integers), `clear_depth` and
  // `clear_stencil`, for a host that clears its G-buffer through another
  // framebuffer or per attachment with its own values. 0 (default): the
  // host clears through [`dmsaa_framebuffer`]'s framebuffer.
  uint8_t clear_twins;
  // With `clear_twins`: each colour attachment's clear value (default 0).
  float clear_colors[DMSAA_MAX_RULES][4];
  // With `clear_twins`: the depth clear value (default 1).
  float clear_depth;
  // With `clear_twins`: the stencil clear value (default 0).
  int32_t clear_stencil;
  // With two layers: the colour attachments the second layer need not
  // carry, as a bit mask (bit n: `GL_COLOR_ATTACHMENTn`; default 0):
  // attachments the host's lighting does not read or reads the same for
  // both surfaces (an object ID, velocity). Not resolved for the second
  // layer; the host's image keeps the first layer's value there during
  // the second lighting.
  uint32_t second_layer_omits;
  // A limit on the twins' memory in bytes: `DMSAA_MEMORY_BUDGET_NONE`
  // (default), `DMSAA_MEMORY_BUDGET_DRIVER`, or a number of bytes. Over
  // it, the sample count steps down (or, strict, the call fails).
  uint64_t memory_budget_bytes;
  // 1: over the budget, fail with `DMSAA_STATUS_MEMORY_BUDGET` rather
  // than step down (default 0).
  uint8_t memory_budget_strict;
  // `DMSAA_DEPTH_*` (default standard): how the host stores depth.
  DmsaaDepthMode depth_mode;
  // With two layers, 1: the host's lit target shows `lit_clear_color`
  // where its lighting writes nothing (a sky left to its `glClear`), and
  // [`dmsaa_begin_second_layer_own_target`]'s target starts cleared to
  // it. 0 (default): that target starts as a copy of the output's lit
  // first layer (a pixel the second lighting leaves unwritten mixes to
  // the first layer's value); never the host's last `glClearColor`.
  uint8_t has_lit_clear;
  // With `has_lit_clear`: the lit target's clear colour (RGBA, as
  // `glClearColor` takes it).
  float lit_clear_color[4];
} DmsaaOptions;

// The GL loader a host already has: returns the address of the GL entry
// point `name` (a NUL-terminated ASCII string), or null where it has none.
// `user_data` is what the host gave [`dmsaa_retrofit_new`]. An
// `eglGetProcAddress`, `glXGetProcAddress` or `SDL_GL_GetProcAddress` is
// wrapped in a one-line function of this type.
typedef const void *(*DmsaaGetProcAddress)(const char *name, void *user_data);

// Every sample weighs 1, as a hardware resolve.
#define DMSAA_METHOD_AVERAGE 0

// Reference: the nearest sample.
#define DMSAA_METHOD_FRONT 1

// Reference: the median sample by depth, the two middle ones of an even
// count taking turns pixel by pixel (the default).
#define DMSAA_METHOD_MEDIAN 2

// Reference: the farthest sample.
#define DMSAA_METHOD_BACK 3

// Reference: the farther of the two middle samples by depth on every
// pixel (FreeSpace Open's median).
#define DMSAA_METHOD_UPPER_MEDIAN 4

// Weight 1 within `window_c` pixel footprints, else 0.
#define DMSAA_WINDOW_HARD 0

// Weight falling smoothly from `window_c_in` to `window_c` (the default).
#define DMSAA_WINDOW_SMOOTH 1

// xyz as they are (a float or snorm attachment; the default).
#define DMSAA_NORMAL_XYZ 0

// xyz packed as `n * 0.5 + 0.5` (an RGBA8 attachment).
#define DMSAA_NORMAL_UNORM 1

// Octahedral, x and y in `[-1, 1]`.
#define DMSAA_NORMAL_OCTAHEDRAL 2

// Octahedral packed into `[0, 1]`.
#define DMSAA_NORMAL_OCTAHEDRAL_UNORM 3

// The format's default: blend, select for integer formats.
#define DMSAA_RULE_DEFAULT 0

// Weighted mean.
#define DMSAA_RULE_BLEND 1

// Normalised weighted sum of xyz (normals), w blended.
#define DMSAA_RULE_BLEND_NORMAL 2

// Weighted mean in the tonemapped domain `x / (1 + max3(x))`.
#define DMSAA_RULE_BLEND_HDR 3

// The reference sample's value, never blended.
#define DMSAA_RULE_SELECT 4

// The best the driver offers (the default).
#define DMSAA_STENCIL_AUTO 0

// One pass, with `GL_ARB_shader_stencil_export`.
#define DMSAA_STENCIL_EXPORT 1

// Eight passes, with `GL_ARB_stencil_texturing` alone.
#define DMSAA_STENCIL_BIT_PASSES 2

// `glBlitFramebuffer`: the sample the driver picks.
#define DMSAA_STENCIL_BLIT 3

// Inferred (the default) where GL state can tell: in linear light for an
// sRGB output the host writes with `GL_FRAMEBUFFER_SRGB` on; as sRGB-encoded
// display values (`DMSAA_LAYER_MIX_SRGB_ENCODED`) for any other 8-bit
// (or other unorm) output, framebuffer 0 included. A floating-point output's tonemap decides
// its domain and GL cannot see it: the first call that mixes into it returns
// `DMSAA_STATUS_LAYER_MIX_UNDECLARED`, naming the declarations to choose from.
#define DMSAA_LAYER_MIX_AUTO 0

// Linear values (linear light, or any values to be mixed as they are):
// `mix(first, second, a)` as the output stores them.
#define DMSAA_LAYER_MIX_LINEAR 1

// In the domain `x / (1 + max3(x))`, mapped back.
#define DMSAA_LAYER_MIX_TONEMAPPED 2

// In the domain of the host's own tonemap curve: `layer_mix_curve` is GLSL
// defining `vec3 dmsaa_curve(vec3)` and `vec3 dmsaa_curve_inverse(vec3)`.
#define DMSAA_LAYER_MIX_CURVE 3

// sRGB-encoded display values the host's shader wrote (or an sRGB image
// written with `GL_FRAMEBUFFER_SRGB` off): decoded, mixed in linear light,
// encoded again.
#define DMSAA_LAYER_MIX_SRGB_ENCODED 4

// Nothing: for a host that reads nothing of its G-buffer after lighting
// until its next geometry pass (no copies).
#define DMSAA_RESTORE_NOTHING 0

// Colours, depth and stencil (the default).
#define DMSAA_RESTORE_EVERYTHING 1

// Depth and stencil only: for a host whose passes after lighting test
// against them (transparent objects drawn with depth testing) but read
// no colour attachment.
#define DMSAA_RESTORE_DEPTH_AND_STENCIL 2

// OpenGL's default: the near plane at 0, cleared to 1 (the default).
#define DMSAA_DEPTH_STANDARD 0

// `glClipControl(..., GL_ZERO_TO_ONE)`, cleared to 1.
#define DMSAA_DEPTH_ZERO_TO_ONE 1

// Reversed-Z: `GL_ZERO_TO_ONE`, the near plane at 1, cleared to 0.
#define DMSAA_DEPTH_REVERSED_Z 2

#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

// The default options: 4 samples, one layer, the depth key from the depth
// buffer, the median method with the smooth window (c = 5, c_in = 2.5),
// the fast path, each attachment's default rule, the first layer restored
// after the second lighting, no memory budget, standard depth.
//
// Threading: any thread; needs no GL context. Never fails.
DmsaaOptions dmsaa_options_default(void);

// Retrofit the host's G-buffer framebuffer `host_fbo` with MSAA: read its
// attachments, formats and draw buffers, make multisampled twins of them
// and compile the resolve's programs.
//
// `get_proc_address` (with `user_data`, passed back to it unchanged) loads
// the GL entry points; the handle keeps the function table it loaded, never
// a context. `options` is read during the call only. On success `*out`
// holds the new handle, which the caller owns and frees with
// [`dmsaa_destroy`]; on failure `*out` is set to null (when `out` is not
// null) and nothing is left allocated.
//
// Threading: the host's GL context must be current on the calling thread,
// here and in every later call on the handle (the same context or one
// sharing its objects). The GL state the host set (bindings, program,
// viewport, enables, draw buffers...) is as it was when the call returns.
//
// Every GL function the library calls is asked of the loader before
// anything is made: one it returns null for is
// `DMSAA_STATUS_UNSUPPORTED`, naming it.
//
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `get_proc_address`,
// `options` or `out`; `DMSAA_STATUS_INVALID_ARGUMENT` for a `host_fbo` of
// 0 (the default framebuffer has no textures to resolve into), a name that
// is no framebuffer object, or options out of range;
// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the framebuffer cannot be
// retrofitted (no depth attachment, for one); `DMSAA_STATUS_UNSUPPORTED`
// (a function the loader lacks, too), `DMSAA_STATUS_MEMORY_BUDGET`,
// `DMSAA_STATUS_GL` as their names say. No GL error is left, and the host's
// GL state is as it was, whatever the status.
DmsaaStatus dmsaa_retrofit_new(DmsaaGetProcAddress get_proc_address,
                               void *user_data,
                               uint32_t host_fbo,
                               const DmsaaOptions *options,
                               DmsaaRetrofit **out);

// The multisampled framebuffer: bind it instead of the host's G-buffer
// framebuffer for the geometry pass. It changes after
// [`dmsaa_set_options`] or [`dmsaa_refresh`] rebuild the twins, so a host
// asks for it each frame (the call is cheap: no GL call).
//
// Ownership: the framebuffer belongs to the handle; do not delete it.
// Threading: the calling thread's context need not be current.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`.
DmsaaStatus dmsaa_framebuffer(DmsaaRetrofit *retrofit, uint32_t *out_fbo);

// The start of a frame, required before each frame's geometry pass: check
// that the multisampled framebuffer and its textures still exist
// (something that deletes them, such as a render-target wrapper deleting
// what it wraps, makes every later frame stale), prepare the twins, and
// give [`dmsaa_framebuffer`]'s framebuffer in `*out_fbo`, to bind for the
// geometry pass. With `clear_twins` 1 the twins are cleared to the
// options' `clear_*` values; with 0 their depth is cleared to a sentinel
// that the host's own clear of `*out_fbo` replaces, and [`dmsaa_resolve`]
// returns `DMSAA_STATUS_TWINS_NOT_CLEARED` for a frame in which much of
// it is left.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`;
// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming a deleted object (then
// [`dmsaa_refresh`] makes new twins); `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_begin_frame(DmsaaRetrofit *retrofit, uint32_t *out_fbo);

// The real sample count of the twins (the driver may round the requested
// count up, or the memory budget step it down).
//
// Threading: the calling thread's context need not be current.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_samples`.
DmsaaStatus dmsaa_samples(DmsaaRetrofit *retrofit, uint32_t *out_samples);

// The pixels of the last resolve that have a second layer, as a stencil,
// for a host to light only those in its second lighting: the name of a
// `GL_TEXTURE_2D` of format `GL_DEPTH24_STENCIL8` whose stencil is
// `DMSAA_SECOND_LAYER_SELECTED` exactly there and 0 elsewhere (its depth is
// not defined, and a lighting pass that clears depth may clear it: the
// library reads the stencil alone). Attach it as the `GL_DEPTH_STENCIL_ATTACHMENT` of the
// framebuffer the second lighting draws into and test
// `glStencilFunc(GL_EQUAL, DMSAA_SECOND_LAYER_SELECTED, 0xFF)` with a
// stencil write mask of 0; [`dmsaa_finish_second_layer`] keeps the first
// layer's lit value wherever the second lighting was masked off, so the
// image is the same, for the cost of the selected pixels. Writes 0 with
// one layer, or where the resolve had no draw buffer to spare for the
// flag the selection is made from.
//
// Ownership: the texture belongs to the handle; do not delete it or write
// its stencil. It changes after [`dmsaa_set_options`] or
// [`dmsaa_refresh`] rebuild the twins, so a host asks for it each frame
// (the call is cheap: no GL call).
// Threading: the calling thread's context need not be current.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_texture`.
DmsaaStatus dmsaa_second_layer_selection(DmsaaRetrofit *retrofit, uint32_t *out_texture);

// Resolve the twins into the host's own G-buffer textures (and depth):
// call it after the geometry pass, before the host's lighting reads its
// G-buffer.
//
// `projection`: the 16 floats of the geometry pass's projection matrix,
// column-major (as `glUniformMatrix4fv` takes them untransposed), a GL
// perspective projection. `view_or_null`: the view matrix likewise when
// the options' position attachment holds world-space positions, else null
// (it is then ignored). Both are read during the call only.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or
// `projection`, or a null `view_or_null` with world-space positions;
// `DMSAA_STATUS_INVALID_ARGUMENT` for a projection that is not a GL
// perspective matrix; `DMSAA_STATUS_OUT_OF_ORDER` between
// [`dmsaa_begin_second_layer`] and [`dmsaa_finish_second_layer`], or
// without [`dmsaa_begin_frame`] since the last resolve;
// `DMSAA_STATUS_TWINS_NOT_CLEARED` where nothing cleared the twins after
// `dmsaa_begin_frame`;
// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the host re-allocated,
// deleted or replaced an attachment since it was read (call
// [`dmsaa_refresh`]); `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_resolve(DmsaaRetrofit *retrofit,
                          const float *projection,
                          const float *view_or_null);

// With two layers, after the host lit the first layer into `output_fbo`
// (its framebuffer; 0 for the default framebuffer; the lit colour is its
// first draw buffer's, the G-buffer's size): keep that lit image and put
// the second layer into the host's G-buffer textures and depth. Then, when
// `*run_lighting` is true, the host runs its lighting again, unchanged,
// into the same `output_fbo`, and calls [`dmsaa_finish_second_layer`].
// With one layer nothing is done and `*run_lighting` is false.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or
// `run_lighting`; `DMSAA_STATUS_OUT_OF_ORDER` before this frame's
// [`dmsaa_resolve`] or when already begun; `DMSAA_STATUS_INVALID_ARGUMENT`
// for an output the second layer cannot use (no framebuffer, or
// incomplete); `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` when the G-buffer
// changed since it was read, as for [`dmsaa_resolve`];
// `DMSAA_STATUS_LAYER_MIX_UNDECLARED` for a floating-point output with
// `DMSAA_LAYER_MIX_AUTO` (declare the output's tonemap); `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_begin_second_layer(DmsaaRetrofit *retrofit,
                                     uint32_t output_fbo,
                                     bool *run_lighting);

// [`dmsaa_begin_second_layer`], for a host that lights the second layer
// into the library's own target instead of `output_fbo`: `*out_fbo` is a
// framebuffer of `output_fbo`'s colour format and the G-buffer's size,
// holding what `output_fbo` would for a second lighting into it: its
// colour the options' `lit_clear_color` with `has_lit_clear`, else a copy
// of the lit first layer (never the host's last `glClearColor`); its depth
// the second layer's where `output_fbo`'s depth attachment is the
// G-buffer's depth (a lighting that depth-tests against it), else the
// host's clear depth (`glClearDepth`); its stencil
// `DMSAA_SECOND_LAYER_SELECTED` exactly where a pixel has a second layer
// (every pixel where no selection could be made). The host
// binds it where it would bind `output_fbo` for its second lighting,
// changing nothing else; with `glStencilFunc(GL_EQUAL,
// DMSAA_SECOND_LAYER_SELECTED, 0xFF)` and `glStencilMask(0)` it lights only
// the pixels the mix reads. It must not clear the stencil (nor a depth
// that is the second layer's). This is the
// route for a host lighting into the default framebuffer (0), to which no
// texture attaches, and one whose lighting keeps its depth test on. Then
// [`dmsaa_finish_second_layer`] with the same `output_fbo`. With one layer
// nothing is done and `*out_fbo` is 0.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: those of [`dmsaa_begin_second_layer`], with `out_fbo` for
// `run_lighting`; `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming the own
// target where the host's code deleted it (then [`dmsaa_refresh`]).
DmsaaStatus dmsaa_begin_second_layer_own_target(DmsaaRetrofit *retrofit,
                                                uint32_t output_fbo,
                                                uint32_t *out_fbo);

// MSAA for what the host draws forward after lighting (light cubes,
// transparent objects, particles): after the lighting (with two layers,
// after [`dmsaa_finish_second_layer`]), copy the lit image of
// `output_fbo` (its first draw buffer's image; 0 for the default
// framebuffer) into every sample of a multisampled colour target attached
// with the G-buffer's multisampled depth and stencil as the geometry pass
// drew them, and give that framebuffer in `*out_fbo`. The host binds it in
// place of `output_fbo`, draws its forward objects unchanged (depth test,
// blending, stencil as it likes), and calls [`dmsaa_finish_forward`].
// `output_fbo`'s own depth is not changed; what the forward objects write
// into depth goes into the multisampled depth, which the next geometry
// pass clears.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `out_fbo`;
// `DMSAA_STATUS_OUT_OF_ORDER` between the second layer's begin and finish
// or when already begun; `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` for an
// output of another size or without a colour draw buffer;
// `DMSAA_STATUS_LAYER_MIX_UNDECLARED` for a floating-point output with
// `DMSAA_LAYER_MIX_AUTO`; `DMSAA_STATUS_UNSUPPORTED`, `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_begin_forward(DmsaaRetrofit *retrofit, uint32_t output_fbo, uint32_t *out_fbo);

// After the host drew its forward objects into [`dmsaa_begin_forward`]'s
// framebuffer: average each pixel's samples into `output_fbo`'s lit image
// (the one given to begin), in the blend domain of the options'
// `layer_mix`; a pixel no forward object touched keeps its value bit for
// bit.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was, but for one binding: where the host left the
// forward target bound (draw, read or both), `output_fbo` is bound there
// instead, as if the host had drawn into it, so a read-back that follows
// (`glReadBuffer(GL_BACK)`, `glReadPixels`) reads the finished image.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
// `DMSAA_STATUS_OUT_OF_ORDER` without [`dmsaa_begin_forward`];
// `DMSAA_STATUS_INVALID_ARGUMENT` for another output than begin's;
// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming the forward target where
// the host's code deleted it (then [`dmsaa_refresh`]); `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_finish_forward(DmsaaRetrofit *retrofit, uint32_t output_fbo);

// After the host lit the second layer into `output_fbo` (the one given to
// [`dmsaa_begin_second_layer`]): mix the two lit layers into it by the
// second layer's coverage and put the first layer back into the host's
// G-buffer (as much of it as the options' `restore_first_layer` says),
// and `output_fbo`'s own depth and stencil (a depth attachment that is
// not the G-buffer's) as the first lighting left them.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was, but for one binding: where the host left
// [`dmsaa_begin_second_layer_own_target`]'s framebuffer bound, `output_fbo`
// is bound there instead, as if the host had lit into it.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
// `DMSAA_STATUS_OUT_OF_ORDER` without a [`dmsaa_begin_second_layer`] that
// returned `*run_lighting` true; `DMSAA_STATUS_INVALID_ARGUMENT` for
// another output than begin's or with one layer; `DMSAA_STATUS_GL`.
DmsaaStatus dmsaa_finish_second_layer(DmsaaRetrofit *retrofit, uint32_t output_fbo);

// Change the options. Only what they change is rebuilt; when the twins
// are, [`dmsaa_framebuffer`] returns the new multisampled framebuffer. On
// error the handle keeps working with the options it had. `options` is
// read during the call only.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit` or `options`;
// `DMSAA_STATUS_INVALID_ARGUMENT` for options out of range; those of
// [`dmsaa_retrofit_new`].
DmsaaStatus dmsaa_set_options(DmsaaRetrofit *retrofit, const DmsaaOptions *options);

// Re-read the host framebuffer after the host resized or re-allocated its
// G-buffer textures, and rebuild the twins (ask [`dmsaa_framebuffer`]
// again). On error the handle keeps working as before.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`; those of
// [`dmsaa_retrofit_new`].
DmsaaStatus dmsaa_refresh(DmsaaRetrofit *retrofit);

// [`dmsaa_refresh`] for a host that made its G-buffer anew under another
// framebuffer name (deleted the old framebuffer and generated a new one):
// the handle reads `host_fbo` from now on and rebuilds its twins, second
// layer and forward target for it, keeping its options (ask
// [`dmsaa_framebuffer`] again). On error the handle keeps working as
// before.
//
// Threading: the host's context current on the calling thread. The host's
// GL state is as it was.
// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
// `DMSAA_STATUS_INVALID_ARGUMENT` for `host_fbo` 0; those of
// [`dmsaa_retrofit_new`] for `host_fbo`.
DmsaaStatus dmsaa_refresh_with(DmsaaRetrofit *retrofit, uint32_t host_fbo);

// Free every GL object the handle made (never the host's) and the handle
// itself; `retrofit` is invalid afterwards. Null is accepted and does
// nothing. A handle that had an internal error is freed too.
//
// Threading: the host's context current on the calling thread.
void dmsaa_destroy(DmsaaRetrofit *retrofit);

// The message of the calling thread's last failed call: one line saying
// what went wrong and, where it can, what to do (shader build failures,
// which only a driver problem causes, add the driver's log on further
// lines). An empty string before any failure. Successful calls leave it
// as it was.
//
// Ownership: the library's; valid until the calling thread's next failed
// call. Threading: any thread; each has its own message.
const char *dmsaa_last_error(void);

// How many GL objects (textures, framebuffers, programs, shaders,
// buffers, vertex arrays, queries) the library has made and not yet freed
// on the calling thread, over every handle: 0 once every handle made on
// this thread is destroyed.
//
// Threading: any thread; counts that thread's objects.
int64_t dmsaa_live_objects(void);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* DEFERRED_MSAA_H */
