//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`).
//!
//! The `gltf` crate parses the JSON into its unvalidated document, which the
//! loader readies for the crate's validation. Everything that touches bytes
//! from the file (the GLB container, buffers, URIs, accessors, images) is read
//! here with explicit bounds checks, so a damaged file yields an error or a
//! warning, never a panic; each place says what the crate (1.4) does instead.
//!
//! What is honoured: the default scene's node tree with its transforms, mesh
//! primitives in the triangle modes (strips and fans converted), positions,
//! normals (generated flat when missing), one texture-coordinate set,
//! metallic-roughness materials with base colour and emissive textures,
//! `KHR_materials_emissive_strength`, alpha modes, double-sidedness, the first
//! perspective camera and `KHR_lights_punctual` lights. Skins, morph targets,
//! animations and other extensions are ignored (with a warning where it shows).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::geometry::{self, RawMesh, Report};
use super::{
    AlphaMode, Background, Camera, Light, LightKind, Material, Object, Scene, TextureData,
    Warnings, camera::look_at, default_lights,
};

/// Extensions whose content the loader uses.
const HONOURED_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// Deepest node nesting followed.
const MAX_NODE_DEPTH: usize = 256;

/// Most node visits (guards against a node DAG that multiplies instances).
const MAX_NODE_VISITS: usize = 200_000;

/// Most elements an accessor without a buffer view may declare (its zeros
/// are allocated).
const MAX_ZERO_ELEMENTS: usize = 1 << 22;

/// Most triangles instanced in total (node graphs can multiply a mesh).
const MAX_TRIANGLES: usize = 50_000_000;

/// Background for glTF scenes: a neutral dusk gradient, so silhouettes show.
const GLTF_BACKGROUND: Background = Background::Gradient {
    zenith: [0.05, 0.07, 0.12],
    horizon: [0.35, 0.38, 0.45],
};

/// Field of view used when the file has no usable camera.
const DEFAULT_FOV_Y: f32 = std::f32::consts::FRAC_PI_4;

/// Loads a glTF 2.0 file.
pub(crate) fn load(path: &Path) -> crate::Result<Scene> {
    load_inner(path).map_err(|reason| crate::Error::Scene {
        path: path.to_path_buf(),
        reason: one_line(&reason),
    })
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn load_inner(path: &Path) -> Result<Scene, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let is_glb_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    load_bytes(&bytes, Some(&base), is_glb_name, name)
}

/// Load a glTF or GLB held in memory. External files are refused: only
/// embedded (GLB or data-URI) buffers and images are read.
pub(crate) fn load_from_memory(bytes: &[u8], name: &str) -> crate::Result<Scene> {
    load_bytes(bytes, None, false, name.to_string()).map_err(|reason| crate::Error::Scene {
        path: name.into(),
        reason: one_line(&reason),
    })
}

fn load_bytes(
    bytes: &[u8],
    base: Option<&Path>,
    is_glb_name: bool,
    name: String,
) -> Result<Scene, String> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        let glb = parse_glb(bytes)?;
        (glb.json, glb.bin)
    } else if is_glb_name {
        let magic: String = bytes
            .iter()
            .take(4)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '.' })
            .collect();
        return Err(format!(
            "not a binary glTF file: the magic is '{magic}', expected 'glTF'"
        ));
    } else {
        (bytes, None)
    };

    let (document, notes) = parse_document(json)?;
    let mut warnings = Warnings::default();
    for note in notes {
        warnings.push(note);
    }
    check_extensions(&document, &mut warnings);
    let buffers = load_buffers(&document, base, bin)?;

    let mut loader = Loader {
        document: &document,
        base,
        buffers: &buffers,
        warnings,
        materials: Vec::new(),
        material_map: HashMap::new(),
        textures: Vec::new(),
        texture_map: HashMap::new(),
        geometry_cache: HashMap::new(),
        objects: Vec::new(),
        lights: Vec::new(),
        camera: None,
        first_skip: None,
        visits: 0,
        cycle_reported: false,
        triangles: 0,
        triangle_cap_reported: false,
    };
    loader.walk_scene()?;
    loader.finish(name)
}

// ---------------------------------------------------------------------------
// Container and JSON

