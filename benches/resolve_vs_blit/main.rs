//! The depth-aware resolve against the hardware resolve, measured in one run.
//!
//! A host G-buffer (RGBA16F colour, RGBA16F view-space position, RGBA16F
//! normal, DEPTH32F) is retrofitted with MSAA; its multisampled twin is drawn
//! once with a scene of a few hundred small-to-medium triangles over a big
//! background triangle, and then these are timed, interleaved round-robin so
//! that machine noise hits every method alike:
//!
//! 1. `MsaaRetrofit::resolve`, median, smooth window, fast path on (with the
//!    opt-in uniformity test when one is asked for);
//! 2. the same with the exact uniformity test (the same as 1 without an
//!    opt-in test: then the pair shows the run's noise);
//! 3. the same with the fast path off (every pixel takes the slow path);
//! 4. three `glBlitFramebuffer` calls (twin → host, one per colour
//!    attachment) plus one depth blit: what a hardware resolve costs, and
//!    the same without the depth blit;
//! 5. the floors of a one-pass resolve at 0 % complex pixels: a pass that
//!    reads only what the exact uniformity test needs (every depth and
//!    position sample) and writes sample 0, and one that reads what the
//!    opt-in position test needs (every position sample, depth sample 0);
//! 6. a trivial full-screen pass writing the three attachments, for scale.
//!
//! `--summarize DIR` measures nothing and prints a markdown table of the
//! reports in DIR (`scripts/resolve-cost` runs every case and calls it).
//!
//! ```text
//! cargo bench --bench resolve_vs_blit [-- --size 640x360 --samples 4 --runs 30]
//! ```
//! Other options: `--warmup N`, `--triangles N`, `--seed N`, `--scene S`
//! (a built-in scene or glTF file seen through its camera instead of the
//! random triangles, drawn by the same host shader),
//! `--timer auto|query|wall`, `--key position|depth` (the depth key: what a
//! host without a position attachment gets), `--plane-uniformity` (the
//! fast path with the opt-in plane test), `--position-uniformity` (the opt-in
//! position test), `--json FILE` (where the report goes). Each run is timed both by a `GL_TIME_ELAPSED`
//! query (where the context has one) and by `glFinish`-bracketed wall time;
//! `auto` reports the query, except on software renderers, whose query does
//! not span the pass (llvmpipe restarts it at every tile a thread rasterises).
//! Results also go to `target/resolve_vs_blit.json`.

#[path = "../common/mod.rs"]
mod common;
mod measure;
mod setup;
mod summary;

use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::gl::FULLSCREEN_VERT;
use deferred_msaa_lab::gl::{
    GpuTimer, Program, ShaderStage, TimerKind, VertexArray, check_error, preamble,
};
use deferred_msaa_lab::resolve::{ResolveRule, ResolveSettings};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use glow::HasContext;
use measure::*;
use setup::*;
use std::path::PathBuf;
use std::process::ExitCode;
use summary::*;

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
}

