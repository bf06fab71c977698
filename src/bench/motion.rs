//! The motion bench (`bench --motion SPEC`): every method renders the
//! whole camera path ([`CameraPath`]), frame after frame, interleaved, and
//! the reference is the 16x supersampled render of every frame. What a
//! moving camera shows is measured per run ([`MotionMeasures`]; each
//! formula is in docs/motion.md), and the crops of every frame make an
//! animated strip (`bench::animation`).
//!
//! Only the camera moves: geometry and lights stay. The timed frames are
//! the path's (`--frames` does not apply); the warm-up rounds render the
//! path's first camera, and then a method with history (`taa`) starts the
//! path from a fresh one, so that its settling is measured. A run's still-frame fields are those of the path's
//! middle frame, which is the scene's own camera, so that the cluster
//! masks and the bar gauge made for the still bench apply to it.

use super::bar_width::{self, BarGauge};
use super::config::{BenchConfig, REFERENCE_SCALE};
use super::pixels::downsample_srgb;
use super::pool::{Job, Pool, median, render_options};
use super::report::MotionMeasures;
use crate::compare;
use crate::context::HeadlessContext;
use crate::renderer::{AaMode, Renderer};
use crate::scene::{CameraPath, MotionSpec, Scene};
use crate::{Error, Result};
use image::RgbaImage;
use indicatif::ProgressBar;

/// What one job gathers along the path.
#[derive(Debug, Default)]
pub(super) struct Track {
    flips: Vec<f64>,
    temporal: Vec<f64>,
    sharpness: Vec<f64>,
    /// Per frame, each bar's width less the reference's (`None` once a
    /// frame's bars could not be measured).
    bar_errors: Option<Vec<Vec<f64>>>,
    previous: Option<RgbaImage>,
    /// The first frame, kept until the crop is chosen.
    first: Option<RgbaImage>,
    /// The crop of every frame.
    pub(super) crops: Vec<RgbaImage>,
}

/// One scene's path as the bench ran it: its spec, measured speed, and the
/// reference's crops beside each job's.
#[derive(Debug)]
pub(super) struct PathRun {
    /// The measured mean image motion per frame, pixels.
    pub(super) px: f64,
    /// The reference's crop of every frame.
    pub(super) reference_crops: Vec<RgbaImage>,
    /// One track per job, in job order.
    pub(super) tracks: Vec<Track>,
    /// Where the crop sits, and its side.
    pub(super) crop: (u32, u32, u32),
}

fn crop_of(img: &RgbaImage, (x, y, side): (u32, u32, u32)) -> RgbaImage {
    let (w, h) = (side.min(img.width()), side.min(img.height()));
    image::imageops::crop_imm(img, x, y, w, h).to_image()
}

