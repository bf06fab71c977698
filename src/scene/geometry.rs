//! Triangle-list sanitising shared by the loaders: drops triangles that cannot
//! be drawn, generates or repairs normals, and compacts the vertex arrays.

use glam::Vec3;

/// Vertex data as read from a file, before any checks.
#[derive(Debug, Default)]
pub(crate) struct RawMesh {
    pub positions: Vec<[f32; 3]>,
    /// Present only when the file has normals for every vertex.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Present only when the file has coordinates for every vertex.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// A triangle list that may hold out-of-range indices and a ragged end.
    pub indices: Vec<u32>,
}

/// Drawable vertex data: every array as long as `positions`, all finite,
/// every index in range, unit normals.
#[derive(Debug, Clone, Default)]
pub(crate) struct Geometry {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
}

/// What [`sanitize`] did, for the warnings.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Report {
    /// Triangles in the input (complete ones).
    pub triangles_in: usize,
    /// Indices left over after the last complete triangle.
    pub ragged_indices: usize,
    /// Triangles dropped for an index ≥ the vertex count.
    pub out_of_range: usize,
    /// Triangles dropped for a NaN/infinite position or normal.
    pub non_finite: usize,
    /// Whether flat normals were generated (the input had none).
    pub flat_normals: bool,
    /// Zero-length normals replaced by the average of the adjacent faces.
    pub recomputed_normals: usize,
    /// Normals whose length was off by more than 1 % and were rescaled.
    pub renormalised: usize,
    /// NaN/infinite texture coordinates set to zero.
    pub bad_uvs: usize,
}

fn finite3(v: &[f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

/// `v` scaled to unit length, or `fallback` when it has no direction (zero
/// or not finite). Scaled by its largest component first: glam's
/// `normalize_or` squares the components, which underflows into subnormals
/// for a tiny triangle's cross product (a "unit" normal of length 1.013
/// came out) and overflows for a huge one's (the fallback came out).
pub(crate) fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let largest = v.abs().max_element();
    if !(largest.is_finite() && largest > 0.0) {
        return fallback;
    }
    (v / largest).normalize_or(fallback)
}

/// The (unnormalised, area-weighted) normal of a counter-clockwise triangle.
pub(crate) fn face_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}

/// Makes `raw` drawable, see [`Geometry`] and [`Report`].
pub(crate) fn sanitize(raw: RawMesh) -> (Geometry, Report) {
    let RawMesh {
        positions,
        normals,
        uvs,
        indices,
    } = raw;
    let n = positions.len();
    let mut report = Report {
        triangles_in: indices.len() / 3,
        ragged_indices: indices.len() % 3,
        ..Report::default()
    };

    // Drop what cannot be drawn.
    let mut kept = Vec::with_capacity(indices.len() - report.ragged_indices);
    for tri in indices.chunks_exact(3) {
        let verts = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if verts.iter().any(|&i| i >= n) {
            report.out_of_range += 1;
            continue;
        }
        let finite = verts.iter().all(|&i| {
            positions.get(i).is_some_and(finite3)
                && normals
                    .as_ref()
                    .is_none_or(|ns| ns.get(i).is_some_and(finite3))
        });
        if !finite {
            report.non_finite += 1;
            continue;
        }
        kept.extend_from_slice(tri);
    }

    // Keep only the vertices the remaining triangles use, in first-use order
    // when any is unused (dropped with a triangle, named only by ragged
    // trailing indices or never indexed), so no NaN vertex survives
    // unreferenced and the bounds hold only what is drawn.
    let mut used = vec![false; n];
    for &i in &kept {
        if let Some(u) = used.get_mut(i as usize) {
            *u = true;
        }
    }
    let all_used = used.iter().all(|&u| u);
    let (positions, normals, uvs, kept) = if !all_used {
        compact(&positions, normals.as_deref(), uvs.as_deref(), &kept)
    } else {
        (positions, normals, uvs, kept)
    };

    let mut uvs = uvs.unwrap_or_else(|| vec![[0.0; 2]; positions.len()]);
    for uv in &mut uvs {
        if !(uv[0].is_finite() && uv[1].is_finite()) {
            *uv = [0.0; 2];
            report.bad_uvs += 1;
        }
    }

    let geometry = match normals {
        Some(mut normals) => {
            let (recomputed, renormalised) = repair_normals(&positions, &mut normals, &kept);
            report.recomputed_normals = recomputed;
            report.renormalised = renormalised;
            Geometry {
                positions,
                normals,
                uvs,
                indices: kept,
            }
        }
        None => {
            report.flat_normals = true;
            flat_shaded(&positions, &uvs, &kept)
        }
    };
    (geometry, report)
}

