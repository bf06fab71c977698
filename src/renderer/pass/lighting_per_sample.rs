//! The per-sample lighting passes of methods
//! [`AaMode::PerSample`](crate::renderer::AaMode::PerSample) and
//! [`AaMode::Complex`](crate::renderer::AaMode::Complex): every sample of the
//! multisampled G-buffer (the retrofit's twins) is lit with `texelFetch`
//! into a radiance target of its own, one draw per light batch (writing up
//! to [`SAMPLES_PER_DRAW`] samples' targets at once), the batches added by
//! blending as the one-sample lighting pass adds them
//! (`lighting_per_sample.frag`); then one pass tonemaps the samples,
//! averages them and maps the average back to HDR (`sample_average.frag`).
//! Each sample's radiance is thus the one-sample lighting's sum for that
//! G-buffer sample, rounded where that sum is rounded, at any light count,
//! and the average is the one the tonemap will see. The lights, the BRDF and
//! the shading of one G-buffer sample are `lighting.frag`'s, with its own
//! batches and uniforms; the tonemap curve and its inverse are
//! `tonemap.frag`'s.

use super::lighting::{
    AMBIENT, LIGHTING_FRAG, LightBatch, StandIns, lighting_defines, set_batch_blend,
};
use super::shared::{LightTarget, StencilSelect, draw_fullscreen};
use super::slots::GBufferSlots;
use super::tonemap::{EXPOSURE, TONEMAP_FRAG, WHITE};
use crate::gl::{
    Attachment, Buffer, Framebuffer, FullscreenPass, HostImage, Made, Program, SamplesPassedQuery,
    ShaderSource, Texture2d, Texture2dArray, TextureRef, VertexArray, check_error,
};
use crate::retrofit::MsaaRetrofit;
use crate::{Error, Result};
use glow::HasContext;

/// The per-sample lighting shader's body (compiled after `lighting.frag`
/// with `LIGHTING_FUNCTIONS_ONLY`): one sample, one light batch.
pub(crate) const LIGHTING_PER_SAMPLE_FRAG: &str = include_str!("lighting_per_sample.frag");

/// Samples one draw of the per-sample lighting lights, one draw buffer
/// each: GL 3.2's least `GL_MAX_DRAW_BUFFERS` and `GL_MAX_COLOR_ATTACHMENTS`.
pub(crate) const SAMPLES_PER_DRAW: u32 = 8;

/// The shader that tonemaps and averages the samples' radiance (compiled
/// after `tonemap.frag` with `TONEMAP_FUNCTIONS_ONLY`).
pub(crate) const SAMPLE_AVERAGE_FRAG: &str = include_str!("sample_average.frag");

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

/// Lights in one draw of the passes that light with all lights per draw
/// (`sparse`'s): four `vec4` arrays in a std140 uniform block of 16 KiB,
/// the least every GL 3.1+ context allows (`GL_MAX_UNIFORM_BLOCK_SIZE`).
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

/// Each sample's radiance: one single-sample layer per sample, in the HDR
/// target's own format, so that adding light batches into a layer rounds as
/// adding them into the HDR target does; and a framebuffer per
/// [`SAMPLES_PER_DRAW`] layers (layer `first + k` at colour attachment and
/// draw buffer `k`), with the complex-pixel stencil attached for `complex`.
#[derive(Debug)]
pub(crate) struct SampleRadiance {
    texture: Texture2dArray,
    /// Each framebuffer with its first layer.
    groups: Vec<(Framebuffer, u32)>,
    stencil: Option<glow::Texture>,
}

