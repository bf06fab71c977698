//! Mesh primitives: one primitive's positions, indices (strips and fans
//! turned into triangle lists), normals and texture coordinates, sanitised
//! into drawable geometry, with a warning for each thing repaired or left
//! out.

use gltf::mesh::Mode;

use super::super::Warnings;
use super::super::geometry::{self, Geometry, RawMesh, Report};
use super::accessors::{read_indices, read_vectors};
use super::materials::uv_set;

/// What became of a primitive that was not structurally broken.
pub(super) enum Built {
    /// Geometry with at least one triangle.
    Drawable(Geometry),
    /// Nothing to draw; the line says why.
    Skipped(String),
}

/// Reads and sanitises one primitive. `Err` for a structurally broken
/// POSITION or index accessor; `Built::Skipped` when there is nothing to
/// draw. `label` names the primitive in messages.
pub(super) fn build_primitive(
    prim: &gltf::Primitive,
    label: &str,
    buffers: &[Vec<u8>],
    warnings: &mut Warnings,
) -> Result<Built, String> {
    let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
        return Ok(Built::Skipped(format!(
            "{label}: no POSITION attribute; skipped"
        )));
    };
    let positions: Vec<[f32; 3]> =
        read_vectors::<3>(&pos_acc, buffers).map_err(|e| format!("{label}: POSITION {e}"))?;
    let n = positions.len();
    let raw_indices = match prim.indices() {
        Some(acc) => read_indices(&acc, buffers).map_err(|e| format!("{label}: indices {e}"))?,
        None => (0..n as u32).collect(),
    };
    let indices = match triangulate(prim.mode(), raw_indices) {
        Ok(t) => t,
        Err(mode) => {
            return Ok(Built::Skipped(format!(
                "{label}: mode {mode} skipped (only triangles are drawn)"
            )));
        }
    };

    let normals = match prim.get(&gltf::Semantic::Normals) {
        None => None,
        Some(acc) => match read_vectors::<3>(&acc, buffers) {
            Ok(v) if v.len() == n => Some(v),
            Ok(v) => {
                warnings.push(format!(
                    "{label}: {} normals for {n} positions; normals generated instead",
                    v.len()
                ));
                None
            }
            Err(e) => {
                warnings.push(format!("{label}: NORMAL {e}; normals generated instead"));
                None
            }
        },
    };

    let uv_set = uv_set(&prim.material(), warnings);
    let uvs = match prim.get(&gltf::Semantic::TexCoords(uv_set)) {
        None => None,
        Some(acc) => match read_vectors::<2>(&acc, buffers) {
            Ok(v) if v.len() == n => Some(v),
            Ok(v) => {
                warnings.push(format!(
                    "{label}: {} TEXCOORD_{uv_set} values for {n} positions; coordinates ignored",
                    v.len()
                ));
                None
            }
            Err(e) => {
                warnings.push(format!(
                    "{label}: TEXCOORD_{uv_set} {e}; coordinates ignored"
                ));
                None
            }
        },
    };

    let (g, report) = geometry::sanitize(RawMesh {
        positions,
        normals,
        uvs,
        indices,
    });
    warn_repairs(label, &report, n, warnings);
    if g.indices.is_empty() {
        let why = if report.triangles_in == 0 {
            "it has no complete triangle".to_string()
        } else {
            let mut causes = Vec::new();
            if report.out_of_range > 0 {
                causes.push(format!("{} with indices out of range", report.out_of_range));
            }
            if report.non_finite > 0 {
                causes.push(format!(
                    "{} touching NaN/infinite positions or normals",
                    report.non_finite
                ));
            }
            format!(
                "all {} triangles dropped ({})",
                report.triangles_in,
                causes.join(", ")
            )
        };
        return Ok(Built::Skipped(format!("{label}: nothing drawable: {why}")));
    }
    Ok(Built::Drawable(g))
}

/// One warning for each kind of repair the sanitiser made.
fn warn_repairs(label: &str, r: &Report, vertices: usize, warnings: &mut Warnings) {
    let total = r.triangles_in;
    if r.ragged_indices > 0 {
        warnings.push(format!(
            "{label}: {} trailing indices do not make a whole triangle; ignored",
            r.ragged_indices
        ));
    }
    if r.out_of_range > 0 {
        warnings.push(format!(
            "{label}: dropped {} of {total} triangles with indices out of range (vertex count {vertices})",
            r.out_of_range
        ));
    }
    if r.non_finite > 0 {
        warnings.push(format!(
            "{label}: dropped {} of {total} triangles touching NaN/infinite positions or normals",
            r.non_finite
        ));
    }
    if r.recomputed_normals > 0 {
        warnings.push(format!(
            "{label}: recomputed {} zero-length normals from the surrounding faces",
            r.recomputed_normals
        ));
    }
    if r.renormalised > 0 {
        warnings.push(format!(
            "{label}: rescaled {} normals that were not unit length",
            r.renormalised
        ));
    }
    if r.bad_uvs > 0 {
        warnings.push(format!(
            "{label}: set {} NaN/infinite texture coordinates to zero",
            r.bad_uvs
        ));
    }
}

/// Converts a primitive's index list to a triangle list, or names the mode
/// when it has no triangles.
fn triangulate(mode: Mode, idx: Vec<u32>) -> Result<Vec<u32>, &'static str> {
    match mode {
        Mode::Triangles => Ok(idx),
        Mode::TriangleStrip => {
            let mut out = Vec::with_capacity(idx.len().saturating_sub(2) * 3);
            for (i, w) in idx.windows(3).enumerate() {
                // Keep every triangle counter-clockwise: odd ones swap.
                if i % 2 == 0 {
                    out.extend_from_slice(&[w[0], w[1], w[2]]);
                } else {
                    out.extend_from_slice(&[w[1], w[0], w[2]]);
                }
            }
            Ok(out)
        }
        Mode::TriangleFan => {
            let mut out = Vec::with_capacity(idx.len().saturating_sub(2) * 3);
            if let Some((&first, rest)) = idx.split_first() {
                for w in rest.windows(2) {
                    out.extend_from_slice(&[first, w[0], w[1]]);
                }
            }
            Ok(out)
        }
        Mode::Points => Err("POINTS"),
        Mode::Lines => Err("LINES"),
        Mode::LineLoop => Err("LINE_LOOP"),
        Mode::LineStrip => Err("LINE_STRIP"),
    }
}
