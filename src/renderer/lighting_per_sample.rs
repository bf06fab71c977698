//! The per-sample lighting pass (`lighting_per_sample.frag`) of
//! methods [`AaMode::PerSample`](super::AaMode::PerSample) and
//! [`AaMode::Complex`](super::AaMode::Complex): every sample of the
//! multisampled G-buffer (the retrofit's twins) is lit with `texelFetch` and
//! the lit samples are averaged as the tonemap will see them (see the
//! shader's header). The lights, the BRDF and the shading of one G-buffer
//! sample are `lighting.frag`'s, compiled in front of it with all lights in
//! one uniform block; the tonemap curve and its inverse are `tonemap.frag`'s.

use super::GBufferSlots;
use super::lighting::{AMBIENT, LIGHTING_FRAG, LightBatch, StandIns, set_batch_blend};
use super::pass::{LightTarget, draw_fullscreen};
use super::tonemap::{EXPOSURE, TONEMAP_FRAG, WHITE};
use crate::gl::{
    Buffer, FullscreenPass, Made, Program, SamplesPassedQuery, ShaderSource, TextureRef,
    VertexArray, check_error,
};
use crate::retrofit::MsaaRetrofit;
use crate::{Error, Result};
use glow::HasContext;

/// The per-sample lighting shader's body (compiled after `lighting.frag`
/// with `LIGHTING_FUNCTIONS_ONLY`).
pub(crate) const LIGHTING_PER_SAMPLE_FRAG: &str = include_str!("lighting_per_sample.frag");

/// The multisampled G-buffer the per-sample passes read: the retrofit's
/// twins of the renderer's attachments.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleInputs {
    /// Base colour.
    pub(crate) color: TextureRef,
    /// View-space position.
    pub(crate) position: TextureRef,
    /// Normal and gloss.
    pub(crate) normal: TextureRef,
    /// F0 and metallic (`None`: the layout has none, see [`StandIns`]).
    pub(crate) specular: Option<TextureRef>,
    /// Emission and the background (`None`: the layout has none).
    pub(crate) emissive: Option<TextureRef>,
    /// Depth.
    pub(crate) depth: TextureRef,
    /// The real sample count.
    pub(crate) samples: u32,
}

impl SampleInputs {
    /// The twins of `retrofit` for the attachments at `slots` (the
    /// renderer's G-buffer has colour `k` at attachment `k`, so host colour
    /// `k` is slot `k`).
    pub(crate) fn of(retrofit: &MsaaRetrofit, slots: GBufferSlots) -> Result<Self> {
        let (depth, colors, _) = retrofit.inputs()?;
        let get = |slot: u32, name: &str| {
            colors.get(slot as usize).copied().ok_or_else(|| {
                Error::from(deferred_msaa::Error::Retrofit {
                    attachment: format!("GL_COLOR_ATTACHMENT{slot}"),
                    reason: format!("the `{name}` attachment has no multisampled twin"),
                })
            })
        };
        Ok(SampleInputs {
            color: get(slots.color, "color")?,
            position: get(slots.position, "position")?,
            normal: get(slots.normal, "normal")?,
            specular: slots.specular.map(|k| get(k, "specular")).transpose()?,
            emissive: slots.emissive.map(|k| get(k, "emissive")).transpose()?,
            depth,
            samples: retrofit.samples(),
        })
    }
}

/// Lights in one draw of the per-sample pass: four `vec4` arrays in a
/// std140 uniform block of 16 KiB, the least every GL 3.1+ context allows
/// (`GL_MAX_UNIFORM_BLOCK_SIZE`).
pub(crate) const LIGHTS_PER_DRAW: usize = 256;

/// The uniform block's binding point.
const LIGHT_BLOCK_BINDING: u32 = 0;

/// Bytes of the light block: four arrays of [`LIGHTS_PER_DRAW`] `vec4`s.
const LIGHT_BLOCK_BYTES: usize = 4 * LIGHTS_PER_DRAW * 16;

/// The std140 `LightBlock` uniform block of `lighting.frag` (built with
/// `LIGHT_BLOCK`), shared by every pass that lights all lights per draw:
/// its buffer, bound to one binding point.
#[derive(Debug)]
pub(crate) struct LightBlock {
    buffer: Buffer,
}

