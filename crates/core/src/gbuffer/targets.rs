//! Owned G-buffer textures: the single-sample G-buffer and multisampled twins.

use super::GBufferLayout;
use crate::gl::{
    Attachment, Format, Framebuffer, GlObject, Handle, Made, Texture2d, Texture2dMultisample,
    TextureRef, destroy_object,
};
use crate::{Error, Result};

/// A single-sample G-buffer built from a layout: what a host engine owns, and
/// what the demo renderer uses as its host G-buffer.
#[derive(Debug)]
pub struct GBuffer {
    /// Colour textures in layout order (attachment `k` at `GL_COLOR_ATTACHMENTk`).
    pub colors: Vec<Texture2d>,
    /// The depth texture.
    pub depth: Texture2d,
    /// The framebuffer, with draw buffer `k` → attachment `k`.
    pub fbo: Framebuffer,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl GBuffer {
    /// The layout's textures at `width`×`height` (colour `k` and depth),
    /// labelled `gbuffer NAME`, for a G-buffer or for a host that attaches
    /// new textures to its existing framebuffer on resize.
    pub fn allocate_textures(
        gl: &glow::Context,
        layout: &GBufferLayout,
        width: u32,
        height: u32,
    ) -> Result<(Vec<Texture2d>, Texture2d)> {
        Made::build(gl, |made| {
            let mut colors = Vec::with_capacity(layout.colors.len());
            for a in &layout.colors {
                let label = format!("gbuffer {}", a.name);
                colors.push(made.keep(Texture2d::new(gl, &label, a.format, width, height)?));
            }
            let depth = made.keep(Texture2d::new(
                gl,
                "gbuffer depth",
                layout.depth,
                width,
                height,
            )?);
            Ok((colors, depth))
        })
    }

    /// Allocate the layout's textures at `width`×`height`.
    pub fn new(
        gl: &glow::Context,
        layout: &GBufferLayout,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        layout.validate()?;
        let (colors, depth) = Self::allocate_textures(gl, layout, width, height)?;
        Made::build(gl, |made| {
            let (colors, depth) = (made.keep(colors), made.keep(depth));
            let mut attachments: Vec<(Attachment, TextureRef)> = colors
                .iter()
                .enumerate()
                .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
                .collect();
            attachments.push((
                Attachment::for_depth_format(layout.depth),
                TextureRef::from(&depth),
            ));
            let draw: Vec<Option<u32>> = (0..colors.len() as u32).map(Some).collect();
            let fbo = Framebuffer::new(gl, "gbuffer", &attachments, &draw)?;
            Ok(GBuffer {
                colors,
                depth,
                fbo,
                width,
                height,
            })
        })
    }

    /// Free the framebuffer and its textures.
    pub fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

/// One attachment of a multisampled twin.
#[derive(Clone, Debug, PartialEq)]
pub struct TwinSpec {
    /// Where it is attached (the same point as its single-sample original).
    pub point: Attachment,
    /// Its internal format (the original's).
    pub format: Format,
    /// A name for labels and errors.
    pub name: String,
}

/// Multisampled twins of a set of attachments, in a framebuffer with the same
/// attachment points and draw-buffer mapping as the original.
#[derive(Debug)]
pub struct MultisampleTwin {
    /// The twins, in the order of the specs.
    pub textures: Vec<Texture2dMultisample>,
    /// The specs they were made from.
    pub specs: Vec<TwinSpec>,
    /// The multisampled framebuffer.
    pub fbo: Framebuffer,
    /// The real sample count (the same for every attachment).
    pub samples: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl MultisampleTwin {
    /// Allocate one `GL_TEXTURE_2D_MULTISAMPLE` per spec with `samples`
    /// samples (the driver's real count is read back and must agree across
    /// attachments) and attach them with `draw_buffers` as the mapping.
    pub fn new(
        gl: &glow::Context,
        specs: &[TwinSpec],
        draw_buffers: &[Option<u32>],
        width: u32,
        height: u32,
        samples: u32,
    ) -> Result<Self> {
        Made::build(gl, |made| {
            let mut textures: Vec<Texture2dMultisample> = Vec::with_capacity(specs.len());
            for spec in specs {
                let label = format!("msaa {}", spec.name);
                textures.push(made.keep(Texture2dMultisample::new(
                    gl,
                    &label,
                    spec.format,
                    width,
                    height,
                    samples,
                )?));
            }
            let real = textures.first().map_or(samples, |t| t.samples);
            if let Some(t) = textures.iter().find(|t| t.samples != real) {
                return Err(Error::UnsupportedSampleCount {
                    requested: samples,
                    format: format!(
                        "{} (the driver gave {} samples to it but {real} to the others)",
                        t.format, t.samples
                    ),
                    supported: vec![real],
                });
            }
            let attachments: Vec<(Attachment, TextureRef)> = specs
                .iter()
                .zip(&textures)
                .map(|(s, t)| (s.point, TextureRef::from(t)))
                .collect();
            let fbo = Framebuffer::new(
                gl,
                &format!("msaa gbuffer {real}x"),
                &attachments,
                draw_buffers,
            )?;
            Ok(MultisampleTwin {
                textures,
                specs: specs.to_vec(),
                fbo,
                samples: real,
                width,
                height,
            })
        })
    }

    /// Twins of a layout's attachments (colour `k` at `GL_COLOR_ATTACHMENTk`, then depth).
    pub fn for_layout(
        gl: &glow::Context,
        layout: &GBufferLayout,
        width: u32,
        height: u32,
        samples: u32,
    ) -> Result<Self> {
        layout.validate()?;
        let mut specs: Vec<TwinSpec> = layout
            .colors
            .iter()
            .enumerate()
            .map(|(k, a)| TwinSpec {
                point: Attachment::Color(k as u32),
                format: a.format,
                name: a.name.clone(),
            })
            .collect();
        specs.push(TwinSpec {
            point: Attachment::for_depth_format(layout.depth),
            format: layout.depth,
            name: "depth".into(),
        });
        let draw: Vec<Option<u32>> = (0..layout.colors.len() as u32).map(Some).collect();
        Self::new(gl, &specs, &draw, width, height, samples)
    }

    /// The twin at an attachment point.
    pub fn texture(&self, point: Attachment) -> Option<&Texture2dMultisample> {
        self.specs
            .iter()
            .position(|s| s.point == point)
            .and_then(|i| self.textures.get(i))
    }

    /// The depth twin.
    pub fn depth(&self) -> Option<&Texture2dMultisample> {
        self.specs
            .iter()
            .position(|s| s.format.is_depth())
            .and_then(|i| self.textures.get(i))
    }

    /// Bytes of all twins.
    pub fn bytes(&self) -> u64 {
        self.textures.iter().map(|t| t.bytes()).sum()
    }

    /// Free the framebuffer and the twins.
    pub fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for GBuffer {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.colors.handles(out);
        self.depth.handles(out);
        self.fbo.handles(out);
    }
}

impl GlObject for MultisampleTwin {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.textures.handles(out);
        self.fbo.handles(out);
    }
}
