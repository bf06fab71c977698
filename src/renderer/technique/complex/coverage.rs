//! The G-buffer pass of [`AaMode::Complex`](crate::renderer::AaMode::Complex)
//! (`geometry_coverage.frag`): the unchanged model shader
//! `geometry.frag`, its `main()` renamed by a `#define` and called from a
//! wrapper that also writes each fragment's coverage flag
//! (`gl_SampleMaskIn` ≠ all samples) into an extra multisampled R8
//! attachment. Needs `gl_SampleMaskIn`: OpenGL 4.0's GLSL, reached from
//! GLSL 1.50 through `GL_ARB_gpu_shader5` (or `GL_ARB_sample_shading`).

use crate::gl::Capabilities;
use crate::renderer::pass::geometry::GeometryPass;
use crate::renderer::pass::geometry::model_wrapped;
use crate::renderer::pass::slots::GBufferSlots;
use glow::HasContext;

/// The wrapper's body (compiled after `geometry.frag` with `main` renamed).
pub(crate) const GEOMETRY_COVERAGE_FRAG: &str = include_str!("geometry_coverage.frag");

/// The extensions, in order of preference, that can give a GLSL 1.50
/// shader `gl_SampleMaskIn`.
const EXTENSIONS: &[&str] = &["GL_ARB_gpu_shader5", "GL_ARB_sample_shading"];

/// The model program wrapped to record coverage, and where the flag goes.
#[derive(Debug)]
pub(crate) struct CoverageGeometryPass {
    pass: GeometryPass,
    coverage_slot: u32,
}

impl CoverageGeometryPass {
    /// Build the wrapped model program with its outputs at `slots` and
    /// `o_coverage` on draw buffer `coverage_slot`. `Err` carries why the
    /// context cannot record coverage (no `gl_SampleMaskIn`, no free draw
    /// buffer, or the driver refused the shader), in one line.
    pub(crate) fn new(
        gl: &glow::Context,
        slots: GBufferSlots,
        coverage_slot: u32,
    ) -> std::result::Result<Self, String> {
        let caps = Capabilities::query(gl);
        if !caps.sample_mask_in {
            return Err(format!(
                "the context (OpenGL {}.{}) has no gl_SampleMaskIn (OpenGL 4.0, GL_ARB_gpu_shader5 or GL_ARB_sample_shading)",
                caps.version.0, caps.version.1
            ));
        }
        let limit = caps.max_draw_buffers.min(caps.max_color_attachments);
        if coverage_slot >= limit {
            return Err(format!(
                "no draw buffer is free for the coverage flags (the G-buffer uses {coverage_slot} of {limit})"
            ));
        }
        let available = gl.supported_extensions();
        let extensions: Vec<&str> = EXTENSIONS
            .iter()
            .copied()
            .filter(|e| available.contains(*e))
            .collect();
        if extensions.is_empty() {
            return Err(format!(
                "GLSL 1.50 reaches gl_SampleMaskIn only through {}, which the context does not list",
                EXTENSIONS.join(" or ")
            ));
        }
        let fragment = model_wrapped(
            GeometryPass::header(slots, &extensions),
            &[("geometry_coverage.frag", GEOMETRY_COVERAGE_FRAG)],
        );
        GeometryPass::with_fragment_source(
            gl,
            "geometry + coverage",
            slots,
            &fragment,
            &[("o_coverage", coverage_slot)],
        )
        .map(|pass| CoverageGeometryPass {
            pass,
            coverage_slot,
        })
        .map_err(|e| {
            format!(
                "the coverage-recording model shader did not build: {}",
                e.to_string().replace('\n', " ")
            )
        })
    }

    /// The wrapped model program, with `u_full_mask` set for `samples` per
    /// pixel; draw it like [`GeometryPass`].
    pub(crate) fn prepare(&self, gl: &glow::Context, samples: u32) -> &GeometryPass {
        let full = if samples >= 32 {
            -1
        } else {
            ((1u32 << samples) - 1) as i32
        };
        let p = self.pass.program();
        p.bind(gl);
        p.set_i32(gl, "u_full_mask", full);
        unsafe { gl.use_program(None) };
        &self.pass
    }

    /// The draw buffer (and colour attachment) of the coverage flags.
    pub(crate) fn coverage_slot(&self) -> u32 {
        self.coverage_slot
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.pass.destroy(gl);
    }
}
