//! Method `gbaa`, geometry-buffer anti-aliasing (after Emil Persson's GBAA),
//! with fixes for converging edges: [`AaMode::Gbaa`](crate::renderer::AaMode::Gbaa).
//!
//! The G-buffer stays single-sampled. Its pass ([`GbaaGeometryPass`]) also
//! writes, per pixel, where the pixel's triangle ends: the signed distance
//! to the nearest edge along x or y (`RG16F`, [`GbaaTargets::edge`]) and
//! the distance to the triangle's boundary the opposite way along that axis
//! (`R16F`, [`GbaaTargets::far`]). Lighting, transparent objects and the
//! tonemap run as for `none`, the tonemap into an sRGB texture
//! ([`GbaaTargets::tonemapped`]); then the post pass (`gbaa.frag`)
//! blends each pixel crossed by an edge with the neighbour beyond it, by
//! the fraction of the pixel on that side, in one bilinear fetch (two for a
//! triangle thinner than a pixel), into the renderer's LDR image, where
//! FXAA (if on) finds it.
//!
//! What it cannot do: restore sub-pixel triangles that no pixel centre
//! hits (they were never rasterised), smooth edges that are not triangle
//! edges (alpha-tested cut-outs, texture and lighting edges), or tell
//! transparent objects' edges (they are drawn after the G-buffer).

use super::geometry::{GbaaGeometryPass, NO_EDGE, edge_defines};
use crate::Result;
use crate::gbuffer::GBuffer;
use crate::gl::{
    Attachment, Capabilities, Format, Framebuffer, FullscreenPass, Made, Program, ShaderSource,
    Texture2d, TextureRef, VertexArray, check_error,
};
use crate::renderer::pass::shared::draw_fullscreen;
use crate::renderer::pass::slots::GBufferSlots;
use crate::renderer::pass::tonemap::TONEMAP_FRAG;
use crate::renderer::targets::ColorTarget;
use glow::HasContext;

/// The post pass's body.
pub(crate) const GBAA_FRAG: &str = include_str!("gbaa.frag");

/// Format of the edge buffer: the signed distance to the nearest edge, in
/// `.r` along x or in `.g` along y.
pub(crate) const EDGE_FORMAT: Format = Format::Rg16f;
/// Format of the far-side buffer: the distance the opposite way.
pub(crate) const FAR_FORMAT: Format = Format::R16f;

/// How far two neighbours' edge distances may fall short of one pixel and
/// still be taken as one edge (f32 geometry, FP16 storage: about 1e-3 at
/// 1 px); a larger gap means a thin triangle lies between them.
const GAP: f32 = 1.0 / 32.0;

/// Bytes the two edge buffers add per pixel.
pub(crate) fn edge_bytes(width: u32, height: u32) -> u64 {
    u64::from(EDGE_FORMAT.bytes_per_texel() + FAR_FORMAT.bytes_per_texel())
        * u64::from(width)
        * u64::from(height)
}

/// The programs of `gbaa`, built when the mode is first used and kept.
#[derive(Debug)]
pub(crate) struct GbaaPasses {
    geometry: GbaaGeometryPass,
    /// The draw buffer of the edge output (the far side is on the next).
    edge_slot: u32,
    post: Program,
    show_edges: Program,
}

impl GbaaPasses {
    /// Build (or, when the layout's attachment numbers moved, rebuild) the
    /// programs in `slot` for a G-buffer with `slots` and `colors` colour
    /// attachments; the edge buffers go to the next two.
    pub(crate) fn prepare(
        slot: &mut Option<GbaaPasses>,
        gl: &glow::Context,
        slots: GBufferSlots,
        colors: u32,
    ) -> Result<()> {
        if slot
            .as_ref()
            .is_some_and(|p| p.geometry.slots() == slots && p.edge_slot == colors)
        {
            return Ok(());
        }
        let caps = Capabilities::query(gl);
        let limit = caps.max_draw_buffers.min(caps.max_color_attachments);
        if colors + 2 > limit {
            return Err(deferred_msaa::Error::Unsupported {
                feature: format!("method `gbaa` on a G-buffer of {colors} colour attachments"),
                requires: format!("{} colour attachments and draw buffers", colors + 2),
                found: format!("{limit}"),
            }
            .into());
        }
        let passes = Self::new(gl, slots, colors)?;
        if let Some(old) = slot.replace(passes) {
            old.destroy(gl);
        }
        Ok(())
    }

