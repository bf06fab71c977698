//! Accessors: the numbers an accessor holds, read from its buffer view with
//! every offset, stride and count checked, sparse substitution and
//! normalisation applied, as float vectors or as indices.
//!
//! Not gltf::mesh::Reader and gltf::accessor::Iter (gltf 1.4.1): `Iter::new`
//! computes `offset + stride * (count - 1) + size` unchecked (a count of 0
//! underflows, a huge one overflows), checks a stride smaller than the
//! element with `debug_assert!` only and then panics reading each element
//! from a slice shorter than it; `read_positions` and `read_normals` read `[f32; 3]` whatever the
//! component type (quantised or normalised data come out as garbage);
//! `read_indices` and `read_tex_coords` hit `unreachable!()` on component
//! types they do not expect, which validation lets through; and a sparse
//! index past the count is dropped silently.

use gltf::accessor::{DataType, Dimensions};

use super::buffers::view_bytes;

/// Most elements an accessor without a buffer view may declare (its zeros
/// are allocated).
const MAX_ZERO_ELEMENTS: usize = 1 << 22;

// The crate spells these only as GL enums (`DataType::as_gl_enum`) and,
// for dimensions, inside its serde impl: the names messages use are here.
fn component_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

fn dimensions_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn read_component(b: &[u8], t: DataType) -> Option<f64> {
    Some(match t {
        DataType::I8 => f64::from(i8::from_le_bytes([*b.first()?])),
        DataType::U8 => f64::from(*b.first()?),
        DataType::I16 => f64::from(i16::from_le_bytes(b.get(..2)?.try_into().ok()?)),
        DataType::U16 => f64::from(u16::from_le_bytes(b.get(..2)?.try_into().ok()?)),
        DataType::U32 => f64::from(u32::from_le_bytes(b.get(..4)?.try_into().ok()?)),
        DataType::F32 => f64::from(f32::from_le_bytes(b.get(..4)?.try_into().ok()?)),
    })
}

/// glTF's normalised-integer decoding.
fn normalize(v: f64, t: DataType) -> f64 {
    match t {
        DataType::I8 => (v / 127.0).max(-1.0),
        DataType::U8 => v / 255.0,
        DataType::I16 => (v / 32767.0).max(-1.0),
        DataType::U16 => v / 65535.0,
        DataType::U32 => v / 4_294_967_295.0,
        DataType::F32 => v,
    }
}

/// Reads `count` elements of `dims` components at `offset` with `stride`.
fn read_elements(
    data: &[u8],
    offset: usize,
    stride: usize,
    count: usize,
    dims: usize,
    t: DataType,
    out: &mut Vec<f64>,
) -> Result<(), String> {
    let cs = t.size();
    let elem = cs * dims;
    if count == 0 {
        return Ok(());
    }
    let need = stride
        .checked_mul(count - 1)
        .and_then(|s| s.checked_add(offset))
        .and_then(|s| s.checked_add(elem))
        .ok_or("its size overflows")?;
    if need > data.len() {
        return Err(format!(
            "reads {need} bytes from a buffer view of {} bytes",
            data.len()
        ));
    }
    out.reserve(count * dims);
    for i in 0..count {
        let at = offset + i * stride;
        for k in 0..dims {
            let p = at + k * cs;
            let v = data
                .get(p..p + cs)
                .and_then(|b| read_component(b, t))
                .ok_or("reads outside its buffer view")?;
            out.push(v);
        }
    }
    Ok(())
}

/// Reads an accessor as `count * dims` numbers (sparse substitution and
/// normalisation applied).
fn read_accessor(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<f64>, String> {
    let fail = |e: String| format!("accessor {}: {e}", acc.index());
    let t = acc.data_type();
    let dims = acc.dimensions().multiplicity();
    let count = acc.count();
    let elem = acc.size();
    let mut out = Vec::new();
    match acc.view() {
        Some(view) => {
            let data = view_bytes(&view, buffers).map_err(fail)?;
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(fail(format!(
                    "byteStride {stride} is smaller than its {elem}-byte elements"
                )));
            }
            read_elements(data, acc.offset(), stride, count, dims, t, &mut out).map_err(fail)?;
        }
        None => {
            if count > MAX_ZERO_ELEMENTS {
                return Err(fail(format!(
                    "declares {count} elements without any buffer view"
                )));
            }
            out = vec![0.0; count * dims];
        }
    }

    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        let indices = sparse.indices();
        let it = match indices.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let mut targets = Vec::new();
        let data = view_bytes(&indices.view(), buffers).map_err(fail)?;
        read_elements(
            data,
            indices.offset(),
            indices.index_type().size(),
            n,
            1,
            it,
            &mut targets,
        )
        .map_err(|e| fail(format!("sparse indices {e}")))?;
        let values = sparse.values();
        let mut subst = Vec::new();
        let data = view_bytes(&values.view(), buffers).map_err(fail)?;
        read_elements(data, values.offset(), elem, n, dims, t, &mut subst)
            .map_err(|e| fail(format!("sparse values {e}")))?;
        for (j, &target) in targets.iter().enumerate() {
            let target = target as usize;
            if target >= count {
                return Err(fail(format!(
                    "sparse index {target} is out of range (count {count})"
                )));
            }
            for k in 0..dims {
                if let (Some(dst), Some(src)) =
                    (out.get_mut(target * dims + k), subst.get(j * dims + k))
                {
                    *dst = *src;
                }
            }
        }
    }

    if acc.normalized() {
        for v in &mut out {
            *v = normalize(*v, t);
        }
    }
    Ok(out)
}

/// Reads a float vector attribute of `N` components.
pub(super) fn read_vectors<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
) -> Result<Vec<[f32; N]>, String> {
    if acc.dimensions().multiplicity() != N {
        return Err(format!(
            "accessor {} has type {}, expected a {N}-component vector",
            acc.index(),
            dimensions_name(acc.dimensions())
        ));
    }
    let raw = read_accessor(acc, buffers)?;
    Ok(raw
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|k| c.get(k).copied().unwrap_or(0.0) as f32))
        .collect())
}

/// Reads an index accessor, which must hold unsigned integer scalars.
pub(super) fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let t = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(t, DataType::U8 | DataType::U16 | DataType::U32)
        || acc.normalized()
    {
        return Err(format!(
            "accessor {} ({} {}) cannot hold indices: they must be unsigned integer scalars",
            acc.index(),
            dimensions_name(acc.dimensions()),
            component_name(t)
        ));
    }
    Ok(read_accessor(acc, buffers)?
        .into_iter()
        .map(|v| v as u32)
        .collect())
}
