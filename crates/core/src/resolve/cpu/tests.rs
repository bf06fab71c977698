//! The CPU reference's own cases, rule by rule.

use super::*;

fn resolver(method: ResolveMethod, window: Window) -> CpuResolve {
    CpuResolve {
        settings: ResolveSettings {
            method,
            window,
            ..ResolveSettings::default()
        },
        rules: vec![ResolveRule::Blend, ResolveRule::Blend],
        key_source: CpuKeySource::Position(1),
        clear_depth: 1.0,
        footprint: 0.001,
        normal: None,
        camera: CpuCamera {
            projection: DepthProjection::from_matrix(&[0.0; 16], false, 1.0),
            fov_y: 1.0,
        },
    }
}

/// A pixel of even parity (`false`) or odd parity (`true`): the median's
/// tie between its two middle samples goes by it.
fn at(odd: bool) -> Option<PixelPlace> {
    Some(PixelPlace {
        x: u32::from(odd),
        y: 0,
        width: 2,
        height: 1,
    })
}

/// Colour = sample index, position z = −depths[i].
fn pixel(depths: &[f64]) -> PixelSamples {
    PixelSamples {
        depth: depths
            .iter()
            .map(|&z| if z.is_infinite() { 1.0 } else { 0.5 })
            .collect(),
        attachments: vec![
            (0..depths.len())
                .map(|i| [i as f64, 0.0, 0.0, 1.0])
                .collect(),
            depths.iter().map(|&z| [0.0, 0.0, -z, 1.0]).collect(),
        ],
    }
}

#[test]
fn median_is_the_median_by_depth_not_by_index() {
    // Sorted by depth the samples are 3, 1, 0, 2: the middle two are
    // samples 1 and 0. An index-comparing network (FreeSpace Open's bug)
    // would return sample 1 or 2 whatever the depths.
    let cpu = resolver(ResolveMethod::Median, Window::Hard);
    let upper = resolver(ResolveMethod::UpperMedian, Window::Hard);
    let px = pixel(&[30.0, 20.0, 40.0, 10.0]);
    assert_eq!(cpu.resolve_pixel_at(&px, at(false)).reference, 1);
    assert_eq!(cpu.resolve_pixel_at(&px, at(true)).reference, 0);
    assert_eq!(upper.resolve_pixel_at(&px, at(false)).reference, 0);
    assert_eq!(upper.resolve_pixel_at(&px, at(true)).reference, 0);
    let px = pixel(&[5.0, 9.0, 1.0, 7.0, 3.0, 8.0, 2.0, 6.0]);
    // Sorted: 1(s2) 2(s6) 3(s4) 5(s0) 6(s7) 7(s3) 8(s5) 9(s1); ranks 3 and 4
    // are s0 and s7.
    assert_eq!(cpu.resolve_pixel_at(&px, at(false)).reference, 0);
    assert_eq!(cpu.resolve_pixel_at(&px, at(true)).reference, 7);
    assert_eq!(upper.resolve_pixel_at(&px, at(false)).reference, 7);
    // An odd count has one middle sample: rank 1 of 3, on either parity.
    let px = pixel(&[30.0, 10.0, 20.0]);
    assert_eq!(cpu.resolve_pixel_at(&px, at(false)).reference, 2);
    assert_eq!(cpu.resolve_pixel_at(&px, at(true)).reference, 2);
}

