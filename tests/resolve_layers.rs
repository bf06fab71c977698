//! The resolve's GLSL against its CPU reference for N = 2, 4, 8 and 16.
//!
//! llvmpipe offers only 4x MSAA, so the same resolve body is compiled over
//! `sampler2DArray` inputs (one layer per sample, DESIGN.md section 5) and fed
//! random and adversarial per-sample data: ties, all background, a single
//! geometry sample, NaN and Inf values, denormals, equal depths with different
//! colours, opposite normals, HDR values up to 65504.

// Per-sample arrays run in parallel; indices read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

mod common;

use common::Rng;
use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::gl::{
    Attachment, Format, Framebuffer, Texture2d, Texture2dArray, TextureRef,
};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::cpu::{CpuKeySource, CpuResolve, PixelSamples};
use deferred_msaa_lab::resolve::{
    DepthProjection, KeySource, ResolveInputs, ResolveMethod, ResolveParams, ResolveRule,
    ResolveSettings, ResolveSlot, Resolver, Window,
};

const W: u32 = 24;
const H: u32 = 16;
const RULES: [ResolveRule; 5] = [
    ResolveRule::Blend,       // colour
    ResolveRule::Blend,       // position (the key)
    ResolveRule::BlendNormal, // normal, gloss in w
    ResolveRule::BlendHdr,    // emissive
    ResolveRule::Select,      // material id (RGBA32UI)
];
const CLEAR_DEPTH: f32 = 1.0;
const FOV_Y: f64 = 0.9;

/// One pixel's inputs, in f32 as the GPU sees them.
struct Case {
    depth: Vec<f32>,
    atts: [Vec<[f32; 4]>; 5],
}

fn gen_case(rng: &mut Rng, n: usize, kind: u32) -> Case {
    let mut depth = vec![0.5f32; n];
    let mut z = vec![0.0f32; n];
    let base = rng.range(1.0, 200.0);
    // A pixel's footprint at distance `base` for a HxFOV_Y camera.
    let foot = base * (FOV_Y as f32 / H as f32).tan();
    for i in 0..n {
        z[i] = match kind {
            0 => rng.range(1.0, 200.0),                    // unrelated depths
            1 => base,                                     // all equal (uniform)
            2 => base + foot * rng.below(3) as f32,        // clusters and exact ties
            3 => base + foot * rng.range(-6.0, 6.0),       // across the window edges
            4 => base,                                     // background (below)
            5 => base + foot * rng.range(0.0, 3.0),        // half background (below)
            6 => base,                                     // one geometry sample (below)
            7 => base + foot * rng.below(2) as f32 * 20.0, // two surfaces
            _ => rng.range(1.0, 200.0),
        };
    }
    match kind {
        4 => depth.iter_mut().for_each(|d| *d = CLEAR_DEPTH),
        5 => (0..n)
            .filter(|i| i % 2 == 1)
            .for_each(|i| depth[i] = CLEAR_DEPTH),
        6 => {
            let keep = rng.below(n as u32) as usize;
            (0..n)
                .filter(|&i| i != keep)
                .for_each(|i| depth[i] = CLEAR_DEPTH);
        }
        _ => {}
    }
    let mut atts: [Vec<[f32; 4]>; 5] = Default::default();
    for i in 0..n {
        let colour = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
        let mut position = [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), -z[i], 1.0];
        let mut normal = {
            let v = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-3);
            [v[0] / l, v[1] / l, v[2] / l, rng.unit()]
        };
        let mut emissive = [
            rng.range(0.0, 4.0),
            rng.range(0.0, 4.0),
            rng.range(0.0, 4.0),
            1.0,
        ];
        let material = [rng.below(255) as f32, i as f32, 0.0, 1.0];
        // Sprinkle the adversarial values.
        match (kind, rng.below(8)) {
            (_, 0) if kind >= 8 => {
                let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40];
                let v = bad[rng.below(4) as usize];
                emissive[rng.below(3) as usize] = v;
            }
            (_, 1) => emissive = [65504.0, rng.range(0.0, 65504.0), 1.0, 1.0],
            (_, 2) if kind >= 8 => position[2] = f32::NAN, // a non-finite key is background
            (_, 3) => {
                normal = if i % 2 == 0 {
                    [0.0, 0.0, 1.0, 0.5]
                } else {
                    [0.0, 0.0, -1.0, 0.25]
                }
            }
            _ => {}
        }
        atts[0].push(colour);
        atts[1].push(position);
        atts[2].push(normal);
        atts[3].push(emissive);
        atts[4].push(material);
    }
    Case { depth, atts }
}

