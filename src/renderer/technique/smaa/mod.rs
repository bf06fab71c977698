//! SMAA 1x, the morphological post filter of Jimenez, Echevarria, Sousa
//! and Gutierrez ("SMAA: Enhanced Subpixel Morphological Antialiasing",
//! Eurographics 2012), written for this crate from the paper's description:
//! [`RenderOptions::smaa`](crate::renderer::RenderOptions::smaa), the method `smaa`
//! (`none` with SMAA) and `+smaa` after any bench entry.
//!
//! It runs after the tonemap (and after `gbaa`'s post pass) on the 8-bit
//! image, in three full-screen passes, each a module beside its shader:
//! 1. **edges** (`edges`, `smaa_edges.frag`): a pixel's left
//!    and top boundaries are edges where luma (or colour, or the view
//!    distance) changes by at least the threshold, and, for luma and
//!    colour, by at least half the largest change around it (local
//!    contrast adaptation: a weak step beside a strong one is not an edge),
//!    into an RG8 target;
//! 2. **blending weights** (`weights`, `smaa_weights.frag`):
//!    for each edge, walk along it to both ends two pixels per fetch (the
//!    search table), read the crossing edges at the ends, and look the
//!    areas up for that pattern and those distances (the area table);
//!    where two boundaries meet at a real corner the smoothing is scaled
//!    down (corner rounding); a run of one-pixel steps along a diagonal is
//!    weighed as one line (the diagonal table) — into an RGBA8 target;
//! 3. **neighbourhood blending** (`blend`, `smaa_blend.frag`):
//!    each pixel mixes in its neighbours across the edges by those areas, in
//!    linear light, along the axis where it takes most, into the final
//!    RGBA8 image. A pixel with no weight is copied bit for bit.
//!
//! The tables come from [`tables`], computed at set-up and
//! uploaded as linear UNORM textures (RG8, RG8 and R8; an sRGB upload
//! would bend every area).

pub(crate) mod blend;
pub(crate) mod edges;
pub(crate) mod options;
pub mod tables;
pub(crate) mod targets;
pub(crate) mod weights;

use crate::gl::{Format, GlObject, GpuTimer, Handle, Made, Texture2d, VertexArray, destroy_object};
use crate::renderer::timing::timed;
use crate::{Error, Result};
use blend::SmaaBlendPass;
use edges::{DepthInput, SmaaEdgesPass};
pub use options::{SmaaEdges, SmaaOptions, SmaaPreset};
use targets::SmaaTargets;
use weights::SmaaWeightsPass;

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
    /// [`tables::area_table`], RG8 UNORM.
    area: Texture2d,
    /// [`tables::search_table`], R8 UNORM.
    search: Texture2d,
    /// [`tables::diagonal_table`], RG8 UNORM.
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
                tables::AREA_WIDTH,
                tables::AREA_HEIGHT,
                Some(&tables::area_table()),
            )?);
            let search = made.keep(Texture2d::with_data(
                gl,
                "smaa search table",
                Format::R8,
                tables::SEARCH_WIDTH,
                tables::SEARCH_HEIGHT,
                Some(&tables::search_table()),
            )?);
            let diagonal = made.keep(Texture2d::with_data(
                gl,
                "smaa diagonal table",
                Format::Rg8,
                tables::DIAGONAL_WIDTH,
                tables::DIAGONAL_HEIGHT,
                Some(&tables::diagonal_table()),
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
        let edges_ms = timed(gl, timer, || {
            self.edges
                .draw(gl, options, &targets.edges, vao, image, depth, depth_input)
        })?;
        let weights_ms = timed(gl, timer, || {
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
        let blend_ms = timed(gl, timer, || {
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