struct Glb<'a> {
    json: &'a [u8],
    bin: Option<&'a [u8]>,
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a `.glb` into its JSON and BIN chunks.
// Not gltf::Glb::from_slice: it underflows on a declared length under 12 and refuses unknown chunk types, which the spec says to skip.
fn parse_glb(bytes: &[u8]) -> Result<Glb<'_>, String> {
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let (Some(version), Some(length)) = (le_u32(bytes, 4), le_u32(bytes, 8)) else {
        return Err(format!(
            "truncated .glb: {} bytes, shorter than the 12-byte header",
            bytes.len()
        ));
    };
    if version != 2 {
        return Err(format!(
            "unsupported .glb container version {version} (only glTF 2.0 is supported)"
        ));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!(
            "truncated .glb: the header declares {length} bytes but the file has {}",
            bytes.len()
        ));
    }
    let data = bytes.get(..length).unwrap_or(bytes);
    let mut offset = 12usize;
    let (mut json, mut bin) = (None, None);
    let mut chunk = 0;
    while offset < data.len() {
        let (Some(chunk_len), Some(kind)) = (le_u32(data, offset), le_u32(data, offset + 4)) else {
            return Err(format!(
                "truncated .glb: chunk {chunk} header at byte {offset} is cut off"
            ));
        };
        let start = offset + 8;
        let end = start.saturating_add(chunk_len as usize);
        let Some(payload) = data.get(start..end) else {
            return Err(format!(
                "truncated .glb: chunk {chunk} declares {chunk_len} bytes but only {} remain",
                data.len().saturating_sub(start)
            ));
        };
        match (chunk, kind) {
            (0, JSON) => json = Some(payload),
            (0, _) => return Err("malformed .glb: the first chunk is not JSON".into()),
            (_, BIN) if bin.is_none() => bin = Some(payload),
            _ => {} // unknown chunks are skipped, as the spec asks
        }
        offset = end;
        chunk += 1;
    }
    let json = json.ok_or("malformed .glb: no JSON chunk")?;
    Ok(Glb { json, bin })
}

/// Parses and validates the JSON; also returns notes for the warnings.
fn parse_document(json: &[u8]) -> Result<(gltf::Document, Vec<String>), String> {
    let first = json.iter().copied().find(|b| !b.is_ascii_whitespace());
    if first != Some(b'{') {
        return Err("not a glTF file: neither the binary magic 'glTF' nor a JSON object".into());
    }
    let mut root = match gltf::json::Root::from_slice(json) {
        Ok(root) => root,
        Err(e) => {
            // A glTF 1.0 file fails the 2.0 schema: say so rather than quote
            // the first mismatching field.
            let value = serde_json::from_slice::<serde_json::Value>(json).ok();
            let version = value
                .as_ref()
                .and_then(|v| v.get("asset"))
                .and_then(|a| a.get("version"))
                .and_then(|v| v.as_str());
            if let Some(v) = version.filter(|v| !v.starts_with('2')) {
                return Err(format!(
                    "glTF version {v} is not supported (only glTF 2.0 is)"
                ));
            }
            return Err(format!("invalid glTF JSON: {e}"));
        }
    };
    if !root.asset.version.starts_with('2') {
        return Err(format!(
            "glTF version {} is not supported (only glTF 2.0 is)",
            root.asset.version
        ));
    }
    let unsupported: Vec<&str> = root
        .extensions_required
        .iter()
        .filter(|e| !HONOURED_EXTENSIONS.contains(&e.as_str()))
        .map(String::as_str)
        .collect();
    if !unsupported.is_empty() {
        return Err(format!(
            "requires extension{} {}, which this loader does not support",
            if unsupported.len() > 1 { "s" } else { "" },
            unsupported.join(", ")
        ));
    }
    let mut notes = Vec::new();
    prepare_positions(&mut root, &mut notes)?;
    let document = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let mut msg = match errors.first() {
                Some((path, err)) => format!("invalid glTF: {path}: {err}"),
                None => "invalid glTF".to_string(),
            };
            if errors.len() > 1 {
                msg.push_str(&format!(" (and {} more problems)", errors.len() - 1));
            }
            msg
        }
        other => format!("invalid glTF: {other}"),
    })?;
    Ok((document, notes))
}