    fn new(gl: &glow::Context, slots: GBufferSlots, edge_slot: u32) -> Result<Self> {
        Made::build(gl, |made| {
            let geometry = made.keep(GbaaGeometryPass::new(gl, slots, edge_slot)?);
            let post = made.keep(Self::post_program(gl, false)?);
            let show_edges = made.keep(Self::post_program(gl, true)?);
            Ok(GbaaPasses {
                geometry,
                edge_slot,
                post,
                show_edges,
            })
        })
    }

    /// `tonemap.frag`'s functions (for `srgb_encode`), then `gbaa.frag`.
    fn post_program(gl: &glow::Context, show_edges: bool) -> Result<Program> {
        let mut defines = edge_defines();
        defines.push(("GBAA_GAP".into(), format!("{GAP:.6}")));
        defines.push(("TONEMAP_FUNCTIONS_ONLY".into(), "1".into()));
        if show_edges {
            defines.push(("GBAA_SHOW_EDGES".into(), "1".into()));
        }

        let fragment = ShaderSource::new()
            .defines(&defines)
            .part("tonemap.frag", TONEMAP_FRAG)
            .part("gbaa.frag", GBAA_FRAG);
        let label = if show_edges { "gbaa edges" } else { "gbaa" };
        Ok(FullscreenPass::new(gl, label, &fragment, &[("o_color", 0)])?.into_program())
    }

    /// The G-buffer pass's program.
    pub(crate) fn geometry(&self) -> &GbaaGeometryPass {
        &self.geometry
    }

    /// Blend `targets.tonemapped` across the edges into `out` (the post
    /// pass), or with `show_edges` draw what it would blend.
    pub(crate) fn draw_post(
        &self,
        gl: &glow::Context,
        out: &ColorTarget,
        vao: &VertexArray,
        targets: &GbaaTargets,
        show_edges: bool,
    ) -> Result<()> {
        out.begin_fullscreen(gl);
        let image = &targets.tonemapped.texture;
        TextureRef::from(image).bind(gl, 0);
        TextureRef::from(&targets.edge).bind(gl, 1);
        TextureRef::from(&targets.far).bind(gl, 2);
        let p = if show_edges {
            &self.show_edges
        } else {
            &self.post
        };
        p.bind(gl);
        p.set_i32(gl, "u_image", 0);
        p.set_i32(gl, "u_edge", 1);
        p.set_i32(gl, "u_edge_far", 2);
        p.set_vec2(
            gl,
            "u_texel",
            [1.0 / image.width as f32, 1.0 / image.height as f32],
        );
        draw_fullscreen(gl, vao);
        unsafe { gl.active_texture(glow::TEXTURE0) };
        Ok(check_error(gl, "the gbaa post pass")?)
    }

    /// Free the programs.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.geometry.destroy(gl);
        self.post.destroy(gl);
        self.show_edges.destroy(gl);
    }
}

