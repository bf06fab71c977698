//! Per-sample and complex lighting, and forward MSAA, against supersampled
//! references: every built-in scene, one-surface pixels, growing light
//! counts, the complex-pixel stencil and its fallback without
//! `gl_SampleMaskIn`.

use super::*;

fn render_with(
    gl: &glow::Context,
    ctx: &HeadlessContext,
    scene: &Scene,
    opts: &RenderOptions,
    what: &str,
) -> image::RgbaImage {
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), scene, opts).expect("renderer");
    let img = render_checked(gl, &mut renderer, what);
    renderer.destroy(gl);
    img
}

/// The scene rendered without MSAA at 4W×4H, tonemapped per pixel and
/// box-filtered 4×4 in linear light: the 16-sample supersampled reference.
fn supersampled(gl: &glow::Context, ctx: &HeadlessContext, scene: &Scene) -> image::RgbaImage {
    let big = RenderOptions {
        width: 4 * W,
        height: 4 * H,
        ..options(AaMode::None)
    };
    bench::downsample_srgb(&render_with(gl, ctx, scene, &big, "4x4 reference"), 4)
        .expect("4W x 4H divides into 4x4 blocks")
}

#[test]
fn per_sample_and_complex_render_every_builtin_scene() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    for name in Scene::builtin_names() {
        let scene = Scene::load(&format!("builtin:{name}")).expect("builtin scene");
        let mut renderer = renderer(&ctx, &scene, &options(AaMode::PerSample));
        let per_sample = render_checked(gl, &mut renderer, &format!("{name} per-sample"));
        let pixels = u64::from(W * H);
        assert_eq!(renderer.per_sample_pixels(), Some(pixels), "{name}");
        assert_eq!(
            renderer.technique::<Complex>().and_then(Complex::fraction),
            None,
            "{name}"
        );
        assert!(renderer.technique::<Complex>().is_none());

        renderer
            .set_options(gl, &options(AaMode::Complex))
            .expect("switching to complex");
        assert_eq!(
            renderer.technique::<Complex>().and_then(Complex::fraction),
            None,
            "no frame yet"
        );
        let complex = render_checked(gl, &mut renderer, &format!("{name} complex"));
        let fraction = renderer
            .technique::<Complex>()
            .and_then(Complex::fraction)
            .expect("a complex fraction");
        assert!((0.0..=1.0).contains(&fraction), "{name}: {fraction}");
        // The query counts exactly the pixels the stencil marks.
        let mask = renderer
            .technique::<Complex>()
            .expect("complex")
            .read_mask(gl)
            .expect("reading the mask")
            .expect("a mask");
        let marked = mask.pixels().filter(|p| p[0] != 0).count() as u64;
        assert_eq!(renderer.per_sample_pixels(), Some(marked), "{name}");
        // Complex pixels are lit exactly as per-sample lights them, simple
        // pixels (all samples one surface) from sample 0: the same image.
        let flip = deferred_msaa_lab::compare::flip(&per_sample, &complex).expect("same size");
        eprintln!(
            "{name}: complex fraction {fraction:.3}; complex vs per-sample FLIP mean {:.5}",
            flip.mean
        );
        assert!(
            flip.mean < 0.002,
            "{name}: complex differs from per-sample (FLIP mean {})",
            flip.mean
        );
        save(&per_sample, &format!("{name}-per-sample"));
        save(&complex, &format!("{name}-complex"));
        renderer.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// One triangle far larger than the view, facing the camera 4 units away,
/// lit by `n` point lights spread in front of it: every sample of every
/// pixel sees the same surface at the same point.
fn one_surface_scene(n: usize) -> Scene {
    let z = -4.0;
    let wall = Object {
        name: "wall".into(),
        positions: vec![[-40.0, -20.0, z], [40.0, -20.0, z], [0.0, 60.0, z]],
        normals: vec![[0.0, 0.0, 1.0]; 3],
        uvs: vec![[0.0, 0.0]; 3],
        indices: vec![0, 1, 2],
        material: 0,
        transform: glam::Mat4::IDENTITY,
        antialias: true,
    };
    let palette = [
        glam::Vec3::new(1.0, 0.8, 0.6),
        glam::Vec3::new(0.6, 0.8, 1.0),
        glam::Vec3::new(1.0, 0.6, 0.8),
        glam::Vec3::new(0.8, 1.0, 0.7),
    ];
    // Spread over the view (about ±3.4 by ±1.9 on the wall), 0.4 to 1.2 in
    // front of it; together about as bright at any count.
    let lights = (0..n)
        .map(|i| {
            let t = i as f32;
            let x = ((t * 0.618_034 + 0.1).fract() - 0.5) * 6.4;
            let y = ((t * 0.414_214 + 0.3).fract() - 0.5) * 3.6;
            Light::point(
                glam::Vec3::new(x, y, z + 0.4 + 0.2 * (i % 5) as f32),
                palette[i % palette.len()],
                4.0 / n as f32,
                Some(3.0),
            )
        })
        .collect();
    let mut scene = Scene {
        name: format!("one surface, {n} lights"),
        objects: vec![wall],
        materials: vec![Material::solid("wall", [0.6, 0.55, 0.5], 0.0, 0.4)],
        textures: Vec::new(),
        lights,
        camera: Camera::look_at(glam::Vec3::ZERO, glam::Vec3::NEG_Z, 0.9, 0.1, Some(50.0)),
        background: Background::Black,
        warnings: Vec::new(),
        bounds: Aabb::EMPTY,
        bars: Vec::new(),
    };
    scene.recompute_bounds();
    scene
}

/// The HDR target after one frame of `scene` with `aa`.
fn hdr_of(
    gl: &glow::Context,
    ctx: &HeadlessContext,
    scene: &Scene,
    aa: AaMode,
    what: &str,
) -> Vec<f32> {
    let mut r = renderer(ctx, scene, &options(aa));
    render_checked(gl, &mut r, what);
    let mut readback = Readback::new(gl).expect("readback");
    let hdr = readback
        .read(gl, r.hdr_texture(), 1)
        .expect("reading the HDR target");
    readback.destroy(gl);
    r.destroy(gl);
    hdr.data
}

/// Where every sample of a pixel sees the same surface, lighting every
/// sample and averaging is lighting the pixel once: `per-sample` and
/// `complex` store the HDR values `none` stores, at one light and at
/// several batches of them (20 and 48 lights are more than one
/// [`LIGHTS_PER_BATCH`](deferred_msaa_lab::renderer::shaders::LIGHTS_PER_BATCH)).
#[test]
fn per_sample_equals_one_sample_lighting_where_each_pixel_holds_one_surface() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let counts = [1, 8, 20, 48];
    assert!(
        counts
            .iter()
            .any(|&n| n > 2 * deferred_msaa_lab::renderer::shaders::LIGHTS_PER_BATCH)
    );
    for n in counts {
        let scene = one_surface_scene(n);
        let none = hdr_of(gl, &ctx, &scene, AaMode::None, &format!("{n} lights, none"));
        let lit = none.chunks(4).filter(|p| p[0] + p[1] + p[2] > 0.05).count();
        assert!(
            lit > none.len() / 4 / 2,
            "{n} lights: the wall is mostly unlit ({lit} pixels)"
        );
        for (method, aa) in [
            ("per-sample", AaMode::PerSample),
            ("complex", AaMode::Complex),
        ] {
            let other = hdr_of(gl, &ctx, &scene, aa, &format!("{n} lights, {method}"));
            // The same float operations on the same G-buffer values, stored
            // in the same half floats: a quarter of a half float's spacing
            // (2^-10 of the value at most) lets no stored value change.
            let worst = none
                .iter()
                .zip(&other)
                .map(|(a, b)| (a - b).abs() / a.abs().max(1e-3))
                .fold(0.0f32, f32::max);
            let differ = none.iter().zip(&other).filter(|(a, b)| a != b).count();
            eprintln!(
                "{n} lights, {method}: {differ} HDR values differ from none's, worst relative difference {worst:e}"
            );
            assert!(
                worst <= 2f32.powi(-12),
                "{n} lights: {method} differs from one-sample lighting by {worst:e} (relative), {differ} values"
            );
        }
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// The ground truth holds at any light count: on `builtin:halo` (point
/// lights just behind a box's edges), `per-sample`'s FLIP against the
/// supersampled reference stays at or below `none`'s, over the edge pixels
/// and over the interior, with the scene's own lights and with 8, 20 and
/// 48 more.
#[test]
fn per_sample_stays_at_or_below_none_against_the_reference_as_lights_are_added() {
    if common::egl_context().is_none() {
        return;
    }
    for lights in [0, 8, 20, 48] {
        let config = bench::BenchConfig {
            scenes: vec!["builtin:halo".into()],
            width: 160,
            height: 90,
            methods: bench::parse_methods("none,per-sample").expect("methods"),
            lights,
            frames: 1,
            warmup: 0,
            ..bench::BenchConfig::default()
        };
        let out = bench::run(&config).expect("bench runs");
        let run = |m: &str| {
            out.report
                .runs
                .iter()
                .find(|r| r.method == m)
                .unwrap_or_else(|| panic!("no `{m}` run"))
        };
        let (none, per_sample) = (run("none"), run("per-sample"));
        for (part, a, b) in [
            ("edges", per_sample.flip_edges, none.flip_edges),
            ("interior", per_sample.flip_interior, none.flip_interior),
        ] {
            let (a, b) = (a.expect("per-sample FLIP"), b.expect("none FLIP"));
            eprintln!("{lights} more lights, {part}: per-sample {a:.5}, none {b:.5}");
            assert!(
                a <= b,
                "{lights} more lights: per-sample's FLIP over the {part} ({a}) is above none's ({b})"
            );
        }
    }
}

#[test]
fn per_sample_lighting_has_the_least_error_against_supersampling() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let average = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Average,
        ..ResolveSettings::default()
    });
    for name in ["greebles", "thin"] {
        let scene = Scene::load(&format!("builtin:{name}")).expect("scene");
        let reference = supersampled(gl, &ctx, &scene);
        save(&reference, &format!("{name}-ssaa-reference"));
        let mut errors = Vec::new();
        for (method, aa) in [
            ("none", AaMode::None),
            ("average", average),
            ("median", median()),
            ("per-sample", AaMode::PerSample),
            ("complex", AaMode::Complex),
        ] {
            let img = render_with(gl, &ctx, &scene, &options(aa), &format!("{name} {method}"));
            let flip = deferred_msaa_lab::compare::flip(&reference, &img).expect("same size");
            errors.push((method, flip.mean));
        }
        eprintln!("{name}: FLIP mean against the 4x4 reference: {errors:?}");
        let error = |m: &str| {
            errors
                .iter()
                .find(|(n, _)| *n == m)
                .map(|(_, e)| *e)
                .expect("measured")
        };
        let per_sample = error("per-sample");
        for other in ["none", "average", "median"] {
            assert!(
                per_sample < error(other),
                "{name}: per-sample ({per_sample}) does not beat {other} ({}): {errors:?}",
                error(other)
            );
        }
        // Complex pixels are lit the same way; simple pixels are uniform.
        let complex = error("complex");
        assert!(
            (complex - per_sample).abs() <= 0.002 + 0.02 * per_sample,
            "{name}: complex ({complex}) is not within a small margin of per-sample ({per_sample})"
        );
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn complex_marks_a_minority_of_pixels_and_the_stencil_limits_per_sample_lighting() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:greebles").expect("scene");
    let mut renderer = renderer(&ctx, &scene, &options(AaMode::PerSample));
    render_checked(gl, &mut renderer, "greebles per-sample");
    let all = renderer.per_sample_pixels().expect("a count");
    assert_eq!(all, u64::from(W * H));
    renderer
        .set_options(gl, &options(AaMode::Complex))
        .expect("complex");
    let img = render_checked(gl, &mut renderer, "greebles complex");
    let fraction = renderer
        .technique::<Complex>()
        .and_then(Complex::fraction)
        .expect("a fraction");
    let some = renderer.per_sample_pixels().expect("a count");
    let mask = renderer
        .technique::<Complex>()
        .expect("complex")
        .read_mask(gl)
        .expect("reading the mask")
        .expect("a mask");
    save(&img, "greebles-complex");
    if let Some(dir) = std::env::var_os("DEFERRED_MSAA_SAVE_RENDERS") {
        let _ = mask.save(std::path::PathBuf::from(dir).join("greebles-complex-mask.png"));
    }
    eprintln!(
        "greebles: {some} of {all} pixels lit per sample (complex fraction {fraction:.3}); coverage flags: {}",
        Capabilities::query(gl).sample_mask_in
    );
    assert!(
        fraction > 0.0 && fraction < 0.5,
        "complex fraction {fraction}"
    );
    assert!(some < all, "the stencil did not limit the per-sample pass");
    assert_eq!(
        mask.pixels().filter(|p| p[0] != 0).count() as u64,
        some,
        "the per-sample pass lit other pixels than the mask marks"
    );
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// The child of `complex_falls_back_to_the_discontinuity_test_without_sample_mask_in`,
/// run in a process whose context has no `gl_SampleMaskIn`.
#[test]
#[ignore = "run by its parent test in a child process with a GL 3.2 context"]
fn complex_without_sample_mask_in_child() {
    let _ = env_logger::builder()
        .filter_level(log::LevelFilter::Warn)
        .try_init();
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    assert!(
        !Capabilities::query(gl).sample_mask_in,
        "the child's context still has gl_SampleMaskIn"
    );
    let scene = Scene::load("builtin:greebles").expect("scene");
    let per_sample = render_with(
        gl,
        &ctx,
        &scene,
        &options(AaMode::PerSample),
        "per-sample, GL 3.2",
    );
    let mut renderer = renderer(&ctx, &scene, &options(AaMode::Complex));
    let complex = render_checked(gl, &mut renderer, "complex, GL 3.2");
    let fraction = renderer
        .technique::<Complex>()
        .and_then(Complex::fraction)
        .expect("a fraction");
    let flip = deferred_msaa_lab::compare::flip(&per_sample, &complex).expect("same size");
    eprintln!(
        "child: complex fraction {fraction:.3} from discontinuities alone; complex vs per-sample FLIP mean {:.5}",
        flip.mean
    );
    assert!(fraction > 0.0 && fraction < 0.5, "{fraction}");
    assert!(flip.mean < 0.005, "FLIP mean {}", flip.mean);
    renderer.destroy(gl);
}

#[test]
fn complex_falls_back_to_the_discontinuity_test_without_sample_mask_in() {
    if common::egl_context().is_none() {
        return;
    }
    // A real 3.2 core context without the extensions that give GLSL 1.50
    // gl_SampleMaskIn.
    let exe = std::env::current_exe().expect("the test binary's path");
    let out = std::process::Command::new(exe)
        .args([
            "--ignored",
            "--exact",
            "renderer::per_sample::complex_without_sample_mask_in_child",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env("MESA_GL_VERSION_OVERRIDE", "3.2")
        .env("MESA_GLSL_VERSION_OVERRIDE", "150")
        .env(
            "MESA_EXTENSION_OVERRIDE",
            "-GL_ARB_gpu_shader5 -GL_ARB_sample_shading",
        )
        .env_remove("RUST_LOG")
        .output()
        .expect("running the child test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("{stderr}");
    assert!(out.status.success(), "child failed:\n{stdout}\n{stderr}");
    assert!(
        stdout.contains("1 passed"),
        "the child test did not run:\n{stdout}"
    );
    if stderr.contains("skipped:") {
        return;
    }
    let line = stderr
        .lines()
        .find(|l| l.contains("method `complex`: no coverage mask"))
        .unwrap_or_else(|| panic!("no log line about the fallback:\n{stderr}"));
    assert!(
        line.contains("gl_SampleMaskIn") && line.contains("discontinuity test alone"),
        "{line}"
    );
}

/// Forward MSAA (`RenderOptions::forward_msaa`): the transparent objects
/// of `builtin:transparent` and the light cubes of `builtin:lamps`, drawn
/// forward after lighting, come closer to the supersampled reference
/// through the retrofit's forward target than single-sampled, with one
/// layer and two; a method without the multisampled depth refuses it in
/// one line; nothing leaks.
#[test]
fn forward_msaa_anti_aliases_what_is_drawn_after_lighting() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let two_layers = AaMode::Resolve(ResolveSettings {
        layers: 2,
        ..ResolveSettings::default()
    });
    for name in ["lamps", "transparent"] {
        let scene = Scene::load(&format!("builtin:{name}")).expect("scene");
        let reference = supersampled(gl, &ctx, &scene);
        let error = |opts: &RenderOptions, what: &str| {
            let img = render_with(gl, &ctx, &scene, opts, &format!("{name} {what}"));
            deferred_msaa_lab::compare::flip(&reference, &img)
                .expect("same size")
                .mean
        };
        let none = error(&options(AaMode::None), "none");
        for (label, aa) in [("median", median()), ("median:layers=2", two_layers)] {
            let single = error(&options(aa), label);
            let forward = error(
                &RenderOptions {
                    forward_msaa: true,
                    ..options(aa)
                },
                &format!("{label}:forward"),
            );
            eprintln!(
                "{name}: FLIP against the 4x4 reference: none {none:.4}, {label} {single:.4}, {label}:forward {forward:.4}"
            );
            assert!(
                forward < single,
                "{name}: {label} with forward MSAA ({forward:.4}) is not below without ({single:.4})"
            );
        }
    }
    let refused = RenderOptions {
        forward_msaa: true,
        ..options(AaMode::None)
    }
    .validate()
    .expect_err("forward MSAA without a multisampled G-buffer");
    assert!(
        refused.to_string().contains("forward MSAA") && !refused.to_string().contains('\n'),
        "{refused}"
    );
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}