impl SampleRadiance {
    /// Allocate `samples` layers the size and format of `hdr`, each layer's
    /// framebuffer with `stencil` (a depth-stencil texture the size of
    /// `hdr`) attached when given. On failure nothing is left allocated.
    pub(crate) fn new(
        gl: &glow::Context,
        hdr: &Texture2d,
        samples: u32,
        stencil: Option<&Texture2d>,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let texture = made.keep(Texture2dArray::new(
                gl,
                "per-sample radiance",
                hdr.format,
                hdr.width,
                hdr.height,
                samples.max(1),
                None,
            )?);
            let mut groups = Vec::new();
            for first in (0..texture.layers).step_by(SAMPLES_PER_DRAW as usize) {
                let count = (texture.layers - first).min(SAMPLES_PER_DRAW);
                let mut attachments = Vec::new();
                let mut images = Vec::new();
                for k in 0..count {
                    attachments.push((Attachment::Color(k), TextureRef::from(&texture)));
                    images.push((
                        Attachment::Color(k),
                        HostImage::TextureLayer {
                            texture: texture.raw(),
                            layer: first + k,
                        },
                    ));
                }
                if let Some(s) = stencil {
                    attachments.push((Attachment::DepthStencil, TextureRef::from(s)));
                }
                let draw: Vec<Option<u32>> = (0..count).map(Some).collect();
                let fbo = made.keep(Framebuffer::with_host_images(
                    gl,
                    &format!("per-sample radiance, samples {first}.."),
                    &attachments,
                    &images,
                    &draw,
                )?);
                groups.push((fbo, first));
            }
            Ok::<_, Error>(SampleRadiance {
                texture,
                groups,
                stencil: stencil.map(Texture2d::raw),
            })
        })
    }

    /// Whether these layers are what [`SampleRadiance::new`] would make for
    /// the same arguments.
    pub(crate) fn fits(&self, hdr: &Texture2d, samples: u32, stencil: Option<&Texture2d>) -> bool {
        let t = &self.texture;
        (t.width, t.height, t.format, t.layers)
            == (hdr.width, hdr.height, hdr.format, samples.max(1))
            && self.stencil == stencil.map(Texture2d::raw)
    }

    /// Free the layers' framebuffers and the texture (not the stencil).
    pub(crate) fn destroy(self, gl: &glow::Context) {
        for (fbo, _) in self.groups {
            fbo.destroy(gl);
        }
        self.texture.destroy(gl);
    }
}

/// Make `slot` hold layers fitting `hdr`, `samples` and `stencil`,
/// replacing what is there unless it fits.
pub(crate) fn prepare_radiance(
    slot: &mut Option<SampleRadiance>,
    gl: &glow::Context,
    hdr: &Texture2d,
    samples: u32,
    stencil: Option<&Texture2d>,
) -> Result<()> {
    if !slot.as_ref().is_some_and(|r| r.fits(hdr, samples, stencil)) {
        let fresh = SampleRadiance::new(gl, hdr, samples, stencil)?;
        if let Some(old) = slot.replace(fresh) {
            old.destroy(gl);
        }
    }
    Ok(())
}

/// The per-sample lighting program, the averaging program, and the
/// occlusion query that counts the pixels averaged.
#[derive(Debug)]
pub(crate) struct PerSampleLightingPass {
    program: Program,
    average: Program,
    slots: GBufferSlots,
    query: Option<SamplesPassedQuery>,
}

