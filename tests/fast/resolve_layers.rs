//! The resolve's GLSL against its CPU reference for N = 2, 4, 8 and 16.
//!
//! llvmpipe offers only 4x MSAA, so the same resolve body is compiled over
//! `sampler2DArray` inputs (one layer per sample, docs/testing.md) and fed
//! random and adversarial per-sample data: ties, all background, a single
//! geometry sample, NaN and Inf values, denormals, equal depths with different
//! colours, opposite normals, HDR values up to 65504.

// Per-sample arrays run in parallel; indices read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

use crate::common;

use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::gl::{
    Attachment, Format, Framebuffer, Texture2d, Texture2dArray, TextureRef,
};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::cpu::{
    CpuKeySource, CpuResolve, PixelSamples, ResolvedPixel, SecondLayerPixel,
    standard_sample_positions,
};
use deferred_msaa_lab::resolve::{
    DepthProjection, KeySource, LayerPass, NormalEncoding, ResolveInputs, ResolveMethod,
    ResolveParams, ResolveRule, ResolveSettings, ResolveSlot, Resolver, Window,
};
use deferred_msaa_testkit::Rng;

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
/// The view matrix's third row for the world-space key: a view turned a
/// little about x and y, so the key mixes every position component.
const WORLD_VIEW_ROW: [f64; 4] = [0.03, -0.04, 0.998_749_217_771_908_6, 0.0];

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
    // A thin box's silhouette (kind 10): per sample its front face, a side
    // face just behind it, or a far wall.
    // (Drawn for that kind alone: the other kinds' cases stay as they were.)
    let (surfaces, side_behind) = if kind == 10 {
        let surfaces: Vec<u32> = (0..n).map(|_| rng.below(3)).collect();
        (surfaces, foot * rng.range(0.02, 0.6))
    } else {
        (vec![0; n], 0.0)
    };
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
            10 => [base, base + side_behind, base * 20.0][surfaces[i] as usize], // front, side, wall
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
            (_, 0) if (8..10).contains(&kind) => {
                let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40];
                let v = bad[rng.below(4) as usize];
                emissive[rng.below(3) as usize] = v;
            }
            (_, 1) => emissive = [65504.0, rng.range(0.0, 65504.0), 1.0, 1.0],
            (_, 2) if (8..10).contains(&kind) => position[2] = f32::NAN, // a non-finite key is background
            (_, 3) => {
                normal = if i % 2 == 0 {
                    [0.0, 0.0, 1.0, 0.5]
                } else {
                    [0.0, 0.0, -1.0, 0.25]
                }
            }
            _ => {}
        }
        if kind == 10 {
            // The front face and the wall face the eye; the side is turned
            // 50 to 90 degrees from them.
            let turn = [0.0, 1.0, 0.0][surfaces[i] as usize] * rng.range(0.87, 1.57);
            normal = [turn.sin(), 0.0, turn.cos(), normal[3]];
        }
        atts[0].push(colour);
        atts[1].push(position);
        atts[2].push(normal);
        atts[3].push(emissive);
        atts[4].push(material);
    }
    Case { depth, atts }
}

/// `close` with its tolerance multiplied by `scale` (at least 1).
fn close_scaled(gpu: f32, cpu: f64, scale: f64) -> bool {
    if !cpu.is_finite() {
        return close(gpu, cpu);
    }
    ((gpu as f64) - cpu).abs() <= (2e-6 + 2e-5 * cpu.abs()) * scale.max(1.0)
}

/// Σ w_i |n_i| / |Σ w_i n_i| over xyz: how much normalising the weighted
/// sum amplifies the rounding of its terms (infinite for a zero sum, where
/// the blend falls back to the reference's normal and needs no scale).
fn normal_conditioning(values: &[[f64; 4]], weights: &[f64]) -> f64 {
    let mut sum = [0.0f64; 3];
    let mut magnitude = 0.0;
    for (v, &w) in values.iter().zip(weights) {
        if w <= 0.0 || !v.iter().all(|c| c.is_finite()) {
            continue;
        }
        for c in 0..3 {
            sum[c] += w * v[c];
        }
        magnitude += w * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    }
    let len = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    if len >= 1e-6 { magnitude / len } else { 1.0 }
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
    /// The normal input (attachment 2) and its encoding, for two layers.
    normal: Option<(usize, NormalEncoding)>,
}

