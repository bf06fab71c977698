//! Method `sparse`: the multisampled G-buffer as per-pixel linked lists of
//! blocks (`src/renderer/technique/sparse/`). Its error against the supersampled
//! reference, its memory against the full multisampled G-buffer, pool
//! overflow, selective anti-aliasing, object lifetimes, the bench's report,
//! and the typed error on contexts without shader storage buffers.
//!
//! On a context that lacks what `sparse` needs, every test here asserts
//! the typed error instead of rendering; `unsupported_contexts_get_a_typed_error`
//! also forces that case through Mesa (`MESA_EXTENSION_OVERRIDE`) in a child
//! process, so the refusal is exercised on every run. (Mesa's OpenGL 3.2
//! override still lists the extensions, so there `sparse` really runs.)

use crate::common;

use deferred_msaa::Error as CoreError;
use deferred_msaa_lab::Error;
use deferred_msaa_lab::bench::{self, BenchConfig, downsample_srgb};
use deferred_msaa_lab::compare;
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_lab::gbuffer::GBufferLayout;
use deferred_msaa_lab::gl::live_objects;
use deferred_msaa_lab::renderer::technique::Sparse;
use deferred_msaa_lab::renderer::{
    AaMode, MASK_OVERFLOW, MASK_SINGLE, RenderOptions, Renderer, SparseOptions,
};
use deferred_msaa_lab::resolve::Region;
use deferred_msaa_lab::scene::Scene;

/// An empty region: every pixel takes one sample (the single-sample path).
const NOWHERE: Region = Region::Rect {
    x: 0.0,
    y: 0.0,
    width: 0.0,
    height: 0.0,
};
use glow::HasContext;
use image::RgbaImage;

const W: u32 = 128;
const H: u32 = 72;

/// What `sparse` needs, listed independently of the crate: if the context
/// lacks any of these, the renderer must refuse with `Error::Unsupported`.
const NEEDED: &[&str] = &[
    "GL_ARB_shader_storage_buffer_object",
    "GL_ARB_shader_atomic_counters",
    "GL_ARB_gpu_shader5",
    "GL_ARB_shading_language_packing",
    "GL_ARB_shading_language_420pack",
    "GL_ARB_shader_image_load_store",
    "GL_ARB_post_depth_coverage",
];

fn options(aa: AaMode, width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        samples: 4,
        aa,
        fxaa: false,
        ..RenderOptions::default()
    }
}

fn sparse(o: SparseOptions) -> AaMode {
    AaMode::Sparse(o)
}

/// Whether the context has what `sparse` needs. When it does not, check
/// that the renderer says so with the typed error, naming what is missing.
fn supported(ctx: &HeadlessContext, scene: &Scene) -> bool {
    let gl = ctx.gl();
    let ext = gl.supported_extensions();
    let missing: Vec<&str> = NEEDED
        .iter()
        .copied()
        .filter(|e| !ext.contains(*e))
        .collect();
    if missing.is_empty() {
        return true;
    }
    let opts = options(sparse(SparseOptions::default()), W, H);
    match Renderer::new(gl, |n| ctx.get_proc_address(n), scene, &opts) {
        Err(Error::Core(CoreError::Unsupported { requires, .. })) => {
            for m in &missing {
                assert!(requires.contains(m), "`{requires}` does not name {m}");
            }
            eprintln!("sparse unsupported here, as the renderer says: missing {missing:?}");
        }
        Err(e) => panic!("expected Error::Unsupported, got {e}"),
        Ok(r) => {
            r.destroy(gl);
            panic!("sparse rendered on a context without {missing:?}");
        }
    }
    false
}

/// One frame; the final image and the renderer (to ask it more).
fn frame(ctx: &HeadlessContext, scene: &Scene, opts: &RenderOptions) -> (RgbaImage, Renderer) {
    let gl = ctx.gl();
    let mut r = Renderer::new(gl, |n| ctx.get_proc_address(n), scene, opts)
        .unwrap_or_else(|e| panic!("{}: {e}", opts.aa.name()));
    r.render(gl)
        .unwrap_or_else(|e| panic!("{}: {e}", opts.aa.name()));
    let img = r.read_final(gl).expect("final image");
    (img, r)
}

fn image(ctx: &HeadlessContext, scene: &Scene, opts: &RenderOptions) -> RgbaImage {
    let (img, r) = frame(ctx, scene, opts);
    r.destroy(ctx.gl());
    img
}

