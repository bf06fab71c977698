//! What a frame is rendered with: the anti-aliasing method ([`AaMode`])
//! and the rest of the options ([`RenderOptions`]).

use super::pass::slots::GBufferSlots;
use crate::gbuffer::{GBufferLayout, MemoryBudget};
use crate::gl::ColorAttachment;
use crate::renderer::depth::DepthMode;
use crate::renderer::technique::smaa::options::{SmaaEdges, SmaaOptions};
use crate::renderer::technique::sparse::options::SparseOptions;
use crate::renderer::technique::taa::options::TaaOptions;
use crate::resolve::NormalEncoding;
use crate::resolve::{KeySource, ResolveSettings, ResolveSlot, SelectionFlag};
use crate::retrofit::{NormalAttachment, PositionSpace, RetrofitOptions};
use crate::second_layer::LayerMix;
use crate::{Error, Result};

/// How the frame is anti-aliased.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AaMode {
    /// No multisampling: the G-buffer pass draws into the single-sample
    /// G-buffer (method `none`).
    None,
    /// The G-buffer pass draws into the retrofit's multisampled twin, which
    /// the depth-aware resolve writes back into the G-buffer; lighting is
    /// per pixel (methods `average`, `front`, `median`, `back`).
    Resolve(ResolveSettings),
    /// Per-sample lighting (method `per-sample`), the reference quality of
    /// MSAA deferred lighting at N× the lighting cost: the multisampled
    /// G-buffer is not resolved for lighting; the lighting pass lights every
    /// sample of the twins (`texelFetch(sampler2DMS, p, i)`) with every
    /// light and averages the lit results after the tonemap curve (then
    /// maps the average back to HDR), so the tonemapped pixel is the box
    /// filter of its tonemapped samples, as in a supersampled image; a
    /// pixel whose samples all have one radiance keeps it exactly. (A plain
    /// HDR average lets a bright sample wash out the others: thin dark wires
    /// vanish against an HDR sky.) With more than 256 lights the pass draws
    /// once per 256 and the average is linear in HDR.
    ///
    /// The G-buffer is still resolved (the default median resolve) for the
    /// decal hook and for the depth test of transparent objects, but the lit
    /// image does not read it, so decals written into it are not lit.
    PerSample,
    /// Per-sample lighting on complex pixels only (method `complex`):
    /// complex pixels are marked in a stencil mask — a triangle edge crosses
    /// the pixel (the coverage mask `gl_SampleMaskIn` recorded by the
    /// G-buffer pass, where the context has it), or its samples differ in
    /// background, depth, normal or base colour (triangles that intersect,
    /// which coverage misses; the whole test without `gl_SampleMaskIn`).
    /// Two stencil-masked passes of the per-sample lighting program then
    /// light simple pixels once, from sample 0, and complex pixels per
    /// sample exactly as [`AaMode::PerSample`] does, so the image matches
    /// it wherever the detection is right. The G-buffer is resolved as with
    /// [`AaMode::PerSample`] (decals are not lit either). See
    /// [`technique::Complex::fraction`](super::technique::Complex::fraction) and [`technique::Complex::read_mask`](super::technique::Complex::read_mask).
    Complex,
    /// Geometry-buffer anti-aliasing (method `gbaa`, after Persson's GBAA,
    /// with fixes for converging edges): no multisampling. The G-buffer
    /// pass runs the unchanged model shaders through a geometry stage that
    /// also writes, per pixel, the distance to its triangle's nearest edge
    /// along x or y (`RG16F`) and to the triangle's far side (`R16F`);
    /// after the tonemap a post pass blends each pixel an edge crosses with
    /// the neighbour beyond it by the covered fraction, in linear light, in
    /// one bilinear fetch (two where a triangle thinner than a pixel puts
    /// both of its sides in the pixel), and leaves two pixels their own
    /// colours when their edges point at each other across a gap (a thin
    /// triangle between their centres). See [`technique::Gbaa::edge_textures`](super::technique::Gbaa::edge_textures)
    /// and [`technique::Gbaa::read_edges`](super::technique::Gbaa::read_edges).
    Gbaa,
    /// The multisampled G-buffer without its redundancy (method `sparse`):
    /// a multisampled depth pre-pass, then one G-buffer block per pixel and
    /// visible triangle, with the count of samples it covers, in per-pixel
    /// linked lists in shader storage buffers; lighting shades each block
    /// once and averages the blocks by their counts as
    /// [`AaMode::PerSample`] averages samples. Needs shader storage buffers,
    /// atomic counters and post-depth coverage; selective anti-aliasing by
    /// screen region, depth and object flag comes with it; no multisampled
    /// twins. See [`SparseOptions`] for how it works and what it needs,
    /// [`technique::Sparse::allocated`](super::technique::Sparse::allocated) and [`technique::Sparse::stats`](super::technique::Sparse::stats).
    Sparse(SparseOptions),
    /// Temporal anti-aliasing as engines ship it (method `taa`), a baseline
    /// to measure the others against in motion: one sample per pixel on
    /// top of `none`'s frame, every frame drawn with its projection shifted
    /// by a sub-pixel offset (Halton (2, 3), [`TaaOptions::phases`] of
    /// them in turn), then a resolve after the tonemap that reprojects the
    /// previous frames' accumulated history through this frame's depth and
    /// the previous frame's view-projection, clips it to this frame's 3x3
    /// neighbourhood in YCoCg (variance clipping) and blends
    /// [`TaaOptions::alpha`] of the new frame into it. The history and
    /// the previous camera live in the technique
    /// ([`technique::Taa`](super::technique::Taa)): render frame after
    /// frame, moving the camera with
    /// [`Renderer::set_camera`](super::Renderer::set_camera); a still frame
    /// is settled after [`AaMode::warmup_frames`] frames.
    Taa(TaaOptions),
}

