//! The demo deferred renderer: every built-in scene with and without MSAA,
//! the unchanged lighting shader, the decal hook, run-time option changes
//! and object lifetimes. Images are small so the suite stays fast on
//! llvmpipe. Set `DEFERRED_MSAA_SAVE_RENDERS=DIR` to keep the images.

mod depth;
mod per_sample;

use crate::common;

use std::cell::RefCell;
use std::rc::Rc;

use deferred_msaa::Error as CoreError;
use deferred_msaa_lab::Error;
use deferred_msaa_lab::bench;
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_lab::gbuffer::{GBuffer, GBufferLayout};
use deferred_msaa_lab::gl::TextureRef;
use deferred_msaa_lab::gl::{Capabilities, ExtraFns, live_objects};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::renderer::technique::Complex;
use deferred_msaa_lab::renderer::{AaMode, DecalTarget, DepthMode, RenderOptions, Renderer};
use deferred_msaa_lab::resolve::{
    DEFAULT_NORMAL_THRESHOLD, ResolveMethod, ResolveRule, ResolveSettings,
};
use deferred_msaa_lab::retrofit::FirstLayerRestore;
use deferred_msaa_lab::scene::{Aabb, Background, Camera, Light, Material, Object, Scene};
use glow::HasContext;

const W: u32 = 128;
const H: u32 = 72;

fn options(aa: AaMode) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        samples: 4,
        aa,
        fxaa: false,
        layout: GBufferLayout::recommended(),
        depth_mode: DepthMode::Auto,
        ..RenderOptions::default()
    }
}

fn median() -> AaMode {
    AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        ..ResolveSettings::default()
    })
}

fn luma(p: &image::Rgba<u8>) -> f32 {
    0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32
}

/// Edge statistics of an image, over horizontal and vertical pixel triples
/// `a p b`: `hard` counts steps between neighbours of more than 48 luma
/// levels, `intermediate` counts pixels strictly between two neighbours
/// that differ by more than 48 levels (by at least 6 levels from each):
/// the in-between values an anti-aliased edge has and an aliased one lacks.
#[derive(Debug, Clone, Copy)]
struct EdgeStats {
    hard: usize,
    intermediate: usize,
}

fn edge_stats(img: &image::RgbaImage) -> EdgeStats {
    let (w, h) = img.dimensions();
    let l = |x: u32, y: u32| luma(img.get_pixel(x, y));
    let mut stats = EdgeStats {
        hard: 0,
        intermediate: 0,
    };
    for y in 0..h {
        for x in 0..w {
            let p = l(x, y);
            if x + 1 < w && (p - l(x + 1, y)).abs() > 48.0 {
                stats.hard += 1;
            }
            if y + 1 < h && (p - l(x, y + 1)).abs() > 48.0 {
                stats.hard += 1;
            }
            let mut triples = Vec::new();
            if x > 0 && x + 1 < w {
                triples.push((l(x - 1, y), l(x + 1, y)));
            }
            if y > 0 && y + 1 < h {
                triples.push((l(x, y - 1), l(x, y + 1)));
            }
            if triples.iter().any(|&(a, b)| {
                let (lo, hi) = (a.min(b), a.max(b));
                hi - lo > 48.0 && p > lo + 6.0 && p < hi - 6.0
            }) {
                stats.intermediate += 1;
            }
        }
    }
    stats
}

fn save(img: &image::RgbaImage, name: &str) {
    if let Some(dir) = std::env::var_os("DEFERRED_MSAA_SAVE_RENDERS") {
        let dir = std::path::PathBuf::from(dir);
        let _ = std::fs::create_dir_all(&dir);
        let _ = img.save(dir.join(format!("{name}.png")));
    }
}

/// A renderer of `scene` with `options` on `ctx`.
fn renderer(ctx: &HeadlessContext, scene: &Scene, options: &RenderOptions) -> Renderer {
    Renderer::new(ctx.gl(), |n| ctx.get_proc_address(n), scene, options).expect("renderer")
}

