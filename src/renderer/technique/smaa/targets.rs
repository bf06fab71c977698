//! The textures SMAA's passes write, allocated with the renderer's other
//! targets when SMAA is on.

use crate::Result;
use crate::gl::{Format, GlObject, Handle, Made, destroy_object};
use crate::renderer::targets::ColorTarget;

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