#[test]
fn a_half_covered_pixel_goes_to_either_surface_by_its_parity() {
    // A bar (z = 10) over a wall (z = 50), two samples each: neighbouring
    // pixels take the bar and the wall in turn, so a thin bar is drawn as
    // wide as it is; FreeSpace Open's rank always takes the wall.
    let cpu = resolver(ResolveMethod::Median, Window::Hard);
    let upper = resolver(ResolveMethod::UpperMedian, Window::Hard);
    let px = pixel(&[50.0, 10.0, 50.0, 10.0]);
    let on = |cpu: &CpuResolve, x: u32, y: u32| {
        let place = PixelPlace {
            x,
            y,
            width: 8,
            height: 8,
        };
        cpu.resolve_pixel_at(&px, Some(place)).reference
    };
    // Rows from the top: y = 0 is GL's row 7, so (0, 0) is odd.
    assert_eq!([on(&cpu, 0, 0), on(&cpu, 1, 0), on(&cpu, 0, 1)], [0, 3, 3]);
    assert_eq!(
        [on(&upper, 0, 0), on(&upper, 1, 0), on(&upper, 0, 1)],
        [0, 0, 0]
    );
    // Without a place the pixel counts as the origin: even, the nearer.
    assert_eq!(cpu.resolve_pixel(&px).reference, 3);
}

#[test]
fn ties_break_to_the_lower_index() {
    let px = pixel(&[10.0, 5.0, 5.0, 10.0]);
    assert_eq!(
        resolver(ResolveMethod::Front, Window::Hard)
            .resolve_pixel(&px)
            .reference,
        1
    );
    assert_eq!(
        resolver(ResolveMethod::Back, Window::Hard)
            .resolve_pixel(&px)
            .reference,
        0
    );
    // Sorted (z, i): s1 s2 s0 s3 → the middle two are s2 and s0.
    let median = resolver(ResolveMethod::Median, Window::Hard);
    assert_eq!(median.resolve_pixel_at(&px, at(false)).reference, 2);
    assert_eq!(median.resolve_pixel_at(&px, at(true)).reference, 0);
}

#[test]
fn background_majority_resolves_to_background() {
    let inf = f64::INFINITY;
    let px = pixel(&[10.0, inf, inf, inf]);
    let out = resolver(ResolveMethod::Median, Window::Smooth).resolve_pixel(&px);
    assert_eq!(out.weights, vec![0.0, 1.0, 1.0, 1.0]);
    assert_eq!(out.attachments[0][0], 2.0); // mean of samples 1..3
    assert_eq!(out.depth, 1.0);
}

#[test]
fn hard_window_blends_only_close_samples() {
    // footprint at z=100: 0.1 → c·m = 0.5.
    let px = pixel(&[100.0, 100.4, 100.6, 300.0]);
    let out = resolver(ResolveMethod::Front, Window::Hard).resolve_pixel(&px);
    assert_eq!(out.reference, 0);
    assert_eq!(out.weights, vec![1.0, 1.0, 0.0, 0.0]);
    assert_eq!(out.attachments[0][0], 0.5);
}

#[test]
fn smooth_window_ramps() {
    // c_in·m = 0.25, c·m = 0.5 at z = 100.
    let px = pixel(&[100.0, 100.2, 100.375, 100.6]);
    let out = resolver(ResolveMethod::Front, Window::Smooth).resolve_pixel(&px);
    assert_eq!(out.weights[1], 1.0);
    assert!((out.weights[2] - 0.5).abs() < 1e-9, "{:?}", out.weights);
    assert_eq!(out.weights[3], 0.0);
}

#[test]
fn average_weighs_everything() {
    let inf = f64::INFINITY;
    let px = pixel(&[1.0, 100.0, inf, 7.0]);
    let out = resolver(ResolveMethod::Average, Window::Hard).resolve_pixel(&px);
    assert_eq!(out.weights, vec![1.0; 4]);
    assert_eq!(out.attachments[0][0], 1.5);
}

#[test]
fn fast_path_takes_sample_zero() {
    let mut px = pixel(&[10.0; 4]);
    px.attachments[0][1] = [9.0, 9.0, 9.0, 9.0];
    let cpu = resolver(ResolveMethod::Median, Window::Smooth);
    let out = cpu.resolve_pixel(&px);
    assert!(!out.complex);
    assert_eq!(out.attachments[0], px.attachments[0][0]);
    let mut slow = cpu.clone();
    slow.settings.fast_path = false;
    let out = slow.resolve_pixel(&px);
    assert!(out.complex);
    assert_eq!(out.attachments[0][0], (0.0 + 9.0 + 2.0 + 3.0) / 4.0);
}

