//! Method `taa` (temporal anti-aliasing): with a still camera it settles
//! within the per-sample 4x method's FLIP of the supersampled reference;
//! its reprojection is exact for a camera translated by whole pixels over
//! a plane, against the previous frame shifted on the CPU; the
//! neighbourhood clip keeps a disoccluded surface's old colour out; its
//! history is freed; bad options are one-line errors. Tiny images, a few
//! frames; the OpenGL 3.2 floor (standard depth, no clip control) runs the
//! same tests.

use crate::common;

use deferred_msaa_lab::bench::{self, BenchConfig};
use deferred_msaa_lab::compare;
use deferred_msaa_lab::gl::live_objects;
use deferred_msaa_lab::renderer::technique::Taa;
use deferred_msaa_lab::renderer::{AaMode, DepthMode, RenderOptions, Renderer, TaaOptions};
use deferred_msaa_lab::scene::{Aabb, Background, Camera, Material, Object, Scene};
use glam::{Mat4, Vec3};

/// After its warm-up (the bench renders [`AaMode::warmup_frames`] frames
/// from a reset before the frame it measures), `taa`'s FLIP against the
/// supersampled reference is at most the per-sample 4x method's, and below
/// `none`'s, on `greebles`, `transparent` and `thin`; on `box`, within
/// 1.25x of per-sample's (there the blend weighs the last phases more,
/// and every edge sits a fraction of a pixel off).
///
/// On `thin` against an 8x8 reference rendered here: the 4x pattern's
/// samples (at odd eighths of the pixel) are four of the 4x4 reference's
/// own sixteen, so on sub-pixel wires per-sample 4x matches that reference
/// better than it matches the scene.
#[test]
fn taa_on_a_still_camera_converges_to_within_per_sample_error() {
    if common::egl_context().is_none() {
        return;
    }
    let (w, h) = (160, 90);
    let asserted = ["box", "greebles", "transparent", "thin"];
    let config = BenchConfig {
        scenes: asserted.iter().map(|s| format!("builtin:{s}")).collect(),
        width: w,
        height: h,
        samples: vec![4],
        methods: bench::parse_methods("none,per-sample,taa").expect("methods parse"),
        frames: 1,
        warmup: 0,
        ..BenchConfig::default()
    };
    let out = bench::run(&config).expect("bench runs");
    // After the bench's own context: this one is current.
    let ctx = common::egl_context().expect("a context");
    let gl = ctx.gl();
    for scene in &asserted {
        let spec = format!("builtin:{scene}");
        let fine = (*scene == "thin").then(|| {
            let options = RenderOptions {
                width: 8 * w,
                height: 8 * h,
                aa: AaMode::None,
                ..RenderOptions::default()
            };
            let loaded = Scene::load(&spec).expect("scene");
            let mut r = Renderer::new(gl, |n| ctx.get_proc_address(n), &loaded, &options)
                .expect("renderer");
            r.render(gl).expect("8x8 reference");
            let big = r.read_final(gl).expect("8x8 reference image");
            r.destroy(gl);
            bench::downsample_srgb(&big, 8).expect("downsampling")
        });
        let flip = |method: &str| {
            let k = out
                .report
                .runs
                .iter()
                .position(|r| r.scene == spec && r.method == method)
                .unwrap_or_else(|| panic!("no run of {method} on {scene}"));
            let run = &out.report.runs[k];
            assert_eq!(run.samples, if method == "per-sample" { 4 } else { 1 });
            match &fine {
                Some(reference) => f64::from(
                    compare::flip(reference, &out.images[k])
                        .expect("same size")
                        .mean,
                ),
                None => run.flip_mean,
            }
        };
        let (none, per_sample, taa) = (flip("none"), flip("per-sample"), flip("taa"));
        let against = if fine.is_some() { "8x8" } else { "4x4" };
        eprintln!(
            "{scene}: FLIP against the {against} reference: none {none:.5}, per-sample 4x {per_sample:.5}, taa {taa:.5} ({:.2}x per-sample)",
            taa / per_sample
        );
        let bound = if *scene == "box" { 1.25 } else { 1.0 };
        assert!(
            taa <= bound * per_sample,
            "{scene}: taa FLIP {taa} is above {bound}x per-sample's {per_sample} ({against} reference)"
        );
        assert!(taa < none, "{scene}: taa FLIP {taa}, none {none}");
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

const W: u32 = 48;
const H: u32 = 32;
const FOV_Y: f32 = 0.7;
/// The distance of the plane from the camera.
const DEPTH: f32 = 10.0;

/// The world size of a pixel on the plane.
fn pixel_size() -> f32 {
    2.0 * DEPTH * (FOV_Y * 0.5).tan() / H as f32
}

/// An emissive quad in the plane z = `z` (camera at the origin looking
/// down −z), from `(x0, y0)` to `(x1, y1)` in pixels of the plane at
/// [`DEPTH`] (the view spans 0..W, 0..H from the bottom left).
fn quad(name: String, (x0, y0, x1, y1): (f32, f32, f32, f32), z: f32, material: usize) -> Object {
    let s = pixel_size() * (-z / DEPTH);
    let wx = |px: f32| (px - 0.5 * W as f32) * s;
    let wy = |py: f32| (py - 0.5 * H as f32) * s;
    Object {
        name,
        positions: vec![
            [wx(x0), wy(y0), z],
            [wx(x1), wy(y0), z],
            [wx(x1), wy(y1), z],
            [wx(x0), wy(y1), z],
        ],
        normals: vec![[0.0, 0.0, 1.0]; 4],
        uvs: vec![[0.0, 0.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        transform: Mat4::IDENTITY,
        antialias: true,
    }
}

fn emissive(rgb: [f32; 3]) -> Material {
    Material {
        base_color: [0.0, 0.0, 0.0, 1.0],
        emissive: rgb,
        metallic: 0.0,
        ..Material::default()
    }
}

fn scene(name: &str, objects: Vec<Object>, materials: Vec<Material>) -> Scene {
    let mut scene = Scene {
        name: name.into(),
        objects,
        materials,
        textures: Vec::new(),
        lights: Vec::new(),
        camera: Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, FOV_Y, 0.5, Some(100.0)),
        background: Background::Black,
        warnings: Vec::new(),
        bounds: Aabb::EMPTY,
        bars: Vec::new(),
    };
    scene.recompute_bounds();
    scene
}

/// A plane at [`DEPTH`] covering the view and a margin, in cells of
/// 2.6 pixels, each of its own colour (a hash of its position).
fn patterned_plane() -> Scene {
    let cell = 2.6;
    let (mut objects, mut materials) = (Vec::new(), Vec::new());
    let (lo, hi_x, hi_y) = (-8.0f32, W as f32 + 8.0, H as f32 + 8.0);
    let (mut y, mut j) = (lo, 0u32);
    while y < hi_y {
        let (mut x, mut i) = (lo, 0u32);
        while x < hi_x {
            let h = (i.wrapping_mul(73_856_093) ^ j.wrapping_mul(19_349_663))
                .wrapping_mul(2_654_435_761);
            let channel = |shift: u32| ((h >> shift) & 0xff) as f32 / 255.0;
            materials.push(emissive([channel(0), channel(8), channel(16)]));
            objects.push(quad(
                format!("cell {i} {j}"),
                (x, y, x + cell, y + cell),
                -DEPTH,
                materials.len() - 1,
            ));
            x += cell;
            i += 1;
        }
        y += cell;
        j += 1;
    }
    scene("taa plane", objects, materials)
}

/// The scene's camera moved by `(dx, dy)` pixels of the plane, parallel to it.
fn moved(scene: &Scene, dx: f32, dy: f32) -> Camera {
    let eye = Vec3::new(dx * pixel_size(), dy * pixel_size(), 0.0);
    Camera::look_at(
        eye,
        eye + Vec3::NEG_Z,
        scene.camera.fov_y,
        scene.camera.near,
        scene.camera.far,
    )
}

fn taa_options(depth_mode: DepthMode) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        aa: AaMode::Taa(TaaOptions::default()),
        depth_mode,
        ..RenderOptions::default()
    }
}

fn reprojected(gl: &glow::Context, renderer: &Renderer) -> image::RgbaImage {
    renderer
        .technique::<Taa>()
        .expect("the taa technique")
        .read_reprojected(gl)
        .expect("reading the reprojected history")
        .expect("a frame was rendered")
}

/// The Catmull-Rom weights of the taps at −1, 0, 1, 2 for a point `f` of
/// the way from tap 0 to tap 1.
fn catmull_rom(f: f64) -> [f64; 4] {
    [
        0.5 * (-f + 2.0 * f * f - f * f * f),
        0.5 * (2.0 - 5.0 * f * f + 3.0 * f * f * f),
        0.5 * (f + 4.0 * f * f - 3.0 * f * f * f),
        0.5 * (-f * f + f * f * f),
    ]
}

/// A camera translated parallel to a plane moves the plane's image by the
/// same number of pixels: the history the resolve finds at each pixel is
/// the previous frame's image shifted by the translation, computed here
/// from the previous final image. By whole pixels (3 across, 2 down) it is
/// that image's pixels, to the rounding of 8 bits; by 2.25 pixels across,
/// their Catmull-Rom interpolation (in linear light, the edge texels
/// repeated), to the rounding of the 8-bit image it is computed from. The
/// history is reset exactly where the shifted pixel comes from outside
/// the previous frame, and on the first frame nothing is found. In both
/// depth conventions; then the history is freed.
#[test]
fn reprojection_is_exact_for_a_camera_translated_parallel_to_a_plane() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let plane = patterned_plane();
    for depth_mode in [DepthMode::Auto, DepthMode::Standard] {
        let mut renderer = Renderer::new(
            gl,
            |name| ctx.get_proc_address(name),
            &plane,
            &taa_options(depth_mode),
        )
        .expect("renderer");
        let mode = renderer.depth_mode();
        for (kx, ky, tolerance) in [(3.0, 2i64, 1.0), (2.25, 1, 2.0)] {
            renderer.set_camera(plane.camera);
            renderer.reset_history();
            renderer.render(gl).expect("frame 1");
            let first = reprojected(gl, &renderer);
            assert!(first.pixels().all(|p| p[3] == 0), "{mode}: no history yet");
            let before = renderer.read_final(gl).expect("frame 1's image");

            renderer.set_camera(moved(&plane, kx as f32, ky as f32));
            renderer.render(gl).expect("frame 2");
            let found = reprojected(gl, &renderer);
            let (mut compared, mut worst) = (0, 0f64);
            for (x, row, p) in found.enumerate_pixels() {
                // Image rows run down; the camera moved up, so the plane's
                // image moved down: pixel (x, row) shows what was at
                // x + kx in row − ky.
                let (sx, srow) = (f64::from(x) + kx, i64::from(row) - ky);
                let inside = sx + 0.5 <= f64::from(W) && srow >= 0;
                assert_eq!(
                    p[3] == 255,
                    inside,
                    "{mode}, by {kx}: ({x}, {row}) found {p:?}"
                );
                if !inside {
                    continue;
                }
                let base = sx.floor();
                let weights = catmull_rom(sx - base);
                for c in 0..3 {
                    let linear: f64 = (0..4)
                        .map(|i| {
                            let tx = (base as i64 - 1 + i as i64).clamp(0, i64::from(W) - 1);
                            weights[i]
                                * common::srgb::decode(before.get_pixel(tx as u32, srow as u32)[c])
                        })
                        .sum();
                    worst =
                        worst.max((f64::from(p[c]) - common::srgb::encode(linear.max(0.0))).abs());
                }
                compared += 1;
            }
            eprintln!(
                "{mode}, by ({kx}, {ky}): {compared} pixels reprojected, the worst off by {worst:.2}/255"
            );
            let columns = (f64::from(W) + 0.5 - kx - 0.5).ceil() as usize;
            assert_eq!(compared, columns * (H as usize - ky as usize));
            assert!(
                worst <= tolerance,
                "{mode}, by ({kx}, {ky}): the reprojected history is off by {worst:.2}/255"
            );
        }
        renderer.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// A red quad in front of a grey plane, the camera moved sideways: the
/// plane pixels the quad covered in the previous frame reproject (through
/// the plane's depth) onto the quad's red in the history. The
/// neighbourhood clip pulls that history onto the grey this frame shows
/// around them, so those pixels come out grey at once rather than 90% red
/// (a ghost of the quad). The same renderer then switches size: the
/// history starts again from the frame itself.
#[test]
fn the_neighbourhood_clip_keeps_a_disoccluded_surface_from_ghosting() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let grey = [0.2, 0.2, 0.2];
    let objects = vec![
        quad(
            "plane".into(),
            (-20.0, -20.0, W as f32 + 20.0, H as f32 + 20.0),
            -DEPTH,
            0,
        ),
        // Half as far: it moves twice as many pixels as the plane.
        quad("quad".into(), (14.0, 8.0, 30.0, 24.0), -DEPTH / 2.0, 1),
    ];
    let two = scene(
        "taa ghost",
        objects,
        vec![emissive(grey), emissive([1.0, 0.0, 0.0])],
    );
    let mut renderer = Renderer::new(
        gl,
        |name| ctx.get_proc_address(name),
        &two,
        &taa_options(DepthMode::Auto),
    )
    .expect("renderer");
    // Settle on the still camera first.
    for _ in 0..8 {
        renderer.render(gl).expect("still frames");
    }
    let before = renderer.read_final(gl).expect("before");
    renderer.set_camera(moved(&two, 6.0, 0.0));
    renderer.render(gl).expect("moved frame");
    let after = renderer.read_final(gl).expect("after");
    let background = *before.get_pixel(2, 2);
    let is_red = |p: &image::Rgba<u8>| p[0] > 100 && p[1] < 60;
    let is_background = |p: &image::Rgba<u8>| (0..3).all(|c| p[c].abs_diff(background[c]) <= 2);
    // Where the frames are taken from `before` alone: the quad now covers
    // what it covered 12 pixels to the right (the plane moved 6), and the
    // history of a plane pixel is what was 6 pixels to its right.
    let red_before = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < i64::from(W)
            && y < i64::from(H)
            && is_red(before.get_pixel(x as u32, y as u32))
    };
    let (mut disoccluded, mut ghost_prone) = (0, 0);
    for (x, y, p) in after.enumerate_pixels() {
        let (x, y) = (i64::from(x), i64::from(y));
        // Red before; now at least two pixels from the quad.
        let quad_near = (-2..=2).any(|dy| (-2..=2).any(|dx| red_before(x + 12 + dx, y + dy)));
        if red_before(x, y) && !quad_near {
            disoccluded += 1;
            ghost_prone += usize::from(red_before(x + 6, y));
            assert!(
                is_background(p),
                "({x}, {y}): {p:?} where the plane ({background:?}) was uncovered"
            );
        }
    }
    eprintln!("{disoccluded} disoccluded pixels, {ghost_prone} of them with red history");
    assert!(ghost_prone >= 10, "{ghost_prone}");

    // A new size: the history is reallocated and starts from the frame.
    let smaller = RenderOptions {
        width: W / 2,
        height: H / 2,
        ..taa_options(DepthMode::Auto)
    };
    renderer.set_options(gl, &smaller).expect("resize");
    renderer.render(gl).expect("resized frame");
    let taa = renderer.technique::<Taa>().expect("taa");
    assert_eq!(taa.frames_since_reset(), 1);
    let history = taa.history_texture().expect("a history");
    assert_eq!((history.width, history.height), (W / 2, H / 2));
    assert!(reprojected(gl, &renderer).pixels().all(|p| p[3] == 0));
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// A thin bright bar in front of a far dark wall moves away over it (the
/// camera pans: the bar moves 3 pixels a frame, the wall, 40 times as far,
/// a fifteenth of a pixel). The wall's pixels barely move, so the history
/// the resolve finds there is the bar's; the neighbourhood clip of every
/// pixel, whatever its own motion, leaves no trail after one frame: every
/// pixel the bar uncovered and no longer touches is the wall's colour, as
/// the frame rendered without history shows it.
#[test]
fn a_bar_moving_away_over_a_far_wall_leaves_no_trail() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let far = 40.0 * DEPTH;
    let wall = quad(
        "far wall".into(),
        (-60.0, -60.0, W as f32 + 60.0, H as f32 + 60.0),
        -far,
        0,
    );
    let bar = quad(
        "bar".into(),
        (20.0, -4.0, 23.0, H as f32 + 4.0),
        -DEPTH / 2.0,
        1,
    );
    let mut two = scene(
        "taa trail",
        vec![wall, bar],
        vec![emissive([0.03, 0.03, 0.05]), emissive([1.0, 0.95, 0.8])],
    );
    two.camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, FOV_Y, 0.5, Some(2.0 * far));
    let mut renderer = Renderer::new(
        gl,
        |name| ctx.get_proc_address(name),
        &two,
        &taa_options(DepthMode::Auto),
    )
    .expect("renderer");
    for _ in 0..8 {
        renderer.render(gl).expect("still frames");
    }
    let before = renderer.read_final(gl).expect("before");
    // 1.5 pixels of the plane at DEPTH: the bar, at half that depth, moves 3.
    renderer.set_camera(moved(&two, 1.5, 0.0));
    renderer.render(gl).expect("moved frame");
    let after = renderer.read_final(gl).expect("after");
    let wall_colour = *before.get_pixel(2, 2);
    let bright = |p: &image::Rgba<u8>| p[0] > 60;
    let (mut uncovered, mut trail) = (0, Vec::new());
    for (x, y, p) in after.enumerate_pixels() {
        let (xi, yi) = (i64::from(x), i64::from(y));
        let was_bar = bright(before.get_pixel(x, y));
        // Now at least two pixels from where the bar is (pixels 17 to 20:
        // it moved 3 pixels left; its edges blend with the wall), known from
        // the geometry, not from this frame's image, where a trail would
        // hide itself.
        let near_bar = (15..22).contains(&xi) && yi >= 0;
        if was_bar && !near_bar {
            uncovered += 1;
            if (0..3).any(|c| p[c].abs_diff(wall_colour[c]) > 2) {
                trail.push(format!("({x}, {y}): {p:?}, the wall is {wall_colour:?}"));
            }
        }
    }
    eprintln!(
        "{uncovered} pixels the bar uncovered, {} with a trail",
        trail.len()
    );
    assert!(uncovered >= 20, "only {uncovered} pixels uncovered");
    assert!(
        trail.is_empty(),
        "a trail behind the bar: {:#?}",
        &trail[..trail.len().min(6)]
    );
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

