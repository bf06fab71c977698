//! One scene measured: its reference, what each run is compared against,
//! and every method entry timed and compared, interleaved frame by frame.

use crate::compare;
use crate::context::HeadlessContext;
use crate::gl::TimerKind;
use crate::renderer::technique::Sparse;
use crate::renderer::{AaMode, Renderer};
use crate::scene::Scene;
use crate::{Error, Result};
use glow::HasContext;
use image::{GrayImage, RgbImage, RgbaImage};
use indicatif::ProgressBar;

use super::bar_width::{self, BarGauge};
use super::config::{BenchConfig, HALO_THRESHOLD, REFERENCE_SCALE, extra_lights};
use super::masks::cluster_masks;
use super::methods::{MethodEntry, adds_geometry, adds_lighting};
use super::pixels::downsample_srgb;
use super::pool::{Job, Pool, median, render_options};
use super::report::{ProfileStep, Run};
use super::{animation, motion};

/// What each run of a scene is measured against: the reference, and what
/// the scene gives beyond it.
pub(super) struct SceneMeasures {
    pub(super) reference: RgbaImage,
    /// The scene's bars as the reference shows them ([`bar_width`]).
    pub(super) bars: Option<BarGauge>,
    /// The pixels [`cluster_masks`] marks as holding two or more clusters.
    pub(super) cluster_mask: Option<GrayImage>,
    /// Those holding three or more.
    pub(super) three_cluster_mask: Option<GrayImage>,
}

/// One scene's results.
pub(super) struct SceneResult {
    pub(super) reference: RgbaImage,
    pub(super) runs: Vec<(Run, RgbaImage)>,
    /// With `--motion`: the animated crop strip's frames.
    pub(super) animation: Option<Vec<RgbImage>>,
}

/// The 4×4 supersampled reference of `scene` at the bench size.
fn render_reference(
    ctx: &HeadlessContext,
    scene: &Scene,
    config: &BenchConfig,
) -> Result<RgbaImage> {
    let gl = ctx.gl();
    let (w, h) = (
        config.width.saturating_mul(REFERENCE_SCALE),
        config.height.saturating_mul(REFERENCE_SCALE),
    );
    let max = unsafe { gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE) }.max(0) as u32;
    if w > max || h > max {
        return Err(Error::invalid(format!(
            "the {REFERENCE_SCALE}x{REFERENCE_SCALE} supersampled reference needs {w}x{h}, \
             over this driver's largest texture ({max}); use a smaller --size"
        )));
    }
    let mut options = render_options(config, AaMode::None, false, 1);
    options.width = w;
    options.height = h;
    let mut renderer = Renderer::new(gl, |name| ctx.get_proc_address(name), scene, &options)?;
    let image = renderer.render(gl).and_then(|_| renderer.read_final(gl));
    renderer.destroy(gl);
    downsample_srgb(&image?, REFERENCE_SCALE)
}

/// The scene's bars as `reference` shows them; `None` for a scene without
/// bars, and, with a warning, when a bar cannot be measured at this size
/// (its runs then have no `bar_width_error_px`).
fn bar_gauge(
    spec: &str,
    scene: &Scene,
    config: &BenchConfig,
    reference: &RgbaImage,
) -> Option<BarGauge> {
    if scene.bars.is_empty() {
        return None;
    }
    let gauge = bar_width::image_bars(&scene.bars, &scene.camera, config.width, config.height)
        .and_then(|bars| BarGauge::new(reference, &bars));
    match gauge {
        Ok(gauge) => Some(gauge),
        Err(e) => {
            log::warn!("{spec}: no bar width error: {e}");
            None
        }
    }
}

pub(super) fn bench_scene(
    ctx: &HeadlessContext,
    config: &BenchConfig,
    spec: &str,
    pb: &ProgressBar,
    rounds: u64,
) -> Result<SceneResult> {
    pb.set_message(format!("{spec}: loading"));
    let mut scene = Scene::load(spec)?;
    for w in &scene.warnings {
        log::warn!("{spec}: {w}");
    }
    let added = extra_lights(&scene.bounds, config.lights);
    scene.lights.extend(added);
    pb.set_message(format!("{spec}: ssaa reference"));
    let reference = render_reference(ctx, &scene, config)?;
    pb.inc(1);
    pb.set_message(format!("{spec}: cluster masks"));
    let (cluster_mask, three_cluster_mask) = cluster_masks(ctx, config, &scene)?.unzip();
    let measures = SceneMeasures {
        bars: bar_gauge(spec, &scene, config, &reference),
        cluster_mask,
        three_cluster_mask,
        reference,
    };

    let mut pool = Pool::default();
    let result = time_scene(ctx, config, spec, &scene, &measures, &mut pool, pb, rounds);
    pool.destroy(ctx.gl());
    let (runs, animation) = result?;
    pb.inc(1);
    Ok(SceneResult {
        reference: measures.reference,
        runs,
        animation,
    })
}

