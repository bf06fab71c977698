//! SMAA 1x, the morphological post filter of Jimenez, Echevarria, Sousa
//! and Gutierrez ("SMAA: Enhanced Subpixel Morphological Antialiasing",
//! Eurographics 2012), written for this crate from the paper's description:
//! [`RenderOptions::smaa`](super::RenderOptions::smaa), the method `smaa`
//! (`none` with SMAA) and `+smaa` after any bench entry.
//!
//! It runs after the tonemap (and after `gbaa`'s post pass) on the 8-bit
//! image, in three full-screen passes, each a module beside its shader:
//! 1. **edges** ([`super::smaa_edges`], `smaa_edges.frag`): a pixel's left
//!    and top boundaries are edges where luma (or colour, or the view
//!    distance) changes by at least the threshold, and, for luma and
//!    colour, by at least half the largest change around it (local
//!    contrast adaptation: a weak step beside a strong one is not an edge),
//!    into an RG8 target;
//! 2. **blending weights** ([`super::smaa_weights`], `smaa_weights.frag`):
//!    for each edge, walk along it to both ends two pixels per fetch (the
//!    search table), read the crossing edges at the ends, and look the
//!    areas up for that pattern and those distances (the area table);
//!    where two boundaries meet at a real corner the smoothing is scaled
//!    down (corner rounding); a run of one-pixel steps along a diagonal is
//!    weighed as one line (the diagonal table) — into an RGBA8 target;
//! 3. **neighbourhood blending** ([`super::smaa_blend`], `smaa_blend.frag`):
//!    each pixel mixes in its neighbours across the edges by those areas, in
//!    linear light, along the axis where it takes most, into the final
//!    RGBA8 image. A pixel with no weight is copied bit for bit.
//!
//! The tables come from [`super::smaa_tables`], computed at set-up and
//! uploaded as linear UNORM textures (RG8, RG8 and R8; an sRGB upload
//! would bend every area).

use super::smaa_blend::SmaaBlendPass;
use super::smaa_edges::SmaaEdgesPass;
use super::smaa_tables;
use super::smaa_weights::SmaaWeightsPass;
use super::targets::ColorTarget;
use crate::gl::destroy_object;
use crate::gl::{Format, GlObject, GpuTimer, Handle, Made, Texture2d, VertexArray};
use crate::{Error, Result};
use std::str::FromStr;

/// SMAA's quality presets, with the reference implementation's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SmaaPreset {
    /// Threshold 0.15, 4 search steps, no diagonals, no corner rounding.
    Low,
    /// Threshold 0.1, 8 search steps, no diagonals, no corner rounding.
    Medium,
    /// Threshold 0.1, 16 search steps, 8 diagonal steps, corner rounding 25
    /// (the default).
    #[default]
    High,
    /// Threshold 0.05, 32 search steps, 16 diagonal steps, corner rounding 25.
    Ultra,
}

impl SmaaPreset {
    /// Every preset, by name.
    pub const ALL: [(SmaaPreset, &'static str); 4] = [
        (SmaaPreset::Low, "low"),
        (SmaaPreset::Medium, "medium"),
        (SmaaPreset::High, "high"),
        (SmaaPreset::Ultra, "ultra"),
    ];

    /// Its name (`low`, `medium`, `high`, `ultra`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map_or("high", |(_, n)| n)
    }

    /// The edge threshold: the least change of luma (or of a colour
    /// channel, 0..1 in the sRGB-encoded image) that is an edge.
    pub fn threshold(self) -> f32 {
        match self {
            SmaaPreset::Low => 0.15,
            SmaaPreset::Medium | SmaaPreset::High => 0.1,
            SmaaPreset::Ultra => 0.05,
        }
    }

    /// The walk's steps each way along an edge (two pixels a step).
    pub fn search_steps(self) -> u32 {
        match self {
            SmaaPreset::Low => 4,
            SmaaPreset::Medium => 8,
            SmaaPreset::High => 16,
            SmaaPreset::Ultra => 32,
        }
    }

    /// The cells walked each way along a diagonal run of one-pixel steps
    /// (`None`: diagonal runs are weighed as their orthogonal pieces).
    pub fn diagonal_steps(self) -> Option<u32> {
        match self {
            SmaaPreset::Low | SmaaPreset::Medium => None,
            SmaaPreset::High => Some(8),
            SmaaPreset::Ultra => Some(16),
        }
    }

    /// Corner rounding in percent: how much of the smoothing a sharp
    /// corner keeps (`None`: corners are not told apart from steps, and are
    /// smoothed fully).
    pub fn corner_rounding(self) -> Option<u32> {
        match self {
            SmaaPreset::Low | SmaaPreset::Medium => None,
            SmaaPreset::High | SmaaPreset::Ultra => Some(25),
        }
    }
}

