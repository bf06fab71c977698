//! The scene model: built-in scenes, the real glTF assets, and the broken-file
//! corpus (`assimp-testmodels`), which must load or fail with one clear line,
//! never panic.
//!
//! Assets that are not installed are skipped through `common::skip`
//! (`skipped: <reason>` on stderr; a failure under
//! `DEFERRED_MSAA_REQUIRE_ALL=1`). Run with `-- --nocapture` to see the
//! corpus outcome table.

mod assets;
mod gltf_files;

use crate::common;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use deferred_msaa_lab::scene::{
    AlphaMode, Background, Camera, DEFAULT_SCENE, LightKind, Object, Scene,
};
use glam::{Vec3, Vec4};
use serde_json::{Value, json};

const ASSIMP_GLTF2: &str = "/usr/share/assimp/models/glTF2";

/// The models that travel with the repository (`assets/`, each with its licence).
fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

/// A fresh scratch directory for one test.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "deferred-msaa-scene-test-{}-{tag}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn load_path(path: &Path) -> deferred_msaa_lab::Result<Scene> {
    Scene::load(path.to_str().expect("utf-8 path"))
}

/// Checks the invariants every loaded scene must hold.
fn assert_sane(scene: &Scene) {
    let what = &scene.name;
    assert!(!scene.objects.is_empty(), "{what}: no objects");
    assert!(scene.triangle_count() > 0, "{what}: no triangles");
    for o in &scene.objects {
        let n = o.positions.len();
        assert_eq!(o.normals.len(), n, "{what}/{}: normals", o.name);
        assert_eq!(o.uvs.len(), n, "{what}/{}: uvs", o.name);
        assert_eq!(o.indices.len() % 3, 0, "{what}/{}: ragged", o.name);
        assert!(
            o.indices.iter().all(|&i| (i as usize) < n),
            "{what}/{}: index out of range",
            o.name
        );
        assert!(
            o.positions.iter().flatten().all(|c| c.is_finite()),
            "{what}/{}: non-finite position",
            o.name
        );
        assert!(
            o.uvs.iter().flatten().all(|c| c.is_finite()),
            "{what}/{}: non-finite uv",
            o.name
        );
        for nrm in &o.normals {
            let l = Vec3::from(*nrm).length();
            assert!(
                (l - 1.0).abs() < 1e-3,
                "{what}/{}: normal length {l}",
                o.name
            );
        }
        assert!(o.transform.is_finite(), "{what}/{}: transform", o.name);
        assert!(
            o.material < scene.materials.len(),
            "{what}/{}: material index",
            o.name
        );
    }
    for m in &scene.materials {
        for t in [m.base_color_texture, m.emissive_texture]
            .into_iter()
            .flatten()
        {
            let tex = scene.textures.get(t).expect("texture index in range");
            assert_eq!(tex.rgba8.len(), (tex.width * tex.height * 4) as usize);
        }
        assert!(
            m.base_color
                .iter()
                .chain(&m.emissive)
                .all(|c| c.is_finite())
        );
    }
    for l in &scene.lights {
        assert!(l.position.is_finite() && l.color.is_finite() && l.intensity.is_finite());
        assert!(
            (l.direction.length() - 1.0).abs() < 1e-3,
            "{what}: light direction {:?}",
            l.direction
        );
    }
    let cam = &scene.camera;
    assert!(cam.view.is_finite(), "{what}: view");
    assert!(cam.near > 0.0 && cam.fov_y > 0.0 && cam.fov_y < std::f32::consts::PI);
    if let Some(far) = cam.far {
        assert!(far > cam.near);
    }
    assert!(!scene.bounds.is_empty(), "{what}: empty bounds");
    for w in &scene.warnings {
        assert!(!w.contains('\n'), "{what}: multi-line warning {w:?}");
    }
}

/// The bounds' centre lies inside the camera's clip volume at 16:9.
fn assert_camera_sees_bounds(scene: &Scene) {
    let clip =
        scene.camera.projection(16.0 / 9.0) * scene.camera.view * scene.bounds.center().extend(1.0);
    assert!(
        clip.w > 0.0,
        "{}: centre behind the camera ({clip:?})",
        scene.name
    );
    let inside = clip.x.abs() <= clip.w && clip.y.abs() <= clip.w && clip.z.abs() <= clip.w;
    assert!(
        inside,
        "{}: centre outside the clip volume ({clip:?})",
        scene.name
    );
}