impl AaMode {
    /// The settings of the G-buffer's resolve, when multisampling: those
    /// given with [`AaMode::Resolve`]; the default (median, smooth) for
    /// the other methods that draw into the twins ([`AaMode::PerSample`],
    /// [`AaMode::Complex`]), whose resolved G-buffer serves decals and
    /// transparent objects.
    pub fn settings(&self) -> Option<ResolveSettings> {
        match self {
            AaMode::Resolve(s) => Some(*s),
            other if other.is_multisampled() => Some(ResolveSettings::default()),
            _ => None,
        }
    }
}

/// What to render at which size and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Requested samples per pixel when multisampling (the driver's real
    /// count is used; see [`Renderer::samples`](super::Renderer::samples)). Ignored with [`AaMode::None`].
    pub samples: u32,
    /// Anti-aliasing of the G-buffer.
    pub aa: AaMode,
    /// Run the FXAA-style post filter after tonemapping.
    pub fxaa: bool,
    /// Run SMAA 1x ([`SmaaOptions`]) after tonemapping instead (not with
    /// [`RenderOptions::fxaa`]: each is a post filter of the tonemapped
    /// image; chaining them smooths twice). Default: `None`.
    pub smaa: Option<SmaaOptions>,
    /// The full G-buffer layout. It must have colour attachments named
    /// `color`, `position` and `normal`, and `specular` and `emissive`
    /// unless the scene does without them (in any order; others are allowed
    /// and left cleared). Default: [`GBufferLayout::recommended`].
    pub layout: GBufferLayout,
    /// Build the G-buffer from the scene-adaptive [`Plan`](super::plan::Plan): `layout` less
    /// what the scene does not need (see [`plan`](super::plan);
    /// [`Renderer::layout`](super::Renderer::layout) is what it became). `false`: `layout` as given.
    /// Default: `true`.
    pub adaptive: bool,
    /// The memory safety valve: the G-buffer's bytes are estimated before
    /// allocating and, over this budget, the sample count steps down with a
    /// warning ([`Renderer::warnings`](super::Renderer::warnings)) or, when strict, the renderer
    /// refuses with [`Error::MemoryBudget`](deferred_msaa::Error::MemoryBudget). Default: half the free video
    /// memory the driver reports, else 1 GiB, not strict.
    pub memory_budget: MemoryBudget,
    /// Standard depth or reversed-Z. Default: [`DepthMode::Auto`] (reversed-Z
    /// where the context and the layout's depth format allow it); see
    /// [`Renderer::depth_mode`](super::Renderer::depth_mode) for what it became.
    pub depth_mode: DepthMode,
    /// Draw the forward passes (transparent objects) into the retrofit's
    /// multisampled forward target
    /// ([`MsaaRetrofit::begin_forward`](deferred_msaa::MsaaRetrofit::begin_forward)),
    /// tested against the G-buffer's multisampled depth, and resolve them
    /// back into the lit image, so their silhouettes get MSAA too (the
    /// bench's `:forward`). Only with the methods that keep a retrofit
    /// (`average`, `front`, `median`, `back`, `per-sample`, `complex`).
    /// Default: `false`: forward objects are drawn single-sampled against
    /// the resolved depth.
    pub forward_msaa: bool,
    /// With two layers: what the renderer declares its lit values to be
    /// for the mix ([`LayerMix`]). `None` (the default): its own tonemap
    /// curve ([`LayerMix::Curve`]), the declaration that matches what it
    /// does; the bench's `:mix=linear`, `:mix=tonemapped` and `:mix=srgb`
    /// measure the others against the same reference.
    pub layer_mix: Option<LayerMix>,
}

