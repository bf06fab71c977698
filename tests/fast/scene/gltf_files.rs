//! Hand-written glTF files, each a case the loader must repair, warn about
//! or refuse in one line.

use super::*;

/// Builds a tiny glTF: accessors over one binary buffer.
#[derive(Default)]
struct Tiny {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Tiny {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A VEC3 float accessor with the min/max glTF requires for POSITION.
    fn vec3(&mut self, data: &[[f32; 3]]) -> usize {
        let i = self.vec3_unbounded(data);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for v in data {
            for k in 0..3 {
                if v[k].is_finite() {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
        }
        self.accessors[i]["min"] = json!(lo);
        self.accessors[i]["max"] = json!(hi);
        i
    }

    /// A VEC3 float accessor without min/max.
    fn vec3_unbounded(&mut self, data: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        self.accessors.push(
            json!({"bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC3"}),
        );
        self.accessors.len() - 1
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({"bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// The JSON document; `extra` fields are merged at the top level.
    fn json(&self, uri: &str, extra: Value) -> Value {
        let mut doc = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": uri, "byteLength": self.bin.len()}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        if let (Some(d), Value::Object(e)) = (doc.as_object_mut(), extra) {
            d.extend(e);
        }
        doc
    }

    /// Writes `name.gltf` and `name.bin` into `dir`.
    fn write(&self, dir: &Path, name: &str, extra: Value) -> PathBuf {
        let gltf = dir.join(format!("{name}.gltf"));
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).expect("write bin");
        let doc = self.json(&format!("{name}.bin"), extra);
        std::fs::write(&gltf, serde_json::to_vec_pretty(&doc).expect("json")).expect("write gltf");
        gltf
    }

    /// A `.glb` holding the document and the buffer.
    fn glb(&self, extra: Value) -> Vec<u8> {
        let mut doc = self.json("", extra);
        if let Some(b) = doc.pointer_mut("/buffers/0").and_then(Value::as_object_mut) {
            b.remove("uri");
        }
        let mut json = serde_json::to_vec(&doc).expect("json");
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

/// A unit quad in z = 0 facing +z, as two triangles, with normals.
fn quad() -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0.0, 0.0, 1.0]; 4],
        vec![0, 1, 2, 0, 2, 3],
    )
}

fn one_mesh_scene(primitive: Value, node: Value) -> Value {
    let mut node = node;
    if let Some(n) = node.as_object_mut() {
        n.insert("mesh".into(), json!(0));
    }
    json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [node],
        "meshes": [{"name": "m", "primitives": [primitive]}],
    })
}

fn err_line(result: deferred_msaa_lab::Result<Scene>) -> String {
    let msg = result.expect_err("expected an error").to_string();
    assert!(!msg.contains('\n'), "multi-line error: {msg}");
    msg
}