fn close(gpu: f32, cpu: f64) -> bool {
    if cpu.is_nan() {
        return gpu.is_nan();
    }
    if cpu.is_infinite() {
        return gpu as f64 == cpu;
    }
    ((gpu as f64) - cpu).abs() <= 2e-6 + 2e-5 * cpu.abs()
}

struct Harness {
    n: u32,
    inputs: Vec<Texture2dArray>,
    depth: Texture2dArray,
    outputs: Vec<Texture2d>,
    out_depth: Texture2d,
    target: Framebuffer,
    cases: Vec<Case>,
}

impl Harness {
    fn new(gl: &glow::Context, n: u32, seed: u64) -> Harness {
        let mut rng = Rng::new(seed);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| gen_case(&mut rng, n as usize, p % 10))
            .collect();
        let formats = [
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32ui,
        ];
        let mut inputs = Vec::new();
        for (k, &format) in formats.iter().enumerate() {
            let mut bytes: Vec<u8> = Vec::new();
            for s in 0..n as usize {
                for case in &cases {
                    let v = case.atts[k][s];
                    if format == Format::Rgba32ui {
                        let u: [u32; 4] = v.map(|c| c as u32);
                        bytes.extend_from_slice(bytemuck::cast_slice(&u));
                    } else {
                        bytes.extend_from_slice(bytemuck::cast_slice(&v));
                    }
                }
            }
            inputs.push(
                Texture2dArray::new(gl, &format!("input {k}"), format, W, H, n, Some(&bytes))
                    .unwrap(),
            );
        }
        let mut depth_bytes: Vec<u8> = Vec::new();
        for s in 0..n as usize {
            for case in &cases {
                depth_bytes.extend_from_slice(&case.depth[s].to_ne_bytes());
            }
        }
        let depth =
            Texture2dArray::new(gl, "input depth", Format::R32f, W, H, n, Some(&depth_bytes))
                .unwrap();
        let outputs: Vec<Texture2d> = formats
            .iter()
            .enumerate()
            .map(|(k, &f)| Texture2d::new(gl, &format!("output {k}"), f, W, H).unwrap())
            .collect();
        let out_depth = Texture2d::new(gl, "output depth", Format::Depth32f, W, H).unwrap();
        let mut attachments: Vec<(Attachment, TextureRef)> = outputs
            .iter()
            .enumerate()
            .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
            .collect();
        attachments.push((Attachment::Depth, TextureRef::from(&out_depth)));
        let draw: Vec<Option<u32>> = (0..outputs.len() as u32).map(Some).collect();
        let target = Framebuffer::new(gl, "layer harness target", &attachments, &draw).unwrap();
        Harness {
            n,
            inputs,
            depth,
            outputs,
            out_depth,
            target,
            cases,
        }
    }

    /// Resolve on the GPU and compare every pixel, attachment and depth with the CPU.
    fn check(
        &self,
        gl: &glow::Context,
        resolver: &mut Resolver,
        readback: &mut Readback,
        settings: ResolveSettings,
    ) {
        let colors: Vec<TextureRef> = self.inputs.iter().map(TextureRef::from).collect();
        let attachments: Vec<ColorAttachment> =
            (0..colors.len() as u32).map(ColorAttachment).collect();
        let projection = DepthProjection {
            p22: -1.0,
            p23: -0.2,
            zero_to_one: false,
            clear_depth: CLEAR_DEPTH as f64,
        };
        let params = ResolveParams {
            settings,
            projection,
            fov_y: FOV_Y,
            height_px: H,
            view_row: None,
        };
        let inputs = ResolveInputs {
            depth: TextureRef::from(&self.depth),
            colors: &colors,
            attachments: &attachments,
            rules: &RULES,
            key: KeySource::Position(ResolveSlot(1)),
            samples: self.n,
        };
        resolver
            .run(gl, &inputs, &self.target, &params, false)
            .unwrap();
        let gpu: Vec<_> = self
            .outputs
            .iter()
            .map(|t| readback.read(gl, TextureRef::from(t), 1).unwrap())
            .collect();
        let gpu_depth = readback
            .read(gl, TextureRef::from(&self.out_depth), 1)
            .unwrap();

        let cpu = CpuResolve {
            settings,
            rules: RULES.to_vec(),
            key_source: CpuKeySource::Position(1),
            clear_depth: CLEAR_DEPTH as f64,
            footprint: params.footprint(),
        };
        let mut ambiguous = 0;
        let mut failures = Vec::new();
        for (p, case) in self.cases.iter().enumerate() {
            let px = PixelSamples {
                depth: case.depth.iter().map(|&d| d as f64).collect(),
                attachments: case
                    .atts
                    .iter()
                    .map(|a| a.iter().map(|v| v.map(|c| c as f64)).collect())
                    .collect(),
            };
            let want = cpu.resolve_pixel(&px);
            if want.ambiguous {
                ambiguous += 1;
                continue;
            }
            let (x, y_gl) = (p as u32 % W, p as u32 / W);
            let y = H - 1 - y_gl;
            for k in 0..RULES.len() {
                let got = gpu[k].get(0, x, y);
                for c in 0..4 {
                    if !close(got[c], want.attachments[k][c]) {
                        failures.push(format!(
                            "pixel {p} (case {}) attachment {k}[{c}]: gpu {} cpu {} (ref {}, weights {:?})",
                            p % 10, got[c], want.attachments[k][c], want.reference, want.weights
                        ));
                    }
                }
            }
            let d = gpu_depth.get(0, x, y)[0];
            if !close(d, want.depth) {
                failures.push(format!("pixel {p} depth: gpu {d} cpu {}", want.depth));
            }
        }
        assert!(
            failures.is_empty(),
            "{}x {:?}: {} mismatches, first: {:#?}",
            self.n,
            settings,
            failures.len(),
            &failures[..failures.len().min(8)]
        );
        // Near-edge pixels are rare by construction; too many would hide bugs.
        assert!(
            ambiguous * 10 < self.cases.len(),
            "{ambiguous} ambiguous pixels"
        );
    }

    fn destroy(self, gl: &glow::Context) {
        self.target.destroy(gl);
        for t in self.inputs {
            t.destroy(gl);
        }
        for t in self.outputs {
            t.destroy(gl);
        }
        self.depth.destroy(gl);
        self.out_depth.destroy(gl);
    }
}