#[test]
fn non_finite_values_are_skipped() {
    let mut px = pixel(&[10.0; 4]);
    px.attachments[0][2] = [f64::NAN, 0.0, 0.0, 1.0];
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    cpu.settings.fast_path = false;
    let out = cpu.resolve_pixel(&px);
    assert_eq!(out.attachments[0][0], (0.0 + 1.0 + 3.0) / 3.0);
}

#[test]
fn equal_normals_are_kept_as_written() {
    // Not unit length (a gloss-scaled normal): one surface's samples
    // resolve to it unchanged, as the host's own render holds it.
    let n = [0.3, 0.1, 0.2, 0.7];
    assert_eq!(blend_normal(&[n, n, n], &[1.0, 0.5, 1.0], 0), n);
}

#[test]
fn opposite_normals_fall_back_to_the_reference() {
    let values = vec![[0.0, 0.0, 1.0, 0.3], [0.0, 0.0, -1.0, 0.5]];
    let out = blend_normal(&values, &[1.0, 1.0], 1);
    assert_eq!(out, [0.0, 0.0, -1.0, 0.4]);
}

#[test]
fn hdr_blend_stays_finite_and_in_range() {
    let values = vec![[65504.0, 65504.0, 65504.0, 1.0], [65504.0, 0.0, 1.0, 1.0]];
    let out = blend_hdr(&values, &[1.0, 1.0], 0);
    assert!(out.iter().all(|c| c.is_finite()));
    assert!(out[0] <= 65504.0 && out[0] >= 65504.0 * 0.99);
    let one = blend_hdr(&values[..1], &[1.0], 0);
    assert_eq!(one[0], 65504.0);
}

#[test]
fn depth_keys_from_the_projection() {
    // Standard GL projection terms for near 0.1, far 100.
    let (n, f) = (0.1, 100.0);
    let dp = DepthProjection {
        p22: -(f + n) / (f - n),
        p23: -2.0 * f * n / (f - n),
        zero_to_one: false,
        clear_depth: 1.0,
    };
    // A point at distance 10: z_clip = p22·(−10) + p23, w = 10.
    let z_ndc = (dp.p22 * -10.0 + dp.p23) / 10.0;
    let depth = (z_ndc + 1.0) * 0.5;
    assert!((dp.linearize(depth) - 10.0).abs() < 1e-9);
    assert!((dp.linearize(0.0) - n).abs() < 1e-12);
    assert!((dp.linearize(1.0) - f).abs() < 1e-9);
    // Reversed-Z with an infinite far plane and GL_ZERO_TO_ONE: depth = n / z.
    let rev = DepthProjection {
        p22: 0.0,
        p23: n,
        zero_to_one: true,
        clear_depth: 0.0,
    };
    assert!((rev.linearize(n / 10.0) - 10.0).abs() < 1e-9);
    assert!(rev.linearize(0.0).is_infinite());
}

