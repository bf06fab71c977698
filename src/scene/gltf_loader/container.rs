//! The container and the JSON: telling `.glb` from `.gltf`, splitting a
//! `.glb` into its JSON and BIN chunks, parsing the JSON into the `gltf`
//! crate's document (readied for its validation first), and the warnings
//! about extensions and skins the document alone decides.

use super::super::Warnings;

/// Extensions whose content the loader uses.
const HONOURED_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// The JSON text of a file and its `.glb` binary chunk, if it has one.
/// `is_glb_name` (the file is called `*.glb`) makes a missing binary magic
/// an error rather than a reason to read the bytes as JSON.
pub(super) fn json_and_bin(
    bytes: &[u8],
    is_glb_name: bool,
) -> Result<(&[u8], Option<&[u8]>), String> {
    if bytes.starts_with(b"glTF") {
        let glb = parse_glb(bytes)?;
        Ok((glb.json, glb.bin))
    } else if is_glb_name {
        let magic: String = bytes
            .iter()
            .take(4)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '.' })
            .collect();
        Err(format!(
            "not a binary glTF file: the magic is '{magic}', expected 'glTF'"
        ))
    } else {
        Ok((bytes, None))
    }
}

struct Glb<'a> {
    json: &'a [u8],
    bin: Option<&'a [u8]>,
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a `.glb` into its JSON and BIN chunks.
// Not gltf::Glb::from_slice (gltf 1.4.1): it computes `header.length - 12`
// unchecked, which underflows (a panic in debug builds) when the header
// declares under 12 bytes, and it fails with `UnknownChunkType` on any chunk
// other than JSON and BIN, which the spec says a reader skips.
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
pub(super) fn parse_document(json: &[u8]) -> Result<(gltf::Document, Vec<String>), String> {
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
    note_images_without_mime_type(&root, &mut notes);
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

/// Readies primitives' POSITION accessors for validation: a POSITION naming
/// a missing accessor is an error here, primitives without POSITION are left
/// out, and absent or malformed bounds are replaced (they are never used:
/// bounds are computed from the data).
// gltf::Document::from_json (gltf-json 1.4.1, mesh.rs's
// primitive_validate_hook) indexes `root.accessors[POSITION]` unchecked, a
// panic on a dangling index, and fails the whole document for a primitive
// without POSITION or a POSITION accessor without `min`/`max`, which many
// exporters omit.
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

/// Notes each image in a buffer view without the `mimeType` glTF requires
/// there (validation does not check it): the decoder reads the format from
/// the bytes, so such an image still loads.
fn note_images_without_mime_type(root: &gltf::json::Root, notes: &mut Vec<String>) {
    for (i, image) in root.images.iter().enumerate() {
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            notes.push(format!(
                "image {i}: a bufferView without the mimeType glTF requires; its format is read from its bytes"
            ));
        }
    }
}

/// Warns about the extensions used but not honoured, and about skins.
pub(super) fn check_extensions(doc: &gltf::Document, warnings: &mut Warnings) {
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
