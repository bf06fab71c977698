//! The built-in scenes that each show one kind of input: `box`, `thin`,
//! `zfight`, `emissive`, `lamps`, `slats` and `transparent`.

use glam::{Mat4, Quat, Vec3};

use super::super::{AlphaMode, Background, Camera, Light, Material, Scene, TextureData};
use super::tools::{MeshBuilder, Rng, SceneBuilder, emissive_material, rgb};

pub(super) fn box_scene() -> Scene {
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

pub(super) fn thin() -> Scene {
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

pub(super) fn zfight() -> Scene {
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

pub(super) fn emissive() -> Scene {
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

/// The deferred tutorial's picture: a 3x3 grid of turned boxes on a dark
/// floor, twelve coloured point lights among them, and each light drawn as
/// a small bright cube after lighting. The cubes are a blended material at
/// alpha 1 with an emissive colour, so the renderer draws them in its
/// forward (transparent) pass, as the tutorial draws its light cubes.
pub(super) fn lamps() -> Scene {
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
pub(super) fn slats() -> Scene {
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

pub(super) fn transparent() -> Scene {
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
