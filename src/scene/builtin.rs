//! Procedural built-in scenes, each a small, deterministic case of what
//! depth-aware MSAA is about. Sizes are chosen so the models fill a good part
//! of a 16:9 view.
//!
//! | name          | what it exercises |
//! |---------------|-------------------|
//! | `greebles`    | the paper's case: a hull covered in small raised boxes, trenches and thin antennas, lit by coloured point lights close to the surface — averaging positions across depth edges lights the edges wrongly (halos) |
//! | `box`         | a cube on a plane, one directional light: the simplest scene |
//! | `thin`        | wires, rods and sliver triangles against a bright HDR sky: sub-pixel geometry |
//! | `zfight`      | coplanar overlapping panels (z-fighting) and degenerate triangles |
//! | `emissive`    | glowing panels and lamps (HDR emissive up to 300) beside plain models |
//! | `far`         | a detailed model 200 km away through a 0.5° lens with near = 0.01: past FP16 positions and D24 depth |
//! | `transparent` | opaque models behind alpha-blended panes, and an alpha-tested grille |
//! | `hull`        | FreeSpace Open's case: a hull filling the view, covered in detail close to it in depth (plates and seams, painted strips, pipes, low greebles), coloured point lights, dark space |
//! | `halo`        | the paper's Figure 4: point lights just behind a box's edges, a far wall out of their range; averaging positions across the edge lights it |
//! | `lamps`       | the deferred tutorial's picture: boxes lit by a dozen coloured point lights, each light shown as a small bright cube drawn forward after lighting (a blended material), over a dark floor and black sky: forward silhouettes the G-buffer never sees |
//! | `slats`       | thin bright boxes seen at an angle (their side faces sub-pixel slivers) in front of a dark, unlit wall 190 units behind: pixels of three surfaces (front face, side sliver, wall), and in motion a background that barely moves while the slats pass over it |
//! | `bars`        | thin silhouettes: bright slanted bars 1.3 to 3.4 pixels wide at 640x360 in front of a dark far wall, beside a plate of shallow ridges (creases: close in depth, different normals); the scene declares the bars, so the bench measures how wide each method draws them |

use glam::{Mat4, Quat, Vec3};

use super::geometry::{Geometry, face_normal};
use super::{
    AlphaMode, Background, Bar, Camera, Light, Material, Object, Scene, TextureData,
    camera::look_at,
};

/// The built-in names, the default first.
pub(crate) const NAMES: &[&str] = &[
    "greebles",
    "box",
    "thin",
    "zfight",
    "emissive",
    "far",
    "transparent",
    "hull",
    "halo",
    "bars",
    "ridges",
    "lamps",
    "slats",
];

/// Builds the built-in scene `name`, or `None` when there is none so named.
pub(crate) fn build(name: &str) -> Option<Scene> {
    let scene = match name {
        "greebles" => greebles(),
        "box" => box_scene(),
        "thin" => thin(),
        "zfight" => zfight(),
        "emissive" => emissive(),
        "far" => far(),
        "transparent" => transparent(),
        "hull" => hull(),
        "halo" => halo(),
        "bars" => bars(),
        "ridges" => ridges(),
        "lamps" => lamps(),
        "slats" => slats(),
        _ => return None,
    };
    Some(scene)
}

// ---------------------------------------------------------------------------
// Tools

/// SplitMix64: tiny, deterministic on every platform.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }
}

/// Accumulates triangles with per-vertex normals and coordinates.
#[derive(Default)]
struct MeshBuilder {
    g: Geometry,
}

impl MeshBuilder {
    fn vertex(&mut self, p: Vec3, n: Vec3, uv: [f32; 2]) -> u32 {
        let i = self.g.positions.len() as u32;
        self.g.positions.push(p.to_array());
        self.g.normals.push(n.normalize_or(Vec3::Z).to_array());
        self.g.uvs.push(uv);
        i
    }

    /// A flat quad; `c` counter-clockwise seen from the front.
    fn quad_uv(&mut self, c: [Vec3; 4], uv: [[f32; 2]; 4]) {
        let n = face_normal(c[0], c[1], c[2]).normalize_or(Vec3::Z);
        let i: Vec<u32> = c
            .iter()
            .zip(uv)
            .map(|(&p, uv)| self.vertex(p, n, uv))
            .collect();
        self.g
            .indices
            .extend_from_slice(&[i[0], i[1], i[2], i[0], i[2], i[3]]);
    }

    fn quad(&mut self, c: [Vec3; 4]) {
        self.quad_uv(c, [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
    }

    /// A single triangle with an explicit normal (degenerate ones included).
    fn triangle(&mut self, p: [Vec3; 3], n: Vec3) {
        for v in p {
            let i = self.vertex(v, n, [0.0, 0.0]);
            self.g.indices.push(i);
        }
    }

    /// A box: `half` extents along the rotated axes.
    fn cuboid(&mut self, center: Vec3, half: Vec3, rot: Quat) {
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        let h = half.to_array();
        for k in 0..3 {
            for sign in [1.0f32, -1.0] {
                let n = axes[k] * sign;
                let (mut u, mut v) = (axes[(k + 1) % 3], axes[(k + 2) % 3]);
                let (mut hu, mut hv) = (h[(k + 1) % 3], h[(k + 2) % 3]);
                if sign < 0.0 {
                    std::mem::swap(&mut u, &mut v);
                    std::mem::swap(&mut hu, &mut hv);
                }
                let f = n * h[k];
                let corner = |a: f32, b: f32| center + rot * (f + u * (a * hu) + v * (b * hv));
                self.quad([
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ]);
            }
        }
    }

    /// An axis-aligned box from its two corners.
    fn aabox(&mut self, min: Vec3, max: Vec3) {
        self.cuboid((min + max) * 0.5, (max - min) * 0.5, Quat::IDENTITY);
    }

    /// A cylinder from `a` to `b`, smooth sides, optional flat caps.
    fn cylinder(&mut self, a: Vec3, b: Vec3, radius: f32, segments: u32, caps: bool) {
        let axis = (b - a).normalize_or(Vec3::Y);
        let (p, q) = axis.any_orthonormal_pair();
        let segments = segments.max(3);
        let ring = |k: u32| {
            let t = k as f32 / segments as f32 * std::f32::consts::TAU;
            p * t.cos() + q * t.sin()
        };
        for k in 0..segments {
            let (d0, d1) = (ring(k), ring(k + 1));
            let (u0, u1) = (k as f32 / segments as f32, (k + 1) as f32 / segments as f32);
            let i0 = self.vertex(a + d0 * radius, d0, [u0, 1.0]);
            let i1 = self.vertex(a + d1 * radius, d1, [u1, 1.0]);
            let i2 = self.vertex(b + d1 * radius, d1, [u1, 0.0]);
            let i3 = self.vertex(b + d0 * radius, d0, [u0, 0.0]);
            self.g.indices.extend_from_slice(&[i0, i1, i2, i0, i2, i3]);
        }
        if caps {
            for (center, n) in [(b, axis), (a, -axis)] {
                let c = self.vertex(center, n, [0.5, 0.5]);
                for k in 0..segments {
                    let (d0, d1) = (ring(k), ring(k + 1));
                    let i0 = self.vertex(center + d0 * radius, n, [0.5, 0.5]);
                    let i1 = self.vertex(center + d1 * radius, n, [0.5, 0.5]);
                    if n.dot(axis) > 0.0 {
                        self.g.indices.extend_from_slice(&[c, i0, i1]);
                    } else {
                        self.g.indices.extend_from_slice(&[c, i1, i0]);
                    }
                }
            }
        }
    }

    /// A UV sphere (no zero-area triangles at the poles).
    fn sphere(&mut self, center: Vec3, radius: f32, rings: u32, segments: u32) {
        let (rings, segments) = (rings.max(2), segments.max(3));
        let base = self.g.positions.len() as u32;
        for i in 0..=rings {
            let theta = i as f32 / rings as f32 * std::f32::consts::PI;
            for j in 0..=segments {
                let phi = j as f32 / segments as f32 * std::f32::consts::TAU;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                );
                let uv = [j as f32 / segments as f32, i as f32 / rings as f32];
                self.vertex(center + d * radius, d, uv);
            }
        }
        let at = |i: u32, j: u32| base + i * (segments + 1) + j;
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                if i + 1 < rings {
                    self.g.indices.extend_from_slice(&[a, b, c]);
                }
                if i > 0 {
                    self.g.indices.extend_from_slice(&[a, c, d]);
                }
            }
        }
    }

    fn is_empty(&self) -> bool {
        self.g.indices.is_empty()
    }
}

/// Collects objects and materials, then finishes a [`Scene`].
struct SceneBuilder {
    name: &'static str,
    objects: Vec<Object>,
    materials: Vec<Material>,
    textures: Vec<TextureData>,
    lights: Vec<Light>,
    bars: Vec<Bar>,
}

impl SceneBuilder {
    fn new(name: &'static str) -> Self {
        SceneBuilder {
            name,
            objects: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            lights: Vec::new(),
            bars: Vec::new(),
        }
    }

    fn material(&mut self, m: Material) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    fn object(&mut self, name: &str, mesh: MeshBuilder, material: usize, transform: Mat4) {
        if mesh.is_empty() {
            return;
        }
        let Geometry {
            positions,
            normals,
            uvs,
            indices,
        } = mesh.g;
        self.objects.push(Object {
            name: name.to_string(),
            positions,
            normals,
            uvs,
            indices,
            material,
            transform,
            antialias: true,
        });
    }