/// Blend factors outside (0, 1], phase counts outside 2..=256 and unknown
/// options are one-line errors naming the entry, from the method parser,
/// the bench's list and the renderer's options alike.
#[test]
fn bad_taa_options_are_one_line_errors() {
    for bad in [
        "taa:alpha=2",
        "taa:alpha=0",
        "taa:alpha=x",
        "taa:phases=0",
        "taa:phases=1",
        "taa:phases=999",
        "taa:speed=3",
    ] {
        let e = bad.parse::<AaMode>().unwrap_err().to_string();
        assert_eq!(e.lines().count(), 1, "{bad}: {e}");
        assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
        let e = bench::parse_methods(&format!("none,{bad}"))
            .unwrap_err()
            .to_string();
        assert_eq!(e.lines().count(), 1, "{bad}: {e}");
    }
    let options = RenderOptions {
        aa: AaMode::Taa(TaaOptions {
            alpha: 2.0,
            phases: 8,
        }),
        ..RenderOptions::default()
    };
    let e = options.validate().unwrap_err().to_string();
    assert!(e.contains("alpha=2") && e.lines().count() == 1, "{e}");
    assert!(matches!(
        "taa:phases=16:alpha=0.05".parse::<AaMode>(),
        Ok(AaMode::Taa(TaaOptions { phases: 16, .. }))
    ));
}

