//! The `--check` mode: the GL state a program keeps, read before and after
//! every call into the library and compared, and the GL errors each call
//! leaves, counted for the summary printed at exit.

use glow::HasContext;
use std::collections::BTreeMap;
use std::sync::Mutex;

/// A named GL state value (several numbers for a vector).
pub(crate) type Value = (String, Vec<f64>);

/// What the checks found over the run.
#[derive(Default)]
pub(crate) struct Totals {
    /// Calls into the library that were checked.
    pub(crate) calls: u64,
    /// State values compared around each call (the last snapshot's).
    pub(crate) values: usize,
    /// Values that differed after a call.
    pub(crate) changed: u64,
    /// GL errors a call left.
    pub(crate) errors: u64,
    /// GL errors the program left pending before a call (read, and so
    /// cleared, by the check).
    pub(crate) program_errors: u64,
    /// How many times each call was made.
    pub(crate) by_call: BTreeMap<String, u64>,
}

/// The run's totals.
pub(crate) static TOTALS: Mutex<Totals> = Mutex::new(Totals {
    calls: 0,
    values: 0,
    changed: 0,
    errors: 0,
    program_errors: 0,
    by_call: BTreeMap::new(),
});

const INTEGERS: &[(&str, u32)] = &[
    ("DRAW_FRAMEBUFFER_BINDING", glow::DRAW_FRAMEBUFFER_BINDING),
    ("READ_FRAMEBUFFER_BINDING", glow::READ_FRAMEBUFFER_BINDING),
    ("RENDERBUFFER_BINDING", glow::RENDERBUFFER_BINDING),
    ("CURRENT_PROGRAM", glow::CURRENT_PROGRAM),
    ("VERTEX_ARRAY_BINDING", glow::VERTEX_ARRAY_BINDING),
    ("ARRAY_BUFFER_BINDING", glow::ARRAY_BUFFER_BINDING),
    (
        "ELEMENT_ARRAY_BUFFER_BINDING",
        glow::ELEMENT_ARRAY_BUFFER_BINDING,
    ),
    ("UNIFORM_BUFFER_BINDING", glow::UNIFORM_BUFFER_BINDING),
    ("PIXEL_PACK_BUFFER_BINDING", glow::PIXEL_PACK_BUFFER_BINDING),
    (
        "PIXEL_UNPACK_BUFFER_BINDING",
        glow::PIXEL_UNPACK_BUFFER_BINDING,
    ),
    ("ACTIVE_TEXTURE", glow::ACTIVE_TEXTURE),
    ("DEPTH_FUNC", glow::DEPTH_FUNC),
    ("DEPTH_WRITEMASK", glow::DEPTH_WRITEMASK),
    ("STENCIL_FUNC", glow::STENCIL_FUNC),
    ("STENCIL_REF", glow::STENCIL_REF),
    ("STENCIL_VALUE_MASK", glow::STENCIL_VALUE_MASK),
    ("STENCIL_WRITEMASK", glow::STENCIL_WRITEMASK),
    ("STENCIL_FAIL", glow::STENCIL_FAIL),
    ("STENCIL_PASS_DEPTH_FAIL", glow::STENCIL_PASS_DEPTH_FAIL),
    ("STENCIL_PASS_DEPTH_PASS", glow::STENCIL_PASS_DEPTH_PASS),
    ("STENCIL_BACK_FUNC", glow::STENCIL_BACK_FUNC),
    ("STENCIL_BACK_WRITEMASK", glow::STENCIL_BACK_WRITEMASK),
    ("CLEAR_STENCIL", glow::STENCIL_CLEAR_VALUE),
    ("BLEND_SRC_RGB", glow::BLEND_SRC_RGB),
    ("BLEND_DST_RGB", glow::BLEND_DST_RGB),
    ("BLEND_SRC_ALPHA", glow::BLEND_SRC_ALPHA),
    ("BLEND_DST_ALPHA", glow::BLEND_DST_ALPHA),
    ("BLEND_EQUATION_RGB", glow::BLEND_EQUATION_RGB),
    ("BLEND_EQUATION_ALPHA", glow::BLEND_EQUATION_ALPHA),
    ("CULL_FACE_MODE", glow::CULL_FACE_MODE),
    ("FRONT_FACE", glow::FRONT_FACE),
    ("PACK_ALIGNMENT", glow::PACK_ALIGNMENT),
    ("UNPACK_ALIGNMENT", glow::UNPACK_ALIGNMENT),
    ("PACK_ROW_LENGTH", glow::PACK_ROW_LENGTH),
    ("UNPACK_ROW_LENGTH", glow::UNPACK_ROW_LENGTH),
    ("DRAW_BUFFER0", glow::DRAW_BUFFER0),
    ("DRAW_BUFFER1", glow::DRAW_BUFFER1),
    ("READ_BUFFER", glow::READ_BUFFER),
];

