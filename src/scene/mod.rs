//! Scenes: the CPU-side scene model, the built-in test scenes and the glTF loader.
//!
//! Nothing here touches OpenGL: a [`Scene`] is plain data (triangle lists,
//! materials, decoded textures, lights, a camera) that the renderer uploads.
//!
//! A scene is named by a *spec* string, see [`Scene::load`]:
//! - `builtin:NAME` — one of the procedural scenes in [`Scene::builtin_names`]
//!   (`builtin:greebles` is the default, [`DEFAULT_SCENE`]);
//! - a path to a `.gltf` or `.glb` file (glTF 2.0).
//!
//! # Conventions
//! - Right-handed world, y up, metres (glTF's conventions); cameras look down
//!   their −z axis.
//! - Triangles are counter-clockwise seen from their front side **in world
//!   space**: when an object's transform mirrors (negative determinant) the
//!   loader has already swapped the winding, so the renderer can cull back faces
//!   with one global `glFrontFace(GL_CCW)`.
//! - Every [`Object`] has as many normals and texture coordinates as positions
//!   (coordinates are zero when the source has none); normals are unit length.
//! - All vertex data and transforms are finite, and every index is in range:
//!   the loader drops or repairs whatever is not, and says so in
//!   [`Scene::warnings`].

mod aabb;
mod bar;
mod builtin;
mod camera;
mod geometry;
mod gltf_loader;
mod model;
pub mod motion;

pub use aabb::Aabb;
pub use bar::{Bar, ImageBar};
pub use camera::Camera;
pub use model::{AlphaMode, Background, Light, LightKind, Material, Object, Scene, TextureData};
pub(crate) use model::{Warnings, default_lights};
pub use motion::{CameraPath, MotionSpec, PathKind};

/// The scene used when none is named.
pub const DEFAULT_SCENE: &str = "builtin:greebles";

impl Scene {
    /// Loads a scene from a spec: `builtin:NAME` (see [`Scene::builtin_names`])
    /// or a path to a glTF 2.0 file (`.gltf` with its buffers and images
    /// beside it, or `.glb`).
    ///
    /// Problems the loader can repair (bad vertices, out-of-range indices, a
    /// missing texture, unsupported primitive modes) become
    /// [`Scene::warnings`]; anything that leaves nothing to draw is an
    /// [`Error::Scene`](crate::Error::Scene) naming the file and the problem
    /// in one line.
    pub fn load(spec: &str) -> crate::Result<Scene> {
        if let Some(name) = spec.strip_prefix("builtin:") {
            return builtin::build(name).ok_or_else(|| crate::Error::Scene {
                path: spec.into(),
                reason: format!(
                    "no built-in scene named `{name}`; the built-ins are {}",
                    Self::builtin_names().join(", ")
                ),
            });
        }
        let path = std::path::Path::new(spec);
        if !path.exists() && Self::builtin_names().contains(&spec) {
            return Err(crate::Error::Scene {
                path: spec.into(),
                reason: format!("no such file; did you mean `builtin:{spec}`?"),
            });
        }
        gltf_loader::load(path)
    }

    /// Load a glTF (JSON) or GLB file held in memory; `name` labels errors.
    /// Only embedded data is read: references to external files are refused.
    pub fn from_bytes(bytes: &[u8], name: &str) -> crate::Result<Scene> {
        gltf_loader::load_from_memory(bytes, name)
    }

    /// The names accepted after `builtin:`, the default (`greebles`) first.
    pub fn builtin_names() -> &'static [&'static str] {
        builtin::NAMES
    }
}
