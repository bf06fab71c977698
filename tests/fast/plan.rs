//! The scene-adaptive plan: what each built-in scene leaves out,
//! that leaving it out changes nothing in the final image, `render
//! --explain`, and the per-pixel view of which pixels took the resolve's
//! slow path (`--view complex`, `complex_fraction`).

use crate::common;

use deferred_msaa_lab::compare;
use deferred_msaa_lab::gbuffer::GBufferLayout;
use deferred_msaa_lab::gl::{TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, pixel_samples};
use deferred_msaa_lab::renderer::plan::{Pass, Plan, PlanContext, SceneNeeds, SpecularResponse};
use deferred_msaa_lab::renderer::technique::Complex;
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer};
use deferred_msaa_lab::resolve::cpu::PixelPlace;
use deferred_msaa_lab::resolve::{KeySource, ResolveSettings, ResolveSlot};
use deferred_msaa_lab::scene::Scene;
use std::process::Command;

const W: u32 = 128;
const H: u32 = 72;

/// The goldens' tolerance for final images (`FINAL` in tests/goldens.rs):
/// what a rasteriser update may change.
const FLIP_MEAN: f32 = 0.01;
const FLIP_P99: f32 = 0.25;

fn options(aa: AaMode, adaptive: bool) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa,
        adaptive,
        ..RenderOptions::default()
    }
}

fn median() -> AaMode {
    AaMode::Resolve(ResolveSettings::default())
}

fn average() -> AaMode {
    AaMode::Resolve(ResolveSettings {
        method: deferred_msaa_lab::resolve::ResolveMethod::Average,
        ..ResolveSettings::default()
    })
}

fn scene(name: &str) -> Scene {
    Scene::load(&format!("builtin:{name}")).expect("built-in scene")
}

/// A context as llvmpipe is: 4x only, no memory report.
fn llvmpipe_like() -> PlanContext {
    PlanContext {
        sample_counts: vec![4],
        driver_memory: None,
    }
}

fn names(plan: &Plan) -> Vec<&str> {
    plan.layout.colors.iter().map(|a| a.name.as_str()).collect()
}

fn left_out(plan: &Plan, name: &str) -> bool {
    plan.left_out.iter().any(|l| l.name == name)
}

