//! The complex-pixel detection pass (`complex_mask.frag`) of
//! [`AaMode::Complex`](crate::renderer::AaMode::Complex): a full-screen pass over the
//! multisampled G-buffer that writes 1 into the stencil buffer of the HDR
//! target for every complex pixel (a triangle edge crosses it, per the
//! coverage flags the G-buffer pass recorded with `gl_SampleMaskIn`, or its
//! samples differ in background, depth, normal or base colour) and leaves 0
//! elsewhere. The two lighting passes then select pixels by that value.

use crate::gl::{FullscreenPass, Program, ShaderSource, TextureRef, VertexArray, check_error};
use crate::renderer::pass::lighting_per_sample::SampleInputs;
use crate::renderer::pass::shared::{begin_fullscreen, draw_fullscreen};
use crate::resolve::{COMPLEX_GLSL, COMPLEX_GLSL_NAME};
use crate::{Error, Result};
use glow::HasContext;

/// The detection shader's body.
pub(crate) const COMPLEX_MASK_FRAG: &str = include_str!("complex_mask.frag");

/// Samples of one pixel whose view depths differ by more than this many
/// pixel footprints (distance × tan(fov_y / height)) are different surfaces.
pub(crate) const DEPTH_TOLERANCE: f32 = 1.0;
/// Samples whose normals are further apart than this angle (radians, 10°)
/// are different surfaces.
pub(crate) const NORMAL_TOLERANCE: f32 = 0.174_532_93;
/// Samples whose base colours differ by more than this in a channel are
/// different materials.
pub(crate) const COLOR_TOLERANCE: f32 = 0.02;

/// The stencil value that marks a complex pixel.
pub(crate) const COMPLEX: u8 = 1;
/// The stencil value of a simple pixel.
pub(crate) const SIMPLE: u8 = 0;

/// Where the mask goes: a framebuffer with the HDR target and a stencil attachment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MaskTarget {
    /// The framebuffer.
    pub(crate) fbo: glow::Framebuffer,
    /// Its width.
    pub(crate) width: u32,
    /// Its height.
    pub(crate) height: u32,
}

/// The detection program, with or without the coverage flags.
#[derive(Debug)]
pub(crate) struct ComplexMaskPass {
    program: Program,
    coverage: bool,
}

impl ComplexMaskPass {
    /// Build the program; `coverage`: it reads the coverage flags (`u_coverage`).
    pub(crate) fn new(gl: &glow::Context, coverage: bool) -> Result<Self> {
        let defines: Vec<(String, String)> = if coverage {
            vec![("COVERAGE".into(), "1".into())]
        } else {
            Vec::new()
        };
        let fragment = ShaderSource::new()
            .defines(&defines)
            .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
            .part("complex_mask.frag", COMPLEX_MASK_FRAG);
        let label = if coverage {
            "complex-pixel mask (coverage + discontinuities)"
        } else {
            "complex-pixel mask (discontinuities)"
        };
        // The pass keeps its own draw code (stencil writes, no colour).
        let program = FullscreenPass::new(gl, label, &fragment, &[])?.into_program();
        Ok(ComplexMaskPass { program, coverage })
    }

    /// Whether the program reads the coverage flags.
    pub(crate) fn uses_coverage(&self) -> bool {
        self.coverage
    }

    /// Clear the stencil of `target` to [`SIMPLE`] and write [`COMPLEX`] for
    /// complex pixels (colour is not written). `coverage` must be given when
    /// the program reads it; `footprint` is tan(fov_y / height).
    /// Background samples are those with position.w = 0 (cleared, never
    /// written by the model shader).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: MaskTarget,
        vao: &VertexArray,
        inputs: &SampleInputs,
        coverage: Option<TextureRef>,
        footprint: f32,
    ) -> Result<()> {
        begin_fullscreen(gl, target.fbo, target.width, target.height);
        unsafe {
            gl.color_mask(false, false, false, false);
            gl.stencil_mask(0xFF);
            gl.clear_stencil(i32::from(SIMPLE));
            gl.clear(glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_func(glow::ALWAYS, i32::from(COMPLEX), 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
        }
        let p = &self.program;
        p.bind(gl);
        let mut textures = vec![
            ("u_position", inputs.position),
            ("u_normal", inputs.normal),
            ("u_color", inputs.color),
        ];
        if self.coverage {
            let c = coverage.ok_or_else(|| {
                Error::invalid("the complex-pixel mask reads coverage flags but none were recorded")
            })?;
            textures.push(("u_coverage", c));
        }
        for (unit, (name, texture)) in textures.iter().enumerate() {
            texture.bind(gl, unit as u32);
            p.set_i32(gl, name, unit as i32);
        }
        p.set_i32(gl, "u_samples", inputs.samples as i32);
        p.set_f32(gl, "u_footprint", footprint);
        p.set_f32(gl, "u_depth_tolerance", DEPTH_TOLERANCE);
        p.set_f32(gl, "u_normal_cos", NORMAL_TOLERANCE.cos());
        p.set_f32(gl, "u_color_tolerance", COLOR_TOLERANCE);
        draw_fullscreen(gl, vao);
        unsafe {
            gl.color_mask(true, true, true, true);
            gl.disable(glow::STENCIL_TEST);
            for unit in 0..textures.len() as u32 {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            }
        }
        Ok(check_error(gl, "the complex-pixel detection pass")?)
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}
