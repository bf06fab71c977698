//! The GL state a host keeps across the retrofit's calls: a snapshot by
//! name (bindings of every texture unit, framebuffers, buffers, program,
//! pixel store, depth, stencil, blend, capabilities, viewport, scissor,
//! masks, clear values, and per draw buffer the blend enable and the colour
//! mask, and with viewport arrays every viewport, scissor box and scissor
//! test), taken before and after a call and compared. The zoo, the
//! property test and the misuse fuzzer read the same list.
//!
//! Two values GL hides are read around the hiding: the per-buffer colour
//! mask through `glGetBooleani_v`, which glow does not wrap (loaded by
//! [`load`], which `common::context` calls), and the stencil references,
//! which a query clamps to the bound draw framebuffer's stencil bits (0 on
//! a surfaceless default framebuffer): they are read again with a
//! framebuffer of an 8-bit stencil bound, made for the read and deleted.

use glow::HasContext;
use std::ffi::c_void;
use std::sync::atomic::{AtomicPtr, Ordering};

type IsEnabledi = unsafe extern "system" fn(target: u32, index: u32) -> u8;
type GetBooleaniV = unsafe extern "system" fn(target: u32, index: u32, data: *mut u8);

type GetFloatiV = unsafe extern "system" fn(target: u32, index: u32, data: *mut f32);
type GetIntegeriV = unsafe extern "system" fn(target: u32, index: u32, data: *mut i32);

static IS_ENABLEDI: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_BOOLEANI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_FLOATI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_INTEGERI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());

/// Load the snapshot's own `glIsEnabledi` and `glGetBooleani_v` (not the
/// crate's, which it checks).
pub fn load(mut loader: impl FnMut(&str) -> *const c_void) {
    IS_ENABLEDI.store(loader("glIsEnabledi").cast_mut(), Ordering::Release);
    GET_BOOLEANI_V.store(loader("glGetBooleani_v").cast_mut(), Ordering::Release);
    GET_FLOATI_V.store(loader("glGetFloati_v").cast_mut(), Ordering::Release);
    GET_INTEGERI_V.store(loader("glGetIntegeri_v").cast_mut(), Ordering::Release);
}

/// Whether the context has viewport arrays (GL 4.1 or
/// `GL_ARB_viewport_array`).
pub fn has_viewport_arrays(gl: &glow::Context) -> bool {
    let v = gl.version();
    (v.major, v.minor) >= (4, 1) || gl.supported_extensions().contains("GL_ARB_viewport_array")
}

/// Every viewport, scissor box and scissor test by index, with viewport
/// arrays.
fn viewport_arrays(gl: &glow::Context, out: &mut Vec<(String, Vec<i64>)>) {
    if !has_viewport_arrays(gl) {
        return;
    }
    let (floats, ints) = (
        GET_FLOATI_V.load(Ordering::Acquire),
        GET_INTEGERI_V.load(Ordering::Acquire),
    );
    assert!(
        !floats.is_null() && !ints.is_null(),
        "gl_state::load was not called"
    );
    // SAFETY: non-null pointers the context's loader gave for these names;
    // each query writes four values.
    let (get_floati_v, get_integeri_v) = unsafe {
        (
            std::mem::transmute::<*mut c_void, GetFloatiV>(floats),
            std::mem::transmute::<*mut c_void, GetIntegeriV>(ints),
        )
    };
    let (is_enabledi, _) = indexed();
    unsafe {
        let count = gl.get_parameter_i32(glow::MAX_VIEWPORTS).clamp(1, 64) as u32;
        for i in 0..count {
            let mut v = [0f32; 4];
            get_floati_v(glow::VIEWPORT, i, v.as_mut_ptr());
            out.push((
                format!("GL_VIEWPORT {i}"),
                v.map(|x| i64::from(x.to_bits())).to_vec(),
            ));
            let mut b = [0i32; 4];
            get_integeri_v(glow::SCISSOR_BOX, i, b.as_mut_ptr());
            out.push((format!("GL_SCISSOR_BOX {i}"), b.map(i64::from).to_vec()));
            out.push((
                format!("GL_SCISSOR_TEST {i}"),
                vec![i64::from(is_enabledi(glow::SCISSOR_TEST, i))],
            ));
        }
    }
}

