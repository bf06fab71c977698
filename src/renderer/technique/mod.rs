//! The anti-aliasing techniques of the frame: one type per technique (the
//! four resolve methods of [`AaMode::Resolve`] share one), each in its own
//! module beside the passes it adds.
//!
//! The renderer runs one frame for every technique (see the
//! [renderer's documentation](super)) and asks the technique for the steps
//! that differ: where the G-buffer pass draws and what it draws
//! (`Technique::geometry_target`, `Technique::draw_gbuffer`), what runs
//! after it (`Technique::after_geometry`: the resolve, for the methods
//! with multisampled twins), how the HDR target is lit
//! (`Technique::light`) and what follows the tonemap
//! (`Technique::tonemap_target`, `Technique::post`). Everything a
//! technique builds or allocates it owns and frees in
//! `Technique::destroy`.
//!
//! What is known of a technique before anything is built (its method
//! names and how their options parse, whether it draws into the
//! multisampled twins, which passes the plan lists for it, ...) is its
//! `Kind`, a unit type beside it that the options, the plan, the bench and
//! the command line ask.
//!
//! Adding a technique: its [`AaMode`] variant (the public option that
//! names it, with its options), a module here with a type implementing
//! `Technique` and a unit type implementing `Kind`, and its line in
//! `KINDS`.
//!
//! The public types here are the techniques whose own state a renderer
//! lends out, through [`Renderer::technique`](super::Renderer::technique).

mod complex;
mod contract;
pub(crate) mod fxaa;
mod gbaa;
mod kind;
mod none;
mod per_sample;
mod resolve;
pub mod smaa;
pub(crate) mod sparse;
pub(crate) mod taa;

use crate::renderer::options::{AaMode, RenderOptions};
use crate::{Error, Result};
pub use complex::Complex;
pub use contract::TechniqueState;
pub(crate) use contract::{
    ComplexPixelsInput, FrameCamera, FrameParts, GeometryStep, LightingStep, Setup, Technique,
};
pub use gbaa::Gbaa;
pub(crate) use kind::Kind;
pub(crate) use per_sample::PerSample;
pub(crate) use resolve::second_layer_bytes;
pub use sparse::Sparse;
pub use sparse::options::{
    DEFAULT_POOL_BLOCKS_PER_PIXEL, MAX_SPARSE_SAMPLES, SparseOptions, SparseStats,
};
pub use sparse::state::{MASK_OVERFLOW, MASK_SINGLE};
pub use sparse::targets::SparseMemory;
pub(crate) use sparse::{
    check_support as sparse_check_support, lighting_program_source as sparse_lighting_source,
};
use std::any::Any;
pub use taa::Taa;
pub use taa::options::{MAX_TAA_PHASES, TaaOptions};

/// Every technique, once. Adding a technique is one line here.
pub(crate) static KINDS: [&dyn Kind; 7] = [
    &none::Kind,
    &resolve::Kind,
    &per_sample::Kind,
    &complex::Kind,
    &gbaa::Kind,
    &sparse::Kind,
    &taa::Kind,
];

/// The kind of the technique that renders `aa`.
pub(crate) fn kind_of(aa: &AaMode) -> &'static dyn Kind {
    // Every AaMode has its kind: the registry's own tests check it.
    KINDS
        .iter()
        .copied()
        .find(|k| k.renders(aa))
        .unwrap_or_else(|| unreachable!("no technique renders {aa:?}"))
}

/// The kind whose methods include `method`.
pub(crate) fn kind_named(method: &str) -> Option<&'static dyn Kind> {
    KINDS
        .iter()
        .copied()
        .find(|k| k.methods().contains(&method))
}

/// Every method name, in the registry's order.
pub(crate) fn method_names() -> Vec<&'static str> {
    KINDS
        .iter()
        .flat_map(|k| k.methods().iter().copied())
        .collect()
}

/// What an [`AaMode`] is, as the registry knows it.
impl AaMode {
    /// `none`, the resolve method's name (`average`, `front`, `median`,
    /// `back`), `per-sample`, `complex`, `gbaa`, `sparse` or `taa`: the
    /// name a bench method entry starts with.
    pub fn name(&self) -> &'static str {
        kind_of(self).method_name(self)
    }

    /// Every method name, as [`AaMode::name`] gives them.
    pub fn method_names() -> Vec<&'static str> {
        method_names()
    }

    /// The technique that renders the method: its name, or `resolve` for
    /// the four resolve methods. Methods of one technique can share a
    /// renderer: switching between them changes nothing on the GPU.
    pub fn technique_name(&self) -> &'static str {
        kind_of(self).name()
    }

    /// How many frames the method renders from a fresh renderer (or after
    /// [`Renderer::reset_history`](crate::renderer::Renderer::reset_history)) before
    /// a still camera's image has settled: 0 but for [`AaMode::Taa`]
    /// ([`TaaOptions::warmup_frames`]). The bench renders them before it
    /// measures a still frame.
    pub fn warmup_frames(&self) -> u32 {
        kind_of(self).warmup_frames(self)
    }

    /// Whether the method renders more than one sample per pixel, so that
    /// [`RenderOptions::samples`] applies: into the multisampled twins, or
    /// into [`AaMode::Sparse`]'s pre-pass.
    pub fn takes_samples(&self) -> bool {
        kind_of(self).takes_samples()
    }

    /// Whether the G-buffer pass draws into the multisampled twins.
    pub fn is_multisampled(&self) -> bool {
        kind_of(self).draws_into_twins()
    }

    /// Whether the lighting pass lights samples of the multisampled
    /// G-buffer ([`AaMode::PerSample`], [`AaMode::Complex`]) rather than
    /// the resolved pixels.
    pub fn lights_per_sample(&self) -> bool {
        kind_of(self).lights_per_sample()
    }

    /// Whether the G-buffer pass fills the G-buffer's attachments.
    pub(crate) fn fills_gbuffer(&self) -> bool {
        kind_of(self).fills_gbuffer()
    }
}

