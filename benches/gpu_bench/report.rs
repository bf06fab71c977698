//! The reports: `report.json` and `report.md`.

use crate::check::*;
use crate::setup::*;
use crate::timing::*;
use deferred_msaa::gl::{Capabilities, TimerKind};
use deferred_msaa_headless::HeadlessContext;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;

pub(crate) fn stats_json(s: Option<Stats>, runs: &[f64]) -> Value {
    match s {
        Some(s) => json!({
            "median_ms": s.median,
            "q1_ms": s.q1,
            "q3_ms": s.q3,
            "min_ms": s.min,
            "max_ms": s.max,
            "runs_ms": runs,
        }),
        None => Value::Null,
    }
}

pub(crate) fn ms(s: Option<Stats>) -> String {
    s.map_or("–".into(), |s| format!("{:.3}", s.median))
}

pub(crate) fn md_escape(s: &str) -> String {
    s.replace('|', "\\|")
}

pub(crate) struct TimingOutcome {
    pub(crate) cases: Vec<CaseResult>,
    /// Counts not timed, and why.
    pub(crate) skipped: Vec<(u32, String)>,
    /// Counts whose timing failed, and the error.
    pub(crate) errors: Vec<(u32, String)>,
}

pub(crate) fn timer_name(k: TimerKind) -> &'static str {
    match k {
        TimerKind::GlTimeElapsed => "GL_TIME_ELAPSED query",
        TimerKind::FinishWallClock => "wall time between glFinish calls",
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn write_reports(
    args: &Args,
    ctx: &HeadlessContext,
    caps: &Capabilities,
    driver_counts: &[(&'static str, Vec<u32>)],
    checks: &[CheckEntry],
    timing: &TimingOutcome,
    headline: TimerKind,
    headline_reason: &str,
    has_query: bool,
    elapsed_s: f64,
    passed: bool,
    warnings: &[String],
) -> Result<(PathBuf, PathBuf), String> {
    let version = ctx.version();
    let other = match (headline, has_query) {
        (TimerKind::GlTimeElapsed, _) => Some(TimerKind::FinishWallClock),
        (TimerKind::FinishWallClock, true) => Some(TimerKind::GlTimeElapsed),
        (TimerKind::FinishWallClock, false) => None,
    };

    // JSON.
    let check_json: Vec<Value> = checks
        .iter()
        .map(|c| {
            let (status, detail) = match &c.offer {
                Offer::NotOffered(why) => ("not-offered", json!({ "reason": why })),
                Offer::Failed(why) => ("error", json!({ "reason": why })),
                Offer::Checked {
                    samples,
                    gl_samples,
                    comparisons,
                } => (
                    if c.passed() { "pass" } else { "fail" },
                    json!({
                        "samples": samples,
                        "gl_samples": gl_samples,
                        "comparisons": comparisons.iter().map(|k| json!({
                            "fast_path": k.fast_path,
                            "pass": k.failure.is_none(),
                            "failure": k.failure,
                            "pixels": k.pixels,
                            "slow_path_pixels": k.complex,
                            "ambiguous_pixels_skipped": k.ambiguous,
                            "values_compared": k.values,
                            "mismatches": k.mismatches,
                            "max_abs_error": k.max_abs_error,
                            "max_error_over_tolerance": k.max_over_tolerance,
                            "worst": k.worst,
                            "first_mismatches": k.first_mismatches,
                        })).collect::<Vec<_>>(),
                    }),
                ),
            };
            json!({
                "requested": c.requested,
                "layout": c.layout,
                "status": status,
                "detail": detail,
            })
        })
        .collect();
    let case_json: Vec<Value> = timing
        .cases
        .iter()
        .map(|c| {
            let methods = |kind: TimerKind| -> Value {
                let all = match kind {
                    TimerKind::GlTimeElapsed => &c.query,
                    TimerKind::FinishWallClock => &c.wall,
                };
                let st = c.stats(kind);
                Value::Array(
                    Method::ALL
                        .iter()
                        .enumerate()
                        .map(|(i, m)| {
                            json!({
                                "method": m.key(),
                                "label": m.label(c.colors),
                                "stats": stats_json(st[i], &all[i]),
                            })
                        })
                        .collect(),
                )
            };
            let ratios = |kind: TimerKind| match c.ratios(kind) {
                Some((f, n)) => {
                    json!({ "resolve_fast_over_blit": f, "resolve_nofast_over_blit": n })
                }
                None => Value::Null,
            };
            json!({
                "samples": c.samples,
                "layout": c.layout,
                "gbuffer": c.gbuffer,
                "timer": headline.name(),
                "methods": methods(headline),
                "ratios": ratios(headline),
                "other_timer": other.map(|o| json!({
                    "timer": o.name(),
                    "methods": methods(o),
                    "ratios": ratios(o),
                })),
            })
        })
        .collect();
    let unix_time = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let report = json!({
        "tool": "gpu_bench",
        "unix_time": unix_time,
        "quick": args.quick,
        "passed": passed,
        "elapsed_s": elapsed_s,
        "warnings": warnings,
        "context": {
            "backend": ctx.backend().name(),
            "renderer": version.renderer,
            "vendor": version.vendor,
            "gl_version": version.version_string,
            "glsl_version": version.glsl_string,
            "max_samples": caps.max_samples,
            "max_color_texture_samples": caps.max_color_texture_samples,
            "max_depth_texture_samples": caps.max_depth_texture_samples,
            "timer_query": caps.timer_query,
            "sample_counts": driver_counts.iter().map(|(k, v)| json!({ "layout": k, "counts": v })).collect::<Vec<_>>(),
        },
        "layouts": layouts().iter().map(|(k, _, l)| json!({ "layout": k, "gbuffer": describe_layout(l) })).collect::<Vec<_>>(),
        "check": {
            "width": CHECK_WIDTH,
            "height": CHECK_HEIGHT,
            "triangles": CHECK_TRIANGLES,
            "seed": args.seed,
            "settings": "median, smooth window, c 5, c_in 2.5; fast path on and off",
            "tolerances": "FP16 storage 1e-5 + 1.2e-3*|x|; FP32 1e-4*(1 + |x|); 8-bit one step (1/255); depth 1e-6",
            "counts": check_json,
        },
        "timing": {
            "width": args.width,
            "height": args.height,
            "triangles": TIMING_TRIANGLES,
            "runs": args.runs,
            "warmup": args.warmup,
            "interleaving": "round-robin over every (layout, method) pair of a count; each round starts one pair later",
            "timer": headline.name(),
            "timer_reason": headline_reason,
            "cases": case_json,
            "skipped": timing.skipped.iter().map(|(n, why)| json!({ "samples": n, "reason": why })).collect::<Vec<_>>(),
            "errors": timing.errors.iter().map(|(n, e)| json!({ "samples": n, "error": e })).collect::<Vec<_>>(),
        },
    });

    // Markdown.
    let mut md = String::new();
    let _ = writeln!(md, "# gpu-bench\n");
    let _ = writeln!(
        md,
        "- renderer: {} ({})\n- GL {} | GLSL {} | {} context\n- result: {}, {:.0} s{}\n",
        md_escape(&version.renderer),
        md_escape(&version.vendor),
        md_escape(&version.version_string),
        md_escape(&version.glsl_string),
        ctx.backend().name(),
        if passed { "pass" } else { "FAIL" },
        elapsed_s,
        if args.quick { ", --quick" } else { "" }
    );
    for w in warnings {
        let _ = writeln!(md, "**Warning:** {}\n", md_escape(w));
    }
    let _ = writeln!(
        md,
        "## Resolve against the CPU reference ({CHECK_WIDTH}x{CHECK_HEIGHT}, real rasterised samples)\n"
    );
    let _ = writeln!(
        md,
        "Median, smooth window. Tolerances: FP16 storage 1e-5 + 1.2e-3·\\|x\\|, FP32 1e-4·(1 + \\|x\\|), 8-bit 1/255, depth 1e-6.\n"
    );
    let _ = writeln!(
        md,
        "| requested | layout | real samples (GL_SAMPLES) | fast path | result | max abs error | worst error / tolerance | slow-path px (CPU) | ambiguous px (skipped) |"
    );
    let _ = writeln!(md, "|---:|---|---:|---|---|---:|---:|---:|---:|");
    for c in checks {
        match &c.offer {
            Offer::NotOffered(why) => {
                let _ = writeln!(
                    md,
                    "| {}x | {} | – | – | not offered ({}) | – | – | – | – |",
                    c.requested,
                    c.layout,
                    md_escape(why)
                );
            }
            Offer::Failed(why) => {
                let _ = writeln!(
                    md,
                    "| {}x | {} | – | – | ERROR: {} | – | – | – | – |",
                    c.requested,
                    c.layout,
                    md_escape(why)
                );
            }
            Offer::Checked {
                gl_samples,
                comparisons,
                ..
            } => {
                for k in comparisons {
                    let _ = writeln!(
                        md,
                        "| {}x | {} | {} | {} | {} | {:.3e} | {:.3} | {} | {} |",
                        c.requested,
                        c.layout,
                        gl_samples,
                        if k.fast_path { "on" } else { "off" },
                        match &k.failure {
                            None => "pass".to_string(),
                            Some(f) => format!("FAIL: {}", md_escape(f)),
                        },
                        k.max_abs_error,
                        k.max_over_tolerance,
                        k.complex,
                        k.ambiguous
                    );
                }
            }
        }
    }
    let _ = writeln!(
        md,
        "\n## Resolve against the hardware blit ({}x{}, {TIMING_TRIANGLES} random triangles + background)\n",
        args.width, args.height
    );
    let _ = writeln!(
        md,
        "Medians of {} runs after {} warm-up rounds, interleaved round-robin. Headline timer: {} ({}).\n",
        args.runs,
        args.warmup,
        timer_name(headline),
        md_escape(headline_reason)
    );
    let table = |md: &mut String, kind: TimerKind| {
        let _ = writeln!(
            md,
            "| samples | layout | resolve, fast path on, ms | resolve, fast path off, ms | blit (colour attachments + depth), ms | fast on / blit | fast off / blit |"
        );
        let _ = writeln!(md, "|---:|---|---:|---:|---:|---:|---:|");
        for c in &timing.cases {
            let st = c.stats(kind);
            let (f, n) = c.ratios(kind).map_or(("–".into(), "–".into()), |(f, n)| {
                (format!("{f:.3}"), format!("{n:.3}"))
            });
            let _ = writeln!(
                md,
                "| {}x | {} | {} | {} | {} ({}x + depth) | {f} | {n} |",
                c.samples,
                c.label,
                ms(st[0]),
                ms(st[1]),
                ms(st[2]),
                c.colors
            );
        }
    };
    table(&mut md, headline);
    if let Some(o) = other {
        let _ = writeln!(md, "\nThe same runs by {}:\n", timer_name(o));
        table(&mut md, o);
    }
    if !timing.skipped.is_empty() || !timing.errors.is_empty() {
        let _ = writeln!(md);
        for (n, why) in &timing.skipped {
            let _ = writeln!(md, "- {n}x not timed: {}", md_escape(why));
        }
        for (n, e) in &timing.errors {
            let _ = writeln!(md, "- {n}x timing failed: {}", md_escape(e));
        }
    }
    let _ = writeln!(md, "\nLayouts:\n");
    for (_, label, l) in layouts() {
        let _ = writeln!(md, "- {label}: {}", describe_layout(&l).join(", "));
    }

    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("creating {}: {e}", args.out.display()))?;
    let json_path = args.out.join("gpu-bench.json");
    let md_path = args.out.join("gpu-bench.md");
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    std::fs::write(&json_path, text + "\n")
        .map_err(|e| format!("writing {}: {e}", json_path.display()))?;
    std::fs::write(&md_path, md).map_err(|e| format!("writing {}: {e}", md_path.display()))?;
    Ok((json_path, md_path))
}