fn indexed() -> (IsEnabledi, GetBooleaniV) {
    let (a, b) = (
        IS_ENABLEDI.load(Ordering::Acquire),
        GET_BOOLEANI_V.load(Ordering::Acquire),
    );
    assert!(
        !a.is_null() && !b.is_null(),
        "gl_state::load was not called (common::context calls it)"
    );
    // SAFETY: non-null pointers the context's loader gave for these names.
    unsafe {
        (
            std::mem::transmute::<*mut c_void, IsEnabledi>(a),
            std::mem::transmute::<*mut c_void, GetBooleaniV>(b),
        )
    }
}

/// The front and back stencil references, read with a framebuffer of an
/// 8-bit stencil bound (and every binding it changes put back).
fn stencil_references(gl: &glow::Context) -> Vec<i64> {
    unsafe {
        let draw = gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) as u32;
        let renderbuffer = gl.get_parameter_i32(glow::RENDERBUFFER_BINDING) as u32;
        let rb = gl.create_renderbuffer().expect("a probe renderbuffer");
        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
        gl.renderbuffer_storage(glow::RENDERBUFFER, glow::DEPTH24_STENCIL8, 1, 1);
        let fbo = gl.create_framebuffer().expect("a probe framebuffer");
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(fbo));
        gl.framebuffer_renderbuffer(
            glow::DRAW_FRAMEBUFFER,
            glow::DEPTH_STENCIL_ATTACHMENT,
            glow::RENDERBUFFER,
            Some(rb),
        );
        let refs = vec![
            gl.get_parameter_i32(glow::STENCIL_REF) as i64,
            gl.get_parameter_i32(glow::STENCIL_BACK_REF) as i64,
        ];
        gl.bind_framebuffer(
            glow::DRAW_FRAMEBUFFER,
            std::num::NonZeroU32::new(draw).map(glow::NativeFramebuffer),
        );
        gl.bind_renderbuffer(
            glow::RENDERBUFFER,
            std::num::NonZeroU32::new(renderbuffer).map(glow::NativeRenderbuffer),
        );
        gl.delete_framebuffer(fbo);
        gl.delete_renderbuffer(rb);
        refs
    }
}

/// The host state the retrofit's calls must leave as they found it, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct GlState(Vec<(String, Vec<i64>)>);