/// The bench's reference: the whole pipeline at 4x4 the size, box-filtered
/// in linear light.
fn reference(ctx: &HeadlessContext, scene: &Scene) -> RgbaImage {
    let big = image(ctx, scene, &options(AaMode::None, W * 4, H * 4));
    downsample_srgb(&big, 4).expect("downsampling")
}

fn flip(a: &RgbaImage, b: &RgbaImage) -> f64 {
    f64::from(compare::flip(a, b).expect("same size").mean)
}

/// Pixels (row 0 at the top) where `a` and `b` differ in any channel.
fn differing(a: &RgbaImage, b: &RgbaImage) -> Vec<(u32, u32)> {
    a.enumerate_pixels()
        .filter(|(x, y, p)| b.get_pixel(*x, *y) != *p)
        .map(|(x, y, _)| (x, y))
        .collect()
}

/// `sparse` computes per-sample lighting's result once per distinct
/// fragment; it differs from per-sample only by how blocks are packed
/// (half floats as the RGBA16F attachments, 16-bit octahedral normals,
/// positions from a 32-bit depth). Criterion: its FLIP error against the
/// reference is within 5 % of per-sample's, plus 0.001 for FLIP's own
/// granularity on a 9216-pixel image (measured: they agree to 0.0001);
/// it is clearly below `none`'s; and it takes less memory than the full
/// 4x multisampled G-buffer, measured from what each allocates.
#[test]
fn error_is_per_samples_and_memory_is_below_the_full_gbuffer() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    for name in ["greebles", "thin"] {
        let scene = Scene::load(&format!("builtin:{name}")).unwrap();
        if !supported(&ctx, &scene) {
            return;
        }
        let reference = reference(&ctx, &scene);
        let none = image(&ctx, &scene, &options(AaMode::None, W, H));
        let full_layout = RenderOptions {
            adaptive: false,
            layout: GBufferLayout::recommended(),
            ..options(AaMode::PerSample, W, H)
        };
        let (per_sample, ps) = frame(&ctx, &scene, &full_layout);
        let twin_bytes = ps.retrofit().expect("per-sample twins").twin().bytes();
        let samples = ps.samples();
        ps.destroy(ctx.gl());
        let (sparse_img, sp) = frame(
            &ctx,
            &scene,
            &options(sparse(SparseOptions::default()), W, H),
        );
        let memory = sp
            .technique::<Sparse>()
            .and_then(Sparse::allocated)
            .expect("sparse memory");
        let stats = sp
            .technique::<Sparse>()
            .expect("sparse")
            .stats(ctx.gl())
            .unwrap()
            .expect("sparse stats");
        assert_eq!(sp.samples(), samples, "{name}");
        sp.destroy(ctx.gl());

        let (e_none, e_ps, e_sparse) = (
            flip(&reference, &none),
            flip(&reference, &per_sample),
            flip(&reference, &sparse_img),
        );
        eprintln!(
            "{name}: FLIP none {e_none:.4}, per-sample {e_ps:.4}, sparse {e_sparse:.4}; \
             sparse vs per-sample {:.5}; {memory:?} = {} B against {twin_bytes} B of twins; {stats:?}",
            flip(&per_sample, &sparse_img),
            memory.total()
        );
        assert!(
            (e_sparse - e_ps).abs() <= 0.05 * e_ps + 0.001,
            "{name}: sparse {e_sparse} is not near per-sample {e_ps}"
        );
        assert!(
            e_sparse < 0.8 * e_none,
            "{name}: sparse {e_sparse} does not anti-alias (none {e_none})"
        );
        assert_eq!(stats.overflow_pixels, 0, "{name}: the default pool ran out");
        assert!(
            stats.pool_requested > 0,
            "{name}: no pixel took a pool block"
        );
        let full = GBufferLayout::recommended().bytes(W, H, samples);
        assert_eq!(twin_bytes, full, "the twins are the full 4x G-buffer");
        assert!(
            memory.total() < full,
            "{name}: sparse takes {} B, the full {samples}x G-buffer {full} B",
            memory.total()
        );
        assert_eq!(
            memory.depth,
            u64::from(W * H * samples) * 8,
            "the pre-pass is D32F_S8"
        );
    }
}