/// What the edge pass compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SmaaEdges {
    /// The luma of the sRGB-encoded image (the default).
    #[default]
    Luma,
    /// Each colour channel: an edge where any one changes enough.
    Color,
    /// The view distance from the G-buffer's (resolved) depth: an edge
    /// where it jumps by more than the threshold relative to the nearer of
    /// the two (0.1: a tenth). Geometry edges only; no local contrast
    /// adaptation.
    Depth,
}

impl SmaaEdges {
    /// Every mode, by name.
    pub const ALL: [(SmaaEdges, &'static str); 3] = [
        (SmaaEdges::Luma, "luma"),
        (SmaaEdges::Color, "color"),
        (SmaaEdges::Depth, "depth"),
    ];

    /// Its name (`luma`, `color`, `depth`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(e, _)| *e == self)
            .map_or("luma", |(_, n)| n)
    }
}

/// SMAA's options: the preset and what the edge pass compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SmaaOptions {
    /// Threshold, search steps and corner rounding.
    pub preset: SmaaPreset,
    /// Luma, colour or depth edges.
    pub edges: SmaaEdges,
}

impl SmaaOptions {
    /// What [`SmaaOptions::from_str`] accepts, for error messages.
    pub const HELP: &'static str = "smaa options: preset=low|medium|high|ultra (default high), edges=luma|color|depth (default luma)";

    /// Parse options written `preset=P`, `edges=E` (the parts after the
    /// colons of `smaa:preset=ultra:edges=color`); `spec` names the whole
    /// entry in the one-line error.
    pub fn parse_options(options: &[&str], spec: &str) -> Result<SmaaOptions> {
        let mut out = SmaaOptions::default();
        for option in options {
            let bad = |what: &str| {
                Error::invalid(format!(
                    "`{spec}`: {what} `{option}`; {}",
                    SmaaOptions::HELP
                ))
            };
            let (key, value) = option
                .split_once('=')
                .ok_or_else(|| bad("unknown option"))?;
            match key {
                "preset" => {
                    out.preset = SmaaPreset::ALL
                        .iter()
                        .find(|(_, n)| *n == value)
                        .map(|(p, _)| *p)
                        .ok_or_else(|| bad("unknown preset in"))?;
                }
                "edges" => {
                    out.edges = SmaaEdges::ALL
                        .iter()
                        .find(|(_, n)| *n == value)
                        .map(|(e, _)| *e)
                        .ok_or_else(|| bad("unknown edge mode in"))?;
                }
                _ => return Err(bad("unknown option")),
            }
        }
        Ok(out)
    }
}

impl FromStr for SmaaOptions {
    type Err = Error;

    /// `preset=P:edges=E` (either, both or neither; empty: the defaults).
    fn from_str(s: &str) -> Result<Self> {
        let options: Vec<&str> = s.split(':').filter(|o| !o.is_empty()).collect();
        SmaaOptions::parse_options(&options, s)
    }
}

/// The textures the passes write: the edges (RG8, linearly filtered for the
/// two-pixel walk), the weights (RGBA8) and the output image (RGBA8).
#[derive(Debug)]
pub(crate) struct SmaaTargets {
    /// Left (`.r`) and top (`.g`) edges, 0 or 1.
    pub(crate) edges: ColorTarget,
    /// What each pixel takes across its top edge (`.r`), what the pixel
    /// above takes from it (`.g`), and the same across its left edge
    /// (`.b`, `.a`).
    pub(crate) weights: ColorTarget,
    /// The filtered image.
    pub(crate) out: ColorTarget,
}

impl SmaaTargets {
    /// Allocate the three at `width`×`height`.
    pub(crate) fn new(gl: &glow::Context, width: u32, height: u32) -> Result<Self> {
        Made::build(gl, |made| {
            let edges = made.keep(ColorTarget::new(
                gl,
                "smaa edges",
                Format::Rg8,
                width,
                height,
            )?);
            edges.texture.set_filter(gl, glow::LINEAR);
            let weights = made.keep(ColorTarget::new(
                gl,
                "smaa weights",
                Format::Rgba8,
                width,
                height,
            )?);
            let out = made.keep(ColorTarget::new(gl, "smaa", Format::Rgba8, width, height)?);
            Ok(SmaaTargets {
                edges,
                weights,
                out,
            })
        })
    }

    /// Free the three.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for SmaaTargets {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.edges.handles(out);
        self.weights.handles(out);
        self.out.handles(out);
    }
}