#[test]
fn each_builtin_scene_keeps_exactly_the_channels_it_uses() {
    let ctx = llvmpipe_like();
    for name in Scene::builtin_names() {
        let s = scene(name);
        let needs = SceneNeeds::of(&s);
        let plan = Plan::for_scene(&s, &ctx, &options(median(), true)).expect("plan");
        let full = Plan::for_scene(&s, &ctx, &options(median(), false)).expect("full plan");
        assert_eq!(
            names(&full),
            ["color", "position", "normal", "specular", "emissive"]
        );
        assert_eq!(full.layout, GBufferLayout::recommended());

        // Emission: kept exactly when a G-buffer material emits.
        let emits = s.objects.iter().any(|o| {
            let m = &s.materials[o.material];
            m.alpha_mode != deferred_msaa_lab::scene::AlphaMode::Blend && m.is_emissive()
        });
        assert_eq!(plan.layout.index_of("emissive").is_some(), emits, "{name}");
        assert_eq!(plan.runs(Pass::BackgroundCopy), emits, "{name}");
        // Specular: kept exactly when the materials' responses differ.
        let uniform = matches!(needs.specular, SpecularResponse::Uniform(_));
        assert_eq!(
            plan.layout.index_of("specular").is_none(),
            uniform,
            "{name}"
        );
        assert_eq!(plan.constant_specular.is_some(), uniform, "{name}");
        assert_eq!(left_out(&plan, "specular"), uniform, "{name}");
        // The transparent pass runs only with alpha-blended objects.
        assert_eq!(
            plan.runs(Pass::Transparent),
            needs.transparent_objects > 0,
            "{name}"
        );
        assert!(!plan.runs(Pass::Fxaa) && !plan.runs(Pass::Decals), "{name}");
        // Every attachment is multisampled for a resolve method, depth included.
        assert_eq!(plan.attachments.len(), plan.layout.colors.len() + 1);
        assert!(plan.attachments.iter().all(|a| a.multisampled), "{name}");
        // The key still reads the position attachment.
        let KeySource::Position(ResolveSlot(k)) = plan.layout.key else {
            panic!("{name}: the key left the position attachment");
        };
        assert_eq!(plan.layout.colors[k].name, "position", "{name}");
        // Smaller whenever something was left out, never larger.
        let trimmed = plan.layout != full.layout;
        assert_eq!(plan.gbuffer_bytes < full.gbuffer_bytes, trimmed, "{name}");
        assert!(plan.gbuffer_bytes <= full.gbuffer_bytes, "{name}");
        assert_eq!(plan.full_gbuffer_bytes, full.full_gbuffer_bytes);
    }
    // What the built-ins are known to lack (src/scene/builtin.rs).
    let plan = |n: &str| Plan::for_scene(&scene(n), &ctx, &options(median(), true)).unwrap();
    assert_eq!(names(&plan("box")), ["color", "position", "normal"]);
    assert_eq!(names(&plan("zfight")), ["color", "position", "normal"]);
    assert_eq!(
        names(&plan("thin")),
        ["color", "position", "normal", "specular"]
    );
    assert_eq!(names(&plan("greebles")).len(), 5);
    assert_eq!(names(&plan("emissive")).len(), 5);
    // Dielectrics write F0 0.04, stored by the full layout's RGBA8 as 10/255.
    assert_eq!(
        plan("box").constant_specular,
        Some([10.0 / 255.0, 10.0 / 255.0, 10.0 / 255.0, 0.0])
    );
    // `average` blends background samples into edge pixels: with a sky
    // behind, the emissive attachment carries it there.
    let thin_average = Plan::for_scene(&scene("thin"), &ctx, &options(average(), true)).unwrap();
    assert!(thin_average.layout.index_of("emissive").is_some());
    assert!(
        thin_average
            .kept
            .iter()
            .any(|k| k.name == "emissive" && k.why.contains("average")),
        "{:?}",
        thin_average.kept
    );
    // 200 km away: FP16 positions would overflow, the plan keeps FP32.
    let far = plan("far");
    assert_eq!(
        far.layout.attachment("position").map(|a| a.format.name()),
        Some("RGBA32F")
    );
    assert!(
        far.kept.iter().any(|k| k.why.contains("65504")),
        "{:?}",
        far.kept
    );
}

#[test]
fn methods_decide_what_is_multisampled_and_which_passes_run() {
    let ctx = llvmpipe_like();
    let s = scene("box");
    let none = Plan::for_scene(&s, &ctx, &options(AaMode::None, true)).unwrap();
    assert!(none.attachments.iter().all(|a| !a.multisampled));
    assert!(!none.runs(Pass::Resolve) && none.runs(Pass::Lighting));
    assert_eq!(none.samples, 1);
    let complex = Plan::for_scene(&s, &ctx, &options(AaMode::Complex, true)).unwrap();
    assert!(complex.runs(Pass::ComplexMask) && complex.runs(Pass::PerSampleLighting));
    assert!(!complex.runs(Pass::Lighting));
    let fxaa = Plan::for_scene(
        &s,
        &ctx,
        &RenderOptions {
            fxaa: true,
            ..options(median(), true)
        },
    )
    .unwrap();
    assert!(fxaa.runs(Pass::Fxaa) && !left_out(&fxaa, "fxaa"));
    // Single-sample: host textures only; 4x adds the twins, 4 samples each.
    let px = u64::from(W * H);
    let per_sample = none.layout.bytes_per_sample();
    assert_eq!(none.gbuffer_bytes, per_sample * px);
    let ms = Plan::for_scene(&s, &ctx, &options(median(), true)).unwrap();
    assert_eq!(ms.gbuffer_bytes, per_sample * px * 5);
    // FreeSpace Open's layout: 40 bytes a sample.
    assert_eq!(ms.full_gbuffer_bytes, 40 * px * 5);
}

#[test]
fn a_layout_without_what_the_scene_needs_is_refused() {
    let ctx = llvmpipe_like();
    let mut no_emissive = GBufferLayout::recommended();
    no_emissive.colors.retain(|a| a.name != "emissive");
    let o = RenderOptions {
        layout: no_emissive,
        ..options(median(), false)
    };
    let e = Plan::for_scene(&scene("emissive"), &ctx, &o).unwrap_err();
    assert!(e.to_string().contains("emissive"), "{e}");
    assert_eq!(e.to_string().lines().count(), 1);
    // A scene with nothing that emits renders with that layout.
    assert!(Plan::for_scene(&scene("box"), &ctx, &o).is_ok());
}