impl LightBlock {
    /// Bind `program`'s `LightBlock` to the binding point and allocate the
    /// buffer (`what` names the pass in errors and labels). On failure
    /// nothing is left allocated; the program stays the caller's.
    pub(crate) fn new(gl: &glow::Context, program: &Program, what: &str) -> Result<Self> {
        let block = unsafe { gl.get_uniform_block_index(program.raw(), "LightBlock") };
        let Some(block) = block else {
            return Err(Error::invalid(format!(
                "the {what} program has no `LightBlock` uniform block"
            )));
        };
        unsafe { gl.uniform_block_binding(program.raw(), block, LIGHT_BLOCK_BINDING) };
        let buffer = Buffer::with_size(
            gl,
            &format!("{what} light block"),
            glow::UNIFORM_BUFFER,
            LIGHT_BLOCK_BYTES,
            glow::DYNAMIC_DRAW,
        )?;
        Ok(LightBlock { buffer })
    }

    /// Bind the buffer to the block's binding point.
    pub(crate) fn bind(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_buffer_base(
                glow::UNIFORM_BUFFER,
                LIGHT_BLOCK_BINDING,
                Some(self.buffer.raw()),
            )
        };
    }

    /// Upload up to [`LIGHTS_PER_DRAW`] lights for the next draw.
    pub(crate) fn upload(&self, gl: &glow::Context, lights: &[[[f32; 4]; 4]]) {
        unsafe {
            gl.bind_buffer(glow::UNIFORM_BUFFER, Some(self.buffer.raw()));
            gl.buffer_sub_data_u8_slice(glow::UNIFORM_BUFFER, 0, &pack_block(lights));
            gl.bind_buffer(glow::UNIFORM_BUFFER, None);
        }
    }

    /// Unbind the binding point.
    pub(crate) fn unbind(gl: &glow::Context) {
        unsafe { gl.bind_buffer_base(glow::UNIFORM_BUFFER, LIGHT_BLOCK_BINDING, None) };
    }

    /// Free the buffer.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.buffer.destroy(gl);
    }
}

/// The per-sample lighting program, its light block, and the occlusion
/// query that counts the pixels it lights.
#[derive(Debug)]
pub(crate) struct PerSampleLightingPass {
    program: Program,
    slots: GBufferSlots,
    lights: LightBlock,
    query: Option<SamplesPassedQuery>,
}

impl PerSampleLightingPass {
    /// Build the program and the light block's buffer (and the
    /// `GL_SAMPLES_PASSED` query; without one the pass still runs, uncounted).
    pub(crate) fn new(gl: &glow::Context, slots: GBufferSlots) -> Result<Self> {
        Made::build(gl, |made| {
            let program = made.keep(
                FullscreenPass::new(
                    gl,
                    "per-sample lighting",
                    &Self::fragment(slots),
                    &[("o_color", 0)],
                )?
                .into_program(),
            );
            let lights = LightBlock::new(gl, &program, "per-sample lighting")?;
            let query = SamplesPassedQuery::new(gl).ok();
            Ok(PerSampleLightingPass {
                program,
                slots,
                lights,
                query,
            })
        })
    }

    fn defines(slots: GBufferSlots) -> Vec<(String, String)> {
        let mut d: Vec<(String, String)> = vec![
            ("MAX_LIGHTS".into(), LIGHTS_PER_DRAW.to_string()),
            ("LIGHT_BLOCK".into(), "1".into()),
            ("LIGHTING_FUNCTIONS_ONLY".into(), "1".into()),
            ("TONEMAP_FUNCTIONS_ONLY".into(), "1".into()),
        ];
        d.extend(slots.defines());
        d
    }

    /// The attachment set the program was built for.
    pub(crate) fn slots(&self) -> GBufferSlots {
        self.slots
    }

    /// `lighting.frag`'s shared part, `tonemap.frag`'s, then this pass's
    /// `main()`, each numbered as its own file.
    fn fragment(slots: GBufferSlots) -> ShaderSource {
        ShaderSource::new()
            .defines(&Self::defines(slots))
            .part("lighting.frag", LIGHTING_FRAG)
            .part("tonemap.frag", TONEMAP_FRAG)
            .part("lighting_per_sample.frag", LIGHTING_PER_SAMPLE_FRAG)
    }

    /// The fragment shader's full source as compiled: header, defines, parts.
    pub(crate) fn source(slots: GBufferSlots) -> String {
        Self::fragment(slots).text()
    }

