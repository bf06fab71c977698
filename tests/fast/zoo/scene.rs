//! The zoo's one scene, as plain CPU data every host uploads its own way
//! (as it would a model file): a chequered floor, a back wall, a box whose
//! three visible faces meet at shared edges, a panel turned and tilted
//! against the view (its depth varies), a small triangle floating in front
//! of the panel (overlapping edges far apart in depth), sky above the wall
//! and beside it; two point lights. Every face has its own flat colour, so
//! the flat planes alone tell faces apart.

use glam::{Mat4, Vec3};

/// One flat-shaded triangle, wound counter-clockwise as seen from the camera.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    /// World-space corners.
    pub corners: [Vec3; 3],
    /// Its flat unit normal, towards the camera.
    pub normal: Vec3,
    /// Its flat colour (linear, 0..1).
    pub colour: Vec3,
    /// The object it belongs to, from 1 (0 is the background).
    pub object: u32,
    /// A small material number (shininess class, roughness class, …), from 1.
    pub material: u32,
}

/// The camera position.
pub const EYE: Vec3 = Vec3::new(0.2, 1.6, 5.0);
const TARGET: Vec3 = Vec3::new(0.0, 0.45, 0.0);
/// Vertical field of view in radians.
pub const FOV_Y: f32 = 0.8;
/// The near plane.
pub const NEAR: f32 = 0.1;
/// The far plane.
pub const FAR: f32 = 60.0;

/// World-space point lights: position and colour.
pub const LIGHTS: [(Vec3, Vec3); 2] = [
    (Vec3::new(-1.6, 2.4, 2.2), Vec3::new(1.0, 0.95, 0.9)),
    (Vec3::new(2.2, 1.2, 1.0), Vec3::new(0.9, 0.6, 0.35)),
];

/// The view matrix (world to view).
pub fn view() -> Mat4 {
    let f = (TARGET - EYE).normalize();
    let s = f.cross(Vec3::Y).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        glam::Vec4::new(s.x, u.x, -f.x, 0.0),
        glam::Vec4::new(s.y, u.y, -f.y, 0.0),
        glam::Vec4::new(s.z, u.z, -f.z, 0.0),
        glam::Vec4::new(-s.dot(EYE), -u.dot(EYE), f.dot(EYE), 1.0),
    )
}

/// The OpenGL projection for `width` x `height`.
pub fn projection(width: u32, height: u32) -> Mat4 {
    let aspect = width as f64 / height as f64;
    let m = deferred_msaa_testkit::projection::perspective(
        FOV_Y.into(),
        aspect,
        NEAR.into(),
        Some(FAR.into()),
    );
    Mat4::from_cols_array(&m.map(|v| v as f32))
}

fn colour(i: u32) -> Vec3 {
    // Distinct, saturated enough to light differently, never black.
    let h = (i as f32 * 0.618_034).fract();
    let v = 0.45 + 0.5 * ((i * 7 % 5) as f32 / 4.0);
    let c = |o: f32| (((h + o) * std::f32::consts::TAU).cos() * 0.5 + 0.5) * 0.8 + 0.15;
    Vec3::new(c(0.0), c(1.0 / 3.0), c(2.0 / 3.0)) * v
}

/// Two triangles with one normal (computed once, so that it is the same
/// bits on both halves of the quad).
fn quad(out: &mut Vec<Face>, c: [Vec3; 4], colour: Vec3, object: u32, material: u32) {
    let first = face([c[0], c[1], c[2]], colour, object, material);
    let mut second = face([c[0], c[2], c[3]], colour, object, material);
    second.normal = first.normal;
    out.push(first);
    out.push(second);
}

fn face(mut corners: [Vec3; 3], colour: Vec3, object: u32, material: u32) -> Face {
    let mut normal = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize();
    if normal.dot(EYE - corners[0]) < 0.0 {
        corners.swap(1, 2);
        normal = -normal;
    }
    Face {
        corners,
        normal,
        colour,
        object,
        material,
    }
}

/// Every triangle of the scene.
pub fn faces() -> Vec<Face> {
    let mut f = Vec::new();
    let mut n = 0;
    let mut next = || {
        n += 1;
        colour(n)
    };
    // A 4x4 chequered floor reaching under the camera: coplanar tiles of
    // different colours.
    for i in 0..4 {
        for j in 0..4 {
            let (x0, z0) = (-3.0 + 1.5 * i as f32, -4.0 + 1.75 * j as f32);
            let (x1, z1) = (x0 + 1.5, z0 + 1.75);
            quad(
                &mut f,
                [
                    Vec3::new(x0, 0.0, z0),
                    Vec3::new(x1, 0.0, z0),
                    Vec3::new(x1, 0.0, z1),
                    Vec3::new(x0, 0.0, z1),
                ],
                next(),
                1,
                1 + (i + j) as u32 % 2,
            );
        }
    }
    // The back wall; sky above it and beside it.
    quad(
        &mut f,
        [
            Vec3::new(-3.0, 0.0, -4.0),
            Vec3::new(3.0, 0.0, -4.0),
            Vec3::new(3.0, 2.0, -4.0),
            Vec3::new(-3.0, 2.0, -4.0),
        ],
        next(),
        2,
        3,
    );
    // A box: front, side and top faces sharing edges.
    let (x0, x1, y1, z0, z1) = (-1.9, -0.8, 1.0, -1.1, 0.0);
    quad(
        &mut f,
        [
            Vec3::new(x0, 0.0, z1),
            Vec3::new(x1, 0.0, z1),
            Vec3::new(x1, y1, z1),
            Vec3::new(x0, y1, z1),
        ],
        next(),
        3,
        2,
    );
    quad(
        &mut f,
        [
            Vec3::new(x1, 0.0, z1),
            Vec3::new(x1, 0.0, z0),
            Vec3::new(x1, y1, z0),
            Vec3::new(x1, y1, z1),
        ],
        next(),
        3,
        2,
    );
    quad(
        &mut f,
        [
            Vec3::new(x0, y1, z1),
            Vec3::new(x1, y1, z1),
            Vec3::new(x1, y1, z0),
            Vec3::new(x0, y1, z0),
        ],
        next(),
        3,
        2,
    );
    // A panel turned about y and leaning back: its depth varies.
    quad(
        &mut f,
        [
            Vec3::new(0.2, 0.0, -1.6),
            Vec3::new(1.7, 0.0, -0.5),
            Vec3::new(1.5, 1.5, -1.0),
            Vec3::new(0.0, 1.5, -2.1),
        ],
        next(),
        4,
        1,
    );
    // A triangle floating in front of the panel.
    f.push(face(
        [
            Vec3::new(0.5, 0.55, 0.6),
            Vec3::new(1.3, 0.45, 0.7),
            Vec3::new(0.8, 1.2, 0.5),
        ],
        next(),
        5,
        3,
    ));
    f
}
