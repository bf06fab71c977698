//! The retrofit on real multisampled renders: a tiny host deferred renderer,
//! written here with its own FBO and shaders, gets MSAA through the public
//! API alone; every resolved pixel is checked against the CPU reference
//! computed from the very samples the GPU rasterised.

mod refusals;
mod two_layers;

use crate::common;

use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Error, FirstLayerRestore, LayerMix, NormalAttachment};
use deferred_msaa_lab::gl::{Attachment, Format, Framebuffer, Texture2d, TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, pixel_samples};
use deferred_msaa_lab::resolve::cpu::{CpuCamera, CpuKeySource, CpuResolve, PixelPlace};
use deferred_msaa_lab::resolve::{
    Region, ResolveMethod, ResolveRule, ResolveSettings, Selection, SelectionFlag, Window,
};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions, introspect};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;
use glow::HasContext;

const W: u32 = 64;
const H: u32 = 48;
const FOV_Y: f64 = 0.8;
const NEAR: f64 = 0.5;
const FAR: f64 = 100.0;

fn projection() -> [f64; 16] {
    perspective(FOV_Y, W as f64 / H as f64, NEAR, Some(FAR))
}

/// Triangles in view space: a far wall, a model with fine detail a little in
/// front of itself, a tilted panel, and a sliver.
fn triangles() -> Vec<f32> {
    let mut v = Vec::new();
    triangle(
        &mut v,
        [
            [-60.0, -40.0, -60.0],
            [60.0, -40.0, -60.0],
            [0.0, 50.0, -60.0],
        ],
        [0.2, 0.3, 0.8],
    );
    triangle(
        &mut v,
        [[-4.0, -3.0, -10.0], [3.0, -2.5, -10.0], [-1.0, 3.0, -10.0]],
        [0.9, 0.4, 0.1],
    );
    triangle(
        &mut v,
        [[-2.0, -1.0, -9.9], [1.5, -1.2, -9.9], [0.0, 1.0, -9.9]],
        [0.1, 0.9, 0.2],
    );
    triangle(
        &mut v,
        [[1.0, -3.0, -8.0], [5.0, -3.0, -20.0], [3.0, 3.0, -14.0]],
        [0.8, 0.8, 0.8],
    );
    triangle(
        &mut v,
        [[-5.0, 2.0, -12.0], [5.0, 2.05, -12.0], [5.0, 2.2, -12.0]],
        [1.0, 0.0, 1.0],
    );
    v
}

fn host(gl: &glow::Context) -> Host {
    let mut host = Host::new(gl, W, H, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    host.set_triangles(gl, &triangles())
        .expect("the toy host's triangles");
    host
}

/// The image a host's lighting writes, and its framebuffer: what the
/// second-layer calls are given as the output.
fn lit_output(gl: &glow::Context, format: Format) -> (Texture2d, Framebuffer) {
    let output = Texture2d::new(gl, "lit output", format, W, H).unwrap();
    let fbo = Framebuffer::new(
        gl,
        "lit output",
        &[(Attachment::Color(0), TextureRef::from(&output))],
        &[Some(0)],
    )
    .unwrap();
    (output, fbo)
}

fn frame() -> deferred_msaa::Frame {
    deferred_msaa_testkit::projection::frame(&projection(), false)
}

/// The camera the resolve derives from the frame, for the CPU reference.
fn camera() -> CpuCamera {
    let (projection, fov_y) = frame().depth_terms().unwrap();
    CpuCamera { projection, fov_y }
}

/// `tan(fov_y / height)`: the pixel footprint the resolve derives from the frame.
fn footprint() -> f64 {
    let (_, fov_y) = frame().depth_terms().unwrap();
    (fov_y / H as f64).tan()
}

fn half_close(gpu: f32, cpu: f64) -> bool {
    // RGBA16F storage keeps 11 significant bits.
    ((gpu as f64) - cpu).abs() <= 1e-5 + 1.2e-3 * cpu.abs()
}

/// Every sample count the driver really offers (4 on llvmpipe; 2, 4, 8 and
/// 16 on desktop GPUs): the tests select themselves from what is there.
fn offered_counts(gl: &glow::Context) -> Vec<u32> {
    let mut counts = deferred_msaa_lab::gl::Capabilities::sample_counts_for(gl, Format::Rgba16f);
    for f in [Format::Rgba32f, Format::Depth32f] {
        let other = deferred_msaa_lab::gl::Capabilities::sample_counts_for(gl, f);
        counts.retain(|n| other.contains(n));
    }
    counts.retain(|&n| n > 1);
    counts
}

#[test]
fn resolve_matches_the_cpu_reference_on_real_samples() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let counts = offered_counts(ctx.gl());
    assert!(!counts.is_empty(), "the driver offers no multisampling");
    for n in counts {
        resolve_matches_at(&ctx, n);
    }
}