/// Render one frame; check the final image is not blank and every HDR value
/// is finite; return the image.
fn render_checked(gl: &glow::Context, renderer: &mut Renderer, what: &str) -> image::RgbaImage {
    renderer
        .render(gl)
        .unwrap_or_else(|e| panic!("{what}: render failed: {e}"));
    let img = renderer
        .read_final(gl)
        .unwrap_or_else(|e| panic!("{what}: read_final failed: {e}"));
    assert_eq!(
        img.dimensions(),
        (renderer.options().width, renderer.options().height)
    );
    let first = *img.get_pixel(0, 0);
    let distinct = img.pixels().filter(|p| **p != first).count();
    let lit = img.pixels().filter(|p| luma(p) > 8.0).count();
    assert!(
        distinct > img.len() / 4 / 20 && lit > 0,
        "{what}: the final image is (nearly) blank ({distinct} pixels differ from the corner, {lit} not black)"
    );
    let mut readback = Readback::new(gl).expect("readback");
    let hdr = readback
        .read(gl, renderer.hdr_texture(), 1)
        .expect("reading the HDR target");
    readback.destroy(gl);
    let bad = hdr.data.iter().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{what}: {bad} non-finite HDR values");
    assert!(
        hdr.data.iter().all(|v| *v >= 0.0),
        "{what}: negative HDR radiance"
    );
    img
}

#[test]
fn every_builtin_scene_renders_and_msaa_smooths_edges() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    // Normals blended (`blend-normal`), so that creases between faces of one
    // material get in-between shades too. The recommended layout takes the
    // reference sample's normal instead (it measures closer to the
    // supersampled reference, see `GBufferLayout::recommended`), which by
    // design leaves such creases one face or the other; `builtin:transparent`,
    // whose only edges are such creases and silhouettes, then shows none.
    // The renderer names its normal attachment, whose test splits a crease
    // into two faces: a cosine threshold of -1 splits nothing.
    let blended_median = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        normal_threshold: -1.0,
        ..ResolveSettings::default()
    });
    let mut blended_normals = options(AaMode::None);
    let normal = blended_normals.layout.index_of("normal").expect("normal");
    blended_normals.layout.colors[normal].rule = ResolveRule::BlendNormal;
    let with = |aa: AaMode| RenderOptions {
        aa,
        ..blended_normals.clone()
    };
    for name in Scene::builtin_names() {
        let scene = Scene::load(&format!("builtin:{name}")).expect("builtin scene");
        let mut renderer = renderer(&ctx, &scene, &with(AaMode::None));
        assert!(renderer.retrofit().is_none());
        let none = render_checked(gl, &mut renderer, &format!("{name} none"));
        // `ridges` is a plate of facets a pixel or two wide, lit apart:
        // one layer lights each pixel as one facet, as no MSAA does (its
        // half-covered pixels by their parity), and only the second layer
        // lights both (docs/bench.md, "One layer against no MSAA").
        let aa = match (*name, blended_median) {
            ("ridges", AaMode::Resolve(settings)) => AaMode::Resolve(ResolveSettings {
                layers: 2,
                normal_threshold: DEFAULT_NORMAL_THRESHOLD,
                ..settings
            }),
            (_, aa) => aa,
        };
        renderer
            .set_options(gl, &with(aa))
            .expect("switching to median");
        assert!(
            renderer.samples() >= 2,
            "{name}: {} samples",
            renderer.samples()
        );
        let msaa = render_checked(gl, &mut renderer, &format!("{name} median"));
        save(&none, &format!("{name}-none"));
        save(&msaa, &format!("{name}-median"));
        let (a, b) = (edge_stats(&none), edge_stats(&msaa));
        eprintln!("{name}: none {a:?}, median 4x {b:?}");
        assert!(
            b.intermediate > a.intermediate || b.hard < a.hard,
            "{name}: MSAA shows no anti-aliased edges (none {a:?}, median {b:?})"
        );
        assert_ne!(none, msaa, "{name}: MSAA changed nothing");
        renderer.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn lighting_and_model_shaders_do_not_change_with_msaa() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:box").expect("scene");
    let plain = renderer(&ctx, &scene, &options(AaMode::None));
    let msaa = renderer(&ctx, &scene, &options(median()));
    assert!(plain.retrofit().is_none() && msaa.retrofit().is_some());
    let source = plain.lighting_program_source();
    assert!(source.starts_with("#version 150 core\n"), "{source}");
    assert!(source.contains("void main()"));
    assert_eq!(source, msaa.lighting_program_source());
    assert_eq!(
        plain.geometry_program_source(),
        msaa.geometry_program_source()
    );
    // The per-sample modes light with a permutation of their own; the
    // per-pixel source stays the same, and the lighting math (lights, BRDF,
    // the shading of one G-buffer sample) is lighting.frag's, verbatim.
    for aa in [AaMode::PerSample, AaMode::Complex] {
        let r = renderer(&ctx, &scene, &options(aa));
        assert_eq!(r.lighting_program_source(), source, "{aa:?}");
        assert_eq!(r.geometry_program_source(), plain.geometry_program_source());
        let per_sample = r.per_sample_lighting_program_source();
        assert!(
            per_sample.contains(deferred_msaa_lab::renderer::shaders::LIGHTING_FRAG)
                && per_sample.contains("#define LIGHTING_FUNCTIONS_ONLY")
                && per_sample.contains("sampler2DMS"),
            "{per_sample}"
        );
        assert_eq!(
            per_sample.matches("vec3 direct_light(").count(),
            1,
            "one BRDF"
        );
        r.destroy(gl);
    }
    plain.destroy(gl);
    msaa.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// Read colour attachment `k` of the G-buffer as RGBA floats (bottom row first).
fn read_attachment(gl: &glow::Context, gbuffer: &GBuffer, k: u32) -> Vec<f32> {
    let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
    let mut data = vec![0f32; w * h * 4];
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(gbuffer.fbo.raw()));
        gl.read_buffer(glow::COLOR_ATTACHMENT0 + k);
        gl.read_pixels(
            0,
            0,
            w as i32,
            h as i32,
            glow::RGBA,
            glow::FLOAT,
            glow::PixelPackData::Slice(Some(bytemuck_cast(&mut data))),
        );
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    }
    data
}