impl std::str::FromStr for AaMode {
    type Err = Error;

    /// A method spec: a method name, then its options after colons
    /// (`median:hard:c=2`, `sparse:pool=64`, `gbaa`), as bench entries
    /// write them. The error is one line.
    fn from_str(spec: &str) -> Result<Self> {
        let mut parts = spec.split(':');
        let name = parts.next().unwrap_or("");
        let options: Vec<&str> = parts.collect();
        let kind = kind_named(name).ok_or_else(|| {
            Error::invalid(format!(
                "unknown method `{spec}`; methods: {}",
                method_names().join(", ")
            ))
        })?;
        kind.parse(name, &options, spec)
    }
}

/// The registry's techniques, with their state.
pub(crate) struct Techniques {
    all: Vec<(&'static dyn Kind, Box<dyn Technique>)>,
}

impl std::fmt::Debug for Techniques {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.all.iter().map(|(_, t)| t))
            .finish()
    }
}

impl Techniques {
    /// Every technique, nothing built yet.
    pub(crate) fn new() -> Self {
        Techniques {
            all: KINDS.iter().map(|&k| (k, k.build())).collect(),
        }
    }

    /// The technique that renders `aa`.
    pub(crate) fn active(&self, aa: &AaMode) -> &dyn Technique {
        let position = self.position(aa);
        &*self.all[position].1
    }

    /// The technique that renders `aa`, to prepare or draw with.
    pub(crate) fn active_mut(&mut self, aa: &AaMode) -> &mut dyn Technique {
        let position = self.position(aa);
        &mut *self.all[position].1
    }

    fn position(&self, aa: &AaMode) -> usize {
        // Every AaMode has its technique: the registry's own tests check it.
        self.all
            .iter()
            .position(|(k, _)| k.renders(aa))
            .unwrap_or_else(|| unreachable!("no technique renders {aa:?}"))
    }

    /// The technique of type `T` when it is the one that renders `aa`.
    pub(crate) fn get<T: Any>(&self, aa: &AaMode) -> Option<&T> {
        self.active(aa).as_any().downcast_ref::<T>()
    }

    /// Tell every technique that the options changed to ones `aa` renders.
    pub(crate) fn options_changed(&mut self, gl: &glow::Context, aa: &AaMode) {
        for (k, t) in &mut self.all {
            t.options_changed(gl, k.renders(aa));
        }
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        for (_, t) in self.all {
            t.destroy(gl);
        }
    }
}

/// The bytes the technique that renders `options.aa` allocates beside the
/// G-buffer and its twins, before anything is built (for the plan).
pub(crate) fn planned_memory(options: &RenderOptions) -> u64 {
    // An empty technique holds no GL object, so it is dropped, not destroyed.
    kind_of(&options.aa).build().memory(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolve::{ResolveMethod, ResolveSettings};

    #[test]
    fn every_method_has_one_technique() {
        let modes = [
            AaMode::None,
            AaMode::Resolve(ResolveSettings::default()),
            AaMode::Resolve(ResolveSettings {
                method: ResolveMethod::Average,
                ..ResolveSettings::default()
            }),
            AaMode::PerSample,
            AaMode::Complex,
            AaMode::Gbaa,
            AaMode::Sparse(Default::default()),
            AaMode::Taa(Default::default()),
        ];
        for aa in modes {
            assert_eq!(KINDS.iter().filter(|k| k.renders(&aa)).count(), 1, "{aa:?}");
            // A mode's method name parses back to a mode of the same kind.
            let name = kind_of(&aa).method_name(&aa);
            let kind = kind_named(name).expect("a method name of the registry");
            assert_eq!(kind.name(), kind_of(&aa).name(), "{aa:?}");
            let parsed = kind
                .parse(name, &[], name)
                .expect("a bare method name parses");
            assert_eq!(kind_of(&parsed).name(), kind.name());
        }
        let mut names = method_names();
        let all = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), all, "a method name belongs to one technique");
    }
}