/// Readies primitives' POSITION accessors for validation, which indexes
/// them unchecked and insists on their `min`/`max`: a POSITION naming a
/// missing accessor is an error here, primitives without POSITION are left
/// out, and absent or malformed bounds are replaced (they are never used:
/// bounds are computed from the data).
fn prepare_positions(root: &mut gltf::json::Root, notes: &mut Vec<String>) -> Result<(), String> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    let position = Checked::Valid(Semantic::Positions);
    let accessor_count = root.accessors.len();
    let mut used = Vec::new();
    for (mi, mesh) in root.meshes.iter_mut().enumerate() {
        let before = mesh.primitives.len();
        mesh.primitives
            .retain(|p| p.attributes.contains_key(&position));
        let skipped = before - mesh.primitives.len();
        if skipped > 0 {
            notes.push(format!(
                "mesh {mi}: {skipped} primitive(s) without a POSITION attribute skipped"
            ));
        }
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            if let Some(index) = prim.attributes.get(&position) {
                let i = index.value();
                if i >= accessor_count {
                    return Err(format!(
                        "invalid glTF: meshes[{mi}].primitives[{pi}] POSITION names accessor {i}, but the file has {accessor_count}"
                    ));
                }
                used.push(i);
            }
        }
    }
    used.sort_unstable();
    used.dedup();
    let is_vec3 = |v: &Option<serde_json::Value>| {
        v.as_ref()
            .is_some_and(|v| serde_json::from_value::<[f32; 3]>(v.clone()).is_ok())
    };
    let mut filled = 0;
    for i in used {
        let Some(acc) = root.accessors.get_mut(i) else {
            continue;
        };
        if !(is_vec3(&acc.min) && is_vec3(&acc.max)) {
            acc.min = Some(serde_json::json!([0.0, 0.0, 0.0]));
            acc.max = Some(serde_json::json!([0.0, 0.0, 0.0]));
            filled += 1;
        }
    }
    if filled > 0 {
        notes.push(format!(
            "{filled} POSITION accessor(s) lack the min/max glTF requires; bounds are computed from the data"
        ));
    }
    Ok(())
}

fn check_extensions(doc: &gltf::Document, warnings: &mut Warnings) {
    let ignored: Vec<&str> = doc
        .extensions_used()
        .filter(|e| !HONOURED_EXTENSIONS.contains(e))
        .collect();
    if !ignored.is_empty() {
        warnings.push(format!("ignored extensions: {}", ignored.join(", ")));
    }
    if doc.skins().next().is_some() {
        warnings.push("skins are ignored: skinned meshes are drawn in their bind pose");
    }
}

// ---------------------------------------------------------------------------
// URIs and buffers

/// Where a URI's bytes come from.
enum UriSource {
    Bytes(Vec<u8>),
    File(PathBuf),
}

// Not the crate's importer: it panics on %-escapes that are not UTF-8, skips decoding file: paths and calls drive letters or a ':' in a path unsupported schemes.
fn resolve_uri(uri: &str, base: Option<&Path>) -> Result<UriSource, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(',') else {
            return Err("malformed data URI (no ',')".into());
        };
        let is_base64 = rest
            .split_once(',')
            .is_some_and(|(meta, _)| meta.ends_with(";base64"));
        return if is_base64 {
            decode_base64(payload).map(UriSource::Bytes)
        } else {
            Ok(UriSource::Bytes(percent_decode(payload)))
        };
    }
    let Some(base) = base else {
        return Err(format!(
            "external file '{}' cannot be read when loading from memory",
            display_uri(uri)
        ));
    };
    if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        let decoded = percent_decode(rest);
        return Ok(UriSource::File(PathBuf::from(
            String::from_utf8_lossy(&decoded).into_owned(),
        )));
    }
    // A scheme is letters/digits/+-. before the first ':' (and no '/' first).
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1 // not a Windows drive letter
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if let Some(scheme) = scheme {
        return Err(format!("unsupported URI scheme '{scheme}:'"));
    }
    let decoded = percent_decode(uri);
    Ok(UriSource::File(
        base.join(String::from_utf8_lossy(&decoded).into_owned()),
    ))
}

fn display_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        "embedded data URI".to_string()
    } else {
        format!("'{uri}'")
    }
}

/// `%XX` escapes decoded; a `%` without two hex digits stays as it is.
fn percent_decode(s: &str) -> Vec<u8> {
    percent_encoding::percent_decode_str(s).collect()
}