/// The decal hook draws with the frame's own matrices: under `taa` the
/// projection it is given is the renderer's moved by that frame's jitter
/// (a decal drawn with the unjittered one would swim against the jittered
/// surface under it), a different one each frame.
#[test]
fn the_decal_hook_is_given_each_frames_jittered_projection() {
    use std::cell::RefCell;
    use std::rc::Rc;
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let plane = patterned_plane();
    let mut renderer = Renderer::new(
        gl,
        |name| ctx.get_proc_address(name),
        &plane,
        &taa_options(DepthMode::Auto),
    )
    .expect("renderer");
    let given = Rc::new(RefCell::new(Vec::new()));
    let given_in_hook = Rc::clone(&given);
    renderer.set_decal_hook(Some(Box::new(move |_, target| {
        given_in_hook
            .borrow_mut()
            .push((target.view, target.projection));
    })));
    let mut projections: Vec<Mat4> = Vec::new();
    for frame in 0..3 {
        renderer.render(gl).expect("frame");
        let [jx, jy] = renderer
            .technique::<Taa>()
            .and_then(Taa::last_jitter)
            .expect("the frame's jitter");
        assert!(jx != 0.0 || jy != 0.0, "frame {frame}: no jitter");
        let shift =
            Mat4::from_translation(Vec3::new(2.0 * jx / W as f32, 2.0 * jy / H as f32, 0.0));
        let (view, projection) = *given.borrow().last().expect("the hook ran");
        assert_eq!(view, plane.camera.view, "frame {frame}");
        let expected = shift * renderer.projection();
        assert!(
            projection.abs_diff_eq(expected, 1e-6),
            "frame {frame}: the hook got {projection:?}, the frame drew with {expected:?}"
        );
        assert!(
            !projection.abs_diff_eq(renderer.projection(), 1e-6),
            "frame {frame}: unjittered"
        );
        projections.push(projection);
    }
    assert!(projections[0] != projections[1] && projections[1] != projections[2]);
    assert_eq!(given.borrow().len(), 3, "once a frame");
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}