impl GlState {
    /// Read it (every texture unit is walked, and the active one put back).
    pub fn capture(gl: &glow::Context) -> GlState {
        let mut s: Vec<(String, Vec<i64>)> = Vec::new();
        unsafe {
            let int = |e: u32| vec![gl.get_parameter_i32(e) as i64];
            let ints = |e: u32, n: usize| {
                let mut v = vec![0i32; n];
                gl.get_parameter_i32_slice(e, &mut v);
                v.into_iter().map(i64::from).collect::<Vec<_>>()
            };
            let floats = |e: u32, n: usize| {
                let mut v = vec![0f32; n];
                gl.get_parameter_f32_slice(e, &mut v);
                v.into_iter()
                    .map(|x| x.to_bits() as i64)
                    .collect::<Vec<_>>()
            };
            let on = |e: u32| vec![gl.is_enabled(e) as i64];
            let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE);
            let units = gl
                .get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS)
                .clamp(1, 32) as u32;
            for unit in 0..units {
                gl.active_texture(glow::TEXTURE0 + unit);
                for (name, e) in [
                    ("2D", glow::TEXTURE_BINDING_2D),
                    ("2D_ARRAY", glow::TEXTURE_BINDING_2D_ARRAY),
                    ("2D_MULTISAMPLE", glow::TEXTURE_BINDING_2D_MULTISAMPLE),
                    ("CUBE_MAP", glow::TEXTURE_BINDING_CUBE_MAP),
                    ("RECTANGLE", glow::TEXTURE_BINDING_RECTANGLE),
                    ("3D", glow::TEXTURE_BINDING_3D),
                ] {
                    s.push((format!("GL_TEXTURE_BINDING_{name} of unit {unit}"), int(e)));
                }
            }
            gl.active_texture(active as u32);
            s.push(("GL_ACTIVE_TEXTURE".into(), vec![active as i64]));
            for (name, e) in [
                (
                    "GL_DRAW_FRAMEBUFFER_BINDING",
                    glow::DRAW_FRAMEBUFFER_BINDING,
                ),
                (
                    "GL_READ_FRAMEBUFFER_BINDING",
                    glow::READ_FRAMEBUFFER_BINDING,
                ),
                ("GL_RENDERBUFFER_BINDING", glow::RENDERBUFFER_BINDING),
                ("GL_CURRENT_PROGRAM", glow::CURRENT_PROGRAM),
                ("GL_VERTEX_ARRAY_BINDING", glow::VERTEX_ARRAY_BINDING),
                ("GL_ARRAY_BUFFER_BINDING", glow::ARRAY_BUFFER_BINDING),
                (
                    "GL_PIXEL_PACK_BUFFER_BINDING",
                    glow::PIXEL_PACK_BUFFER_BINDING,
                ),
                (
                    "GL_PIXEL_UNPACK_BUFFER_BINDING",
                    glow::PIXEL_UNPACK_BUFFER_BINDING,
                ),
                ("GL_UNIFORM_BUFFER_BINDING", glow::UNIFORM_BUFFER_BINDING),
                ("GL_PACK_ALIGNMENT", glow::PACK_ALIGNMENT),
                ("GL_UNPACK_ALIGNMENT", glow::UNPACK_ALIGNMENT),
                ("GL_PACK_ROW_LENGTH", glow::PACK_ROW_LENGTH),
                ("GL_UNPACK_ROW_LENGTH", glow::UNPACK_ROW_LENGTH),
                ("GL_DEPTH_FUNC", glow::DEPTH_FUNC),
                ("GL_DEPTH_WRITEMASK", glow::DEPTH_WRITEMASK),
                ("GL_STENCIL_FUNC", glow::STENCIL_FUNC),
                ("GL_STENCIL_REF", glow::STENCIL_REF),
                ("GL_STENCIL_VALUE_MASK", glow::STENCIL_VALUE_MASK),
                ("GL_STENCIL_FAIL", glow::STENCIL_FAIL),
                ("GL_STENCIL_PASS_DEPTH_FAIL", glow::STENCIL_PASS_DEPTH_FAIL),
                ("GL_STENCIL_PASS_DEPTH_PASS", glow::STENCIL_PASS_DEPTH_PASS),
                ("GL_STENCIL_WRITEMASK", glow::STENCIL_WRITEMASK),
                ("GL_STENCIL_BACK_FUNC", glow::STENCIL_BACK_FUNC),
                ("GL_STENCIL_BACK_REF", glow::STENCIL_BACK_REF),
                ("GL_STENCIL_BACK_WRITEMASK", glow::STENCIL_BACK_WRITEMASK),
                ("GL_BLEND_SRC_RGB", glow::BLEND_SRC_RGB),
                ("GL_BLEND_DST_RGB", glow::BLEND_DST_RGB),
                ("GL_BLEND_SRC_ALPHA", glow::BLEND_SRC_ALPHA),
                ("GL_BLEND_DST_ALPHA", glow::BLEND_DST_ALPHA),
                ("GL_BLEND_EQUATION_RGB", glow::BLEND_EQUATION_RGB),
                ("GL_BLEND_EQUATION_ALPHA", glow::BLEND_EQUATION_ALPHA),
                ("GL_CULL_FACE_MODE", glow::CULL_FACE_MODE),
                ("GL_FRONT_FACE", glow::FRONT_FACE),
                ("GL_STENCIL_CLEAR_VALUE", glow::STENCIL_CLEAR_VALUE),
                ("GL_READ_BUFFER", glow::READ_BUFFER),
            ] {
                s.push((name.into(), int(e)));
            }
            let max_draw = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(1, 32) as u32;
            for i in 0..max_draw {
                s.push((format!("GL_DRAW_BUFFER{i}"), int(glow::DRAW_BUFFER0 + i)));
            }
            for (name, e) in [
                ("GL_DEPTH_TEST", glow::DEPTH_TEST),
                ("GL_STENCIL_TEST", glow::STENCIL_TEST),
                ("GL_BLEND", glow::BLEND),
                ("GL_CULL_FACE", glow::CULL_FACE),
                ("GL_SCISSOR_TEST", glow::SCISSOR_TEST),
                ("GL_FRAMEBUFFER_SRGB", glow::FRAMEBUFFER_SRGB),
                ("GL_SAMPLE_MASK", glow::SAMPLE_MASK),
                (
                    "GL_SAMPLE_ALPHA_TO_COVERAGE",
                    glow::SAMPLE_ALPHA_TO_COVERAGE,
                ),
                ("GL_RASTERIZER_DISCARD", glow::RASTERIZER_DISCARD),
                ("GL_MULTISAMPLE", glow::MULTISAMPLE),
                ("GL_POLYGON_OFFSET_FILL", glow::POLYGON_OFFSET_FILL),
                ("GL_COLOR_LOGIC_OP", glow::COLOR_LOGIC_OP),
                ("GL_CLIP_DISTANCE0", glow::CLIP_DISTANCE0),
                ("GL_DITHER", glow::DITHER),
            ] {
                s.push((name.into(), on(e)));
            }
            s.push(("GL_VIEWPORT".into(), ints(glow::VIEWPORT, 4)));
            s.push(("GL_SCISSOR_BOX".into(), ints(glow::SCISSOR_BOX, 4)));
            s.push(("GL_POLYGON_MODE".into(), ints(glow::POLYGON_MODE, 2)));
            s.push(("GL_COLOR_WRITEMASK".into(), ints(glow::COLOR_WRITEMASK, 4)));
            s.push((
                "GL_COLOR_CLEAR_VALUE".into(),
                floats(glow::COLOR_CLEAR_VALUE, 4),
            ));
            s.push((
                "GL_DEPTH_CLEAR_VALUE".into(),
                floats(glow::DEPTH_CLEAR_VALUE, 1),
            ));
            s.push(("GL_BLEND_COLOR".into(), floats(glow::BLEND_COLOR, 4)));
            s.push((
                "GL_SAMPLE_MASK_VALUE".into(),
                vec![gl.get_parameter_indexed_i32(glow::SAMPLE_MASK_VALUE, 0) as i64],
            ));
            let (is_enabledi, get_booleani_v) = indexed();
            for i in 0..max_draw {
                s.push((
                    format!("GL_BLEND of draw buffer {i}"),
                    vec![i64::from(is_enabledi(glow::BLEND, i))],
                ));
                let mut mask = [0u8; 4];
                get_booleani_v(glow::COLOR_WRITEMASK, i, mask.as_mut_ptr());
                s.push((
                    format!("GL_COLOR_WRITEMASK of draw buffer {i}"),
                    mask.map(i64::from).to_vec(),
                ));
            }
            s.push((
                "GL_STENCIL_REF and GL_STENCIL_BACK_REF through an 8-bit stencil".into(),
                stencil_references(gl),
            ));
            viewport_arrays(gl, &mut s);
            for (name, e) in [
                ("GL_STENCIL_BACK_VALUE_MASK", glow::STENCIL_BACK_VALUE_MASK),
                ("GL_STENCIL_BACK_FAIL", glow::STENCIL_BACK_FAIL),
                (
                    "GL_STENCIL_BACK_PASS_DEPTH_FAIL",
                    glow::STENCIL_BACK_PASS_DEPTH_FAIL,
                ),
                (
                    "GL_STENCIL_BACK_PASS_DEPTH_PASS",
                    glow::STENCIL_BACK_PASS_DEPTH_PASS,
                ),
            ] {
                s.push((name.into(), int(e)));
            }
        }
        GlState(s)
    }

    /// `"NAME: before -> after"` for each difference.
    pub fn differences(&self, after: &GlState) -> Vec<String> {
        self.0
            .iter()
            .zip(&after.0)
            .filter(|(a, b)| a.1 != b.1)
            .map(|(a, b)| format!("{}: {:?} -> {:?}", a.0, a.1, b.1))
            .collect()
    }
}
