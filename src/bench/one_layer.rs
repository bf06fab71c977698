//! The one-layer table: per scene and image size, what the default
//! one-layer resolve (`median`) and FreeSpace Open's rank (`upper-median`)
//! measure against no MSAA (`none`) in the same run: FLIP and its ratio,
//! halo pixels and the bar width error. `scripts/docs` writes it into
//! docs/bench.md with `cargo run --release --example one_layer_table`.

use super::layers::{cell, run, scene_name};
use super::report::Report;
use std::fmt::Write as _;

/// The entries the table reads; a report without one of them for a scene
/// leaves a dash.
pub const ONE_LAYER_METHODS: &[&str] = &["none", "median", "upper-median"];

/// One Markdown table over `reports` (each a bench run, e.g. one per image
/// size): a row per scene and size, and a last line counting the rows
/// where `median` is above `none`.
pub fn one_layer_table(reports: &[&Report]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| scene | size | FLIP none | **median** | × none | upper-median | × none | halo px none | median | upper-median | bar width px none | median | upper-median |"
    );
    let _ = writeln!(
        md,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let (mut rows, mut above) = (0, 0);
    for report in reports {
        for scene in report.scenes() {
            let get = |m: &str| run(report, scene, m);
            let flip = |m: &str| get(m).map(|r| r.flip_mean);
            let ratio = |m: &str| match (flip(m), flip("none")) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            };
            let halo = |m: &str| get(m).map(|r| r.halo_pixels as f64);
            let width = |m: &str| get(m).and_then(|r| r.bar_width_error_px);
            let size = get("none")
                .or(get("median"))
                .map_or_else(|| "–".into(), |r| format!("{}x{}", r.width, r.height));
            if let Some(r) = ratio("median") {
                rows += 1;
                above += usize::from(r > 1.0);
            }
            let _ = writeln!(
                md,
                "| `{}` | {size} | {} | **{}** | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                scene_name(scene),
                cell(flip("none"), 4),
                cell(flip("median"), 4),
                cell(ratio("median"), 2),
                cell(flip("upper-median"), 4),
                cell(ratio("upper-median"), 2),
                cell(halo("none"), 0),
                cell(halo("median"), 0),
                cell(halo("upper-median"), 0),
                cell(width("none"), 3),
                cell(width("median"), 3),
                cell(width("upper-median"), 3),
            );
        }
    }
    let _ = writeln!(
        md,
        "\n`median` above `none` on {above} of {rows} scene and size pairs."
    );
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::report::tests::{report, run as make_run};

    #[test]
    fn the_table_compares_each_rank_with_no_msaa_in_the_same_run() {
        let mut none = make_run("none", 1.0);
        none.flip_mean = 0.004;
        let mut median = make_run("median", 1.0);
        median.flip_mean = 0.003;
        let mut upper = make_run("upper-median", 1.0);
        upper.flip_mean = 0.006;
        let table = one_layer_table(&[&report(vec![none, median, upper])]);
        // 0.003 and 0.006 against 0.004.
        assert!(table.contains("| 0.75 |"), "{table}");
        assert!(table.contains("| 1.50 |"), "{table}");
        assert!(table.contains("above `none` on 0 of 1"), "{table}");
        // A scene without `median` counts in no row and shows dashes.
        let table = one_layer_table(&[&report(vec![make_run("none", 1.0)])]);
        assert!(table.contains("| – |"), "{table}");
        assert!(table.contains("on 0 of 0"), "{table}");
    }
}