/// More lights than one light block holds (256): both `sparse` and
/// `per-sample` light in several additive draws and average linearly; the
/// criterion of the test above holds there too.
#[test]
fn many_lights_are_lit_in_several_draws_like_per_sample() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let mut scene = Scene::load("builtin:greebles").unwrap();
    if !supported(&ctx, &scene) {
        return;
    }
    let lights = bench::extra_lights(&scene.bounds, 300);
    scene.lights.extend(lights);
    let reference = reference(&ctx, &scene);
    let per_sample = image(&ctx, &scene, &options(AaMode::PerSample, W, H));
    let sparse_img = image(
        &ctx,
        &scene,
        &options(sparse(SparseOptions::default()), W, H),
    );
    let (e_ps, e_sparse) = (flip(&reference, &per_sample), flip(&reference, &sparse_img));
    eprintln!(
        "{} lights: FLIP per-sample {e_ps:.4}, sparse {e_sparse:.4}",
        scene.lights.len()
    );
    assert!(
        (e_sparse - e_ps).abs() <= 0.05 * e_ps + 0.001,
        "sparse {e_sparse} is not near per-sample {e_ps}"
    );
}

/// A pool of a few blocks: the pixels that asked for more fall back to
/// sample 0 and are counted; every pixel is either the full-pool image's
/// (all its blocks fit) or the single-sample path's (it fell back), so
/// nothing is garbage. Also bounded by `none`'s error: a fallback pixel is
/// a single-sample pixel.
#[test]
fn pool_overflow_falls_back_to_sample_zero_and_is_counted() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let scene = Scene::load("builtin:greebles").unwrap();
    if !supported(&ctx, &scene) {
        return;
    }
    let reference = reference(&ctx, &scene);
    let none = image(&ctx, &scene, &options(AaMode::None, W, H));
    let full = image(
        &ctx,
        &scene,
        &options(sparse(SparseOptions::default()), W, H),
    );
    let single = image(
        &ctx,
        &scene,
        &options(
            sparse(SparseOptions {
                region: Some(NOWHERE),
                ..SparseOptions::default()
            }),
            W,
            H,
        ),
    );
    for cap in [0u32, 64] {
        let opts = options(
            sparse(SparseOptions {
                pool_blocks: Some(cap),
                ..SparseOptions::default()
            }),
            W,
            H,
        );
        let (img, r) = frame(&ctx, &scene, &opts);
        let gl = ctx.gl();
        let stats = r
            .technique::<Sparse>()
            .expect("sparse")
            .stats(gl)
            .unwrap()
            .expect("stats");
        let mask = r
            .technique::<Sparse>()
            .expect("sparse")
            .read_mask(gl)
            .unwrap()
            .expect("mask");
        assert_eq!(
            r.technique::<Sparse>()
                .and_then(Sparse::allocated)
                .unwrap()
                .pool,
            32 * u64::from(cap.max(1))
        );
        r.destroy(gl);
        assert_eq!(stats.pool_capacity, cap);
        assert!(stats.pool_requested > cap, "{stats:?}");
        assert_eq!(stats.pool_used(), cap);
        assert!(stats.overflow_pixels > 0, "{stats:?}");
        let flagged: Vec<(u32, u32)> = mask
            .enumerate_pixels()
            .filter(|(_, _, v)| v[0] == MASK_OVERFLOW)
            .map(|(x, y, _)| (x, y))
            .collect();
        assert_eq!(flagged.len() as u32, stats.overflow_pixels);
        for (x, y, p) in img.enumerate_pixels() {
            let expected = if mask.get_pixel(x, y)[0] == MASK_OVERFLOW {
                single.get_pixel(x, y)
            } else {
                full.get_pixel(x, y)
            };
            assert_eq!(p, expected, "pool {cap}: pixel ({x}, {y})");
        }
        let (e, e_none, e_full, e_single) = (
            flip(&reference, &img),
            flip(&reference, &none),
            flip(&reference, &full),
            flip(&reference, &single),
        );
        eprintln!(
            "pool {cap}: {stats:?}; FLIP {e:.4} (full pool {e_full:.4}, single-sample path \
             {e_single:.4}, none {e_none:.4})"
        );
        assert!(
            e <= e_single.max(e_full) + 0.001,
            "pool {cap}: FLIP {e} beyond the single-sample path's {e_single}"
        );
    }
}

