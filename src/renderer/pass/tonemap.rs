//! The tonemap pass (`tonemap.frag`): linear HDR to sRGB-encoded
//! RGBA8.

use super::shared::{draw_fullscreen, fullscreen_program};
use crate::Result;
use crate::gl::{GlObject, Handle, Program, Texture2d, VertexArray, check_error};
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The tonemap shader's body; its first part (the curve, its inverse, the
/// sRGB encoding) also goes into the per-sample lighting shader, compiled
/// with `TONEMAP_FUNCTIONS_ONLY`.
pub(crate) const TONEMAP_FRAG: &str = include_str!("tonemap.frag");

/// Exposure applied before the curve.
pub(crate) const EXPOSURE: f32 = 1.0;
/// The HDR value the curve maps to 1.0.
pub(crate) const WHITE: f32 = 8.0;

/// The curve's part of `tonemap.frag` as the retrofit's
/// [`LayerMix::Curve`](crate::second_layer::LayerMix::Curve): the two lit
/// layers are mixed after the tonemap curve, as the per-sample lighting
/// averages its samples, so the tonemapped pixel is the coverage-weighted
/// mix of its tonemapped layers.
pub(crate) fn layer_mix_curve() -> String {
    format!(
        "#define TONEMAP_FUNCTIONS_ONLY 1\n#define TONEMAP_CONSTANTS 1\n\
         #define TONEMAP_EXPOSURE {EXPOSURE:?}\n#define TONEMAP_WHITE {WHITE:?}\n{TONEMAP_FRAG}\n\
         vec3 dmsaa_curve(vec3 hdr) {{ return tonemap_linear(hdr); }}\n\
         vec3 dmsaa_curve_inverse(vec3 y) {{ return tonemap_linear_inverse(y); }}\n"
    )
}

/// The tonemap program.
#[derive(Debug)]
pub(crate) struct TonemapPass {
    program: Program,
}

impl TonemapPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program =
            fullscreen_program(gl, "tonemap", "tonemap.frag", TONEMAP_FRAG, &[], "o_color")?;
        Ok(TonemapPass { program })
    }

    /// Tonemap `hdr` into `target`.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: &ColorTarget,
        vao: &VertexArray,
        hdr: &Texture2d,
    ) -> Result<()> {
        target.begin_fullscreen(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(hdr.raw()));
        }
        let p = &self.program;
        p.bind(gl);
        p.set_i32(gl, "u_hdr", 0);
        p.set_f32(gl, "u_exposure", EXPOSURE);
        p.set_f32(gl, "u_white", WHITE);
        draw_fullscreen(gl, vao);
        Ok(check_error(gl, "the tonemap pass")?)
    }
}

impl GlObject for TonemapPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