fn bytemuck_cast(data: &mut [f32]) -> &mut [u8] {
    // SAFETY: f32 has no invalid bit patterns and u8 has alignment 1.
    unsafe {
        std::slice::from_raw_parts_mut(data.as_mut_ptr().cast::<u8>(), std::mem::size_of_val(data))
    }
}

#[test]
fn decal_hook_sees_and_writes_the_resolved_gbuffer() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:box").expect("scene");
    let layout = GBufferLayout::recommended();
    let color = layout.index_of("color").expect("color attachment") as u32;
    let mut renderer = renderer(&ctx, &scene, &options(median()));
    let before = {
        renderer.render(gl).expect("frame without decal");
        renderer.read_final(gl).expect("final image")
    };

    // The hook: count the model's texels in the resolved colour attachment
    // (only a resolved G-buffer has them: the pass drew into the
    // multisampled twin), then paint a green decal over a rectangle.
    let seen = Rc::new(RefCell::new(Vec::new()));
    let seen_in_hook = Rc::clone(&seen);
    let matrices = Rc::new(RefCell::new(Vec::new()));
    let matrices_in_hook = Rc::clone(&matrices);
    let rect = (W as i32 / 4, H as i32 / 4, W as i32 / 2, H as i32 / 2);
    renderer.set_decal_hook(Some(Box::new(
        move |gl: &glow::Context, target: &DecalTarget<'_>| {
            let gbuffer = target.gbuffer;
            // Without jitter the hook draws with the renderer's projection.
            matrices_in_hook
                .borrow_mut()
                .push((target.view, target.projection));
            let bound = unsafe { gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) };
            assert_eq!(
                bound as u32,
                gbuffer.fbo.raw().0.get(),
                "the G-buffer is bound for the hook"
            );
            let texels = read_attachment(gl, gbuffer, color);
            let model = texels
                .chunks_exact(4)
                .filter(|p| p[0] + p[1] + p[2] > 0.05)
                .count();
            seen_in_hook.borrow_mut().push(model);
            unsafe {
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(gbuffer.fbo.raw()));
                gl.enable(glow::SCISSOR_TEST);
                gl.scissor(rect.0, rect.1, rect.2, rect.3);
                gl.clear_buffer_f32_slice(glow::COLOR, color, &[0.05, 0.9, 0.05, 1.0]);
            }
        },
    )));
    renderer.render(gl).expect("frame with decal");
    let after = renderer.read_final(gl).expect("final image");
    let seen = seen.borrow().clone();
    assert_eq!(seen.len(), 1, "the hook runs once per frame");
    assert_eq!(
        matrices.borrow().as_slice(),
        &[(scene.camera.view, renderer.projection())],
        "the hook draws with the frame's matrices"
    );
    assert!(
        seen[0] > (W * H) as usize / 10,
        "the hook saw {} model texels",
        seen[0]
    );

    // Inside the rectangle, lit geometry turned green; outside nothing changed.
    let mut greener = 0;
    for (x, y, p) in after.enumerate_pixels() {
        let (xi, yi) = (x as i32, H as i32 - 1 - y as i32);
        let inside = xi >= rect.0 && xi < rect.0 + rect.2 && yi >= rect.1 && yi < rect.1 + rect.3;
        let q = before.get_pixel(x, y);
        if inside {
            if p[1] as i32 > p[0] as i32 + 20 && p[1] as i32 > q[1] as i32 {
                greener += 1;
            }
        } else {
            assert_eq!(p, q, "pixel ({x}, {y}) outside the decal changed");
        }
    }
    assert!(
        greener > (rect.2 * rect.3) as usize / 4,
        "only {greener} pixels show the decal"
    );
    save(&after, "decal");

    renderer.set_decal_hook(None);
    renderer.render(gl).expect("frame after removing the hook");
    assert_eq!(renderer.read_final(gl).expect("final image"), before);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// `Renderer::set_keep_gbuffer(false)`, as the bench sets it: with two