/// Render `name` with `aa`, adaptive or with the full layout.
fn render(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    s: &Scene,
    aa: AaMode,
    adaptive: bool,
) -> (image::RgbaImage, Plan, usize) {
    let gl = ctx.gl();
    let mut r = Renderer::new(gl, |n| ctx.get_proc_address(n), s, &options(aa, adaptive))
        .expect("renderer");
    r.render(gl).expect("frame");
    let image = r.read_final(gl).expect("final image");
    let plan = r.plan().clone();
    let attachments = r.gbuffer().colors.len();
    assert_eq!(r.layout(), &plan.layout);
    r.destroy(gl);
    (image, plan, attachments)
}

#[test]
fn leaving_out_unused_channels_changes_nothing_in_the_image() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let before = live_objects();
    // The built-ins that lack a channel: box and zfight (no emission, one
    // specular response), thin and transparent (no emission).
    for name in ["box", "zfight", "thin", "transparent"] {
        let s = scene(name);
        for aa in [median(), AaMode::None, AaMode::PerSample, average()] {
            let (adapted, plan, attachments) = render(&ctx, &s, aa, true);
            let (full, full_plan, full_attachments) = render(&ctx, &s, aa, false);
            if aa == average() {
                // `average` blends the sky into edge pixels through the
                // emissive attachment: it stays.
                assert!(plan.layout.index_of("emissive").is_some(), "{name}");
            }
            if plan.layout == full_plan.layout {
                assert_eq!(adapted, full, "{name} {}", aa.name());
                continue;
            }
            assert!(attachments <= full_attachments, "{name} {}", aa.name());
            assert_eq!(attachments, plan.layout.colors.len());
            assert!(
                plan.gbuffer_bytes < full_plan.gbuffer_bytes,
                "{name} {}: {} vs {}",
                aa.name(),
                plan.gbuffer_bytes,
                full_plan.gbuffer_bytes
            );
            let flip = compare::flip(&full, &adapted).expect("same size");
            eprintln!(
                "{name} {}: G-buffer {} -> {} bytes, FLIP mean {:.5}, p99 {:.4}",
                aa.name(),
                full_plan.gbuffer_bytes,
                plan.gbuffer_bytes,
                flip.mean,
                flip.p99
            );
            assert!(
                flip.mean < FLIP_MEAN && flip.p99 < FLIP_P99,
                "{name} {}: {flip:?}",
                aa.name()
            );
            // Leaving attachments out, with no format narrowed, is exact:
            // the stand-ins hold what the attachments would have held.
            let position = |p: &Plan| p.layout.attachment("position").map(|a| a.format);
            if position(&plan) == position(&full_plan) {
                assert!(adapted == full, "{name} {}: the images differ", aa.name());
            }
        }
    }
    assert_eq!(live_objects(), before);
}

