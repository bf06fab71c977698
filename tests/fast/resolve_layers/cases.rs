//! The per-pixel cases the resolve is fed, and how close the GPU must come.

use deferred_msaa_lab::resolve::ResolveRule;
use deferred_msaa_lab::resolve::cpu::standard_sample_positions;
use deferred_msaa_testkit::Rng;

pub(super) const W: u32 = 24;
pub(super) const H: u32 = 16;
pub(super) const RULES: [ResolveRule; 5] = [
    ResolveRule::Blend,       // colour
    ResolveRule::Blend,       // position (the key)
    ResolveRule::BlendNormal, // normal, gloss in w
    ResolveRule::BlendHdr,    // emissive
    ResolveRule::Select,      // material id (RGBA32UI)
];
pub(super) const CLEAR_DEPTH: f32 = 1.0;
pub(super) const FOV_Y: f64 = 0.9;
/// The view matrix's third row for the world-space key: a view turned a
/// little about x and y, so the key mixes every position component.
pub(super) const WORLD_VIEW_ROW: [f64; 4] = [0.03, -0.04, 0.998_749_217_771_908_6, 0.0];

/// One pixel's inputs, in f32 as the GPU sees them.
pub(super) struct Case {
    pub(super) depth: Vec<f32>,
    pub(super) atts: [Vec<[f32; 4]>; 5],
}

pub(super) fn gen_case(rng: &mut Rng, n: usize, kind: u32) -> Case {
    let mut depth = vec![0.5f32; n];
    let mut z = vec![0.0f32; n];
    let base = rng.range(1.0, 200.0);
    // A pixel's footprint at distance `base` for a HxFOV_Y camera.
    let foot = base * (FOV_Y as f32 / H as f32).tan();
    // A thin box's silhouette (kind 10): per sample its front face, a side
    // face just behind it, or a far wall.
    // (Drawn for that kind alone: the other kinds' cases stay as they were.)
    let (surfaces, side_behind) = if kind == 10 {
        let surfaces: Vec<u32> = (0..n).map(|_| rng.below(3)).collect();
        (surfaces, foot * rng.range(0.02, 0.6))
    } else {
        (vec![0; n], 0.0)
    };
    for i in 0..n {
        z[i] = match kind {
            0 => rng.range(1.0, 200.0),                    // unrelated depths
            1 => base,                                     // all equal (uniform, or below)
            2 => base + foot * rng.below(3) as f32,        // clusters and exact ties
            3 => base + foot * rng.range(-6.0, 6.0),       // across the window edges
            4 => base,                                     // background (below)
            5 => base + foot * rng.range(0.0, 3.0),        // half background (below)
            6 => base,                                     // one geometry sample (below)
            7 => base + foot * rng.below(2) as f32 * 20.0, // two surfaces
            10 => [base, base + side_behind, base * 20.0][surfaces[i] as usize], // front, side, wall
            _ => rng.range(1.0, 200.0),
        };
    }
    match kind {
        // Equal keys over depth samples that differ in half of these pixels
        // (a half-float position rounds two faces' depths to one value): one
        // surface only where the normals agree (below), else the normal test
        // sees the random normals.
        1 if base > 100.0 => depth
            .iter_mut()
            .enumerate()
            .for_each(|(i, d)| *d = 0.5 + 1e-4 * (i % 2) as f32),
        4 => depth.iter_mut().for_each(|d| *d = CLEAR_DEPTH),
        5 => (0..n)
            .filter(|i| i % 2 == 1)
            .for_each(|i| depth[i] = CLEAR_DEPTH),
        6 => {
            let keep = rng.below(n as u32) as usize;
            (0..n)
                .filter(|&i| i != keep)
                .for_each(|i| depth[i] = CLEAR_DEPTH);
        }
        _ => {}
    }
    let mut atts: [Vec<[f32; 4]>; 5] = Default::default();
    for i in 0..n {
        let colour = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
        let mut position = [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), -z[i], 1.0];
        let mut normal = {
            let v = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-3);
            [v[0] / l, v[1] / l, v[2] / l, rng.unit()]
        };
        let mut emissive = [
            rng.range(0.0, 4.0),
            rng.range(0.0, 4.0),
            rng.range(0.0, 4.0),
            1.0,
        ];
        let material = [rng.below(255) as f32, i as f32, 0.0, 1.0];
        // Sprinkle the adversarial values.
        match (kind, rng.below(8)) {
            (_, 0) if (8..10).contains(&kind) => {
                let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40];
                let v = bad[rng.below(4) as usize];
                emissive[rng.below(3) as usize] = v;
            }
            (_, 1) => emissive = [65504.0, rng.range(0.0, 65504.0), 1.0, 1.0],
            (_, 2) if (8..10).contains(&kind) => position[2] = f32::NAN, // a non-finite key is background
            (_, 3) => {
                normal = if i % 2 == 0 {
                    [0.0, 0.0, 1.0, 0.5]
                } else {
                    [0.0, 0.0, -1.0, 0.25]
                }
            }
            _ => {}
        }
        if kind == 10 {
            // The front face and the wall face the eye; the side is turned
            // 50 to 90 degrees from them.
            let turn = [0.0, 1.0, 0.0][surfaces[i] as usize] * rng.range(0.87, 1.57);
            normal = [turn.sin(), 0.0, turn.cos(), normal[3]];
        }
        atts[0].push(colour);
        atts[1].push(position);
        atts[2].push(normal);
        atts[3].push(emissive);
        atts[4].push(material);
    }
    if kind == 1 && base > 150.0 {
        // A slanted plane whose keys round alike: one orientation.
        let first = atts[2][0];
        atts[2].iter_mut().for_each(|n| *n = first);
    }
    Case { depth, atts }
}

