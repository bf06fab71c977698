//! Pixels of three surfaces with two layers: a thin box's front face, a
//! sub-pixel sliver of its side face and a far wall (docs/resolve.md, "The
//! second layer"). Rasterised through the retrofit by the toy host, lit by
//! its lighting, mixed; checked against the CPU reference over the samples
//! read back and against the samples' own proportions.

use crate::common;

use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, LayerMix, NormalAttachment};
use deferred_msaa_lab::gl::{Attachment, Format, Framebuffer, Texture2d, TextureRef, live_objects};
use deferred_msaa_lab::readback::{Readback, pixel_samples};
use deferred_msaa_lab::resolve::ResolveSettings;
use deferred_msaa_lab::resolve::cpu::PixelPlace;
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;

const W: u32 = 48;
const H: u32 = 40;
const FOV_Y: f64 = 0.8;
/// The column whose pixels hold the three surfaces.
const COLUMN: f64 = 30.0;
const BOX: [f32; 3] = [0.8, 0.7, 0.6];
const WALL: [f32; 3] = [0.05, 0.06, 0.1];
/// The front face's distance, and how far the side face recedes across
/// its sliver.
const FRONT_Z: f64 = 10.0;
const SIDE_DEPTH: f64 = 0.06;

fn projection() -> [f64; 16] {
    perspective(FOV_Y, W as f64 / H as f64, 0.5, Some(100.0))
}

/// A view-space point at distance `z` that projects to window column
/// `sx` (pixels from the left) and NDC height `ny`.
fn at(sx: f64, ny: f64, z: f64) -> [f32; 3] {
    let tan = (FOV_Y / 2.0).tan();
    let nx = 2.0 * sx / W as f64 - 1.0;
    let aspect = W as f64 / H as f64;
    [
        (nx * z * tan * aspect) as f32,
        (ny * z * tan) as f32,
        -z as f32,
    ]
}

fn quad(v: &mut Vec<f32>, corners: [[f32; 3]; 4], colour: [f32; 3]) {
    let [a, b, c, d] = corners;
    triangle(v, [a, b, c], colour);
    triangle(v, [a, c, d], colour);
}

/// A far wall, then three boxes in bands of rows: each a front face
/// (facing the eye) up to `COLUMN + 0.5 + e1` and its side face receding
/// from there to `COLUMN + 0.5 + e2`. At 4x (sample x offsets -0.375,
/// -0.125, 0.125, 0.375) the column's samples are then front : side : wall
/// = 1 : 1 : 2, 2 : 1 : 1 and 1 : 2 : 1, one proportion per band.
fn triangles() -> Vec<f32> {
    let mut v = Vec::new();
    let far = 60.0;
    quad(
        &mut v,
        [
            at(-10.0, -1.5, far),
            at(W as f64 + 10.0, -1.5, far),
            at(W as f64 + 10.0, 1.5, far),
            at(-10.0, 1.5, far),
        ],
        WALL,
    );
    let bands = [
        ((-0.9, -0.4), (-0.25, 0.0)),
        ((-0.25, 0.25), (0.0, 0.25)),
        ((0.4, 0.9), (-0.25, 0.25)),
    ];
    for ((y0, y1), (e1, e2)) in bands {
        let (x1, x2) = (COLUMN + 0.5 + e1, COLUMN + 0.5 + e2);
        let back = FRONT_Z + SIDE_DEPTH;
        quad(
            &mut v,
            [
                at(4.0, y0, FRONT_Z),
                at(x1, y0, FRONT_Z),
                at(x1, y1, FRONT_Z),
                at(4.0, y1, FRONT_Z),
            ],
            BOX,
        );
        quad(
            &mut v,
            [
                at(x1, y0, FRONT_Z),
                at(x2, y0, back),
                at(x2, y1, back),
                at(x1, y1, FRONT_Z),
            ],
            BOX,
        );
    }
    v
}