/// layers the retrofit stops putting the first layer back after the second
/// lighting (the G-buffer then holds the second layer's copy), the lit
/// image is the same bit for bit, and `true` brings the restore back. A
/// scene with transparent objects, which depth-test against the G-buffer
/// after lighting, keeps the restore whatever the caller says.
#[test]
fn not_keeping_the_gbuffer_skips_the_restore_and_leaves_the_lit_image_alone() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let two_layers = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        layers: 2,
        ..ResolveSettings::default()
    });
    let normal = GBufferLayout::recommended()
        .index_of("normal")
        .expect("normal attachment") as u32;
    let scene = Scene::load("builtin:greebles").expect("scene");
    let mut renderer = renderer(&ctx, &scene, &options(two_layers));
    let restores = |r: &Renderer| {
        r.retrofit()
            .expect("a retrofit with two layers")
            .options()
            .restore_first_layer
    };
    assert_eq!(
        restores(&renderer),
        FirstLayerRestore::Everything,
        "the default keeps the G-buffer"
    );
    let kept_image = render_checked(gl, &mut renderer, "two layers, G-buffer kept");
    let kept_normals = read_attachment(gl, renderer.gbuffer(), normal);

    renderer
        .set_keep_gbuffer(gl, false)
        .expect("keep_gbuffer off");
    assert_eq!(
        restores(&renderer),
        FirstLayerRestore::Nothing,
        "keep_gbuffer(false) turns the restore off"
    );
    let image = render_checked(gl, &mut renderer, "two layers, G-buffer not kept");
    assert!(
        image == kept_image,
        "the lit image changed without the restore"
    );
    let normals = read_attachment(gl, renderer.gbuffer(), normal);
    let changed = normals
        .chunks_exact(4)
        .zip(kept_normals.chunks_exact(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        changed > 0,
        "without the restore the G-buffer should hold the second layer's normals"
    );

    renderer
        .set_keep_gbuffer(gl, true)
        .expect("keep_gbuffer on");
    assert_eq!(restores(&renderer), FirstLayerRestore::Everything);
    let image = render_checked(gl, &mut renderer, "two layers, G-buffer kept again");
    assert!(
        image == kept_image,
        "the lit image changed with the restore back"
    );
    assert!(
        read_attachment(gl, renderer.gbuffer(), normal) == kept_normals,
        "the restore is back: the G-buffer holds the first layer again"
    );
    renderer.destroy(gl);

    let scene = Scene::load("builtin:transparent").expect("scene");
    let mut with_glass = self::renderer(&ctx, &scene, &options(two_layers));
    let kept = render_checked(gl, &mut with_glass, "two layers, transparent objects");
    with_glass
        .set_keep_gbuffer(gl, false)
        .expect("keep_gbuffer off");
    assert_eq!(
        restores(&with_glass),
        FirstLayerRestore::DepthAndStencil,
        "transparent objects depth-test against the G-buffer after lighting: its depth comes back"
    );
    let image = render_checked(gl, &mut with_glass, "two layers, transparent objects");
    assert!(
        image == kept,
        "with the depth alone put back, the transparent objects' image changed"
    );
    with_glass.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn set_options_switches_at_run_time_without_leaks() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:transparent").expect("scene");
    let start = options(median());
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &start).expect("renderer");
    let reference = render_checked(gl, &mut renderer, "start");

    let front = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Front,
        ..ResolveSettings::default()
    });
    // The most samples the driver offers, up to 8 (llvmpipe: 4).
    let max = unsafe { gl.get_parameter_i32(glow::MAX_SAMPLES) }.clamp(1, 8) as u32;
    let steps: Vec<(&str, RenderOptions)> = vec![
        (
            "1 sample",
            RenderOptions {
                samples: 1,
                ..start.clone()
            },
        ),
        (
            "2 samples",
            RenderOptions {
                samples: 2,
                ..start.clone()
            },
        ),
        (
            "most samples",
            RenderOptions {
                samples: max,
                ..start.clone()
            },
        ),
        (
            "front",
            RenderOptions {
                aa: front,
                ..start.clone()
            },
        ),
        ("none", options(AaMode::None)),
        (
            "none + fxaa",
            RenderOptions {
                fxaa: true,
                ..options(AaMode::None)
            },
        ),
        (
            "median + fxaa",
            RenderOptions {
                fxaa: true,
                ..start.clone()
            },
        ),
        (
            "larger",
            RenderOptions {
                width: 160,
                height: 90,
                ..start.clone()
            },
        ),
        (
            "smaller, none",
            RenderOptions {
                width: 96,
                height: 64,
                ..options(AaMode::None)
            },
        ),
        (
            "resize into msaa",
            RenderOptions {
                width: 100,
                height: 60,
                fxaa: true,
                ..start.clone()
            },
        ),
        (
            "freespace layout",
            RenderOptions {
                layout: GBufferLayout::freespace_open(),
                ..start.clone()
            },
        ),
        (
            "per-sample",
            RenderOptions {
                aa: AaMode::PerSample,
                ..start.clone()
            },
        ),
        (
            "complex",
            RenderOptions {
                aa: AaMode::Complex,
                ..start.clone()
            },
        ),
        (
            "complex, resized",
            RenderOptions {
                aa: AaMode::Complex,
                width: 112,
                height: 64,
                fxaa: true,
                ..start.clone()
            },
        ),
        (
            "complex, freespace layout",
            RenderOptions {
                aa: AaMode::Complex,
                layout: GBufferLayout::freespace_open(),
                ..start.clone()
            },
        ),
        (
            "per-sample, 2 samples",
            RenderOptions {
                aa: AaMode::PerSample,
                samples: 2,
                ..start.clone()
            },
        ),
        (
            "taa, with fxaa",
            RenderOptions {
                aa: AaMode::Taa(Default::default()),
                fxaa: true,
                ..start.clone()
            },
        ),
        ("complex into none", options(AaMode::None)),
        ("back to start", start.clone()),
    ];
    for (what, opts) in &steps {
        renderer
            .set_options(gl, opts)
            .unwrap_or_else(|e| panic!("{what}: set_options failed: {e}"));
        assert_eq!(renderer.options(), opts);
        assert_eq!(renderer.gbuffer().width, opts.width, "{what}");
        assert_eq!(renderer.gbuffer().height, opts.height, "{what}");
        match opts.aa {
            AaMode::None | AaMode::Gbaa | AaMode::Sparse(_) | AaMode::Taa(_) => {
                assert!(renderer.retrofit().is_none(), "{what}")
            }
            AaMode::Resolve(_) | AaMode::PerSample | AaMode::Complex => {
                let r = renderer.retrofit().expect("a retrofit");
                assert_eq!(r.twin().width, opts.width, "{what}");
                assert!(
                    r.samples() >= opts.samples.min(4),
                    "{what}: {} samples",
                    r.samples()
                );
            }
        }
        let img = render_checked(gl, &mut renderer, what);
        assert_eq!(img.dimensions(), (opts.width, opts.height));
        save(&img, &format!("switch-{}", what.replace([' ', ','], "_")));
    }
    // Back where it started, the image is the same as at first.
    let again = renderer.read_final(gl).expect("final image");
    assert_eq!(
        again, reference,
        "the start options render differently after switching"
    );

    // A bad request fails cleanly and leaves the renderer as it was.
    let bad = RenderOptions {
        width: 0,
        ..start.clone()
    };
    assert!(renderer.set_options(gl, &bad).is_err());
    let mut no_normal = start.clone();
    no_normal.layout.colors.remove(2);
    let e = renderer
        .set_options(gl, &no_normal)
        .expect_err("a layout without normals");
    assert!(e.to_string().contains("normal"), "{e}");
    assert_eq!(renderer.options(), &start);
    renderer
        .render(gl)
        .expect("rendering after failed switches");

    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn fxaa_softens_edges_and_timings_are_reported() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:box").expect("scene");
    let mut renderer = renderer(&ctx, &scene, &options(AaMode::None));
    let plain = render_checked(gl, &mut renderer, "box none");
    renderer
        .set_options(
            gl,
            &RenderOptions {
                fxaa: true,
                ..options(AaMode::None)
            },
        )
        .expect("fxaa on");
    let timings = renderer.render(gl).expect("frame");
    let filtered = renderer.read_final(gl).expect("final image");
    save(&filtered, "box-none-fxaa");
    let (a, b) = (edge_stats(&plain), edge_stats(&filtered));
    eprintln!("box: none {a:?}, none + fxaa {b:?}; {timings:?}");
    assert!(
        b.intermediate > a.intermediate,
        "FXAA added no in-between values ({a:?} → {b:?})"
    );
    assert!(timings.fxaa_ms >= 0.0 && timings.resolve_ms == 0.0);
    let sum = timings.geometry_ms
        + timings.resolve_ms
        + timings.decal_ms
        + timings.lighting_ms
        + timings.transparent_ms
        + timings.tonemap_ms
        + timings.fxaa_ms;
    assert!(
        (timings.total_ms - sum).abs() < 1e-9 && timings.total_ms > 0.0,
        "{timings:?}"
    );
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}