#[test]
fn the_model_and_lighting_shaders_follow_the_plan_not_the_method() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let s = scene("box");
    let new = |aa, adaptive| {
        Renderer::new(gl, |n| ctx.get_proc_address(n), &s, &options(aa, adaptive)).unwrap()
    };
    let plain = new(AaMode::None, true);
    let mut msaa = new(median(), true);
    let full = new(median(), false);
    assert_eq!(
        plain.lighting_program_source(),
        msaa.lighting_program_source()
    );
    assert_eq!(
        plain.geometry_program_source(),
        msaa.geometry_program_source()
    );
    assert!(
        msaa.lighting_program_source()
            .contains("#define GBUFFER_NO_SPECULAR")
    );
    assert!(
        !full
            .lighting_program_source()
            .contains("#define GBUFFER_NO")
    );
    // Switching to the full layout at run time rebuilds the programs.
    msaa.set_options(gl, &options(median(), false)).unwrap();
    assert_eq!(
        msaa.lighting_program_source(),
        full.lighting_program_source()
    );
    assert_eq!(msaa.gbuffer().colors.len(), 5);
    msaa.render(gl).unwrap();
    // The decal pass is in the plan once a hook is installed.
    assert!(!msaa.plan().runs(Pass::Decals));
    msaa.set_decal_hook(Some(Box::new(|_, _| {})));
    assert!(msaa.plan().runs(Pass::Decals));
    msaa.render(gl).unwrap();
    for r in [plain, msaa, full] {
        r.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// The pixels the resolve's CPU reference sends to the slow path, over the
/// twins' samples read back (row 0 at the top, as in the mask): keys that
/// differ, or, with the normal test, equal keys over depth samples that
/// differ under more than one orientation.
fn cpu_complex_pixels(gl: &glow::Context, r: &Renderer) -> Vec<bool> {
    let retrofit = r.retrofit().expect("multisampled");
    let cpu = retrofit.cpu_reference(&r.resolve_frame()).unwrap();
    assert!(
        matches!(retrofit.key(), KeySource::Position(ResolveSlot(_))),
        "the key comes from the position attachment"
    );
    let (depth, colors, _) = retrofit.inputs().unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let colors: Vec<_> = colors
        .iter()
        .map(|t| readback.read(gl, *t, 1).unwrap())
        .collect();
    let depth = readback.read(gl, depth, 1).unwrap();
    readback.destroy(gl);
    let mut complex = Vec::new();
    for y in 0..depth.height {
        for x in 0..depth.width {
            let px = pixel_samples(&depth, &colors, x, y);
            let at = PixelPlace {
                x,
                y,
                width: depth.width,
                height: depth.height,
            };
            complex.push(cpu.resolve_pixel_at(&px, Some(at)).complex);
        }
    }
    complex
}

#[test]
fn the_complex_view_shows_the_resolves_slow_path() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let s = scene("greebles");
    let mut r = Renderer::new(
        gl,
        |n| ctx.get_proc_address(n),
        &s,
        &options(median(), true),
    )
    .unwrap();
    r.render(gl).unwrap();
    let before = r.gbuffer().colors.len();
    let color_before = {
        let mut rb = Readback::new(gl).unwrap();
        let img = rb
            .read(gl, TextureRef::from(&r.gbuffer().colors[0]), 1)
            .unwrap();
        rb.destroy(gl);
        img.data
    };
    let mask = r.read_complex_pixels(gl).unwrap().expect("a mask");
    assert_eq!(mask.dimensions(), (W, H));
    let expected = cpu_complex_pixels(gl, &r);
    let marked: Vec<bool> = mask.pixels().map(|p| p[0] == 255).collect();
    assert!(mask.pixels().all(|p| p[0] == 0 || p[0] == 255));
    // The fast path skips exactly the pixels the CPU reference calls
    // uniform.
    let differ = marked.iter().zip(&expected).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} pixels disagree");
    let fraction = r.complex_pixel_fraction(gl).unwrap().expect("a fraction");
    let n = expected.iter().filter(|&&c| c).count() as f64;
    assert!((fraction - n / f64::from(W * H)).abs() < 1e-12);
    assert!(fraction > 0.0 && fraction < 0.5, "{fraction}");
    // Reading the mask leaves the G-buffer as the frame made it.
    let mut rb = Readback::new(gl).unwrap();
    let after = rb
        .read(gl, TextureRef::from(&r.gbuffer().colors[0]), 1)
        .unwrap();
    rb.destroy(gl);
    assert_eq!(after.data, color_before);
    assert_eq!(r.gbuffer().colors.len(), before);

    // Without the fast path every pixel takes the slow path.
    let nofast = AaMode::Resolve(ResolveSettings {
        fast_path: false,
        ..ResolveSettings::default()
    });
    r.set_options(gl, &options(nofast, true)).unwrap();
    r.render(gl).unwrap();
    assert_eq!(r.complex_pixel_fraction(gl).unwrap(), Some(1.0));
    // `complex` shows its own stencil mask; per-sample lights every pixel; none has none.
    r.set_options(gl, &options(AaMode::Complex, true)).unwrap();
    r.render(gl).unwrap();
    let own = r
        .technique::<Complex>()
        .expect("complex")
        .read_mask(gl)
        .unwrap()
        .expect("complex mask");
    assert_eq!(r.read_complex_pixels(gl).unwrap(), Some(own));
    r.set_options(gl, &options(AaMode::PerSample, true))
        .unwrap();
    r.render(gl).unwrap();
    assert_eq!(r.complex_pixel_fraction(gl).unwrap(), Some(1.0));
    r.set_options(gl, &options(AaMode::None, true)).unwrap();
    r.render(gl).unwrap();
    assert_eq!(r.read_complex_pixels(gl).unwrap(), None);
    r.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_deferred-msaa"))
        .args(args)
        .output()
        .expect("running deferred-msaa")
}