/// Render the path for every job and measure each frame. Fills each job's
/// timings (one per path frame), its image and last-frame statistics (at
/// the scene's own camera), and returns what the runs' motion measures and
/// the animation are made from.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_path(
    ctx: &HeadlessContext,
    config: &BenchConfig,
    motion: MotionSpec,
    spec: &str,
    scene: &Scene,
    pool: &mut Pool,
    jobs: &mut [Job],
    pb: &ProgressBar,
) -> Result<PathRun> {
    let gl = ctx.gl();
    let (w, h) = (config.width, config.height);
    let path = CameraPath::new(motion, &scene.camera, &scene.bounds, w, h)?;
    let px = f64::from(path.measured_px(&scene.bounds, w, h).unwrap_or(motion.px));
    let mut reference_options = render_options(config, AaMode::None, false, 1);
    reference_options.width = w.saturating_mul(REFERENCE_SCALE);
    reference_options.height = h.saturating_mul(REFERENCE_SCALE);
    let mut reference = Renderer::new(
        gl,
        |name| ctx.get_proc_address(name),
        scene,
        &reference_options,
    )?;
    let result = (|| {
        // Warm-up at the path's first camera.
        for _ in 0..config.warmup {
            for job in jobs.iter() {
                pb.set_message(format!(
                    "{spec}: {} {}x, warm-up",
                    job.entry.label, job.samples
                ));
                let renderer = pool.get(job.slot)?;
                if renderer.options() != &job.options {
                    renderer.set_options(gl, &job.options)?;
                }
                renderer.set_camera(path.cameras[0]);
                renderer.render(gl)?;
                pb.inc(1);
            }
        }
        // A temporal method starts the path afresh: how long it takes to
        // settle is one of the measures.
        for job in jobs.iter() {
            pool.get(job.slot)?.reset_history();
        }
        let mut tracks: Vec<Track> = jobs
            .iter()
            .map(|_| Track {
                bar_errors: (!scene.bars.is_empty()).then(Vec::new),
                ..Track::default()
            })
            .collect();
        let mut reference_crops = Vec::new();
        let mut reference_before: Option<RgbaImage> = None;
        let mut crop = None;
        for (t, camera) in path.cameras.iter().enumerate() {
            pb.set_message(format!(
                "{spec}: frame {}/{}, reference",
                t + 1,
                path.cameras.len()
            ));
            reference.set_camera(*camera);
            reference.render(gl)?;
            let r = downsample_srgb(&reference.read_final(gl)?, REFERENCE_SCALE)?;
            let gauge = if scene.bars.is_empty() {
                None
            } else {
                match bar_width::image_bars(&scene.bars, camera, w, h)
                    .and_then(|bars| BarGauge::new(&r, &bars))
                {
                    Ok(g) => Some(g),
                    Err(e) => {
                        log::warn!("{spec}: frame {t}: no bar width jitter: {e}");
                        tracks.iter_mut().for_each(|k| k.bar_errors = None);
                        None
                    }
                }
            };
            for (job, track) in jobs.iter_mut().zip(tracks.iter_mut()) {
                pb.set_message(format!(
                    "{spec}: frame {}/{}, {} {}x",
                    t + 1,
                    path.cameras.len(),
                    job.entry.label,
                    job.samples
                ));
                let renderer = pool.get(job.slot)?;
                if renderer.options() != &job.options {
                    renderer.set_options(gl, &job.options)?;
                }
                renderer.set_camera(*camera);
                job.frames.push(renderer.render(gl)?);
                let image = renderer.read_final(gl)?;
                let flip = compare::flip(&r, &image).ok_or_else(|| {
                    Error::invalid("bench: the reference and the run differ in size")
                })?;
                track.flips.push(f64::from(flip.mean));
                if let (Some(rb), Some(ib)) = (&reference_before, &track.previous) {
                    let e = compare::temporal_error(rb, &r, ib, &image).ok_or_else(|| {
                        Error::invalid("bench: consecutive frames differ in size")
                    })?;
                    track.temporal.push(e);
                }
                if let Some(s) = compare::edge_sharpness(&r, &image) {
                    track.sharpness.push(s);
                }
                if let (Some(gauge), Some(errors)) = (&gauge, track.bar_errors.as_mut()) {
                    let widths = gauge.widths(&image)?;
                    errors.push(
                        widths
                            .iter()
                            .zip(gauge.reference_widths())
                            .map(|(w, r)| w - r)
                            .collect(),
                    );
                }
                if t == CameraPath::middle(motion.frames) {
                    job.image = Some(image.clone());
                    job.complex_fraction = renderer.complex_pixel_fraction(gl)?;
                    job.second_layer_share = renderer.read_second_layer_coverage(gl)?.map(|c| {
                        let covered = c.pixels().filter(|p| p[0] > 0).count();
                        covered as f64 / (c.width() as f64 * c.height() as f64).max(1.0)
                    });
                }
                match crop {
                    Some(c) => track.crops.push(crop_of(&image, c)),
                    None => track.first = Some(image.clone()),
                }
                track.previous = Some(image);
                pb.inc(1);
            }
            // The crop: where the methods' first frames disagree most.
            let c = match crop {
                Some(c) => c,
                None => {
                    let firsts: Vec<&RgbaImage> =
                        tracks.iter().filter_map(|k| k.first.as_ref()).collect();
                    let side = super::crops::crop_side(w, h);
                    let (x, y) = super::crops::choose_crop(&r, &firsts, side);
                    let c = (x, y, side);
                    for track in tracks.iter_mut() {
                        if let Some(first) = track.first.take() {
                            track.crops.push(crop_of(&first, c));
                        }
                    }
                    crop = Some(c);
                    c
                }
            };
            reference_crops.push(crop_of(&r, c));
            reference_before = Some(r);
        }
        Ok(PathRun {
            px,
            reference_crops,
            tracks,
            crop: crop.unwrap_or((0, 0, 1)),
        })
    })();
    reference.destroy(gl);
    result
}

/// The first frame from which every frame's FLIP stays within 10 % of the
/// median FLIP of the path's second half.
pub fn settle_frames(flips: &[f64]) -> u32 {
    if flips.is_empty() {
        return 0;
    }
    let settled = median(flips[flips.len() / 2..].to_vec()) * 1.1;
    let last_above = flips.iter().rposition(|&f| f > settled);
    last_above.map_or(0, |k| k as u32 + 1)
}

/// The standard deviation of `values` (over n, the frames being all there
/// is); 0 for fewer than two.
fn std_dev(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return 0.0;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt()
}

/// The measures of one track.
pub(super) fn measures(track: &Track, frames: u32, px: f64) -> MotionMeasures {
    let (worst_frame, worst) =
        track
            .flips
            .iter()
            .copied()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (k, f)| {
                if f > best.1 { (k, f) } else { best }
            });
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let bar_width_jitter_px = track.bar_errors.as_ref().and_then(|errors| {
        let bars = errors.first()?.len();
        let per_bar: Vec<f64> = (0..bars)
            .map(|b| std_dev(&errors.iter().map(|e| e[b]).collect::<Vec<_>>()))
            .collect();
        mean(&per_bar)
    });
    MotionMeasures {
        frames,
        px_per_frame: px,
        flip_mean: mean(&track.flips).unwrap_or(0.0),
        flip_first: track.flips.first().copied().unwrap_or(0.0),
        flip_worst: worst.max(0.0),
        flip_worst_frame: worst_frame as u32,
        temporal_error: mean(&track.temporal).unwrap_or(0.0),
        bar_width_jitter_px,
        settle_frames: settle_frames(&track.flips),
        sharpness: mean(&track.sharpness),
    }
}

