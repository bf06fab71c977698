//! The deferred lighting pass (`lighting.frag`): per-pixel
//! lighting from the resolved single-sample G-buffer into the HDR target.
//! Its source and defines do not depend on MSAA.

use super::shared::{LightTarget, draw_fullscreen, fullscreen_program};
use super::slots::GBufferSlots;
use crate::Result;
use crate::gbuffer::GBuffer;
use crate::gl::{GlObject, Handle, Program, ShaderSource, Texture2d, VertexArray, check_error};
use crate::scene::{Light, LightKind};
use glam::DMat4;
use glow::HasContext;

/// The deferred lighting fragment shader's body (`lighting.frag`;
/// its first part is shared with the transparent pass). Compiled after
/// [`preamble`](crate::gl::preamble) with [`lighting_defines`]; it reads the
/// resolved G-buffer through `u_color`, `u_position`, `u_normal`,
/// `u_specular`, `u_emissive` and `u_depth` with `texelFetch` at
/// `gl_FragCoord`, treats pixels whose depth equals `u_clear_depth` as
/// background, and writes `o_color`. A layout the scene-adaptive plan
/// trimmed adds `GBUFFER_NO_SPECULAR` (`u_specular_constant` instead of
/// `u_specular`) and `GBUFFER_NO_EMISSIVE` (`u_background`, the
/// background's own texture, instead of `u_emissive`).
pub const LIGHTING_FRAG: &str = include_str!("lighting.frag");

/// Lights per batch (one draw each); sized to fit GL 3.2's minimum of 1024
/// fragment uniform components with room to spare.
pub const LIGHTS_PER_BATCH: usize = 16;

/// Constant ambient radiance (`u_ambient`), scaled by the surface's diffuse colour and F0.
pub const AMBIENT: [f32; 3] = [0.03, 0.03, 0.035];

/// The `#define`s the lighting code is compiled with (the same for every
/// renderer option): `MAX_LIGHTS` = [`LIGHTS_PER_BATCH`].
pub fn lighting_defines() -> Vec<(String, String)> {
    vec![("MAX_LIGHTS".to_string(), LIGHTS_PER_BATCH.to_string())]
}

/// Up to [`LIGHTS_PER_BATCH`] lights in view space, packed as the shader reads them.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct LightBatch {
    position: Vec<[f32; 4]>,
    direction: Vec<[f32; 4]>,
    color: Vec<[f32; 4]>,
    cone: Vec<[f32; 4]>,
}

/// The scene's lights in view space, in batches (always at least one, which
/// may be empty: the first batch also carries emission and ambient light).
pub(crate) fn light_batches(lights: &[Light], view: &DMat4) -> Vec<LightBatch> {
    let mut batches = vec![LightBatch::default()];
    for light in lights {
        if batches
            .last()
            .is_some_and(|b| b.position.len() == LIGHTS_PER_BATCH)
        {
            batches.push(LightBatch::default());
        }
        let Some(batch) = batches.last_mut() else {
            break;
        };
        let position = view.transform_point3(light.position.as_dvec3()).as_vec3();
        let direction = view
            .transform_vector3(light.direction.as_dvec3())
            .normalize_or(glam::DVec3::NEG_Z)
            .as_vec3();
        let range = light
            .range
            .filter(|r| r.is_finite() && *r > 0.0)
            .unwrap_or(0.0);
        let (kind, cone) = match light.kind {
            LightKind::Point => (0.0, [0.0; 4]),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => (1.0, [outer_cone.cos(), inner_cone.cos(), 0.0, 0.0]),
            LightKind::Directional => (2.0, [0.0; 4]),
        };
        let c = light.color * light.intensity;
        batch
            .position
            .push([position.x, position.y, position.z, range]);
        batch
            .direction
            .push([direction.x, direction.y, direction.z, kind]);
        batch.color.push([c.x, c.y, c.z, 0.0]);
        batch.cone.push(cone);
    }
    batches
}

impl LightBatch {
    /// The packed lights, one entry per light: view-space position and
    /// range, direction and kind, colour × intensity, spot cone.
    pub(crate) fn lights(&self) -> impl Iterator<Item = [[f32; 4]; 4]> + '_ {
        (0..self.position.len()).map(|i| {
            [
                self.position[i],
                self.direction[i],
                self.color[i],
                self.cone[i],
            ]
        })
    }

    /// Set the light uniforms of a bound program; `first` adds emission and ambient.
    pub(crate) fn apply(&self, gl: &glow::Context, program: &Program, first: bool) {
        program.set_i32(gl, "u_light_count", self.position.len() as i32);
        if !self.position.is_empty() {
            program.set_vec4_array(gl, "u_light_position[0]", &self.position);
            program.set_vec4_array(gl, "u_light_direction[0]", &self.direction);
            program.set_vec4_array(gl, "u_light_color[0]", &self.color);
            program.set_vec4_array(gl, "u_light_cone[0]", &self.cone);
        }
        program.set_vec3(gl, "u_ambient", AMBIENT);
        program.set_i32(gl, "u_first_batch", first as i32);
    }
}

