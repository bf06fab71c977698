//! The table printed after a run, and the summary of earlier reports.

use crate::measure::*;
use std::path::PathBuf;

pub(crate) fn print_table(st: &[Stats]) {
    println!(
        "  {:<40} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "method", "median ms", "q1", "q3", "IQR", "min", "max"
    );
    for (m, s) in Method::ALL.iter().zip(st) {
        println!(
            "  {:<40} {:>9.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
            m.label(),
            s.median,
            s.q1,
            s.q3,
            s.q3 - s.q1,
            s.min,
            s.max
        );
    }
}

/// The median of `method` in a report.
pub(crate) fn median_of(report: &serde_json::Value, method: &str) -> Option<f64> {
    report["methods"]
        .as_array()?
        .iter()
        .find(|m| m["method"] == method)?["median_ms"]
        .as_f64()
}

/// A markdown table of every report (`*.json`) in `dir`, in file-name order.
pub(crate) fn summarize(dir: &std::path::Path) -> Result<(), String> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("reading {}: {e}", dir.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(format!("no reports (*.json) in {}", dir.display()));
    }
    println!(
        "| scene | key | opt-in test | complex pixels | resolve, ms | blits, ms | resolve / blits | \
         resolve / always-slow | exact test / blits | always-slow / blits | \
         floor, exact test / blits | floor, position test / blits | changed by the opt-in test |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    let mut renderer = None;
    for path in &paths {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("reading {}: {e}", path.display()))?;
        let r: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a resolve_vs_blit report ({e})", path.display()))?;
        let median = |m: &str| {
            median_of(&r, m).ok_or_else(|| format!("{}: no median for {m}", path.display()))
        };
        let (floor_exact, floor_position) =
            (median("floor_exact_test")?, median("floor_position_test")?);
        let (fast, exact, slow, blit) = (
            median("resolve_median_smooth_fast")?,
            median("resolve_median_smooth_fast_exact")?,
            median("resolve_median_smooth_nofast")?,
            median("blit_x3_depth")?,
        );
        let scene = match r["scene"].as_str() {
            Some(s) => std::path::Path::new(s)
                .file_stem()
                .map_or(s.to_string(), |f| f.to_string_lossy().into_owned()),
            None => format!("{} random triangles", r["triangles"]),
        };
        let option = if r["position_uniformity"] == true {
            "position"
        } else if r["plane_uniformity"] == true {
            "plane"
        } else {
            "none (exact)"
        };
        let changed = if option.starts_with("none") {
            "".to_string()
        } else {
            format!(
                "{} px, by at most {:.2e}",
                r["option_changed_pixels"],
                r["option_max_difference"].as_f64().unwrap_or(f64::NAN)
            )
        };
        println!(
            "| {scene} | {} | {option} | {:.1} % | {fast:.1} | {blit:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {changed} |",
            r["key"].as_str().unwrap_or("?"),
            100.0 * r["complex_fraction"].as_f64().unwrap_or(f64::NAN),
            fast / blit,
            fast / slow,
            exact / blit,
            slow / blit,
            floor_exact / blit,
            floor_position / blit,
        );
        renderer.get_or_insert_with(|| {
            format!(
                "{}x{}, {}x, {} runs each, {}; {}",
                r["width"],
                r["height"],
                r["samples"],
                r["runs"],
                r["timer"].as_str().unwrap_or("?"),
                r["renderer"].as_str().unwrap_or("?")
            )
        });
    }
    if let Some(line) = renderer {
        println!("\n{line}");
    }
    Ok(())
}
