//! The resolve's GLSL against its CPU reference for N = 2, 4, 8 and 16.
//!
//! llvmpipe offers only 4x MSAA, so the same resolve body is compiled over
//! `sampler2DArray` inputs (one layer per sample, docs/testing.md) and fed
//! random and adversarial per-sample data: ties, all background, a single
//! geometry sample, NaN and Inf values, denormals, equal depths with different
//! colours, opposite normals, HDR values up to 65504.

// Per-sample arrays run in parallel; indices read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

mod cases;
mod creases;
mod harness;

use crate::common;

use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::{
    KeySource, NormalEncoding, ResolveMethod, ResolveSettings, ResolveSlot, Resolver, Window,
};
use deferred_msaa_testkit::Rng;

use cases::*;
use creases::{Normals, gen_crease_case};
use harness::Harness;

fn settings_matrix() -> Vec<ResolveSettings> {
    let mut all = Vec::new();
    for &method in ResolveMethod::all() {
        for &window in Window::all() {
            if method == ResolveMethod::Average && window == Window::Hard {
                continue;
            }
            all.push(ResolveSettings {
                method,
                window,
                ..ResolveSettings::default()
            });
        }
    }
    all.push(ResolveSettings {
        fast_path: false,
        ..ResolveSettings::default()
    });
    all.push(ResolveSettings {
        blend_depth: true,
        c: 3.0,
        c_in: 1.0,
        ..ResolveSettings::default()
    });
    all
}

fn run_for(n: u32) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = deferred_msaa_lab::gl::live_objects();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let harness = Harness::new(gl, n, 0xD5A0 + n as u64);
    for settings in settings_matrix() {
        harness.check(gl, &mut resolver, &mut readback, settings);
    }
    harness.destroy(gl);
    resolver.destroy(gl);
    readback.destroy(gl);
    assert_eq!(deferred_msaa_lab::gl::live_objects(), before);
}

/// A world-space position key: the GPU and the CPU reference agree, with
/// uniformity decided on the whole position.
#[test]
fn a_world_space_key_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let harness = Harness::new(gl, 4, 0x5EED);
    for fast_path in [true, false] {
        let settings = ResolveSettings {
            fast_path,
            ..ResolveSettings::default()
        };
        let key = KeySource::WorldPosition(ResolveSlot(1));
        harness.check_keyed(gl, &mut resolver, &mut readback, settings, key);
    }
    harness.destroy(gl);
    resolver.destroy(gl);
    readback.destroy(gl);
}

/// The opt-in position test: the GPU agrees with its CPU mirror for every
/// count and both position keys, and a pixel takes one sample exactly where
/// its position samples are all equal, background samples included.
#[test]
fn position_uniformity_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 4, 8, 16] {
        // A third of the pixels get one position in every sample (one
        // fragment, or the adversarial case of background samples that hold
        // the geometry's position); the rest keep their random ones.
        let mut rng = Rng::new(0x9051 + n as u64);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| {
                let mut case = gen_case(&mut rng, n as usize, p % 10);
                if p % 3 == 0 {
                    let first = case.atts[1][0];
                    case.atts[1].iter_mut().for_each(|v| *v = first);
                }
                case
            })
            .collect();
        let harness = Harness::upload(gl, n, cases);
        let equal: Vec<bool> = harness
            .cases
            .iter()
            .map(|c| c.atts[1].iter().all(|v| *v == c.atts[1][0]))
            .collect();
        assert!(equal.iter().any(|&e| e) && equal.iter().any(|&e| !e));
        for key in [
            KeySource::Position(ResolveSlot(1)),
            KeySource::WorldPosition(ResolveSlot(1)),
        ] {
            for method in [ResolveMethod::Median, ResolveMethod::Front] {
                let settings = ResolveSettings {
                    method,
                    position_uniformity: true,
                    ..ResolveSettings::default()
                };
                let off = ResolveSettings {
                    position_uniformity: false,
                    ..settings
                };
                harness.check_keyed(gl, &mut resolver, &mut readback, off, key);
                let with = harness.check_keyed(gl, &mut resolver, &mut readback, settings, key);
                for (p, px) in with.iter().enumerate() {
                    assert_eq!(px.complex, !equal[p], "{n}x {key:?} {method}: pixel {p}");
                }
            }
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
}

