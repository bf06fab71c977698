//! The measurement behind `scripts/gpu-bench`: native sample counts checked
//! against the CPU reference, then the resolve timed against the hardware
//! resolve, for FreeSpace Open's G-buffer and the crate's recommended one.
//!
//! 1. Check. For each of 2, 4, 8 and 16 samples and both layouts, a small
//!    scene (random triangles over a background triangle that leaves one
//!    corner empty) is drawn into the retrofit's multisampled twins; the real
//!    count is read back (`GL_SAMPLES`), every sample of every attachment and
//!    of depth is read back, the GL resolve runs through `MsaaRetrofit`
//!    (fast path on and off), and every resolved value is compared with
//!    `resolve::cpu::CpuResolve` on the same samples, within the tolerances
//!    of `tests/fast/retrofit/` (FP16 storage `1e-5 + 1.2e-3·|x|`, FP32
//!    `1e-4·(1 + |x|)`, depth `1e-6`; 8-bit attachments one step, 1/255).
//!    A count the driver refuses or rounds to another is "not offered".
//! 2. Time. At 1920x1080 (`--quick`: 640x360), for each offered count (4x
//!    first, the others while `--budget-s` allows) and both layouts: the
//!    resolve with the fast path on and off, and the hardware resolve (one
//!    `glBlitFramebuffer` per colour attachment plus one for depth),
//!    interleaved round-robin, each run timed by `GL_TIME_ELAPSED` (where
//!    `GpuTimer` trusts it) and by `glFinish`-bracketed wall time.
//!
//! ```text
//! cargo bench --bench gpu_bench -- [--out DIR] [--quick] [--size WxH] [--runs K]
//!                                  [--warmup N] [--budget-s S] [--seed N]
//! ```
//! Writes `DIR/gpu-bench.json` and `DIR/gpu-bench.md` (default DIR:
//! `target/gpu-bench`). Exits 1 when no context can be made, when a check
//! fails or when a timed case errs (the reports are still written then).

mod check;
#[path = "../common/mod.rs"]
mod common;
mod report;
mod setup;
mod timing;

use check::*;
use deferred_msaa::Error;
use deferred_msaa::gl::{Capabilities, GpuTimer, TimerKind};
use deferred_msaa::readback::Readback;
use deferred_msaa_headless::{Backend, HeadlessContext};
use report::*;
use setup::*;
use std::process::ExitCode;
use std::time::Instant;
use timing::*;