#[test]
fn the_second_layer_is_the_largest_other_cluster_sharing_with_the_first() {
    let inf = f64::INFINITY;
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    cpu.settings.layers = 2;
    // A bar (z = 10) over the sky: median takes the sky (samples 1..3),
    // the second layer is the bar's one sample.
    let out = cpu.resolve_second_layer_at(&pixel(&[10.0, inf, inf, inf]), at(true));
    assert_eq!(out.reference, Some(0));
    assert_eq!(out.coverage, 0.25);
    assert_eq!(out.weights, vec![1.0, 0.0, 0.0, 0.0]);
    // On a pixel of odd parity (the farther middle sample):
    // three clusters (10, 50, 200): the median's (50, samples 1 and 2),
    // then the largest of the rest, ties to the nearer: 10 (sample 0).
    let px = pixel(&[10.0, 50.0, 50.0, 200.0]);
    let first = cpu.resolve_pixel_at(&px, at(true));
    assert_eq!(first.weights, vec![0.0, 1.0, 1.0, 0.0]);
    let out = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!(out.reference, Some(0));
    // Sample 3 (200) is in neither: it joins the nearer in depth, the
    // first (50 is 150 away, 10 is 190), so the second keeps 1 of 4.
    assert_eq!((out.coverage, out.joined), (0.25, [1, 0]));
    // A third cluster nearer the second (12 beside 10): it joins the
    // second, which then holds 2 of 4.
    let px = pixel(&[10.0, 12.0, 50.0, 50.0]);
    let out = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!(out.reference, Some(0));
    assert_eq!(out.weights, vec![1.0, 0.0, 0.0, 0.0]);
    assert_eq!((out.coverage, out.joined), (0.5, [0, 1]));
    // On an even pixel the median is the 12: the 50s are the second layer
    // (the largest cluster outside) and the 10 joins the first, nearer.
    let out = cpu.resolve_second_layer_at(&px, at(false));
    assert_eq!(out.reference, Some(2));
    assert_eq!((out.coverage, out.joined), (0.5, [1, 0]));
    // One cluster: no second layer, sample 0's values at the clear depth.
    let out = cpu.resolve_second_layer_at(&pixel(&[10.0, 10.01, 10.0, 10.02]), None);
    assert_eq!((out.reference, out.coverage, out.depth), (None, 0.0, 1.0));
}

#[test]
fn normals_split_a_crease_with_one_layer_or_two() {
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    // One depth, two orientations 90 degrees apart (attachment 0 holds
    // the normals here): samples 0, 1 face +z, samples 2, 3 face +x.
    // Sorted (z, i): s0 s2 s1 s3, the middle two s2 and s1.
    let mut px = pixel(&[10.0, 10.01, 10.0, 10.01]);
    px.attachments[0] = vec![
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ];
    // By depth alone the crease is one surface.
    assert_eq!(cpu.resolve_pixel(&px).weights, vec![1.0; 4]);
    // With the normals named it is two, with one layer and with two; the
    // faces are a tie (two samples each): an even pixel keeps the
    // median's (s2, +x), an odd one moves from the median's (s1, +z) to
    // the other face's first sample (s2): the face of the nearest
    // samples on both.
    cpu.normal = Some((0, NormalEncoding::Xyz));
    let even = cpu.resolve_pixel_at(&px, at(false));
    assert_eq!(
        (even.reference, even.weights),
        (2, vec![0.0, 0.0, 1.0, 1.0])
    );
    let odd = cpu.resolve_pixel_at(&px, at(true));
    assert_eq!((odd.reference, odd.weights), (2, vec![0.0, 0.0, 1.0, 1.0]));
    // Where both middle samples are on one face (+z; +x holds the first
    // and last by depth), the median alone would take it on every pixel:
    // even pixels keep it (the median's own sample, s1), odd ones take +x.
    let mut spans = px.clone();
    spans.depth = vec![0.5; 4];
    for (i, z) in [10.02, 10.01, 10.0, 10.03].into_iter().enumerate() {
        spans.attachments[1][i] = [0.0, 0.0, -z, 1.0];
    }
    assert_eq!(cpu.resolve_pixel_at(&spans, at(false)).reference, 1);
    assert_eq!(cpu.resolve_pixel_at(&spans, at(true)).reference, 2);
    cpu.settings.layers = 2;
    let first = cpu.resolve_pixel_at(&px, at(true));
    assert_eq!(first.weights, vec![0.0, 0.0, 1.0, 1.0]);
    let second = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!(second.reference, Some(0));
    assert_eq!(second.coverage, 0.5);
}

