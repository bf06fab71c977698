//! The crease rule (`crease.glsl`'s `crease_side`, in `f64`): which of a
//! crease's two faces the pixel centre sees, from the depth samples and
//! the normals alone (docs/resolve.md, "The crease rule").

use super::{CpuResolve, PixelPlace, PixelSamples, standard_sample_positions};
use crate::resolve::DepthProjection;

/// What the crease rule needs of the camera: how a stored depth turns into
/// a distance, and the vertical field of view that gives each window
/// position its view ray (a symmetric perspective with square pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CpuCamera {
    /// The depth linearisation.
    pub projection: DepthProjection,
    /// Vertical field of view, radians.
    pub fov_y: f64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl CpuCamera {
    /// The camera of a GPU resolve's parameters.
    pub fn of(params: &crate::resolve::ResolveParams) -> Self {
        CpuCamera {
            projection: params.projection,
            fov_y: params.fov_y,
        }
    }

    /// The inverse view distance of a stored depth (affine in window
    /// position over a plane).
    fn inverse_distance(&self, depth: f64) -> f64 {
        let p = self.projection;
        let ndc = if p.zero_to_one {
            depth
        } else {
            depth * 2.0 - 1.0
        };
        (ndc + p.p22) / p.p23
    }
}

impl CpuResolve {
    /// Which face of a crease the centre of the pixel at `at` sees: the
    /// cluster of sample `a` (its members `in_a`) or that of `b`. Each face
    /// is the plane through its seed sample with that sample's normal, taken
    /// as view-space; the crease is where their inverse distances are equal.
    /// `Some(true)`: `a`'s face; `None` where it is not known: no place, no
    /// standard pattern, a face's samples off its plane by more than the gap
    /// at the centre (normals that are not view-space, or not the faces'),
    /// or the two faces' samples on one side (faces that do not meet, a
    /// silhouette). The second value: `f32` may decide differently.
    pub(super) fn crease_side(
        &self,
        px: &PixelSamples,
        (a, in_a): (usize, &[bool]),
        (b, in_b): (usize, &[bool]),
        at: Option<PixelPlace>,
    ) -> (Option<bool>, bool) {
        let n = px.depth.len();
        let (Some(at), Some(pattern), Some((k, encoding))) =
            (at, standard_sample_positions(n), self.splits_by_normal())
        else {
            return (None, false);
        };
        let camera = self.camera;
        let t = (camera.fov_y / 2.0).tan();
        let (w, h) = (f64::from(at.width), f64::from(at.height));
        let step = 2.0 * t / h;
        // gl_FragCoord of the pixel: rows count up from the bottom.
        let (fx, fy) = (at.x as f64 + 0.5, (at.height - 1 - at.y) as f64 + 0.5);
        let centre = [
            (2.0 * fx / w - 1.0) * t * w / h,
            (2.0 * fy / h - 1.0) * t,
            -1.0,
        ];
        let ray = |i: usize| {
            let o = pattern[i];
            [
                centre[0] + step * o[0] / 16.0,
                centre[1] + step * o[1] / 16.0,
                -1.0,
            ]
        };
        let inv_w: Vec<f64> = px
            .depth
            .iter()
            .map(|&d| camera.inverse_distance(d))
            .collect();
        let normal = |i: usize| encoding.decode(px.attachments[k][i]);
        let (n_a, n_b) = (normal(a), normal(b));
        // A plane's inverse distance along ray v is k * dot(n, v).
        let k_a = inv_w[a] / dot(n_a, ray(a));
        let k_b = inv_w[b] / dot(n_b, ray(b));
        let (mut residual, mut g_a, mut g_b) = (0.0, 0.0, 0.0);
        for s in 0..n {
            let (on_a, on_b) = (k_a * dot(n_a, ray(s)), k_b * dot(n_b, ray(s)));
            if in_a[s] {
                residual += (on_a - inv_w[s]).abs();
                g_a += inv_w[s] - on_b;
            }
            if in_b[s] {
                residual += (on_b - inv_w[s]).abs();
                g_b += on_a - inv_w[s];
            }
        }
        let g_c = k_a * dot(n_a, centre) - k_b * dot(n_b, centre);
        let scale = inv_w[a].abs().max(inv_w[b].abs());
        // Well above f32's rounding of the inverse distances (crease.glsl's
        // noise), so a decided side is f32's too.
        let noise = 1e-5 * scale;
        let crease = (g_a > noise && g_b < -noise) || (g_a < -noise && g_b > noise);
        let clear = g_c.abs() > residual + noise;
        let near = |x: f64| x.abs() <= 4e-6 * scale;
        let ambiguous = near(g_c.abs() - residual - noise)
            || (clear && (near(g_a.abs() - noise) || near(g_b.abs() - noise)));
        let side = (crease && clear).then_some((g_c > 0.0) == (g_a > 0.0));
        (side, ambiguous)
    }
}