    /// Finishes the scene; `camera` gets the scene with its bounds computed.
    fn finish(self, background: Background, camera: impl FnOnce(&Scene) -> Camera) -> Scene {
        let mut scene = Scene {
            name: self.name.to_string(),
            objects: self.objects,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            camera: Camera::look_at(Vec3::Z, Vec3::ZERO, 1.0, 0.1, None),
            background,
            warnings: Vec::new(),
            bounds: super::Aabb::EMPTY,
            bars: self.bars,
        };
        scene.recompute_bounds();
        scene.camera = camera(&scene);
        scene
    }
}

fn rgb(r: f32, g: f32, b: f32) -> Vec3 {
    Vec3::new(r, g, b)
}

fn emissive_material(name: &str, base: [f32; 3], emissive: [f32; 3]) -> Material {
    Material {
        emissive,
        ..Material::solid(name, base, 0.0, 0.6)
    }
}

// ---------------------------------------------------------------------------
// The greeble ship, shared by `greebles` and `far`

/// The ship's parts, in ship space: about 12.6 long (x), 2.4 tall, 2 wide.
struct Ship {
    hull: MeshBuilder,
    plates: MeshBuilder,
    dark: MeshBuilder,
    antennas: MeshBuilder,
    glow: MeshBuilder,
}

/// A surface patch greebles are scattered on: `origin + u*s + v*t`, s and t
/// in 0..1, raised along `normal`.
struct Patch {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    normal: Vec3,
    count: u32,
    max_height: f32,
}

fn greeble_ship(seed: u64) -> Ship {
    let mut rng = Rng(seed);
    let mut hull = MeshBuilder::default();
    // Upper and lower hull with a recessed band between them: a trench along
    // each side.
    hull.aabox(Vec3::new(-5.0, 0.15, -1.0), Vec3::new(5.0, 0.6, 1.0));
    hull.aabox(Vec3::new(-5.0, -0.15, -0.82), Vec3::new(5.0, 0.15, 0.82));
    hull.aabox(Vec3::new(-5.0, -0.6, -1.0), Vec3::new(5.0, -0.15, 1.0));
    // Two raised decks with a trench between them (floor at y = 0.6).
    hull.aabox(Vec3::new(-3.5, 0.6, 0.15), Vec3::new(2.5, 1.1, 0.69));
    hull.aabox(Vec3::new(-3.5, 0.6, -0.69), Vec3::new(2.5, 1.1, -0.15));
    // Bridge spanning the trench, and its roof.
    hull.aabox(Vec3::new(-3.3, 1.1, -0.45), Vec3::new(-1.9, 1.8, 0.45));
    hull.aabox(Vec3::new(-3.1, 1.8, -0.3), Vec3::new(-2.4, 2.0, 0.3));
    // Nose.
    hull.aabox(Vec3::new(5.0, -0.3, -0.7), Vec3::new(6.2, 0.5, 0.7));
    hull.aabox(Vec3::new(6.2, -0.15, -0.4), Vec3::new(6.5, 0.35, 0.4));

    let mut dark = MeshBuilder::default();
    let mut glow = MeshBuilder::default();
    for (y, z) in [(0.1, -0.55), (0.1, 0.55), (-0.3, 0.0)] {
        dark.cylinder(Vec3::new(-5.0, y, z), Vec3::new(-6.0, y, z), 0.32, 20, true);
        glow.cylinder(
            Vec3::new(-6.0, y, z),
            Vec3::new(-6.03, y, z),
            0.25,
            20,
            true,
        );
    }
    // Pipes along the side trenches.
    for side in [1.0f32, -1.0] {
        for (y, r) in [(0.07, 0.045), (-0.06, 0.035)] {
            dark.cylinder(
                Vec3::new(-4.8, y, 0.82 * side + r * side),
                Vec3::new(4.8, y, 0.82 * side + r * side),
                r,
                8,
                true,
            );
        }
    }

    let patches = [
        // Deck tops, both sides of the trench.
        Patch {
            origin: Vec3::new(-3.4, 1.1, 0.17),
            u: Vec3::X * 5.8,
            v: Vec3::Z * 0.5,
            normal: Vec3::Y,
            count: 32,
            max_height: 0.22,
        },
        Patch {
            origin: Vec3::new(-3.4, 1.1, -0.67),
            u: Vec3::X * 5.8,
            v: Vec3::Z * 0.5,
            normal: Vec3::Y,
            count: 32,
            max_height: 0.22,
        },
        // The trench floor: detail deep between the decks.
        Patch {
            origin: Vec3::new(-3.4, 0.6, -0.13),
            u: Vec3::X * 5.8,
            v: Vec3::Z * 0.26,
            normal: Vec3::Y,
            count: 26,
            max_height: 0.2,
        },
        // Exposed hull top, fore and aft of the decks.
        Patch {
            origin: Vec3::new(2.6, 0.6, -0.95),
            u: Vec3::X * 2.3,
            v: Vec3::Z * 1.9,
            normal: Vec3::Y,
            count: 26,
            max_height: 0.3,
        },
        Patch {
            origin: Vec3::new(-4.9, 0.6, -0.95),
            u: Vec3::X * 1.3,
            v: Vec3::Z * 1.9,
            normal: Vec3::Y,
            count: 14,
            max_height: 0.3,
        },
        // Sides, above and below the side trenches.
        Patch {
            origin: Vec3::new(-4.9, 0.2, 1.0),
            u: Vec3::X * 9.8,
            v: Vec3::Y * 0.35,
            normal: Vec3::Z,
            count: 22,
            max_height: 0.15,
        },
        Patch {
            origin: Vec3::new(-4.9, -0.55, 1.0),
            u: Vec3::X * 9.8,
            v: Vec3::Y * 0.35,
            normal: Vec3::Z,
            count: 12,
            max_height: 0.12,
        },
        Patch {
            origin: Vec3::new(-4.9, 0.2, -1.0),
            u: Vec3::X * 9.8,
            v: Vec3::Y * 0.35,
            normal: Vec3::NEG_Z,
            count: 18,
            max_height: 0.15,
        },
        // Nose top.
        Patch {
            origin: Vec3::new(5.1, 0.5, -0.6),
            u: Vec3::X * 1.0,
            v: Vec3::Z * 1.2,
            normal: Vec3::Y,
            count: 8,
            max_height: 0.12,
        },
    ];

    let mut plates = MeshBuilder::default();
    for patch in &patches {
        let (ul, vl) = (patch.u.length(), patch.v.length());
        let (ud, vd) = (patch.u / ul, patch.v / vl);
        for _ in 0..patch.count {
            let a = rng.range(0.05, 0.4).min(ul * 0.5);
            let b = rng.range(0.05, 0.3).min(vl * 0.9);
            let h = rng.range(0.02, patch.max_height);
            let s = rng.range(a * 0.5 / ul, 1.0 - a * 0.5 / ul);
            let t = rng.range(b * 0.5 / vl, 1.0 - b * 0.5 / vl);
            let base = patch.origin + patch.u * s + patch.v * t;
            let target = if rng.chance(0.35) {
                &mut dark
            } else {
                &mut plates
            };
            greeble_box(target, base, ud * a, vd * b, patch.normal * h);
            // Sometimes a smaller block on top: one more depth level.
            if rng.chance(0.3) {
                let top = base + patch.normal * h;
                let (a2, b2) = (a * rng.range(0.3, 0.7), b * rng.range(0.3, 0.7));
                greeble_box(
                    &mut plates,
                    top,
                    ud * a2,
                    vd * b2,
                    patch.normal * rng.range(0.02, patch.max_height * 0.6),
                );
            }
        }
    }

    // Thin antennas: a fraction of a pixel to a few pixels wide.
    let mut antennas = MeshBuilder::default();
    let masts: [(Vec3, f32, f32, Vec3); 8] = [
        (
            Vec3::new(-2.9, 2.0, 0.1),
            1.4,
            0.014,
            Vec3::new(0.05, 1.0, 0.0),
        ),
        (
            Vec3::new(-2.6, 2.0, -0.15),
            0.9,
            0.022,
            Vec3::new(-0.1, 1.0, 0.05),
        ),
        (
            Vec3::new(0.6, 1.1, 0.55),
            0.8,
            0.009,
            Vec3::new(0.0, 1.0, 0.15),
        ),
        (
            Vec3::new(1.6, 1.1, -0.45),
            0.7,
            0.016,
            Vec3::new(0.1, 1.0, -0.1),
        ),
        (
            Vec3::new(3.6, 0.6, 0.7),
            0.65,
            0.008,
            Vec3::new(0.2, 1.0, 0.3),
        ),
        (
            Vec3::new(-4.2, 0.6, -0.7),
            1.0,
            0.011,
            Vec3::new(-0.15, 1.0, -0.1),
        ),
        (
            Vec3::new(-4.5, 0.6, 0.75),
            0.75,
            0.007,
            Vec3::new(-0.3, 1.0, 0.25),
        ),
        (
            Vec3::new(5.6, 0.5, 0.3),
            0.5,
            0.012,
            Vec3::new(0.6, 1.0, 0.0),
        ),
    ];
    for (foot, length, radius, dir) in masts {
        let tip = foot + dir.normalize() * length;
        antennas.cylinder(foot, tip, radius, 6, true);
        antennas.cuboid(tip, Vec3::splat(radius * 2.2), Quat::IDENTITY);
    }
    // A cross-bar on the tallest mast.
    let bar = Vec3::new(-2.9, 2.0, 0.1) + Vec3::new(0.05, 1.0, 0.0).normalize() * 1.1;
    antennas.cylinder(bar - Vec3::Z * 0.35, bar + Vec3::Z * 0.35, 0.008, 6, true);

    Ship {
        hull,
        plates,
        dark,
        antennas,
        glow,
    }
}

