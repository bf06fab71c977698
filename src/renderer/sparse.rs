//! Method `sparse` ([`AaMode::Sparse`]): the multisampled G-buffer without
//! its redundancy, as per-pixel linked lists of G-buffer blocks in shader
//! storage buffers. The design, the frame, selective anti-aliasing and the
//! requirements are documented on [`SparseOptions`] (public); the layout of
//! heads and blocks in `sparse.frag`.

#[path = "sparse_geometry.rs"]
mod sparse_geometry;
#[path = "sparse_lighting.rs"]
mod sparse_lighting;
#[path = "sparse_targets.rs"]
mod sparse_targets;

use super::lighting::LightBatch;
use super::mesh::GpuScene;
use super::pass::LightTarget;
use super::{AaMode, RenderOptions, Renderer};
use crate::gl::{Capabilities, Program, VertexArray};
use crate::resolve::Region;
use crate::{Error, Result};
use glow::HasContext;
pub(crate) use sparse_geometry::BuildParams;
use sparse_geometry::SparseBuildPasses;
pub(crate) use sparse_lighting::LightParams;
use sparse_lighting::SparseLightingPass;
use sparse_targets::{SparseTargets, TargetKey, prepass_format};
use std::cell::Cell;
use std::collections::HashSet;

/// The layout of heads and blocks and the region test, compiled in front
/// of every sparse pass (`sparse.frag`).
pub(crate) const SPARSE_FRAG: &str = include_str!("sparse.frag");

/// The extensions every sparse pass is compiled with, in this order.
pub(crate) const EXTENSIONS: &[&str] = &[
    "GL_ARB_shader_storage_buffer_object",
    "GL_ARB_shader_atomic_counters",
    "GL_ARB_gpu_shader5",
    "GL_ARB_shading_language_packing",
    "GL_ARB_shading_language_420pack",
    "GL_ARB_shader_image_load_store",
    "GL_ARB_post_depth_coverage",
];

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
pub const MAX_SPARSE_SAMPLES: u32 = sparse_lighting::MAX_SAMPLES;

/// Set a sparse program's region uniforms (the program must be bound).
/// Outside the region every pixel shows its sample 0; `None` is everywhere.
pub(crate) fn apply_region(
    gl: &glow::Context,
    program: &Program,
    region: &Option<Region>,
    height: u32,
) {
    // SPARSE_REGION_* in sparse.frag; the numbers are the resolve's own.
    let (kind, values) = match region {
        None => (0, [0.0; 4]),
        Some(r @ Region::Rect { .. }) => (2, r.window_uniform(height)),
        Some(r @ Region::Ellipse { .. }) => (3, r.window_uniform(height)),
    };
    program.set_i32(gl, "u_region_kind", kind);
    program.set_vec4(gl, "u_region", values.map(|v| v as f32));
}

/// Method `sparse` ([`AaMode::Sparse`]): the multisampled G-buffer without
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
///    [`AaMode::PerSample`] takes it, so the two agree up to the blocks'
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
/// extension list at run time; without them [`Renderer::new`] and
/// [`Renderer::set_options`] return [`Error::Unsupported`](deferred_msaa::Error::Unsupported) naming what is
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
    /// back to one sample ([`super::technique::Sparse::stats`] counts them).
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

/// The GPU memory [`AaMode::Sparse`] allocates, in bytes, by part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SparseMemory {
    /// Per-pixel heads: the list's first pool block and the flags (8 bytes a pixel).
    pub heads: u64,
    /// The first-block area: one 32-byte block per pixel.
    pub first_blocks: u64,
    /// The pool: [`SparseOptions::pool_capacity`] 32-byte blocks.
    pub pool: u64,
    /// The multisampled depth-stencil of the pre-pass.
    pub depth: u64,
    /// The two atomic counters.
    pub counters: u64,
}

impl SparseMemory {
    /// What [`AaMode::Sparse`] with `options` allocates for a
    /// `width`×`height` frame at `samples` samples with a depth format
    /// `depth` (the layout's; the pre-pass adds stencil), before allocating.
    pub fn planned(
        options: &SparseOptions,
        width: u32,
        height: u32,
        samples: u32,
        depth: crate::gl::Format,
    ) -> SparseMemory {
        use sparse_targets::{BLOCK_BYTES, COUNTER_BYTES, HEAD_BYTES};
        let pixels = u64::from(width) * u64::from(height);
        let pool = u64::from(options.pool_capacity(width, height).max(1));
        SparseMemory {
            heads: pixels * HEAD_BYTES,
            first_blocks: pixels * BLOCK_BYTES,
            pool: pool * BLOCK_BYTES,
            depth: pixels * u64::from(samples) * u64::from(prepass_format(depth).bytes_per_texel()),
            counters: COUNTER_BYTES as u64,
        }
    }