/// A scene's runs with their images, and with `--motion` its crop strip.
type TimedScene = (Vec<(Run, RgbaImage)>, Option<Vec<RgbImage>>);

#[allow(clippy::too_many_arguments)]
fn time_scene(
    ctx: &HeadlessContext,
    config: &BenchConfig,
    spec: &str,
    scene: &Scene,
    measures: &SceneMeasures,
    pool: &mut Pool,
    pb: &ProgressBar,
    rounds: u64,
) -> Result<TimedScene> {
    let gl = ctx.gl();
    // The jobs, with a hidden `none` as the lighting (and G-buffer pass)
    // baseline when a method that adds to them has no `none` entry beside it.
    let hidden_none: Option<MethodEntry> = (config
        .methods
        .iter()
        .any(|e| adds_lighting(&e.method) || adds_geometry(&e.method))
        && !config.methods.iter().any(|e| e.method == AaMode::None))
    .then(|| MethodEntry {
        label: "none".into(),
        method: AaMode::None,
        fxaa: false,
        smaa: None,
    });
    let mut jobs: Vec<Job> = Vec::new();
    let entries = config
        .methods
        .iter()
        .map(|e| (e, true))
        .chain(hidden_none.iter().map(|e| (e, false)));
    for (entry, reported) in entries {
        let counts: Vec<u32> = if entry.method.takes_samples() {
            config.samples.clone()
        } else {
            vec![1]
        };
        for requested in counts {
            let mut options = render_options(config, entry.method, entry.fxaa, requested);
            options.smaa = entry.smaa;
            // `:full`: every attachment of the layout, not the plan's.
            options.adaptive = !entry.full_layout();
            options.forward_msaa = entry.forward();
            options.layer_mix = entry.layer_mix();
            options.validate()?;
            let key = (
                entry.method.technique_name(),
                entry.fxaa,
                entry.smaa.is_some(),
                requested,
                (
                    options.adaptive,
                    options.forward_msaa,
                    options.layer_mix.as_ref().map(|m| format!("{m:?}")),
                ),
                (entry.method.warmup_frames() > 0).then(|| entry.label.clone()),
            );
            let slot = pool.slot(ctx, scene, key, &options)?;
            let renderer = pool.get(slot)?;
            if renderer.options() != &options {
                renderer.set_options(gl, &options)?;
            }
            let samples = renderer.samples();
            if jobs
                .iter()
                .any(|j| j.entry.label == entry.label && j.samples == samples)
            {
                log::warn!(
                    "{spec}: `{}` at {requested}x runs at {samples}x, which is already measured; skipped",
                    entry.label
                );
                pb.set_length(pb.length().unwrap_or(0).saturating_sub(rounds));
                continue;
            }
            // The planned G-buffer: single-sample textures plus the twins
            // (and `gbaa`'s edge buffers); `sparse`: what it really
            // allocates (heads, blocks, pool, MS depth).
            let gbuffer_bytes = match renderer.technique::<Sparse>().and_then(Sparse::allocated) {
                Some(m) => m.total(),
                None => renderer.plan().gbuffer_bytes,
            };
            jobs.push(Job {
                entry,
                reported,
                samples_requested: requested,
                options,
                slot,
                samples,
                frames: Vec::new(),
                image: None,
                gbuffer_bytes,
                complex_fraction: None,
                second_layer_share: None,
                sparse_overflow_pixels: None,
                profile: None,
            });
        }
    }

    // A camera path, or still frames round-robin: every job renders once
    // per round.
    let path = match config.motion {
        Some(motion) => Some(motion::run_path(
            ctx, config, motion, spec, scene, pool, &mut jobs, pb,
        )?),
        None => None,
    };
    for round in (0..rounds).filter(|_| path.is_none()) {
        let timed = round >= config.warmup as u64;
        let last = round + 1 == rounds;
        for job in jobs.iter_mut() {
            pb.set_message(format!(
                "{spec}: {} {}x, {}",
                job.entry.label,
                job.samples,
                if timed { "timing" } else { "warm-up" }
            ));
            let renderer = pool.get(job.slot)?;
            if renderer.options() != &job.options {
                renderer.set_options(gl, &job.options)?;
            }
            if last {
                // A temporal method's still frame is the one it settles on:
                // its warm-up frames from a fresh history, then the frame
                // measured (shared renderers may have reset it between rounds).
                let warmup = job.options.aa.warmup_frames();
                if warmup > 0 {
                    renderer.reset_history();
                    for _ in 0..warmup {
                        renderer.render(gl)?;
                    }
                }
            }
            let t = renderer.render(gl)?;
            if timed {
                job.frames.push(t);
            }
            if last {
                job.image = Some(renderer.read_final(gl)?);
                job.complex_fraction = renderer.complex_pixel_fraction(gl)?;
                job.second_layer_share = renderer.read_second_layer_coverage(gl)?.map(|c| {
                    let covered = c.pixels().filter(|p| p[0] > 0).count();
                    covered as f64 / (c.width() as f64 * c.height() as f64).max(1.0)
                });
                job.sparse_overflow_pixels = renderer
                    .technique::<Sparse>()
                    .map_or(Ok(None), |s| s.stats(gl))?
                    .map(|s| u64::from(s.overflow_pixels));
            }
            pb.inc(1);
        }
    }

    // The profile: more frames of each job with a retrofit, every step of
    // the retrofit's (and the renderer's second-layer passes) timed between
    // two glFinish calls; each step's median over the frames.
    if config.profile {
        for job in jobs.iter_mut().filter(|j| j.reported) {
            let renderer = pool.get(job.slot)?;
            if renderer.retrofit().is_none() {
                continue;
            }
            if renderer.options() != &job.options {
                renderer.set_options(gl, &job.options)?;
            }
            pb.set_message(format!(
                "{spec}: {} {}x, profiling",
                job.entry.label, job.samples
            ));
            renderer.set_profiling(true);
            let mut samples: Vec<(&'static str, Vec<f64>)> = Vec::new();
            let frames = (|| {
                for _ in 0..config.frames {
                    renderer.render(gl)?;
                    let steps = renderer.retrofit().map(|r| r.profile().steps().to_vec());
                    for (k, (name, ms)) in steps.unwrap_or_default().into_iter().enumerate() {
                        match samples.get_mut(k) {
                            Some((n, v)) if *n == name => v.push(ms),
                            _ => samples.insert(k, (name, vec![ms])),
                        }
                    }
                }
                Ok::<_, Error>(())
            })();
            renderer.set_profiling(false);
            frames?;
            job.profile = Some(
                samples
                    .into_iter()
                    .map(|(step, ms)| ProfileStep {
                        step: step.to_string(),
                        ms: median(ms),
                    })
                    .collect(),
            );
        }
    }

    // The lighting baseline: `none`'s median lighting time.
    let base_lighting = median(
        jobs.iter()
            .filter(|j| j.entry.method == AaMode::None)
            .flat_map(|j| j.frames.iter().map(|t| t.lighting_ms))
            .collect(),
    );
    // The G-buffer pass baseline: `none`'s median G-buffer time.
    let base_geometry = median(
        jobs.iter()
            .filter(|j| j.entry.method == AaMode::None)
            .flat_map(|j| j.frames.iter().map(|t| t.geometry_ms))
            .collect(),
    );
    pb.set_message(format!("{spec}: measuring error"));
    let reference = &measures.reference;
    let mut runs = Vec::new();
    let tracks: Vec<Option<&motion::Track>> = match &path {
        Some(p) => p.tracks.iter().map(Some).collect(),
        None => jobs.iter().map(|_| None).collect(),
    };
    let mut columns = Vec::new();
    for (job, track) in jobs.into_iter().zip(tracks).filter(|(j, _)| j.reported) {
        let image = job
            .image
            .ok_or_else(|| Error::invalid("bench: a run has no final image"))?;
        let flip = compare::flip(reference, &image)
            .ok_or_else(|| Error::invalid("bench: the reference and the run differ in size"))?;
        let psnr = compare::psnr(reference, &image);
        let by_mask = match &measures.cluster_mask {
            Some(mask) => Some(compare::flip_by_mask(reference, &image, mask).ok_or_else(
                || Error::invalid("bench: the cluster mask and the run differ in size"),
            )?),
            None => None,
        };
        let by_three = match &measures.three_cluster_mask {
            Some(mask) => Some(compare::flip_by_mask(reference, &image, mask).ok_or_else(
                || Error::invalid("bench: the cluster mask and the run differ in size"),
            )?),
            None => None,
        };
        let bar_width_error_px = match &measures.bars {
            Some(gauge) => Some(gauge.width_error(&image)?),
            None => None,
        };
        let adds = adds_lighting(&job.entry.method);
        let ms_aa = median(
            job.frames
                .iter()
                .map(|t| {
                    let extra = if adds {
                        (t.lighting_ms - base_lighting).max(0.0)
                    } else {
                        0.0
                    };
                    let extra_geometry = if adds_geometry(&job.entry.method) {
                        (t.geometry_ms - base_geometry).max(0.0)
                    } else {
                        0.0
                    };
                    t.resolve_ms
                        + t.second_layer_ms
                        + t.fxaa_ms
                        + t.post_ms
                        + t.smaa_ms
                        + extra
                        + extra_geometry
                })
                .collect(),
        );
        let timer = job
            .frames
            .first()
            .map_or(TimerKind::FinishWallClock, |t| t.timer);
        let run = Run {
            scene: spec.to_string(),
            method: job.entry.label.clone(),
            fxaa: job.entry.fxaa,
            smaa: job.entry.smaa.is_some(),
            samples: job.samples,
            width: config.width,
            height: config.height,
            ms_total: median(job.frames.iter().map(|t| t.total_ms).collect()),
            ms_aa,
            timer: timer.name().to_string(),
            flip_mean: flip.mean as f64,
            psnr_db: psnr.is_finite().then_some(psnr),
            halo_pixels: compare::halo_pixels(reference, &image, HALO_THRESHOLD) as u64,
            gbuffer_bytes: job.gbuffer_bytes,
            ms_resolve: median(job.frames.iter().map(|t| t.resolve_ms).collect()),
            ms_fxaa: median(job.frames.iter().map(|t| t.fxaa_ms).collect()),
            ms_smaa: median(job.frames.iter().map(|t| t.smaa_ms).collect()),
            ms_smaa_edges: median(job.frames.iter().map(|t| t.smaa_edges_ms).collect()),
            ms_smaa_weights: median(job.frames.iter().map(|t| t.smaa_weights_ms).collect()),
            ms_smaa_blend: median(job.frames.iter().map(|t| t.smaa_blend_ms).collect()),
            ms_lighting: median(job.frames.iter().map(|t| t.lighting_ms).collect()),
            ms_second_layer: median(job.frames.iter().map(|t| t.second_layer_ms).collect()),
            flip_p95: flip.p95 as f64,
            complex_fraction: job.complex_fraction,
            second_layer_share: job.second_layer_share,
            sparse_overflow_pixels: job.sparse_overflow_pixels,
            profile: job.profile,
            full_ms_gbuffer_bytes: matches!(job.entry.method, AaMode::Sparse(_)).then(|| {
                config
                    .layout
                    .bytes(config.width, config.height, job.samples)
            }),
            samples_requested: job.samples_requested,
            lights: scene.lights.len() as u32,
            bar_width_error_px,
            flip_edges: by_mask.and_then(|m| m.marked),
            flip_interior: by_mask.and_then(|m| m.unmarked),
            edge_pixel_share: by_mask.map(|m| m.marked_share),
            flip_three_clusters: by_three.and_then(|m| m.marked),
            three_cluster_share: by_three.map(|m| m.marked_share),
            motion: match (track, &path, config.motion) {
                (Some(track), Some(p), Some(m)) => Some(motion::measures(track, m.frames, p.px)),
                _ => None,
            },
        };
        if let Some(track) = track {
            columns.push(animation::Column {
                label: format!("{} {}x", run.method, run.samples),
                crops: &track.crops,
            });
        }
        runs.push((run, image));
    }
    let animation = match &path {
        Some(p) => {
            let (x, y, side) = p.crop;
            let mut all = vec![animation::Column {
                label: format!("ssaa, {side}px at ({x}, {y})"),
                crops: &p.reference_crops,
            }];
            all.extend(columns);
            animation::strip_frames(&all)?
        }
        None => None,
    };
    Ok((runs, animation))
}