#[test]
fn explain_prints_the_plan_with_the_design_keys() {
    if common::egl_context().is_none() {
        return;
    }
    let out = cli(&[
        "render",
        "--scene",
        "builtin:box",
        "--size",
        "128x72",
        "--explain",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let plan: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    let attachments = plan["attachments"].as_array().expect("attachments");
    let names: Vec<&str> = attachments
        .iter()
        .filter_map(|a| a["name"].as_str())
        .collect();
    assert_eq!(names, ["color", "position", "normal", "depth"]);
    assert_eq!(attachments[0]["format"], "RGBA16F");
    assert_eq!(attachments[3]["format"], "DEPTH_COMPONENT32F");
    for a in attachments {
        assert!(
            a["format"].is_string() && a["multisampled"].as_bool() == Some(true),
            "{a}"
        );
    }
    let passes: Vec<&str> = plan["passes"]
        .as_array()
        .expect("passes")
        .iter()
        .filter_map(|p| p.as_str())
        .collect();
    assert!(
        passes.contains(&"resolve") && !passes.contains(&"transparent"),
        "{passes:?}"
    );
    let left: Vec<&str> = plan["left_out"]
        .as_array()
        .expect("left_out")
        .iter()
        .filter_map(|l| {
            assert!(!l["why"].as_str().unwrap_or("").is_empty(), "{l}");
            l["name"].as_str()
        })
        .collect();
    for name in ["emissive", "specular", "transparent", "fxaa"] {
        assert!(left.contains(&name), "{left:?}");
    }
    let bytes = plan["gbuffer_bytes"].as_u64().expect("gbuffer_bytes");
    let full = plan["full_gbuffer_bytes"]
        .as_u64()
        .expect("full_gbuffer_bytes");
    assert!(bytes > 0 && bytes < full, "{bytes} vs {full}");
    // The readable form says the same.
    let text = cli(&[
        "render",
        "--scene",
        "builtin:box",
        "--size",
        "128x72",
        "--explain",
    ]);
    assert!(text.status.success());
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("left out:") && text.contains("emissive:"),
        "{text}"
    );
    // --json alone is a usage error, in one line.
    let bad = cli(&["render", "--json"]);
    assert!(!bad.status.success());
    assert_eq!(
        String::from_utf8_lossy(&bad.stderr).trim().lines().count(),
        1
    );
}

#[test]
fn the_complex_view_and_dump_report_the_slow_path() {
    if common::egl_context().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("dmsaa-plan-{}", std::process::id()));
    let png = dir.join("complex.png");
    let out = cli(&[
        "render",
        "--scene",
        "builtin:greebles",
        "--size",
        "96x54",
        "--view",
        "complex",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).expect("the complex view").to_luma8();
    let marked = img.pixels().filter(|p| p[0] == 255).count();
    assert!(marked > 0 && marked < img.pixels().len() / 2, "{marked}");
    assert!(img.pixels().all(|p| p[0] == 0 || p[0] == 255));
    // Without multisampling there is no slow path to show: one line, non-zero.
    let none = cli(&[
        "render", "--method", "none", "--size", "32x18", "--view", "complex",
    ]);
    assert!(!none.status.success());
    let err = String::from_utf8_lossy(&none.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("complex"), "{err}");

    let dump = dir.join("dump");
    let out = cli(&[
        "dump",
        "--scene",
        "builtin:greebles",
        "--size",
        "96x54",
        "--out",
        dump.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dump.join("meta.json")).unwrap()).unwrap();
    let fraction = meta["complex_fraction"].as_f64().expect("complex_fraction");
    assert!(
        (fraction - marked as f64 / (96.0 * 54.0)).abs() < 1e-9,
        "{fraction} vs {marked}"
    );
    let out = cli(&[
        "dump",
        "--scene",
        "builtin:greebles",
        "--size",
        "32x18",
        "--method",
        "none",
        "--out",
        dump.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dump.join("meta.json")).unwrap()).unwrap();
    assert!(meta["complex_fraction"].is_null(), "{meta}");
    std::fs::remove_dir_all(&dir).unwrap();
}
