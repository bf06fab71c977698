//! The examples: every one builds; `headless` turns a glTF file into the
//! renderer's anti-aliased image; `retrofit`'s own small engine, with MSAA
//! added in four lines, matches the built-in pipeline within a FLIP
//! tolerance; `viewer` opens a real window under Xvfb, survives live
//! switching of every option without a blank frame, and its screenshot shows
//! the scene. Images are tiny (160×90): the machine has two cores.
//!
//! The examples are built here with `cargo build --examples` (a no-op after
//! a plain `cargo test`, which builds them too), so the binaries are never
//! stale when one runs `cargo test --test slow -- --ignored examples::`.

use crate::common;
use crate::common::examples::{built_examples, example};
use crate::common::xvfb::start_xvfb;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use deferred_msaa_lab::compare::flip;
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer};
use deferred_msaa_lab::resolve::{ResolveMethod, ResolveSettings};
use deferred_msaa_lab::scene::Scene;

const W: u32 = 160;
const H: u32 = 90;

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("examples");
    std::fs::create_dir_all(&dir).expect("creating the scratch directory");
    dir.join(name)
}

/// Run a command with a time limit; kill it when the limit passes.
fn run_with_limit(cmd: &mut Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {cmd:?}: {e}"));
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let out = child.wait_with_output().expect("collecting output");
                panic!(
                    "{cmd:?} ran past {limit:?}; stderr:\n{}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(50)),
            Err(e) => panic!("waiting for {cmd:?}: {e}"),
        }
    }
    child.wait_with_output().expect("collecting output")
}

fn assert_success(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed ({}):\nstdout: {}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A failure the user caused: a non-zero exit and exactly one line on stderr, no panic.
fn assert_one_line_error(out: &Output, what: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{what} should fail");
    assert_eq!(out.status.code(), Some(1), "{what}: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{what}: one line expected, got:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{what} panicked: {stderr}");
}

fn load_png(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
        .to_rgba8()
}

/// Not blank: a good share of the pixels differ from the first one.
fn assert_not_blank(img: &image::RgbaImage, what: &str) {
    let first = *img.get_pixel(0, 0);
    let differing = img.pixels().filter(|p| **p != first).count();
    assert!(
        differing > img.len() / 4 / 10,
        "{what}: (nearly) blank, {differing} pixels differ from the corner"
    );
}

fn save_for_people(img: &image::RgbaImage, name: &str) {
    if let Some(dir) = std::env::var_os("DEFERRED_MSAA_SAVE_RENDERS") {
        let dir = PathBuf::from(dir);
        let _ = std::fs::create_dir_all(&dir);
        let _ = img.save(dir.join(format!("{name}.png")));
    }
}

/// The built-in renderer's final image of `scene` at W×H.
fn builtin_render(scene: &Scene, aa: AaMode) -> Option<image::RgbaImage> {
    let ctx = common::egl_context()?;
    let gl = ctx.gl();
    let options = RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa,
        fxaa: false,
        ..RenderOptions::default()
    };
    let mut renderer = Renderer::new(gl, |name| ctx.get_proc_address(name), scene, &options)
        .expect("building the renderer");
    renderer.render(gl).expect("rendering");
    let img = renderer.read_final(gl).expect("reading the final image");
    renderer.destroy(gl);
    Some(img)
}

fn median() -> AaMode {
    AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        ..ResolveSettings::default()
    })
}

#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn every_example_builds() {
    let dir = built_examples().as_ref().unwrap_or_else(|e| panic!("{e}"));
    for name in ["retrofit", "viewer", "headless", "layers_table"] {
        let path = dir.join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
        assert!(path.is_file(), "{} was not built", path.display());
    }
}

/// The README's second-layer table: no report, or a file that is not one,
/// is a one-line error and a non-zero exit.
#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn layers_table_refuses_what_is_not_a_report() {
    let none = Command::new(example("layers_table"))
        .output()
        .expect("runs");
    assert_eq!(none.status.code(), Some(2));
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("layers-table");
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let bad = dir.join("report.json");
    std::fs::write(&bad, "{ not json").expect("written");
    for path in [bad, dir.join("missing.json")] {
        let out = Command::new(example("layers_table"))
            .arg(&path)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(&path.display().to_string()), "{err}");
    }
}

// ---------------------------------------------------------------------------
// headless

