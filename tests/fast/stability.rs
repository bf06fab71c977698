//! The stiff and extreme catalogue (numerical stability): every case
//! asserts finite outputs and the right classification of geometry and
//! background, through a host G-buffer retrofitted by the public API.

use crate::common;

use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::gbuffer::{DepthSetup, GBufferLayout, precision_warnings};
use deferred_msaa_lab::gl::{ExtraFns, Format, TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, SampleImage};
use deferred_msaa_lab::resolve::{ResolveRule, ResolveSettings};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::{perspective, perspective_reversed};
use deferred_msaa_testkit::scene::triangle;

struct Case {
    name: String,
    width: u32,
    height: u32,
    fov_y: f64,
    near: f64,
    far: Option<f64>,
    reversed: bool,
    depth: Format,
    position: Format,
    /// Distance of the model, and its size across.
    distance: f64,
    detail_gap: f64,
}

impl Case {
    fn new(name: &str) -> Case {
        Case {
            name: name.into(),
            width: 48,
            height: 32,
            fov_y: 0.9,
            near: 0.1,
            far: Some(1000.0),
            reversed: false,
            depth: Format::Depth32f,
            position: Format::Rgba32f,
            distance: 20.0,
            detail_gap: 0.5,
        }
    }

    fn projection(&self) -> [f64; 16] {
        let aspect = self.width as f64 / self.height as f64;
        if self.reversed {
            perspective_reversed(self.fov_y, aspect, self.near, self.far)
        } else {
            perspective(self.fov_y, aspect, self.near, self.far)
        }
    }

    /// A model filling the middle half of the view: a hull and a raised
    /// panel `detail_gap` in front of it. The rest of the view is background.
    fn triangles(&self) -> Vec<f32> {
        let half = (self.fov_y / 2.0).tan() * self.distance * 0.5;
        let (z, h) = (-self.distance, half);
        let zp = z + self.detail_gap;
        let mut v = Vec::new();
        let c = |x: f64, y: f64, z: f64| [x as f32, y as f32, z as f32];
        triangle(
            &mut v,
            [c(-h, -h, z), c(h, -h, z), c(h, h, z)],
            [0.8, 0.2, 0.2],
        );
        triangle(
            &mut v,
            [c(-h, -h, z), c(h, h, z), c(-h, h, z)],
            [0.8, 0.2, 0.2],
        );
        let p = h * 0.4;
        triangle(
            &mut v,
            [c(-p, -p, zp), c(p, -p, zp), c(0.0, p, zp)],
            [0.2, 0.8, 0.2],
        );
        v
    }
}

struct Outcome {
    depth: SampleImage,
    position: SampleImage,
    albedo: SampleImage,
    normal: SampleImage,
}

/// Draw, resolve (key from position and from depth) and read back.
fn run(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    case: &Case,
    key_from_position: bool,
) -> Outcome {
    let gl = ctx.gl();
    let extra = ExtraFns::load(gl, |n| ctx.get_proc_address(n));
    if case.reversed {
        assert!(
            extra.set_clip_depth_zero_to_one(true),
            "glClipControl is needed for reversed-Z"
        );
    }
    let mut host =
        Host::new(gl, case.width, case.height, case.position, case.depth).expect("the toy host");
    host.set_triangles(gl, &case.triangles())
        .expect("the toy host's triangles");
    let options = RetrofitOptions {
        samples: 4,
        rules: vec![(ColorAttachment(2), ResolveRule::BlendNormal)],
        position_attachment: key_from_position.then_some(ColorAttachment(1)),
        resolve: ResolveSettings {
            fast_path: false,
            ..ResolveSettings::default()
        },
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    unsafe {
        glow::HasContext::bind_framebuffer(
            gl,
            glow::FRAMEBUFFER,
            Some(msaa.begin_frame(gl).unwrap()),
        )
    };
    let m = case.projection();
    host.draw(gl, &m, case.reversed);
    msaa.resolve(
        gl,
        &deferred_msaa_testkit::projection::frame(&m, case.reversed),
    )
    .unwrap();
    if case.reversed {
        extra.set_clip_depth_zero_to_one(false);
    }
    let mut rb = Readback::new(gl).unwrap();
    let out = Outcome {
        depth: rb.read(gl, TextureRef::from(&host.depth), 1).unwrap(),
        position: rb.read(gl, TextureRef::from(host.position()), 1).unwrap(),
        albedo: rb.read(gl, TextureRef::from(host.color()), 1).unwrap(),
        normal: rb.read(gl, TextureRef::from(host.normal()), 1).unwrap(),
    };
    rb.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);
    out
}