/// Standard or URL-safe base64, padding optional, whitespace ignored, and
/// nothing after the first `=` (lenient, as glTF writers in the wild are);
/// the gltf crate's importer takes strict base64 only.
fn decode_base64(s: &str) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const LENIENT: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new()
            .with_decode_padding_mode(DecodePaddingMode::RequireNone)
            .with_decode_allow_trailing_bits(true),
    );
    let payload = s.split('=').next().unwrap_or("");
    let standard: String = payload
        .chars()
        .filter(|c| !c.is_ascii_whitespace())
        .map(|c| match c {
            '-' => '+',
            '_' => '/',
            c => c,
        })
        .collect();
    LENIENT.decode(standard.as_bytes()).map_err(|e| match e {
        base64::DecodeError::InvalidByte(at, byte) => format!(
            "invalid base64 data: {:?} at character {at} of the payload",
            char::from(byte)
        ),
        other => format!("invalid base64 data: {other}"),
    })
}

// Not gltf::import_buffers: it zero-pads buffers to four bytes (a view overrunning by up to 3 then reads zeros) and gives the BIN chunk to one buffer only.
fn load_buffers(
    doc: &gltf::Document,
    base: Option<&Path>,
    bin: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let (data, what) = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let Some(bin) = bin else {
                    return Err(format!(
                        "buffer {i} refers to the .glb binary chunk, which is missing"
                    ));
                };
                (bin.to_vec(), "the .glb binary chunk".to_string())
            }
            gltf::buffer::Source::Uri(uri) => {
                match resolve_uri(uri, base).map_err(|e| format!("buffer {i}: {e}"))? {
                    UriSource::Bytes(b) => (b, display_uri(uri)),
                    UriSource::File(file) => match std::fs::read(&file) {
                        Ok(b) => (b, display_uri(uri)),
                        Err(e) => {
                            return Err(format!(
                                "missing buffer file {} (buffer {i}): {e}",
                                display_uri(uri)
                            ));
                        }
                    },
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} ({what}) has {} bytes, fewer than its declared byteLength {} (truncated?)",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

// ---------------------------------------------------------------------------
// Accessors

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

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

/// The bytes of a buffer view.
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer = view.buffer().index();
    let data = buffers
        .get(buffer)
        .ok_or_else(|| format!("buffer view {} names missing buffer {buffer}", view.index()))?;
    let start = view.offset();
    let end = start.saturating_add(view.length());
    data.get(start..end).ok_or_else(|| {
        format!(
            "buffer view {} (bytes {start}..{end}) lies outside buffer {buffer} ({} bytes)",
            view.index(),
            data.len()
        )
    })
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
    let cs = component_size(t);
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
    let elem = component_size(t) * dims;
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
            component_size(it),
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
fn read_vectors<const N: usize>(
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

fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
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

// ---------------------------------------------------------------------------
// The scene walk

struct Loader<'a> {
    document: &'a gltf::Document,
    base: Option<&'a Path>,
    buffers: &'a [Vec<u8>],
    warnings: Warnings,
    materials: Vec<Material>,
    /// glTF material index (None: the default material) → ours.
    material_map: HashMap<Option<usize>, usize>,
    textures: Vec<TextureData>,
    /// glTF image index → ours (None: it failed to load; warned once).
    texture_map: HashMap<usize, Option<usize>>,
    /// (mesh, primitive) → sanitised geometry (None: nothing drawable).
    geometry_cache: HashMap<(usize, usize), Option<geometry::Geometry>>,
    objects: Vec<Object>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    /// The first reason something was left out, for the "nothing to draw" error.
    first_skip: Option<String>,
    visits: usize,
    cycle_reported: bool,
    /// Triangles instanced so far.
    triangles: usize,
    triangle_cap_reported: bool,
}

/// The `{"deferred_msaa": {"antialias": bool}}` setting in an extras object.
fn antialias_extra(
    extras: &gltf::json::Extras,
    what: &str,
    warnings: &mut Warnings,
) -> Option<bool> {
    let raw = extras.as_ref()?;
    let value: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    let ours = value.get("deferred_msaa")?;
    match ours.get("antialias") {
        Some(serde_json::Value::Bool(b)) => Some(*b),
        Some(other) => {
            warnings.push(format!(
                "{what}: extras deferred_msaa.antialias is {other}, not a boolean; ignored"
            ));
            None
        }
        None => None,
    }
}

fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) if !n.is_empty() => format!("node '{n}'"),
        _ => format!("node {}", node.index()),
    }
}