impl PerSampleLightingPass {
    /// Build both programs (and the `GL_SAMPLES_PASSED` query; without one
    /// the pass still runs, uncounted).
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
            let average = made.keep(
                FullscreenPass::new(
                    gl,
                    "per-sample average",
                    &ShaderSource::new()
                        .defines(&[("TONEMAP_FUNCTIONS_ONLY".into(), "1".into())])
                        .part("tonemap.frag", TONEMAP_FRAG)
                        .part("sample_average.frag", SAMPLE_AVERAGE_FRAG),
                    &[("o_color", 0)],
                )?
                .into_program(),
            );
            let query = SamplesPassedQuery::new(gl).ok();
            Ok::<_, Error>(PerSampleLightingPass {
                program,
                average,
                slots,
                query,
            })
        })
    }

    /// `lighting.frag`'s defines (its batch size), the function-only
    /// switch, and the attachment set's.
    fn defines(slots: GBufferSlots) -> Vec<(String, String)> {
        let mut d = lighting_defines();
        d.push(("LIGHTING_FUNCTIONS_ONLY".into(), "1".into()));
        d.push(("SAMPLES_PER_DRAW".into(), SAMPLES_PER_DRAW.to_string()));
        d.extend(slots.defines());
        d
    }

    /// The attachment set the program was built for.
    pub(crate) fn slots(&self) -> GBufferSlots {
        self.slots
    }

    /// `lighting.frag`'s shared part, then this pass's `main()`, each
    /// numbered as its own file.
    fn fragment(slots: GBufferSlots) -> ShaderSource {
        ShaderSource::new()
            .defines(&Self::defines(slots))
            .part("lighting.frag", LIGHTING_FRAG)
            .part("lighting_per_sample.frag", LIGHTING_PER_SAMPLE_FRAG)
    }

    /// The lighting shader's full source as compiled: header, defines, parts.
    pub(crate) fn source(slots: GBufferSlots) -> String {
        Self::fragment(slots).text()
    }

    /// Light samples `first .. first + count` of `inputs` (`count` at most
    /// [`SAMPLES_PER_DRAW`]) with all of `batches` (one draw each, later
    /// batches added by blending), sample `first + k` into draw buffer `k`
    /// of `target`, the pixels its stencil selects.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn light_samples(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        inputs: &SampleInputs,
        (first, count): (u32, u32),
        batches: &[LightBatch],
        clear_depth: f32,
        stand_ins: StandIns<'_>,
    ) -> Result<()> {
        let samples = inputs.samples.max(1);
        if first + count > samples || count > SAMPLES_PER_DRAW {
            return Err(Error::invalid(format!(
                "per-sample lighting of samples {first}..{} of {samples}, {SAMPLES_PER_DRAW} at a time",
                first + count
            )));
        }
        target.bind(gl);
        let p = &self.program;
        p.bind(gl);
        let units = self.bind_inputs(gl, inputs, stand_ins);
        p.set_f32(gl, "u_clear_depth", clear_depth);
        p.set_i32(gl, "u_first_sample", first as i32);
        p.set_i32(gl, "u_sample_count", count as i32);
        for (index, batch) in batches.iter().enumerate() {
            set_batch_blend(gl, index, false);
            batch.apply(gl, p, index == 0);
            draw_fullscreen(gl, vao);
        }
        unbind_units(gl, units);
        unsafe {
            gl.disable(glow::BLEND);
            gl.disable(glow::STENCIL_TEST);
        }
        check_error(gl, "the per-sample lighting pass")?;
        Ok(())
    }

    /// Light every sample of `inputs` into its layer of `radiance` (the
    /// pixels `stencil` selects there: `radiance` must carry a stencil for
    /// anything but [`StencilSelect::All`]), then tonemap, average and map
    /// back into `target` (the pixels its own stencil selects). With
    /// `count`, the average is wrapped in a `GL_SAMPLES_PASSED` query and
    /// the number of pixels it wrote is returned (`None` without a query
    /// object).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        radiance: &SampleRadiance,
        stencil: StencilSelect,
        vao: &VertexArray,
        inputs: &SampleInputs,
        batches: &[LightBatch],
        clear_depth: f32,
        count: bool,
        stand_ins: StandIns<'_>,
    ) -> Result<Option<u64>> {
        let samples = inputs.samples.max(1);
        if radiance.texture.layers != samples {
            return Err(Error::invalid(format!(
                "the per-sample radiance has {} layers for {samples} samples",
                radiance.texture.layers
            )));
        }
        if stencil != StencilSelect::All && radiance.stencil.is_none() {
            return Err(Error::invalid(
                "the per-sample radiance has no stencil to select pixels by",
            ));
        }
        for (fbo, first) in &radiance.groups {
            let layers = LightTarget {
                fbo: fbo.raw(),
                width: fbo.width,
                height: fbo.height,
                stencil,
            };
            let count = (samples - first).min(SAMPLES_PER_DRAW);
            self.light_samples(
                gl,
                layers,
                vao,
                inputs,
                (*first, count),
                batches,
                clear_depth,
                stand_ins,
            )?;
        }
        target.bind(gl);
        let p = &self.average;
        p.bind(gl);
        TextureRef::from(&radiance.texture).bind(gl, 0);
        p.set_i32(gl, "u_radiance", 0);
        p.set_i32(gl, "u_samples", samples as i32);
        p.set_f32(gl, "u_exposure", EXPOSURE);
        p.set_f32(gl, "u_white", WHITE);
        let query = self.query.as_ref().filter(|_| count);
        if let Some(q) = query {
            q.begin(gl);
        }
        draw_fullscreen(gl, vao);
        if let Some(q) = query {
            q.end(gl);
        }
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, None);
            gl.disable(glow::STENCIL_TEST);
        }
        check_error(gl, "the per-sample average")?;
        Ok(query.map(|q| q.result(gl)))
    }

    /// Bind the G-buffer samples (and the stand-ins) of the bound lighting
    /// program to texture units 0.., set their samplers and the stand-in
    /// specular; the number of units used.
    fn bind_inputs(
        &self,
        gl: &glow::Context,
        inputs: &SampleInputs,
        stand_ins: StandIns<'_>,
    ) -> u32 {
        let p = &self.program;
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
        p.set_vec3(gl, "u_ambient", AMBIENT);
        for (unit, (name, texture)) in textures.iter().enumerate() {
            texture.bind(gl, unit as u32);
            p.set_i32(gl, name, unit as i32);
        }
        textures.len() as u32
    }

    /// Free the programs and the query.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
        self.average.destroy(gl);
        if let Some(q) = self.query {
            q.destroy(gl);
        }
    }
}

/// Unbind texture units `0..units` (both targets the passes bind).
fn unbind_units(gl: &glow::Context, units: u32) {
    unsafe {
        for unit in 0..units {
            gl.active_texture(glow::TEXTURE0 + unit);
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            gl.bind_texture(glow::TEXTURE_2D, None);
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
