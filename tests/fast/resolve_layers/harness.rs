//! The inputs uploaded as one texture array per attachment, resolved on
//! the GPU and compared with the CPU reference pixel by pixel.

use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::gl::{
    Attachment, Format, Framebuffer, Texture2d, Texture2dArray, TextureRef,
};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::cpu::{
    CpuCamera, CpuKeySource, CpuResolve, PixelPlace, PixelSamples, ResolvedPixel, SecondLayerPixel,
};
use deferred_msaa_lab::resolve::{
    DepthProjection, KeySource, LayerPass, NormalEncoding, ResolveInputs, ResolveParams,
    ResolveRule, ResolveSettings, ResolveSlot, Resolver,
};
use deferred_msaa_testkit::Rng;

use super::cases::*;

pub(super) struct Harness {
    n: u32,
    inputs: Vec<Texture2dArray>,
    depth: Texture2dArray,
    outputs: Vec<Texture2d>,
    out_depth: Texture2d,
    target: Framebuffer,
    pub(super) cases: Vec<Case>,
    /// The normal input (attachment 2) and its encoding, for two layers.
    pub(super) normal: Option<(usize, NormalEncoding)>,
}

impl Harness {
    pub(super) fn new(gl: &glow::Context, n: u32, seed: u64) -> Harness {
        let mut rng = Rng::new(seed);
        let cases: Vec<Case> = (0..W * H)
            .map(|p| gen_case(&mut rng, n as usize, p % 11))
            .collect();
        Harness::upload(gl, n, cases)
    }

    /// A harness over given cases (`W * H` of them, row by row from the bottom).
    pub(super) fn upload(gl: &glow::Context, n: u32, cases: Vec<Case>) -> Harness {
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
    pub(super) fn check(
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
    pub(super) fn check_keyed(
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
            camera: CpuCamera::of(&params),
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
            // Case p is drawn at GL's (p % W, p / W); the place counts rows
            // from the top.
            let at = PixelPlace {
                x: p as u32 % W,
                y: H - 1 - p as u32 / W,
                width: W,
                height: H,
            };
            let want = cpu.resolve_pixel_at(&px, Some(at));
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
                    let within = if RULES[k] == ResolveRule::Blend {
                        let scale = blend_conditioning(&px.attachments[k], &want.weights, c);
                        close_scaled(got[c], want.attachments[k][c], scale)
                    } else if c < 3 {
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
    pub(super) fn check_second_layer(
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
            camera: CpuCamera::of(&params),
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
            let at = PixelPlace {
                x: p as u32 % W,
                y: H - 1 - p as u32 / W,
                width: W,
                height: H,
            };
            let want = cpu.resolve_second_layer_at(&px, Some(at));
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
                    let within = if RULES[k] == ResolveRule::Blend {
                        let scale = blend_conditioning(&px.attachments[k], &want.weights, c);
                        close_scaled(got[c], want.attachments[k][c], scale)
                    } else if c < 3 {
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

    pub(super) fn destroy(self, gl: &glow::Context) {
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
