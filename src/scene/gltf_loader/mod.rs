//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`).
//!
//! The `gltf` crate parses the JSON into its unvalidated document, which the
//! loader readies for the crate's validation. Everything that touches bytes
//! from the file (the GLB container, buffers, URIs, accessors, images) is read
//! here with explicit bounds checks, so a damaged file yields an error or a
//! warning, never a panic; each place names the function of gltf 1.4.1 (the
//! version in the lock file) it stands in for and what that does instead.
//!
//! What is honoured: the default scene's node tree with its transforms, mesh
//! primitives in the triangle modes (strips and fans converted), positions,
//! normals (generated flat when missing), one texture-coordinate set,
//! metallic-roughness materials with base colour and emissive textures,
//! `KHR_materials_emissive_strength`, alpha modes, double-sidedness, the first
//! perspective camera and `KHR_lights_punctual` lights. Skins, morph targets,
//! animations and other extensions are ignored (with a warning where it shows).
//!
//! The modules, in the order a file passes through them: [`container`]
//! (GLB chunks, the JSON document), [`uri`] and [`buffers`] (the bytes the
//! document names), [`walk`] (the node tree, instancing, the assembled
//! scene), which uses [`primitives`] (over [`accessors`]), [`materials`]
//! (over [`images`]) and [`cameras_lights`].

mod accessors;
mod buffers;
mod cameras_lights;
mod container;
mod images;
mod materials;
mod primitives;
mod uri;
mod walk;

use std::path::Path;

use super::{Scene, Warnings};

/// Loads a glTF 2.0 file.
pub(crate) fn load(path: &Path) -> crate::Result<Scene> {
    load_inner(path).map_err(|reason| crate::Error::Scene {
        path: path.to_path_buf(),
        reason: one_line(&reason),
    })
}

/// Load a glTF or GLB held in memory. External files are refused: only
/// embedded (GLB or data-URI) buffers and images are read.
pub(crate) fn load_from_memory(bytes: &[u8], name: &str) -> crate::Result<Scene> {
    load_bytes(bytes, None, false, name.to_string()).map_err(|reason| crate::Error::Scene {
        path: name.into(),
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

fn load_bytes(
    bytes: &[u8],
    base: Option<&Path>,
    is_glb_name: bool,
    name: String,
) -> Result<Scene, String> {
    let (json, bin) = container::json_and_bin(bytes, is_glb_name)?;
    let (document, notes) = container::parse_document(json)?;
    let mut warnings = Warnings::default();
    for note in notes {
        warnings.push(note);
    }
    container::check_extensions(&document, &mut warnings);
    let buffers = buffers::load_buffers(&document, base, bin)?;

    let mut loader = walk::Loader::new(&document, base, &buffers, warnings);
    loader.walk_scene()?;
    loader.finish(name)
}
