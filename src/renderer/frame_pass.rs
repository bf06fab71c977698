//! The passes of the renderer's frame, by name: what the plan lists (and
//! `--explain` prints) and what each technique adds to it. A leaf module,
//! so that the plan and the techniques both name passes without naming
//! each other.

/// One pass of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pass {
    /// Clear the G-buffer pass's framebuffer.
    Clear,
    /// Draw the background, single-sampled, into its own texture.
    Background,
    /// Copy the background into every sample of the emissive attachment.
    BackgroundCopy,
    /// Opaque and alpha-tested models into the G-buffer.
    Geometry,
    /// The depth-aware resolve of the multisampled G-buffer.
    Resolve,
    /// The host's decal hook on the resolved G-buffer.
    Decals,
    /// Method `complex`: mark complex pixels in a stencil mask.
    ComplexMask,
    /// Per-pixel deferred lighting of the resolved G-buffer.
    Lighting,
    /// Lighting of every sample (methods `per-sample` and `complex`).
    PerSampleLighting,
    /// The resolve's second layer (`layers=2`): the same lighting pass
    /// again on the second layer, where its coverage is above 0, and the
    /// mix of the two lit layers (its resolve runs in `resolve`).
    SecondLayer,
    /// Alpha-blended objects, forward, single-sampled.
    Transparent,
    /// HDR to the 8-bit image.
    Tonemap,
    /// The FXAA post filter.
    Fxaa,
    /// SMAA 1x: its edge, blending-weight and neighbourhood-blending passes.
    Smaa,
    /// Method `gbaa`: the post pass that blends across the edges the
    /// G-buffer pass recorded (the geometry pass then also runs a geometry
    /// shader and writes the edge buffers).
    GbaaPost,
    /// Method `taa`: the resolve that blends the frame with the history
    /// reprojected from the frame before (every pass of the frame then
    /// draws with a jittered projection).
    TaaResolve,
    /// Method `sparse`: the multisampled depth-only pre-pass.
    SparseDepth,
    /// Method `sparse`: the G-buffer pass writing per-pixel block lists.
    SparseLists,
    /// Method `sparse`: lighting each block once, weighted by its samples.
    SparseLighting,
}

impl Pass {
    /// The pass's name in `--explain`.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Clear => "clear",
            Pass::Background => "background",
            Pass::BackgroundCopy => "background-copy",
            Pass::Geometry => "geometry",
            Pass::Resolve => "resolve",
            Pass::Decals => "decals",
            Pass::ComplexMask => "complex-mask",
            Pass::Lighting => "lighting",
            Pass::PerSampleLighting => "lighting-per-sample",
            Pass::SecondLayer => "second-layer",
            Pass::Transparent => "transparent",
            Pass::Tonemap => "tonemap",
            Pass::Fxaa => "fxaa",
            Pass::Smaa => "smaa",
            Pass::GbaaPost => "gbaa",
            Pass::TaaResolve => "taa",
            Pass::SparseDepth => "sparse-depth",
            Pass::SparseLists => "sparse-lists",
            Pass::SparseLighting => "sparse-lighting",
        }
    }
}
