//! The background pass (`background.frag`): the scene's
//! background drawn single-sampled into its own RGBA16F texture.

use super::shared::{draw_fullscreen, fullscreen_program};
use crate::Result;
use crate::gl::{GlObject, Handle, Program, VertexArray, check_error};
use crate::renderer::targets::ColorTarget;
use crate::scene::Background;
use glam::{DMat3, DMat4, Mat4};

/// The background shader's body.
pub(crate) const BACKGROUND_FRAG: &str = include_str!("background.frag");

/// The background program.
#[derive(Debug)]
pub(crate) struct BackgroundPass {
    program: Program,
}

impl BackgroundPass {
    /// Build the program.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "background",
            "background.frag",
            BACKGROUND_FRAG,
            &[],
            "o_color",
        )?;
        Ok(BackgroundPass { program })
    }

    /// Draw `background` as seen through `view` and `projection` into `target`.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: &ColorTarget,
        vao: &VertexArray,
        background: &Background,
        view: &DMat4,
        projection: &Mat4,
    ) -> Result<()> {
        let p = &self.program;
        target.begin_fullscreen(gl);
        p.bind(gl);
        let (kind, zenith, horizon, seed) = match *background {
            Background::Black => (0, [0.0; 3], [0.0; 3], 0),
            Background::Gradient { zenith, horizon } => (1, zenith, horizon, 0),
            Background::Stars { seed } => (2, [0.0; 3], [0.0; 3], seed),
        };
        p.set_i32(gl, "u_kind", kind);
        p.set_vec3(gl, "u_zenith", zenith);
        p.set_vec3(gl, "u_horizon", horizon);
        p.set_u32(gl, "u_seed", seed);
        let tan_half = [1.0 / projection.x_axis.x, 1.0 / projection.y_axis.y];
        p.set_vec2(gl, "u_tan_half_fov", tan_half);
        // About one star cell per 1.5 pixels, whatever the lens.
        let cells = target.texture.height as f32 / (3.0 * tan_half[1]);
        p.set_f32(gl, "u_star_cells", cells);
        let view_to_world = DMat4::from_mat3(DMat3::from_mat4(*view).transpose());
        p.set_mat4(
            gl,
            "u_view_to_world",
            &view_to_world.as_mat4().to_cols_array(),
        );
        draw_fullscreen(gl, vao);
        Ok(check_error(gl, "the background pass")?)
    }
}

impl GlObject for BackgroundPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
