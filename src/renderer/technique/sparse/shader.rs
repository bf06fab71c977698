//! What every sparse pass shares: the layout of heads and blocks
//! (`sparse.frag`), the extensions the passes are compiled with, the most
//! samples the lighting sums, and the region uniforms.

use crate::gl::Program;
use crate::resolve::Region;

/// The layout of heads and blocks and the region test, compiled in front
/// of every sparse pass (`sparse.frag`).
pub(crate) const SPARSE_FRAG: &str = include_str!("sparse.frag");

/// The most samples per pixel the lighting pass sums (a `uint` mask of
/// sample indices; 32 samples of 24-bit fixed point fit a `uint`).
pub(crate) const MAX_SAMPLES: u32 = 32;

/// The extensions every sparse pass is compiled with, in this order.
pub(crate) const EXTENSIONS: &[&str] = &[
    "GL_ARB_shader_storage_buffer_object",
    "GL_ARB_shader_atomic_counters",
    "GL_ARB_gpu_shader5",
    "GL_ARB_shading_language_packing",
    "GL_ARB_shading_language_420pack",
    "GL_ARB_shader_image_load_store",
    "GL_ARB_post_depth_coverage",
];

/// Set a sparse program's region uniforms (the program must be bound).
/// Outside the region every pixel shows its sample 0; `None` is everywhere.
pub(crate) fn apply_region(
    gl: &glow::Context,
    program: &Program,
    region: &Option<Region>,
    height: u32,
) {
    // SPARSE_REGION_* in sparse.frag; the numbers are the resolve's own.
    let (kind, values) = match region {
        None => (0, [0.0; 4]),
        Some(r @ Region::Rect { .. }) => (2, r.window_uniform(height)),
        Some(r @ Region::Ellipse { .. }) => (3, r.window_uniform(height)),
    };
    program.set_i32(gl, "u_region_kind", kind);
    program.set_vec4(gl, "u_region", values.map(|v| v as f32));
}