/// Finite everywhere; the view's centre (inside the panel) and the model's
/// interior are geometry at the right distance; the corners are background.
fn assert_classified(case: &Case, out: &Outcome, what: &str) {
    let clear = if case.reversed { 0.0 } else { 1.0 };
    for img in [&out.depth, &out.position, &out.albedo, &out.normal] {
        assert!(
            img.data.iter().all(|v| v.is_finite()),
            "{} ({what}): non-finite output",
            case.name
        );
    }
    let (w, h) = (case.width, case.height);
    if w < 8 || h < 8 {
        return;
    }
    // Corners: background, with the clear depth and the cleared position.
    for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
        assert_eq!(
            out.depth.get(0, x, y)[0],
            clear,
            "{} ({what}): corner ({x},{y}) is not background",
            case.name
        );
        assert_eq!(
            out.position.get(0, x, y),
            [0.0; 4],
            "{} ({what}): corner position",
            case.name
        );
    }
    // Centre: the panel, in front of the hull by the detail gap.
    let centre = out.position.get(0, w / 2, h / 2);
    let z_panel = -(case.distance - case.detail_gap);
    assert!(
        ((centre[2] as f64) - z_panel).abs() <= 1e-3 * case.distance.max(1.0),
        "{} ({what}): centre z {} expected {z_panel}",
        case.name,
        centre[2]
    );
    assert_ne!(
        out.depth.get(0, w / 2, h / 2)[0],
        clear,
        "{} ({what}): the model is lost to background",
        case.name
    );
    // Hull beside the panel: geometry, and farther than the panel.
    let hull = out.position.get(0, w / 2 + w / 10, h / 2 + h / 5);
    assert!(
        ((hull[2] as f64) + case.distance).abs() <= 1e-3 * case.distance.max(1.0),
        "{} ({what}): hull z {} expected {}",
        case.name,
        hull[2],
        -case.distance
    );
    // Normals of geometry are unit length (never NaN).
    let n = out.normal.get(0, w / 2, h / 2);
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    assert!(
        (len - 1.0).abs() < 1e-2,
        "{} ({what}): normal length {len}",
        case.name
    );
}

fn check(case: &Case) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let before = live_objects();
    for key_from_position in [true, false] {
        let out = run(&ctx, case, key_from_position);
        assert_classified(
            case,
            &out,
            if key_from_position {
                "key from position"
            } else {
                "key from depth"
            },
        );
    }
    assert_eq!(live_objects(), before);
}

#[test]
fn near_1e_minus_4_with_far_1e9() {
    for depth in [Format::Depth32f, Format::Depth24] {
        check(&Case {
            near: 1e-4,
            far: Some(1e9),
            depth,
            name: format!("near 1e-4 far 1e9 {depth}"),
            ..Case::new("")
        });
    }
}

#[test]
fn infinite_far_plane() {
    check(&Case {
        far: None,
        ..Case::new("infinite far")
    });
}

#[test]
fn reversed_z() {
    check(&Case {
        reversed: true,
        ..Case::new("reversed-Z")
    });
    check(&Case {
        reversed: true,
        far: None,
        ..Case::new("reversed-Z infinite")
    });
}

#[test]
fn d24_and_d32f_agree_on_an_ordinary_scene() {
    check(&Case {
        depth: Format::Depth24,
        ..Case::new("D24")
    });
    check(&Case {
        depth: Format::Depth32f,
        ..Case::new("D32F")
    });
}