fn resolve_matches_at(ctx: &deferred_msaa_lab::context::HeadlessContext, samples: u32) {
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let options = RetrofitOptions {
        samples,
        rules: vec![(ColorAttachment(2), ResolveRule::BlendNormal)],
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    assert_eq!(
        msaa.samples(),
        samples,
        "the driver offered {samples}x but allocated another count"
    );
    // Two lines: draw into our FBO, resolve.
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);

    let mut readback = Readback::new(gl).unwrap();
    let (depth_ref, color_refs, _) = msaa.inputs().unwrap();
    let samples: Vec<_> = color_refs
        .iter()
        .map(|t| readback.read(gl, *t, 1).unwrap())
        .collect();
    let depth_samples = readback.read(gl, depth_ref, 1).unwrap();
    let n = msaa.samples();

    // A depth threshold inside the scene's range: the median geometry key.
    let mut keys: Vec<f64> = (0..H)
        .flat_map(|y| (0..W).map(move |x| (x, y)))
        .flat_map(|(x, y)| (0..n).map(move |s| (s, x, y)))
        .filter(|&(s, x, y)| depth_samples.get(s, x, y)[0] != 1.0)
        .map(|(s, x, y)| -(samples[1].get(s, x, y)[2] as f64))
        .collect();
    keys.sort_by(f64::total_cmp);
    let max_depth = keys[keys.len() / 2];
    // Every method, window and fast path; the opt-in uniformity tests (on
    // rasterised samples the position test agrees with its CPU mirror); and
    // selective AA.
    let mut cases = Vec::new();
    for &method in ResolveMethod::all() {
        for &window in Window::all() {
            for fast_path in [true, false] {
                let settings = ResolveSettings {
                    method,
                    window,
                    fast_path,
                    ..ResolveSettings::default()
                };
                cases.push(settings);
            }
        }
    }
    for (position_uniformity, plane_uniformity) in [(true, false), (false, true), (true, true)] {
        cases.push(ResolveSettings {
            position_uniformity,
            plane_uniformity,
            ..ResolveSettings::default()
        });
    }
    let selections = [
        Selection {
            region: Some(Region::Rect {
                x: 10.0,
                y: 8.0,
                width: 30.0,
                height: 20.0,
            }),
            ..Selection::default()
        },
        Selection {
            region: Some(Region::Ellipse {
                x: 32.0,
                y: 24.0,
                rx: 20.0,
                ry: 12.0,
            }),
            ..Selection::default()
        },
        Selection {
            max_depth: Some(max_depth),
            ..Selection::default()
        },
        Selection {
            // Triangles whose colour has red >= 0.5 are anti-aliased.
            flag: Some(SelectionFlag {
                attachment: ColorAttachment(0),
                component: 0,
            }),
            ..Selection::default()
        },
    ];
    for selection in selections {
        for fast_path in [true, false] {
            for position_uniformity in [false, true] {
                cases.push(ResolveSettings {
                    fast_path,
                    selection,
                    position_uniformity,
                    ..ResolveSettings::default()
                });
            }
        }
    }
    let default_options = msaa.options().clone();
    let mut complex_pixels = 0;
    let mut outside_pixels = 0;
    for settings in cases {
        {
            {
                let options = RetrofitOptions {
                    resolve: settings,
                    ..default_options.clone()
                };
                msaa.set_options(gl, &options).unwrap();
                // The same frame again: a resolve takes a begun one.
                unsafe {
                    gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap()))
                };
                host.draw(gl, &projection(), false);
                msaa.resolve(gl, &frame()).unwrap();
                let resolved: Vec<_> = [host.color(), host.position(), host.normal()]
                    .iter()
                    .map(|t| readback.read(gl, TextureRef::from(*t), 1).unwrap())
                    .collect();
                let resolved_depth = readback.read(gl, TextureRef::from(&host.depth), 1).unwrap();
                let cpu = CpuResolve {
                    settings,
                    rules: msaa.rules().to_vec(),
                    key_source: CpuKeySource::Position(1),
                    clear_depth: 1.0,
                    footprint: footprint(),
                    normal: None,
                    camera: camera(),
                };
                // The same resolve without selective AA.
                let plain = CpuResolve {
                    settings: ResolveSettings {
                        selection: Selection::default(),
                        ..settings
                    },
                    ..cpu.clone()
                };
                let mut bad = Vec::new();
                for y in 0..H {
                    for x in 0..W {
                        let px = pixel_samples(&depth_samples, &samples, x, y);
                        let at = PixelPlace {
                            x,
                            y,
                            width: W,
                            height: H,
                        };
                        let want = cpu.resolve_pixel_at(&px, Some(at));
                        if settings.selection.is_active() {
                            let all = plain.resolve_pixel_at(&px, Some(at));
                            outside_pixels += usize::from(all.complex && !want.complex);
                        } else {
                            complex_pixels += usize::from(want.complex);
                        }
                        if want.ambiguous {
                            continue;
                        }
                        for (k, plane) in resolved.iter().enumerate() {
                            let got = plane.get(0, x, y);
                            let ok = if k == 1 {
                                (0..4).all(|c| {
                                    ((got[c] as f64) - want.attachments[k][c]).abs()
                                        <= 1e-4 * (1.0 + want.attachments[k][c].abs())
                                })
                            } else {
                                (0..4).all(|c| half_close(got[c], want.attachments[k][c]))
                            };
                            if !ok {
                                bad.push(format!(
                                    "({x},{y}) att {k}: gpu {got:?} cpu {:?}",
                                    want.attachments[k]
                                ));
                            }
                        }
                        let d = resolved_depth.get(0, x, y)[0] as f64;
                        if (d - want.depth).abs() > 1e-6 {
                            bad.push(format!("({x},{y}) depth: gpu {d} cpu {}", want.depth));
                        }
                    }
                }
                assert!(
                    bad.is_empty(),
                    "{settings:?}: {} mismatches: {:#?}",
                    bad.len(),
                    &bad[..bad.len().min(6)]
                );
            }
        }
    }
    // Two layers on rasterised samples: the first layer split by normal and
    // the second layer (only where the first resolve flagged a sample
    // outside its cluster) against the CPU reference.
    let mut second_pixels = 0;
    for (method, window) in [
        (ResolveMethod::Median, Window::Smooth),
        (ResolveMethod::Front, Window::Hard),
    ] {
        let settings = ResolveSettings {
            method,
            window,
            layers: 2,
            ..ResolveSettings::default()
        };
        let options = RetrofitOptions {
            resolve: settings,
            normal_attachment: Some(NormalAttachment {
                attachment: ColorAttachment(2),
                encoding: NormalEncoding::Xyz,
            }),
            ..default_options.clone()
        };
        // A second layer changes what the retrofit allocates, so its twins
        // are new: the host draws into them again.
        msaa.set_options(gl, &options).unwrap();
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
        let (colors, depth) = msaa.second_layer_gbuffer().unwrap();
        let layer: Vec<_> = colors
            .iter()
            .map(|t| readback.read(gl, *t, 1).unwrap())
            .collect();
        let layer_depth = readback.read(gl, depth, 1).unwrap();
        let coverage = readback
            .read(gl, msaa.second_layer_coverage().unwrap(), 1)
            .unwrap();
        let first: Vec<_> = [host.color(), host.position(), host.normal()]
            .iter()
            .map(|t| readback.read(gl, TextureRef::from(*t), 1).unwrap())
            .collect();
        // The retrofit's own CPU reference, which the comparison below holds
        // to the GPU's two layers.
        let cpu = msaa.cpu_reference(&frame()).unwrap();
        assert_eq!(cpu.settings, settings);
        assert!(matches!(cpu.key_source, CpuKeySource::Position(1)));
        assert_eq!(cpu.normal, Some((2, NormalEncoding::Xyz)));
        assert_eq!(cpu.clear_depth, 1.0);
        assert!((cpu.footprint - footprint()).abs() <= 1e-12 * footprint());
        let mut bad = Vec::new();
        for y in 0..H {
            for x in 0..W {
                let px = pixel_samples(&depth_samples, &samples, x, y);
                let at = Some(PixelPlace {
                    x,
                    y,
                    width: W,
                    height: H,
                });
                let want_first = cpu.resolve_pixel_at(&px, at);
                let want = cpu.resolve_second_layer_at(&px, at);
                second_pixels += usize::from(want.reference.is_some());
                if want.ambiguous {
                    continue;
                }
                let a = coverage.get(0, x, y)[0] as f64;
                if (a - want.coverage).abs() > 1e-3 {
                    bad.push(format!("({x},{y}) coverage: gpu {a} cpu {}", want.coverage));
                }
                for k in 0..3 {
                    // The second layer's colours mean something where it covers the pixel.
                    let mut pairs = vec![(&first[k], &want_first.attachments[k], "first")];
                    if want.coverage > 0.0 {
                        pairs.push((&layer[k], &want.attachments[k], "second"));
                    }
                    for (plane, expected, which) in pairs {
                        let got = plane.get(0, x, y);
                        let ok = if k == 1 {
                            (0..4).all(|c| {
                                ((got[c] as f64) - expected[c]).abs()
                                    <= 1e-4 * (1.0 + expected[c].abs())
                            })
                        } else {
                            (0..4).all(|c| half_close(got[c], expected[c]))
                        };
                        if !ok {
                            bad.push(format!(
                                "({x},{y}) {which} layer att {k}: gpu {got:?} cpu {expected:?}"
                            ));
                        }
                    }
                }
                let d = layer_depth.get(0, x, y)[0] as f64;
                if (d - want.depth).abs() > 1e-6 {
                    bad.push(format!(
                        "({x},{y}) second layer depth: gpu {d} cpu {}",
                        want.depth
                    ));
                }
            }
        }
        assert!(
            bad.is_empty(),
            "{settings:?}: {} mismatches: {:#?}",
            bad.len(),
            &bad[..bad.len().min(6)]
        );
    }
    assert!(
        second_pixels > 20,
        "only {second_pixels} pixels with a second layer"
    );
    msaa.set_options(gl, &default_options).unwrap();
    // The scene has edges: the slow path must really have been exercised,
    // and every selection must have turned some complex pixels into one-sample ones.
    assert!(complex_pixels > 30, "only {complex_pixels} complex pixels");
    assert!(
        outside_pixels > 4 * 20,
        "selective AA left only {outside_pixels} complex pixels out"
    );

    readback.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

