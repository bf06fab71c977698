//! What `deferred-msaa` with no subcommand does (and so `cargo run
//! --release`): the built-in default scene with no MSAA, the one-layer
//! resolve and the crate's best method, measured as the bench measures
//! them, then a side-by-side figure and a one-line summary.

use crate::bench::{self, BenchConfig};
use crate::context::Backend;
use crate::scene::DEFAULT_SCENE;
use crate::{Error, Result};
use std::io::IsTerminal;
use std::path::Path;

/// The methods compared: none, the one-layer resolve, the best method.
pub const FIRST_RUN_METHODS: &str = "none,median,median:layers=2";

/// Where the first run writes, relative to the working directory (beside
/// `render`'s default output).
pub const FIRST_RUN_DIR: &str = "target/deferred-msaa";

/// The bench configuration of the first run: the default scene at 640x360
/// and 4x, few frames (the run stays well under a minute on two cores).
pub fn first_run_config(backend: Backend) -> Result<BenchConfig> {
    Ok(BenchConfig {
        backend,
        scenes: vec![DEFAULT_SCENE.to_string()],
        methods: bench::parse_methods(FIRST_RUN_METHODS)?,
        frames: 5,
        warmup: 2,
        progress: std::io::stderr().is_terminal(),
        ..BenchConfig::default()
    })
}

/// The one-line summary: each run's FLIP against the reference and frame time.
pub fn summary_line(report: &bench::Report) -> String {
    let runs: Vec<String> = report
        .runs
        .iter()
        .map(|r| {
            let samples = if r.samples > 1 {
                format!(" {}x", r.samples)
            } else {
                String::new()
            };
            format!(
                "{}{samples}: FLIP {:.4}, {:.1} ms",
                r.method, r.flip_mean, r.ms_total
            )
        })
        .collect();
    let scene = report
        .runs
        .first()
        .map_or(DEFAULT_SCENE, |r| r.scene.as_str());
    let size = report
        .runs
        .first()
        .map_or(String::new(), |r| format!(" {}x{}", r.width, r.height));
    format!(
        "{scene}{size} against {} {} spp · {}",
        report.reference.method,
        report.reference.spp,
        runs.join(" · ")
    )
}

/// Run the first run into `dir`: `first-run.png` (the side-by-side) and
/// `first-run.txt` (the summary line), and print both paths.
pub fn run(backend: Backend, dir: &Path) -> Result<()> {
    let config = first_run_config(backend)?;
    bench::prepare_output_dir(dir)?;
    let output = bench::run(&config)?;
    let figure = dir.join("first-run.png");
    bench::write_side_by_side(&output, &figure)?;
    let line = summary_line(&output.report);
    let text = dir.join("first-run.txt");
    std::fs::write(&text, format!("{line}\n")).map_err(|e| Error::io(&text, e))?;
    println!("{line}");
    println!(
        "side-by-side -> {}; summary -> {} (`deferred-msaa render` writes one image, `bench` the full report)",
        figure.display(),
        text.display()
    );
    Ok(())
}
