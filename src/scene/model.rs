//! The scene model: [`Scene`] and what it holds (objects, materials,
//! textures, lights, the background), and what it computes from them. The
//! loading ([`Scene::load`]) is in `scene/mod.rs`, beside the modules that
//! build scenes, so that they import the model without importing it.

use glam::{Mat4, Vec3};

use super::aabb::Aabb;
use super::bar::Bar;
use super::camera::Camera;

/// A scene ready to upload: geometry, materials, textures, lights, a camera.
#[derive(Debug, Clone)]
pub struct Scene {
    /// A short human-readable name (`greebles`, or the glTF file's stem).
    pub name: String,
    /// The drawable objects, each one triangle list with one material.
    pub objects: Vec<Object>,
    /// Materials, indexed by [`Object::material`].
    pub materials: Vec<Material>,
    /// Decoded textures, indexed by the materials' texture fields.
    pub textures: Vec<TextureData>,
    /// Punctual lights, in world space.
    pub lights: Vec<Light>,
    /// The camera to render from.
    pub camera: Camera,
    /// What is drawn where no geometry is.
    pub background: Background,
    /// Everything the loader repaired, dropped or ignored, one line each.
    pub warnings: Vec<String>,
    /// World-space bounds of all objects' vertices.
    pub bounds: Aabb,
    /// Thin bars whose drawn width the bench measures (its
    /// `bar_width_error_px`); empty for scenes that declare none.
    pub bars: Vec<Bar>,
}

/// One drawable: an indexed triangle list with a single material.
#[derive(Debug, Clone)]
pub struct Object {
    /// The glTF node/mesh name, or a descriptive name for built-ins.
    pub name: String,
    /// Model-space positions.
    pub positions: Vec<[f32; 3]>,
    /// Model-space unit normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates, one per position (glTF convention: (0, 0) is the
    /// first texel row of [`TextureData::rgba8`]).
    pub uvs: Vec<[f32; 2]>,
    /// Triangle list, three indices per triangle, all `< positions.len()`.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Model to world.
    pub transform: Mat4,
    /// Selective anti-aliasing: `false` asks the renderer to leave this object
    /// out of the depth-aware blend (glTF extras
    /// `{"deferred_msaa": {"antialias": false}}` on the node, an ancestor node
    /// or the mesh; the nearest setting wins, the mesh being nearest).
    pub antialias: bool,
}

/// A metallic-roughness material (glTF 2.0 core plus emissive strength).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The material's name (empty when the file has none).
    pub name: String,
    /// Linear RGBA base colour factor.
    pub base_color: [f32; 4],
    /// sRGB base colour texture, multiplied by [`Material::base_color`].
    pub base_color_texture: Option<usize>,
    /// Metalness, 0..1.
    pub metallic: f32,
    /// Perceptual roughness, 0..1.
    pub roughness: f32,
    /// Linear emitted radiance: the glTF emissive factor times
    /// `KHR_materials_emissive_strength` (HDR, may exceed 1).
    pub emissive: [f32; 3],
    /// sRGB emissive texture, multiplied by [`Material::emissive`].
    pub emissive_texture: Option<usize>,
    /// How alpha is interpreted.
    pub alpha_mode: AlphaMode,
    /// The cut-off for [`AlphaMode::Mask`] (glTF default 0.5).
    pub alpha_cutoff: f32,
    /// Whether back faces are drawn (and lit with the flipped normal).
    pub double_sided: bool,
}

impl Default for Material {
    /// glTF's default material: white, fully metallic, fully rough, opaque.
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: [1.0; 4],
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
        }
    }
}

impl Material {
    /// An opaque, untextured material.
    pub fn solid(name: &str, rgb: [f32; 3], metallic: f32, roughness: f32) -> Material {
        Material {
            name: name.to_string(),
            base_color: [rgb[0], rgb[1], rgb[2], 1.0],
            metallic,
            roughness,
            ..Material::default()
        }
    }

    /// True when the material emits light (a non-zero emissive factor).
    pub fn is_emissive(&self) -> bool {
        self.emissive.iter().any(|&e| e > 0.0)
    }
}

/// How a material's alpha is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Fragments with alpha below [`Material::alpha_cutoff`] are discarded.
    Mask,
    /// Alpha-blended: drawn in the forward transparent pass, not the G-buffer.
    Blend,
}

/// A decoded texture image.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureData {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height * 4` bytes, rows from the top of the image (the first
    /// row is glTF's v = 0: upload it first and sample with the glTF
    /// coordinates unchanged).
    pub rgba8: Vec<u8>,
    /// Whether the RGB channels are sRGB-encoded (colour textures are).
    pub srgb: bool,
}