#[test]
fn two_samples() {
    run_for(2);
}

#[test]
fn four_samples() {
    run_for(4);
}

#[test]
fn eight_samples() {
    run_for(8);
}

#[test]
fn sixteen_samples() {
    run_for(16);
}

#[test]
fn odd_counts_follow_the_same_rules() {
    // Not a hardware count, but the math must not assume powers of two.
    run_for(3);
}

#[test]
fn plane_uniformity_takes_one_sample_on_a_tilted_triangle() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 3, 4, 8, 16] {
        let mut rng = Rng::new(0x91A7E + n as u64);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| gen_plane_case(&mut rng, n as usize, p % 8))
            .collect();
        let kinds: Vec<u32> = (0..W * H).map(|p| p % 8).collect();
        let harness = Harness::upload(gl, n, cases);
        for method in [ResolveMethod::Median, ResolveMethod::Front] {
            let on = ResolveSettings {
                method,
                plane_uniformity: true,
                ..ResolveSettings::default()
            };
            let off = ResolveSettings {
                plane_uniformity: false,
                ..on
            };
            // The GPU agrees with the CPU reference with the option on and off.
            let with = harness.check_keyed(gl, &mut resolver, &mut readback, on, KeySource::Depth);
            let without =
                harness.check_keyed(gl, &mut resolver, &mut readback, off, KeySource::Depth);
            let mut fired = [0usize; 8];
            let mut depth_moved = 0;
            let mut worst = [0.0f64; 6];
            for (p, (w, o)) in with.iter().zip(&without).enumerate() {
                if w.ambiguous || o.ambiguous || w.complex || !o.complex {
                    continue;
                }
                fired[kinds[p] as usize] += 1;
                let d = (w.depth - o.depth).abs();
                worst[5] = worst[5].max(d);
                if d > 1e-4 {
                    depth_moved += 1;
                }
                for k in 0..RULES.len() {
                    for c in 0..4 {
                        let e = (w.attachments[k][c] - o.attachments[k][c]).abs();
                        worst[k] = worst[k].max(e);
                    }
                }
            }
            let per_kind = (W * H / 8) as usize;
            eprintln!(
                "{n}x {method}: the plane test fired on {fired:?} pixels by kind \
                 ({per_kind} each); largest change against the slow path per \
                 attachment and depth {worst:?}"
            );
            // Every one-triangle pixel takes one sample; for 4 samples and
            // more, two surfaces and differing colours never do.
            assert!(fired[0] * 10 >= per_kind * 9, "{fired:?}");
            if n >= 4 {
                assert_eq!(fired[1] + fired[2], 0, "{fired:?}");
            } else {
                assert!(fired[1] * 10 >= per_kind * 9, "{fired:?}");
                assert_eq!(fired[2], 0, "{fired:?}");
            }
            // The slow path would have given another depth there, so the
            // GPU's agreement with the CPU shows that it took the plane test.
            assert!(depth_moved * 2 >= fired[0], "{depth_moved} of {fired:?}");
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
}

