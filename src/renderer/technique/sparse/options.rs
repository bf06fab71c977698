//! Method `sparse`'s public options and what it reports: the pool's size,
//! the anti-aliased region, the depth limit, its memory and its counters.

use super::shader::MAX_SAMPLES;
use crate::resolve::Region;
use crate::{Error, Result};

/// Pool blocks per pixel when [`SparseOptions::pool_blocks`] is `None`.
///
/// A pixel needs a pool block for every visible fragment beyond the one in
/// sample 0, so only pixels an edge crosses take any. Measured at 640×360
/// 4x: the built-in scenes take 0.01 to 0.07 blocks per pixel except
/// `builtin:hull` (0.19), FlightHelmet 0.11, 2CylinderEngine 0.16; half a
/// block per pixel leaves those 2.5 times the room (smaller images have
/// more edge pixels per pixel).
pub const DEFAULT_POOL_BLOCKS_PER_PIXEL: f64 = 0.5;

/// The most samples per pixel the sparse G-buffer takes.
pub const MAX_SPARSE_SAMPLES: u32 = MAX_SAMPLES;

/// Method `sparse` ([`AaMode::Sparse`](crate::renderer::AaMode::Sparse)): the multisampled G-buffer without
/// its redundancy, as per-pixel linked lists of G-buffer blocks in shader
/// storage buffers.
///
/// A 4x multisampled G-buffer stores every attribute four times, although
/// in most pixels one triangle covers all four samples and the four copies
/// are equal. Here the G-buffer holds one block per *fragment* (one triangle
/// in one pixel) that is visible in at least one sample, with the number of
/// samples it is visible in; lighting then shades each block once and
/// weights it by that count, which is per-sample lighting's result for a
/// fraction of its work and memory.
///
/// # The frame
///
/// 1. **Depth pre-pass** (`sparse_depth.frag`): every opaque and
///    alpha-tested object into an N-sample depth-stencil texture, depth only
///    (the alpha test of `geometry.frag` is repeated so cut-out texels do
///    not hide what is behind them).
/// 2. **Set-up** (`sparse_setup.frag`, full screen): empties every pixel's
///    list and writes sample 0's depth into the single-sample G-buffer's
///    depth (the decal hook reads it; transparent objects are tested
///    against it).
/// 3. **G-buffer pass** (`geometry.frag` unchanged, wrapped by
///    `sparse_geometry.frag`): the objects again into the pre-pass's
///    framebuffer, one fragment shader invocation per pixel and triangle,
///    depth test EQUAL against the pre-pass depth, early, with
///    `GL_ARB_post_depth_coverage` so that `gl_SampleMaskIn` holds exactly
///    the samples in which this fragment is the visible surface; its
///    popcount is the block's sample count, its lowest bit the block's
///    sample index. **The stencil bit keeps blocks unique**: the stencil is
///    cleared to 0, tested EQUAL 0 and incremented where the depth test
///    passes, so the first fragment that passes in a sample claims it; where
///    triangles intersect or are coplanar, a second fragment with bitwise
///    the same depth in that sample fails the stencil test there (the same
///    choice a multisampled G-buffer's depth test LESS makes). Every visible
///    sample thus belongs to exactly one fragment.
///    The fragment that owns sample 0 writes the pixel's pre-allocated
///    first block; every other fragment takes a block from the pool through
///    an atomic counter and pushes it onto the pixel's list. Each allocation
///    is bounds-checked against the pool's capacity: past it nothing is
///    written, the pixel is flagged and counted once (a second atomic
///    counter), and it falls back to one sample, its first block.
/// 4. **Lighting** (`sparse_lighting.frag`): per pixel, every block of the
///    list is shaded once with `lighting.frag`'s `shade_surface()` and
///    weighted by its sample count / N; samples no block covers show the
///    background. The average is taken after the tonemap curve, as
///    [`AaMode::PerSample`](crate::renderer::AaMode::PerSample) takes it, so the two agree up to the blocks'
///    packing (see `sparse.frag`); the tonemapped values are summed in
///    fixed point, so the image does not depend on the order of the list
///    (which fragment took a pool block first).
///
/// The rest of the frame (background, decal hook, transparent objects,
/// tonemap, FXAA) is the renderer's usual one. The single-sample G-buffer's
/// colour attachments are cleared but not written: the attributes live in
/// the blocks, so what a decal hook draws into them is not lit.
///
/// # Selective anti-aliasing
///
/// The same passes anti-alias only where asked ([`SparseOptions`]): a pixel
/// outside [`SparseOptions::region`], one where a visible fragment is
/// farther than [`SparseOptions::max_depth`], and one where a visible
/// fragment belongs to an object whose [`Object::antialias`] is `false`
/// shows its sample 0 only, exactly as the single-sample path does (an
/// empty region makes every pixel so), and takes no pool block.
///
/// # Requirements
///
/// Shader storage buffers and atomic counters (OpenGL 4.3, or
/// `GL_ARB_shader_storage_buffer_object` and `GL_ARB_shader_atomic_counters`),
/// reached from GLSL 1.50 through extensions, with `GL_ARB_gpu_shader5`,
/// `GL_ARB_shading_language_packing`, `GL_ARB_shading_language_420pack`,
/// `GL_ARB_shader_image_load_store` (all core by OpenGL 4.3) and
/// `GL_ARB_post_depth_coverage`. They are checked against the context's
/// extension list at run time; without them [`Renderer::new`](crate::renderer::Renderer::new) and
/// [`Renderer::set_options`](crate::renderer::Renderer::set_options) return [`Error::Unsupported`](deferred_msaa::Error::Unsupported) naming what is
/// missing. The pre-pass requests [`RenderOptions::samples`] (at most 32).
///
/// [`Object::antialias`]: crate::scene::Object::antialias
/// [`RenderOptions::samples`]: super::RenderOptions::samples
///
/// # Options
///
/// The pool's size, the anti-aliased region and the depth limit; the
/// default anti-aliases everywhere with [`DEFAULT_POOL_BLOCKS_PER_PIXEL`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SparseOptions {
    /// Blocks in the pool, shared by all pixels, for the fragments beyond
    /// each pixel's first. `None`: [`DEFAULT_POOL_BLOCKS_PER_PIXEL`] per
    /// pixel. When the pool runs out, the pixels that asked for more fall
    /// back to one sample ([`crate::renderer::technique::Sparse::stats`] counts them).
    pub pool_blocks: Option<u32>,
    /// Where to anti-alias (the resolve's selective-AA region; `None`:
    /// everywhere). Pixel centres inside are anti-aliased, the others show
    /// their sample 0.
    pub region: Option<Region>,
    /// View-space distance beyond which a fragment is not anti-aliased
    /// (its pixel shows sample 0); `None`: no limit.
    pub max_depth: Option<f32>,
}

