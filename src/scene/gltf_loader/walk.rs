//! The scene walk: the default scene's node tree (depth, visits, cycles and
//! instanced triangles bounded), world transforms, the per-node and per-mesh
//! anti-aliasing setting in extras, mesh instances with their materials,
//! and the assembled [`Scene`] with a camera and lights when the file has
//! none.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::super::geometry::{self, Geometry};
use super::super::{Aabb, Background, Camera, Light, Object, Scene, Warnings, default_lights};
use super::cameras_lights;
use super::materials::Materials;
use super::primitives::{Built, build_primitive};

/// Deepest node nesting followed.
const MAX_NODE_DEPTH: usize = 256;

/// Most node visits (guards against a node DAG that multiplies instances).
const MAX_NODE_VISITS: usize = 200_000;

/// Most triangles instanced in total (node graphs can multiply a mesh).
const MAX_TRIANGLES: usize = 50_000_000;

/// Background for glTF scenes: a neutral dusk gradient, so silhouettes show.
const GLTF_BACKGROUND: Background = Background::Gradient {
    zenith: [0.05, 0.07, 0.12],
    horizon: [0.35, 0.38, 0.45],
};

/// Field of view used when the file has no usable camera.
const DEFAULT_FOV_Y: f32 = std::f32::consts::FRAC_PI_4;

/// The walk's state: what it has built so far and the limits it has hit.
pub(super) struct Loader<'a> {
    document: &'a gltf::Document,
    base: Option<&'a Path>,
    buffers: &'a [Vec<u8>],
    warnings: Warnings,
    materials: Materials,
    /// (mesh, primitive) → sanitised geometry (None: nothing drawable).
    geometry_cache: HashMap<(usize, usize), Option<Geometry>>,
    objects: Vec<Object>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    /// The first reason something was left out, for the "nothing to draw" error.
    first_skip: Option<String>,
    visits: usize,
    cycle_reported: bool,
    /// Triangles instanced so far.
    triangles: usize,
    triangle_cap_reported: bool,
}

/// The `{"deferred_msaa": {"antialias": bool}}` setting in an extras object.
fn antialias_extra(
    extras: &gltf::json::Extras,
    what: &str,
    warnings: &mut Warnings,
) -> Option<bool> {
    let raw = extras.as_ref()?;
    let value: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    let ours = value.get("deferred_msaa")?;
    match ours.get("antialias") {
        Some(serde_json::Value::Bool(b)) => Some(*b),
        Some(other) => {
            warnings.push(format!(
                "{what}: extras deferred_msaa.antialias is {other}, not a boolean; ignored"
            ));
            None
        }
        None => None,
    }
}

fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) if !n.is_empty() => format!("node '{n}'"),
        _ => format!("node {}", node.index()),
    }
}

fn mesh_label(mesh: &gltf::Mesh) -> String {
    match mesh.name() {
        Some(n) if !n.is_empty() => format!("mesh '{n}'"),
        _ => format!("mesh {}", mesh.index()),
    }
}

impl<'a> Loader<'a> {
    /// A walk over `document`, whose buffers are loaded; `base` is the
    /// folder of the file (`None` when loading from memory); `warnings`
    /// holds what was found before the walk.
    pub(super) fn new(
        document: &'a gltf::Document,
        base: Option<&'a Path>,
        buffers: &'a [Vec<u8>],
        warnings: Warnings,
    ) -> Self {
        Self {
            document,
            base,
            buffers,
            warnings,
            materials: Materials::default(),
            geometry_cache: HashMap::new(),
            objects: Vec::new(),
            lights: Vec::new(),
            camera: None,
            first_skip: None,
            visits: 0,
            cycle_reported: false,
            triangles: 0,
            triangle_cap_reported: false,
        }
    }

    fn skip(&mut self, line: String) {
        if self.first_skip.is_none() {
            self.first_skip = Some(line.clone());
        }
        self.warnings.push(line);
    }

