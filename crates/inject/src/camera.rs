//! A camera given as one view-projection matrix (`P · V`, as engines that
//! upload `viewProjection` keep it), taken apart into what the resolve
//! needs: the projection's depth terms and field of view, and the view's
//! third row (view-space z of a world position).
//!
//! For OpenGL's perspective `P` (rows `[sx 0 a 0]`, `[0 f b 0]`,
//! `[0 0 p22 p23]`, `[0 0 −1 0]`) and a rigid view `V` (rotation and
//! translation), the rows `r` of `P · V` are `r3 = −v2`, `r2 = p22 v2 +
//! p23 e3`, `r1 = f v1 + b v2`, `r0 = sx v0 + a v2`. So `v2 = −r3`, `p22 =
//! −(r2 · r3) / (r3 · r3)` over xyz, `p23 = r2.w + p22 r3.w`, and `f`,
//! `sx` are the lengths of `r1`, `r0` (xyz) once their `v2` part is taken
//! out. A view with scale is not rigid: the result is then off by it.

/// The projection (column-major, a GL perspective matrix with the depth
/// terms, field of view and aspect of `vp`'s) and a view matrix whose third
/// row is `vp`'s view's (its other rows identity's), or `None` where `vp`
/// is not a perspective view-projection (its last row has no xyz part).
pub(crate) fn split_view_projection(vp: &[f32; 16]) -> Option<([f32; 16], [f32; 16])> {
    let row = |i: usize| [vp[i], vp[4 + i], vp[8 + i], vp[12 + i]].map(f64::from);
    let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
    let dot3 = |a: &[f64; 4], b: &[f64; 4]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let n = dot3(&r3, &r3);
    if !(n.is_finite() && n > 0.0) {
        return None;
    }
    let p22 = -dot3(&r2, &r3) / n;
    let p23 = r2[3] + p22 * r3[3];
    // The part of a row along v2 (= −r3 / |r3|) taken out, its length left.
    let across = |r: &[f64; 4]| {
        let along = -dot3(r, &r3) / n;
        let rest = [
            r[0] + along * r3[0],
            r[1] + along * r3[1],
            r[2] + along * r3[2],
        ];
        (rest.iter().map(|v| v * v).sum::<f64>() / n).sqrt()
    };
    let (sx, f) = (across(&r0), across(&r1));
    if !(p22.is_finite() && p23.is_finite() && f > 0.0 && sx > 0.0) {
        return None;
    }
    let mut projection = [0f32; 16];
    projection[0] = sx as f32;
    projection[5] = f as f32;
    projection[10] = p22 as f32;
    projection[11] = -1.0;
    projection[14] = p23 as f32;
    let scale = n.sqrt();
    let mut view = [0f32; 16];
    view[0] = 1.0;
    view[5] = 1.0;
    view[15] = 1.0;
    view[2] = (-r3[0] / scale) as f32;
    view[6] = (-r3[1] / scale) as f32;
    view[10] = (-r3[2] / scale) as f32;
    view[14] = (-r3[3] / scale) as f32;
    Some((projection, view))
}

/// Whether `m` is a perspective projection times a view other than the
/// identity (a rotation or a translation in it): a view-projection
/// product, not a projection alone.
pub(crate) fn is_view_projection_product(m: &[f32; 16]) -> bool {
    let Some((_, view)) = split_view_projection(m) else {
        return false;
    };
    // A projection alone has the view's z row (0, 0, 1, 0).
    let z_row = [view[2], view[6], view[10], view[14]];
    let identity = [0.0, 0.0, 1.0, 0.0];
    z_row
        .iter()
        .zip(identity)
        .any(|(a, b)| (a - b).abs() > 1e-4)
}

#[cfg(test)]
mod tests {
    use super::{is_view_projection_product, split_view_projection};

    fn multiply(a: &[f32; 16], b: &[f32; 16]) -> [f32; 16] {
        let mut m = [0f32; 16];
        for c in 0..4 {
            for r in 0..4 {
                m[c * 4 + r] = (0..4).map(|k| a[k * 4 + r] * b[c * 4 + k]).sum();
            }
        }
        m
    }

    /// A view looking from `eye` at `target`, y up (column-major).
    fn look_at(eye: [f32; 3], target: [f32; 3]) -> [f32; 16] {
        let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let norm = |v: [f32; 3]| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            v.map(|x| x / l)
        };
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let f = norm(sub(target, eye));
        let s = norm(cross(f, [0.0, 1.0, 0.0]));
        let u = cross(s, f);
        [
            s[0],
            u[0],
            -f[0],
            0.0,
            s[1],
            u[1],
            -f[1],
            0.0,
            s[2],
            u[2],
            -f[2],
            0.0,
            -dot(s, eye),
            -dot(u, eye),
            dot(f, eye),
            1.0,
        ]
    }

    fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> [f32; 16] {
        let f = 1.0 / (fov_y / 2.0).tan();
        let mut m = [0f32; 16];
        m[0] = f / aspect;
        m[5] = f;
        m[10] = (far + near) / (near - far);
        m[11] = -1.0;
        m[14] = 2.0 * far * near / (near - far);
        m
    }

    #[test]
    fn a_view_projection_gives_back_the_projection_and_the_views_z_row() {
        for (eye, target, fov, near, far) in [
            ([0.0, 0.0, 3.0], [0.0, 0.0, 0.0], 0.8, 0.1, 100.0),
            ([2.0, 3.5, -4.0], [0.3, -0.2, 0.9], 1.2, 0.5, 40.0),
            ([-7.0, 1.0, 2.0], [1.0, 0.5, -3.0], 0.4, 0.05, 1000.0),
        ] {
            let p = perspective(fov, 1.6, near, far);
            let v = look_at(eye, target);
            let (q, w) = split_view_projection(&multiply(&p, &v)).expect("a perspective camera");
            for k in [0, 5, 10, 14] {
                assert!(
                    (q[k] - p[k]).abs() <= 1e-4 * p[k].abs().max(1.0),
                    "p[{k}]: {} vs {}",
                    q[k],
                    p[k]
                );
            }
            assert_eq!(q[11], -1.0);
            for k in [2, 6, 10, 14] {
                assert!(
                    (w[k] - v[k]).abs() <= 1e-4 * v[k].abs().max(1.0),
                    "v[{k}]: {} vs {}",
                    w[k],
                    v[k]
                );
            }
        }
    }

    #[test]
    fn a_product_is_told_from_a_projection_alone() {
        let p = perspective(0.8, 1.6, 0.1, 100.0);
        assert!(!is_view_projection_product(&p));
        let v = look_at([2.0, 3.5, -4.0], [0.3, -0.2, 0.9]);
        assert!(is_view_projection_product(&multiply(&p, &v)));
        let mut identity = [0f32; 16];
        identity[0] = 1.0;
        identity[5] = 1.0;
        identity[10] = 1.0;
        identity[15] = 1.0;
        assert!(!is_view_projection_product(&identity));
    }

    #[test]
    fn an_orthographic_or_empty_matrix_is_none() {
        let mut ortho = [0f32; 16];
        ortho[0] = 1.0;
        ortho[5] = 1.0;
        ortho[10] = -1.0;
        ortho[15] = 1.0;
        assert!(split_view_projection(&ortho).is_none());
        assert!(split_view_projection(&[0.0; 16]).is_none());
    }
}