/// Write a small glTF 2.0 scene: a cube and a second cube turned 30° about
/// two axes (diagonal edges to anti-alias), one material, no camera (the
/// loader frames the bounds) and no lights (it places its default rig).
fn write_gltf(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).expect("creating the glTF directory");
    let mut positions: Vec<f32> = Vec::new();
    let mut normals: Vec<f32> = Vec::new();
    let mut indices: Vec<u16> = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0f32; 3];
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = (positions.len() / 3) as u16;
            for (a, b) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0f32; 3];
                p[axis] = sign * 0.5;
                p[u] = a * 0.5;
                p[v] = b * 0.5;
                positions.extend_from_slice(&p);
                normals.extend_from_slice(&n);
            }
            // Counter-clockwise seen from outside.
            if sign > 0.0 {
                indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            } else {
                indices.extend_from_slice(&[base, base + 2, base + 1, base, base + 3, base + 2]);
            }
        }
    }
    let mut bin: Vec<u8> = Vec::new();
    bin.extend(positions.iter().flat_map(|f| f.to_le_bytes()));
    bin.extend(normals.iter().flat_map(|f| f.to_le_bytes()));
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let (pos_len, idx_len) = (positions.len() * 4, indices.len() * 2);
    std::fs::write(dir.join("cubes.bin"), &bin).expect("writing cubes.bin");
    let (s, c) = (15f32.to_radians().sin(), 15f32.to_radians().cos());
    let gltf = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"mesh": 0, "translation": [-0.8, 0, 0]}},
    {{"mesh": 0, "translation": [0.9, 0.2, -0.5], "rotation": [{s}, 0, {s}, {c}]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.3, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 0.5}}}}],
  "buffers": [{{"uri": "cubes.bin", "byteLength": {total}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": {pos_len}}},
    {{"buffer": 0, "byteOffset": {pos_len}, "byteLength": {pos_len}}},
    {{"buffer": 0, "byteOffset": {nrm_end}, "byteLength": {idx_len}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}},
    {{"bufferView": 1, "componentType": 5126, "count": 24, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": {count}, "type": "SCALAR"}}
  ]
}}"#,
        total = bin.len(),
        nrm_end = 2 * pos_len,
        count = indices.len(),
    );
    let path = dir.join("cubes.gltf");
    std::fs::write(&path, gltf).expect("writing cubes.gltf");
    path
}

#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn headless_example_renders_a_gltf_file_like_the_library() {
    if common::egl_context().is_none() {
        return;
    }
    let model = write_gltf(&scratch("gltf"));
    let out = scratch("headless.png");
    let _ = std::fs::remove_file(&out);
    let result = run_with_limit(
        Command::new(example("headless"))
            .arg(&model)
            .arg(&out)
            .arg(format!("{W}x{H}")),
        Duration::from_secs(120),
    );
    assert_success(&result, "the headless example");
    let img = load_png(&out);
    save_for_people(&img, "example-headless");
    assert_eq!(img.dimensions(), (W, H));
    assert_not_blank(&img, "headless example");

    // The same thing through the library in this process: the same image.
    let scene = Scene::load(model.to_str().expect("a UTF-8 path")).expect("loading the glTF file");
    let Some(reference) = builtin_render(&scene, median()) else {
        return;
    };
    let stats = flip(&reference, &img).expect("same sizes");
    eprintln!("headless example vs library: FLIP mean {:.4}", stats.mean);
    assert!(
        stats.mean < 0.002,
        "headless example vs library: FLIP mean {}",
        stats.mean
    );
}

#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn examples_refuse_bad_input_in_one_line() {
    let missing = scratch("no-such-model.gltf");
    let out = run_with_limit(
        Command::new(example("headless"))
            .arg(&missing)
            .arg(scratch("never.png")),
        Duration::from_secs(60),
    );
    assert_one_line_error(&out, "headless with a missing file");
    let out = run_with_limit(
        &mut Command::new(example("headless")),
        Duration::from_secs(60),
    );
    assert_one_line_error(&out, "headless without arguments");
    let out = run_with_limit(
        Command::new(example("retrofit")).args(["--method", "fastest"]),
        Duration::from_secs(60),
    );
    assert_one_line_error(&out, "retrofit with an unknown method");
    let out = run_with_limit(
        Command::new(example("retrofit")).args(["--size", "0x90"]),
        Duration::from_secs(60),
    );
    assert_one_line_error(&out, "retrofit with a zero size");
    // No display: one line saying so.
    let out = run_with_limit(
        Command::new(example("viewer"))
            .arg("builtin:box")
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET"),
        Duration::from_secs(60),
    );
    assert_one_line_error(&out, "viewer without a display");
    // The viewer reads its arguments and the scene before it opens a window.
    for args in [
        &["builtin:nonesuch"][..],
        &["--size", "huge"],
        &["--frames", "0"],
        &["builtin:box", "builtin:thin"],
        &["--bogus"],
    ] {
        let out = run_with_limit(
            Command::new(example("viewer")).args(args),
            Duration::from_secs(60),
        );
        assert_one_line_error(&out, &format!("viewer {args:?}"));
    }
}