/// The kind of a punctual light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Emits in all directions from [`Light::position`].
    Point,
    /// A cone along [`Light::direction`]; angles are half-angles in radians
    /// from the axis (full intensity inside `inner_cone`, none outside
    /// `outer_cone`).
    Spot {
        /// Where the fall-off begins.
        inner_cone: f32,
        /// Where the fall-off ends.
        outer_cone: f32,
    },
    /// Parallel light along [`Light::direction`]; the position is unused.
    Directional,
}

/// A punctual light in world space, with `KHR_lights_punctual` semantics:
/// a point or spot light gives irradiance `color * intensity / d²` at distance
/// `d` (intensity in candela), a directional light `color * intensity`
/// (intensity in lux).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Point, spot or directional.
    pub kind: LightKind,
    /// World-space position (unused by directional lights).
    pub position: Vec3,
    /// World-space unit vector the light points along (unused by point lights).
    pub direction: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Candela (point, spot) or lux (directional).
    pub intensity: f32,
    /// Distance beyond which a point or spot light contributes nothing
    /// (`None`: unlimited).
    pub range: Option<f32>,
}

impl Light {
    /// A point light.
    pub fn point(position: Vec3, color: Vec3, intensity: f32, range: Option<f32>) -> Light {
        Light {
            kind: LightKind::Point,
            position,
            direction: Vec3::NEG_Y,
            color,
            intensity,
            range,
        }
    }

    /// A directional light pointing along `direction` (normalised here).
    pub fn directional(direction: Vec3, color: Vec3, intensity: f32) -> Light {
        Light {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: direction.normalize_or(Vec3::NEG_Y),
            color,
            intensity,
            range: None,
        }
    }

    /// A spot light at `position` pointing along `direction` (normalised here).
    pub fn spot(
        position: Vec3,
        direction: Vec3,
        cones: (f32, f32),
        color: Vec3,
        intensity: f32,
        range: Option<f32>,
    ) -> Light {
        Light {
            kind: LightKind::Spot {
                inner_cone: cones.0,
                outer_cone: cones.1,
            },
            position,
            direction: direction.normalize_or(Vec3::NEG_Y),
            color,
            intensity,
            range,
        }
    }
}

/// What is drawn behind all geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Background {
    /// Plain black.
    Black,
    /// A vertical gradient, linear HDR RGB, drawn single-sampled: `horizon`
    /// at the view-space horizon (and below), blending to `zenith` straight up.
    Gradient {
        /// Colour straight up.
        zenith: [f32; 3],
        /// Colour at and below the horizon.
        horizon: [f32; 3],
    },
    /// A deterministic star field generated from `seed`.
    Stars {
        /// The star field's seed.
        seed: u32,
    },
}

impl Object {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// World-space bounds of the vertices the triangles use.
    pub fn world_bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &i in &self.indices {
            if let Some(p) = self.positions.get(i as usize) {
                b.extend(self.transform.transform_point3(Vec3::from(*p)));
            }
        }
        b
    }
}