/// A box standing on `base` with edges `u`, `v` (along the surface) and
/// height vector `h`: all three are axis-aligned in the ship.
fn greeble_box(mesh: &mut MeshBuilder, base: Vec3, u: Vec3, v: Vec3, h: Vec3) {
    let lo = base - u * 0.5 - v * 0.5;
    let hi = base + u * 0.5 + v * 0.5 + h;
    mesh.aabox(lo.min(hi), lo.max(hi));
}

/// Adds the ship's parts with their materials.
fn add_ship(sb: &mut SceneBuilder, ship: Ship, transform: Mat4) {
    let hull = sb.material(Material::solid("hull", [0.55, 0.57, 0.6], 0.3, 0.45));
    let plates = sb.material(Material::solid("plates", [0.62, 0.5, 0.36], 0.1, 0.55));
    let dark = sb.material(Material::solid("dark metal", [0.2, 0.21, 0.23], 0.6, 0.35));
    let antenna = sb.material(Material::solid("antenna", [0.85, 0.85, 0.88], 0.8, 0.25));
    let glow = sb.material(emissive_material(
        "engine glow",
        [0.1, 0.1, 0.1],
        [6.0, 3.5, 1.5],
    ));
    sb.object("hull", ship.hull, hull, transform);
    sb.object("greebles", ship.plates, plates, transform);
    sb.object("dark greebles", ship.dark, dark, transform);
    sb.object("antennas", ship.antennas, antenna, transform);
    sb.object("engine glow", ship.glow, glow, transform);
}

/// Coloured point lights close to the hull, in ship space:
/// (position, colour, intensity, range).
const SHIP_LIGHTS: [([f32; 3], [f32; 3], f32, f32); 5] = [
    ([0.8, 1.6, 0.0], [1.0, 0.6, 0.25], 0.8, 3.0),
    ([-1.2, 1.55, 0.95], [0.3, 0.8, 1.0], 0.7, 2.5),
    ([3.6, 1.05, 0.4], [1.0, 0.3, 0.7], 0.6, 2.5),
    ([-4.0, 0.0, 1.35], [0.4, 1.0, 0.45], 0.5, 2.0),
    ([2.0, 0.1, 1.45], [1.0, 0.9, 0.75], 0.6, 2.5),
];

/// The ship's lights under a uniform `scale` (irradiance kept: intensity
/// grows with the square of the scale).
fn ship_lights(transform: Mat4, scale: f32) -> Vec<Light> {
    let mut lights: Vec<Light> = SHIP_LIGHTS
        .iter()
        .map(|&(p, c, i, r)| {
            Light::point(
                transform.transform_point3(Vec3::from(p)),
                Vec3::from(c),
                i * scale * scale,
                Some(r * scale),
            )
        })
        .collect();
    lights.push(Light::directional(
        Vec3::new(-0.3, -1.0, -0.5),
        rgb(0.9, 0.92, 1.0),
        0.6,
    ));
    lights.push(Light::directional(
        Vec3::new(0.7, -0.2, 0.6),
        rgb(0.5, 0.55, 0.8),
        0.2,
    ));
    lights
}

// ---------------------------------------------------------------------------
// The scenes

fn greebles() -> Scene {
    let mut sb = SceneBuilder::new("greebles");
    add_ship(&mut sb, greeble_ship(0x5EED_0001), Mat4::IDENTITY);
    sb.lights = ship_lights(Mat4::IDENTITY, 1.0);
    sb.finish(
        Background::Gradient {
            zenith: [0.02, 0.03, 0.08],
            horizon: [0.25, 0.3, 0.4],
        },
        |s| s.framing_camera(40f32.to_radians()),
    )
}

fn box_scene() -> Scene {
    let mut sb = SceneBuilder::new("box");
    let red = sb.material(Material::solid("cube", [0.8, 0.2, 0.15], 0.0, 0.5));
    let grey = sb.material(Material::solid("ground", [0.6, 0.6, 0.6], 0.0, 0.8));
    let mut cube = MeshBuilder::default();
    cube.aabox(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
    let mut ground = MeshBuilder::default();
    let s = 8.0;
    ground.quad([
        Vec3::new(-s, 0.0, s),
        Vec3::new(s, 0.0, s),
        Vec3::new(s, 0.0, -s),
        Vec3::new(-s, 0.0, -s),
    ]);
    sb.object("cube", cube, red, Mat4::IDENTITY);
    sb.object("ground", ground, grey, Mat4::IDENTITY);
    sb.lights.push(Light::directional(
        Vec3::new(-0.4, -1.0, -0.3),
        Vec3::ONE,
        3.0,
    ));
    sb.finish(
        Background::Gradient {
            zenith: [0.1, 0.2, 0.45],
            horizon: [0.55, 0.6, 0.7],
        },
        |_| {
            Camera::look_at(
                Vec3::new(4.2, 3.0, 5.6),
                Vec3::new(0.0, 0.9, 0.0),
                40f32.to_radians(),
                0.1,
                Some(100.0),
            )
        },
    )
}

fn thin() -> Scene {
    let mut sb = SceneBuilder::new("thin");
    let wire_mat = sb.material(Material::solid("wire", [0.06, 0.06, 0.07], 0.7, 0.4));
    let post_mat = sb.material(Material::solid("post", [0.3, 0.24, 0.18], 0.0, 0.7));
    let sliver_mat = sb.material(Material {
        double_sided: true,
        ..Material::solid("slivers", [0.15, 0.3, 0.1], 0.0, 0.6)
    });

    // A fence: posts, five rows of wires of decreasing gauge, X bracing.
    let mut posts = MeshBuilder::default();
    let mut wires = MeshBuilder::default();
    let xs = [-4.0f32, -2.0, 0.0, 2.0, 4.0];
    for &x in &xs {
        posts.cylinder(
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x, 2.1, 0.0),
            0.04,
            10,
            true,
        );
    }
    for (row, radius) in [0.012f32, 0.009, 0.006, 0.004, 0.003].iter().enumerate() {
        let y = 0.4 + row as f32 * 0.4;
        wires.cylinder(
            Vec3::new(xs[0], y, 0.03),
            Vec3::new(xs[4], y, 0.03),
            *radius,
            6,
            false,
        );
    }
    for pair in xs.windows(2) {
        let (x0, x1) = (pair[0], pair[1]);
        wires.cylinder(
            Vec3::new(x0, 0.2, 0.05),
            Vec3::new(x1, 2.0, 0.05),
            0.005,
            5,
            false,
        );
        wires.cylinder(
            Vec3::new(x0, 2.0, 0.06),
            Vec3::new(x1, 0.2, 0.06),
            0.0035,
            5,
            false,
        );
    }

    // An antenna mast behind, with cross-bars and guy wires.
    let (foot, top) = (Vec3::new(2.3, 0.0, -3.0), Vec3::new(2.3, 4.2, -3.0));
    posts.cylinder(foot, top, 0.03, 8, true);
    for k in 0..4 {
        let y = 2.8 + k as f32 * 0.35;
        let half = 0.7 - k as f32 * 0.12;
        wires.cylinder(
            Vec3::new(2.3 - half, y, -3.0),
            Vec3::new(2.3 + half, y, -3.0),
            0.008,
            6,
            true,
        );
    }
    for anchor in [
        Vec3::new(0.3, 0.0, -1.8),
        Vec3::new(4.6, 0.0, -2.2),
        Vec3::new(2.0, 0.0, -6.0),
    ] {
        wires.cylinder(top - Vec3::Y * 0.2, anchor, 0.004, 5, false);
    }

    // A fan of sliver triangles: each well under a pixel wide.
    let mut slivers = MeshBuilder::default();
    let root = Vec3::new(-2.9, 0.0, 1.2);
    for k in 0..14 {
        let angle = (k as f32 - 6.5) * 0.07;
        let dir = Vec3::new(angle.sin(), angle.cos(), 0.0);
        let side = Vec3::new(dir.y, -dir.x, 0.0) * 0.002;
        let tip = root + dir * (1.4 + 0.05 * (k % 3) as f32);
        let n = Vec3::Z;
        slivers.triangle([root, tip + side, tip - side], n);
    }
    // Grass-like blades: long thin quads, some a fraction of a pixel wide.
    let mut rng = Rng(0x7417);
    for k in 0..24 {
        let x = -1.6 + k as f32 * 0.12 + rng.range(-0.03, 0.03);
        let h = rng.range(0.5, 1.1);
        let w = rng.range(0.002, 0.01);
        let lean = rng.range(-0.15, 0.15);
        let z = 1.0 + rng.range(-0.1, 0.1);
        slivers.quad([
            Vec3::new(x - w, 0.0, z),
            Vec3::new(x + w, 0.0, z),
            Vec3::new(x + lean + w * 0.2, h, z),
            Vec3::new(x + lean - w * 0.2, h, z),
        ]);
    }

    sb.object("posts", posts, post_mat, Mat4::IDENTITY);
    sb.object("wires", wires, wire_mat, Mat4::IDENTITY);
    sb.object("slivers", slivers, sliver_mat, Mat4::IDENTITY);
    sb.lights.push(Light::directional(
        Vec3::new(-0.3, -1.0, -0.6),
        rgb(1.0, 0.97, 0.9),
        2.5,
    ));
    sb.lights.push(Light::directional(
        Vec3::new(0.4, -0.3, 0.8),
        rgb(0.6, 0.7, 1.0),
        0.6,
    ));
    sb.finish(
        Background::Gradient {
            zenith: [1.2, 1.45, 1.9],
            horizon: [2.6, 2.45, 2.2],
        },
        |_| {
            Camera::look_at(
                Vec3::new(0.6, 1.2, 6.3),
                Vec3::new(0.0, 1.5, -1.0),
                45f32.to_radians(),
                0.05,
                Some(60.0),
            )
        },
    )
}