    /// Everything together.
    pub fn total(&self) -> u64 {
        self.heads + self.first_blocks + self.pool + self.depth + self.counters
    }
}

/// What the last [`AaMode::Sparse`] frame's G-buffer pass counted.
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

/// The value [`super::technique::Sparse::read_mask`] gives a pixel that fell back
/// to one sample because the pool ran out.
pub const MASK_OVERFLOW: u8 = 255;
/// The value [`super::technique::Sparse::read_mask`] gives a pixel that shows one
/// sample because a visible fragment is not to be anti-aliased (its
/// object's flag, or beyond the depth limit).
pub const MASK_SINGLE: u8 = 128;

/// Flag bits of a pixel's head (`sparse.frag`).
const FLAG_OVERFLOW: u32 = 2;
const FLAG_SINGLE: u32 = 4;

/// The extensions of [`EXTENSIONS`] that `available` lacks.
pub(crate) fn missing_extensions(available: &HashSet<String>) -> Vec<&'static str> {
    EXTENSIONS
        .iter()
        .copied()
        .filter(|e| !available.contains(*e))
        .collect()
}

/// [`Error::Unsupported`](deferred_msaa::Error::Unsupported) when `aa` is [`AaMode::Sparse`] and the context
/// lacks what it needs; `Ok` otherwise.
pub(crate) fn check_support(gl: &glow::Context, aa: &AaMode) -> Result<()> {
    if !matches!(aa, AaMode::Sparse(_)) {
        return Ok(());
    }
    let missing = missing_extensions(gl.supported_extensions());
    if missing.is_empty() {
        return Ok(());
    }
    let caps = Capabilities::query(gl);
    Err(deferred_msaa::Error::Unsupported {
        feature: "method `sparse` (per-pixel linked lists of G-buffer blocks)".into(),
        requires: format!(
            "{} (the shader storage buffers and atomic counters of OpenGL 4.3, and post-depth \
             coverage, reached from GLSL 1.50 through extensions)",
            missing.join(" and ")
        ),
        found: format!(
            "OpenGL {}.{}, {}{}",
            caps.version.0,
            caps.version.1,
            caps.renderer,
            if caps.storage_buffers {
                ""
            } else {
                ", no shader storage buffers"
            }
        ),
    }
    .into())
}

/// The programs and targets of [`AaMode::Sparse`]; the programs are built
/// when the method is first used and kept, the targets follow the options
/// and are freed when another method is chosen.
#[derive(Debug, Default)]
pub(crate) struct SparseState {
    build: Option<SparseBuildPasses>,
    lighting: Option<SparseLightingPass>,
    targets: Option<SparseTargets>,
    /// A frame has built the lists in the current targets.
    rendered: Cell<bool>,
}

impl SparseState {
    /// Bring programs and targets in line with `options`: for
    /// [`AaMode::Sparse`], build what is missing and (re)allocate the
    /// targets unless they match (new ones before the old are freed);
    /// otherwise free the targets.
    pub(crate) fn prepare(&mut self, gl: &glow::Context, options: &RenderOptions) -> Result<()> {
        let AaMode::Sparse(sparse) = options.aa else {
            self.release(gl);
            return Ok(());
        };
        check_support(gl, &options.aa)?;
        sparse.validate(options.samples)?;
        if self.build.is_none() {
            self.build = Some(SparseBuildPasses::new(gl)?);
        }
        if self.lighting.is_none() {
            self.lighting = Some(SparseLightingPass::new(gl)?);
        }
        let key = TargetKey {
            width: options.width,
            height: options.height,
            samples: options.samples,
            format: prepass_format(options.layout.depth),
            pool_capacity: sparse.pool_capacity(options.width, options.height),
        };
        if self.targets.as_ref().map(SparseTargets::key) != Some(key) {
            let targets = SparseTargets::new(gl, key)?;
            if let Some(old) = self.targets.replace(targets) {
                old.destroy(gl);
            }
            self.rendered.set(false);
        }
        Ok(())
    }

    /// The pre-pass's real sample count, once allocated.
    pub(crate) fn samples(&self) -> Option<u32> {
        self.targets.as_ref().map(SparseTargets::samples)
    }

    /// What the targets take, once allocated.
    pub(crate) fn memory(&self) -> Option<SparseMemory> {
        self.targets.as_ref().map(SparseTargets::memory)
    }

    fn parts(&self) -> Result<(&SparseBuildPasses, &SparseLightingPass, &SparseTargets)> {
        match (&self.build, &self.lighting, &self.targets) {
            (Some(b), Some(l), Some(t)) => Ok((b, l, t)),
            _ => Err(Error::invalid(
                "method `sparse` has no programs or targets (not prepared)",
            )),
        }
    }

