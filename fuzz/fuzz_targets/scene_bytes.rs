//! Bytes to scene: the glTF/GLB loading path must return a scene or a
//! one-line error for any input, never panic, hang or read out of bounds.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match deferred_msaa_lab::scene::Scene::from_bytes(data, "fuzz-input") {
        Ok(scene) => {
            // Whatever loads is sane: finite data and indices in range.
            for o in &scene.objects {
                assert!(o.positions.iter().flatten().all(|v| v.is_finite()));
                assert!(o.indices.iter().all(|&i| (i as usize) < o.positions.len()));
            }
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "multi-line error: {e}"),
    }
});
