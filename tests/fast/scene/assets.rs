//! The real glTF assets, and the broken-file corpus (`assimp-testmodels`),
//! which must load or fail with one clear line, never panic.

use super::*;

fn find_model(dir: &Path) -> Option<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
        })
        .collect();
    found.sort();
    found.into_iter().next()
}

/// Load the model in `dir`, one of the repository's `assets/`: missing is a
/// failure, not a skip, since the models travel with the repository.
fn load_asset(dir: &Path) -> Scene {
    let path = find_model(dir).unwrap_or_else(|| panic!("no .gltf/.glb in {}", dir.display()));
    let start = std::time::Instant::now();
    let scene = load_path(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_sane(&scene);
    eprintln!(
        "{:<60} {:>7} triangles {:>4} objects {:>2} textures {:>2} lights {:>3} warnings, {:.0} ms",
        path.display(),
        scene.triangle_count(),
        scene.objects.len(),
        scene.textures.len(),
        scene.lights.len(),
        scene.warnings.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    for w in &scene.warnings {
        eprintln!("    warning: {w}");
    }
    scene
}

#[test]
fn box_asset_loads() {
    let scene = load_asset(&assets().join("Box"));
    assert_eq!(scene.triangle_count(), 12);
    assert_camera_sees_bounds(&scene);
}

#[test]
fn flight_helmet_asset_loads() {
    let scene = load_asset(&assets().join("FlightHelmet"));
    assert!(scene.has_textures(), "the helmet's base colour maps decode");
    assert!(scene.has_transparent() || scene.has_alpha_mask() || !scene.textures.is_empty());
    assert!(scene.triangle_count() > 10_000);
    assert_camera_sees_bounds(&scene);
}

#[test]
fn retro_ufo_asset_loads() {
    let scene = load_asset(&assets().join("RetroUFO"));
    assert!(scene.triangle_count() > 100);
}

#[test]
fn two_cylinder_engine_loads() {
    let path = Path::new(ASSIMP_GLTF2).join("2CylinderEngine-glTF-Binary");
    if !path.exists() {
        common::skip(&format!(
            "{} is absent (install assimp-testmodels)",
            path.display()
        ));
        return;
    }
    let scene = load_asset(&path);
    let n = scene.triangle_count();
    assert!(
        (100_000..150_000).contains(&n),
        "2CylinderEngine: {n} triangles"
    );
    assert_camera_sees_bounds(&scene);
}

// ---------------------------------------------------------------------------
// The broken-file corpus

fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            gltf_files(&path, out);
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
        {
            out.push(path);
        }
    }
}

#[test]
fn assimp_corpus_never_panics() {
    let root = Path::new(ASSIMP_GLTF2);
    if !root.exists() {
        common::skip(&format!(
            "{ASSIMP_GLTF2} is absent (install assimp-testmodels)"
        ));
        return;
    }
    let mut files = Vec::new();
    gltf_files(root, &mut files);
    files.sort();
    assert!(!files.is_empty());

    let mut panics = Vec::new();
    let mut bad_errors = Vec::new();
    let (mut loaded, mut failed) = (0, 0);
    eprintln!("{:<72} outcome", "file");
    for path in &files {
        let rel = path
            .strip_prefix(root)
            .unwrap_or(path)
            .display()
            .to_string();
        let outcome = catch_unwind(AssertUnwindSafe(|| load_path(path)));
        let line = match outcome {
            Err(_) => {
                panics.push(rel.clone());
                "PANIC".to_string()
            }
            Ok(Ok(scene)) => {
                loaded += 1;
                assert_sane(&scene);
                format!(
                    "ok: {} triangles, {} warnings{}",
                    scene.triangle_count(),
                    scene.warnings.len(),
                    scene
                        .warnings
                        .first()
                        .map(|w| format!(" (first: {w})"))
                        .unwrap_or_default()
                )
            }
            Ok(Err(e)) => {
                failed += 1;
                let msg = e.to_string();
                let name = path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                if msg.contains('\n') || !msg.contains(&name) {
                    bad_errors.push(format!("{rel}: {msg:?}"));
                }
                let reason = msg.split_once(": ").map_or(msg.as_str(), |(_, r)| r);
                format!("error: {reason}")
            }
        };
        eprintln!("{rel:<72} {line}");
    }
    eprintln!(
        "{} files: {loaded} loaded, {failed} refused, {} panicked",
        files.len(),
        panics.len()
    );
    assert!(panics.is_empty(), "panicked on {panics:?}");
    assert!(
        bad_errors.is_empty(),
        "errors not one line naming the file: {bad_errors:?}"
    );
}
