//! Selective anti-aliasing through the demo renderer: objects that opt out
//! (`Object::antialias`, a glTF `extras` field) and screen regions. Outside
//! the selection a pixel takes sample 0 of every attachment, exactly.
//! (The resolve's selection math against the CPU reference, every criterion
//! and schedule, is in `tests/retrofit.rs`.)

use crate::common;

use deferred_msaa_lab::gl::{TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, SampleImage};
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer};
use deferred_msaa_lab::resolve::{Region, ResolveSettings, Selection};
use deferred_msaa_lab::scene::Scene;

const W: u32 = 128;
const H: u32 = 72;

/// The colour attachment's samples (the twin) and its resolved texture.
fn color_samples_and_resolved(
    gl: &glow::Context,
    renderer: &Renderer,
) -> (SampleImage, SampleImage) {
    let slot = renderer
        .layout()
        .index_of("color")
        .expect("a color attachment");
    let mut readback = Readback::new(gl).expect("readback");
    let (_, twins, _) = renderer
        .retrofit()
        .expect("multisampled")
        .inputs()
        .expect("twins");
    let samples = readback.read(gl, twins[slot], 1).expect("samples");
    let resolved = readback
        .read(gl, TextureRef::from(&renderer.gbuffer().colors[slot]), 1)
        .expect("resolved");
    readback.destroy(gl);
    (samples, resolved)
}

/// Pixels whose samples are not all equal: where a resolve could blend.
fn varied(samples: &SampleImage, x: u32, y: u32) -> bool {
    (1..samples.samples).any(|s| samples.get(s, x, y) != samples.get(0, x, y))
}

fn render(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    scene: &Scene,
    aa: AaMode,
) -> Renderer {
    let gl = ctx.gl();
    let options = RenderOptions {
        width: W,
        height: H,
        aa,
        ..RenderOptions::default()
    };
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), scene, &options).expect("renderer");
    renderer.render(gl).expect("frame");
    renderer
}

#[test]
fn objects_that_opt_out_take_sample_zero() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let mut scene = Scene::load("builtin:greebles").expect("scene");
    // Every other object opts out.
    for (i, object) in scene.objects.iter_mut().enumerate() {
        object.antialias = i % 2 == 0;
    }
    assert!(
        scene.objects.iter().any(|o| !o.antialias) && scene.objects.iter().any(|o| o.antialias)
    );
    let renderer = render(&ctx, &scene, AaMode::Resolve(ResolveSettings::default()));
    let (samples, resolved) = color_samples_and_resolved(gl, &renderer);
    let (mut opted_out, mut blended) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            if !varied(&samples, x, y) {
                continue;
            }
            // color.a is the flag: 1 for objects that are anti-aliased.
            let wanted = (0..samples.samples).any(|s| samples.get(s, x, y)[3] >= 0.5);
            let got = resolved.get(0, x, y);
            if wanted {
                blended += usize::from(got != samples.get(0, x, y));
            } else {
                opted_out += 1;
                assert_eq!(
                    got,
                    samples.get(0, x, y),
                    "({x},{y}): no sample wants AA, but the pixel is not sample 0"
                );
            }
        }
    }
    assert!(
        opted_out > 20,
        "only {opted_out} varied pixels of opted-out objects"
    );
    assert!(
        blended > 20,
        "only {blended} blended pixels of anti-aliased objects"
    );
    renderer.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

#[test]
fn outside_a_screen_rectangle_pixels_take_sample_zero() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let scene = Scene::load("builtin:greebles").expect("scene");
    let (rx, ry, rw, rh) = (32u32, 16u32, 64u32, 40u32);
    let settings = ResolveSettings {
        selection: Selection {
            region: Some(Region::Rect {
                x: rx as f64,
                y: ry as f64,
                width: rw as f64,
                height: rh as f64,
            }),
            ..Selection::default()
        },
        ..ResolveSettings::default()
    };
    let renderer = render(&ctx, &scene, AaMode::Resolve(settings));
    let (samples, resolved) = color_samples_and_resolved(gl, &renderer);
    let (mut outside, mut inside_blended) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            if !varied(&samples, x, y) {
                continue;
            }
            let inside = (rx..rx + rw).contains(&x) && (ry..ry + rh).contains(&y);
            let got = resolved.get(0, x, y);
            if inside {
                inside_blended += usize::from(got != samples.get(0, x, y));
            } else {
                outside += 1;
                assert_eq!(
                    got,
                    samples.get(0, x, y),
                    "({x},{y}) is outside the rectangle"
                );
            }
        }
    }
    assert!(
        outside > 20 && inside_blended > 20,
        "outside {outside}, inside blended {inside_blended}"
    );
    renderer.destroy(gl);
}