fn zfight() -> Scene {
    let mut sb = SceneBuilder::new("zfight");
    let colours: [(&str, [f32; 3]); 5] = [
        ("wall", [0.2, 0.3, 0.75]),
        ("red panel", [0.85, 0.15, 0.1]),
        ("green panel", [0.15, 0.7, 0.2]),
        ("yellow panel", [0.9, 0.8, 0.1]),
        ("white panel", [0.9, 0.9, 0.9]),
    ];
    let mats: Vec<usize> = colours
        .iter()
        .map(|(n, c)| sb.material(Material::solid(n, *c, 0.0, 0.5)))
        .collect();
    let rect = |x0: f32, y0: f32, x1: f32, y1: f32, z: f32| {
        let mut m = MeshBuilder::default();
        m.quad([
            Vec3::new(x0, y0, z),
            Vec3::new(x1, y0, z),
            Vec3::new(x1, y1, z),
            Vec3::new(x0, y1, z),
        ]);
        m
    };
    let mat = |i: usize| mats.get(i).copied().unwrap_or(0);
    // Exactly coplanar: the wall and two panels on it.
    sb.object(
        "wall",
        rect(-3.0, -1.6, 3.0, 1.8, 0.0),
        mat(0),
        Mat4::IDENTITY,
    );
    sb.object(
        "red panel",
        rect(-0.6, -0.4, 2.2, 1.4, 0.0),
        mat(1),
        Mat4::IDENTITY,
    );
    sb.object(
        "green panel",
        rect(-2.4, -1.2, 0.6, 0.6, 0.0),
        mat(2),
        Mat4::IDENTITY,
    );
    // Nearly coplanar: 1e-4 and 1e-3 in front (still fights at a distance).
    sb.object(
        "yellow panel",
        rect(-1.2, 0.2, 0.2, 1.6, 1e-4),
        mat(3),
        Mat4::IDENTITY,
    );
    sb.object(
        "white panel",
        rect(0.8, -1.4, 2.6, -0.1, 1e-3),
        mat(4),
        Mat4::IDENTITY,
    );
    // The same coplanar pair, tilted steeply away from the view: fighting in
    // depth-gradient direction too.
    let tilt = Mat4::from_translation(Vec3::new(0.0, -1.6, 0.6))
        * Mat4::from_rotation_x(-80f32.to_radians());
    sb.object("floor", rect(-3.0, 0.0, 3.0, 3.0, 0.0), mat(4), tilt);
    sb.object("floor stripe", rect(-0.8, 0.2, 0.8, 2.8, 0.0), mat(1), tilt);

    // Degenerate triangles: collinear, and two coincident vertices.
    let mut degenerate = MeshBuilder::default();
    degenerate.triangle(
        [
            Vec3::new(-2.0, -0.8, 0.3),
            Vec3::new(-1.0, -0.8, 0.3),
            Vec3::new(0.0, -0.8, 0.3),
        ],
        Vec3::Z,
    );
    degenerate.triangle(
        [
            Vec3::new(1.0, 1.0, 0.3),
            Vec3::new(1.0, 1.0, 0.3),
            Vec3::new(1.5, 1.5, 0.3),
        ],
        Vec3::Z,
    );
    // A normal triangle alongside, so the object is visible at all.
    degenerate.triangle(
        [
            Vec3::new(-2.8, 1.2, 0.3),
            Vec3::new(-2.2, 1.2, 0.3),
            Vec3::new(-2.5, 1.7, 0.3),
        ],
        Vec3::Z,
    );
    sb.object("degenerate", degenerate, mat(3), Mat4::IDENTITY);

    sb.lights.push(Light::directional(
        Vec3::new(-0.2, -0.5, -1.0),
        Vec3::ONE,
        2.5,
    ));
    sb.lights.push(Light::point(
        Vec3::new(0.5, 0.3, 1.2),
        rgb(1.0, 0.9, 0.8),
        1.5,
        Some(6.0),
    ));
    sb.finish(
        Background::Gradient {
            zenith: [0.05, 0.05, 0.1],
            horizon: [0.3, 0.3, 0.35],
        },
        |_| {
            Camera::look_at(
                Vec3::new(1.4, 0.9, 5.8),
                Vec3::new(0.0, 0.0, 0.0),
                45f32.to_radians(),
                0.1,
                Some(50.0),
            )
        },
    )
}

fn emissive() -> Scene {
    let mut sb = SceneBuilder::new("emissive");
    let grey = sb.material(Material::solid("station", [0.5, 0.5, 0.52], 0.4, 0.5));
    let plain = sb.material(Material::solid("crate", [0.35, 0.3, 0.25], 0.0, 0.7));
    let windows = sb.material(emissive_material(
        "windows",
        [0.05, 0.05, 0.05],
        [60.0, 50.0, 30.0],
    ));
    let beacon = sb.material(emissive_material(
        "beacon",
        [0.3, 0.02, 0.02],
        [300.0, 40.0, 20.0],
    ));
    let screen = sb.material(emissive_material(
        "screen",
        [0.02, 0.02, 0.05],
        [0.8, 2.0, 4.0],
    ));
    let thruster = sb.material(emissive_material(
        "thruster",
        [0.05, 0.05, 0.05],
        [20.0, 80.0, 200.0],
    ));

    // A station: a drum with rings of lit windows and a mast with a beacon.
    let mut drum = MeshBuilder::default();
    drum.cylinder(
        Vec3::new(0.0, -1.5, 0.0),
        Vec3::new(0.0, 1.5, 0.0),
        1.0,
        32,
        true,
    );
    drum.cylinder(
        Vec3::new(0.0, 1.5, 0.0),
        Vec3::new(0.0, 2.6, 0.0),
        0.04,
        8,
        false,
    );
    let mut lit = MeshBuilder::default();
    for (ring, y) in [-0.9f32, 0.0, 0.9].iter().enumerate() {
        for k in 0..16 {
            if (k + ring) % 5 == 0 {
                continue; // some windows dark
            }
            let a = k as f32 / 16.0 * std::f32::consts::TAU;
            let rot = Quat::from_rotation_y(a);
            lit.cuboid(
                Vec3::new(0.0, *y, 0.0) + rot * Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(0.09, 0.12, 0.015),
                rot,
            );
        }
    }
    let mut lamp = MeshBuilder::default();
    lamp.sphere(Vec3::new(0.0, 2.7, 0.0), 0.1, 8, 12);

    // A screen on a stand and a small ship with thrusters.
    let mut stand = MeshBuilder::default();
    stand.aabox(Vec3::new(2.2, -1.5, 0.4), Vec3::new(2.3, -0.2, 0.5));
    stand.aabox(Vec3::new(1.6, -0.2, 0.42), Vec3::new(2.9, 0.6, 0.46));
    let mut panel = MeshBuilder::default();
    panel.quad([
        Vec3::new(1.65, -0.15, 0.47),
        Vec3::new(2.85, -0.15, 0.47),
        Vec3::new(2.85, 0.55, 0.47),
        Vec3::new(1.65, 0.55, 0.47),
    ]);
    let mut shuttle = MeshBuilder::default();
    shuttle.aabox(Vec3::new(-3.2, 0.6, 0.2), Vec3::new(-1.8, 1.0, 0.9));
    shuttle.aabox(Vec3::new(-3.0, 1.0, 0.35), Vec3::new(-2.3, 1.2, 0.75));
    let mut jets = MeshBuilder::default();
    for z in [0.38f32, 0.72] {
        jets.cylinder(
            Vec3::new(-3.2, 0.8, z),
            Vec3::new(-3.26, 0.8, z),
            0.12,
            16,
            true,
        );
    }
    // Plain crates for contrast.
    let mut crates = MeshBuilder::default();
    crates.aabox(Vec3::new(-2.6, -1.5, 0.8), Vec3::new(-1.8, -0.7, 1.6));
    crates.cuboid(
        Vec3::new(-1.4, -1.2, 1.8),
        Vec3::splat(0.3),
        Quat::from_rotation_y(0.6),
    );
    crates.aabox(Vec3::new(1.4, -1.5, 1.2), Vec3::new(2.0, -0.9, 1.8));

    sb.object("station", drum, grey, Mat4::IDENTITY);
    sb.object("windows", lit, windows, Mat4::IDENTITY);
    sb.object("beacon", lamp, beacon, Mat4::IDENTITY);
    sb.object("screen stand", stand, plain, Mat4::IDENTITY);
    sb.object("screen", panel, screen, Mat4::IDENTITY);
    sb.object("shuttle", shuttle, grey, Mat4::IDENTITY);
    sb.object("thrusters", jets, thruster, Mat4::IDENTITY);
    sb.object("crates", crates, plain, Mat4::IDENTITY);
    sb.lights.push(Light::directional(
        Vec3::new(-0.5, -0.6, -0.6),
        rgb(0.9, 0.9, 1.0),
        0.4,
    ));
    sb.lights.push(Light::point(
        Vec3::new(0.0, 2.4, 0.8),
        rgb(1.0, 0.2, 0.1),
        0.6,
        Some(3.0),
    ));
    sb.finish(Background::Stars { seed: 7 }, |s| {
        s.framing_camera(40f32.to_radians())
    })
}

/// Distance from the camera to the `far` ship, world units (metres).
pub(crate) const FAR_DISTANCE: f32 = 200_000.0;

