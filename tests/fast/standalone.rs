//! The repository stands alone: no file reaches outside the checkout or
//! cites the retired specification, the models the tests load travel with
//! their licences, and every published package carries its README and both
//! licences.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every file of the checkout that git would track: the tree less the
/// build outputs and the fuzzer's working folders (as `.gitignore` says).
fn repository_files(dir: &Path, out: &mut Vec<PathBuf>) {
    const SKIPPED: &[&str] = &[
        ".git",
        "target",
        "fuzz/target",
        "fuzz/corpus",
        "fuzz/artifacts",
        "fuzz/coverage",
        "tests/golden/candidates",
        "report",
        "out",
    ];
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let relative = path.strip_prefix(root()).unwrap_or(&path);
        if SKIPPED.iter().any(|s| relative == Path::new(s)) {
            continue;
        }
        if path.is_dir() {
            repository_files(&path, out);
        } else {
            out.push(path);
        }
    }
}

#[test]
fn no_file_reaches_outside_the_repository() {
    // Spelled in pieces so that this file does not match itself.
    let outside = ["..", "/shared"].concat();
    let retired_spec = ["DESIGN", ".md"].concat();
    let mut files = Vec::new();
    repository_files(root(), &mut files);
    assert!(files.len() > 100, "only {} files found", files.len());
    let mut offenders = Vec::new();
    for path in &files {
        // Binary files (models, goldens, images) cannot name a path we wrote.
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        for (n, line) in text.lines().enumerate() {
            if line.contains(&outside) || line.contains(&retired_spec) {
                offenders.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
            }
        }
    }
    assert!(offenders.is_empty(), "{}", offenders.join("\n"));
}

#[test]
fn the_models_travel_with_their_licences() {
    let assets = root().join("assets");
    let mut models: Vec<PathBuf> = std::fs::read_dir(&assets)
        .expect("assets/ is in the repository")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    models.sort();
    assert!(models.len() >= 3, "{models:?}");
    for model in &models {
        for file in ["README.md", "LICENSE.txt"] {
            let path = model.join(file);
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(text.contains("icen"), "{} says no licence", path.display());
        }
    }
}

#[test]
fn every_published_package_has_its_readme_and_licences() {
    for dir in ["", "crates/core", "crates/headless", "crates/capi"] {
        let package = root().join(dir);
        for file in ["README.md", "LICENSE-MIT", "LICENSE-APACHE"] {
            let path = package.join(file);
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(!text.trim().is_empty(), "{} is empty", path.display());
        }
    }
    let apache = std::fs::read_to_string(root().join("LICENSE-APACHE")).expect("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0"));
    let mit = std::fs::read_to_string(root().join("LICENSE-MIT")).expect("LICENSE-MIT");
    assert!(mit.contains("Permission is hereby granted"));
}