fn settings_matrix() -> Vec<ResolveSettings> {
    let mut all = Vec::new();
    for &method in ResolveMethod::all() {
        for &window in Window::all() {
            if method == ResolveMethod::Average && window == Window::Hard {
                continue;
            }
            all.push(ResolveSettings {
                method,
                window,
                ..ResolveSettings::default()
            });
        }
    }
    all.push(ResolveSettings {
        fast_path: false,
        ..ResolveSettings::default()
    });
    all.push(ResolveSettings {
        blend_depth: true,
        c: 3.0,
        c_in: 1.0,
        ..ResolveSettings::default()
    });
    all
}

fn run_for(n: u32) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = deferred_msaa_lab::gl::live_objects();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let harness = Harness::new(gl, n, 0xD5A0 + n as u64);
    for settings in settings_matrix() {
        harness.check(gl, &mut resolver, &mut readback, settings);
    }
    harness.destroy(gl);
    resolver.destroy(gl);
    readback.destroy(gl);
    assert_eq!(deferred_msaa_lab::gl::live_objects(), before);
}

#[test]
fn two_samples() {
    run_for(2);
}

#[test]
fn four_samples() {
    run_for(4);
}

#[test]
fn eight_samples() {
    run_for(8);
}

#[test]
fn sixteen_samples() {
    run_for(16);
}

#[test]
fn odd_counts_follow_the_same_rules() {
    // Not a hardware count, but the math must not assume powers of two.
    run_for(3);
}