    /// Light samples `0..samples` of `inputs` (every sample: `inputs.samples`;
    /// sample 0 alone: 1) into `target` (the pixels its stencil selects)
    /// with all of `batches`' lights and average (after the tonemap curve
    /// when one draw holds every light), one draw per [`LIGHTS_PER_DRAW`]
    /// lights. With `count`, the first draw is wrapped
    /// in a `GL_SAMPLES_PASSED` query and the number of pixels it lit is
    /// returned (`None` without a query object).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        inputs: &SampleInputs,
        samples: u32,
        batches: &[LightBatch],
        clear_depth: f32,
        count: bool,
        stand_ins: StandIns<'_>,
    ) -> Result<Option<u64>> {
        let lights: Vec<[[f32; 4]; 4]> = batches.iter().flat_map(LightBatch::lights).collect();
        let blocks: Vec<&[[[f32; 4]; 4]]> = if lights.is_empty() {
            vec![&[]]
        } else {
            lights.chunks(LIGHTS_PER_DRAW).collect()
        };
        target.bind(gl);
        let p = &self.program;
        p.bind(gl);
        let mut textures = vec![
            ("u_color", inputs.color),
            ("u_position", inputs.position),
            ("u_normal", inputs.normal),
            ("u_depth", inputs.depth),
        ];
        if let Some(t) = inputs.specular {
            textures.push(("u_specular", t));
        }
        textures.push(match inputs.emissive {
            Some(t) => ("u_emissive", t),
            None => ("u_background", TextureRef::from(stand_ins.background)),
        });
        p.set_vec4(gl, "u_specular_constant", stand_ins.specular);
        for (unit, (name, texture)) in textures.iter().enumerate() {
            texture.bind(gl, unit as u32);
            p.set_i32(gl, name, unit as i32);
        }
        p.set_f32(gl, "u_clear_depth", clear_depth);
        p.set_i32(gl, "u_samples", samples.clamp(1, inputs.samples) as i32);
        p.set_i32(gl, "u_tonemapped_average", i32::from(blocks.len() == 1));
        p.set_f32(gl, "u_exposure", EXPOSURE);
        p.set_f32(gl, "u_white", WHITE);
        p.set_vec3(gl, "u_ambient", AMBIENT);
        self.lights.bind(gl);
        let query = self.query.as_ref().filter(|_| count);
        for (index, block) in blocks.iter().enumerate() {
            self.lights.upload(gl, block);
            set_batch_blend(gl, index, false);
            p.set_i32(gl, "u_light_count", block.len() as i32);
            p.set_i32(gl, "u_first_batch", i32::from(index == 0));
            let counted = query.filter(|_| index == 0);
            if let Some(q) = counted {
                q.begin(gl);
            }
            draw_fullscreen(gl, vao);
            if let Some(q) = counted {
                q.end(gl);
            }
        }
        LightBlock::unbind(gl);
        unsafe {
            for unit in 0..textures.len() as u32 {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
                gl.bind_texture(glow::TEXTURE_2D, None);
            }
        }
        check_error(gl, "the per-sample lighting pass")?;
        Ok(query.map(|q| q.result(gl)))
    }

    /// Free the program, the buffer and the query.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
        self.lights.destroy(gl);
        if let Some(q) = self.query {
            q.destroy(gl);
        }
    }
}

/// The light block's std140 bytes for up to [`LIGHTS_PER_DRAW`] lights:
/// positions, directions, colours, cones, each array [`LIGHTS_PER_DRAW`]
/// `vec4`s long (unused entries zero).
fn pack_block(lights: &[[[f32; 4]; 4]]) -> Vec<u8> {
    let mut bytes = vec![0u8; LIGHT_BLOCK_BYTES];
    for (i, light) in lights.iter().take(LIGHTS_PER_DRAW).enumerate() {
        for (array, value) in light.iter().enumerate() {
            let offset = (array * LIGHTS_PER_DRAW + i) * 16;
            for (c, v) in value.iter().enumerate() {
                bytes[offset + 4 * c..offset + 4 * c + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_light_block_is_packed_as_std140_arrays() {
        let light = |k: f32| {
            [
                [k, 1.0, 2.0, 3.0],
                [k, 4.0, 5.0, 6.0],
                [k, 7.0, 8.0, 9.0],
                [k; 4],
            ]
        };
        let bytes = pack_block(&[light(10.0), light(20.0)]);
        assert_eq!(bytes.len(), 16 * 1024);
        let at = |offset: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&bytes[offset..offset + 4]);
            f32::from_le_bytes(b)
        };
        // u_light_position[1].x, u_light_direction[0].y, u_light_color[1].z, u_light_cone[0].w
        assert_eq!(at(16), 20.0);
        assert_eq!(at(LIGHTS_PER_DRAW * 16 + 4), 4.0);
        assert_eq!(at(2 * LIGHTS_PER_DRAW * 16 + 16 + 8), 8.0);
        assert_eq!(at(3 * LIGHTS_PER_DRAW * 16 + 12), 10.0);
        assert_eq!(at(3 * LIGHTS_PER_DRAW * 16 + 2 * 16), 0.0);
    }
}