fn mesh_label(mesh: &gltf::Mesh) -> String {
    match mesh.name() {
        Some(n) if !n.is_empty() => format!("mesh '{n}'"),
        _ => format!("mesh {}", mesh.index()),
    }
}

impl Loader<'_> {
    fn skip(&mut self, line: String) {
        if self.first_skip.is_none() {
            self.first_skip = Some(line.clone());
        }
        self.warnings.push(line);
    }

    fn walk_scene(&mut self) -> Result<(), String> {
        let doc = self.document;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for node in doc.nodes() {
                    for child in node.children() {
                        if let Some(flag) = is_child.get_mut(child.index()) {
                            *flag = true;
                        }
                    }
                }
                let roots: Vec<gltf::Node> = doc
                    .nodes()
                    .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                    .collect();
                if !roots.is_empty() {
                    self.warnings.push(format!(
                        "the file defines no scene; drawing its {} root node(s)",
                        roots.len()
                    ));
                }
                roots
            }
        };
        let mut on_path = vec![false; doc.nodes().len()];
        for root in roots {
            self.visit(&root, Mat4::IDENTITY, true, 0, &mut on_path)?;
        }
        Ok(())
    }

    fn visit(
        &mut self,
        node: &gltf::Node,
        parent: Mat4,
        inherited_aa: bool,
        depth: usize,
        on_path: &mut [bool],
    ) -> Result<(), String> {
        self.visits += 1;
        if self.visits == MAX_NODE_VISITS {
            self.warnings.push(format!(
                "the node graph expands to more than {MAX_NODE_VISITS} nodes; the rest is left out"
            ));
        }
        if self.visits >= MAX_NODE_VISITS {
            return Ok(());
        }
        if depth >= MAX_NODE_DEPTH {
            self.warnings.push(format!(
                "{}: nested deeper than {MAX_NODE_DEPTH} levels; its subtree is left out",
                node_label(node)
            ));
            return Ok(());
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !local.is_finite() || !world.is_finite() {
            self.skip(format!(
                "{}: non-finite transform; the node and its subtree are left out",
                node_label(node)
            ));
            return Ok(());
        }
        let label = node_label(node);
        let aa = antialias_extra(node.extras(), &label, &mut self.warnings).unwrap_or(inherited_aa);

        if let Some(mesh) = node.mesh() {
            self.add_mesh(node, &mesh, world, aa)?;
        }
        if let Some(cam) = node.camera().filter(|_| self.camera.is_none()) {
            self.camera = self.make_camera(&cam, world, &label);
        }
        if let Some(light) = node.light() {
            self.add_light(&light, world, &label);
        }

        if let Some(flag) = on_path.get_mut(node.index()) {
            *flag = true;
        }
        for child in node.children() {
            if on_path.get(child.index()).copied().unwrap_or(false) {
                if !self.cycle_reported {
                    self.cycle_reported = true;
                    self.warnings.push(format!(
                        "the node graph has a cycle ({} is its own ancestor); the repeated edge is ignored",
                        node_label(&child)
                    ));
                }
                continue;
            }
            self.visit(&child, world, aa, depth + 1, on_path)?;
        }
        if let Some(flag) = on_path.get_mut(node.index()) {
            *flag = false;
        }
        Ok(())
    }

    fn add_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
        node_aa: bool,
    ) -> Result<(), String> {
        let mlabel = mesh_label(mesh);
        let aa = antialias_extra(mesh.extras(), &mlabel, &mut self.warnings).unwrap_or(node_aa);
        let base_name = node
            .name()
            .filter(|n| !n.is_empty())
            .or(mesh.name().filter(|n| !n.is_empty()))
            .map(str::to_string)
            .unwrap_or_else(|| format!("node {}", node.index()));
        let primitive_count = mesh.primitives().len();
        let mirrored = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            let key = (mesh.index(), prim.index());
            if !self.geometry_cache.contains_key(&key) {
                let plabel = format!("{mlabel} primitive {}", prim.index());
                let g = self.build_primitive(&prim, &plabel)?;
                self.geometry_cache.insert(key, g);
            }
            let Some(Some(g)) = self.geometry_cache.get(&key) else {
                continue;
            };
            let tris = g.indices.len() / 3;
            if self.triangles + tris > MAX_TRIANGLES {
                if !self.triangle_cap_reported {
                    self.triangle_cap_reported = true;
                    self.warnings.push(format!(
                        "more than {MAX_TRIANGLES} triangles instanced; further instances are left out"
                    ));
                }
                continue;
            }
            self.triangles += tris;
            let mut g = g.clone();
            if mirrored {
                geometry::flip_winding(&mut g.indices);
            }
            let material = self.material(prim.material());
            let name = if primitive_count > 1 {
                format!("{base_name}/{}", prim.index())
            } else {
                base_name.clone()
            };
            self.objects.push(Object {
                name,
                positions: g.positions,
                normals: g.normals,
                uvs: g.uvs,
                indices: g.indices,
                material,
                transform: world,
                antialias: aa,
            });
        }
        Ok(())
    }

    /// Reads and sanitises one primitive. `Err` for a structurally broken
    /// POSITION or index accessor; `Ok(None)` when there is nothing to draw.
    fn build_primitive(
        &mut self,
        prim: &gltf::Primitive,
        label: &str,
    ) -> Result<Option<geometry::Geometry>, String> {
        let buffers = self.buffers;
        let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
            self.skip(format!("{label}: no POSITION attribute; skipped"));
            return Ok(None);
        };
        let positions: Vec<[f32; 3]> =
            read_vectors::<3>(&pos_acc, buffers).map_err(|e| format!("{label}: POSITION {e}"))?;
        let n = positions.len();
        let raw_indices = match prim.indices() {
            Some(acc) => {
                read_indices(&acc, buffers).map_err(|e| format!("{label}: indices {e}"))?
            }
            None => (0..n as u32).collect(),
        };
        let indices = match triangulate(prim.mode(), raw_indices) {
            Ok(t) => t,
            Err(mode) => {
                self.skip(format!(
                    "{label}: mode {mode} skipped (only triangles are drawn)"
                ));
                return Ok(None);
            }
        };

        let normals = match prim.get(&gltf::Semantic::Normals) {
            None => None,
            Some(acc) => match read_vectors::<3>(&acc, buffers) {
                Ok(v) if v.len() == n => Some(v),
                Ok(v) => {
                    self.warnings.push(format!(
                        "{label}: {} normals for {n} positions; normals generated instead",
                        v.len()
                    ));
                    None
                }
                Err(e) => {
                    self.warnings
                        .push(format!("{label}: NORMAL {e}; normals generated instead"));
                    None
                }
            },
        };

        let uv_set = self.uv_set(&prim.material());
        let uvs = match prim.get(&gltf::Semantic::TexCoords(uv_set)) {
            None => None,
            Some(acc) => match read_vectors::<2>(&acc, buffers) {
                Ok(v) if v.len() == n => Some(v),
                Ok(v) => {
                    self.warnings.push(format!(
                        "{label}: {} TEXCOORD_{uv_set} values for {n} positions; coordinates ignored",
                        v.len()
                    ));
                    None
                }
                Err(e) => {
                    self.warnings.push(format!(
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
        self.report(label, &report, n);
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
            self.skip(format!("{label}: nothing drawable: {why}"));
            return Ok(None);
        }
        Ok(Some(g))
    }

    fn report(&mut self, label: &str, r: &Report, vertices: usize) {
        let total = r.triangles_in;
        if r.ragged_indices > 0 {
            self.warnings.push(format!(
                "{label}: {} trailing indices do not make a whole triangle; ignored",
                r.ragged_indices
            ));
        }
        if r.out_of_range > 0 {
            self.warnings.push(format!(
                "{label}: dropped {} of {total} triangles with indices out of range (vertex count {vertices})",
                r.out_of_range
            ));
        }
        if r.non_finite > 0 {
            self.warnings.push(format!(
                "{label}: dropped {} of {total} triangles touching NaN/infinite positions or normals",
                r.non_finite
            ));
        }
        if r.recomputed_normals > 0 {
            self.warnings.push(format!(
                "{label}: recomputed {} zero-length normals from the surrounding faces",
                r.recomputed_normals
            ));
        }
        if r.renormalised > 0 {
            self.warnings.push(format!(
                "{label}: rescaled {} normals that were not unit length",
                r.renormalised
            ));
        }
        if r.bad_uvs > 0 {
            self.warnings.push(format!(
                "{label}: set {} NaN/infinite texture coordinates to zero",
                r.bad_uvs
            ));
        }
    }

    /// The texture-coordinate set the material's textures use.
    fn uv_set(&mut self, m: &gltf::Material) -> u32 {
        let base = m
            .pbr_metallic_roughness()
            .base_color_texture()
            .map(|t| t.tex_coord());
        let emissive = m.emissive_texture().map(|t| t.tex_coord());
        match (base, emissive) {
            (Some(b), Some(e)) if b != e => {
                self.warnings.push(format!(
                    "material {}: base colour and emissive textures use different coordinate sets; TEXCOORD_{b} is used for both",
                    m.index().map_or("default".into(), |i| i.to_string())
                ));
                b
            }
            (Some(b), _) => b,
            (None, Some(e)) => e,
            (None, None) => 0,
        }
    }

    fn material(&mut self, m: gltf::Material) -> usize {
        if let Some(&i) = self.material_map.get(&m.index()) {
            return i;
        }
        let pbr = m.pbr_metallic_roughness();
        let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
        let base = pbr.base_color_factor().map(|c| finite_or(c, 1.0));
        let strength = m.emissive_strength().unwrap_or(1.0);
        let strength = if strength.is_finite() && strength >= 0.0 {
            strength
        } else {
            1.0
        };
        let emissive = m
            .emissive_factor()
            .map(|e| finite_or(e, 0.0).max(0.0) * strength);
        let base_color_texture = pbr
            .base_color_texture()
            .and_then(|info| self.texture(&info.texture()));
        let emissive_texture = m
            .emissive_texture()
            .and_then(|info| self.texture(&info.texture()));
        let material = Material {
            name: m.name().unwrap_or_default().to_string(),
            base_color: base,
            base_color_texture,
            metallic: finite_or(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0),
            roughness: finite_or(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0),
            emissive,
            emissive_texture,
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha_cutoff: finite_or(m.alpha_cutoff().unwrap_or(0.5), 0.5),
            double_sided: m.double_sided(),
        };
        self.materials.push(material);
        let i = self.materials.len() - 1;
        self.material_map.insert(m.index(), i);
        i
    }

    /// Decodes a texture's image once; `None` (with a warning) when it cannot.
    fn texture(&mut self, texture: &gltf::Texture) -> Option<usize> {
        let image = texture.source();
        let index = image.index();
        if let Some(&known) = self.texture_map.get(&index) {
            return known;
        }
        let result = match self.decode_image(&image) {
            Ok(t) => {
                self.textures.push(t);
                Some(self.textures.len() - 1)
            }
            Err(e) => {
                self.warnings.push(format!(
                    "texture image {index}: {e}; the material's factor is used alone"
                ));
                None
            }
        };
        self.texture_map.insert(index, result);
        result
    }

    // Not gltf::image::Data::from_source: it slices buffer views without bounds checks and refuses data URIs when loading from memory.
    fn decode_image(&self, image: &gltf::Image) -> Result<TextureData, String> {
        let (bytes, what) = match image.source() {
            gltf::image::Source::View { view, .. } => (
                view_bytes(&view, self.buffers)?.to_vec(),
                format!("buffer view {}", view.index()),
            ),
            gltf::image::Source::Uri { uri, .. } => match resolve_uri(uri, self.base)? {
                UriSource::Bytes(b) => (b, display_uri(uri)),
                UriSource::File(file) => match std::fs::read(&file) {
                    Ok(b) => (b, display_uri(uri)),
                    Err(e) => return Err(format!("missing image file {}: {e}", display_uri(uri))),
                },
            },
        };
        let decoded = image::load_from_memory(&bytes).map_err(|e| {
            let jpeg = bytes.starts_with(&[0xFF, 0xD8, 0xFF]);
            if jpeg && matches!(e, image::ImageError::Unsupported(_)) {
                format!("{what} is a JPEG and this build cannot decode JPEG (enable the image crate's `jpeg` feature)")
            } else {
                format!("cannot decode {what}: {e}")
            }
        })?;
        let rgba = decoded.to_rgba8();
        Ok(TextureData {
            width: rgba.width(),
            height: rgba.height(),
            rgba8: rgba.into_raw(),
            srgb: true,
        })
    }

    fn make_camera(&mut self, cam: &gltf::Camera, world: Mat4, label: &str) -> Option<Camera> {
        let p = match cam.projection() {
            gltf::camera::Projection::Perspective(p) => p,
            gltf::camera::Projection::Orthographic(_) => {
                self.warnings.push(format!(
                    "{label}: orthographic cameras are not supported; looking for a perspective one"
                ));
                return None;
            }
        };
        let (yfov, znear) = (p.yfov(), p.znear());
        let usable = yfov.is_finite()
            && yfov > 0.0
            && yfov < std::f32::consts::PI
            && znear.is_finite()
            && znear > 0.0;
        if !usable {
            self.warnings.push(format!(
                "{label}: camera with yfov {yfov} and znear {znear} is unusable; ignored"
            ));
            return None;
        }
        let far = match p.zfar() {
            Some(f) if f.is_finite() && f > znear => Some(f),
            Some(f) => {
                self.warnings.push(format!(
                    "{label}: camera zfar {f} is not beyond znear {znear}; using an infinite far plane"
                ));
                None
            }
            None => None,
        };
        let eye = world.w_axis.truncate();
        let forward = world.transform_vector3(Vec3::NEG_Z);
        let up = world.transform_vector3(Vec3::Y);
        if forward.length_squared() < 1e-20 || !forward.is_finite() || !eye.is_finite() {
            self.warnings
                .push(format!("{label}: camera transform is degenerate; ignored"));
            return None;
        }
        Some(Camera {
            view: look_at(eye, eye + forward, up.normalize_or(Vec3::Y)),
            fov_y: yfov,
            near: znear,
            far,
        })
    }

    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4, label: &str) {
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if !(color.is_finite() && intensity.is_finite() && intensity >= 0.0 && position.is_finite())
        {
            self.warnings.push(format!(
                "{label}: light with non-finite or negative values; ignored"
            ));
            return;
        }
        let range = light.range().filter(|r| r.is_finite() && *r > 0.0);
        let kind = match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
            gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
            gltf::khr_lights_punctual::Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let half_pi = std::f32::consts::FRAC_PI_2;
                let outer = if outer_cone_angle.is_finite() {
                    outer_cone_angle.clamp(1e-4, half_pi)
                } else {
                    std::f32::consts::FRAC_PI_4
                };
                let inner = if inner_cone_angle.is_finite() {
                    inner_cone_angle.clamp(0.0, outer * 0.999)
                } else {
                    0.0
                };
                LightKind::Spot {
                    inner_cone: inner,
                    outer_cone: outer,
                }
            }
        };
        if kind != LightKind::Point && direction == Vec3::ZERO {
            self.warnings.push(format!(
                "{label}: light has a degenerate direction; ignored"
            ));
            return;
        }
        self.lights.push(Light {
            kind,
            position,
            direction: if direction == Vec3::ZERO {
                Vec3::NEG_Z
            } else {
                direction
            },
            color,
            intensity,
            range,
        });
    }

    fn finish(self, name: String) -> Result<Scene, String> {
        if self.objects.is_empty() {
            let meshes = self.document.meshes().len();
            return Err(match (self.first_skip, meshes) {
                (Some(first), _) => format!("no triangles to draw: {first}"),
                (None, 0) => "no triangles to draw: the file has no meshes".to_string(),
                (None, m) => format!(
                    "no triangles to draw: the file has {m} mesh(es) but its scene places none of them"
                ),
            });
        }
        let warnings = self.warnings;
        let mut scene = Scene {
            name,
            objects: self.objects,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            camera: Camera::look_at(Vec3::Z, Vec3::ZERO, DEFAULT_FOV_Y, 0.1, None),
            background: GLTF_BACKGROUND,
            warnings: Vec::new(),
            bounds: super::Aabb::EMPTY,
            bars: Vec::new(),
        };
        scene.recompute_bounds();
        scene.camera = match self.camera {
            Some(c) => c,
            None => scene.framing_camera(DEFAULT_FOV_Y),
        };
        if scene.lights.is_empty() {
            scene.lights = default_lights(&scene.bounds);
        }
        scene.warnings = warnings.into_vec();
        Ok(scene)
    }
}