#[test]
fn a_crease_a_half_float_position_hides_is_found_by_its_depth_samples() {
    // Two facets meeting at a ridge, a quarter pixel apart: their view
    // depths round to one half float, so every key is equal; the depth
    // samples (32-bit) differ, and the normals are 40 degrees apart.
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    cpu.normal = Some((0, NormalEncoding::Xyz));
    let (s, c) = (20f64.to_radians().sin(), 20f64.to_radians().cos());
    let mut px = pixel(&[12.0; 4]);
    px.attachments[0] = vec![
        [-s, 0.0, c, 0.0],
        [s, 0.0, c, 0.0],
        [-s, 0.0, c, 0.0],
        [s, 0.0, c, 0.0],
    ];
    px.depth = vec![0.9000, 0.9001, 0.9000, 0.9001];
    let out = cpu.resolve_pixel_at(&px, at(false));
    assert!(
        out.complex,
        "equal keys over different depth samples are not one surface"
    );
    assert_eq!(out.weights.iter().filter(|&&w| w > 0.0).count(), 2);
    cpu.settings.layers = 2;
    let second = cpu.resolve_second_layer_at(&px, at(false));
    assert_eq!(second.coverage, 0.5);
    // Where the depth samples agree too, the pixel is one surface: sample 0.
    cpu.settings.layers = 1;
    let mut flat = px.clone();
    flat.depth = vec![0.9; 4];
    let out = cpu.resolve_pixel_at(&flat, at(false));
    assert!(!out.complex);
    assert_eq!(out.attachments[0], flat.attachments[0][0]);
    // So is a slanted plane whose keys round alike: depths that differ
    // under one orientation.
    let mut slanted = px.clone();
    slanted.attachments[0] = vec![[s, 0.0, c, 0.0]; 4];
    let out = cpu.resolve_pixel_at(&slanted, at(false));
    assert!(!out.complex);
    // Without the normal test there is nothing to split: equal keys are
    // one surface, as before.
    cpu.normal = None;
    assert!(!cpu.resolve_pixel_at(&px, at(false)).complex);
}