/// World-space triangles are counter-clockwise seen from the side their
/// normals point to (zero-area ones excepted).
fn assert_winding_follows_normals(scene: &Scene, o: &Object) {
    let normal_matrix = o.transform.inverse().transpose();
    let mut wrong = 0;
    let mut checked = 0;
    for tri in o.indices.chunks_exact(3) {
        let p = |k: usize| {
            o.transform
                .transform_point3(Vec3::from(o.positions[tri[k] as usize]))
        };
        let n = |k: usize| {
            normal_matrix
                .transform_vector3(Vec3::from(o.normals[tri[k] as usize]))
                .normalize_or_zero()
        };
        let face = (p(1) - p(0)).cross(p(2) - p(0));
        let scale = (p(1) - p(0)).length() * (p(2) - p(0)).length();
        if face.length() <= 1e-4 * scale || scale == 0.0 {
            continue; // degenerate or sliver-thin
        }
        checked += 1;
        if face.dot(n(0) + n(1) + n(2)) <= 0.0 {
            wrong += 1;
        }
    }
    assert_eq!(
        wrong, 0,
        "{}/{}: {wrong} of {checked} triangles wound against their normals",
        scene.name, o.name
    );
}

// ---------------------------------------------------------------------------
// Built-ins

#[test]
fn every_builtin_loads_and_is_sane() {
    assert_eq!(Scene::builtin_names().first(), Some(&"greebles"));
    assert_eq!(DEFAULT_SCENE, "builtin:greebles");
    for name in Scene::builtin_names() {
        let scene = Scene::load(&format!("builtin:{name}")).expect("built-in loads");
        assert_eq!(&scene.name, name);
        assert_sane(&scene);
        assert_camera_sees_bounds(&scene);
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        assert!(
            scene.triangle_count() <= 5000,
            "{name}: {} triangles is not small",
            scene.triangle_count()
        );
        assert!(!scene.lights.is_empty(), "{name}: no lights");
        for o in &scene.objects {
            assert_winding_follows_normals(&scene, o);
        }
        let (near, far) = scene.depth_range();
        assert!(
            near > 0.0 && far >= near,
            "{name}: depth range {near}..{far}"
        );
        eprintln!(
            "builtin:{name:<12} {:>5} triangles {:>3} objects {} lights, depth {near:.3}..{far:.3}",
            scene.triangle_count(),
            scene.objects.len(),
            scene.lights.len()
        );
    }
}

#[test]
fn builtins_are_deterministic() {
    for name in Scene::builtin_names() {
        let a = Scene::load(&format!("builtin:{name}")).expect("loads");
        let b = Scene::load(&format!("builtin:{name}")).expect("loads");
        assert_eq!(a.objects.len(), b.objects.len());
        for (x, y) in a.objects.iter().zip(&b.objects) {
            assert_eq!(x.positions, y.positions, "{name}/{}", x.name);
            assert_eq!(x.indices, y.indices, "{name}/{}", x.name);
        }
        assert_eq!(a.camera, b.camera);
    }
}

