//! The lighting pass of [`AaMode::Sparse`](crate::renderer::AaMode::Sparse)
//! (`sparse_lighting.frag`): each block of each pixel's list
//! lit once with `lighting.frag`'s shading and every light (in the same
//! std140 light block as the per-sample pass), weighted by its sample
//! count and averaged after the tonemap curve as per-sample lighting does.

use super::shader::{EXTENSIONS, MAX_SAMPLES, SPARSE_FRAG, apply_region};
use super::targets::SparseTargets;
use crate::Result;
use crate::gl::{FullscreenPass, Made, Program, ShaderSource, Texture2d, VertexArray, check_error};
use crate::renderer::pass::lighting::{AMBIENT, LIGHTING_FRAG, LightBatch, set_batch_blend};
use crate::renderer::pass::lighting_per_sample::{LIGHTS_PER_DRAW, LightBlock};
use crate::renderer::pass::shared::{LightTarget, draw_fullscreen};
use crate::renderer::pass::tonemap::{EXPOSURE, TONEMAP_FRAG, WHITE};
use crate::resolve::{COMPLEX_GLSL, COMPLEX_GLSL_NAME, Region};
use glam::Mat4;
use glow::HasContext;

/// The lighting pass's body (after `lighting.frag`, `tonemap.frag` and `sparse.frag`).
pub(crate) const SPARSE_LIGHTING_FRAG: &str = include_str!("sparse_lighting.frag");

/// What the lighting pass is given besides the lists.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightParams<'a> {
    /// The background, drawn single-sampled.
    pub(crate) background: &'a Texture2d,
    /// The frame's projection (for positions from depth).
    pub(crate) projection: &'a Mat4,
    /// The anti-aliased region.
    pub(crate) region: Option<Region>,
}

/// The lighting program and its light block.
#[derive(Debug)]
pub(crate) struct SparseLightingPass {
    program: Program,
    lights: LightBlock,
}

impl SparseLightingPass {
    /// Build the program and the light block's buffer.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            let program = made.keep(
                FullscreenPass::new(gl, "sparse lighting", &Self::fragment(), &[("o_color", 0)])?
                    .into_program(),
            );
            let lights = LightBlock::new(gl, &program, "sparse lighting")?;
            Ok(SparseLightingPass { program, lights })
        })
    }

    fn defines() -> Vec<(String, String)> {
        vec![
            ("MAX_LIGHTS".into(), LIGHTS_PER_DRAW.to_string()),
            ("LIGHT_BLOCK".into(), "1".into()),
            ("LIGHTING_FUNCTIONS_ONLY".into(), "1".into()),
            ("TONEMAP_FUNCTIONS_ONLY".into(), "1".into()),
            ("SPARSE_MAX_SAMPLES".into(), MAX_SAMPLES.to_string()),
        ]
    }

    /// `lighting.frag`'s shared part, `tonemap.frag`'s, `complex.glsl`,
    /// `sparse.frag`, then this pass's `main()`, each numbered as its own file.
    fn fragment() -> ShaderSource {
        ShaderSource::new()
            .extensions(EXTENSIONS)
            .defines(&Self::defines())
            .part("lighting.frag", LIGHTING_FRAG)
            .part("tonemap.frag", TONEMAP_FRAG)
            .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
            .part("sparse.frag", SPARSE_FRAG)
            .part("sparse_lighting.frag", SPARSE_LIGHTING_FRAG)
    }

    /// The fragment shader's full source as compiled: header, defines, parts.
    pub(crate) fn source() -> String {
        Self::fragment().text()
    }

    /// Light the lists of `targets` into `target` with all of `batches`'
    /// lights, one draw per [`LIGHTS_PER_DRAW`] lights (averaged after the
    /// tonemap curve when one draw holds them all).
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        targets: &SparseTargets,
        batches: &[LightBatch],
        params: &LightParams<'_>,
    ) -> Result<()> {
        let lights: Vec<[[f32; 4]; 4]> = batches.iter().flat_map(LightBatch::lights).collect();
        let blocks: Vec<&[[[f32; 4]; 4]]> = if lights.is_empty() {
            vec![&[]]
        } else {
            lights.chunks(LIGHTS_PER_DRAW).collect()
        };
        target.bind(gl);
        let p = &self.program;
        p.bind(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(params.background.raw()));
        }
        p.set_i32(gl, "u_background", 0);
        p.set_u32(gl, "u_width", targets.width);
        p.set_u32(gl, "u_pool_capacity", targets.pool_capacity);
        p.set_i32(gl, "u_samples", targets.samples().min(MAX_SAMPLES) as i32);
        p.set_i32(gl, "u_tonemapped_average", i32::from(blocks.len() == 1));
        p.set_vec2(
            gl,
            "u_viewport",
            [targets.width as f32, targets.height as f32],
        );
        let m = params.projection;
        p.set_vec4(
            gl,
            "u_ndc_to_view",
            [1.0 / m.x_axis.x, 1.0 / m.y_axis.y, m.z_axis.x, m.z_axis.y],
        );
        p.set_f32(gl, "u_exposure", EXPOSURE);
        p.set_f32(gl, "u_white", WHITE);
        p.set_vec3(gl, "u_ambient", AMBIENT);
        apply_region(gl, p, &params.region, targets.height);
        targets.bind_buffers(gl);
        self.lights.bind(gl);
        for (index, block) in blocks.iter().enumerate() {
            self.lights.upload(gl, block);
            set_batch_blend(gl, index, false);
            p.set_i32(gl, "u_light_count", block.len() as i32);
            p.set_i32(gl, "u_first_batch", i32::from(index == 0));
            draw_fullscreen(gl, vao);
        }
        LightBlock::unbind(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        SparseTargets::unbind_buffers(gl);
        Ok(check_error(gl, "the sparse lighting pass")?)
    }

    /// Free the program and the buffer.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
        self.lights.destroy(gl);
    }
}
