//! Where the glTF loader reads bytes itself instead of through the `gltf`
//! crate's GLB splitter and importer, it accepts or refuses files the crate
//! (1.4) would treat otherwise. These tests pin those cases, so that a switch
//! to the crate that changes them shows here.

use std::path::{Path, PathBuf};

use deferred_msaa_lab::scene::Scene;
use serde_json::{Value, json};

/// Quad positions, then its six indices as unsigned bytes: 54 bytes, so a
/// buffer holding them is not a multiple of four long.
fn quad_bytes() -> Vec<u8> {
    let positions: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut bytes: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bytes.extend_from_slice(&[0, 1, 2, 0, 2, 3]);
    bytes
}

/// A one-quad document over `buffers`, whose buffer 0 holds `quad_bytes`;
/// `index_view_len` is the byte length of the index view (6 when intact).
fn quad_doc(buffers: Value, index_view_len: usize) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "buffers": buffers,
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": index_view_len},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5121, "count": 6, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    })
}

/// A `.glb` from chunks of (type, payload), each padded to four bytes.
fn glb(chunks: &[(&[u8; 4], &[u8])]) -> Vec<u8> {
    let mut body = Vec::new();
    for (kind, payload) in chunks {
        let mut payload = payload.to_vec();
        let pad = if kind == &b"JSON" { b' ' } else { 0 };
        while payload.len() % 4 != 0 {
            payload.push(pad);
        }
        body.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        body.extend_from_slice(*kind);
        body.extend_from_slice(&payload);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(12 + body.len() as u32).to_le_bytes());
    out.extend(body);
    out
}

fn standard_base64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn from_json(doc: &Value) -> deferred_msaa_lab::Result<Scene> {
    Scene::from_bytes(&serde_json::to_vec(doc).expect("json"), "doc")
}

fn err_line(result: deferred_msaa_lab::Result<Scene>) -> String {
    let msg = result.expect_err("expected an error").to_string();
    assert!(!msg.contains('\n'), "multi-line error: {msg}");
    msg
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "deferred-msaa-gltf-sources-{}-{tag}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn load_path(path: &Path) -> deferred_msaa_lab::Result<Scene> {
    Scene::load(path.to_str().expect("utf-8 path"))
}

#[test]
fn glb_skips_unknown_chunks_before_the_binary_one() {
    let bin = quad_bytes();
    let doc = quad_doc(json!([{"byteLength": bin.len()}]), 6);
    let json = serde_json::to_vec(&doc).expect("json");
    let file = glb(&[
        (b"JSON", &json),
        (b"XTRA", b"extension data"),
        (b"JSON", b"{}"),
        (b"BIN\0", &bin),
    ]);
    let scene = Scene::from_bytes(&file, "chunks").expect("unknown chunks are skipped");
    assert_eq!(scene.triangle_count(), 2);
}