impl Harness {
    fn new(gl: &glow::Context, n: u32, seed: u64) -> Harness {
        let mut rng = Rng::new(seed);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| gen_case(&mut rng, n as usize, p % 11))
            .collect();
        Harness::upload(gl, n, cases)
    }

    /// A harness over given cases (`W * H` of them, row by row from the bottom).
    fn upload(gl: &glow::Context, n: u32, cases: Vec<Case>) -> Harness {
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
            normal: None,
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
        self.check_keyed(
            gl,
            resolver,
            readback,
            settings,
            KeySource::Position(ResolveSlot(1)),
        );
    }

    /// [`Harness::check`] with the key from `key`; returns the CPU's pixels.
    fn check_keyed(
        &self,
        gl: &glow::Context,
        resolver: &mut Resolver,
        readback: &mut Readback,
        settings: ResolveSettings,
        key: KeySource,
    ) -> Vec<ResolvedPixel> {
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
            view_row: matches!(key, KeySource::WorldPosition(_)).then_some(WORLD_VIEW_ROW),
        };
        let inputs = ResolveInputs {
            depth: TextureRef::from(&self.depth),
            colors: &colors,
            attachments: &attachments,
            rules: &RULES,
            key,
            samples: self.n,
            normal: self.normal.map(|(k, e)| (ResolveSlot(k), e)),
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
            key_source: match key {
                KeySource::Position(ResolveSlot(k)) => CpuKeySource::Position(k),
                KeySource::WorldPosition(ResolveSlot(k)) => CpuKeySource::WorldPosition {
                    attachment: k,
                    view_row: WORLD_VIEW_ROW,
                },
                KeySource::Depth => CpuKeySource::Depth(projection),
            },
            clear_depth: CLEAR_DEPTH as f64,
            footprint: params.footprint(),
            normal: self.normal,
        };
        let mut ambiguous = 0;
        let mut pixels = Vec::with_capacity(self.cases.len());
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
            pixels.push(want.clone());
            if want.ambiguous {
                ambiguous += 1;
                continue;
            }
            let (x, y_gl) = (p as u32 % W, p as u32 / W);
            let y = H - 1 - y_gl;
            for k in 0..RULES.len() {
                let got = gpu[k].get(0, x, y);
                // A normalised blend divides f32 rounding, which grows with
                // the sum of the terms, by the length of their sum: nearly
                // opposite normals amplify it by that ratio.
                let scale = if RULES[k] == ResolveRule::BlendNormal {
                    normal_conditioning(&px.attachments[k], &want.weights)
                } else {
                    1.0
                };
                for c in 0..4 {
                    let within = if c < 3 {
                        close_scaled(got[c], want.attachments[k][c], scale)
                    } else {
                        close(got[c], want.attachments[k][c])
                    };
                    if !within {
                        failures.push(format!(
                            "pixel {p} (case {}) attachment {k}[{c}]: gpu {} cpu {} (ref {}, weights {:?})",
                            p % 11, got[c], want.attachments[k][c], want.reference, want.weights
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
        pixels
    }

    /// The second layer on the GPU against the CPU reference's
    /// `resolve_second_layer_at`: every attachment, the depth and the
    /// coverage of every pixel. Returns the CPU's second layers.
    fn check_second_layer(
        &self,
        gl: &glow::Context,
        resolver: &mut Resolver,
        readback: &mut Readback,
        settings: ResolveSettings,
    ) -> Vec<SecondLayerPixel> {
        let formats = [
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32f,
            Format::Rgba32ui,
            Format::R32f,
            Format::R32f,
        ];
        let outputs: Vec<Texture2d> = formats
            .iter()
            .enumerate()
            .map(|(k, &f)| Texture2d::new(gl, &format!("second layer {k}"), f, W, H).unwrap())
            .collect();
        let attachments: Vec<(Attachment, TextureRef)> = outputs
            .iter()
            .enumerate()
            .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
            .collect();
        let draw: Vec<Option<u32>> = (0..outputs.len() as u32).map(Some).collect();
        let target = Framebuffer::new(gl, "second layer target", &attachments, &draw).unwrap();
        let colors: Vec<TextureRef> = self.inputs.iter().map(TextureRef::from).collect();
        let points: Vec<ColorAttachment> = (0..colors.len() as u32).map(ColorAttachment).collect();
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
            attachments: &points,
            rules: &RULES,
            key: KeySource::Position(ResolveSlot(1)),
            samples: self.n,
            normal: self.normal.map(|(k, e)| (ResolveSlot(k), e)),
        };
        resolver
            .run_second_layer(
                gl,
                &inputs,
                &target,
                &params,
                false,
                None,
                LayerPass::all(inputs.colors.len()),
            )
            .unwrap();
        let gpu: Vec<_> = outputs
            .iter()
            .map(|t| readback.read(gl, TextureRef::from(t), 1).unwrap())
            .collect();
        let cpu = CpuResolve {
            settings,
            rules: RULES.to_vec(),
            key_source: CpuKeySource::Position(1),
            clear_depth: CLEAR_DEPTH as f64,
            footprint: params.footprint(),
            normal: self.normal,
        };
        let mut failures = Vec::new();
        let mut ambiguous = 0;
        let mut layers = Vec::with_capacity(self.cases.len());
        for (p, case) in self.cases.iter().enumerate() {
            let px = PixelSamples {
                depth: case.depth.iter().map(|&d| d as f64).collect(),
                attachments: case
                    .atts
                    .iter()
                    .map(|a| a.iter().map(|v| v.map(|c| c as f64)).collect())
                    .collect(),
            };
            let want = cpu.resolve_second_layer_at(&px, None);
            layers.push(want.clone());
            if want.ambiguous {
                ambiguous += 1;
                continue;
            }
            let (x, y) = (p as u32 % W, H - 1 - p as u32 / W);
            for k in 0..RULES.len() {
                let got = gpu[k].get(0, x, y);
                let scale = if RULES[k] == ResolveRule::BlendNormal {
                    normal_conditioning(&px.attachments[k], &want.weights)
                } else {
                    1.0
                };
                for c in 0..4 {
                    let within = if c < 3 {
                        close_scaled(got[c], want.attachments[k][c], scale)
                    } else {
                        close(got[c], want.attachments[k][c])
                    };
                    if !within {
                        failures.push(format!(
                            "pixel {p} (case {}) attachment {k}[{c}]: gpu {} cpu {} (seed {:?}, weights {:?})",
                            p % 11, got[c], want.attachments[k][c], want.reference, want.weights
                        ));
                    }
                }
            }
            let coverage = gpu[5].get(0, x, y)[0];
            if !close(coverage, want.coverage) {
                failures.push(format!(
                    "pixel {p} (case {}) coverage: gpu {coverage} cpu {} (seed {:?})",
                    p % 11,
                    want.coverage,
                    want.reference
                ));
            }
            let d = gpu[6].get(0, x, y)[0];
            if !close(d, want.depth) {
                failures.push(format!("pixel {p} depth: gpu {d} cpu {}", want.depth));
            }
        }
        target.destroy(gl);
        for t in outputs {
            t.destroy(gl);
        }
        assert!(
            failures.is_empty(),
            "{}x {:?} normals {:?}: {} mismatches, first: {:#?}",
            self.n,
            settings,
            self.normal,
            failures.len(),
            &failures[..failures.len().min(8)]
        );
        assert!(
            ambiguous * 10 < self.cases.len(),
            "{ambiguous} ambiguous pixels"
        );
        layers
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

/// A world-space position key: the GPU and the CPU reference agree, with
/// uniformity decided on the whole position.
#[test]
fn a_world_space_key_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    let harness = Harness::new(gl, 4, 0x5EED);
    for fast_path in [true, false] {
        let settings = ResolveSettings {
            fast_path,
            ..ResolveSettings::default()
        };
        let key = KeySource::WorldPosition(ResolveSlot(1));
        harness.check_keyed(gl, &mut resolver, &mut readback, settings, key);
    }
    harness.destroy(gl);
    resolver.destroy(gl);
    readback.destroy(gl);
}

/// The opt-in position test: the GPU agrees with its CPU mirror for every
/// count and both position keys, and a pixel takes one sample exactly where
/// its position samples are all equal, background samples included.
#[test]
fn position_uniformity_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 4, 8, 16] {
        // A third of the pixels get one position in every sample (one
        // fragment, or the adversarial case of background samples that hold
        // the geometry's position); the rest keep their random ones.
        let mut rng = Rng::new(0x9051 + n as u64);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| {
                let mut case = gen_case(&mut rng, n as usize, p % 10);
                if p % 3 == 0 {
                    let first = case.atts[1][0];
                    case.atts[1].iter_mut().for_each(|v| *v = first);
                }
                case
            })
            .collect();
        let harness = Harness::upload(gl, n, cases);
        let equal: Vec<bool> = harness
            .cases
            .iter()
            .map(|c| c.atts[1].iter().all(|v| *v == c.atts[1][0]))
            .collect();
        assert!(equal.iter().any(|&e| e) && equal.iter().any(|&e| !e));
        for key in [
            KeySource::Position(ResolveSlot(1)),
            KeySource::WorldPosition(ResolveSlot(1)),
        ] {
            for method in [ResolveMethod::Median, ResolveMethod::Front] {
                let settings = ResolveSettings {
                    method,
                    position_uniformity: true,
                    ..ResolveSettings::default()
                };
                let off = ResolveSettings {
                    position_uniformity: false,
                    ..settings
                };
                harness.check_keyed(gl, &mut resolver, &mut readback, off, key);
                let with = harness.check_keyed(gl, &mut resolver, &mut readback, settings, key);
                for (p, px) in with.iter().enumerate() {
                    assert_eq!(px.complex, !equal[p], "{n}x {key:?} {method}: pixel {p}");
                }
            }
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
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

/// A depth-key host's pixels for the opt-in plane test: `kind` 0 is one
/// tilted triangle (depths on a plane over the standard pattern, every
/// attachment equal: one fragment), 1 two surfaces with the same attachment
/// values, 2 one plane whose first blended attachment (colour) differs by
/// sample, 3 one plane with equal colour but normals that differ (two
/// coplanar triangles with different shading), 4 and above the general cases.
fn gen_plane_case(rng: &mut Rng, n: usize, kind: u32) -> Case {
    if kind >= 4 {
        return gen_case(rng, n, kind % 10);
    }
    let pattern: Vec<[f64; 2]> = match standard_sample_positions(n) {
        Some(p) => p.to_vec(),
        None => (0..n).map(|i| [i as f64, (i * i) as f64]).collect(),
    };
    let d0 = rng.range(0.3, 0.9) as f64;
    // Per sixteenth of a pixel: up to ~1e-3 across the pixel.
    let (a, b) = (rng.range(-1e-4, 1e-4) as f64, rng.range(-1e-4, 1e-4) as f64);
    let depth: Vec<f32> = pattern
        .iter()
        .enumerate()
        .map(|(i, q)| {
            // A second surface under the last sample (two surfaces split
            // two against two can lie on one plane over the 4x pattern).
            let other = if kind == 1 && i == n - 1 { 0.05 } else { 0.0 };
            (d0 + a * q[0] + b * q[1] + other) as f32
        })
        .collect();
    let one = [rng.unit(), rng.unit(), rng.unit(), 1.0];
    let z = (0.1 / (1.0 - d0)) as f32;
    let position = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), -z, 1.0];
    let normal = [0.0, 0.6, 0.8, 0.5];
    let emissive = [rng.range(0.0, 4.0), 1.0, 2.0, 1.0];
    let material = [7.0, 0.0, 0.0, 1.0];
    let mut atts: [Vec<[f32; 4]>; 5] = Default::default();
    for i in 0..n {
        let mut colour = one;
        let mut nrm = normal;
        if kind == 2 && i == n - 1 {
            colour[0] = 1.0 - colour[0] + 0.25;
        }
        if kind == 3 && i % 2 == 1 {
            nrm = [0.6, 0.0, 0.8, 0.5];
        }
        atts[0].push(colour);
        atts[1].push(position);
        atts[2].push(nrm);
        atts[3].push(emissive);
        atts[4].push(material);
    }
    Case { depth, atts }
}

#[test]
fn plane_uniformity_takes_one_sample_on_a_tilted_triangle() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 3, 4, 8, 16] {
        let mut rng = Rng::new(0x91A7E + n as u64);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| gen_plane_case(&mut rng, n as usize, p % 8))
            .collect();
        let kinds: Vec<u32> = (0..W * H).map(|p| p % 8).collect();
        let harness = Harness::upload(gl, n, cases);
        for method in [ResolveMethod::Median, ResolveMethod::Front] {
            let on = ResolveSettings {
                method,
                plane_uniformity: true,
                ..ResolveSettings::default()
            };
            let off = ResolveSettings {
                plane_uniformity: false,
                ..on
            };
            // The GPU agrees with the CPU reference with the option on and off.
            let with = harness.check_keyed(gl, &mut resolver, &mut readback, on, KeySource::Depth);
            let without =
                harness.check_keyed(gl, &mut resolver, &mut readback, off, KeySource::Depth);
            let mut fired = [0usize; 8];
            let mut depth_moved = 0;
            let mut worst = [0.0f64; 6];
            for (p, (w, o)) in with.iter().zip(&without).enumerate() {
                if w.ambiguous || o.ambiguous || w.complex || !o.complex {
                    continue;
                }
                fired[kinds[p] as usize] += 1;
                let d = (w.depth - o.depth).abs();
                worst[5] = worst[5].max(d);
                if d > 1e-4 {
                    depth_moved += 1;
                }
                for k in 0..RULES.len() {
                    for c in 0..4 {
                        let e = (w.attachments[k][c] - o.attachments[k][c]).abs();
                        worst[k] = worst[k].max(e);
                    }
                }
            }
            let per_kind = (W * H / 8) as usize;
            eprintln!(
                "{n}x {method}: the plane test fired on {fired:?} pixels by kind \
                 ({per_kind} each); largest change against the slow path per \
                 attachment and depth {worst:?}"
            );
            // Every one-triangle pixel takes one sample; for 4 samples and
            // more, two surfaces and differing colours never do.
            assert!(fired[0] * 10 >= per_kind * 9, "{fired:?}");
            if n >= 4 {
                assert_eq!(fired[1] + fired[2], 0, "{fired:?}");
            } else {
                assert!(fired[1] * 10 >= per_kind * 9, "{fired:?}");
                assert_eq!(fired[2], 0, "{fired:?}");
            }
            // The slow path would have given another depth there, so the
            // GPU's agreement with the CPU shows that it took the plane test.
            assert!(depth_moved * 2 >= fired[0], "{depth_moved} of {fired:?}");
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
}

