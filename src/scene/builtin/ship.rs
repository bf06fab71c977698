//! The greeble ship, and the two scenes that show it: `greebles` close up
//! and `far` 200 km away.

use glam::{Mat4, Quat, Vec3};

use super::super::{Background, Camera, Light, Material, Scene, camera::look_at};
use super::tools::{MeshBuilder, Rng, SceneBuilder, emissive_material, rgb};

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

pub(super) fn greebles() -> Scene {
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

/// Distance from the camera to the `far` ship, world units (metres).
pub(crate) const FAR_DISTANCE: f32 = 200_000.0;

pub(super) fn far() -> Scene {
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