fn far() -> Scene {
    let mut sb = SceneBuilder::new("far");
    // The greeble ship, 150× larger (about 1.9 km long), turned a little.
    let scale = 150.0;
    let transform = Mat4::from_rotation_y(0.35) * Mat4::from_scale(Vec3::splat(scale));
    add_ship(&mut sb, greeble_ship(0x5EED_0002), transform);
    sb.lights = ship_lights(transform, scale);
    sb.finish(Background::Stars { seed: 42 }, |s| {
        let target = s.bounds.center();
        let dir = Vec3::new(0.55, 0.35, 0.76).normalize();
        Camera {
            view: look_at(target + dir * FAR_DISTANCE, target, Vec3::Y),
            fov_y: 0.5f32.to_radians(),
            near: 0.01,
            far: None,
        }
    })
}

/// The deferred tutorial's picture: a 3x3 grid of turned boxes on a dark
/// floor, twelve coloured point lights among them, and each light drawn as
/// a small bright cube after lighting. The cubes are a blended material at
/// alpha 1 with an emissive colour, so the renderer draws them in its
/// forward (transparent) pass, as the tutorial draws its light cubes.
fn lamps() -> Scene {
    let mut sb = SceneBuilder::new("lamps");
    let floor_mat = sb.material(Material::solid("floor", [0.08, 0.08, 0.09], 0.0, 0.8));
    let mut floor = MeshBuilder::default();
    floor.quad([
        Vec3::new(-7.0, -0.6, 6.0),
        Vec3::new(7.0, -0.6, 6.0),
        Vec3::new(7.0, -0.6, -7.0),
        Vec3::new(-7.0, -0.6, -7.0),
    ]);
    sb.object("floor", floor, floor_mat, Mat4::IDENTITY);
    for i in 0..9 {
        let (x, z) = ((i % 3) as f32 * 3.0 - 3.0, (i / 3) as f32 * 3.0 - 3.0);
        let fi = i as f32;
        let colour = [
            0.45 + 0.05 * fi,
            0.8 - 0.06 * fi,
            0.5 + 0.1 * (i % 3) as f32,
        ];
        let mat = sb.material(Material::solid(&format!("box {i}"), colour, 0.0, 0.45));
        let mut block = MeshBuilder::default();
        block.cuboid(
            Vec3::new(x, 0.0, z),
            Vec3::splat(0.6),
            Quat::from_axis_angle(Vec3::new(1.0, 0.8, 0.3).normalize(), 0.35 + 0.6 * fi),
        );
        sb.object(&format!("box {i}"), block, mat, Mat4::IDENTITY);
    }
    // Twelve lights between and above the boxes, each with its cube.
    for i in 0..12u32 {
        // The golden angle: spread without a grid.
        let a = i as f32 * 2.39996;
        let r = 1.2 + 0.35 * i as f32;
        let at = Vec3::new(r * a.cos(), 0.4 + 0.25 * (i % 4) as f32, r * a.sin() - 0.5);
        let c = rgb(
            0.5 + 0.5 * ((i * 7) % 10) as f32 / 10.0,
            0.5 + 0.5 * ((i * 3) % 10) as f32 / 10.0,
            0.5 + 0.5 * ((i * 9) % 10) as f32 / 10.0,
        );
        sb.lights.push(Light::point(at, c, 6.0, Some(5.0)));
        let lamp = sb.material(Material {
            alpha_mode: AlphaMode::Blend,
            emissive: [c.x * 4.0, c.y * 4.0, c.z * 4.0],
            ..Material::solid(&format!("lamp {i}"), [0.0, 0.0, 0.0], 0.0, 1.0)
        });
        let mut cube = MeshBuilder::default();
        cube.cuboid(at, Vec3::splat(0.12), Quat::from_rotation_y(0.4 * i as f32));
        sb.object(&format!("lamp {i}"), cube, lamp, Mat4::IDENTITY);
    }
    sb.finish(Background::Black, |_| {
        Camera::look_at(
            Vec3::new(0.0, 5.5, 7.5),
            Vec3::new(0.0, -0.3, -0.6),
            40f32.to_radians(),
            0.1,
            Some(60.0),
        )
    })
}

/// Thin bright slats, boxes turned 40 degrees about their long axis so
/// that a side face shows as a sliver beside the front one, slanted in the
/// image plane, in front of a dark wall 190 units behind them that no light
/// reaches. At 640x360 a slat's front face is 1.5 to 4.3 pixels wide and its
/// side face 0.3 to 0.9 of a pixel (a sub-pixel sliver: its pixels hold the
/// front face, the side and the wall).
fn slats() -> Scene {
    let mut sb = SceneBuilder::new("slats");
    let slat_mat = sb.material(Material::solid("slats", [0.85, 0.82, 0.76], 0.0, 0.6));
    let wall_mat = sb.material(Material::solid("wall", [0.03, 0.03, 0.035], 0.0, 0.9));
    // World units per pixel in z = 0 at 360 pixels high.
    let unit_per_px = 2.0 * 10.0 * (15f32.to_radians()).tan() / 360.0;
    let mut slats = MeshBuilder::default();
    for k in 0..25 {
        let (width_px, slant_deg) = (2.0 + 0.15 * k as f32, -36.0 + 3.0 * k as f32);
        // The side face's width in the image is the box's depth times the
        // sine of the turn.
        let side_px = 0.3 + 0.025 * k as f32;
        let depth = side_px * unit_per_px / 0.7f32.sin();
        let centre = Vec3::new(-4.5 + 0.375 * k as f32, 0.3 * ((k % 3) as f32 - 1.0), 0.0);
        let turn = Quat::from_rotation_z(slant_deg.to_radians()) * Quat::from_rotation_y(0.7);
        // Long enough to run off the top and bottom of the view.
        slats.cuboid(
            centre,
            Vec3::new(0.5 * width_px * unit_per_px, 3.2, 0.5 * depth),
            turn,
        );
    }
    sb.object("slats", slats, slat_mat, Mat4::IDENTITY);
    let (wall_z, w, h) = (-190.0f32, 130.0f32, 75.0f32);
    let mut wall = MeshBuilder::default();
    wall.quad([
        Vec3::new(-w, -h, wall_z),
        Vec3::new(w, -h, wall_z),
        Vec3::new(w, h, wall_z),
        Vec3::new(-w, h, wall_z),
    ]);
    sb.object("far wall", wall, wall_mat, Mat4::IDENTITY);
    // Lights near the slats, out of the wall's reach.
    for (x, y, c) in [
        (-3.0, 2.0, rgb(1.0, 0.95, 0.85)),
        (3.0, -1.5, rgb(0.8, 0.9, 1.0)),
    ] {
        sb.lights
            .push(Light::point(Vec3::new(x, y, 3.0), c, 60.0, Some(20.0)));
    }
    sb.finish(Background::Black, |_| {
        Camera::look_at(
            Vec3::new(0.0, 0.0, 10.0),
            Vec3::ZERO,
            30f32.to_radians(),
            0.1,
            Some(250.0),
        )
    })
}

fn transparent() -> Scene {
    let mut sb = SceneBuilder::new("transparent");
    let ground = sb.material(Material::solid("ground", [0.5, 0.5, 0.5], 0.0, 0.85));
    let orange = sb.material(Material::solid("box", [0.9, 0.45, 0.1], 0.0, 0.5));
    let blue = sb.material(Material::solid("pillar", [0.15, 0.3, 0.85], 0.2, 0.35));
    let white = sb.material(Material::solid("ball", [0.85, 0.85, 0.8], 0.0, 0.25));
    let pane = |sb: &mut SceneBuilder, name: &str, rgba: [f32; 4]| {
        sb.material(Material {
            base_color: rgba,
            alpha_mode: AlphaMode::Blend,
            double_sided: true,
            ..Material::solid(name, [0.0; 3], 0.0, 0.1)
        })
    };
    let cyan = pane(&mut sb, "cyan glass", [0.2, 0.8, 0.9, 0.35]);
    let magenta = pane(&mut sb, "magenta glass", [0.9, 0.2, 0.7, 0.5]);
    let yellow = pane(&mut sb, "yellow glass", [1.0, 0.9, 0.2, 0.25]);

    // A 64×64 grille: opaque bars, transparent holes (alpha-tested).
    let size = 64u32;
    let mut rgba8 = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let bar = x % 16 < 3 || y % 16 < 3;
            rgba8.extend_from_slice(if bar {
                &[200, 200, 190, 255]
            } else {
                &[0, 0, 0, 0]
            });
        }
    }
    sb.textures.push(TextureData {
        width: size,
        height: size,
        rgba8,
        srgb: true,
    });
    let grille = sb.material(Material {
        base_color_texture: Some(0),
        alpha_mode: AlphaMode::Mask,
        alpha_cutoff: 0.5,
        double_sided: true,
        ..Material::solid("grille", [1.0, 1.0, 1.0], 0.6, 0.4)
    });

    let mut floor = MeshBuilder::default();
    floor.quad([
        Vec3::new(-6.0, 0.0, 4.0),
        Vec3::new(6.0, 0.0, 4.0),
        Vec3::new(6.0, 0.0, -6.0),
        Vec3::new(-6.0, 0.0, -6.0),
    ]);
    let mut block = MeshBuilder::default();
    block.cuboid(
        Vec3::new(-1.6, 0.6, -1.2),
        Vec3::splat(0.6),
        Quat::from_rotation_y(0.5),
    );
    let mut pillar = MeshBuilder::default();
    pillar.cylinder(
        Vec3::new(1.5, 0.0, -1.6),
        Vec3::new(1.5, 2.2, -1.6),
        0.45,
        24,
        true,
    );
    let mut ball = MeshBuilder::default();
    ball.sphere(Vec3::new(0.1, 0.7, -0.4), 0.7, 16, 24);
    sb.object("ground", floor, ground, Mat4::IDENTITY);
    sb.object("box", block, orange, Mat4::IDENTITY);
    sb.object("pillar", pillar, blue, Mat4::IDENTITY);
    sb.object("ball", ball, white, Mat4::IDENTITY);

    let vertical = |x0: f32, x1: f32, y0: f32, y1: f32, z: f32| {
        let mut m = MeshBuilder::default();
        m.quad([
            Vec3::new(x0, y0, z),
            Vec3::new(x1, y0, z),
            Vec3::new(x1, y1, z),
            Vec3::new(x0, y1, z),
        ]);
        m
    };
    sb.object(
        "cyan pane",
        vertical(-2.4, -0.2, 0.1, 1.9, 1.2),
        cyan,
        Mat4::IDENTITY,
    );
    sb.object(
        "magenta pane",
        vertical(-0.8, 1.2, 0.4, 2.2, 1.6),
        magenta,
        Mat4::IDENTITY,
    );
    sb.object(
        "yellow pane",
        vertical(0.4, 2.5, 0.0, 1.5, 2.0),
        yellow,
        Mat4::IDENTITY,
    );
    let mut grid = MeshBuilder::default();
    grid.quad_uv(
        [
            Vec3::new(-3.2, 0.0, 0.4),
            Vec3::new(-2.0, 0.0, 0.9),
            Vec3::new(-2.0, 1.6, 0.9),
            Vec3::new(-3.2, 1.6, 0.4),
        ],
        [[0.0, 4.0], [3.0, 4.0], [3.0, 0.0], [0.0, 0.0]],
    );
    sb.object("grille", grid, grille, Mat4::IDENTITY);

    sb.lights.push(Light::directional(
        Vec3::new(-0.4, -1.0, -0.5),
        rgb(1.0, 0.97, 0.92),
        2.2,
    ));
    sb.lights.push(Light::point(
        Vec3::new(0.5, 2.5, 1.0),
        rgb(0.8, 0.85, 1.0),
        3.0,
        Some(8.0),
    ));
    sb.finish(
        Background::Gradient {
            zenith: [0.15, 0.25, 0.5],
            horizon: [0.6, 0.62, 0.65],
        },
        |_| {
            Camera::look_at(
                Vec3::new(0.3, 2.1, 6.4),
                Vec3::new(-0.1, 0.8, -0.2),
                42f32.to_radians(),
                0.1,
                Some(60.0),
            )
        },
    )
}