/// Outside a rectangle (or an ellipse) the image is the single-sample
/// path's (every pixel sample 0's), inside it the anti-aliased one's; the
/// same for the pixels a depth limit or an object's flag marks.
#[test]
fn selective_antialiasing_keeps_sample_zero_where_asked() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let mut scene = Scene::load("builtin:greebles").unwrap();
    if !supported(&ctx, &scene) {
        return;
    }
    let with = |o: SparseOptions, scene: &Scene| {
        let (img, r) = frame(&ctx, scene, &options(sparse(o), W, H));
        let mask = r
            .technique::<Sparse>()
            .expect("sparse")
            .read_mask(ctx.gl())
            .unwrap()
            .expect("mask");
        r.destroy(ctx.gl());
        (img, mask)
    };
    let (full, _) = with(SparseOptions::default(), &scene);
    let nowhere = SparseOptions {
        region: Some(NOWHERE),
        ..SparseOptions::default()
    };
    let (single, _) = with(nowhere, &scene);
    let anti_aliased = differing(&full, &single);
    assert!(
        anti_aliased.len() > 50,
        "only {} pixels differ between anti-aliased and single-sample",
        anti_aliased.len()
    );

    let rect = Region::Rect {
        x: 30.0,
        y: 10.0,
        width: 60.0,
        height: 40.0,
    };
    let (img, _) = with(
        SparseOptions {
            region: Some(rect),
            ..SparseOptions::default()
        },
        &scene,
    );
    let mut inside_aa = 0;
    for (x, y, p) in img.enumerate_pixels() {
        if rect.contains_pixel(x, y, H) {
            assert_eq!(p, full.get_pixel(x, y), "inside ({x}, {y})");
            inside_aa += usize::from(anti_aliased.contains(&(x, y)));
        } else {
            assert_eq!(p, single.get_pixel(x, y), "outside ({x}, {y})");
        }
    }
    assert!(inside_aa > 0, "the rectangle holds no anti-aliased pixel");

    // An ellipse; pixels within float rounding of its edge are not judged.
    let (cx, cy, rx, ry) = (64.0f32, 36.0f32, 40.3f32, 22.7f32);
    let (img, _) = with(
        SparseOptions {
            region: Some(Region::Ellipse {
                x: f64::from(cx),
                y: f64::from(cy),
                rx: f64::from(rx),
                ry: f64::from(ry),
            }),
            ..SparseOptions::default()
        },
        &scene,
    );
    for (x, y, p) in img.enumerate_pixels() {
        let (dx, dy) = ((x as f32 + 0.5 - cx) / rx, (y as f32 + 0.5 - cy) / ry);
        let d = dx * dx + dy * dy;
        if d < 0.99 {
            assert_eq!(p, full.get_pixel(x, y), "inside ({x}, {y})");
        } else if d > 1.01 {
            assert_eq!(p, single.get_pixel(x, y), "outside ({x}, {y})");
        }
    }

    // A depth limit at the distance of the scene's centre, then one object
    // left out of anti-aliasing: the marked pixels are single-sample ones,
    // the others anti-aliased, and both kinds occur.
    let camera_to_center = (scene.camera.position() - scene.bounds.center()).length();
    let limited = SparseOptions {
        max_depth: Some(camera_to_center),
        ..SparseOptions::default()
    };
    let (by_depth, depth_mask) = with(limited, &scene);
    let biggest = (0..scene.objects.len())
        .max_by_key(|&k| scene.objects[k].indices.len())
        .expect("an object");
    scene.objects[biggest].antialias = false;
    let (by_flag, flag_mask) = with(SparseOptions::default(), &scene);
    for (what, img, mask) in [
        ("depth", &by_depth, &depth_mask),
        ("flag", &by_flag, &flag_mask),
    ] {
        let mut marked_aa = 0;
        let mut unmarked_aa = 0;
        for (x, y, p) in img.enumerate_pixels() {
            let aa = usize::from(anti_aliased.contains(&(x, y)));
            if mask.get_pixel(x, y)[0] == MASK_SINGLE {
                assert_eq!(p, single.get_pixel(x, y), "{what}: marked ({x}, {y})");
                marked_aa += aa;
            } else {
                assert_eq!(mask.get_pixel(x, y)[0], 0, "{what}: ({x}, {y})");
                assert_eq!(p, full.get_pixel(x, y), "{what}: unmarked ({x}, {y})");
                unmarked_aa += aa;
            }
        }
        eprintln!("{what}: {marked_aa} edge pixels kept single-sample, {unmarked_aa} anti-aliased");
        assert!(
            marked_aa > 0 && unmarked_aa > 0,
            "{what}: {marked_aa} / {unmarked_aa}"
        );
    }
}