#[test]
fn a_model_200_km_away_through_a_half_degree_lens() {
    let fso = GBufferLayout::freespace_open();
    let rec = GBufferLayout::recommended();
    let standard = DepthSetup {
        near: 0.01,
        far: Some(1.0e6),
        reversed: false,
    };
    let reversed = DepthSetup {
        reversed: true,
        ..standard
    };
    // FreeSpace Open's layout: detected and warned about.
    let w = precision_warnings(&fso, &standard, 200_000.0, 5.0);
    assert!(w.iter().any(|m| m.contains("65504")), "{w:#?}");
    assert!(w.iter().any(|m| m.contains("DEPTH_COMPONENT24")), "{w:#?}");
    // The recommended layout with reversed-Z holds it: no warning, and the
    // model and its 5-unit detail survive the resolve.
    assert!(precision_warnings(&rec, &reversed, 200_000.0, 5.0).is_empty());
    let case = Case {
        fov_y: 0.5f64.to_radians(),
        near: 0.01,
        far: Some(1.0e6),
        reversed: true,
        distance: 200_000.0,
        detail_gap: 5.0,
        depth: rec.depth,
        position: rec.colors[1].format,
        ..Case::new("200 km, 0.5°, recommended layout")
    };
    check(&case);
    // What FreeSpace Open's layout does with it: the FP16 position overflows
    // (to infinity, or clamped at 65504 by some drivers): the depth is gone.
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let fso_case = Case {
        depth: Format::Depth24,
        position: Format::Rgba16f,
        reversed: false,
        ..case
    };
    let out = run(&ctx, &fso_case, true);
    let z = out.position.get(0, fso_case.width / 2, fso_case.height / 2)[2];
    assert!(
        !z.is_finite() || z.abs() <= 65504.0,
        "FP16 position unexpectedly held {z}"
    );
    assert!(
        ((z as f64) + 199_995.0).abs() > 1000.0,
        "FP16 position unexpectedly held {z}"
    );
}

#[test]
fn fields_of_view_from_a_hundredth_of_a_degree_to_179() {
    for deg in [0.01f64, 0.5, 10.0, 60.0, 120.0, 179.0] {
        check(&Case {
            fov_y: deg.to_radians(),
            name: format!("fov {deg}°"),
            ..Case::new("")
        });
    }
}

#[test]
fn framebuffers_from_1x1_to_the_maximum_width() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let max = deferred_msaa_lab::gl::Capabilities::query(ctx.gl()).max_texture_size;
    drop(ctx);
    for (w, h) in [(1, 1), (2, 1), (1, 3), (max, 1), (1, max)] {
        check(&Case {
            width: w,
            height: h,
            name: format!("{w}x{h}"),
            ..Case::new("")
        });
    }
}

#[test]
fn resolve_is_bit_identical_run_after_run() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let case = Case::new("determinism");
    let first = run(&ctx, &case, true);
    for _ in 0..3 {
        let again = run(&ctx, &case, true);
        for (a, b) in [
            (&first.albedo, &again.albedo),
            (&first.position, &again.position),
            (&first.normal, &again.normal),
            (&first.depth, &again.depth),
        ] {
            let same = a
                .data
                .iter()
                .zip(&b.data)
                .all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same, "resolved output differs between runs");
        }
    }
}

#[test]
fn hdr_values_up_to_65504_stay_finite() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut host = Host::new(gl, 32, 32, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    let mut v = Vec::new();
    // A 65504-bright triangle over a dim one: edge pixels blend the two.
    triangle(
        &mut v,
        [[-9.0, -9.0, -10.0], [9.0, -9.0, -10.0], [0.0, 9.0, -10.0]],
        [0.5, 0.5, 0.5],
    );
    triangle(
        &mut v,
        [[-3.0, -3.0, -9.99], [3.0, -3.0, -9.99], [0.0, 3.0, -9.99]],
        [65504.0, 65504.0, 1.0],
    );
    host.set_triangles(gl, &v)
        .expect("the toy host's triangles");
    let options = RetrofitOptions {
        samples: 4,
        rules: vec![(ColorAttachment(0), ResolveRule::BlendHdr)],
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    unsafe {
        glow::HasContext::bind_framebuffer(
            gl,
            glow::FRAMEBUFFER,
            Some(msaa.begin_frame(gl).unwrap()),
        )
    };
    let m = perspective(1.2, 1.0, 0.1, Some(100.0));
    host.draw(gl, &m, false);
    msaa.resolve(gl, &deferred_msaa_testkit::projection::frame(&m, false))
        .unwrap();
    let mut rb = Readback::new(gl).unwrap();
    let albedo = rb.read(gl, TextureRef::from(host.color()), 1).unwrap();
    assert!(
        albedo.data.iter().all(|v| v.is_finite() && *v <= 65504.0),
        "HDR blend left the FP16 range"
    );
    // Edge pixels blend the two in the tonemapped domain: strictly between them.
    let blended = albedo
        .data
        .chunks_exact(4)
        .filter(|p| p[0] > 0.6 && p[0] < 65000.0)
        .count();
    assert!(blended > 0, "no blended HDR edge pixel");
    rb.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);
}
