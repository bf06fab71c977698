//! Reading textures back to the CPU, every sample of a multisampled one
//! included (`glGetTexImage` cannot read those): a full-screen pass copies
//! one sample at a time into an RGBA32F texture, which is then read.

use crate::Result;
use crate::gl::format::SampleKind;
use crate::gl::{
    Attachment, Format, Framebuffer, FullscreenPass, RenderTarget, SavedState, ShaderSource,
    TextureRef, VertexArray, check_error,
};
use crate::resolve::cpu::PixelSamples;
use glow::HasContext;
use std::collections::HashMap;

const READBACK_FRAG: &str = include_str!("readback.frag");

/// Float values of a texture, `[samples][height][width][4]`, row 0 = the TOP row.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleImage {
    /// Samples (1 for single-sample textures, layers for arrays).
    pub samples: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGBA per sample and texel; depth textures carry depth in `.r`.
    pub data: Vec<f32>,
}

impl SampleImage {
    /// The RGBA value of sample `s` at (`x`, `y`), `y` counted from the top.
    pub fn get(&self, s: u32, x: u32, y: u32) -> [f32; 4] {
        let i = (((s * self.height + y) * self.width + x) * 4) as usize;
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// One sample's plane as `[height][width][4]`.
    pub fn plane(&self, s: u32) -> &[f32] {
        let n = (self.width * self.height * 4) as usize;
        &self.data[s as usize * n..(s as usize + 1) * n]
    }
}

/// Pixel (`x`, `y`; row 0 at the top) of a frame's samples read back, for
/// the resolve's CPU reference: the depth in `depth`'s first component, each
/// colour attachment's RGBA from `colors`, in the order the reference
/// numbers its attachments.
pub fn pixel_samples(depth: &SampleImage, colors: &[SampleImage], x: u32, y: u32) -> PixelSamples {
    let n = depth.samples;
    PixelSamples {
        depth: (0..n).map(|s| f64::from(depth.get(s, x, y)[0])).collect(),
        attachments: colors
            .iter()
            .map(|a| (0..n).map(|s| a.get(s, x, y).map(f64::from)).collect())
            .collect(),
    }
}

/// The readback pass, with its programs cached by sampler type.
#[derive(Debug)]
pub struct Readback {
    programs: HashMap<(u32, SampleKind), FullscreenPass>,
    vao: VertexArray,
}

impl Readback {
    /// Create the pass.
    pub fn new(gl: &glow::Context) -> Result<Self> {
        Ok(Readback {
            programs: HashMap::new(),
            vao: VertexArray::new(gl, "readback full-screen triangle")?,
        })
    }

    fn program(
        &mut self,
        gl: &glow::Context,
        target: u32,
        kind: SampleKind,
    ) -> Result<&FullscreenPass> {
        let entry = match self.programs.entry((target, kind)) {
            std::collections::hash_map::Entry::Occupied(e) => return Ok(e.into_mut()),
            std::collections::hash_map::Entry::Vacant(v) => v,
        };
        let prefix = match kind {
            SampleKind::Float => "",
            SampleKind::Uint => "u",
            SampleKind::Int => "i",
        };
        let (sampler, flavour) = match target {
            glow::TEXTURE_2D_MULTISAMPLE => ("sampler2DMS", Some("SRC_MS")),
            glow::TEXTURE_2D_ARRAY => ("sampler2DArray", Some("SRC_ARRAY")),
            _ => ("sampler2D", None),
        };
        let mut source = ShaderSource::new().define("SRC_SAMPLER", &format!("{prefix}{sampler}"));
        if let Some(f) = flavour {
            source = source.define(f, "1");
        }
        let program = FullscreenPass::new(
            gl,
            &format!("readback {prefix}{sampler}"),
            &source.part("readback.frag", READBACK_FRAG),
            &[("o_value", 0)],
        )?;
        Ok(entry.insert(program))
    }

    /// Read every sample (or layer) of `texture`.
    pub fn read(
        &mut self,
        gl: &glow::Context,
        texture: TextureRef,
        layers: u32,
    ) -> Result<SampleImage> {
        let count = match texture.target {
            glow::TEXTURE_2D_MULTISAMPLE => texture.samples,
            glow::TEXTURE_2D_ARRAY => layers.max(1),
            _ => 1,
        };
        let (w, h) = (texture.width, texture.height);
        let scratch = RenderTarget::new(
            gl,
            "readback",
            w,
            h,
            &[(Attachment::Color(0), Format::Rgba32f)],
            &[Some(0)],
        )?;
        let result = self.read_into(gl, texture, count, scratch.fbo());
        scratch.destroy(gl);
        result
    }

    fn read_into(
        &mut self,
        gl: &glow::Context,
        texture: TextureRef,
        count: u32,
        fbo: &Framebuffer,
    ) -> Result<SampleImage> {
        let (w, h) = (texture.width as usize, texture.height as usize);
        let state = SavedState::capture(gl, 1).guard(gl);
        self.program(gl, texture.target, texture.format.sample_kind())?;
        let pass = &self.programs[&(texture.target, texture.format.sample_kind())];
        let mut data = vec![0.0f32; count as usize * w * h * 4];
        let mut plane = vec![0.0f32; w * h * 4];
        let program = pass.begin(gl, fbo);
        unsafe {
            texture.bind(gl, 0);
            program.set_i32(gl, "u_src", 0);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo.raw));
            gl.read_buffer(glow::COLOR_ATTACHMENT0);
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            for s in 0..count {
                program.set_i32(gl, "u_sample", s as i32);
                pass.draw(gl, &self.vao);
                gl.read_pixels(
                    0,
                    0,
                    w as i32,
                    h as i32,
                    glow::RGBA,
                    glow::FLOAT,
                    glow::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut plane))),
                );
                // GL rows run bottom-up; ours top-down.
                let base = s as usize * w * h * 4;
                for y in 0..h {
                    let src = (h - 1 - y) * w * 4;
                    data[base + y * w * 4..base + (y + 1) * w * 4]
                        .copy_from_slice(&plane[src..src + w * 4]);
                }
            }
            gl.bind_texture(texture.target, None);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        drop(state);
        check_error(gl, "reading a texture back")?;
        Ok(SampleImage {
            samples: count,
            width: w as u32,
            height: h as u32,
            data,
        })
    }

    /// Free the programs and the vertex array.
    pub fn destroy(self, gl: &glow::Context) {
        for (_, p) in self.programs {
            p.destroy(gl);
        }
        self.vao.destroy(gl);
    }
}