impl Default for SparseOptions {
    /// The default pool, everywhere, no depth limit.
    fn default() -> Self {
        SparseOptions {
            pool_blocks: None,
            region: None,
            max_depth: None,
        }
    }
}

impl SparseOptions {
    /// The pool's capacity in blocks for a `width`×`height` image.
    pub fn pool_capacity(&self, width: u32, height: u32) -> u32 {
        self.pool_blocks.unwrap_or_else(|| {
            let pixels = f64::from(width) * f64::from(height);
            (pixels * DEFAULT_POOL_BLOCKS_PER_PIXEL)
                .ceil()
                .min(f64::from(u32::MAX)) as u32
        })
    }

    /// Check the depth limit, the region and the sample count.
    pub fn validate(&self, samples: u32) -> Result<()> {
        if samples > MAX_SPARSE_SAMPLES {
            return Err(Error::invalid(format!(
                "method `sparse` takes at most {MAX_SPARSE_SAMPLES} samples per pixel, got {samples}"
            )));
        }
        if let Some(d) = self.max_depth {
            if d.is_nan() || d <= 0.0 {
                return Err(Error::invalid(format!(
                    "method `sparse`: the anti-aliasing depth limit must be a positive distance, got {d}"
                )));
            }
        }
        if let Some(region) = &self.region {
            region.validate()?;
        }
        Ok(())
    }
}

/// What the last [`AaMode::Sparse`](crate::renderer::AaMode::Sparse) frame's G-buffer pass counted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SparseStats {
    /// Blocks the pool holds.
    pub pool_capacity: u32,
    /// Blocks fragments asked the pool for, those refused included.
    pub pool_requested: u32,
    /// Pixels that asked for a block when the pool was empty, and fell back
    /// to one sample.
    pub overflow_pixels: u32,
}

impl SparseStats {
    /// Blocks the pool handed out.
    pub fn pool_used(&self) -> u32 {
        self.pool_requested.min(self.pool_capacity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_checked() {
        assert!(SparseOptions::default().validate(4).is_ok());
        assert!(SparseOptions::default().validate(64).is_err());
        for d in [0.0, -1.0, f32::NAN] {
            let o = SparseOptions {
                max_depth: Some(d),
                ..SparseOptions::default()
            };
            let e = o.validate(4).unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        let o = SparseOptions {
            region: Some(Region::Ellipse {
                x: 1.0,
                y: f64::INFINITY,
                rx: 1.0,
                ry: 1.0,
            }),
            ..SparseOptions::default()
        };
        assert!(o.validate(4).is_err());
        assert_eq!(SparseOptions::default().pool_capacity(640, 360), 115_200);
        let fixed = SparseOptions {
            pool_blocks: Some(7),
            ..SparseOptions::default()
        };
        assert_eq!(fixed.pool_capacity(640, 360), 7);
    }
}
