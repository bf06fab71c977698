//! The memory safety valve: the G-buffer's bytes are
//! estimated before allocating; over the budget the sample count steps
//! down to the highest offered count that fits (or to single-sample), with
//! a warning, or the request is refused when the budget is strict.

use crate::common;

use deferred_msaa::Error;
use deferred_msaa_lab::gbuffer::{MemoryBudget, choose_samples, gbuffer_bytes, real_sample_count};
use deferred_msaa_lab::gl::live_objects;
use deferred_msaa_lab::renderer::plan::{Plan, PlanContext};
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::scene::Scene;
use std::process::Command;

/// 100 bytes a sample: count n costs 100·n (1: single-sample).
fn per_count(n: u32) -> u64 {
    100 * u64::from(n)
}

const OFFERED: &[u32] = &[2, 4, 8, 16];

#[test]
fn a_tight_budget_steps_down_to_the_highest_offered_count_that_fits() {
    let pick = |requested, budget| {
        choose_samples(requested, OFFERED, budget, false, true, per_count).expect("a choice")
    };
    // Fits: kept, no warning.
    let c = pick(16, 1600);
    assert_eq!((c.samples, c.stepped_from), (16, None));
    assert!(c.warning(1600).is_none());
    // 16x over: 8x is the highest that fits, then 4x, then 2x.
    let c = pick(16, 1599);
    assert_eq!(
        (c.samples, c.bytes, c.stepped_from),
        (8, 800, Some((16, 1600)))
    );
    assert_eq!(pick(16, 799).samples, 4);
    assert_eq!(pick(8, 399).samples, 2);
    // Nothing multisampled fits: single-sample, said so in the warning.
    let c = pick(4, 150);
    assert_eq!(c.samples, 1);
    let w = c.warning(150).expect("a warning");
    assert!(w.contains("4x") && w.contains("without MSAA"), "{w}");
    assert_eq!(w.lines().count(), 1);
    // Below even single-sample: there is nothing lower; it says so.
    let c = pick(4, 50);
    assert_eq!(c.samples, 1);
    assert!(c.warning(50).unwrap().contains("still over"));
    // A request is rounded as the driver rounds it before it is weighed:
    // llvmpipe offers only 4, so 1, 2 and 3 cost what 4 costs.
    assert_eq!(real_sample_count(3, &[4]), 4);
    assert_eq!(real_sample_count(5, OFFERED), 8);
    assert_eq!(real_sample_count(32, OFFERED), 32);
    let c = choose_samples(2, &[4], 399, false, true, per_count).unwrap();
    assert_eq!((c.samples, c.stepped_from), (1, Some((4, 400))));
}

#[test]
fn a_strict_budget_refuses_with_the_numbers() {
    let e = choose_samples(16, OFFERED, 1000, true, true, per_count).unwrap_err();
    match &e {
        Error::MemoryBudget {
            needed,
            budget,
            samples,
        } => assert_eq!((*needed, *budget, *samples), (1600, 1000, 16)),
        other => panic!("not a budget error: {other}"),
    }
    let text = e.to_string();
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(text.contains("16x") && text.contains("budget"), "{text}");
    // Strict but within budget: no refusal.
    assert_eq!(
        choose_samples(16, OFFERED, 1600, true, true, per_count)
            .unwrap()
            .samples,
        16
    );
    // Without single-sample to fall back to (the retrofit), nothing fitting refuses too.
    assert!(matches!(
        choose_samples(4, OFFERED, 150, false, false, per_count),
        Err(Error::MemoryBudget { samples: 4, .. })
    ));
}

#[test]
fn the_plan_weighs_the_whole_g_buffer_before_anything_is_allocated() {
    let scene = Scene::load("builtin:box").unwrap();
    let context = PlanContext {
        sample_counts: vec![2, 4, 8],
        driver_memory: None,
    };
    let options = |budget: MemoryBudget| RenderOptions {
        width: 256,
        height: 144,
        samples: 8,
        memory_budget: budget,
        ..RenderOptions::default()
    };
    let full = Plan::for_scene(&scene, &context, &options(MemoryBudget::default())).unwrap();
    assert_eq!(full.samples, 8);
    assert!(full.warnings.is_empty());
    let at = |n| gbuffer_bytes(&full.layout, 256, 144, (n > 1).then_some(n));
    assert_eq!(full.gbuffer_bytes, at(8));
    // A budget just under 8x's needs: 4x.
    let plan = Plan::for_scene(&scene, &context, &options(MemoryBudget::limit(at(8) - 1))).unwrap();
    assert_eq!((plan.samples, plan.gbuffer_bytes), (4, at(4)));
    assert_eq!(plan.aa, full.aa);
    assert_eq!(plan.warnings.len(), 1);
    // Under 2x's: the frame runs single-sample, method `none`.
    let plan = Plan::for_scene(&scene, &context, &options(MemoryBudget::limit(at(2) - 1))).unwrap();
    assert_eq!((plan.samples, plan.aa), (1, AaMode::None));
    assert!(plan.attachments.iter().all(|a| !a.multisampled));
    let e = Plan::for_scene(
        &scene,
        &context,
        &options(MemoryBudget::limit(at(8) - 1).strict()),
    )
    .unwrap_err();
    assert!(
        matches!(e.core(), Some(Error::MemoryBudget { samples: 8, .. })),
        "{e}"
    );
}