// ---------------------------------------------------------------------------
// retrofit

fn run_retrofit(method: &str, out: &Path) -> image::RgbaImage {
    let _ = std::fs::remove_file(out);
    let result = run_with_limit(
        Command::new(example("retrofit"))
            .arg(out)
            .args(["--scene", "builtin:greebles", "--size", &format!("{W}x{H}")])
            .args(["--samples", "4", "--method", method]),
        Duration::from_secs(120),
    );
    assert_success(&result, &format!("the retrofit example ({method})"));
    let img = load_png(out);
    assert_eq!(img.dimensions(), (W, H));
    img
}

/// The example's engine lights with the same model as the built-in renderer
/// (GGX, Schlick-GGX visibility, Schlick Fresnel, Lambert, the same ambient
/// term, sky gradient and tonemap), so exact parity is not the question;
/// what differs is its G-buffer: albedo in RGBA8 (the renderer: RGBA16F), no
/// position attachment (the position is rebuilt from D24 depth; the renderer
/// stores it in RGBA32F and keys the resolve on it), emission in
/// R11F_G11F_B10F, and the sky computed in the lighting pass instead of
/// copied into the emissive attachment. Away from edges that is
/// quantisation-sized; at edges the two resolves weigh samples by different
/// keys (linearised D24 depth vs FP32 position), which moves a few edge
/// pixels a little. Measured on llvmpipe (FLIP mean, 160x90 greebles):
/// 0.0008 without MSAA, 0.0023 with 4x median, while MSAA itself changes the
/// image by 0.0127. The bounds allow about 4x the measured difference for
/// other drivers' rounding, stay well below the size of the MSAA effect, and
/// the example's MSAA image must be nearer the renderer's MSAA image than
/// the aliased one.
#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn retrofit_example_matches_the_builtin_pipeline() {
    let Some(_probe) = common::egl_context() else {
        return;
    };
    drop(_probe);
    let scene = Scene::load("builtin:greebles").expect("the built-in scene");
    let ours_none = run_retrofit("none", &scratch("retrofit-none.png"));
    let ours_median = run_retrofit("median", &scratch("retrofit-median.png"));
    let Some(theirs_none) = builtin_render(&scene, AaMode::None) else {
        return;
    };
    let Some(theirs_median) = builtin_render(&scene, median()) else {
        return;
    };
    save_for_people(&ours_none, "example-retrofit-none");
    save_for_people(&ours_median, "example-retrofit-median");
    save_for_people(&theirs_median, "example-retrofit-builtin-median");
    assert_not_blank(&ours_median, "retrofit example");

    let lighting = flip(&theirs_none, &ours_none).expect("same sizes");
    let msaa = flip(&theirs_median, &ours_median).expect("same sizes");
    let aliased = flip(&theirs_none, &ours_median).expect("same sizes");
    let effect = flip(&ours_none, &ours_median).expect("same sizes");
    eprintln!(
        "FLIP mean: lighting (none vs none) {:.4}, MSAA (median vs median) {:.4}, \
         example median vs renderer none {:.4}, example none vs median {:.4}",
        lighting.mean, msaa.mean, aliased.mean, effect.mean
    );
    assert!(
        lighting.mean < 0.004,
        "the engines' lighting differs: FLIP mean {}",
        lighting.mean
    );
    assert!(
        msaa.mean < 0.008,
        "the MSAA images differ: FLIP mean {}",
        msaa.mean
    );
    assert!(
        effect.mean > 0.006,
        "MSAA barely changed the example's image: FLIP mean {}",
        effect.mean
    );
    assert!(
        msaa.mean < aliased.mean,
        "the example's MSAA image is nearer the renderer's aliased image ({}) than its MSAA image ({})",
        aliased.mean,
        msaa.mean
    );
}

// ---------------------------------------------------------------------------
// viewer