/// Set the blend state of light batch `index`: the first replaces (or, for
/// `alpha_blend`, blends over) what is there, later ones add to it.
pub(crate) fn set_batch_blend(gl: &glow::Context, index: usize, alpha_blend: bool) {
    unsafe {
        match (index, alpha_blend) {
            (0, false) => gl.disable(glow::BLEND),
            (0, true) => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func_separate(
                    glow::SRC_ALPHA,
                    glow::ONE_MINUS_SRC_ALPHA,
                    glow::ONE,
                    glow::ONE_MINUS_SRC_ALPHA,
                );
            }
            (_, false) => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func_separate(glow::ONE, glow::ONE, glow::ZERO, glow::ONE);
            }
            (_, true) => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func_separate(glow::SRC_ALPHA, glow::ONE, glow::ZERO, glow::ONE);
            }
        }
    }
}

/// What stands in for the attachments a scene-adaptive layout leaves out.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StandIns<'a> {
    /// The background's own single-sample texture, read for background
    /// pixels when there is no `emissive` attachment to carry it.
    pub(crate) background: &'a Texture2d,
    /// The specular value (F0 rgb, metallic) every material writes, used
    /// when there is no `specular` attachment.
    pub(crate) specular: [f32; 4],
}

/// The lighting program, compiled for one attachment set.
#[derive(Debug)]
pub(crate) struct LightingPass {
    program: Program,
    slots: GBufferSlots,
}

impl LightingPass {
    /// Build the program for the attachments at `slots`.
    pub(crate) fn new(gl: &glow::Context, slots: GBufferSlots) -> Result<Self> {
        let program = fullscreen_program(
            gl,
            "deferred lighting",
            "lighting.frag",
            LIGHTING_FRAG,
            &Self::defines(slots),
            "o_color",
        )?;
        Ok(LightingPass { program, slots })
    }

    fn defines(slots: GBufferSlots) -> Vec<(String, String)> {
        let mut d = lighting_defines();
        d.extend(slots.defines());
        d
    }

    /// The attachment set the program was built for.
    pub(crate) fn slots(&self) -> GBufferSlots {
        self.slots
    }

    /// The fragment shader's full source as compiled for `slots`: preamble,
    /// defines, body.
    pub(crate) fn source(slots: GBufferSlots) -> String {
        ShaderSource::new()
            .defines(&Self::defines(slots))
            .part("lighting.frag", LIGHTING_FRAG)
            .text()
    }

    /// Light the resolved `gbuffer` into `target`, one draw per light batch;
    /// pixels whose depth is `clear_depth` are background.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        gbuffer: &GBuffer,
        slots: GBufferSlots,
        batches: &[LightBatch],
        clear_depth: f32,
        stand_ins: StandIns<'_>,
    ) -> Result<()> {
        target.bind(gl);
        let p = &self.program;
        p.bind(gl);
        let mut inputs = vec![
            ("u_color", &gbuffer.colors[slots.color as usize]),
            ("u_position", &gbuffer.colors[slots.position as usize]),
            ("u_normal", &gbuffer.colors[slots.normal as usize]),
            ("u_depth", &gbuffer.depth),
        ];
        if let Some(k) = slots.specular {
            inputs.push(("u_specular", &gbuffer.colors[k as usize]));
        }
        inputs.push(match slots.emissive {
            Some(k) => ("u_emissive", &gbuffer.colors[k as usize]),
            None => ("u_background", stand_ins.background),
        });
        p.set_vec4(gl, "u_specular_constant", stand_ins.specular);
        for (unit, (name, texture)) in inputs.iter().enumerate() {
            unsafe {
                gl.active_texture(glow::TEXTURE0 + unit as u32);
                gl.bind_texture(glow::TEXTURE_2D, Some(texture.raw()));
            }
            p.set_i32(gl, name, unit as i32);
        }
        p.set_f32(gl, "u_clear_depth", clear_depth);
        for (index, batch) in batches.iter().enumerate() {
            set_batch_blend(gl, index, false);
            batch.apply(gl, p, index == 0);
            draw_fullscreen(gl, vao);
        }
        // Leave no G-buffer texture bound: the depth texture is attached to
        // the framebuffer the transparent pass draws into next.
        for unit in 0..inputs.len() as u32 {
            unsafe {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, None);
            }
        }
        unsafe { gl.disable(glow::STENCIL_TEST) };
        Ok(check_error(gl, "the lighting pass")?)
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}

impl GlObject for LightingPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