/// The README's motion lines: per scene of a motion report, each run's
/// temporal error and mean FLIP over the frames, and where the two-layer
/// resolve stands against per-sample lighting, as Markdown bullets. Empty
/// for a report of still frames.
pub fn motion_summary(report: &super::report::Report) -> String {
    let Some(path) = &report.motion else {
        return String::new();
    };
    let mut out = String::new();
    for scene in report.scenes() {
        let runs: Vec<(&super::report::Run, &MotionMeasures)> = report
            .runs_of(scene)
            .filter_map(|r| r.motion.as_ref().map(|m| (r, m)))
            .collect();
        if runs.is_empty() {
            continue;
        }
        let cells: Vec<String> = runs
            .iter()
            .map(|(r, m)| {
                format!(
                    "`{}` {:.4} (FLIP {:.4})",
                    r.method, m.temporal_error, m.flip_mean
                )
            })
            .collect();
        let of = |method: &str| {
            runs.iter()
                .find(|(r, _)| r.method == method)
                .map(|(_, m)| m.temporal_error)
        };
        let ratio = match (of("median:layers=2"), of("per-sample")) {
            (Some(a), Some(b)) if b > 0.0 => {
                format!("; `median:layers=2` at {:.2}x per-sample's", a / b)
            }
            _ => String::new(),
        };
        // Which method changes least unlike the reference: stated, whichever it is.
        let lowest = runs
            .iter()
            .min_by(|a, b| a.1.temporal_error.total_cmp(&b.1.temporal_error))
            .map_or(String::new(), |(r, _)| format!("; lowest: `{}`", r.method));
        out.push_str(&format!(
            "- `{scene}` (`{path}`): temporal error {}{ratio}{lowest}\n",
            cells.join(", ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_has_a_line_per_moving_scene() {
        let mut none = super::super::report::tests::run("none", 1.0);
        let mut two = super::super::report::tests::run("median:layers=2", 1.0);
        let mut per_sample = super::super::report::tests::run("per-sample", 1.0);
        let mut report = super::super::report::tests::report(Vec::new());
        assert_eq!(motion_summary(&report), "");
        for (run, temporal) in [
            (&mut none, 0.02),
            (&mut two, 0.006),
            (&mut per_sample, 0.005),
        ] {
            run.motion = Some(measures(
                &Track {
                    flips: vec![0.1],
                    temporal: vec![temporal],
                    ..Track::default()
                },
                2,
                0.5,
            ));
        }
        report.runs = vec![none, two, per_sample];
        report.motion = Some("pan:frames=2,px=0.5".into());
        let line = motion_summary(&report);
        assert_eq!(line.lines().count(), 1, "{line}");
        assert!(line.contains("`none` 0.0200 (FLIP 0.1000)"), "{line}");
        assert!(line.contains("at 1.20x per-sample's"), "{line}");
        assert!(line.ends_with("lowest: `per-sample`\n"), "{line}");
    }

    #[test]
    fn the_error_settles_after_its_last_frame_above_the_settled_level() {
        assert_eq!(settle_frames(&[0.1, 0.1, 0.1, 0.1]), 0);
        // A warm-up: high error for three frames, then flat.
        assert_eq!(settle_frames(&[0.5, 0.3, 0.2, 0.1, 0.1, 0.1, 0.1, 0.1]), 3);
        // A late spike counts too.
        assert_eq!(settle_frames(&[0.1, 0.1, 0.1, 0.1, 0.1, 0.3, 0.1, 0.1]), 6);
        assert_eq!(settle_frames(&[]), 0);
    }

    #[test]
    fn jitter_is_the_spread_of_each_bars_error_over_the_frames() {
        let track = Track {
            flips: vec![0.2, 0.1, 0.3],
            temporal: vec![0.01, 0.03],
            sharpness: vec![0.9, 1.1],
            // Bar 0 steady at +0.5 px, bar 1 popping between −1 and +1.
            bar_errors: Some(vec![vec![0.5, -1.0], vec![0.5, 1.0], vec![0.5, -1.0]]),
            ..Track::default()
        };
        let m = measures(&track, 3, 0.5);
        assert!((m.flip_mean - 0.2).abs() < 1e-12);
        assert_eq!((m.flip_worst, m.flip_worst_frame), (0.3, 2));
        assert_eq!(m.flip_first, 0.2);
        assert!((m.temporal_error - 0.02).abs() < 1e-12);
        assert_eq!(m.sharpness, Some(1.0));
        let sd1 = (8.0f64 / 9.0).sqrt();
        assert!((m.bar_width_jitter_px.unwrap() - sd1 / 2.0).abs() < 1e-12);
    }
}