/// Every pixel the box and the wall share: the final image, with two
/// layers, is the samples' own mix of the lit surfaces (the front face and
/// the side are lit alike here, so two layers can be exact), and the
/// coverage is the CPU reference's, which gives every sample of the
/// dropped third cluster to a kept layer.
#[test]
fn a_front_face_a_side_sliver_and_a_wall_keep_their_shares() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let mut host = Host::new(gl, W, H, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    host.set_triangles(gl, &triangles()).expect("the triangles");
    let mut readback = Readback::new(gl).unwrap();
    let output = Texture2d::new(gl, "lit output", Format::Rgba8, W, H).unwrap();
    let fbo = Framebuffer::new(
        gl,
        "lit output",
        &[(Attachment::Color(0), TextureRef::from(&output))],
        &[Some(0)],
    )
    .unwrap();
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        layer_mix: LayerMix::Linear,
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let n = msaa.samples();
    if n != 4 {
        common::skip(&format!(
            "the bands are laid out for 4x; the context gives {n}x"
        ));
        msaa.destroy(gl);
        fbo.destroy(gl);
        output.destroy(gl);
        readback.destroy(gl);
        host.destroy(gl);
        return;
    }
    let frame = deferred_msaa_testkit::projection::frame(&projection(), false);
    unsafe {
        use glow::HasContext;
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap()));
    }
    host.draw(gl, &projection(), false);
    // The samples, before the resolve reads them.
    let (depth, colors, _) = msaa.inputs().unwrap();
    let depth = readback.read(gl, depth, 1).unwrap();
    let colors: Vec<_> = colors
        .iter()
        .map(|t| readback.read(gl, *t, 1).unwrap())
        .collect();
    let cpu = msaa.cpu_reference(&frame).unwrap();
    msaa.resolve(gl, &frame).unwrap();
    let coverage = readback
        .read(gl, msaa.second_layer_coverage().unwrap(), 1)
        .unwrap();
    host.light(gl, fbo.raw(), 1.0);
    assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
    host.light(gl, fbo.raw(), 1.0);
    msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
    let mixed = readback.read(gl, TextureRef::from(&output), 1).unwrap();

    // front, side, wall sample counts -> pixels seen with them
    let mut seen = std::collections::BTreeMap::<(usize, usize, usize), usize>::new();
    let mut bad = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let px = pixel_samples(&depth, &colors, x, y);
            let (mut front, mut side, mut wall) = (0, 0, 0);
            for s in 0..n as usize {
                let (position, normal) = (px.attachments[1][s], px.attachments[2][s]);
                if position[2] < -30.0 {
                    wall += 1;
                } else if normal[2] > 0.999 {
                    front += 1;
                } else if normal[0] > 0.4 {
                    // The side face recedes by 0.06 across a quarter or a
                    // half pixel (0.05 or 0.1 units here): its normal is
                    // about (0.75, 0, 0.66) or (0.5, 0, 0.87).
                    side += 1;
                }
            }
            let second = cpu.resolve_second_layer_at(
                &px,
                Some(PixelPlace {
                    x,
                    y,
                    width: W,
                    height: H,
                }),
            );
            if front + side + wall == n as usize && side > 0 && wall > 0 {
                *seen.entry((front, side, wall)).or_default() += 1;
                assert!(
                    second.joined.iter().sum::<usize>() > 0,
                    "({x},{y}) {front}:{side}:{wall}: no sample joined a kept layer"
                );
            }
            let alpha = f64::from(coverage.get(0, x, y)[0]);
            if (alpha - second.coverage).abs() > 1e-6 && !second.ambiguous {
                bad.push(format!(
                    "({x},{y}): coverage {alpha}, the CPU reference's {}",
                    second.coverage
                ));
            }
            // The samples' own proportions of the lit surfaces.
            let want: Vec<f64> = (0..3)
                .map(|c| {
                    (0..n as usize)
                        .map(|s| px.attachments[0][s][c])
                        .sum::<f64>()
                        / f64::from(n)
                })
                .collect();
            let got = mixed.get(0, x, y);
            if (0..3).any(|c| (f64::from(got[c]) - want[c]).abs() > 1.5 / 255.0) {
                bad.push(format!(
                    "({x},{y}) {front}:{side}:{wall}, α {alpha}: lit {got:?}, the samples' mix {want:?}"
                ));
            }
        }
    }
    for proportion in [(1, 1, 2), (2, 1, 1), (1, 2, 1)] {
        assert!(
            seen.get(&proportion).copied().unwrap_or(0) >= 3,
            "front : side : wall = {proportion:?} in too few pixels: {seen:?}"
        );
    }
    assert!(
        bad.is_empty(),
        "{} pixels wrong: {:#?}",
        bad.len(),
        &bad[..bad.len().min(8)]
    );
    msaa.destroy(gl);
    fbo.destroy(gl);
    output.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}