#[test]
fn nan_vertices_and_bad_indices_are_dropped_with_warnings() {
    let dir = scratch("sanitise");
    let mut t = Tiny::default();
    let nan = f32::NAN;
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [nan, 0.5, 0.0],
        [2.0, f32::INFINITY, 0.0],
    ];
    let normals = [
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 2.0], // not unit: rescaled
        [0.0, 0.0, 0.0], // zero: recomputed
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
    ];
    let pos = t.vec3(&positions);
    let nrm = t.vec3(&normals);
    // Good, good, NaN vertex, infinite vertex, index 99, index 6.
    let idx = t.indices(&[0, 1, 2, 0, 2, 3, 0, 4, 3, 1, 5, 2, 0, 99, 1, 6, 1, 2]);
    let doc = one_mesh_scene(
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}),
        json!({"name": "panel", "extras": {"deferred_msaa": {"antialias": false}}}),
    );
    let path = t.write(&dir, "sanitise", doc);
    let scene = load_path(&path).expect("loads despite the damage");
    assert_sane(&scene);
    assert_eq!(scene.triangle_count(), 2);
    let o = &scene.objects[0];
    assert_eq!(o.positions.len(), 4, "unused NaN vertices compacted away");
    assert!(!o.antialias, "node extras turn AA off");
    assert!(scene.has_selective_aa());
    let all = scene.warnings.join("\n");
    assert!(
        all.contains("dropped 2 of 6 triangles with indices out of range"),
        "{all}"
    );
    assert!(
        all.contains("dropped 2 of 6 triangles touching NaN/infinite"),
        "{all}"
    );
    assert!(all.contains("recomputed 1 zero-length normals"), "{all}");
    assert!(all.contains("rescaled 1 normals"), "{all}");
    // The default rig stands in for missing lights; the box is framed.
    assert_eq!(scene.lights.len(), 4);
    assert_camera_sees_bounds(&scene);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_finite_normals_drop_triangles() {
    let dir = scratch("nan-normals");
    let mut t = Tiny::default();
    let (p, mut n, i) = quad();
    n[3] = [f32::NAN, 0.0, 1.0];
    let doc = one_mesh_scene(
        json!({"attributes": {"POSITION": t.vec3(&p), "NORMAL": t.vec3(&n)}, "indices": t.indices(&i)}),
        json!({}),
    );
    let scene = load_path(&t.write(&dir, "nn", doc)).expect("loads");
    assert_eq!(scene.triangle_count(), 1);
    assert_sane(&scene);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Vertices no kept triangle uses are dropped even when no triangle is:
/// an unreferenced NaN vertex (indexed), and one only a ragged trailing
/// index names (unindexed), would otherwise reach the bounds and the GPU.
#[test]
fn vertices_no_triangle_uses_are_compacted_away() {
    let dir = scratch("unreferenced");
    let mut t = Tiny::default();
    let (mut p, mut n, i) = quad();
    p.push([f32::NAN, 1e30, 0.0]);
    n.push([0.0, 0.0, 0.0]);
    let unreferenced = json!({
        "attributes": {"POSITION": t.vec3(&p), "NORMAL": t.vec3(&n)},
        "indices": t.indices(&i),
    });
    let ragged = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [f32::INFINITY, 0.0, 0.0],
    ];
    let unindexed = json!({"attributes": {"POSITION": t.vec3(&ragged)}});
    let doc = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1}],
        "meshes": [{"primitives": [unreferenced]}, {"primitives": [unindexed]}],
    });
    let scene = load_path(&t.write(&dir, "unreferenced", doc)).expect("loads");
    assert_sane(&scene);
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.objects[0].positions.len(), 4, "the quad's own four");
    assert_eq!(scene.objects[1].triangle_count(), 1);
    assert!(scene.bounds.max.x <= 1.0, "bounds {:?}", scene.bounds);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Flat normals of triangles whose cross product squares into subnormals