/// The second layer, and the first layer with clusters split by normal
/// (one layer or two), against the CPU reference for N = 2, 4, 8 and 16 over the adversarial
/// cases, by depth alone and with each normal encoding; pixels of one
/// cluster, two, and three or more all occur.
#[test]
fn second_layer_matches_the_cpu_reference() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = deferred_msaa_lab::gl::live_objects();
    let mut resolver = Resolver::new(gl).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    for n in [2u32, 4, 8, 16] {
        let mut harness = Harness::new(gl, n, 0x2A7E + n as u64);
        let normals = [
            None,
            Some((2, NormalEncoding::Xyz)),
            Some((2, NormalEncoding::Unorm)),
            Some((2, NormalEncoding::Octahedral)),
            Some((2, NormalEncoding::OctahedralUnorm)),
        ];
        for normal in normals {
            harness.normal = normal;
            for (method, window) in [
                (ResolveMethod::Median, Window::Smooth),
                (ResolveMethod::Front, Window::Hard),
                (ResolveMethod::Back, Window::Smooth),
            ] {
                let settings = ResolveSettings {
                    method,
                    window,
                    layers: 2,
                    ..ResolveSettings::default()
                };
                // The first layer, its clusters split by normal, with two
                // layers and with one (the normal test is the same).
                harness.check(gl, &mut resolver, &mut readback, settings);
                let one_layer = ResolveSettings {
                    layers: 1,
                    ..settings
                };
                harness.check(gl, &mut resolver, &mut readback, one_layer);
                let layers = harness.check_second_layer(gl, &mut resolver, &mut readback, settings);
                let two = layers.iter().filter(|l| l.reference.is_some()).count();
                // Three or more clusters: samples of neither kept cluster
                // join one of them.
                let three = layers
                    .iter()
                    .filter(|l| l.reference.is_some() && l.joined.iter().sum::<usize>() > 0)
                    .count();
                assert!(
                    two > 0,
                    "{n}x {normal:?} {method}: no pixel has a second layer"
                );
                if n >= 4 && method == ResolveMethod::Median {
                    assert!(three > 0, "{n}x {normal:?}: no pixel has three clusters");
                }
                assert!(two < layers.len(), "{n}x: every pixel has a second layer");
            }
        }
        harness.destroy(gl);
    }
    resolver.destroy(gl);
    readback.destroy(gl);
    assert_eq!(deferred_msaa_lab::gl::live_objects(), before);
}