type Compacted = (
    Vec<[f32; 3]>,
    Option<Vec<[f32; 3]>>,
    Option<Vec<[f32; 2]>>,
    Vec<u32>,
);

/// Keeps only referenced vertices. `indices` must all be in range.
fn compact(
    positions: &[[f32; 3]],
    normals: Option<&[[f32; 3]]>,
    uvs: Option<&[[f32; 2]]>,
    indices: &[u32],
) -> Compacted {
    let mut remap = vec![u32::MAX; positions.len()];
    let mut new_positions = Vec::new();
    let mut new_normals = normals.map(|_| Vec::new());
    let mut new_uvs = uvs.map(|_| Vec::new());
    let mut new_indices = Vec::with_capacity(indices.len());
    for &i in indices {
        let Some(slot) = remap.get_mut(i as usize) else {
            continue;
        };
        if *slot == u32::MAX {
            *slot = new_positions.len() as u32;
            let iu = i as usize;
            new_positions.push(positions.get(iu).copied().unwrap_or_default());
            if let (Some(out), Some(src)) = (new_normals.as_mut(), normals) {
                out.push(src.get(iu).copied().unwrap_or_default());
            }
            if let (Some(out), Some(src)) = (new_uvs.as_mut(), uvs) {
                out.push(src.get(iu).copied().unwrap_or_default());
            }
        }
        new_indices.push(*slot);
    }
    (new_positions, new_normals, new_uvs, new_indices)
}

/// Unindexes the mesh so each triangle gets its own vertices carrying the
/// face normal (glTF's rule when a primitive has no normals).
pub(crate) fn flat_shaded(positions: &[[f32; 3]], uvs: &[[f32; 2]], indices: &[u32]) -> Geometry {
    let mut g = Geometry {
        positions: Vec::with_capacity(indices.len()),
        normals: Vec::with_capacity(indices.len()),
        uvs: Vec::with_capacity(indices.len()),
        indices: Vec::with_capacity(indices.len()),
    };
    for tri in indices.chunks_exact(3) {
        let p = |k: usize| {
            let i = tri[k] as usize;
            Vec3::from(positions.get(i).copied().unwrap_or_default())
        };
        let normal = unit_or(face_normal(p(0), p(1), p(2)), Vec3::Z);
        for &i in tri {
            g.indices.push(g.positions.len() as u32);
            g.positions
                .push(positions.get(i as usize).copied().unwrap_or_default());
            g.normals.push(normal.to_array());
            g.uvs.push(uvs.get(i as usize).copied().unwrap_or_default());
        }
    }
    g
}

/// Replaces zero-length normals with the area-weighted average of the faces
/// around the vertex (+z when that too is zero) and rescales the others to
/// unit length. Returns (replaced, rescaled by more than 1 %).
fn repair_normals(
    positions: &[[f32; 3]],
    normals: &mut [[f32; 3]],
    indices: &[u32],
) -> (usize, usize) {
    let bad: Vec<bool> = normals
        .iter()
        .map(|n| {
            let l = Vec3::from(*n).length();
            !(l > 1e-6 && l.is_finite())
        })
        .collect();
    let bad_count = bad.iter().filter(|&&b| b).count();

    if bad_count > 0 {
        let mut acc = vec![Vec3::ZERO; normals.len()];
        for tri in indices.chunks_exact(3) {
            let i = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            if !i.iter().any(|&k| bad.get(k).copied().unwrap_or(false)) {
                continue;
            }
            let p = |k: usize| Vec3::from(positions.get(k).copied().unwrap_or_default());
            let fnorm = face_normal(p(i[0]), p(i[1]), p(i[2]));
            if !fnorm.is_finite() {
                continue;
            }
            for k in i {
                if let Some(a) = acc.get_mut(k) {
                    *a += fnorm;
                }
            }
        }
        for ((n, &is_bad), a) in normals.iter_mut().zip(&bad).zip(&acc) {
            if is_bad {
                *n = unit_or(*a, Vec3::Z).to_array();
            }
        }
    }

    let mut rescaled = 0;
    for (n, &is_bad) in normals.iter_mut().zip(&bad) {
        if is_bad {
            continue;
        }
        let v = Vec3::from(*n);
        let l = v.length();
        if (l - 1.0).abs() > 0.01 {
            rescaled += 1;
        }
        *n = unit_or(v, Vec3::Z).to_array();
    }
    (bad_count, rescaled)
}

/// Swaps the second and third index of every triangle (mirrors the winding).
pub(crate) fn flip_winding(indices: &mut [u32]) {
    for tri in indices.chunks_exact_mut(3) {
        tri.swap(1, 2);
    }
}