// ---------------------------------------------------------------------------
// The scenes the bench's claims are about

/// The paper's Figure 4 artefact, isolated: a box in front of a far wall,
/// with short-range point lights just behind its edges. Nothing the camera
/// sees is in a light's range (the lights reach only the box's hidden sides),
/// so the reference shows none of their light. A resolve that averages
/// positions puts an edge pixel's position between box and wall, close to a
/// light, and lights it: a halo. Box and wall are lit alike and dimly, so
/// aliasing between them stays far below the halo threshold; the painted
/// stripes on the box are the contrasty detail inside the model, 2 mm proud
/// of it, that a depth-aware resolve blends (and plain aliasing shows).
fn halo() -> Scene {
    let mut sb = SceneBuilder::new("halo");
    let box_mat = sb.material(Material::solid("box", [0.16, 0.15, 0.14], 0.0, 0.7));
    let paint = sb.material(Material::solid("stripes", [0.85, 0.85, 0.8], 0.0, 0.7));
    let wall_mat = sb.material(Material::solid("wall", [0.14, 0.145, 0.16], 0.0, 0.9));
    // Turned in the image plane so that no edge runs along a pixel row or
    // column; the camera stays between each pair of side faces, which it
    // therefore never sees.
    let turn = Mat4::from_rotation_z(0.35);
    let (lo, hi) = (Vec3::new(-1.6, -1.1, -0.6), Vec3::new(1.6, 1.1, 0.6));
    let mut block = MeshBuilder::default();
    block.aabox(lo, hi);
    // Quads 2 mm proud of the front face, without sides: a side would face
    // some light and catch its light where the box should shadow it.
    let mut stripes = MeshBuilder::default();
    let (x_lo, x_hi, z) = (lo.x + 0.3, hi.x - 0.3, hi.z + 0.002);
    for y in [-0.6f32, 0.0, 0.6] {
        stripes.quad([
            Vec3::new(x_lo, y - 0.06, z),
            Vec3::new(x_hi, y - 0.06, z),
            Vec3::new(x_hi, y + 0.06, z),
            Vec3::new(x_lo, y + 0.06, z),
        ]);
    }
    let wall_z = -10.0;
    let mut wall = MeshBuilder::default();
    wall.quad([
        Vec3::new(-14.0, -9.0, wall_z),
        Vec3::new(14.0, -9.0, wall_z),
        Vec3::new(14.0, 9.0, wall_z),
        Vec3::new(-14.0, 9.0, wall_z),
    ]);
    sb.object("box", block, box_mat, turn);
    sb.object("stripes", stripes, paint, turn);
    sb.object("wall", wall, wall_mat, Mat4::IDENTITY);

    // Behind the box (0.6 past its back face) and 0.15 outside an edge: from
    // the camera the box hides the light, and the wall is out of its range.
    let behind = lo.z - 0.6;
    let (out, range) = (0.15, 6.0);
    let warm = rgb(1.0, 0.75, 0.45);
    for (x, y) in [
        (hi.x + out, 0.4),
        (hi.x + out, -0.5),
        (lo.x - out, 0.0),
        (-0.6, hi.y + out),
        (0.8, hi.y + out),
        (0.2, lo.y - out),
    ] {
        let at = turn.transform_point3(Vec3::new(x, y, behind));
        sb.lights.push(Light::point(at, warm, 40.0, Some(range)));
    }
    // A fill from the camera's side: the only light the camera sees.
    sb.lights.push(Light::directional(
        Vec3::new(0.1, -0.15, -1.0),
        rgb(0.9, 0.92, 1.0),
        1.0,
    ));
    sb.finish(Background::Black, |_| {
        Camera::look_at(
            Vec3::new(0.0, 0.0, 9.0),
            Vec3::ZERO,
            30f32.to_radians(),
            0.1,
            Some(50.0),
        )
    })
}