/// (sides of 1e-19) or past f32's range (sides of 1e19) are unit vectors
/// facing the face: +x for a triangle in the y-z plane, not +z.
#[test]
fn tiny_and_huge_triangles_get_unit_normals_facing_them() {
    let dir = scratch("extreme-sizes");
    let mut t = Tiny::default();
    let triangle = |s: f32| [[0.0, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]];
    let (tiny, huge) = (t.vec3(&triangle(1e-19)), t.vec3(&triangle(1e19)));
    let doc = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": tiny}}]},
            {"primitives": [{"attributes": {"POSITION": huge}}]},
        ],
    });
    let scene = load_path(&t.write(&dir, "extreme", doc)).expect("loads");
    assert_sane(&scene);
    for o in &scene.objects {
        for n in &o.normals {
            assert!(
                (Vec3::from(*n) - Vec3::X).length() < 1e-6,
                "{}: normal {n:?}",
                o.name
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two triangles, each finite, 6e38 apart: no f32 camera frames them and no
/// depth range holds them, so the file is refused in one line (the framing
/// camera's near plane and position came out infinite and NaN).
#[test]
fn a_scene_wider_than_f32_is_a_one_line_error() {
    let dir = scratch("too-wide");
    let mut t = Tiny::default();
    let at = |x: f32| [[x, 0.0, 0.0], [x, 1.0, 0.0], [x, 0.0, 1.0]];
    let (left, right) = (t.vec3(&at(-3e38)), t.vec3(&at(3e38)));
    let doc = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": left}}]},
            {"primitives": [{"attributes": {"POSITION": right}}]},
        ],
    });
    let msg = err_line(load_path(&t.write(&dir, "wide", doc)));
    assert!(
        msg.contains("wide.gltf") && msg.contains("too far for single-precision"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn strips_fans_and_missing_normals() {
    let dir = scratch("modes");
    let mut t = Tiny::default();
    let (p, _, _) = quad();
    let pos = t.vec3(&p);
    // Strip 0-1-3-2 and fan 0-1-2-3 both make the quad, counter-clockwise.
    let strip = t.indices(&[0, 1, 3, 2]);
    let fan = t.indices(&[0, 1, 2, 3]);
    let doc = json!({
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"mesh": 1}, {"mesh": 2}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": pos}, "indices": strip, "mode": 5}]},
            {"primitives": [{"attributes": {"POSITION": pos}, "indices": fan, "mode": 6}]},
            {"primitives": [{"attributes": {"POSITION": pos}, "mode": 1}]},
        ],
    });
    let scene = load_path(&t.write(&dir, "modes", doc)).expect("loads");
    assert_sane(&scene);
    assert_eq!(scene.objects.len(), 2);
    for o in &scene.objects {
        assert_eq!(o.triangle_count(), 2);
        // Flat normals: unindexed, each facing +z.
        assert_eq!(o.positions.len(), 6);
        assert!(
            o.normals
                .iter()
                .all(|n| (Vec3::from(*n) - Vec3::Z).length() < 1e-6)
        );
        assert_winding_follows_normals(&scene, o);
    }
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("mode LINES skipped")),
        "{:?}",
        scene.warnings
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn only_points_is_an_error() {
    let dir = scratch("points");
    let mut t = Tiny::default();
    let (p, _, _) = quad();
    let doc = one_mesh_scene(
        json!({"attributes": {"POSITION": t.vec3(&p)}, "mode": 0}),
        json!({}),
    );
    let path = t.write(&dir, "points", doc);
    let msg = err_line(load_path(&path));
    assert!(
        msg.contains("points.gltf") && msg.contains("no triangles"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn camera_lights_mirroring_and_mesh_extras() {
    let dir = scratch("camlights");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let doc = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 20.0, "range": 7.5},
            {"type": "spot", "intensity": 5.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 3.0},
        ]}},
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4, 5]}],
        "nodes": [
            {"mesh": 0, "name": "plain"},
            {"mesh": 1, "name": "mirrored", "scale": [-1.0, 1.0, 1.0], "translation": [3.0, 0.0, 0.0]},
            {"camera": 0, "translation": [0.5, 0.5, 4.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1.0, 2.0, 3.0]},
            // Rotated -90° about x: -z (the light's axis) turns to -y.
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-s, 0.0, 0.0, s]},
            {"extensions": {"KHR_lights_punctual": {"light": 2}}},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}]},
            {"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}],
             "extras": {"deferred_msaa": {"antialias": false}}},
        ],
    });
    let scene = load_path(&t.write(&dir, "camlights", doc)).expect("loads");
    assert_sane(&scene);
    // The camera node's transform and perspective are used; no zfar = infinite.
    assert!((scene.camera.position() - Vec3::new(0.5, 0.5, 4.0)).length() < 1e-5);
    assert_eq!(scene.camera.fov_y, 0.8);
    assert_eq!(scene.camera.near, 0.05);
    assert_eq!(scene.camera.far, None);
    assert_eq!(scene.lights.len(), 3);
    let point = scene.lights[0];
    assert_eq!(point.kind, LightKind::Point);
    assert!((point.position - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
    assert_eq!(point.range, Some(7.5));
    assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
    let spot = scene.lights[1];
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner_cone: 0.2,
            outer_cone: 0.5
        }
    );
    assert!(
        (spot.direction - Vec3::NEG_Y).length() < 1e-5,
        "{:?}",
        spot.direction
    );
    assert_eq!(scene.lights[2].kind, LightKind::Directional);
    assert!((scene.lights[2].direction - Vec3::NEG_Z).length() < 1e-6);
    // Mirroring: the winding is swapped so world-space CCW still faces the normal.
    let plain = scene
        .objects
        .iter()
        .find(|o| o.name == "plain")
        .expect("plain");
    let mirrored = scene
        .objects
        .iter()
        .find(|o| o.name == "mirrored")
        .expect("mirrored");
    assert!(plain.antialias);
    assert!(!mirrored.antialias, "mesh extras turn AA off");
    assert!(mirrored.transform.determinant() < 0.0);
    assert_ne!(plain.indices, mirrored.indices);
    assert_winding_follows_normals(&scene, plain);
    assert_winding_follows_normals(&scene, mirrored);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn position_bounds_and_missing_positions_are_tolerated() {
    let dir = scratch("bounds");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3_unbounded(&p), t.vec3(&n), t.indices(&i));
    let mut doc = one_mesh_scene(
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}),
        json!({}),
    );
    // A second primitive with no POSITION at all.
    doc["meshes"][0]["primitives"]
        .as_array_mut()
        .expect("primitives")
        .push(json!({"attributes": {"NORMAL": nrm}}));
    let scene = load_path(&t.write(&dir, "bounds", doc.clone())).expect("loads");
    assert_sane(&scene);
    assert_eq!(scene.triangle_count(), 2);
    let all = scene.warnings.join("\n");
    assert!(all.contains("lack the min/max"), "{all}");
    assert!(all.contains("without a POSITION"), "{all}");

    // POSITION naming an accessor that does not exist: an error, not a panic
    // (the glTF crate's validator would index it unchecked).
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(57);
    let path = t.write(&dir, "dangling", doc);
    let outcome = catch_unwind(AssertUnwindSafe(|| load_path(&path)));
    let msg = err_line(outcome.expect("no panic"));
    assert!(msg.contains("dangling.gltf") && msg.contains("57"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn recursive_node_graph_is_cut() {
    let dir = scratch("recursive");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let doc = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "mesh": 0}, {"children": [0], "mesh": 0, "translation": [2.0, 0.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}]}],
    });
    let scene = load_path(&t.write(&dir, "recursive", doc)).expect("loads");
    assert_eq!(scene.objects.len(), 2);
    assert!(
        scene.warnings.iter().any(|w| w.contains("cycle")),
        "{:?}",
        scene.warnings
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn embedded_base64_buffer_loads() {
    let dir = scratch("base64");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let uri = format!("data:application/octet-stream;base64,{}", base64(&t.bin));
    let doc = t.json(
        &uri,
        one_mesh_scene(
            json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}),
            json!({}),
        ),
    );
    let path = dir.join("embedded.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write");
    let scene = load_path(&path).expect("loads");
    assert_eq!(scene.objects[0].positions, p);
    let _ = std::fs::remove_dir_all(&dir);
}