#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn viewer_runs_in_a_window_and_switches_live() {
    let viewer = example("viewer");
    let Some(xvfb) = start_xvfb() else {
        return;
    };
    let shot = scratch("viewer.png");
    let _ = std::fs::remove_file(&shot);
    // One key per frame: no MSAA, taa, per-sample, back to median, its
    // second layer on, off and on, FXAA on and off, SMAA on and off, the next
    // sample count, every view round to the final image, orbit away and
    // back. The viewer fails on any blank frame. The views are the final
    // image, the attachments the scene-adaptive plan keeps, depth and complex.
    let plan = deferred_msaa_lab::renderer::plan::Plan::for_scene(
        &Scene::load("builtin:box").expect("the built-in scene"),
        &deferred_msaa_lab::renderer::plan::PlanContext {
            sample_counts: vec![4],
            driver_memory: None,
        },
        &RenderOptions::default(),
    )
    .expect("a plan");
    let views = 1 + plan.layout.colors.len() + 2;
    let keys = format!("0563tttffssn{}lh", "v".repeat(views));
    let frames = keys.chars().count() + 2;
    let result = run_with_limit(
        Command::new(&viewer)
            .args(["builtin:box", "--size", &format!("{W}x{H}")])
            .args(["--frames", &frames.to_string(), "--keys", &keys])
            .arg("--screenshot")
            .arg(&shot)
            .env("DISPLAY", xvfb.display())
            .env_remove("WAYLAND_DISPLAY"),
        Duration::from_secs(300),
    );
    drop(xvfb);
    assert_success(&result, "the viewer under Xvfb");
    let img = load_png(&shot);
    save_for_people(&img, "example-viewer");
    assert_eq!(img.dimensions(), (W, H), "the window was not {W}x{H}");
    assert_not_blank(&img, "viewer screenshot");
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        stdout.contains("median:layers=2"),
        "the title should name the method and its second layer: {stdout}"
    );

    // The window shows what the renderer renders: the model is there.
    let scene = Scene::load("builtin:box").expect("the built-in scene");
    let two_layers = AaMode::Resolve(ResolveSettings {
        layers: 2,
        ..ResolveSettings::default()
    });
    let Some(reference) = builtin_render(&scene, two_layers) else {
        return;
    };
    let stats = flip(&reference, &img).expect("same sizes");
    eprintln!("viewer screenshot vs renderer: FLIP mean {:.4}", stats.mean);
    assert!(
        stats.mean < 0.02,
        "viewer screenshot vs renderer: FLIP mean {}",
        stats.mean
    );
    let model_pixels = reference
        .pixels()
        .zip(img.pixels())
        .filter(|(r, s)| {
            let red = |p: &image::Rgba<u8>| p[0] as i32 - p[2] as i32 > 60;
            red(r) && red(s)
        })
        .count();
    assert!(
        model_pixels > 200,
        "the red cube is missing from the window: {model_pixels} pixels"
    );
}

/// A thousand live mode switches in the viewer (method and FXAA, one per
/// frame, each a `Renderer::set_options` that builds new resources and frees
/// the old): no GL object outlives the run and resident memory stays flat
/// after the first hundred frames (every mode has been built by then).
#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn viewer_survives_a_thousand_mode_switches_without_leaking() {
    let viewer = example("viewer");
    let Some(xvfb) = start_xvfb() else {
        return;
    };
    let keys = "mf".repeat(500);
    let frames = keys.len() + 1;
    let result = run_with_limit(
        Command::new(&viewer)
            .args(["builtin:box", "--size", "64x36"])
            .args(["--frames", &frames.to_string(), "--keys", &keys])
            .env("DISPLAY", xvfb.display())
            .env_remove("WAYLAND_DISPLAY"),
        Duration::from_secs(600),
    );
    drop(xvfb);
    assert_success(&result, "the viewer's thousand switches");
    let stdout = String::from_utf8_lossy(&result.stdout);
    let number_after = |prefix: &str| -> i64 {
        let line = stdout
            .lines()
            .find_map(|l| l.strip_prefix(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in: {stdout}"));
        line.split_whitespace()
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no number in `{line}`"))
    };
    assert_eq!(
        number_after("viewer: live GL objects at exit: "),
        0,
        "GL objects outlived the viewer"
    );
    let grown_kib = number_after("viewer: resident memory changed by ");
    // Allocator noise is a few MiB; one leaked small texture per switch
    // would be tens of MiB over 900 switches.
    assert!(
        grown_kib < 16 * 1024,
        "resident memory grew by {grown_kib} KiB over 900 switches"
    );
}