/// The second layer, and the first layer with clusters split by normal
/// (one layer or two), against the CPU reference for N = 2, 4, 8 and 16 over the adversarial
/// cases, by depth alone and with each normal encoding; pixels of one
/// cluster, two, and three or more all occur.
#[test]
fn second_layer_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = deferred_msaa_lab::gl::live_objects();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 4, 8, 16] {
        let mut harness = Harness::new(gl, n, 0x2A7E + n as u64);
        let normals = [
            None,
            Some((2, NormalEncoding::Xyz)),
            Some((2, NormalEncoding::Unorm)),
            Some((2, NormalEncoding::Octahedral)),
            Some((2, NormalEncoding::OctahedralUnorm)),
        ];
        for normal in normals {
            harness.normal = normal;
            for (method, window) in [
                (ResolveMethod::Median, Window::Smooth),
                (ResolveMethod::Front, Window::Hard),
                (ResolveMethod::Back, Window::Smooth),
            ] {
                let settings = ResolveSettings {
                    method,
                    window,
                    layers: 2,
                    ..ResolveSettings::default()
                };
                // The first layer, its clusters split by normal, with two
                // layers and with one (the normal test is the same).
                harness.check(gl, &mut resolver, &mut readback, settings);
                let one_layer = ResolveSettings {
                    layers: 1,
                    ..settings
                };
                harness.check(gl, &mut resolver, &mut readback, one_layer);
                let layers = harness.check_second_layer(gl, &mut resolver, &mut readback, settings);
                let two = layers.iter().filter(|l| l.reference.is_some()).count();
                // Three or more clusters: samples of neither kept cluster
                // join one of them.
                let three = layers
                    .iter()
                    .filter(|l| l.reference.is_some() && l.joined.iter().sum::<usize>() > 0)
                    .count();
                assert!(
                    two > 0,
                    "{n}x {normal:?} {method}: no pixel has a second layer"
                );
                if n >= 4 && method == ResolveMethod::Median {
                    assert!(three > 0, "{n}x {normal:?}: no pixel has three clusters");
                }
                assert!(two < layers.len(), "{n}x: every pixel has a second layer");
            }
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
    assert_eq!(deferred_msaa_lab::gl::live_objects(), before);
}

/// A tie between a crease's two faces (as many samples on each) goes to the
/// face the pixel centre sees where the normals are the faces' view-space
/// normals (the crease rule), and by the pixel's parity where they are not
/// (turned normals, which the rule must not trust): the GPU agrees with the
/// CPU reference on every pixel either way.
#[test]
fn a_crease_tie_goes_to_the_face_the_centre_sees() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 4, 8, 16] {
        for normals in [Normals::View, Normals::Turned] {
            let mut rng = Rng::new(0xC4EA5E + n as u64);
            let (cases, truths): (Vec<_>, Vec<_>) = (0..W * H)
                .map(|p| gen_crease_case(&mut rng, n as usize, p, normals))
                .unzip();
            let mut harness = Harness::upload(gl, n, cases);
            harness.normal = Some((2, NormalEncoding::Xyz));
            for layers in [1, 2] {
                let settings = ResolveSettings {
                    layers,
                    ..ResolveSettings::default()
                };
                let key = KeySource::Position(ResolveSlot(1));
                let got = harness.check_keyed(gl, &mut resolver, &mut readback, settings, key);
                let (mut ties, mut centre) = (0usize, 0usize);
                for (px, truth) in got.iter().zip(&truths) {
                    let on_first = truth.faces.iter().filter(|&&f| f == 0).count();
                    if on_first * 2 != n as usize || px.ambiguous {
                        continue;
                    }
                    ties += 1;
                    centre += usize::from(truth.faces[px.reference] == truth.centre);
                }
                eprintln!(
                    "{n}x {layers} layer(s): {centre} of {ties} crease ties on the centre's face"
                );
                assert!(ties >= 30, "too few ties to judge: {ties}");
                if normals == Normals::View {
                    assert!(centre * 100 >= ties * 97, "{centre} of {ties}");
                } else {
                    assert!(
                        centre * 4 >= ties && centre * 4 <= ties * 3,
                        "{centre} of {ties}"
                    );
                }
            }
            harness.destroy(gl);
        }
    }
    resolver.destroy(gl);
    readback.destroy(gl);
}