/// FreeSpace Open's case: a hull filling most of the view, covered in detail
/// that lies close to it in depth (raised plates with seams between them,
/// painted strips, pipes, low greebles) and a few short antennas, lit by
/// coloured point lights close to the surface, against dark space. The
/// depth-aware resolve blends these edges inside the model; the few
/// silhouettes against space are left to the post filter. (Space is a dark
/// gradient, not the star field: stars are placed per pixel of the target,
/// so the bench's supersampled reference would show other stars.)
fn hull() -> Scene {
    let mut sb = SceneBuilder::new("hull");
    let mut rng = Rng(0x4077_0001);
    let mut solid = |name: &str, rgb: [f32; 3], metallic: f32, roughness: f32| {
        sb.material(Material::solid(name, rgb, metallic, roughness))
    };
    let deck = solid("deck", [0.1, 0.1, 0.11], 0.2, 0.6);
    let plate_kinds = [
        ("light plates", [0.56, 0.57, 0.6], 0.2, 0.5),
        ("grey plates", [0.38, 0.39, 0.42], 0.2, 0.55),
        ("ochre plates", [0.55, 0.43, 0.28], 0.1, 0.6),
    ]
    .map(|(name, rgb, metallic, roughness)| (name, solid(name, rgb, metallic, roughness)));
    let paint = solid("paint", [0.85, 0.66, 0.12], 0.0, 0.5);
    let metal = solid("pipes", [0.8, 0.78, 0.74], 0.7, 0.3);
    let dark = solid("greebles", [0.18, 0.19, 0.21], 0.5, 0.4);

    // A long slab, its deck at y = 0 and one side (+z) in view, on a keel.
    let (x0, x1, z0, z1) = (-9.0f32, 9.0f32, -3.6f32, 3.6f32);
    let mut body = MeshBuilder::default();
    body.aabox(Vec3::new(x0, -2.4, z0), Vec3::new(x1, 0.0, z1));
    body.aabox(
        Vec3::new(x0 + 1.0, -2.9, z0 + 0.6),
        Vec3::new(x1 - 1.5, -2.4, z1 - 0.6),
    );

    // Deck plates on a 1.2 x 0.9 grid with 4-7 cm seams, each raised 5-20 mm.
    let mut plates: [MeshBuilder; 3] = Default::default();
    let (cell_x, cell_z) = (1.2f32, 0.9f32);
    for i in 0..((x1 - x0) / cell_x) as u32 {
        for k in 0..((z1 - z0) / cell_z) as u32 {
            let half_seam = rng.range(0.02, 0.035);
            let corner = Vec3::new(x0 + i as f32 * cell_x, 0.0, z0 + k as f32 * cell_z);
            let lo = corner + Vec3::new(half_seam, 0.0, half_seam);
            let hi = corner
                + Vec3::new(
                    cell_x - half_seam,
                    rng.range(0.005, 0.02),
                    cell_z - half_seam,
                );
            plates[(rng.next_u64() % 3) as usize].aabox(lo, hi);
        }
    }
    // Side plates: five bands, 0.8-2.2 long with 5 cm seams, raised 5-15 mm.
    let mut side = MeshBuilder::default();
    for band in 0..5 {
        let y = -2.3 + band as f32 * 0.46;
        let mut x = x0 + 0.1;
        while x < x1 - 0.6 {
            let length = rng.range(0.8, 2.2).min(x1 - 0.1 - x);
            side.aabox(
                Vec3::new(x, y, z1),
                Vec3::new(x + length - 0.05, y + 0.41, z1 + rng.range(0.005, 0.015)),
            );
            x += length;
        }
    }
    // Painted dashes along the deck, 2.5 cm wide.
    let mut strips = MeshBuilder::default();
    for z in [-2.25f32, 0.45, 2.7] {
        let mut x = x0 + 0.3;
        while x < x1 - 0.6 {
            strips.aabox(Vec3::new(x, 0.0, z), Vec3::new(x + 0.5, 0.024, z + 0.025));
            x += 0.75;
        }
    }
    // Pipes 1.5-2.5 cm in radius along the deck and the side, and short
    // antennas under a pixel to two pixels wide at 640x360.
    let mut pipes = MeshBuilder::default();
    for (z, r) in [
        (-1.37f32, 0.02f32),
        (-1.3, 0.015),
        (1.33, 0.025),
        (3.2, 0.018),
    ] {
        let y = 0.02 + r;
        pipes.cylinder(
            Vec3::new(x0 + 0.4, y, z),
            Vec3::new(x1 - 0.4, y, z),
            r,
            8,
            true,
        );
    }
    for y in [-0.6f32, -1.45] {
        let z = z1 + 0.035;
        pipes.cylinder(
            Vec3::new(x0 + 0.3, y, z),
            Vec3::new(x1 - 0.3, y, z),
            0.02,
            8,
            true,
        );
    }
    for (x, z, height, r) in [
        (-4.6f32, -0.8f32, 0.7f32, 0.008f32),
        (-1.2, 1.9, 0.5, 0.012),
        (2.4, -2.6, 0.9, 0.006),
        (5.3, 0.9, 0.6, 0.01),
    ] {
        let foot = Vec3::new(x, 0.02, z);
        pipes.cylinder(foot, foot + Vec3::Y * height, r, 6, true);
    }
    // Low greebles: clusters of 4-16 cm boxes, 1-4 cm tall, on the plates.
    let mut greebles = MeshBuilder::default();
    for _ in 0..14 {
        let centre = Vec3::new(
            rng.range(x0 + 1.0, x1 - 1.0),
            0.02,
            rng.range(z0 + 0.5, z1 - 0.5),
        );
        for _ in 0..8 {
            let base = centre + Vec3::new(rng.range(-0.5, 0.5), 0.0, rng.range(-0.35, 0.35));
            let half = Vec3::new(rng.range(0.02, 0.08), 0.0, rng.range(0.02, 0.08));
            let height = rng.range(0.01, 0.04);
            greebles.aabox(base - half, base + half + Vec3::Y * height);
        }
    }

    sb.object("hull", body, deck, Mat4::IDENTITY);
    for (mesh, (name, material)) in plates.into_iter().zip(plate_kinds) {
        sb.object(name, mesh, material, Mat4::IDENTITY);
    }
    sb.object("side plates", side, plate_kinds[1].1, Mat4::IDENTITY);
    sb.object("strips", strips, paint, Mat4::IDENTITY);
    sb.object("pipes", pipes, metal, Mat4::IDENTITY);
    sb.object("greebles", greebles, dark, Mat4::IDENTITY);

    // Coloured point lights 0.6-1 above the deck (one beside the side), a
    // key and a fill.
    for (p, c, intensity) in [
        ([-5.5f32, 0.8f32, 0.5f32], [1.0f32, 0.6f32, 0.25f32], 1.2f32),
        ([-1.0, 0.7, -1.5], [0.3, 0.8, 1.0], 1.0),
        ([3.0, 0.9, 1.2], [1.0, 0.35, 0.7], 1.2),
        ([6.5, 0.6, -2.0], [0.5, 1.0, 0.5], 0.9),
        ([0.5, -1.0, 4.4], [1.0, 0.9, 0.75], 1.2),
    ] {
        sb.lights.push(Light::point(
            Vec3::from(p),
            Vec3::from(c),
            intensity,
            Some(4.0),
        ));
    }
    sb.lights.push(Light::directional(
        Vec3::new(-0.35, -1.0, -0.45),
        rgb(0.95, 0.95, 1.0),
        0.9,
    ));
    sb.lights.push(Light::directional(
        Vec3::new(0.6, -0.2, -0.7),
        rgb(0.5, 0.55, 0.8),
        0.25,
    ));
    sb.finish(
        Background::Gradient {
            zenith: [0.004, 0.005, 0.012],
            horizon: [0.012, 0.014, 0.025],
        },
        |_| {
            Camera::look_at(
                Vec3::new(5.0, 5.2, 10.0),
                Vec3::new(-1.8, -0.6, -0.6),
                38f32.to_radians(),
                0.1,
                Some(80.0),
            )
        },
    )
}

/// The view height the `bars` scene's widths are chosen for: the bench's
/// default size, 640x360.
const BARS_VIEW_HEIGHT_PX: f32 = 360.0;

/// The `bars` scene's bars: (width in pixels at 640x360, slant from the
/// vertical in degrees; positive leans right). Widths span thin silhouettes
/// from barely over a pixel to a few; the slants cover both image axes,
/// since a bar nearer horizontal is measured down the columns.
const BARS: [(f32, f32); 6] = [
    (1.3, 8.0),
    (1.7, -17.0),
    (2.1, 27.0),
    (2.6, -36.0),
    (3.0, 58.0),
    (3.4, -71.0),
];

/// Thin silhouettes: bright bars, flat and facing the camera, slanted at
/// several angles and [`BARS`] wide, in front of a dark wall at twice their
/// distance (far outside any resolve window around them, so a pixel on a
/// bar's edge has two depth clusters), beside a plate of shallow ridges
/// whose facets are close in depth but differ in normal (creases). Only
/// directional lights, so each bar and the wall behind it are lit evenly
/// and the bench can measure a bar's drawn width from its luminance; the
/// scene declares each bar's central stretch ([`Scene::bars`]), with
/// nothing but wall around it.
fn bars() -> Scene {
    // The plate: ridges along its y, facets 21° either side of facing the
    // camera, 5 cm from valley to crest; turned in the image plane so that
    // no crease runs along a pixel row or column.
    let plate_at = Mat4::from_translation(Vec3::new(2.6, 0.0, 0.0)) * Mat4::from_rotation_z(0.35);
    bars_with_plate("bars", ridged_plate(1.3, 1.9, 10), plate_at, true)
}

/// `bars` and `ridges`: the [`BARS`], a ridged `plate` placed by
/// `plate_at`, the far wall, the lights and the camera; with
/// `declare_bars`, the bars' central stretches for the bench's width
/// measure.
fn bars_with_plate(
    name: &'static str,
    plate: MeshBuilder,
    plate_at: Mat4,
    declare_bars: bool,
) -> Scene {
    let mut sb = SceneBuilder::new(name);
    let bar_mat = sb.material(Material::solid("bars", [0.8, 0.78, 0.74], 0.0, 0.8));
    let plate_mat = sb.material(Material::solid("plate", [0.45, 0.46, 0.5], 0.0, 0.6));
    let wall_mat = sb.material(Material::solid("wall", [0.03, 0.03, 0.035], 0.0, 0.9));
    let (bar_mesh, bars) = slanted_bars();
    if declare_bars {
        sb.bars = bars;
    }
    sb.object("bars", bar_mesh, bar_mat, Mat4::IDENTITY);
    sb.object("ridged plate", plate, plate_mat, plate_at);
    sb.object("wall", far_wall(), wall_mat, Mat4::IDENTITY);
    bars_lights(&mut sb);
    sb.finish(Background::Black, |_| bars_camera())
}

/// Where `bars` and `ridges` are seen from: 10 units in front of the bars'
/// plane, a 30° field of view.
fn bars_camera() -> Camera {
    Camera::look_at(
        BARS_EYE,
        Vec3::ZERO,
        BARS_FOV_Y_DEG.to_radians(),
        0.1,
        Some(40.0),
    )
}

/// The eye of [`bars_camera`].
const BARS_EYE: Vec3 = Vec3::new(0.0, 0.0, 10.0);
/// The vertical field of view of [`bars_camera`], in degrees.
const BARS_FOV_Y_DEG: f32 = 30.0;

/// The [`BARS`], one per cell of a 3x2 grid on the left of the view in the
/// plane z = 0, each centred in its cell and four fifths as long as the cell
/// lets it be, and the central 70 % of each as the bench measures it (the
/// ends stay out of every scanline across it).
fn slanted_bars() -> (MeshBuilder, Vec<Bar>) {
    // World units per pixel in z = 0 at the design height.
    let unit_per_px =
        2.0 * BARS_EYE.z * (BARS_FOV_Y_DEG.to_radians() * 0.5).tan() / BARS_VIEW_HEIGHT_PX;
    let mut mesh = MeshBuilder::default();
    let mut bars = Vec::new();
    let (cell_w, cell_h, grid_left, grid_top) = (1.5f32, 2.4f32, -4.5f32, 2.4f32);
    for (k, &(width_px, slant_deg)) in BARS.iter().enumerate() {
        let centre = Vec3::new(
            grid_left + cell_w * ((k % 3) as f32 + 0.5),
            grid_top - cell_h * ((k / 3) as f32 + 0.5),
            0.0,
        );
        let slant = slant_deg.to_radians();
        let along = Vec3::new(slant.sin(), slant.cos(), 0.0);
        let across = Vec3::new(along.y, -along.x, 0.0);
        let half_length =
            0.4 * (cell_w / slant.sin().abs().max(1e-3)).min(cell_h / slant.cos().abs().max(1e-3));
        let half_width = across * (0.5 * width_px * unit_per_px);
        let (bottom, top) = (centre - along * half_length, centre + along * half_length);
        mesh.quad([
            bottom - half_width,
            bottom + half_width,
            top + half_width,
            top - half_width,
        ]);
        bars.push(Bar {
            from: centre - along * (0.7 * half_length),
            to: centre + along * (0.7 * half_length),
            half_width,
        });
    }
    (mesh, bars)
}