#[test]
fn sample_count_and_size_changes_rebuild_the_twins() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut msaa = MsaaRetrofit::new(
        gl,
        host.fbo.raw(),
        &RetrofitOptions {
            position_attachment: Some(ColorAttachment(1)),
            ..Default::default()
        },
    )
    .unwrap();
    let first = msaa.framebuffer();
    for requested in [2, 4, 1, 3] {
        msaa.set_samples(gl, requested).unwrap();
        // Drivers round: the count is read back, never assumed.
        assert!(msaa.samples() >= requested.max(1));
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
    }
    assert_ne!(first, msaa.framebuffer());
    let e = msaa.set_samples(gl, 64).unwrap_err();
    assert!(matches!(e, Error::UnsupportedSampleCount { .. }), "{e}");
    assert!(e.to_string().contains("offers"), "{e}");
    // A failed change leaves the retrofit working.
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    msaa.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before);
}

/// The profile (`set_profiling`): off, nothing is recorded; on, every step
/// of the three calls is, in order, with a host's own step timed into the
/// same profile between them, and the lit image is bit for bit the one
/// made without profiling; a new resolve starts a new profile.
#[test]
fn profiling_times_each_step_and_changes_nothing() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    let (output, fbo) = lit_output(gl, Format::Rgba16f);
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        layer_mix: LayerMix::Tonemapped, // an RGBA16F lit output: its tonemap declared
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let mut frame_of = |msaa: &mut MsaaRetrofit| {
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
        host.light(gl, fbo.raw(), 1.0);
        assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
        msaa.profile_mut()
            .time(gl, "the host's second lighting", || {
                host.light(gl, fbo.raw(), 1.0)
            });
        msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
        let image = readback
            .read(gl, TextureRef::from(&output), 1)
            .unwrap()
            .data;
        let steps: Vec<&str> = msaa.profile().steps().iter().map(|(n, _)| *n).collect();
        let times_ok = msaa.profile().steps().iter().all(|(_, ms)| *ms >= 0.0);
        (image, steps.join(", "), times_ok)
    };
    let (plain, steps, _) = frame_of(&mut msaa);
    assert_eq!(steps, "", "nothing is recorded unless asked");
    msaa.set_profiling(true);
    let (profiled, steps, times_ok) = frame_of(&mut msaa);
    assert!(times_ok);
    assert_eq!(
        steps,
        "clear check, resolve, second layer: selection, second layer: resolve, second layer: count, \
         second layer: keep lit first layer, second layer: save host G-buffer, \
         second layer: copy in, second layer: depth into host, the host's second lighting, \
         second layer: keep lit second layer, second layer: mix, \
         second layer: restore host G-buffer"
    );
    assert!(
        plain
            .iter()
            .zip(&profiled)
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "profiling changes the image"
    );
    // The next frame's profile replaces this one's, it does not add to it.
    let (_, again, _) = frame_of(&mut msaa);
    assert_eq!(again, steps);
    msaa.set_profiling(false);
    let (_, off, _) = frame_of(&mut msaa);
    assert_eq!(off, "");
    msaa.destroy(gl);
    fbo.destroy(gl);
    output.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before);
}