fn run(args: &Args) -> Result<(), String> {
    Backend::Egl.check_library().map_err(|e| e.to_string())?;
    let ctx = HeadlessContext::new(Backend::Egl).map_err(|e| format!("EGL context: {e}"))?;
    let gl = ctx.gl();
    let version = ctx.version();
    let e = |e: deferred_msaa::Error| e.to_string();

    let host = Host::new(gl, args).map_err(e)?;
    let options = RetrofitOptions {
        samples: args.samples,
        // As the recommended layout resolves normals: the reference sample's.
        rules: vec![(ColorAttachment(2), ResolveRule::Select)],
        position_attachment: (!args.key_from_depth).then_some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.engine.fbo.raw(), &options).map_err(e)?;
    let samples = msaa.samples();
    let twin = msaa.begin_frame(gl).map_err(e)?;

    // The host's geometry pass into the multisampled twin (again before
    // each resolve timed, outside the timed stretch).
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(twin)) };
    host.draw(gl);
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    check_error(gl, "drawing the scene").map_err(e)?;

    let fast = host.params(ResolveSettings {
        plane_uniformity: args.plane_uniformity,
        position_uniformity: args.position_uniformity,
        ..ResolveSettings::default()
    });
    let exact = host.params(ResolveSettings::default());
    let nofast = host.params(ResolveSettings {
        fast_path: false,
        ..ResolveSettings::default()
    });
    let complexity = count_complex(gl, &msaa, &fast, &exact).map_err(e)?;

    let trivial = Program::build(
        gl,
        "trivial full-screen pass",
        &preamble(&[], &[]),
        &[
            (ShaderStage::Vertex, "fullscreen.vert", FULLSCREEN_VERT),
            (ShaderStage::Fragment, "trivial.frag", TRIVIAL_FRAG),
        ],
        &[("o_color", 0), ("o_position", 1), ("o_normal", 2)],
    )
    .map_err(e)?;
    let floor = |exact: bool| {
        let mut defines = vec![("NUM_SAMPLES".to_string(), samples.to_string())];
        if exact {
            defines.push(("EXACT_TEST".to_string(), "1".to_string()));
        }
        Program::build(
            gl,
            if exact {
                "floor of the exact test"
            } else {
                "floor of the position test"
            },
            &preamble(&[], &defines),
            &[
                (ShaderStage::Vertex, "fullscreen.vert", FULLSCREEN_VERT),
                (ShaderStage::Fragment, "floor.frag", FLOOR_FRAG),
            ],
            &[("o_color", 0), ("o_position", 1), ("o_normal", 2)],
        )
    };
    let floor_exact = floor(true).map_err(e)?;
    let floor_position = floor(false).map_err(e)?;
    let empty_vao = VertexArray::new(gl, "trivial pass vao").map_err(e)?;
    // Every run is timed twice at once: a GL_TIME_ELAPSED query (where the
    // context has one) inside a glFinish-bracketed wall clock.
    let mut wall = GpuTimer::new(gl, true).map_err(e)?;
    let query = GpuTimer::new(gl, false).map_err(e)?;
    let mut query = match query.kind() {
        TimerKind::GlTimeElapsed => Some(query),
        TimerKind::FinishWallClock => {
            query.destroy(gl);
            None
        }
    };
    let software = ["llvmpipe", "softpipe", "swrast", "lavapipe"]
        .iter()
        .any(|name| version.renderer.to_lowercase().contains(name));
    let (primary, reason) = match (args.timer, query.is_some()) {
        (TimerChoice::Wall, _) => (TimerKind::FinishWallClock, "asked for with --timer wall"),
        (TimerChoice::Query, true) => (TimerKind::GlTimeElapsed, "asked for with --timer query"),
        (TimerChoice::Query, false) => {
            return Err("--timer query: this context has no GL_TIME_ELAPSED queries".into());
        }
        (TimerChoice::Auto, false) => (
            TimerKind::FinishWallClock,
            "the context has no GL_TIME_ELAPSED queries",
        ),
        (TimerChoice::Auto, true) if software => (
            TimerKind::FinishWallClock,
            "software renderer: llvmpipe's GL_TIME_ELAPSED restarts at every tile a thread \
             rasterises, so it spans only the last tiles, not the pass",
        ),
        (TimerChoice::Auto, true) => (TimerKind::GlTimeElapsed, "the context has GL_TIME_ELAPSED"),
    };

    let frame = host.frame();
    let with = |resolve: ResolveSettings| RetrofitOptions {
        resolve,
        ..options.clone()
    };
    // The resolve's variants, all compiled now: switching between them
    // (outside the timed region) only picks a cached program.
    let variants = [
        (Method::ResolveFast, with(fast.settings)),
        (Method::ResolveExact, with(exact.settings)),
        (Method::ResolveNoFast, with(nofast.settings)),
    ];
    for (_, v) in &variants {
        msaa.set_options(gl, v).map_err(e)?;
    }
    let mut once = |m: Method| -> deferred_msaa::Result<(f64, Option<f64>)> {
        if let Some((_, v)) = variants.iter().find(|(method, _)| *method == m) {
            msaa.set_options(gl, v)?;
        }
        if matches!(
            m,
            Method::ResolveFast | Method::ResolveExact | Method::ResolveNoFast
        ) {
            // A resolve requires a begun frame: drawn again, untimed.
            let fbo = msaa.begin_frame(gl)?;
            unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
            host.draw(gl);
            unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
        }
        wall.begin(gl);
        if let Some(q) = query.as_mut() {
            q.begin(gl);
        }
        match m {
            Method::ResolveFast | Method::ResolveExact | Method::ResolveNoFast => {
                msaa.resolve(gl, &frame)?
            }
            Method::Blit => blit_resolve(gl, twin, &host, true),
            Method::BlitColor => blit_resolve(gl, twin, &host, false),
            Method::FloorExact => floor_pass(gl, &floor_exact, &empty_vao, &host, &msaa)?,
            Method::FloorPosition => floor_pass(gl, &floor_position, &empty_vao, &host, &msaa)?,
            Method::Trivial => trivial_pass(gl, &trivial, &empty_vao, &host),
        }
        let q_ms = query.as_mut().map(|q| q.end(gl));
        let w_ms = wall.end(gl);
        check_error(gl, m.label())?;
        Ok((w_ms, q_ms))
    };

    // Warm-up (compiles the resolve permutations too), then K interleaved
    // rounds; each round starts one method later, so none always goes first.
    for _ in 0..args.warmup {
        for m in Method::ALL {
            once(m).map_err(e)?;
        }
    }
    let mut wall_ms: Vec<Vec<f64>> = vec![Vec::with_capacity(args.runs); Method::ALL.len()];
    let mut query_ms: Vec<Vec<f64>> = vec![Vec::with_capacity(args.runs); Method::ALL.len()];
    for round in 0..args.runs {
        for i in 0..Method::ALL.len() {
            let k = (round + i) % Method::ALL.len();
            let (w, q) = once(Method::ALL[k]).map_err(e)?;
            wall_ms[k].push(w);
            if let Some(q) = q {
                query_ms[k].push(q);
            }
        }
    }
    let have_query = query.is_some();
    wall.destroy(gl);
    if let Some(q) = query {
        q.destroy(gl);
    }
    trivial.destroy(gl);
    empty_vao.destroy(gl);
    floor_exact.destroy(gl);
    floor_position.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);

    // Report: the primary timer's table and ratios, then the other timer's.
    let (primary_ms, secondary_ms) = match primary {
        TimerKind::FinishWallClock => (&wall_ms, have_query.then_some(&query_ms)),
        TimerKind::GlTimeElapsed => (&query_ms, Some(&wall_ms)),
    };
    let secondary = match primary {
        TimerKind::FinishWallClock => TimerKind::GlTimeElapsed,
        TimerKind::GlTimeElapsed => TimerKind::FinishWallClock,
    };
    let primary_stats: Vec<Stats> = primary_ms.iter().map(|t| stats(t)).collect();
    let secondary_stats: Option<Vec<Stats>> =
        secondary_ms.map(|all| all.iter().map(|t| stats(t)).collect());
    let ratios = |st: &[Stats]| {
        let median = |m: Method| st[Method::ALL.iter().position(|x| *x == m).unwrap_or(0)].median;
        let blit = median(Method::Blit);
        (
            median(Method::ResolveFast) / blit,
            median(Method::ResolveNoFast) / blit,
        )
    };
    let (ratio_fast, ratio_nofast) = ratios(&primary_stats);
    let frac = |n: u64| n as f64 / complexity.pixels.max(1) as f64;
    let describe = |k: TimerKind| match k {
        TimerKind::GlTimeElapsed => "GL_TIME_ELAPSED query",
        TimerKind::FinishWallClock => "wall time between glFinish calls",
    };

    println!(
        "resolve_vs_blit: {}x{}, {}x MSAA (requested {}), G-buffer 3x RGBA16F + DEPTH32F, {}",
        args.width,
        args.height,
        samples,
        args.samples,
        match &args.scene {
            Some(spec) => format!("scene {spec}"),
            None => format!("{} random triangles + background", args.triangles),
        }
    );
    println!(
        "key: {}{}",
        if args.key_from_depth {
            "the depth buffer, linearised"
        } else {
            "the view-space position attachment"
        },
        match (
            args.plane_uniformity,
            args.position_uniformity && !args.key_from_depth
        ) {
            (_, true) => "; fast path with the opt-in position test",
            (true, false) => "; fast path with the opt-in plane test",
            _ => "",
        }
    );
    println!(
        "context: EGL, {} | GL {} | GLSL {}",
        version.renderer, version.version_string, version.glsl_string
    );
    println!(
        "timer: {} ({}); why: {reason}",
        primary.name(),
        describe(primary)
    );
    println!(
        "complex pixels: {:.2}% ({} of {}; depth keys differ across samples, the fast path's test, via resolve::cpu)",
        100.0 * frac(complexity.complex_key),
        complexity.complex_key,
        complexity.pixels
    );
    println!(
        "                {:.2}% ({}; raw depth-buffer samples differ, tilted interiors included)",
        100.0 * frac(complexity.complex_depth),
        complexity.complex_depth
    );
    println!(
        "{} warm-up rounds, then {} runs per method, interleaved round-robin",
        args.warmup, args.runs
    );
    print_table(&primary_stats);
    if args.plane_uniformity || args.position_uniformity {
        println!(
            "the opt-in test changes {} pixels ({:.2}%) against the exact resolve, by at most {:.3e}",
            complexity.option_changed,
            100.0 * frac(complexity.option_changed),
            complexity.option_max_difference
        );
    }
    println!("ratio resolve/blit (medians, fast path on):  {ratio_fast:.3}");
    println!("ratio resolve/blit (medians, fast path off): {ratio_nofast:.3}");
    println!(
        "ratio resolve fast path on/off (medians):    {:.3}",
        ratio_fast / ratio_nofast
    );
    if let Some(st) = &secondary_stats {
        let (f, n) = ratios(st);
        println!(
            "for comparison, the same runs by {} ({}):",
            secondary.name(),
            describe(secondary)
        );
        print_table(st);
        println!("  ratios resolve/blit: fast path on {f:.3}, off {n:.3}");
    }

    let methods_json = |st: &[Stats], all: &[Vec<f64>]| -> Vec<serde_json::Value> {
        Method::ALL
            .iter()
            .zip(st)
            .zip(all)
            .map(|((m, s), t)| {
                serde_json::json!({
                    "method": m.key(),
                    "label": m.label(),
                    "median_ms": s.median,
                    "q1_ms": s.q1,
                    "q3_ms": s.q3,
                    "iqr_ms": s.q3 - s.q1,
                    "min_ms": s.min,
                    "max_ms": s.max,
                    "runs_ms": t,
                })
            })
            .collect()
    };
    let secondary_json = match (&secondary_stats, secondary_ms) {
        (Some(st), Some(all)) => {
            let (f, n) = ratios(st);
            serde_json::json!({
                "timer": secondary.name(),
                "methods": methods_json(st, all),
                "ratio_resolve_fast_over_blit": f,
                "ratio_resolve_nofast_over_blit": n,
            })
        }
        _ => serde_json::Value::Null,
    };
    let report = serde_json::json!({
        "renderer": version.renderer,
        "gl_version": version.version_string,
        "glsl_version": version.glsl_string,
        "backend": "egl",
        "width": args.width,
        "height": args.height,
        "samples_requested": args.samples,
        "samples": samples,
        "gbuffer": ["RGBA16F color", "RGBA16F position", "RGBA16F normal", "DEPTH32F"],
        "triangles": args.triangles,
        "scene": args.scene,
        "seed": args.seed,
        "key": if args.key_from_depth { "depth" } else { "position" },
        "plane_uniformity": args.plane_uniformity,
        "position_uniformity": args.position_uniformity && !args.key_from_depth,
        "option_changed_pixels": complexity.option_changed,
        "option_max_difference": complexity.option_max_difference,
        "pixels": complexity.pixels,
        "complex_pixels": complexity.complex_key,
        "complex_fraction": frac(complexity.complex_key),
        "depth_differs_pixels": complexity.complex_depth,
        "depth_differs_fraction": frac(complexity.complex_depth),
        "timer": primary.name(),
        "timer_reason": reason,
        "warmup": args.warmup,
        "runs": args.runs,
        "methods": methods_json(&primary_stats, primary_ms),
        "ratio_resolve_fast_over_blit": ratio_fast,
        "ratio_resolve_nofast_over_blit": ratio_nofast,
        "ratio_resolve_fast_over_nofast": ratio_fast / ratio_nofast,
        "other_timer": secondary_json,
    });
    let path = args
        .json
        .clone()
        .unwrap_or_else(|| target_dir().join("resolve_vs_blit.json"));
    let dir = path.parent().map(PathBuf::from).unwrap_or_default();
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(&path, text + "\n"))
        .map_err(|e| format!("writing {}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn main() -> ExitCode {
    let args = parse_args();
    let result = match &args.summarize {
        Some(dir) => summarize(dir),
        None => run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("resolve_vs_blit: {msg}");
            ExitCode::FAILURE
        }
    }
}