fn base64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[test]
fn glb_loads_and_truncated_glb_fails() {
    let dir = scratch("glb");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let glb = t.glb(one_mesh_scene(
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}),
        json!({}),
    ));
    let whole = dir.join("whole.glb");
    std::fs::write(&whole, &glb).expect("write");
    let scene = load_path(&whole).expect("the intact .glb loads");
    assert_eq!(scene.triangle_count(), 2);

    for cut in [6, 30, glb.len() - 10] {
        let path = dir.join(format!("cut{cut}.glb"));
        std::fs::write(&path, &glb[..cut]).expect("write");
        let msg = err_line(load_path(&path));
        assert!(msg.contains(&format!("cut{cut}.glb")), "{msg}");
        assert!(msg.contains("truncated"), "{msg}");
    }
    // A real .glb from the corpus, cut in half.
    let real = Path::new(ASSIMP_GLTF2).join("BoxTextured-glTF-Binary/BoxTextured.glb");
    match std::fs::read(&real) {
        Ok(bytes) => {
            let path = dir.join("BoxTextured-half.glb");
            std::fs::write(&path, &bytes[..bytes.len() / 2]).expect("write");
            let msg = err_line(load_path(&path));
            assert!(
                msg.contains("BoxTextured-half.glb") && msg.contains("truncated"),
                "{msg}"
            );
        }
        Err(e) => common::skip(&format!(
            "{}: {e} (install assimp-testmodels)",
            real.display()
        )),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn not_gltf_files_fail_clearly() {
    let dir = scratch("notgltf");
    let text = dir.join("notes.gltf");
    std::fs::write(&text, "this is not a glTF file\n").expect("write");
    let msg = err_line(load_path(&text));
    assert!(
        msg.contains("notes.gltf") && msg.contains("not a glTF"),
        "{msg}"
    );

    let png = dir.join("picture.glb");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n0000000000000000").expect("write");
    let msg = err_line(load_path(&png));
    assert!(
        msg.contains("picture.glb") && msg.contains("magic"),
        "{msg}"
    );

    let bad_json = dir.join("broken.gltf");
    std::fs::write(
        &bad_json,
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [",
    )
    .expect("write");
    let msg = err_line(load_path(&bad_json));
    assert!(msg.contains("broken.gltf") && msg.contains("JSON"), "{msg}");

    let v1 = dir.join("old.gltf");
    std::fs::write(
        &v1,
        "{\"asset\": {\"version\": \"1.0\"}, \"scene\": \"defaultScene\"}",
    )
    .expect("write");
    let msg = err_line(load_path(&v1));
    assert!(msg.contains("old.gltf") && msg.contains("1.0"), "{msg}");

    let missing = dir.join("absent.gltf");
    let msg = err_line(load_path(&missing));
    assert!(msg.contains("absent.gltf"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_bin_and_missing_texture() {
    let dir = scratch("missing");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let mut doc = one_mesh_scene(
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": 0}),
        json!({}),
    );
    if let Some(d) = doc.as_object_mut() {
        d.insert("materials".into(), json!([{
            "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "baseColorTexture": {"index": 0}},
            "emissiveFactor": [1.0, 0.5, 0.0],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 40.0}}
        }]));
        d.insert("textures".into(), json!([{"source": 0}]));
        d.insert("images".into(), json!([{"uri": "gone.png"}]));
        d.insert(
            "extensionsUsed".into(),
            json!(["KHR_materials_emissive_strength"]),
        );
    }
    let path = t.write(&dir, "textured", doc);
    let scene = load_path(&path).expect("a missing texture is only a warning");
    let m = scene.material_of(&scene.objects[0]);
    assert_eq!(m.base_color_texture, None);
    assert_eq!(m.base_color, [0.5, 0.25, 1.0, 1.0]);
    assert_eq!(m.emissive, [40.0, 20.0, 0.0]);
    assert!(scene.has_emissive());
    assert!(
        scene.warnings.iter().any(|w| w.contains("gone.png")),
        "{:?}",
        scene.warnings
    );

    std::fs::remove_file(dir.join("textured.bin")).expect("remove bin");
    let msg = err_line(load_path(&path));
    assert!(
        msg.contains("textured.gltf") && msg.contains("textured.bin"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// What glTF requires but its schema validation does not check: an image
/// in a buffer view without `mimeType` (read from its bytes), an image with
/// neither a buffer view nor a URI (a warning), a camera whose `type` names
/// an object it lacks (ignored with a warning). Each once panicked inside
/// the `gltf` crate's accessors.
#[test]
fn images_and_cameras_the_schema_leaves_incomplete_load() {
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 3, image::Rgba([200, 100, 50, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    let png_view = t.view(&png);
    let primitive = |material: usize| json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": material});
    let doc = json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "name": "sniffed"},
            {"mesh": 1, "name": "sourceless"},
            {"camera": 0, "translation": [0.0, 0.0, 50.0]},
        ],
        "meshes": [{"primitives": [primitive(0)]}, {"primitives": [primitive(1)]}],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
        ],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"bufferView": png_view}, {"name": "nowhere"}],
        "cameras": [{"type": "perspective", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 9.0}}],
    });
    let scene = Scene::from_bytes(&t.glb(doc), "incomplete").expect("loads");
    assert_sane(&scene);
    let object = |name: &str| {
        let o = scene.objects.iter().find(|o| o.name == name).expect(name);
        scene.material_of(o)
    };
    let texture = object("sniffed")
        .base_color_texture
        .and_then(|t| scene.textures.get(t))
        .expect("the PNG in the buffer view is decoded");
    assert_eq!((texture.width, texture.height), (2, 3));
    assert_eq!(object("sourceless").base_color_texture, None);
    let all = scene.warnings.join("\n");
    assert!(all.contains("image 0") && all.contains("mimeType"), "{all}");
    assert!(all.contains("neither a bufferView nor a uri"), "{all}");
    assert!(
        all.contains("camera 0") && all.contains("no perspective"),
        "{all}"
    );
    // The camera is ignored: the scene is framed, not seen from z = 50.
    assert!(
        scene.camera.position().z < 50.0,
        "{:?}",
        scene.camera.position()
    );
}

#[test]
fn invalid_accessor_is_an_error() {
    let dir = scratch("accessor");
    let mut t = Tiny::default();
    let (p, n, i) = quad();
    let (pos, nrm, idx) = (t.vec3(&p), t.vec3(&n), t.indices(&i));
    // Claim more positions than the view holds.
    if let Some(a) = t.accessors.get_mut(pos) {
        a["count"] = json!(400);
    }
    let doc = one_mesh_scene(
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}),
        json!({}),
    );
    let msg = err_line(load_path(&t.write(&dir, "overrun", doc)));
    assert!(
        msg.contains("overrun.gltf") && msg.contains("accessor"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
