//! Creases through the pixel: two planar faces meeting along a line near
//! the pixel centre, drawn from the harness camera (its field of view,
//! aspect and depth projection), so the crease rule (crease.glsl) has real
//! faces to settle a tie with.

use super::*;
use deferred_msaa_lab::resolve::cpu::standard_sample_positions;

/// What a crease case is made of: which face each sample holds (0 or 1) and
/// the face the pixel centre sees.
pub(super) struct CreaseTruth {
    pub(super) faces: Vec<usize>,
    pub(super) centre: usize,
}

/// How the case's normals are stored.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Normals {
    /// View-space, as the faces have them.
    View,
    /// Turned 20 degrees about x, as world-space normals under a view turned
    /// that way would be: the crease rule must not trust them.
    Turned,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The view ray (z = −1) through window position `(x, y)`, GL's pixels.
fn ray(x: f64, y: f64) -> [f64; 3] {
    let t = (FOV_Y / 2.0).tan();
    let (w, h) = (W as f64, H as f64);
    [
        (2.0 * x / w - 1.0) * t * w / h,
        (2.0 * y / h - 1.0) * t,
        -1.0,
    ]
}

/// A unit normal facing the eye, tilted from it by up to `tilt` radians.
fn facing(rng: &mut Rng, tilt: f32) -> [f64; 3] {
    let (a, b) = (rng.range(-tilt, tilt) as f64, rng.range(-tilt, tilt) as f64);
    let v = [a.sin(), b.sin(), a.cos() * b.cos()];
    let l = dot(v, v).sqrt();
    v.map(|c| c / l)
}

/// The crease case for pixel `p` of the harness (drawn at GL's `(p % W, p / W)`).
pub(super) fn gen_crease_case(
    rng: &mut Rng,
    n: usize,
    p: u32,
    normals: Normals,
) -> (Case, CreaseTruth) {
    loop {
        if let Some(case) = try_crease_case(rng, n, p, normals) {
            return case;
        }
    }
}

/// A crease case, or `None` where a face would pass behind the eye or
/// nearer than 0.5 on some sample's ray (drawn again).
fn try_crease_case(
    rng: &mut Rng,
    n: usize,
    p: u32,
    normals: Normals,
) -> Option<(Case, CreaseTruth)> {
    let pattern = standard_sample_positions(n).expect("a standard pattern");
    let (px, py) = ((p % W) as f64 + 0.5, (p / W) as f64 + 0.5);
    // The crease passes through the view ray of a point within 0.4 px of
    // the centre, at a distance of 2 to 60.
    let (ex, ey) = (rng.range(-0.4, 0.4) as f64, rng.range(-0.4, 0.4) as f64);
    let distance = rng.range(2.0, 60.0) as f64;
    let on_crease = ray(px + ex, py + ey).map(|c| c * distance);
    // Two faces 25 to 80 degrees apart (the normal test splits them).
    let (n_a, n_b) = loop {
        let (a, b) = (facing(rng, 0.9), facing(rng, 0.9));
        let cos = dot(a, b);
        if cos < 0.9 && cos > 0.17 {
            break (a, b);
        }
    };
    // A convex crease shows the farther face on each ray, a concave one the nearer.
    let convex = rng.below(2) == 0;
    let face_at = |x: f64, y: f64| {
        let v = ray(x, y);
        let w_a = dot(n_a, on_crease) / dot(n_a, v);
        let w_b = dot(n_b, on_crease) / dot(n_b, v);
        let a_farther = w_a > w_b;
        if a_farther == convex {
            (0, w_a)
        } else {
            (1, w_b)
        }
    };
    let stored = |v: [f64; 3]| match normals {
        Normals::View => v,
        Normals::Turned => {
            let (s, c) = 0.349_065_850_398_865_9_f64.sin_cos();
            [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]
        }
    };
    let colours = [
        [rng.unit(), rng.unit(), rng.unit(), 1.0],
        [rng.unit(), rng.unit(), rng.unit(), 1.0],
    ];
    let mut depth = Vec::with_capacity(n);
    let mut atts: [Vec<[f32; 4]>; 5] = Default::default();
    let mut faces = Vec::with_capacity(n);
    for o in pattern {
        let (x, y) = (px + o[0] / 16.0, py + o[1] / 16.0);
        let (face, w) = face_at(x, y);
        if w.is_nan() || w <= 0.5 {
            return None;
        }
        // The harness projection: distance = 0.2 / (1 − z_ndc), depth = (z_ndc + 1) / 2.
        depth.push((1.0 - 0.1 / w) as f32);
        let v = ray(x, y);
        let normal = stored([n_a, n_b][face]);
        atts[0].push(colours[face]);
        atts[1].push([(v[0] * w) as f32, (v[1] * w) as f32, (-w) as f32, 1.0]);
        atts[2].push([normal[0] as f32, normal[1] as f32, normal[2] as f32, 0.5]);
        atts[3].push([0.0, 0.0, 0.0, 1.0]);
        atts[4].push([face as f32, 0.0, 0.0, 1.0]);
        faces.push(face);
    }
    let centre = face_at(px, py).0;
    Some((Case { depth, atts }, CreaseTruth { faces, centre }))
}