/// A plate of `ridges` ridges along its y, `2 half_w` by `2 half_h`, in its
/// plane z = 0: facets 21° either side of facing the camera (5 cm from
/// valley to crest at the `bars` plate's pitch), close in depth but
/// differing in normal.
fn ridged_plate(half_w: f32, half_h: f32, ridges: u32) -> MeshBuilder {
    let pitch = 2.0 * half_w / ridges as f32;
    let height = 0.05 * pitch / 0.26;
    let mut plate = MeshBuilder::default();
    for r in 0..ridges {
        let x0 = -half_w + r as f32 * pitch;
        let (x1, x2) = (x0 + 0.5 * pitch, x0 + pitch);
        for (a, za, b, zb) in [(x0, 0.0, x1, height), (x1, height, x2, 0.0)] {
            plate.quad([
                Vec3::new(a, -half_h, za),
                Vec3::new(b, -half_h, zb),
                Vec3::new(b, half_h, zb),
                Vec3::new(a, half_h, za),
            ]);
        }
    }
    plate
}

/// The dark wall at z = −10 behind `bars` and `ridges`: two triangles whose
/// shared edge runs below the view, so that no triangle edge crosses the
/// wall anywhere the camera sees.
fn far_wall() -> MeshBuilder {
    let (wall_z, w, h) = (-10.0f32, 12.0f32, 7.0f32);
    let mut wall = MeshBuilder::default();
    let normal = Vec3::Z;
    wall.triangle(
        [
            Vec3::new(-3.0 * w, -h, wall_z),
            Vec3::new(3.0 * w, -h, wall_z),
            Vec3::new(0.0, 3.0 * h, wall_z),
        ],
        normal,
    );
    wall.triangle(
        [
            Vec3::new(3.0 * w, -h, wall_z),
            Vec3::new(-3.0 * w, -h, wall_z),
            Vec3::new(0.0, -3.0 * h, wall_z),
        ],
        normal,
    );
    wall
}

/// `bars`' lights: a key low from the left, so that the plate's two facet
/// directions differ clearly in light, and a weak fill from the right.
fn bars_lights(sb: &mut SceneBuilder) {
    sb.lights.push(Light::directional(
        Vec3::new(0.8, -0.3, -1.0),
        rgb(1.0, 0.97, 0.92),
        3.0,
    ));
    sb.lights.push(Light::directional(
        Vec3::new(-0.6, 0.1, -1.0),
        rgb(0.75, 0.8, 1.0),
        0.4,
    ));
}

/// Three clusters in a pixel: `bars`' thin slanted bars in front of a
/// ridged plate, 2 units behind them (far outside any resolve window), in
/// front of the far wall. A pixel on a bar's edge over a crease holds the
/// bar and both facets; over the plate's rim, the bar, a facet and the
/// wall. Two layers keep two of the three; the bench's
/// `flip_three_clusters` measures what that costs against per-sample
/// lighting. The bars are not declared for the width measure: the plate,
/// not the evenly lit wall, is behind them.
fn ridges() -> Scene {
    // Behind the bar grid, larger than it, ridges at twice `bars`' density.
    let plate_at =
        Mat4::from_translation(Vec3::new(-2.25, 0.0, -2.0)) * Mat4::from_rotation_z(0.35);
    bars_with_plate("ridges", ridged_plate(2.6, 2.6, 40), plate_at, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Aabb, LightKind};

    /// `bars` holds what the bench's bar width error needs: at 640x360
    /// the declared bars are as wide as [`BARS`] says (1.3 to 3.4 pixels),
    /// slanted at distinct angles clear of both image axes, wholly in view
    /// with room for their bands, clear of each other and of the plate, and
    /// in front of a wall twice as far away; and the bars are drawn where
    /// they are declared.
    #[test]
    fn bars_are_thin_slanted_and_only_wall_is_behind_them() {
        let scene = bars();
        let (w, h) = (640, 360);
        let image: Vec<_> = scene
            .bars
            .iter()
            .map(|b| b.in_image(&scene.camera, w, h).expect("in view"))
            .collect();
        assert_eq!(image.len(), BARS.len());
        let widths: Vec<f64> = image.iter().map(|b| b.width).collect();
        for (got, &(want, _)) in widths.iter().zip(&BARS) {
            assert!((got - f64::from(want)).abs() < 1e-3, "{widths:?}");
        }
        let (thinnest, widest) = widths
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &w| (lo.min(w), hi.max(w)));
        assert!(thinnest <= 1.3 + 1e-3 && widest >= 3.4 - 1e-3, "{widths:?}");
        let mut angles: Vec<f64> = image
            .iter()
            .map(|b| {
                let d = b.to - b.from;
                d.y.atan2(d.x).to_degrees().rem_euclid(180.0)
            })
            .collect();
        for a in &angles {
            let off_axis = (a % 90.0).min(90.0 - a % 90.0);
            assert!(off_axis > 5.0, "{angles:?}");
        }
        angles.sort_by(f64::total_cmp);
        assert!(angles.windows(2).all(|p| p[1] - p[0] > 5.0), "{angles:?}");

        // Each bar's surroundings as a box in pixels, padded by its band.
        let pad = |b: &crate::scene::ImageBar| b.width + 4.0;
        let boxes: Vec<_> = image
            .iter()
            .map(|b| (b.from.min(b.to) - pad(b), b.from.max(b.to) + pad(b)))
            .collect();
        for (lo, hi) in &boxes {
            assert!(lo.x >= 0.0 && lo.y >= 0.0 && hi.x <= 640.0 && hi.y <= 360.0);
        }
        let overlap = |a: &(glam::DVec2, glam::DVec2), b: &(glam::DVec2, glam::DVec2)| {
            a.0.x < b.1.x && b.0.x < a.1.x && a.0.y < b.1.y && b.0.y < a.1.y
        };
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                assert!(!overlap(a, b), "{a:?} {b:?}");
            }
        }
        let view = scene.camera.projection(16.0 / 9.0) * scene.camera.view;
        let pixel = |p: Vec3| {
            let c = view * p.extend(1.0);
            glam::DVec2::new(
                f64::from((c.x / c.w + 1.0) * 320.0),
                f64::from((1.0 - c.y / c.w) * 180.0),
            )
        };
        let object = |name: &str| {
            scene
                .objects
                .iter()
                .find(|o| o.name == name)
                .unwrap_or_else(|| panic!("no {name}"))
        };
        let plate = object("ridged plate");
        let plate_box =
            plate
                .positions
                .iter()
                .fold((glam::DVec2::MAX, glam::DVec2::MIN), |(lo, hi), &p| {
                    let q = pixel(plate.transform.transform_point3(Vec3::from(p)));
                    (lo.min(q), hi.max(q))
                });
        for b in &boxes {
            assert!(!overlap(b, &plate_box), "{b:?} {plate_box:?}");
        }

        let eye = scene.camera.position();
        let wall = object("wall").world_bounds();
        let bars_far = object("bars").world_bounds().min.z;
        assert!(eye.z - wall.max.z >= 2.0 * (eye.z - bars_far));
        // The declared stretch lies on the drawn bar: its ends are inside
        // one of the bar quads (in z = 0, so the xy plane tells).
        let quads = object("bars");
        for bar in &scene.bars {
            for p in [bar.from, bar.to] {
                let inside = quads.indices.chunks_exact(3).any(|t| {
                    let v = |k: usize| Vec3::from(quads.positions[t[k] as usize]);
                    let (a, b, c) = (v(0), v(1), v(2));
                    let side = |u: Vec3, w: Vec3| (w - u).cross(p - u).z >= -1e-6;
                    side(a, b) && side(b, c) && side(c, a)
                });
                assert!(inside, "{p} is on no bar");
            }
        }
    }

    /// `halo` shows the Figure 4 artefact and nothing but it: no point
    /// light reaches a face the camera sees (each is behind the face's plane
    /// or out of range of it), and the box hides each light from the camera.
    #[test]
    fn halo_lights_reach_nothing_the_camera_sees() {
        let scene = halo();
        let eye = scene.camera.position();
        let points: Vec<&Light> = scene
            .lights
            .iter()
            .filter(|l| l.kind == LightKind::Point)
            .collect();
        assert!(points.len() >= 4, "{} point lights", points.len());
        let mut seen = 0;
        for o in &scene.objects {
            let at = |i: u32| {
                o.transform
                    .transform_point3(Vec3::from(o.positions[i as usize]))
            };
            for tri in o.indices.chunks_exact(3) {
                let (a, b, c) = (at(tri[0]), at(tri[1]), at(tri[2]));
                let n = face_normal(a, b, c).normalize_or_zero();
                if n.dot(eye - a) <= 0.0 {
                    continue; // culled: the camera sees its back
                }
                seen += 1;
                for l in &points {
                    let height = n.dot(l.position - a);
                    let range = l.range.expect("a ranged light");
                    assert!(
                        height <= 0.0 || height > range,
                        "{}: a face the camera sees is lit by the light at {}",
                        o.name,
                        l.position
                    );
                }
            }
        }
        assert!(seen >= 4, "{seen} faces seen");

        let block = scene
            .objects
            .iter()
            .find(|o| o.name == "box")
            .expect("a box");
        let to_box = block.transform.inverse();
        let outline = Aabb::from_points(block.positions.iter().map(|&p| Vec3::from(p)));
        let front_z = block.world_bounds().max.z;
        for l in points {
            let p = l.position;
            let crossing = eye + (p - eye) * ((front_z - eye.z) / (p.z - eye.z));
            let c = to_box.transform_point3(crossing);
            assert!(
                p.z < front_z && c.x.abs() < outline.max.x && c.y.abs() < outline.max.y,
                "{p}: the camera sees past the box to the light"
            );
        }
    }
}
