//! Bytes to scene: the glTF/GLB loading path must return a scene or a
//! one-line error for any input, never panic, hang or read out of bounds.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match deferred_msaa_lab::scene::Scene::from_bytes(data, "fuzz-input") {
        Ok(scene) => {
            // Whatever loads is drawable as it is: whole triangles over
            // finite vertices, unit normals, finite coordinates, transforms
            // and camera, materials in range, one-line warnings.
            assert!(!scene.objects.is_empty());
            for o in &scene.objects {
                let n = o.positions.len();
                assert_eq!(o.normals.len(), n);
                assert_eq!(o.uvs.len(), n);
                assert_eq!(o.indices.len() % 3, 0);
                assert!(o.indices.iter().all(|&i| (i as usize) < n));
                assert!(o.positions.iter().flatten().all(|v| v.is_finite()));
                assert!(o.uvs.iter().flatten().all(|v| v.is_finite()));
                for normal in &o.normals {
                    let length = glam::Vec3::from(*normal).length();
                    assert!((length - 1.0).abs() < 1e-3, "normal length {length}");
                }
                assert!(o.transform.is_finite());
                assert!(o.material < scene.materials.len());
            }
            assert!(scene.camera.view.is_finite());
            assert!(scene.camera.near > 0.0 && scene.camera.fov_y > 0.0);
            assert!(scene.warnings.iter().all(|w| !w.contains('\n')));
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "multi-line error: {e}"),
    }
});