#[test]
fn on_a_real_context_a_tiny_budget_falls_back_to_single_sample_or_refuses() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:box").unwrap();
    let generous = RenderOptions {
        width: 96,
        height: 54,
        ..RenderOptions::default()
    };
    let r = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &generous).unwrap();
    let layout = r.layout().clone();
    let multisampled = r.samples();
    assert!(multisampled > 1);
    assert!(r.warnings().is_empty(), "{:?}", r.warnings());
    r.destroy(gl);

    // Room for the single-sample G-buffer, not for any multisampled count
    // the driver offers (llvmpipe: only 4x).
    let single = gbuffer_bytes(&layout, 96, 54, None);
    let tiny = RenderOptions {
        memory_budget: MemoryBudget::limit(single),
        ..generous.clone()
    };
    let mut r = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &tiny).unwrap();
    assert_eq!(r.samples(), 1);
    assert!(r.retrofit().is_none());
    assert_eq!(r.effective_options().aa, AaMode::None);
    assert_eq!(r.options(), &tiny, "the options asked for stay as asked");
    let w = r.warnings().join("\n");
    assert!(
        w.contains("memory budget") && w.contains("without MSAA"),
        "{w}"
    );
    r.render(gl).expect("a single-sample frame");
    // Back to a generous budget at run time: multisampled again.
    r.set_options(gl, &generous).unwrap();
    assert_eq!(r.samples(), multisampled);
    assert!(r.warnings().is_empty());
    r.render(gl).unwrap();
    // Strict: refused with the numbers, and the renderer keeps going as it was.
    let strict = RenderOptions {
        memory_budget: MemoryBudget::limit(single).strict(),
        ..generous.clone()
    };
    let e = r.set_options(gl, &strict).unwrap_err();
    assert!(
        matches!(e.core(), Some(Error::MemoryBudget { budget, samples, .. }) if *budget == single && *samples == multisampled),
        "{e}"
    );
    assert_eq!(r.samples(), multisampled);
    r.render(gl).unwrap();
    r.destroy(gl);
    let e = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &strict).unwrap_err();
    assert!(matches!(e.core(), Some(Error::MemoryBudget { .. })), "{e}");
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn the_retrofit_weighs_its_twins_and_refuses_what_does_not_fit() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let host = deferred_msaa_testkit::Host::new(
        gl,
        64,
        36,
        deferred_msaa_lab::gl::Format::Rgba32f,
        deferred_msaa_lab::gl::Format::Depth32f,
    )
    .expect("the toy host");
    let budgeted = |budget: MemoryBudget| RetrofitOptions {
        memory_budget: Some(budget),
        ..RetrofitOptions::default()
    };
    let ok =
        MsaaRetrofit::new(gl, host.fbo.raw(), &budgeted(MemoryBudget::limit(1 << 30))).unwrap();
    assert!(ok.warnings().is_empty());
    let twins = ok.twin().bytes();
    let samples = ok.samples();
    ok.destroy(gl);
    // One byte short of the twins: a lower offered count, or (llvmpipe,
    // 4x only) a refusal, since the retrofit cannot go single-sample.
    let short = MemoryBudget::limit(twins - 1);
    match MsaaRetrofit::new(gl, host.fbo.raw(), &budgeted(short)) {
        Ok(r) => {
            assert!(r.samples() < samples && r.twin().bytes() < twins);
            assert_eq!(r.warnings().len(), 1);
            r.destroy(gl);
        }
        Err(e) => assert!(
            matches!(e, Error::MemoryBudget { needed, samples: s, .. } if needed == twins && s == samples),
            "{e}"
        ),
    }
    let e = MsaaRetrofit::new(gl, host.fbo.raw(), &budgeted(short.strict())).unwrap_err();
    assert!(matches!(e, Error::MemoryBudget { .. }), "{e}");
    host.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_deferred-msaa"))
        .args(args)
        .output()
        .expect("running deferred-msaa")
}

#[test]
fn the_cli_steps_down_with_a_warning_or_refuses_in_one_line() {
    if common::egl_context().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("dmsaa-budget-{}", std::process::id()));
    let out = dir.join("budget.png");
    let base = [
        "render",
        "--scene",
        "builtin:box",
        "--size",
        "64x36",
        "--memory-budget",
        "20KiB",
    ];
    let strict = cli(&[
        &base[..],
        &["--strict-memory", "--out", out.to_str().unwrap()],
    ]
    .concat());
    assert!(!strict.status.success());
    let err = String::from_utf8_lossy(&strict.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("memory budget"),
        "{err}"
    );
    assert!(!out.exists(), "nothing is rendered when refused");

    let stepped = cli(&[&base[..], &["--out", out.to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&stepped.stderr);
    assert!(stepped.status.success(), "{err}");
    assert!(
        err.contains("memory budget") && err.contains("without MSAA"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&stepped.stdout).contains(" 1x "));
    assert!(out.exists());

    let bad = cli(&["render", "--memory-budget", "lots"]);
    assert!(!bad.status.success());
    assert_eq!(
        String::from_utf8_lossy(&bad.stderr).trim().lines().count(),
        1
    );
    let _ = std::fs::remove_dir_all(&dir);
}