    /// Walks the default scene (else the first, else the root nodes).
    pub(super) fn walk_scene(&mut self) -> Result<(), String> {
        let doc = self.document;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for node in doc.nodes() {
                    for child in node.children() {
                        if let Some(flag) = is_child.get_mut(child.index()) {
                            *flag = true;
                        }
                    }
                }
                let roots: Vec<gltf::Node> = doc
                    .nodes()
                    .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                    .collect();
                if !roots.is_empty() {
                    self.warnings.push(format!(
                        "the file defines no scene; drawing its {} root node(s)",
                        roots.len()
                    ));
                }
                roots
            }
        };
        let mut on_path = vec![false; doc.nodes().len()];
        for root in roots {
            self.visit(&root, Mat4::IDENTITY, true, 0, &mut on_path)?;
        }
        Ok(())
    }

    fn visit(
        &mut self,
        node: &gltf::Node,
        parent: Mat4,
        inherited_aa: bool,
        depth: usize,
        on_path: &mut [bool],
    ) -> Result<(), String> {
        self.visits += 1;
        if self.visits == MAX_NODE_VISITS {
            self.warnings.push(format!(
                "the node graph expands to more than {MAX_NODE_VISITS} nodes; the rest is left out"
            ));
        }
        if self.visits >= MAX_NODE_VISITS {
            return Ok(());
        }
        if depth >= MAX_NODE_DEPTH {
            self.warnings.push(format!(
                "{}: nested deeper than {MAX_NODE_DEPTH} levels; its subtree is left out",
                node_label(node)
            ));
            return Ok(());
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !local.is_finite() || !world.is_finite() {
            self.skip(format!(
                "{}: non-finite transform; the node and its subtree are left out",
                node_label(node)
            ));
            return Ok(());
        }
        let label = node_label(node);
        let aa = antialias_extra(node.extras(), &label, &mut self.warnings).unwrap_or(inherited_aa);

        if let Some(mesh) = node.mesh() {
            self.add_mesh(node, &mesh, world, aa)?;
        }
        if let Some(cam) = node.camera().filter(|_| self.camera.is_none()) {
            self.camera =
                cameras_lights::camera(self.document, &cam, world, &label, &mut self.warnings);
        }
        if let Some(light) = node.light() {
            if let Some(light) = cameras_lights::light(&light, world, &label, &mut self.warnings) {
                self.lights.push(light);
            }
        }

        if let Some(flag) = on_path.get_mut(node.index()) {
            *flag = true;
        }
        for child in node.children() {
            if on_path.get(child.index()).copied().unwrap_or(false) {
                if !self.cycle_reported {
                    self.cycle_reported = true;
                    self.warnings.push(format!(
                        "the node graph has a cycle ({} is its own ancestor); the repeated edge is ignored",
                        node_label(&child)
                    ));
                }
                continue;
            }
            self.visit(&child, world, aa, depth + 1, on_path)?;
        }
        if let Some(flag) = on_path.get_mut(node.index()) {
            *flag = false;
        }
        Ok(())
    }

    fn add_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
        node_aa: bool,
    ) -> Result<(), String> {
        let mlabel = mesh_label(mesh);
        let aa = antialias_extra(mesh.extras(), &mlabel, &mut self.warnings).unwrap_or(node_aa);
        let base_name = node
            .name()
            .filter(|n| !n.is_empty())
            .or(mesh.name().filter(|n| !n.is_empty()))
            .map(str::to_string)
            .unwrap_or_else(|| format!("node {}", node.index()));
        let primitive_count = mesh.primitives().len();
        let mirrored = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            let key = (mesh.index(), prim.index());
            if !self.geometry_cache.contains_key(&key) {
                let plabel = format!("{mlabel} primitive {}", prim.index());
                let g = match build_primitive(&prim, &plabel, self.buffers, &mut self.warnings)? {
                    Built::Drawable(g) => Some(g),
                    Built::Skipped(why) => {
                        self.skip(why);
                        None
                    }
                };
                self.geometry_cache.insert(key, g);
            }
            let Some(Some(g)) = self.geometry_cache.get(&key) else {
                continue;
            };
            let tris = g.indices.len() / 3;
            if self.triangles + tris > MAX_TRIANGLES {
                if !self.triangle_cap_reported {
                    self.triangle_cap_reported = true;
                    self.warnings.push(format!(
                        "more than {MAX_TRIANGLES} triangles instanced; further instances are left out"
                    ));
                }
                continue;
            }
            self.triangles += tris;
            let mut g = g.clone();
            if mirrored {
                geometry::flip_winding(&mut g.indices);
            }
            let material = self.materials.material(
                self.document,
                prim.material(),
                self.buffers,
                self.base,
                &mut self.warnings,
            );
            let name = if primitive_count > 1 {
                format!("{base_name}/{}", prim.index())
            } else {
                base_name.clone()
            };
            self.objects.push(Object {
                name,
                positions: g.positions,
                normals: g.normals,
                uvs: g.uvs,
                indices: g.indices,
                material,
                transform: world,
                antialias: aa,
            });
        }
        Ok(())
    }

    /// The scene named `name`, or an error naming why nothing is drawn.
    pub(super) fn finish(self, name: String) -> Result<Scene, String> {
        if self.objects.is_empty() {
            let meshes = self.document.meshes().len();
            return Err(match (self.first_skip, meshes) {
                (Some(first), _) => format!("no triangles to draw: {first}"),
                (None, 0) => "no triangles to draw: the file has no meshes".to_string(),
                (None, m) => format!(
                    "no triangles to draw: the file has {m} mesh(es) but its scene places none of them"
                ),
            });
        }
        let warnings = self.warnings;
        let (materials, textures) = self.materials.into_parts();
        let mut scene = Scene {
            name,
            objects: self.objects,
            materials,
            textures,
            lights: self.lights,
            camera: Camera::look_at(Vec3::Z, Vec3::ZERO, DEFAULT_FOV_Y, 0.1, None),
            background: GLTF_BACKGROUND,
            warnings: Vec::new(),
            bounds: Aabb::EMPTY,
            bars: Vec::new(),
        };
        scene.recompute_bounds();
        scene.camera = match self.camera {
            Some(c) => c,
            None => scene.framing_camera(DEFAULT_FOV_Y),
        };
        if scene.lights.is_empty() {
            scene.lights = default_lights(&scene.bounds);
        }
        // Vertices can each be finite and still span more than an f32 can
        // measure: the camera framing them (or the rig lighting them) then
        // overflows, and no depth range could hold them.
        let camera = &scene.camera;
        let measurable = (scene.bounds.max - scene.bounds.min).length().is_finite()
            && camera.view.is_finite()
            && camera.near.is_finite()
            && camera.far.is_none_or(f32::is_finite)
            && scene.lights.iter().all(|l| {
                l.position.is_finite() && l.direction.is_finite() && l.intensity.is_finite()
            });
        if !measurable {
            let (lo, hi) = (scene.bounds.min, scene.bounds.max);
            return Err(format!(
                "the scene spans [{}, {}, {}] to [{}, {}, {}], too far for single-precision floats to frame, light and depth-test",
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
            ));
        }
        scene.warnings = warnings.into_vec();
        Ok(scene)
    }
}