/// The size-dependent targets of `gbaa`: the edge buffers, a framebuffer
/// with the G-buffer's textures plus them, and the tonemapped image.
#[derive(Debug)]
pub(crate) struct GbaaTargets {
    /// `RG16F`: the signed distance to the nearest edge along x (`.r`) or
    /// y (`.g`); [`NO_EDGE`] in the other channel and where nothing was drawn.
    pub(crate) edge: Texture2d,
    /// `R16F`: the distance to the triangle's boundary the opposite way.
    pub(crate) far: Texture2d,
    /// The G-buffer's attachments, then `edge` and `far` at colour
    /// attachments (and draw buffers) `colors` and `colors + 1`.
    pub(crate) fbo: Framebuffer,
    /// Its draw-buffer mapping.
    pub(crate) draw_buffers: Vec<Option<u32>>,
    /// The tonemapped frame (`SRGB8_ALPHA8`, linear filtering): fetches
    /// decode to linear light before they blend.
    pub(crate) tonemapped: ColorTarget,
}

impl GbaaTargets {
    /// Allocate for `gbuffer` (its size; its textures are attached, not owned).
    pub(crate) fn new(gl: &glow::Context, gbuffer: &GBuffer) -> Result<Self> {
        let (w, h) = (gbuffer.width, gbuffer.height);
        let colors = gbuffer.colors.len() as u32;
        let (edge, far, fbo, draw_buffers, tonemapped) = Made::build(gl, |made| {
            let edge = made.keep(Texture2d::new(gl, "gbaa edge", EDGE_FORMAT, w, h)?);
            let far = made.keep(Texture2d::new(gl, "gbaa far side", FAR_FORMAT, w, h)?);
            let mut attachments = gbuffer.fbo.attachments.clone();
            attachments.push((Attachment::Color(colors), TextureRef::from(&edge)));
            attachments.push((Attachment::Color(colors + 1), TextureRef::from(&far)));
            let draw_buffers: Vec<Option<u32>> = (0..colors + 2).map(Some).collect();
            let fbo = made.keep(Framebuffer::new(
                gl,
                "G-buffer with gbaa edges",
                &attachments,
                &draw_buffers,
            )?);
            let tonemapped = made.keep(ColorTarget::new(
                gl,
                "gbaa tonemapped",
                Format::Srgb8Alpha8,
                w,
                h,
            )?);
            Ok::<_, crate::Error>((edge, far, fbo, draw_buffers, tonemapped))
        })?;
        tonemapped.texture.set_filter(gl, glow::LINEAR);
        Ok(GbaaTargets {
            edge,
            far,
            fbo,
            draw_buffers,
            tonemapped,
        })
    }

    /// Set both edge buffers to "no edge" (after the G-buffer's clear,
    /// which zeroes every draw buffer; zero would read as an edge through
    /// the pixel centre).
    pub(crate) fn clear_edges(&self, gl: &glow::Context) {
        let colors = self.draw_buffers.len() as u32 - 2;
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo.raw()));
            gl.disable(glow::SCISSOR_TEST);
            gl.color_mask(true, true, true, true);
            gl.clear_buffer_f32_slice(glow::COLOR, colors, &[NO_EDGE, NO_EDGE, 0.0, 1.0]);
            gl.clear_buffer_f32_slice(glow::COLOR, colors + 1, &[NO_EDGE, 0.0, 0.0, 1.0]);
        }
    }

    /// Draw the edges view (see [`GbaaPasses::draw_post`]) into a scratch
    /// RGBA8 target and read it back, row 0 at the top.
    pub(crate) fn read_edges_view(
        &self,
        gl: &glow::Context,
        passes: &GbaaPasses,
        vao: &VertexArray,
    ) -> Result<image::RgbaImage> {
        let (w, h) = (self.edge.width, self.edge.height);
        let scratch = ColorTarget::new(gl, "gbaa edges view", Format::Rgba8, w, h)?;
        let result = passes
            .draw_post(gl, &scratch, vao, self, true)
            .and_then(|()| scratch.read_rgba8(gl, "the gbaa edges view"));
        scratch.destroy(gl);
        result
    }

    /// Free what it owns (not the G-buffer's textures).
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.edge.destroy(gl);
        self.far.destroy(gl);
        self.tonemapped.destroy(gl);
    }
}