const CAPABILITIES: &[(&str, u32)] = &[
    ("DEPTH_TEST", glow::DEPTH_TEST),
    ("STENCIL_TEST", glow::STENCIL_TEST),
    ("BLEND", glow::BLEND),
    ("CULL_FACE", glow::CULL_FACE),
    ("SCISSOR_TEST", glow::SCISSOR_TEST),
    ("FRAMEBUFFER_SRGB", glow::FRAMEBUFFER_SRGB),
    ("MULTISAMPLE", glow::MULTISAMPLE),
    ("SAMPLE_ALPHA_TO_COVERAGE", glow::SAMPLE_ALPHA_TO_COVERAGE),
    ("SAMPLE_COVERAGE", glow::SAMPLE_COVERAGE),
    ("POLYGON_OFFSET_FILL", glow::POLYGON_OFFSET_FILL),
    ("RASTERIZER_DISCARD", glow::RASTERIZER_DISCARD),
    ("DITHER", glow::DITHER),
    ("PRIMITIVE_RESTART", glow::PRIMITIVE_RESTART),
    ("DEPTH_CLAMP", glow::DEPTH_CLAMP),
    ("PROGRAM_POINT_SIZE", glow::PROGRAM_POINT_SIZE),
];

const INTEGER_VECTORS: &[(&str, u32, usize)] = &[
    ("VIEWPORT", glow::VIEWPORT, 4),
    ("SCISSOR_BOX", glow::SCISSOR_BOX, 4),
];

const FLOAT_VECTORS: &[(&str, u32, usize)] = &[
    ("COLOR_CLEAR_VALUE", glow::COLOR_CLEAR_VALUE, 4),
    ("DEPTH_CLEAR_VALUE", glow::DEPTH_CLEAR_VALUE, 1),
    ("DEPTH_RANGE", glow::DEPTH_RANGE, 2),
    ("BLEND_COLOR", glow::BLEND_COLOR, 4),
    ("POLYGON_OFFSET_FACTOR", glow::POLYGON_OFFSET_FACTOR, 1),
    ("POLYGON_OFFSET_UNITS", glow::POLYGON_OFFSET_UNITS, 1),
];

/// Texture units whose 2D and cube-map bindings are read.
const TEXTURE_UNITS: u32 = 16;

/// The state values, by name. Reads the bindings of every texture unit by
/// switching the active unit, and puts it back.
pub(crate) fn snapshot(gl: &glow::Context) -> Vec<Value> {
    let mut out = Vec::with_capacity(128);
    // SAFETY: queries of the current context with enums it knows (the
    // unit switch is put back before returning).
    unsafe {
        // GL clamps the stencil reference it reports to the stencil bits of
        // the draw framebuffer, which a driver may learn only when it next
        // validates the framebuffer (Mesa: at a draw or a read): asked
        // first, so that a bind of a framebuffer with stencil before the
        // call does not read as the call changing the reference.
        gl.check_framebuffer_status(glow::DRAW_FRAMEBUFFER);
        gl.check_framebuffer_status(glow::READ_FRAMEBUFFER);
        for &(name, pname) in INTEGERS {
            out.push((
                name.to_string(),
                vec![f64::from(gl.get_parameter_i32(pname))],
            ));
        }
        for &(name, cap) in CAPABILITIES {
            out.push((
                name.to_string(),
                vec![f64::from(u8::from(gl.is_enabled(cap)))],
            ));
        }
        for &(name, pname, n) in INTEGER_VECTORS {
            let mut v = [0i32; 4];
            gl.get_parameter_i32_slice(pname, &mut v[..n]);
            out.push((
                name.to_string(),
                v[..n].iter().map(|&x| f64::from(x)).collect(),
            ));
        }
        for &(name, pname, n) in FLOAT_VECTORS {
            let mut v = [0f32; 4];
            gl.get_parameter_f32_slice(pname, &mut v[..n]);
            out.push((
                name.to_string(),
                v[..n].iter().map(|&x| f64::from(x)).collect(),
            ));
        }
        let mask: [bool; 4] = gl.get_parameter_bool_array(glow::COLOR_WRITEMASK);
        out.push((
            "COLOR_WRITEMASK".to_string(),
            mask.iter().map(|&b| f64::from(u8::from(b))).collect(),
        ));
        let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
        let units = (gl.get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS) as u32)
            .min(TEXTURE_UNITS);
        for unit in 0..units {
            gl.active_texture(glow::TEXTURE0 + unit);
            for (kind, pname) in [
                ("TEXTURE_BINDING_2D", glow::TEXTURE_BINDING_2D),
                ("TEXTURE_BINDING_CUBE_MAP", glow::TEXTURE_BINDING_CUBE_MAP),
            ] {
                out.push((
                    format!("{kind}[{unit}]"),
                    vec![f64::from(gl.get_parameter_i32(pname))],
                ));
            }
        }
        gl.active_texture(active);
    }
    out
}

/// Every GL error pending, drained.
pub(crate) fn drain_errors(gl: &glow::Context) -> Vec<u32> {
    let mut errors = Vec::new();
    // SAFETY: glGetError on the current context; bounded, as a lost
    // context can return an error for ever.
    unsafe {
        for _ in 0..16 {
            match gl.get_error() {
                glow::NO_ERROR => break,
                e => errors.push(e),
            }
        }
    }
    errors
}

/// The values that differ between two snapshots, as `name: before -> after`.
pub(crate) fn differences(before: &[Value], after: &[Value]) -> Vec<String> {
    before
        .iter()
        .zip(after)
        .filter(|(b, a)| b.1 != a.1)
        .map(|(b, a)| format!("{}: {:?} -> {:?}", b.0, b.1, a.1))
        .collect()
}