/// Switching to and from `sparse`, changing its pool and the size, and
/// destroying the renderer leaves no GL object behind; the image after the
/// switches is the one a fresh renderer makes.
#[test]
fn live_objects_return_to_zero() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let scene = Scene::load("builtin:thin").unwrap();
    if !supported(&ctx, &scene) {
        return;
    }
    let gl = ctx.gl();
    let before = live_objects();
    let start = options(sparse(SparseOptions::default()), W, H);
    let mut r = Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &start).unwrap();
    let steps = [
        options(AaMode::PerSample, W, H),
        options(
            sparse(SparseOptions {
                pool_blocks: Some(10),
                ..SparseOptions::default()
            }),
            W,
            H,
        ),
        options(sparse(SparseOptions::default()), 96, 54),
        options(AaMode::None, 96, 54),
        start.clone(),
    ];
    for opts in &steps {
        r.set_options(gl, opts).unwrap();
        r.render(gl).unwrap();
        assert_eq!(
            r.technique::<Sparse>()
                .and_then(Sparse::allocated)
                .is_some(),
            matches!(opts.aa, AaMode::Sparse(_)),
            "{opts:?}"
        );
    }
    let after_switches = r.read_final(gl).unwrap();
    r.destroy(gl);
    assert_eq!(live_objects(), before);
    assert_eq!(after_switches, image(&ctx, &scene, &start));
    assert_eq!(live_objects(), before);
}

/// The bench runs `sparse` like any method, with its real allocation as
/// `gbuffer_bytes`, its overflow count and the full G-buffer beside it, in
/// `report.json` and `report.md`; the default list carries it.
#[test]
fn bench_reports_memory_and_overflow() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let scene = Scene::load("builtin:greebles").unwrap();
    if !supported(&ctx, &scene) {
        return;
    }
    drop(ctx);
    assert!(bench::default_methods().iter().any(|e| e.label == "sparse"));
    let config = BenchConfig {
        scenes: vec!["builtin:greebles".into()],
        width: 64,
        height: 36,
        methods: bench::parse_methods("none,sparse,sparse:pool=4").unwrap(),
        frames: 1,
        warmup: 0,
        ..BenchConfig::default()
    };
    let out = bench::run(&config).unwrap();
    let run = |m: &str| {
        out.report
            .runs
            .iter()
            .find(|r| r.method == m)
            .unwrap_or_else(|| panic!("no `{m}` run"))
    };
    let (none, roomy, tight) = (run("none"), run("sparse"), run("sparse:pool=4"));
    assert_eq!(none.sparse_overflow_pixels, None);
    assert_eq!(roomy.sparse_overflow_pixels, Some(0));
    assert!(tight.sparse_overflow_pixels.unwrap_or(0) > 0, "{tight:?}");
    let full = roomy.full_ms_gbuffer_bytes.expect("full G-buffer bytes");
    assert_eq!(
        full,
        GBufferLayout::recommended().bytes(64, 36, roomy.samples)
    );
    assert!(roomy.gbuffer_bytes < full);
    assert!(tight.gbuffer_bytes < roomy.gbuffer_bytes);
    let json = out.report.to_json().unwrap();
    assert!(json.contains("\"sparse_overflow_pixels\""));
    let md = out.report.to_markdown();
    assert!(
        md.contains("`sparse` 4x: its G-buffer") && md.contains("pixels fell back to one sample"),
        "{md}"
    );
}

/// Without the extensions `sparse` needs, `render --method sparse` exits
/// non-zero with one line naming what is missing (forced through Mesa's
/// extension override in a child process, under OpenGL 3.2 as the floor
/// run has it).
#[test]
fn unsupported_contexts_get_a_typed_error() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let mesa = ctx.gl().version().vendor_info.contains("Mesa");
    drop(ctx);
    if !mesa {
        common::skip("forcing missing extensions needs Mesa's MESA_EXTENSION_OVERRIDE");
        return;
    }
    let out = common::floor_command()
        .args(["render", "--method", "sparse", "--size", "32x18", "--out"])
        .arg(std::env::temp_dir().join("deferred-msaa-sparse-unsupported.png"))
        .env(
            "MESA_EXTENSION_OVERRIDE",
            "-GL_ARB_shader_storage_buffer_object -GL_ARB_post_depth_coverage",
        )
        .output()
        .expect("running deferred-msaa");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "sparse ran without its extensions");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    for needle in [
        "method `sparse`",
        "GL_ARB_shader_storage_buffer_object",
        "GL_ARB_post_depth_coverage",
        "OpenGL 3.2",
    ] {
        assert!(stderr.contains(needle), "`{needle}` not in: {stderr}");
    }
}