#[test]
fn a_side_sliver_joins_its_front_face_not_the_wall() {
    // A thin box's silhouette pixel: its front face (+z, sample 0), its
    // side face 0.06 behind it (+x, sample 1), a far wall (samples 2, 3).
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    cpu.settings.layers = 2;
    cpu.normal = Some((0, NormalEncoding::Xyz));
    let mut px = pixel(&[10.0, 10.06, 200.0, 200.0]);
    px.attachments[0] = vec![
        [0.0, 0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    // On an odd pixel the median is the wall; the front face and the side
    // are two clusters of one sample, of which the nearer is the second
    // layer.
    assert_eq!(
        cpu.resolve_pixel_at(&px, at(true)).weights,
        vec![0.0, 0.0, 1.0, 1.0]
    );
    let second = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!(second.reference, Some(0));
    assert_eq!(second.weights, vec![1.0, 0.0, 0.0, 0.0]);
    // The side joins the front face (0.06 away, the wall 189.94): the
    // box keeps its two samples' share, and its layer the front
    // face's values alone.
    assert_eq!((second.coverage, second.joined), (0.5, [0, 1]));
    // Equal distances go by orientation: a sample midway in depth that
    // faces like the wall joins the first layer, like the bar the
    // second.
    let mut px = pixel(&[10.0, 105.0, 200.0, 200.0]);
    px.attachments[0] = vec![
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.6, 0.8, 0.0],
        [0.0, 0.8, 0.6, 0.0],
        [0.0, 0.8, 0.6, 0.0],
    ];
    let out = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!((out.reference, out.joined), (Some(0), [1, 0]));
    px.attachments[0][1] = [0.0, 0.28, 0.96, 0.0];
    let out = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!((out.reference, out.joined), (Some(0), [0, 1]));
}

#[test]
fn the_reference_moves_to_the_larger_face_with_one_layer_or_two() {
    // Front face twice, the side just behind it once, the wall: on an odd
    // pixel the median is the side (the 3rd of 4 by depth).
    let mut cpu = resolver(ResolveMethod::Median, Window::Hard);
    let mut px = pixel(&[10.0, 10.0, 10.001, 200.0]);
    px.attachments[0] = vec![
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    // By depth alone the median's sample stays.
    assert_eq!(cpu.resolve_pixel_at(&px, at(true)).reference, 2);
    // With the normals named, one layer takes the front face, which two
    // samples share, and so does the first of two; the wall (another
    // depth) is the second, and the side joins the first.
    cpu.normal = Some((0, NormalEncoding::Xyz));
    let one = cpu.resolve_pixel_at(&px, at(true));
    assert_eq!((one.reference, one.weights), (0, vec![1.0, 1.0, 0.0, 0.0]));
    cpu.settings.layers = 2;
    let first = cpu.resolve_pixel_at(&px, at(true));
    assert_eq!(
        (first.reference, first.weights),
        (0, vec![1.0, 1.0, 0.0, 0.0])
    );
    let second = cpu.resolve_second_layer_at(&px, at(true));
    assert_eq!(second.reference, Some(3));
    assert_eq!((second.coverage, second.joined), (0.25, [1, 0]));
}

#[test]
fn normal_encodings_decode_to_the_stored_direction() {
    let n = [0.48, -0.6, -0.64];
    let unorm = [n[0] * 0.5 + 0.5, n[1] * 0.5 + 0.5, n[2] * 0.5 + 0.5, 0.0];
    let d = NormalEncoding::Unorm.decode(unorm);
    assert!((0..3).all(|c| (d[c] - n[c]).abs() < 1e-12));
    // Octahedral: project onto |x| + |y| + |z| = 1, fold the lower half.
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let (px, py) = (n[0] / l1, n[1] / l1);
    let sign = |c: f64| if c >= 0.0 { 1.0 } else { -1.0 };
    let folded = [(1.0 - py.abs()) * sign(px), (1.0 - px.abs()) * sign(py)];
    for (encoding, stored) in [
        (NormalEncoding::Octahedral, [folded[0], folded[1], 0.0, 0.0]),
        (
            NormalEncoding::OctahedralUnorm,
            [folded[0] * 0.5 + 0.5, folded[1] * 0.5 + 0.5, 0.0, 0.0],
        ),
    ] {
        let d = encoding.decode(stored);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        assert!(
            (0..3).all(|c| (d[c] / len - n[c]).abs() < 1e-9),
            "{encoding}: {d:?}"
        );
    }
}

/// A convex crease through pixel (x, 3) of an 8x8 target (rows from the
/// top), its line vertical at `offset` pixels right of the centre: two
/// samples on each face of the standard 4x pattern for |offset| < 2/16.
/// The faces are turned ±0.5 rad about y; `turn` more turns every stored
/// normal about x (world-space normals under a view turned that way).
/// Returns the pixel, its place, which face (0: the left one) each sample
/// holds and the face the centre sees.
fn crease_pixel(x: u32, offset: f64, turn: f64) -> (PixelSamples, PixelPlace, Vec<usize>, usize) {
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let t = 0.5f64.tan(); // fov_y 1.0
    let ray = |x: f64, y: f64| [(2.0 * x / 8.0 - 1.0) * t, (2.0 * y / 8.0 - 1.0) * t, -1.0];
    let (cx, cy) = (x as f64 + 0.5, (8 - 1 - 3) as f64 + 0.5);
    let on_crease = ray(cx + offset, cy).map(|c| c * 10.0);
    // The left face leans left, the right face right: a ridge.
    let faces = [
        [-0.5f64.sin(), 0.0, 0.5f64.cos()],
        [0.5f64.sin(), 0.0, 0.5f64.cos()],
    ];
    let face_at = |x: f64, y: f64| {
        let v = ray(x, y);
        let w = faces.map(|n| dot(n, on_crease) / dot(n, v));
        // A convex crease shows the farther face.
        if w[0] > w[1] { (0, w[0]) } else { (1, w[1]) }
    };
    let (s, c) = turn.sin_cos();
    let stored = |n: [f64; 3]| [n[0], c * n[1] - s * n[2], s * n[1] + c * n[2], 0.0];
    let mut px = PixelSamples {
        depth: Vec::new(),
        attachments: vec![Vec::new(), Vec::new(), Vec::new()],
    };
    let mut which = Vec::new();
    for o in standard_sample_positions(4).unwrap() {
        let (x, y) = (cx + o[0] / 16.0, cy + o[1] / 16.0);
        let (face, w) = face_at(x, y);
        let v = ray(x, y);
        // Standard depth of an infinite-far projection with near 0.1.
        px.depth.push(1.0 - 0.1 / w);
        px.attachments[0].push([face as f64, 0.0, 0.0, 1.0]);
        px.attachments[1].push([v[0] * w, v[1] * w, -w, 1.0]);
        px.attachments[2].push(stored(faces[face]));
        which.push(face);
    }
    let place = PixelPlace {
        x,
        y: 3,
        width: 8,
        height: 8,
    };
    (px, place, which, face_at(cx, cy).0)
}

#[test]
fn a_crease_tie_goes_to_the_face_the_pixel_centre_sees() {
    let cpu = CpuResolve {
        rules: vec![ResolveRule::Blend, ResolveRule::Blend, ResolveRule::Select],
        normal: Some((2, NormalEncoding::Xyz)),
        camera: CpuCamera {
            projection: DepthProjection {
                p22: -1.0,
                p23: -0.2,
                zero_to_one: false,
                clear_depth: 1.0,
            },
            fov_y: 1.0,
        },
        // tan(fov_y / height), as a resolve of this target has it.
        footprint: 0.125f64.tan(),
        ..resolver(ResolveMethod::Median, Window::Smooth)
    };
    // GL's (4, 4) is an even place, (5, 4) an odd one.
    for x in [4, 5] {
        for (offset, centre) in [(0.05, 0), (-0.05, 1)] {
            let (px, at, which, truth) = crease_pixel(x, offset, 0.0);
            assert_eq!(which, [0, 1, 0, 1], "a tie");
            assert_eq!(truth, centre);
            let got = cpu.resolve_pixel_at(&px, Some(at));
            assert!(!got.ambiguous);
            assert_eq!(which[got.reference], centre, "x {x} offset {offset}");
            let faces = |face: usize| which.iter().map(|&f| f == face).collect::<Vec<_>>();
            let side = cpu.crease_side(&px, (0, &faces(0)), (1, &faces(1)), Some(at));
            assert_eq!(side, (Some(centre == 0), false));
            // Normals that are not the faces' view-space normals: the rule
            // does not decide (the parity does); nor does it without a place.
            let (px, at, ..) = crease_pixel(x, offset, 0.35);
            let side = cpu.crease_side(&px, (0, &faces(0)), (1, &faces(1)), Some(at));
            assert_eq!(side.0, None);
            assert_eq!(
                cpu.crease_side(&px, (0, &faces(0)), (1, &faces(1)), None).0,
                None
            );
        }
    }
    // Faces that do not meet (a silhouette: the left face 5 units nearer
    // than its plane would meet the right one) are not a crease.
    let (mut px, at, which, _) = crease_pixel(4, 0.05, 0.0);
    for (i, &face) in which.iter().enumerate() {
        if face == 0 {
            let w = 0.1 / (1.0 - px.depth[i]) - 5.0;
            px.depth[i] = 1.0 - 0.1 / w;
        }
    }
    let faces = |face: usize| which.iter().map(|&f| f == face).collect::<Vec<_>>();
    let side = cpu.crease_side(&px, (0, &faces(0)), (1, &faces(1)), Some(at));
    assert_eq!(side.0, None);
}