#[test]
fn builtins_exercise_what_they_claim() {
    let load = |n: &str| Scene::load(&format!("builtin:{n}")).expect("loads");

    let greebles = load("greebles");
    let close_points = greebles
        .lights
        .iter()
        .filter(|l| l.kind == LightKind::Point && l.range.is_some())
        .count();
    assert!(
        close_points >= 3,
        "greebles needs several ranged point lights"
    );
    assert!(matches!(greebles.background, Background::Gradient { .. }));
    assert!(greebles.objects.iter().any(|o| o.name == "antennas"));
    assert!(greebles.triangle_count() > 1000);

    let far = load("far");
    let distance = far.camera.position().distance(far.bounds.center());
    assert!(
        (distance - 200_000.0).abs() < 100.0,
        "far: distance {distance}"
    );
    assert!((far.camera.fov_y.to_degrees() - 0.5).abs() < 1e-4);
    assert_eq!(far.camera.near, 0.01);
    assert_eq!(far.camera.far, None);
    let (near, _) = far.depth_range();
    assert!(
        near > 65504.0,
        "far: the model must overflow FP16 positions"
    );
    // Fills a good part of the view: the box spans a third of the height or more.
    let proj = far.camera.projection(16.0 / 9.0) * far.camera.view;
    let ys: Vec<f32> = far
        .bounds
        .corners()
        .iter()
        .map(|c| {
            let p = proj * c.extend(1.0);
            p.y / p.w
        })
        .collect();
    let span =
        ys.iter().cloned().fold(f32::MIN, f32::max) - ys.iter().cloned().fold(f32::MAX, f32::min);
    assert!(
        span > 0.66,
        "far: the model spans only {span} of NDC height"
    );

    let emissive = load("emissive");
    assert!(emissive.has_emissive());
    assert!(emissive.max_emissive() >= 100.0);
    assert!(
        emissive
            .objects
            .iter()
            .any(|o| !emissive.material_of(o).is_emissive())
    );

    let transparent = load("transparent");
    assert!(transparent.has_transparent());
    assert!(transparent.has_alpha_mask());
    assert!(transparent.has_textures());
    assert!(
        transparent
            .objects
            .iter()
            .any(|o| transparent.material_of(o).alpha_mode == AlphaMode::Opaque)
    );
    assert!(!load("box").has_transparent());
    assert!(!load("box").has_emissive());
    assert_eq!(load("box").uniform_specular(), None);

    let zfight = load("zfight");
    let degenerate = zfight
        .objects
        .iter()
        .flat_map(|o| {
            o.indices.chunks_exact(3).map(move |t| {
                let p = |k: usize| Vec3::from(o.positions[t[k] as usize]);
                (p(1) - p(0)).cross(p(2) - p(0)).length()
            })
        })
        .filter(|&area| area == 0.0)
        .count();
    assert!(degenerate >= 1, "zfight needs a degenerate triangle");

    let thin = load("thin");
    match thin.background {
        Background::Gradient { zenith, horizon } => {
            assert!(
                zenith.iter().chain(&horizon).all(|&c| c > 1.0),
                "thin: bright HDR sky"
            );
        }
        other => panic!("thin: background {other:?}"),
    }
}

#[test]
fn unknown_builtin_is_a_one_line_error() {
    let err = Scene::load("builtin:nope")
        .expect_err("no such built-in")
        .to_string();
    assert!(err.contains("nope") && err.contains("greebles"), "{err}");
    assert!(!err.contains('\n'));
    let err = Scene::load("greebles").expect_err("not a file").to_string();
    assert!(err.contains("builtin:greebles"), "{err}");
}

#[test]
fn projection_maps_near_and_far() {
    let cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 1.0, 0.5, Some(100.0));
    let ndc_z = |cam: &Camera, d: f32| {
        let c = cam.projection(1.5) * cam.view * Vec4::new(0.0, 0.0, -d, 1.0);
        c.z / c.w
    };
    assert!((ndc_z(&cam, 0.5) + 1.0).abs() < 1e-5);
    assert!((ndc_z(&cam, 100.0) - 1.0).abs() < 1e-5);
    let inf = Camera { far: None, ..cam };
    assert!((ndc_z(&inf, 0.5) + 1.0).abs() < 1e-5);
    assert!(ndc_z(&inf, 1e6) < 1.0 && ndc_z(&inf, 1e6) > 0.9999);
    // fov_y: a point on the top edge of the view lands on y = 1.
    let top = cam.projection(1.0) * Vec4::new(0.0, (0.5f32).tan() * 10.0, -10.0, 1.0);
    assert!((top.y / top.w - 1.0).abs() < 1e-5);
    assert!(cam.position().length() < 1e-6);
    let moved = Camera::look_at(Vec3::new(3.0, 4.0, 5.0), Vec3::ZERO, 1.0, 0.1, None);
    assert!((moved.position() - Vec3::new(3.0, 4.0, 5.0)).length() < 1e-4);
}