impl Default for RenderOptions {
    /// 640×360, 4x MSAA with the default (median, smooth) resolve, no FXAA
    /// nor SMAA,
    /// the recommended layout adapted to the scene, the default memory
    /// budget, [`DepthMode::Auto`].
    fn default() -> Self {
        RenderOptions {
            width: 640,
            height: 360,
            samples: 4,
            aa: AaMode::Resolve(ResolveSettings::default()),
            fxaa: false,
            smaa: None,
            layout: GBufferLayout::recommended(),
            adaptive: true,
            memory_budget: MemoryBudget::default(),
            depth_mode: DepthMode::Auto,
            forward_msaa: false,
            layer_mix: None,
        }
    }
}

impl RenderOptions {
    /// Check sizes, sample count, resolve settings and the layout.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(format!(
                "the image size must be at least 1x1, got {}x{}",
                self.width, self.height
            )));
        }
        if let Some(settings) = self.aa.settings() {
            if self.samples == 0 {
                return Err(Error::invalid(
                    "a sample count of 0 is not a count; use 1 or more (or the `none` method)",
                ));
            }
            settings.validate()?;
        }
        if let AaMode::Sparse(sparse) = &self.aa {
            if self.samples == 0 {
                return Err(Error::invalid(
                    "a sample count of 0 is not a count; use 1 or more (or the `none` method)",
                ));
            }
            sparse.validate(self.samples)?;
        }
        if let AaMode::Taa(taa) = &self.aa {
            taa.validate()?;
        }
        if self.forward_msaa
            && !matches!(
                self.aa,
                AaMode::Resolve(_) | AaMode::PerSample | AaMode::Complex
            )
        {
            return Err(Error::invalid(format!(
                "forward MSAA draws into the multisampled G-buffer's depth, which `{}` does not keep; use it with average, front, median, back, upper-median, per-sample or complex",
                self.aa.technique_name()
            )));
        }
        if let Some(smaa) = &self.smaa {
            if self.fxaa {
                return Err(Error::invalid(
                    "FXAA and SMAA are both post filters of the tonemapped image; choose one",
                ));
            }
            if smaa.edges == SmaaEdges::Depth && !self.aa.fills_gbuffer() {
                return Err(Error::invalid(format!(
                    "SMAA's depth edges read the G-buffer's depth, which `{}` does not fill; use edges=luma or edges=color",
                    self.aa.name()
                )));
            }
        }
        self.layout.validate()?;
        GBufferSlots::of(&self.layout).map(|_| ())
    }

    /// The retrofit options for this layout, sample count and method: each
    /// attachment's rule, the position attachment as the depth key, and
    /// the resolve's settings, with `opt_out_flag` as the selective-AA flag
    /// unless the settings name one.
    pub(super) fn retrofit_options(&self, opt_out_flag: Option<SelectionFlag>) -> RetrofitOptions {
        let mut resolve = self.aa.settings().unwrap_or_default();
        if resolve.selection.flag.is_none() {
            resolve.selection.flag = opt_out_flag;
        }
        let (position_attachment, position_space) = match self.layout.key {
            KeySource::Position(ResolveSlot(k)) => {
                (Some(ColorAttachment(k as u32)), PositionSpace::View)
            }
            KeySource::WorldPosition(ResolveSlot(k)) => {
                (Some(ColorAttachment(k as u32)), PositionSpace::World)
            }
            KeySource::Depth => (None, PositionSpace::View),
        };
        RetrofitOptions {
            samples: self.samples,
            rules: self
                .layout
                .colors
                .iter()
                .enumerate()
                .map(|(k, a)| (ColorAttachment(k as u32), a.rule))
                .collect(),
            position_attachment,
            position_space,
            resolve,
            // The layouts' normals are xyz, named with one layer as with
            // two: clusters split by them, and a crease's reference is its
            // larger face, a tie by the pixel's parity (docs/resolve.md).
            // Measured on `builtin:ridges` at 320x180, one layer against
            // none 2.02x unnamed, 1.28x named (docs/bench.md).
            normal_attachment: GBufferSlots::of(&self.layout)
                .ok()
                .map(|slots| NormalAttachment {
                    attachment: ColorAttachment(slots.normal),
                    encoding: NormalEncoding::Xyz,
                }),
            layer_mix: self
                .layer_mix
                .clone()
                .unwrap_or_else(|| LayerMix::Curve(super::pass::tonemap::layer_mix_curve())),
            ..RetrofitOptions::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolve::{ResolveMethod, Window};

    #[test]
    fn method_specs_parse_through_the_registry() {
        let aa: AaMode = "median:hard:c=3".parse().unwrap();
        let AaMode::Resolve(s) = aa else {
            panic!("{aa:?}")
        };
        assert_eq!(
            (s.method, s.window, s.c),
            (ResolveMethod::Median, Window::Hard, 3.0)
        );
        assert_eq!("gbaa".parse::<AaMode>().unwrap(), AaMode::Gbaa);
        assert!(matches!(
            "sparse:pool=8".parse::<AaMode>().unwrap(),
            AaMode::Sparse(o) if o.pool_blocks == Some(8)
        ));
        assert_eq!(
            "taa:alpha=0.05:phases=16".parse::<AaMode>().unwrap(),
            AaMode::Taa(TaaOptions {
                alpha: 0.05,
                phases: 16
            })
        );
        for bad in [
            "sideways",
            "none:hard",
            "median:round",
            "sparse:pool=x",
            "",
            "taa:alpha=2",
            "taa:alpha=0",
            "taa:phases=0",
            "taa:phases=x",
            "taa:beta=1",
        ] {
            let e = bad.parse::<AaMode>().unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{bad}: {e}");
            assert!(e.contains(&format!("`{bad}")), "{bad}: {e}");
        }
        assert_eq!(
            AaMode::method_names(),
            [
                "none",
                "average",
                "front",
                "median",
                "back",
                "upper-median",
                "per-sample",
                "complex",
                "gbaa",
                "sparse",
                "taa"
            ]
        );
    }
}