/// `close` with its tolerance multiplied by `scale` (at least 1).
pub(super) fn close_scaled(gpu: f32, cpu: f64, scale: f64) -> bool {
    if !cpu.is_finite() {
        return close(gpu, cpu);
    }
    ((gpu as f64) - cpu).abs() <= (2e-6 + 2e-5 * cpu.abs()) * scale.max(1.0)
}

/// Σ w_i |n_i| / |Σ w_i n_i| over xyz: how much normalising the weighted
/// sum amplifies the rounding of its terms (infinite for a zero sum, where
/// the blend falls back to the reference's normal and needs no scale).
pub(super) fn normal_conditioning(values: &[[f64; 4]], weights: &[f64]) -> f64 {
    let mut sum = [0.0f64; 3];
    let mut magnitude = 0.0;
    for (v, &w) in values.iter().zip(weights) {
        if w <= 0.0 || !v.iter().all(|c| c.is_finite()) {
            continue;
        }
        for c in 0..3 {
            sum[c] += w * v[c];
        }
        magnitude += w * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    }
    let len = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    if len >= 1e-6 { magnitude / len } else { 1.0 }
}

/// Σ w_i |x_i| / |Σ w_i x_i| for component `c`: how much a weighted mean
/// whose terms cancel amplifies the `f32` rounding of its terms and
/// weights (1 where nothing cancels; terms that are not finite take no
/// part, as in the blend).
pub(super) fn blend_conditioning(values: &[[f64; 4]], weights: &[f64], c: usize) -> f64 {
    let (mut sum, mut magnitude) = (0.0f64, 0.0f64);
    for (v, &w) in values.iter().zip(weights) {
        if w <= 0.0 || !v.iter().all(|x| x.is_finite()) {
            continue;
        }
        sum += w * v[c];
        magnitude += w * v[c].abs();
    }
    if sum.abs() > 0.0 {
        (magnitude / sum.abs()).max(1.0)
    } else {
        1.0
    }
}

pub(super) fn close(gpu: f32, cpu: f64) -> bool {
    if cpu.is_nan() {
        return gpu.is_nan();
    }
    if cpu.is_infinite() {
        return gpu as f64 == cpu;
    }
    ((gpu as f64) - cpu).abs() <= 2e-6 + 2e-5 * cpu.abs()
}

/// A depth-key host's pixels for the opt-in plane test: `kind` 0 is one
/// tilted triangle (depths on a plane over the standard pattern, every
/// attachment equal: one fragment), 1 two surfaces with the same attachment
/// values, 2 one plane whose first blended attachment (colour) differs by
/// sample, 3 one plane with equal colour but normals that differ (two
/// coplanar triangles with different shading), 4 and above the general cases.
pub(super) fn gen_plane_case(rng: &mut Rng, n: usize, kind: u32) -> Case {
    if kind >= 4 {
        return gen_case(rng, n, kind % 10);
    }
    let pattern: Vec<[f64; 2]> = match standard_sample_positions(n) {
        Some(p) => p.to_vec(),
        None => (0..n).map(|i| [i as f64, (i * i) as f64]).collect(),
    };
    let d0 = rng.range(0.3, 0.9) as f64;
    // Per sixteenth of a pixel: up to ~1e-3 across the pixel.
    let (a, b) = (rng.range(-1e-4, 1e-4) as f64, rng.range(-1e-4, 1e-4) as f64);
    let depth: Vec<f32> = pattern
        .iter()
        .enumerate()
        .map(|(i, q)| {
            // A second surface under the last sample (two surfaces split
            // two against two can lie on one plane over the 4x pattern).
            let other = if kind == 1 && i == n - 1 { 0.05 } else { 0.0 };
            (d0 + a * q[0] + b * q[1] + other) as f32
        })
        .collect();
    let one = [rng.unit(), rng.unit(), rng.unit(), 1.0];
    let z = (0.1 / (1.0 - d0)) as f32;
    let position = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), -z, 1.0];
    let normal = [0.0, 0.6, 0.8, 0.5];
    let emissive = [rng.range(0.0, 4.0), 1.0, 2.0, 1.0];
    let material = [7.0, 0.0, 0.0, 1.0];
    let mut atts: [Vec<[f32; 4]>; 5] = Default::default();
    for i in 0..n {
        let mut colour = one;
        let mut nrm = normal;
        if kind == 2 && i == n - 1 {
            colour[0] = 1.0 - colour[0] + 0.25;
        }
        if kind == 3 && i % 2 == 1 {
            nrm = [0.6, 0.0, 0.8, 0.5];
        }
        atts[0].push(colour);
        atts[1].push(position);
        atts[2].push(nrm);
        atts[3].push(emissive);
        atts[4].push(material);
    }
    Case { depth, atts }
}