fn run(args: &Args) -> Result<bool, String> {
    let started = Instant::now();
    Backend::Egl
        .check_library()
        .map_err(|e| format!("no OpenGL context: {e}"))?;
    let ctx = HeadlessContext::new(Backend::Egl)
        .map_err(|e| format!("no OpenGL context could be made (EGL): {e}"))?;
    let gl = ctx.gl();
    let version = ctx.version();
    let caps = Capabilities::query(gl);
    let software = ["llvmpipe", "softpipe", "swrast", "lavapipe"]
        .iter()
        .any(|s| version.renderer.to_lowercase().contains(s));
    let mut warnings = Vec::new();
    // libglvnd hands EGL to Mesa's surfaceless platform when Mesa is
    // installed beside the NVIDIA driver; the numbers would be llvmpipe's.
    if software && std::path::Path::new("/dev/nvidia0").exists() {
        warnings.push(
            "software renderer although /dev/nvidia0 exists: EGL chose Mesa, not the NVIDIA driver \
             (scripts/gpu-bench restricts EGL to NVIDIA's vendor library when it finds it)"
                .to_string(),
        );
    }
    for w in &warnings {
        eprintln!("[gpu_bench] warning: {w}");
    }
    eprintln!(
        "[gpu_bench] {} | GL {} | GLSL {}",
        version.renderer, version.version_string, version.glsl_string
    );
    let driver_counts: Vec<(&'static str, Vec<u32>)> = layouts()
        .iter()
        .map(|(key, _, l)| {
            let mut counts = Capabilities::sample_counts_for(gl, l.depth);
            for a in &l.colors {
                let c = Capabilities::sample_counts_for(gl, a.format);
                counts.retain(|n| c.contains(n));
            }
            (*key, counts)
        })
        .collect();
    for (key, counts) in &driver_counts {
        eprintln!(
            "[gpu_bench] {key}: the driver offers {}",
            counts_text(counts)
        );
    }
    let e = |e: Error| e.to_string();

    // 1. The check.
    let mut readback = Readback::new(gl).map_err(e)?;
    let model = Model::new(CHECK_WIDTH, CHECK_HEIGHT, CHECK_TRIANGLES, args.seed, true);
    let all_layouts = layouts();
    let mut checked: Vec<Vec<u32>> = vec![Vec::new(); all_layouts.len()];
    let mut checks = Vec::new();
    for requested in COUNTS {
        for (l, (key, _, layout)) in all_layouts.iter().enumerate() {
            let offer = check_count(
                gl,
                &mut readback,
                layout,
                requested,
                &model,
                &mut checked[l],
            )
            .unwrap_or_else(|err| Offer::Failed(err.to_string()));
            let entry = CheckEntry {
                requested,
                layout: key,
                offer,
            };
            let line = match &entry.offer {
                Offer::NotOffered(why) => format!("not offered ({why})"),
                Offer::Failed(why) => format!("ERROR: {why}"),
                Offer::Checked {
                    samples,
                    comparisons,
                    ..
                } => comparisons
                    .iter()
                    .map(|c| {
                        format!(
                            "{}x fast path {}: {} (max abs error {:.2e}, {:.2} of tolerance, {} slow-path px)",
                            samples,
                            if c.fast_path { "on" } else { "off" },
                            c.failure.as_deref().unwrap_or("pass"),
                            c.max_abs_error,
                            c.max_over_tolerance,
                            c.complex
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
            };
            eprintln!("[check] {requested}x {key}: {line}");
            checks.push(entry);
        }
    }
    readback.destroy(gl);

    // 2. The timing: what each layout was checked at, the headline count first.
    let mut counts: Vec<u32> = checked.iter().flatten().copied().collect();
    counts.sort_unstable();
    counts.dedup();
    let first = if counts.contains(&HEADLINE_SAMPLES) {
        Some(HEADLINE_SAMPLES)
    } else {
        counts.first().copied()
    };
    if let Some(f) = first {
        counts.retain(|&n| n != f);
        counts.insert(0, f);
    }
    let mut wall = GpuTimer::new(gl, true).map_err(e)?;
    let mut query = match GpuTimer::new(gl, false).map_err(e)? {
        q if q.kind() == TimerKind::GlTimeElapsed => Some(q),
        q => {
            q.destroy(gl);
            None
        }
    };
    let (headline, headline_reason) = match (&query, software) {
        (Some(_), _) => (
            TimerKind::GlTimeElapsed,
            "the context has GL_TIME_ELAPSED queries",
        ),
        (None, true) => (
            TimerKind::FinishWallClock,
            "software renderer: its GL_TIME_ELAPSED restarts at every tile a thread rasterises, so GpuTimer does not use it",
        ),
        (None, false) => (
            TimerKind::FinishWallClock,
            "the context has no GL_TIME_ELAPSED queries",
        ),
    };
    eprintln!(
        "[time] {}x{}, counts {}, timer: {}",
        args.width,
        args.height,
        counts_text(&counts),
        timer_name(headline)
    );
    let mut timing = TimingOutcome {
        cases: Vec::new(),
        skipped: Vec::new(),
        errors: Vec::new(),
    };
    let model = Model::new(args.width, args.height, TIMING_TRIANGLES, args.seed, false);
    // Seconds per sample of the first count's timing, to predict the others.
    let mut per_sample: Option<f64> = None;
    for (i, &n) in counts.iter().enumerate() {
        let here: Vec<_> = all_layouts
            .iter()
            .zip(&checked)
            .filter(|(_, c)| c.contains(&n))
            .map(|(l, _)| l.clone())
            .collect();
        let spent = started.elapsed().as_secs_f64();
        if i > 0 {
            let estimate = per_sample.map_or(0.0, |s| s * n as f64);
            if spent + estimate > args.budget_s {
                let why = format!(
                    "time budget: {spent:.0} s spent, about {estimate:.0} s more needed, budget {:.0} s",
                    args.budget_s
                );
                eprintln!("[time] {n}x skipped ({why})");
                timing.skipped.push((n, why));
                continue;
            }
        }
        eprintln!(
            "[time] {n}x: {} ({:.0} s)",
            here.iter().map(|l| l.0).collect::<Vec<_>>().join(", "),
            spent
        );
        let t0 = Instant::now();
        match time_count(gl, n, &here, &model, args, &mut wall, &mut query, started) {
            Ok(cases) => {
                for c in &cases {
                    if let Some((f, o)) = c.ratios(headline) {
                        eprintln!(
                            "[time] {n}x {}: resolve/blit {f:.3} (fast path on), {o:.3} (off)",
                            c.layout
                        );
                    }
                }
                timing.cases.extend(cases);
            }
            Err(err) => {
                eprintln!("[time] {n}x failed: {err}");
                timing.errors.push((n, err.to_string()));
            }
        }
        if per_sample.is_none() {
            per_sample = Some(t0.elapsed().as_secs_f64() / n as f64);
        }
    }
    let has_query = query.is_some();
    wall.destroy(gl);
    if let Some(q) = query {
        q.destroy(gl);
    }

    let checks_pass = checks.iter().all(CheckEntry::passed);
    let nothing_checked = checked.iter().all(|c| c.is_empty());
    let passed = checks_pass && !nothing_checked && timing.errors.is_empty();
    let elapsed = started.elapsed().as_secs_f64();
    let (json_path, md_path) = write_reports(
        args,
        &ctx,
        &caps,
        &driver_counts,
        &checks,
        &timing,
        headline,
        headline_reason,
        has_query,
        elapsed,
        passed,
        &warnings,
    )?;

    // The summary.
    println!(
        "gpu_bench: {} | GL {} ({:.0} s)",
        version.renderer, version.version_string, elapsed
    );
    for c in &checks {
        let status = match &c.offer {
            Offer::NotOffered(why) => format!("not offered ({why})"),
            Offer::Failed(why) => format!("ERROR ({why})"),
            Offer::Checked { comparisons, .. } => {
                let worst = comparisons
                    .iter()
                    .map(|k| k.max_abs_error)
                    .fold(0.0, f64::max);
                format!(
                    "{} (max abs error {worst:.2e})",
                    if c.passed() { "pass" } else { "FAIL" }
                )
            }
        };
        println!("  check {:>2}x {:<15} {status}", c.requested, c.layout);
    }
    for c in &timing.cases {
        let st = c.stats(headline);
        match c.ratios(headline) {
            Some((f, n)) => println!(
                "  time  {:>2}x {:<15} resolve {} ms (fast path off {} ms), blit {} ms: ratio {f:.3} ({n:.3} off) [{}]",
                c.samples,
                c.layout,
                ms(st[0]),
                ms(st[1]),
                ms(st[2]),
                headline.name()
            ),
            None => println!("  time  {:>2}x {:<15} no timings", c.samples, c.layout),
        }
    }
    for (n, why) in &timing.skipped {
        println!("  time  {n:>2}x skipped: {why}");
    }
    for (n, err) in &timing.errors {
        println!("  time  {n:>2}x ERROR: {err}");
    }
    if nothing_checked {
        println!("  no sample count could be checked");
    }
    println!("wrote {} and {}", json_path.display(), md_path.display());
    Ok(passed)
}

fn main() -> ExitCode {
    let args = parse_args();
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => {
            eprintln!("gpu_bench: a check or a timed case failed (see the report)");
            ExitCode::FAILURE
        }
        Err(msg) => {
            eprintln!("gpu_bench: {msg}");
            ExitCode::FAILURE
        }
    }
}
