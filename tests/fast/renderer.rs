//! The demo deferred renderer: every built-in scene with and without MSAA,
//! the unchanged lighting shader, the decal hook, run-time option changes
//! and object lifetimes. Images are small so the suite stays fast on
//! llvmpipe. Set `DEFERRED_MSAA_SAVE_RENDERS=DIR` to keep the images.

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
use deferred_msaa_lab::resolve::{ResolveMethod, ResolveRule, ResolveSettings};
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
        renderer
            .set_options(gl, &with(median()))
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

/// Read a texture of the renderer back (row 0 at the top).
fn read_texture(
    gl: &glow::Context,
    texture: deferred_msaa_lab::gl::TextureRef,
) -> deferred_msaa_lab::readback::SampleImage {
    let mut readback = Readback::new(gl).expect("readback");
    let img = readback.read(gl, texture, 1).expect("reading a texture");
    readback.destroy(gl);
    img
}

fn with_depth(mode: DepthMode, aa: AaMode) -> RenderOptions {
    RenderOptions {
        depth_mode: mode,
        ..options(aa)
    }
}

#[test]
fn far_scene_keeps_its_model_with_reversed_z_and_warns_with_the_freespace_layout() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let clip_control = Capabilities::query(gl).clip_control;
    let scene = Scene::load("builtin:far").expect("scene");

    // The recommended layout, Auto: reversed-Z where the context allows it.
    let mut renderer = renderer(&ctx, &scene, &options(median()));
    if clip_control {
        assert_eq!(renderer.depth_mode(), DepthMode::Reversed);
        assert_eq!(renderer.clear_depth(), 0.0);
        assert!(renderer.warnings().is_empty(), "{:#?}", renderer.warnings());
        let frame = renderer.resolve_frame();
        assert_eq!(frame.depth_mode, deferred_msaa::DepthMode::ReversedZ);
        let (projection, _) = frame.depth_terms().expect("a perspective projection");
        assert!(projection.zero_to_one && projection.clear_depth == 0.0);
        assert_eq!(projection.p22, 0.0, "an infinite far plane");
        let img = render_checked(gl, &mut renderer, "far, reversed-Z");
        save(&img, "far-reversed");
        // The model, not background, covers most of the view: its depth is
        // not the clear depth and its positions are finite and 200 km away.
        let depth = read_texture(gl, TextureRef::from(&renderer.gbuffer().depth));
        let k = GBufferLayout::recommended()
            .index_of("position")
            .expect("position");
        let position = read_texture(gl, TextureRef::from(&renderer.gbuffer().colors[k]));
        let model: Vec<usize> = (0..(W * H) as usize)
            .filter(|&i| depth.data[i * 4] != 0.0)
            .collect();
        assert!(
            model.len() > (W * H) as usize / 20,
            "only {} of {} pixels show the model",
            model.len(),
            W * H
        );
        for &i in &model {
            let z = -position.data[i * 4 + 2];
            assert!((1.9e5..2.1e5).contains(&z), "pixel {i}: view depth {z}");
        }
    } else {
        // Without glClipControl the standard float depth loses the model, and says so.
        assert_eq!(renderer.depth_mode(), DepthMode::Standard);
        assert!(!renderer.warnings().is_empty());
        let e = Renderer::new(
            gl,
            |n| ctx.get_proc_address(n),
            &scene,
            &with_depth(DepthMode::Reversed, median()),
        )
        .expect_err("reversed-Z without glClipControl");
        assert!(
            matches!(e, Error::Core(CoreError::Unsupported { .. })),
            "{e}"
        );
    }
    renderer.destroy(gl);

    // FreeSpace Open's layout (FP16 positions, D24) in standard depth warns
    // about both, before anything is allocated.
    let fso = RenderOptions {
        layout: GBufferLayout::freespace_open(),
        ..with_depth(DepthMode::Standard, median())
    };
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &fso).expect("renderer");
    assert_eq!(renderer.depth_mode(), DepthMode::Standard);
    let warnings = renderer.warnings().to_vec();
    assert_eq!(warnings.len(), 2, "{warnings:#?}");
    assert!(
        warnings[0].contains("65504") && warnings[0].contains("position"),
        "{warnings:#?}"
    );
    assert!(warnings[1].contains("DEPTH_COMPONENT24"), "{warnings:#?}");
    renderer.render(gl).expect("a frame, warned or not");
    // Switching back to the recommended layout clears them (when reversed-Z is there).
    renderer
        .set_options(gl, &options(median()))
        .expect("recommended layout");
    assert_eq!(renderer.warnings().is_empty(), clip_control);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn every_builtin_scene_looks_the_same_with_reversed_and_standard_depth() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    if !Capabilities::query(gl).clip_control {
        let scene = Scene::load("builtin:box").expect("scene");
        let e = Renderer::new(
            gl,
            |n| ctx.get_proc_address(n),
            &scene,
            &with_depth(DepthMode::Reversed, median()),
        )
        .expect_err("reversed-Z without glClipControl");
        assert!(e.to_string().contains("glClipControl"), "{e}");
        return;
    }
    for name in Scene::builtin_names() {
        let scene = Scene::load(&format!("builtin:{name}")).expect("builtin scene");
        let mut renderer = renderer(&ctx, &scene, &with_depth(DepthMode::Reversed, median()));
        assert_eq!(renderer.depth_mode(), DepthMode::Reversed);
        assert!(
            renderer.warnings().is_empty(),
            "{name}: {:#?}",
            renderer.warnings()
        );
        let reversed = render_checked(gl, &mut renderer, &format!("{name} reversed"));
        let position = |r: &Renderer| {
            let k = r.options().layout.index_of("position").expect("position");
            read_texture(gl, TextureRef::from(&r.gbuffer().colors[k]))
        };
        let reversed_position = position(&renderer);

        // The same renderer switched to standard depth: nothing is rebuilt.
        renderer
            .set_options(gl, &with_depth(DepthMode::Standard, median()))
            .expect("standard depth");
        assert_eq!(renderer.depth_mode(), DepthMode::Standard);
        assert_eq!(renderer.clear_depth(), 1.0);
        if *name == "far" {
            // 200 km away, standard float depth rounds the model to the
            // clear depth: the precision check says so (and the image may
            // lose the model), but the frame stays finite.
            assert!(
                !renderer.warnings().is_empty(),
                "far: no warning in standard depth"
            );
            renderer.render(gl).expect("far, standard depth");
            let hdr = read_texture(gl, renderer.hdr_texture());
            assert!(
                hdr.data.iter().all(|v| v.is_finite()),
                "far: non-finite HDR values"
            );
            renderer.destroy(gl);
            continue;
        }
        assert!(
            renderer.warnings().is_empty(),
            "{name}: {:#?}",
            renderer.warnings()
        );
        let standard = render_checked(gl, &mut renderer, &format!("{name} standard"));
        save(&reversed, &format!("{name}-reversed"));
        save(&standard, &format!("{name}-standard"));
        // The same surfaces at the same places: resolved positions agree.
        let standard_position = position(&renderer);
        let off = reversed_position
            .data
            .chunks_exact(4)
            .zip(standard_position.data.chunks_exact(4))
            .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3 * (1.0 + a[2].abs())))
            .count();
        let flip = deferred_msaa_lab::compare::flip(&standard, &reversed).expect("same size");
        eprintln!(
            "{name}: FLIP mean {:.5} (max {:.3}); {off} pixels with other positions",
            flip.mean, flip.max
        );
        assert!(
            off <= (W * H) as usize / 200,
            "{name}: {off} pixels resolve to other positions with reversed-Z"
        );
        // `zfight`'s coplanar panels have no right answer: which one wins a
        // pixel is decided by rounding, which the depth convention changes,
        // so only its positions are compared.
        if *name != "zfight" {
            assert!(
                flip.mean < 0.02,
                "{name}: reversed-Z and standard depth differ (FLIP mean {})",
                flip.mean
            );
        }
        renderer.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn the_renderer_leaves_the_hosts_depth_state_as_it_found_it() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let extra = ExtraFns::load(gl, |n| ctx.get_proc_address(n));
    if !extra.has_clip_control() {
        return;
    }
    let state = || unsafe {
        (
            gl.get_parameter_i32(glow::CLIP_ORIGIN) as u32,
            gl.get_parameter_i32(glow::CLIP_DEPTH_MODE) as u32,
            gl.get_parameter_i32(glow::DEPTH_FUNC) as u32,
            gl.get_parameter_f32(glow::DEPTH_CLEAR_VALUE),
        )
    };
    let scene = Scene::load("builtin:box").expect("scene");
    let mut renderer = renderer(&ctx, &scene, &with_depth(DepthMode::Standard, median()));
    let standard = render_checked(gl, &mut renderer, "box standard");

    // A host with its own depth state.
    unsafe {
        gl.depth_func(glow::LEQUAL);
        gl.clear_depth_f64(0.75);
    }
    let host = (
        glow::LOWER_LEFT,
        glow::NEGATIVE_ONE_TO_ONE,
        glow::LEQUAL,
        0.75,
    );
    assert_eq!(state(), host);
    renderer
        .set_options(gl, &with_depth(DepthMode::Reversed, median()))
        .expect("reversed-Z");
    let reversed = render_checked(gl, &mut renderer, "box reversed");
    assert_eq!(state(), host, "after a reversed-Z frame");

    // A host that uses GL_ZERO_TO_ONE itself: a standard frame still renders
    // as before, and the host gets its clip control back.
    assert!(extra.set_clip_depth_zero_to_one(true));
    let host = (glow::LOWER_LEFT, glow::ZERO_TO_ONE, glow::LEQUAL, 0.75);
    renderer
        .set_options(gl, &with_depth(DepthMode::Standard, median()))
        .expect("standard");
    let again = render_checked(gl, &mut renderer, "box standard, host in zero-to-one");
    assert_eq!(state(), host, "after a standard frame");
    assert_eq!(again, standard);
    let flip = deferred_msaa_lab::compare::flip(&standard, &reversed).expect("same size");
    assert!(flip.mean < 0.02, "FLIP mean {}", flip.mean);
    extra.set_clip_depth_zero_to_one(false);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

// ---------------------------------------------------------------------------
// Per-sample lighting (`per-sample`) and per-sample lighting of complex
// pixels only (`complex`).

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
            "renderer::complex_without_sample_mask_in_child",
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
