//! The error-against-run-time benchmark behind `deferred-msaa bench`.
//!
//! For every scene it renders a reference — the whole pipeline at 4×4
//! supersampling (16 samples per pixel, tonemapped per sample, box-filtered
//! in linear light) — and then times every method entry ([`methods`]) at
//! every requested sample count, interleaved round-robin frame by frame so
//! that machine noise hits all methods alike: `warmup` untimed rounds, then
//! `frames` timed ones, whose median is reported. The last frame of each
//! method is compared with the reference (FLIP mean, PSNR, halo pixels),
//! its FLIP also split into the mean over the scene's edge pixels (those
//! holding two or more surface clusters, a mask made once per scene) and
//! over the rest, and, for a scene that declares thin bars, the error of
//! the bars' drawn width ([`bar_width`]).
//!
//! Methods whose switch changes nothing on the GPU (the resolve methods and
//! their options) share one [`Renderer`]; `none`, `+fxaa` and each sample
//! count get their own, so no frame pays for re-allocated targets.
//!
//! With [`BenchConfig::motion`] (`bench --motion SPEC`) every method
//! renders a camera path instead, against the reference of every frame
//! ([`motion`]; docs/motion.md).
//!
//! Outputs ([`write_outputs`]): `report.json` and `report.md`
//! ([`report`]), `error_vs_time.png` (FLIP mean against frame time per
//! scene, Pareto front marked) and `crops.png` (the same crop of every method
//! beside the reference). The plots need a TrueType font at run time:
//! Debian's `fonts-dejavu-core` (`/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf`),
//! or any `.ttf` named by the `DEFERRED_MSAA_FONT` environment variable.
//!
//! ```no_run
//! use deferred_msaa_lab::bench::{self, BenchConfig};
//! let config = BenchConfig { width: 320, height: 180, ..BenchConfig::default() };
//! let out = std::path::Path::new("target/bench");
//! bench::prepare_output_dir(out)?;
//! let output = bench::run(&config)?;
//! bench::write_outputs(&output, out)?;
//! # Ok::<(), deferred_msaa_lab::Error>(())
//! ```

pub mod bar_width;
mod bar_width_error;

mod animation;
mod config;
mod crops;
pub mod layers;
mod masks;
mod measure;
pub mod methods;
pub mod motion;
pub mod one_layer;
mod output;
mod pixels;
mod plot;
mod pool;
pub mod report;

pub use config::{
    BenchConfig, DEFAULT_SCENES, HALO_THRESHOLD, REFERENCE_SCALE, extra_lights, parse_size,
};
pub use methods::{MethodEntry, default_methods, parse_methods};
pub use output::{BenchOutput, motion_strip_name, write_images};
pub use pixels::downsample_srgb;
pub use report::{MotionMeasures, ProfileStep, Reference, Report, Run, pareto_front};

use crate::context::{GlVersion, HeadlessContext};
use crate::gbuffer::GBufferLayout;
use crate::renderer::Renderer;
use crate::{Error, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use measure::bench_scene;
use std::path::Path;

/// Create the report folder and load the plots' font, so that a bench does
/// not run for minutes only to fail at the end.
pub fn prepare_output_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    plot::load_font()
}

/// Write `report.json`, `report.md`, `error_vs_time.png` and `crops.png`
/// into `dir`; after a motion bench also `temporal_error_vs_time.png` and
/// each scene's animated crop strip, `motion-SCENE.png` (an APNG).
pub fn write_outputs(output: &BenchOutput, dir: &Path) -> Result<()> {
    prepare_output_dir(dir)?;
    output.report.write(dir)?;
    plot::error_vs_time(&output.report, &dir.join("error_vs_time.png"))?;
    if output.report.motion.is_some() {
        plot::temporal_error_vs_time(&output.report, &dir.join("temporal_error_vs_time.png"))?;
    }
    for (scene, frames) in &output.animations {
        animation::write_apng(frames, &dir.join(motion_strip_name(scene)))?;
    }
    crops::crops(output, &dir.join("crops.png"))
}

/// Write the first run's side-by-side figure: per scene, the reference's
/// and every run's whole frame above the same crop, magnified, each run
/// labelled with its FLIP and frame time.
pub fn write_side_by_side(output: &BenchOutput, path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        prepare_output_dir(dir)?;
    }
    crops::side_by_side(output, path)
}

/// Run the benchmark (see the [module documentation](self)).
pub fn run(config: &BenchConfig) -> Result<BenchOutput> {
    config.validate()?;
    let ctx = HeadlessContext::new(config.backend)?;
    let gl = ctx.gl();
    let version = GlVersion::query(gl);
    // The default list leaves out what this context cannot run (`sparse`
    // below OpenGL 4.3), with a warning; a list given explicitly fails on it
    // when its renderer is made.
    let trimmed;
    let config = if config.methods == default_methods() {
        let (kept, dropped): (Vec<&MethodEntry>, Vec<&MethodEntry>) = config
            .methods
            .iter()
            .partition(|e| Renderer::check_support(gl, &e.method).is_ok());
        for e in dropped {
            if let Err(why) = Renderer::check_support(gl, &e.method) {
                log::warn!(
                    "bench: `{}` left out of the default methods: {why}",
                    e.label
                );
            }
        }
        trimmed = BenchConfig {
            methods: kept.into_iter().cloned().collect(),
            ..config.clone()
        };
        &trimmed
    } else {
        config
    };
    let rounds = (config.warmup + config.motion.map_or(config.frames, |m| m.frames)) as u64;
    let ms_entries = config
        .methods
        .iter()
        .filter(|e| e.method.takes_samples())
        .count() as u64;
    let ss_entries = config.methods.len() as u64 - ms_entries;
    let jobs_per_scene = ms_entries * config.samples.len() as u64 + ss_entries;
    let per_scene = 1 + jobs_per_scene * rounds + 1;
    let pb = if config.progress {
        ProgressBar::with_draw_target(
            Some(per_scene * config.scenes.len() as u64),
            ProgressDrawTarget::stderr(),
        )
    } else {
        ProgressBar::hidden()
    };
    let style = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:30}] {pos}/{len} frames, eta {eta} · {msg}",
    )
    .map_err(|e| Error::invalid(format!("progress bar template: {e}")))?
    .progress_chars("=> ");
    pb.set_style(style);

    let mut report = Report {
        renderer: version.renderer.clone(),
        gl_version: version.version_string.clone(),
        reference: Reference {
            method: "ssaa".into(),
            spp: REFERENCE_SCALE * REFERENCE_SCALE,
        },
        runs: Vec::new(),
        backend: config.backend.name().to_string(),
        // With a camera path, the timed frames are the path's.
        frames: config.motion.map_or(config.frames, |m| m.frames),
        warmup: config.warmup,
        extra_lights: config.lights,
        motion: config.motion.map(|m| m.to_string()),
        layout: if config.layout == GBufferLayout::freespace_open() {
            "freespace-open".into()
        } else if config.layout == GBufferLayout::recommended() {
            "recommended".into()
        } else {
            "custom".into()
        },
    };
    let mut references = Vec::new();
    let mut images = Vec::new();
    let mut animations = Vec::new();
    for spec in &config.scenes {
        let measured = bench_scene(&ctx, config, spec, &pb, rounds)?;
        references.push((spec.clone(), measured.reference));
        for (run, image) in measured.runs {
            report.runs.push(run);
            images.push(image);
        }
        if let Some(frames) = measured.animation {
            animations.push((spec.clone(), frames));
        }
    }
    pb.finish_and_clear();
    Ok(BenchOutput {
        report,
        references,
        images,
        animations,
    })
}
