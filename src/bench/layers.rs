//! The second layer's table: per scene and light setting, what
//! `median:layers=2` measures against `none`, `average`, `median`,
//! `per-sample` and the post filters FXAA and SMAA in the same run (FLIP, halo pixels, the bar width error, the
//! AA time), from the bench's reports. `scripts/docs` writes it into the
//! README with `cargo run --release --example layers_table`.

use super::report::{Report, Run};
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// The method entry the table is about.
pub const TWO_LAYERS: &str = "median:layers=2";

/// Every entry the table reads; a report without one of them for a scene
/// leaves a dash.
pub const TABLE_METHODS: &[&str] = &[
    "none",
    "average",
    "median",
    TWO_LAYERS,
    "per-sample",
    "none+fxaa",
    "median:layers=2+fxaa",
    "smaa",
    "median+smaa",
];

/// Load a `report.json`.
pub fn load_report(path: &Path) -> Result<Report> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::invalid(format!("reading {}: {e}", path.display())))?;
    serde_json::from_str(&text)
        .map_err(|e| Error::invalid(format!("{} is not a bench report: {e}", path.display())))
}

/// The run of `method` on `scene` in `report`, if it measured one.
pub(crate) fn run<'a>(report: &'a Report, scene: &str, method: &str) -> Option<&'a Run> {
    report
        .runs
        .iter()
        .find(|r| r.scene == scene && r.method == method)
}

/// A scene spec as a short name: `builtin:NAME`, or a path's file stem.
pub fn scene_name(spec: &str) -> String {
    if spec.starts_with("builtin:") {
        return spec.to_string();
    }
    Path::new(spec)
        .file_stem()
        .map_or_else(|| spec.to_string(), |s| s.to_string_lossy().into_owned())
}

/// A table cell: the value to `digits` places, or a dash.
pub(crate) fn cell(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".into(), |v| format!("{v:.digits$}"))
}

/// Two Markdown tables over `reports` (each a bench run, e.g. the scenes'
/// own lights and `--lights 48`): quality (FLIP of each method, the
/// two-layer ratio to `per-sample`, FXAA, SMAA, halo pixels, bar width) and cost
/// (AA time against `per-sample`'s, the second layer's own time and bytes).
pub fn layers_table(reports: &[&Report]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| scene | lights | FLIP none | average | median | **median:layers=2** | per-sample | layers=2 / per-sample | none+fxaa | layers=2+fxaa | smaa | median+smaa | halo px median | halo px layers=2 | bar width px median | bar width px layers=2 |"
    );
    let _ = writeln!(
        md,
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for report in reports {
        for scene in report.scenes() {
            let get = |m: &str| run(report, scene, m);
            let flip = |m: &str| get(m).map(|r| r.flip_mean);
            let ratio = match (flip(TWO_LAYERS), flip("per-sample")) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            };
            let lights = get(TWO_LAYERS).or(get("none")).map_or(0, |r| r.lights);
            let _ = writeln!(
                md,
                "| `{}` | {lights} | {} | {} | {} | **{}** | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                scene_name(scene),
                cell(flip("none"), 4),
                cell(flip("average"), 4),
                cell(flip("median"), 4),
                cell(flip(TWO_LAYERS), 4),
                cell(flip("per-sample"), 4),
                cell(ratio, 2),
                cell(flip("none+fxaa"), 4),
                cell(flip("median:layers=2+fxaa"), 4),
                cell(flip("smaa"), 4),
                cell(flip("median+smaa"), 4),
                cell(get("median").map(|r| r.halo_pixels as f64), 0),
                cell(get(TWO_LAYERS).map(|r| r.halo_pixels as f64), 0),
                cell(get("median").and_then(|r| r.bar_width_error_px), 3),
                cell(get(TWO_LAYERS).and_then(|r| r.bar_width_error_px), 3),
            );
        }
    }
    let _ = writeln!(md);
    let _ = writeln!(
        md,
        "| scene | lights | ms AA median | ms AA **median:layers=2** | of which the second lighting with its copies, mask and mix | ms AA per-sample | layers=2 / per-sample | second layer MiB | pixels with two clusters |"
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for report in reports {
        for scene in report.scenes() {
            let get = |m: &str| run(report, scene, m);
            let aa = |m: &str| get(m).map(|r| r.ms_aa);
            let ratio = match (aa(TWO_LAYERS), aa("per-sample")) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            };
            let extra_mib = match (get(TWO_LAYERS), get("median")) {
                (Some(a), Some(b)) => {
                    Some((a.gbuffer_bytes as f64 - b.gbuffer_bytes as f64) / (1024.0 * 1024.0))
                }
                _ => None,
            };
            let share = get(TWO_LAYERS)
                .and_then(|r| r.edge_pixel_share)
                .map(|s| 100.0 * s);
            let lights = get(TWO_LAYERS).or(get("none")).map_or(0, |r| r.lights);
            let _ = writeln!(
                md,
                "| `{}` | {lights} | {} | **{}** | {} | {} | {} | {} | {} % |",
                scene_name(scene),
                cell(aa("median"), 1),
                cell(aa(TWO_LAYERS), 1),
                cell(get(TWO_LAYERS).map(|r| r.ms_second_layer), 1),
                cell(aa("per-sample"), 1),
                cell(ratio, 2),
                cell(extra_mib, 1),
                cell(share, 1),
            );
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::report::tests::{report, run as make_run};

    #[test]
    fn the_table_compares_two_layers_with_per_sample_in_the_same_run() {
        let mut two = make_run(TWO_LAYERS, 1.0);
        two.flip_mean = 0.003;
        two.ms_aa = 30.0;
        let mut ps = make_run("per-sample", 1.0);
        ps.flip_mean = 0.002;
        ps.ms_aa = 60.0;
        let table = layers_table(&[&report(vec![make_run("none", 1.0), two, ps])]);
        // FLIP 0.003 against 0.002, AA 30 against 60 ms.
        assert!(table.contains("| 1.50 |"), "{table}");
        assert!(table.contains("| 0.50 |"), "{table}");
        // A method the run did not measure is a dash, never a number.
        assert!(table.contains("| – |"), "{table}");
    }
}
