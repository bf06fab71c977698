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

/// Whether `m` (column-major) is a GL perspective projection alone: last
/// row `(0, 0, −1, 0)`, no shear or translation in x and y (an off-centre
/// frustum's `m[8]`, `m[9]` allowed), positive scales and a depth term
/// with a near plane (`m[14]` not 0; `m[10]` is 0 for a reversed, infinite
/// far plane).
pub(crate) fn is_perspective_projection(m: &[f32; 16]) -> bool {
    m.iter().all(|v| v.is_finite())
        && [1, 2, 3, 4, 6, 7, 12, 13, 15].iter().all(|&k| m[k] == 0.0)
        && m[11] == -1.0
        && m[0] > 0.0
        && m[5] > 0.0
        && m[14] != 0.0
}

/// Whether `m` (column-major) is a rigid view: a rotation (orthonormal
/// rows, within float rounding) and a translation, last row `(0, 0, 0, 1)`.
pub(crate) fn is_rigid_view(m: &[f32; 16]) -> bool {
    if !m.iter().all(|v| v.is_finite()) || [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        return false;
    }
    let row = |r: usize| [m[r], m[4 + r], m[8 + r]];
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    (0..3).all(|i| {
        (0..3).all(|j| {
            let expected = if i == j { 1.0 } else { 0.0 };
            (dot(row(i), row(j)) - expected).abs() < 1e-3
        })
    })
}

/// The 16 floats at `at` in `bytes` (native order), where they fit.
pub(crate) fn matrix_at(bytes: &[u8], at: usize) -> Option<[f32; 16]> {
    let chunk = bytes.get(at..at + 64)?;
    let mut m = [0f32; 16];
    for (k, v) in m.iter_mut().enumerate() {
        *v = f32::from_ne_bytes([
            chunk[4 * k],
            chunk[4 * k + 1],
            chunk[4 * k + 2],
            chunk[4 * k + 3],
        ]);
    }
    Some(m)
}

/// What a `mat4` written into a uniform buffer is, for finding a camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BlockMatrix {
    /// A perspective projection alone.
    Projection,
    /// A rigid view.
    View,
}

/// Every `mat4` place (std140: a multiple of 16 bytes into the buffer)
/// that bytes written at byte `base` of a uniform buffer cover whole,
/// with what they put there (`None`: neither a projection nor a view).
pub(crate) fn block_matrices(bytes: &[u8], base: usize) -> Vec<(u32, Option<BlockMatrix>)> {
    let first = base.div_ceil(16) * 16;
    let end = base + bytes.len();
    (first..end.saturating_sub(63))
        .step_by(16)
        .map(|o| {
            let kind = matrix_at(bytes, o - base).and_then(|m| {
                if is_perspective_projection(&m) {
                    Some(BlockMatrix::Projection)
                } else if is_rigid_view(&m) {
                    Some(BlockMatrix::View)
                } else {
                    None
                }
            });
            (o as u32, kind)
        })
        .collect()
}

/// The camera in a uniform buffer whose matrices are `kinds` (byte offset
/// → kind): the offset of its one perspective projection, and of a rigid
/// view in the 64 bytes after or before it, if one is there. `None` where
/// no projection is there, or more than one (a shadow or reflection
/// camera beside the view's: not told apart here).
pub(crate) fn block_camera(
    kinds: &std::collections::BTreeMap<u32, BlockMatrix>,
) -> Option<(u32, Option<u32>)> {
    let projections: Vec<u32> = kinds
        .iter()
        .filter(|(_, k)| **k == BlockMatrix::Projection)
        .map(|(o, _)| *o)
        .collect();
    let [projection] = projections.as_slice() else {
        return None;
    };
    let view_at = |o: u32| kinds.get(&o) == Some(&BlockMatrix::View);
    let view = Some(projection + 64)
        .filter(|&o| view_at(o))
        .or_else(|| projection.checked_sub(64).filter(|&o| view_at(o)));
    Some((*projection, view))
}

#[cfg(test)]
mod tests {
    use super::{
        block_camera, block_matrices, is_perspective_projection, is_view_projection_product,
        split_view_projection,
    };

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

    fn bytes(matrices: &[[f32; 16]]) -> Vec<u8> {
        matrices
            .iter()
            .flat_map(|m| m.iter().flat_map(|v| v.to_ne_bytes()))
            .collect()
    }

    /// The camera of a buffer written `writes` (bytes, at byte), in order.
    fn camera_of(writes: &[(Vec<u8>, usize)]) -> Option<(u32, Option<u32>)> {
        let mut kinds = std::collections::BTreeMap::new();
        for (bytes, at) in writes {
            for (o, kind) in block_matrices(bytes, *at) {
                match kind {
                    Some(k) => kinds.insert(o, k),
                    None => kinds.remove(&o),
                };
            }
        }
        block_camera(&kinds)
    }

    #[test]
    fn a_camera_block_is_found_by_its_matrices() {
        let p = perspective(0.8, 1.6, 0.1, 100.0);
        let v = look_at([2.0, 3.5, -4.0], [0.3, -0.2, 0.9]);
        assert!(is_perspective_projection(&p));
        assert!(!is_perspective_projection(&multiply(&p, &v)));
        // projection, then view, in one write
        assert_eq!(camera_of(&[(bytes(&[p, v]), 0)]), Some((0, Some(64))));
        // in two writes (the C engine's block)
        assert_eq!(
            camera_of(&[(bytes(&[p]), 0), (bytes(&[v]), 64)]),
            Some((0, Some(64)))
        );
        // view, then projection, written at byte 128 of the buffer
        assert_eq!(camera_of(&[(bytes(&[v, p]), 128)]), Some((192, Some(128))));
        // a projection alone, after a vec4 (16 bytes) of something else
        let mut alone = vec![0u8; 16];
        alone.extend(bytes(&[p]));
        assert_eq!(camera_of(&[(alone, 0)]), Some((16, None)));
        // two projections (a shadow camera's beside the view's): not told
        let q = perspective(1.2, 1.0, 0.5, 40.0);
        assert_eq!(camera_of(&[(bytes(&[p, v, q]), 0)]), None);
        // a projection overwritten by something else is gone
        assert_eq!(
            camera_of(&[(bytes(&[p]), 0), (bytes(&[multiply(&p, &v)]), 0)]),
            None
        );
        // misaligned: no mat4 place
        let mut shifted = vec![0u8; 4];
        shifted.extend(bytes(&[p]));
        assert_eq!(camera_of(&[(shifted, 0)]), None);
    }
}
