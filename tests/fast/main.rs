//! The fast tier of the lab's integration tests, one binary: what plain
//! `cargo test` runs, in minutes on two cores. The resolve against the CPU
//! reference, the retrofit, the goldens, reliability, the renderer, scenes,
//! the CLI, the host zoo, the C API from C and the C API under misuse, a Rust host on glow 0.17 through `deferred_msaa::foreign`. The slow tier (`tests/slow`) is the bench, the
//! examples under Xvfb and the viewer's long runs; `scripts/test` runs both.
//! The shared test kit (contexts and skips, the RNG, the host renderer and
//! its projections, goldens) is `tests/common`.

#[path = "../common/mod.rs"]
mod common;

mod budget;
mod capi;
mod cli;
mod context;
mod foreign;
mod gbaa;
mod gl_layer;
mod gltf_sources;
mod goldens;
mod host_equivalence;
mod host_habits;
mod inject;
mod lit_target;
mod misuse;
mod plan;
mod property;
mod reliability;
mod renderer;
mod resolve_layers;
mod retrofit;
mod scene;
mod selective;
mod silent_frames;
mod smaa;
mod sparse;
mod stability;
mod standalone;
mod structure;
mod taa;
mod three_surfaces;
mod zoo;
