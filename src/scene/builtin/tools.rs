//! What the built-in scenes are made with: a deterministic random
//! generator, a mesh builder and a scene builder.

use glam::{Mat4, Quat, Vec3};

use super::super::geometry::{Geometry, face_normal};
use super::super::{Background, Bar, Camera, Light, Material, Object, Scene, TextureData};

/// SplitMix64: tiny, deterministic on every platform.
pub(super) struct Rng(pub(super) u64);

impl Rng {
    pub(super) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(super) fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub(super) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    pub(super) fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }
}

/// Accumulates triangles with per-vertex normals and coordinates.
#[derive(Default)]
pub(super) struct MeshBuilder {
    pub(super) g: Geometry,
}

impl MeshBuilder {
    pub(super) fn vertex(&mut self, p: Vec3, n: Vec3, uv: [f32; 2]) -> u32 {
        let i = self.g.positions.len() as u32;
        self.g.positions.push(p.to_array());
        self.g.normals.push(n.normalize_or(Vec3::Z).to_array());
        self.g.uvs.push(uv);
        i
    }

    /// A flat quad; `c` counter-clockwise seen from the front.
    pub(super) fn quad_uv(&mut self, c: [Vec3; 4], uv: [[f32; 2]; 4]) {
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

    pub(super) fn quad(&mut self, c: [Vec3; 4]) {
        self.quad_uv(c, [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
    }

    /// A single triangle with an explicit normal (degenerate ones included).
    pub(super) fn triangle(&mut self, p: [Vec3; 3], n: Vec3) {
        for v in p {
            let i = self.vertex(v, n, [0.0, 0.0]);
            self.g.indices.push(i);
        }
    }

    /// A box: `half` extents along the rotated axes.
    pub(super) fn cuboid(&mut self, center: Vec3, half: Vec3, rot: Quat) {
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
    pub(super) fn aabox(&mut self, min: Vec3, max: Vec3) {
        self.cuboid((min + max) * 0.5, (max - min) * 0.5, Quat::IDENTITY);
    }

    /// A cylinder from `a` to `b`, smooth sides, optional flat caps.
    pub(super) fn cylinder(&mut self, a: Vec3, b: Vec3, radius: f32, segments: u32, caps: bool) {
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
    pub(super) fn sphere(&mut self, center: Vec3, radius: f32, rings: u32, segments: u32) {
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

    pub(super) fn is_empty(&self) -> bool {
        self.g.indices.is_empty()
    }
}

/// Collects objects and materials, then finishes a [`Scene`].
pub(super) struct SceneBuilder {
    pub(super) name: &'static str,
    pub(super) objects: Vec<Object>,
    pub(super) materials: Vec<Material>,
    pub(super) textures: Vec<TextureData>,
    pub(super) lights: Vec<Light>,
    pub(super) bars: Vec<Bar>,
}

impl SceneBuilder {
    pub(super) fn new(name: &'static str) -> Self {
        SceneBuilder {
            name,
            objects: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            lights: Vec::new(),
            bars: Vec::new(),
        }
    }

    pub(super) fn material(&mut self, m: Material) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    pub(super) fn object(
        &mut self,
        name: &str,
        mesh: MeshBuilder,
        material: usize,
        transform: Mat4,
    ) {
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
    pub(super) fn finish(
        self,
        background: Background,
        camera: impl FnOnce(&Scene) -> Camera,
    ) -> Scene {
        let mut scene = Scene {
            name: self.name.to_string(),
            objects: self.objects,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            camera: Camera::look_at(Vec3::Z, Vec3::ZERO, 1.0, 0.1, None),
            background,
            warnings: Vec::new(),
            bounds: super::super::Aabb::EMPTY,
            bars: self.bars,
        };
        scene.recompute_bounds();
        scene.camera = camera(&scene);
        scene
    }
}

pub(super) fn rgb(r: f32, g: f32, b: f32) -> Vec3 {
    Vec3::new(r, g, b)
}

pub(super) fn emissive_material(name: &str, base: [f32; 3], emissive: [f32; 3]) -> Material {
    Material {
        emissive,
        ..Material::solid(name, base, 0.0, 0.6)
    }
}