/// The time of each pass, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SmaaTimes {
    pub(crate) edges_ms: f64,
    pub(crate) weights_ms: f64,
    pub(crate) blend_ms: f64,
}

/// The three programs and the two tables, built when SMAA is first used.
#[derive(Debug)]
pub(crate) struct SmaaPasses {
    edges: SmaaEdgesPass,
    weights: SmaaWeightsPass,
    blend: SmaaBlendPass,
    /// [`smaa_tables::area_table`], RG8 UNORM.
    area: Texture2d,
    /// [`smaa_tables::search_table`], R8 UNORM.
    search: Texture2d,
    /// [`smaa_tables::diagonal_table`], RG8 UNORM.
    diagonal: Texture2d,
}

impl SmaaPasses {
    /// Compile the programs and upload the tables.
    pub(crate) fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            let area = made.keep(Texture2d::with_data(
                gl,
                "smaa area table",
                Format::Rg8,
                smaa_tables::AREA_WIDTH,
                smaa_tables::AREA_HEIGHT,
                Some(&smaa_tables::area_table()),
            )?);
            let search = made.keep(Texture2d::with_data(
                gl,
                "smaa search table",
                Format::R8,
                smaa_tables::SEARCH_WIDTH,
                smaa_tables::SEARCH_HEIGHT,
                Some(&smaa_tables::search_table()),
            )?);
            let diagonal = made.keep(Texture2d::with_data(
                gl,
                "smaa diagonal table",
                Format::Rg8,
                smaa_tables::DIAGONAL_WIDTH,
                smaa_tables::DIAGONAL_HEIGHT,
                Some(&smaa_tables::diagonal_table()),
            )?);
            Ok(SmaaPasses {
                edges: made.keep(SmaaEdgesPass::new(gl)?),
                weights: made.keep(SmaaWeightsPass::new(gl)?),
                blend: made.keep(SmaaBlendPass::new(gl)?),
                area,
                search,
                diagonal,
            })
        })
    }

    /// Run the three passes on `image` (the tonemapped RGBA8 image) into
    /// `targets.out`, timing each. `depth` (the G-buffer's depth texture)
    /// and `inverse_projection` serve depth edges.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        options: &SmaaOptions,
        targets: &SmaaTargets,
        vao: &VertexArray,
        image: &Texture2d,
        depth: &Texture2d,
        depth_input: DepthInput,
        timer: &mut GpuTimer,
    ) -> Result<SmaaTimes> {
        let edges_ms = super::timed(gl, timer, || {
            self.edges
                .draw(gl, options, &targets.edges, vao, image, depth, depth_input)
        })?;
        let weights_ms = super::timed(gl, timer, || {
            self.weights.draw(
                gl,
                options.preset,
                &targets.weights,
                vao,
                &targets.edges.texture,
                &self.area,
                &self.search,
                &self.diagonal,
            )
        })?;
        let blend_ms = super::timed(gl, timer, || {
            self.blend
                .draw(gl, &targets.out, vao, image, &targets.weights.texture)
        })?;
        Ok(SmaaTimes {
            edges_ms,
            weights_ms,
            blend_ms,
        })
    }
}

impl GlObject for SmaaPasses {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.edges.handles(out);
        self.weights.handles(out);
        self.blend.handles(out);
        self.area.handles(out);
        self.search.handles(out);
        self.diagonal.handles(out);
    }
}

/// SMAA on its own, on any RGBA8 image (sRGB-encoded values): what the
/// renderer runs after its tonemap, for a host's own images and for tests
/// that read each pass's output.
#[derive(Debug)]
pub struct SmaaFilter {
    passes: SmaaPasses,
    fullscreen: VertexArray,
    timer: GpuTimer,
}

/// What [`SmaaFilter::apply`] read back from each pass, row 0 at the top.
#[derive(Clone, Debug)]
pub struct SmaaOutput {
    /// The edges: `[0]` the pixel's left boundary, `[1]` its top one (255:
    /// an edge).
    pub edges: Vec<[u8; 2]>,
    /// The weights as UNORM bytes: `[0]` what the pixel takes from the one
    /// above, `[1]` what the one above takes from it, `[2]` and `[3]` the
    /// same with the pixel to the left.
    pub weights: Vec<[u8; 4]>,
    /// The filtered image.
    pub image: image::RgbaImage,
}

impl SmaaFilter {
    /// Compile the passes and upload the tables.
    pub fn new(gl: &glow::Context) -> Result<Self> {
        Made::build(gl, |made| {
            Ok(SmaaFilter {
                passes: made.keep(SmaaPasses::new(gl)?),
                fullscreen: made.keep(VertexArray::new(gl, "smaa filter triangle")?),
                timer: made.keep(GpuTimer::new(gl, false)?),
            })
        })
    }