impl Scene {
    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(Object::triangle_count).sum()
    }

    /// Total number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.positions.len()).sum()
    }

    /// The material an object uses (glTF's default material if the index is
    /// somehow out of range).
    pub fn material_of(&self, object: &Object) -> Material {
        self.materials
            .get(object.material)
            .cloned()
            .unwrap_or_default()
    }

    fn object_materials(&self) -> impl Iterator<Item = (&Object, Option<&Material>)> {
        self.objects
            .iter()
            .map(|o| (o, self.materials.get(o.material)))
    }

    /// True when some drawn object's material emits light, i.e. the emissive
    /// G-buffer attachment carries more than the background.
    pub fn has_emissive(&self) -> bool {
        self.object_materials()
            .any(|(_, m)| m.is_some_and(Material::is_emissive))
    }

    /// The largest emissive component of any drawn material (0 when none):
    /// tells whether the emissive attachment needs an HDR format.
    pub fn max_emissive(&self) -> f32 {
        self.object_materials()
            .filter_map(|(_, m)| m)
            .flat_map(|m| m.emissive)
            .fold(0.0, f32::max)
    }

    /// True when some object is alpha-blended ([`AlphaMode::Blend`]) and so
    /// needs the forward transparent pass.
    pub fn has_transparent(&self) -> bool {
        self.object_materials()
            .any(|(_, m)| m.is_some_and(|m| m.alpha_mode == AlphaMode::Blend))
    }

    /// True when some object is alpha-tested ([`AlphaMode::Mask`]).
    pub fn has_alpha_mask(&self) -> bool {
        self.object_materials()
            .any(|(_, m)| m.is_some_and(|m| m.alpha_mode == AlphaMode::Mask))
    }

    /// True when some drawn material samples a texture.
    pub fn has_textures(&self) -> bool {
        self.object_materials().any(|(_, m)| {
            m.is_some_and(|m| m.base_color_texture.is_some() || m.emissive_texture.is_some())
        })
    }

    /// True when some object opts out of anti-aliasing ([`Object::antialias`]).
    pub fn has_selective_aa(&self) -> bool {
        self.objects.iter().any(|o| !o.antialias)
    }

    /// `Some((metallic, roughness))` when every opaque or masked object's
    /// material has exactly the same metallic and roughness factors (`None`
    /// otherwise, or when there is no such object). With metallic 0 the
    /// specular response is then the same everywhere (F0 = 0.04, one gloss),
    /// so a plan may leave the specular attachment out; with metallic > 0 the
    /// specular colour still follows the base colour.
    pub fn uniform_specular(&self) -> Option<(f32, f32)> {
        let mut found: Option<(f32, f32)> = None;
        for (_, m) in self.object_materials() {
            let m = m.cloned().unwrap_or_default();
            if m.alpha_mode == AlphaMode::Blend {
                continue;
            }
            let mr = (m.metallic, m.roughness);
            match found {
                None => found = Some(mr),
                Some(f) if f.0.to_bits() == mr.0.to_bits() && f.1.to_bits() == mr.1.to_bits() => {}
                Some(_) => return None,
            }
        }
        found
    }

    /// The range of view-space distances (positive, in front of the camera)
    /// the scene's bounds cover: `(nearest, farthest)` over the box's
    /// corners, both clamped to at least the camera's near plane. With an
    /// empty scene, `(near, near)`.
    pub fn depth_range(&self) -> (f32, f32) {
        let near = self.camera.near;
        if self.bounds.is_empty() {
            return (near, near);
        }
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for c in self.bounds.corners() {
            let z = -self.camera.view.transform_point3(c).z;
            lo = lo.min(z);
            hi = hi.max(z);
        }
        (lo.max(near), hi.max(near))
    }

    /// A camera framing the scene's geometry from a 3/4 angle: aimed at the
    /// centre of [`Scene::bounds`] and fitted to every vertex, so the model
    /// fills the view (see [`Camera::frame_points`]).
    pub fn framing_camera(&self, fov_y: f32) -> Camera {
        let points = self.objects.iter().flat_map(|o| {
            o.indices.iter().filter_map(move |&i| {
                o.positions
                    .get(i as usize)
                    .map(|p| o.transform.transform_point3(Vec3::from(*p)))
            })
        });
        Camera::frame_points(&self.bounds, points, fov_y)
    }

    /// Recomputes [`Scene::bounds`] from the objects' vertices.
    pub fn recompute_bounds(&mut self) {
        self.bounds = self
            .objects
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(&o.world_bounds()));
    }
}

/// Keeps a warnings list readable: at most this many lines, then a summary.
const MAX_WARNINGS: usize = 40;

/// Collects load warnings, folding the excess into one final line.
#[derive(Debug, Default)]
pub(crate) struct Warnings {
    lines: Vec<String>,
    dropped: usize,
}

impl Warnings {
    pub(crate) fn push(&mut self, line: impl Into<String>) {
        let line = line.into();
        log::debug!("scene warning: {line}");
        if self.lines.len() < MAX_WARNINGS {
            self.lines.push(line);
        } else {
            self.dropped += 1;
        }
    }

    pub(crate) fn into_vec(mut self) -> Vec<String> {
        if self.dropped > 0 {
            self.lines
                .push(format!("… and {} more warnings", self.dropped));
        }
        self.lines
    }
}

/// A default light rig for a scene without lights, scaled to its bounds: a
/// warm key and a cool fill (directional) and two point lights beside the box.
pub(crate) fn default_lights(bounds: &Aabb) -> Vec<Light> {
    let c = bounds.center();
    let r = bounds.radius().max(1e-3);
    let point_intensity = (1.6 * r) * (1.6 * r) * 1.2;
    vec![
        Light::directional(
            Vec3::new(-0.45, -0.8, -0.4),
            Vec3::new(1.0, 0.95, 0.88),
            2.0,
        ),
        Light::directional(Vec3::new(0.6, -0.25, 0.75), Vec3::new(0.6, 0.7, 1.0), 0.5),
        Light::point(
            c + Vec3::new(1.2, 0.6, 0.9) * r,
            Vec3::new(1.0, 0.8, 0.6),
            point_intensity,
            Some(5.0 * r),
        ),
        Light::point(
            c + Vec3::new(-1.1, 0.35, -1.0) * r,
            Vec3::new(0.55, 0.75, 1.0),
            point_intensity,
            Some(5.0 * r),
        ),
    ]
}