#[test]
fn glb_header_declaring_less_than_itself_is_an_error() {
    let mut file = glb(&[(b"JSON", br#"{"asset": {"version": "2.0"}}"#)]);
    file[8..12].copy_from_slice(&8u32.to_le_bytes());
    let msg = err_line(Scene::from_bytes(&file, "short-header"));
    assert!(
        msg.contains("short-header") && msg.contains(".glb"),
        "{msg}"
    );
}

#[test]
fn several_buffers_may_name_the_binary_chunk() {
    let bin = quad_bytes();
    let len = bin.len();
    let doc = quad_doc(json!([{"byteLength": len}, {"byteLength": len}]), 6);
    let json = serde_json::to_vec(&doc).expect("json");
    let file = glb(&[(b"JSON", &json), (b"BIN\0", &bin)]);
    let scene = Scene::from_bytes(&file, "two-bin").expect("loads");
    assert_eq!(scene.triangle_count(), 2);
}

#[test]
fn a_view_past_the_end_of_an_unaligned_buffer_is_an_error() {
    // 54 bytes of data; the index view claims 8 from byte 48. Padding the
    // buffer to 56 bytes would let the view read two zeros instead.
    let bin = quad_bytes();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        standard_base64(&bin)
    );
    let doc = quad_doc(json!([{"uri": uri, "byteLength": bin.len()}]), 8);
    let msg = err_line(from_json(&doc));
    assert!(msg.contains("lies outside buffer 0"), "{msg}");
}

#[test]
fn lenient_base64_data_uris_load() {
    let bin = quad_bytes();
    // Bytes past the buffer's length, so the text holds '+', '/' and '='.
    let mut data = bin.clone();
    data.extend_from_slice(&[0xFB, 0xFF, 0xBF, 0]);
    let strict = standard_base64(&data);
    assert!(strict.contains('+') && strict.contains('/') && strict.ends_with('='));
    let unpadded = strict.trim_end_matches('=').to_string();
    let url_safe = strict.replace('+', "-").replace('/', "_");
    let wrapped: String = strict
        .as_bytes()
        .chunks(20)
        .map(|c| String::from_utf8_lossy(c).into_owned())
        .collect::<Vec<_>>()
        .join("\n ");
    for payload in [strict, unpadded, url_safe, wrapped] {
        let uri = format!("data:application/octet-stream;base64,{payload}");
        let doc = quad_doc(json!([{"uri": uri, "byteLength": bin.len()}]), 6);
        let scene = from_json(&doc).unwrap_or_else(|e| panic!("{payload:?}: {e}"));
        assert_eq!(scene.triangle_count(), 2);
    }
}

#[test]
fn percent_encoded_data_uri_loads() {
    let bin = quad_bytes();
    let payload: String = bin.iter().map(|b| format!("%{b:02X}")).collect();
    let uri = format!("data:application/octet-stream,{payload}");
    let doc = quad_doc(json!([{"uri": uri, "byteLength": bin.len()}]), 6);
    let scene = from_json(&doc).expect("a plain data URI loads");
    assert_eq!(scene.triangle_count(), 2);
}

#[test]
fn bad_base64_is_an_error() {
    let doc = quad_doc(
        json!([{"uri": "data:application/octet-stream;base64,AAAA*AAA", "byteLength": 54}]),
        6,
    );
    let msg = err_line(from_json(&doc));
    assert!(msg.contains("base64"), "{msg}");
}

#[test]
fn external_file_uris_are_percent_decoded_and_may_hold_colons() {
    let dir = scratch("uris");
    let bin = quad_bytes();
    std::fs::write(dir.join("quad data.bin"), &bin).expect("write bin");
    let doc = quad_doc(
        json!([{"uri": "quad%20data.bin", "byteLength": bin.len()}]),
        6,
    );
    let path = dir.join("spaced.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write");
    assert_eq!(load_path(&path).expect("loads").triangle_count(), 2);

    // A one-letter "scheme" is a drive letter, and a ':' after a '/' is part
    // of a path: both are files, here missing ones.
    for uri in ["C:/quad.bin", "sub/a:b.bin"] {
        let doc = quad_doc(json!([{"uri": uri, "byteLength": bin.len()}]), 6);
        std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write");
        let msg = err_line(load_path(&path));
        assert!(msg.contains("missing buffer file"), "{uri}: {msg}");
    }
    let doc = quad_doc(
        json!([{"uri": "https://example.invalid/quad.bin", "byteLength": bin.len()}]),
        6,
    );
    std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write");
    let msg = err_line(load_path(&path));
    assert!(msg.contains("unsupported URI scheme 'https:'"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_utf8_percent_escapes_are_an_error_not_a_panic() {
    let dir = scratch("escapes");
    let doc = quad_doc(json!([{"uri": "%FF%FE.bin", "byteLength": 54}]), 6);
    let path = dir.join("escaped.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write");
    let msg = err_line(load_path(&path));
    assert!(msg.contains("missing buffer file"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn images_from_data_uris_load_from_memory_and_bad_views_only_warn() {
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 0, 0, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    let bin = quad_bytes();
    let mut doc = quad_doc(json!([{"byteLength": bin.len()}]), 6);
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        standard_base64(&bin)
    ));
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["images"] = json!([{
        "uri": format!("data:image/png;base64,{}", standard_base64(&png))
    }]);
    let scene = from_json(&doc).expect("loads");
    assert_eq!(scene.textures.len(), 1, "{:?}", scene.warnings);
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (2, 2));

    // An image in a buffer view that runs past its buffer: the texture is
    // dropped with a warning.
    doc["bufferViews"]
        .as_array_mut()
        .expect("views")
        .push(json!({"buffer": 0, "byteOffset": 40, "byteLength": 400}));
    doc["images"] = json!([{"bufferView": 2, "mimeType": "image/png"}]);
    let scene = from_json(&doc).expect("a bad image view is only a warning");
    assert!(scene.textures.is_empty());
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("texture image 0") && w.contains("outside buffer 0")),
        "{:?}",
        scene.warnings
    );
}