    /// Filter `image` with `options` and read every pass back. Depth edges
    /// need the renderer's depth: [`SmaaEdges::Depth`] is refused here.
    pub fn apply(
        &mut self,
        gl: &glow::Context,
        image: &image::RgbaImage,
        options: &SmaaOptions,
    ) -> Result<SmaaOutput> {
        if options.edges == SmaaEdges::Depth {
            return Err(Error::invalid(
                "SmaaFilter has no depth to compare: use edges=luma or edges=color (the renderer runs depth edges)",
            ));
        }
        let (w, h) = image.dimensions();
        // GL's rows run bottom-up.
        let rows: Vec<u8> = image
            .as_raw()
            .chunks_exact((w * 4).max(1) as usize)
            .rev()
            .flatten()
            .copied()
            .collect();
        let input = Texture2d::with_data(gl, "smaa input", Format::Rgba8, w, h, Some(&rows))?;
        let result = SmaaTargets::new(gl, w, h).and_then(|targets| {
            let read = (|| {
                self.passes.draw(
                    gl,
                    options,
                    &targets,
                    &self.fullscreen,
                    &input,
                    &input,
                    DepthInput::new(&glam::Mat4::IDENTITY, false),
                    &mut self.timer,
                )?;
                let edges = targets
                    .edges
                    .fbo
                    .read_u8(gl, glow::RG, 2, "the SMAA edges")?;
                let weights = targets
                    .weights
                    .fbo
                    .read_u8(gl, glow::RGBA, 4, "the SMAA weights")?;
                let image = targets.out.read_rgba8(gl, "the SMAA image")?;
                Ok(SmaaOutput {
                    edges: edges.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
                    weights: weights
                        .chunks_exact(4)
                        .map(|c| [c[0], c[1], c[2], c[3]])
                        .collect(),
                    image,
                })
            })();
            targets.destroy(gl);
            read
        });
        input.destroy(gl);
        result
    }

    /// Free everything it made.
    pub fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for SmaaFilter {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.passes.handles(out);
        self.fullscreen.handles(out);
        self.timer.handles(out);
    }
}

/// How the edge pass turns a depth texel into a view distance: the depth
/// to NDC z (`ndc = depth · scale + offset`: standard depth −1..1 or
/// `GL_ZERO_TO_ONE`), then the inverse projection's z and w rows at
/// x = y = 0 (`z = a·ndc + b`, `w = c·ndc + d`; the distance is `−z / w`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DepthInput {
    /// `scale`, `offset`.
    pub(crate) to_ndc: [f32; 2],
    /// `a`, `b`, `c`, `d`.
    pub(crate) unproject: [f32; 4],
}

impl DepthInput {
    /// For `projection` with the clip control `zero_to_one`.
    pub(crate) fn new(projection: &glam::Mat4, zero_to_one: bool) -> DepthInput {
        let inverse = projection.inverse();
        // Row r, column c of a column-major glam matrix: col(c)[r].
        let at = |r: usize, c: usize| inverse.col(c)[r];
        DepthInput {
            to_ndc: if zero_to_one { [1.0, 0.0] } else { [2.0, -1.0] },
            unproject: [at(2, 2), at(2, 3), at(3, 2), at(3, 3)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_parse_and_refuse_in_one_line() {
        assert_eq!("".parse::<SmaaOptions>().unwrap(), SmaaOptions::default());
        let o: SmaaOptions = "preset=ultra:edges=color".parse().unwrap();
        assert_eq!((o.preset, o.edges), (SmaaPreset::Ultra, SmaaEdges::Color));
        assert_eq!(SmaaOptions::default().preset, SmaaPreset::High);
        for bad in ["preset=extreme", "edges=normal", "steps=3", "preset"] {
            let e = bad.parse::<SmaaOptions>().unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(
                e.contains(bad) && e.contains("preset=low|medium|high|ultra"),
                "{e}"
            );
        }
        let values: Vec<_> = SmaaPreset::ALL
            .iter()
            .map(|(p, _)| {
                (
                    p.threshold(),
                    p.search_steps(),
                    p.diagonal_steps(),
                    p.corner_rounding(),
                )
            })
            .collect();
        assert_eq!(
            values,
            [
                (0.15, 4, None, None),
                (0.1, 8, None, None),
                (0.1, 16, Some(8), Some(25)),
                (0.05, 32, Some(16), Some(25))
            ]
        );
    }
}
