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
use deferred_msaa::{Error, FirstLayerRestore, Frame, RetrofitOptions};
use std::ffi::{CString, c_char, c_void};
use std::num::NonZeroU32;

mod call;
mod convert;
mod types;

use call::{Failure, LAST_ERROR, entry, with_handle};
use convert::*;
pub use types::*;

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
        has_lit_clear: 0,
        lit_clear_color: [0.0; 4],
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

/// The start of a frame, required before each frame's geometry pass: check
/// that the multisampled framebuffer and its textures still exist
/// (something that deletes them, such as a render-target wrapper deleting
/// what it wraps, makes every later frame stale), prepare the twins, and
/// give [`dmsaa_framebuffer`]'s framebuffer in `*out_fbo`, to bind for the
/// geometry pass. With `clear_twins` 1 the twins are cleared to the
/// options' `clear_*` values; with 0 their depth is cleared to a sentinel
/// that the host's own clear of `*out_fbo` replaces, and [`dmsaa_resolve`]
/// returns `DMSAA_STATUS_TWINS_NOT_CLEARED` for a frame in which much of
/// it is left.
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
/// [`dmsaa_begin_second_layer`] and [`dmsaa_finish_second_layer`], or
/// without [`dmsaa_begin_frame`] since the last resolve;
/// `DMSAA_STATUS_TWINS_NOT_CLEARED` where nothing cleared the twins after
/// `dmsaa_begin_frame`;
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
/// changed since it was read, as for [`dmsaa_resolve`];
/// `DMSAA_STATUS_LAYER_MIX_UNDECLARED` for a floating-point output with
/// `DMSAA_LAYER_MIX_AUTO` (declare the output's tonemap); `DMSAA_STATUS_GL`.
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
/// holding what `output_fbo` would for a second lighting into it: its
/// colour the options' `lit_clear_color` with `has_lit_clear`, else a copy
/// of the lit first layer (never the host's last `glClearColor`); its depth
/// the second layer's where `output_fbo`'s depth attachment is the
/// G-buffer's depth (a lighting that depth-tests against it), else the
/// host's clear depth (`glClearDepth`); its stencil
/// `DMSAA_SECOND_LAYER_SELECTED` exactly where a pixel has a second layer
/// (every pixel where no selection could be made). The host
/// binds it where it would bind `output_fbo` for its second lighting,
/// changing nothing else; with `glStencilFunc(GL_EQUAL,
/// DMSAA_SECOND_LAYER_SELECTED, 0xFF)` and `glStencilMask(0)` it lights only
/// the pixels the mix reads. It must not clear the stencil (nor a depth
/// that is the second layer's). This is the
/// route for a host lighting into the default framebuffer (0), to which no
/// texture attaches, and one whose lighting keeps its depth test on. Then
/// [`dmsaa_finish_second_layer`] with the same `output_fbo`. With one layer
/// nothing is done and `*out_fbo` is 0.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: those of [`dmsaa_begin_second_layer`], with `out_fbo` for
/// `run_lighting`; `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming the own
/// target where the host's code deleted it (then [`dmsaa_refresh`]).
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
/// `DMSAA_STATUS_LAYER_MIX_UNDECLARED` for a floating-point output with
/// `DMSAA_LAYER_MIX_AUTO`; `DMSAA_STATUS_UNSUPPORTED`, `DMSAA_STATUS_GL`.
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
/// GL state is as it was, but for one binding: where the host left the
/// forward target bound (draw, read or both), `output_fbo` is bound there
/// instead, as if the host had drawn into it, so a read-back that follows
/// (`glReadBuffer(GL_BACK)`, `glReadPixels`) reads the finished image.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
/// `DMSAA_STATUS_OUT_OF_ORDER` without [`dmsaa_begin_forward`];
/// `DMSAA_STATUS_INVALID_ARGUMENT` for another output than begin's;
/// `DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER` naming the forward target where
/// the host's code deleted it (then [`dmsaa_refresh`]); `DMSAA_STATUS_GL`.
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
/// G-buffer (as much of it as the options' `restore_first_layer` says),
/// and `output_fbo`'s own depth and stencil (a depth attachment that is
/// not the G-buffer's) as the first lighting left them.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was, but for one binding: where the host left
/// [`dmsaa_begin_second_layer_own_target`]'s framebuffer bound, `output_fbo`
/// is bound there instead, as if the host had lit into it.
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

/// [`dmsaa_refresh`] for a host that made its G-buffer anew under another
/// framebuffer name (deleted the old framebuffer and generated a new one):
/// the handle reads `host_fbo` from now on and rebuilds its twins, second
/// layer and forward target for it, keeping its options (ask
/// [`dmsaa_framebuffer`] again). On error the handle keeps working as
/// before.
///
/// Threading: the host's context current on the calling thread. The host's
/// GL state is as it was.
/// Errors: `DMSAA_STATUS_NULL_POINTER` for a null `retrofit`;
/// `DMSAA_STATUS_INVALID_ARGUMENT` for `host_fbo` 0; those of
/// [`dmsaa_retrofit_new`] for `host_fbo`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dmsaa_refresh_with(
    retrofit: *mut DmsaaRetrofit,
    host_fbo: u32,
) -> DmsaaStatus {
    const F: &str = "dmsaa_refresh_with";
    entry(F, || {
        let Some(fbo) = NonZeroU32::new(host_fbo) else {
            return Err(Failure::invalid(format!(
                "{F}: host_fbo is 0, the default framebuffer, which has no G-buffer textures to \
                 retrofit: pass the G-buffer framebuffer the geometry pass draws into"
            )));
        };
        with_handle(F, retrofit, |h| {
            h.msaa.refresh_with(fbo)?;
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
    use deferred_msaa::gbuffer::MemoryBudget;
    use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
    use deferred_msaa::{ColorAttachment, DepthMode, LayerMix, NormalAttachment, PositionSpace};
    use std::ffi::CStr;

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