    /// Steps 1–3 of the frame: the depth pre-pass, the set-up pass into
    /// the G-buffer's framebuffer `gbuffer_fbo`, and the G-buffer pass.
    pub(crate) fn build_lists(
        &self,
        gl: &glow::Context,
        scene: &GpuScene,
        gbuffer_fbo: glow::Framebuffer,
        vao: &VertexArray,
        params: &BuildParams<'_>,
    ) -> Result<()> {
        let (build, _, targets) = self.parts()?;
        build.draw_depth(gl, targets, scene, params)?;
        build.draw_setup(gl, targets, gbuffer_fbo, vao)?;
        let result = build.draw_blocks(gl, targets, scene, params);
        SparseTargets::unbind_buffers(gl);
        self.rendered.set(result.is_ok());
        result
    }

    /// Step 4: light the lists into `target`.
    pub(crate) fn light(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        batches: &[LightBatch],
        params: &LightParams<'_>,
    ) -> Result<()> {
        let (_, lighting, targets) = self.parts()?;
        lighting.draw(gl, target, vao, targets, batches, params)
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        if let Some(p) = self.build {
            p.destroy(gl);
        }
        if let Some(p) = self.lighting {
            p.destroy(gl);
        }
        if let Some(t) = self.targets {
            t.destroy(gl);
        }
    }
}

impl SparseState {
    /// Free the targets (another method was chosen); the programs stay.
    pub(crate) fn release(&mut self, gl: &glow::Context) {
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
        self.rendered.set(false);
    }

    /// What the last frame's G-buffer pass counted, read back from the
    /// atomic counters (this waits for the frame); `None` before the first
    /// frame.
    pub(crate) fn stats(&self, gl: &glow::Context) -> Result<Option<SparseStats>> {
        if !self.rendered.get() {
            return Ok(None);
        }
        let Some(targets) = self.targets.as_ref() else {
            return Ok(None);
        };
        let (pool_requested, overflow_pixels) = targets.read_counters(gl)?;
        Ok(Some(SparseStats {
            pool_capacity: targets.pool_capacity,
            pool_requested,
            overflow_pixels,
        }))
    }

    /// The last frame's one-sample pixels, read back from the heads (see
    /// [`super::technique::Sparse::read_mask`]); `None` before the first frame.
    pub(crate) fn read_mask(&self, gl: &glow::Context) -> Result<Option<image::GrayImage>> {
        if !self.rendered.get() {
            return Ok(None);
        }
        let Some(targets) = self.targets.as_ref() else {
            return Ok(None);
        };
        let flags = targets.read_flags(gl)?;
        let (w, h) = (targets.width as usize, targets.height as usize);
        if flags.len() != w * h {
            return Err(Error::invalid(format!(
                "the sparse heads hold {} pixels, not {w}x{h}",
                flags.len()
            )));
        }
        // The heads run bottom-up, as gl_FragCoord counts rows.
        let pixels: Vec<u8> = flags
            .chunks_exact(w.max(1))
            .rev()
            .flatten()
            .map(|&f| {
                if f & FLAG_OVERFLOW != 0 {
                    MASK_OVERFLOW
                } else if f & FLAG_SINGLE != 0 {
                    MASK_SINGLE
                } else {
                    0
                }
            })
            .collect();
        image::GrayImage::from_raw(w as u32, h as u32, pixels)
            .map(Some)
            .ok_or_else(|| Error::invalid("the sparse mask does not hold the image"))
    }
}

impl Renderer {
    /// Whether this context can render with `aa`: [`Error::Unsupported`](deferred_msaa::Error::Unsupported),
    /// naming what is missing, when it cannot. Of the methods, only
    /// [`AaMode::Sparse`] needs more than OpenGL 3.2 (the others fall back
    /// where a feature is missing); [`Renderer::new`] and
    /// [`Renderer::set_options`] make the same check.
    pub fn check_support(gl: &glow::Context, aa: &AaMode) -> Result<()> {
        check_support(gl, aa)
    }

    /// The fragment shader of [`AaMode::Sparse`]'s lighting pass exactly as
    /// compiled: `lighting.frag` (with `LIGHTING_FUNCTIONS_ONLY`),
    /// `tonemap.frag`'s curve, `complex.glsl` (the resolve's selection test),
    /// `sparse.frag`, then `sparse_lighting.frag`.
    pub fn sparse_lighting_program_source(&self) -> String {
        SparseLightingPass::source()
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

    #[test]
    fn missing_extensions_are_named() {
        let all: HashSet<String> = EXTENSIONS.iter().map(|e| e.to_string()).collect();
        assert!(missing_extensions(&all).is_empty());
        let mut some = all.clone();
        some.remove("GL_ARB_post_depth_coverage");
        some.remove("GL_ARB_shader_storage_buffer_object");
        assert_eq!(
            missing_extensions(&some),
            [
                "GL_ARB_shader_storage_buffer_object",
                "GL_ARB_post_depth_coverage"
            ]
        );
    }
}
