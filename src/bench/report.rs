//! The bench report: `report.json` (its schema: docs/bench.md,
//! "report.json") and `report.md` (a table per scene with ratios to `none`).

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// The whole report, as written to `report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VERSION`.
    pub gl_version: String,
    /// What the error measures compare against.
    pub reference: Reference,
    /// One run per (scene, method entry, real sample count).
    pub runs: Vec<Run>,
    /// `egl` or `osmesa` (extra key).
    pub backend: String,
    /// Frames timed per run; `ms_total` is their median (extra key).
    pub frames: u32,
    /// Untimed frames first (extra key).
    pub warmup: u32,
    /// Point lights added to each scene by `--lights` (extra key).
    pub extra_lights: u32,
    /// `recommended` or `freespace-open` (extra key).
    pub layout: String,
    /// With `bench --motion`: the camera path every run followed, e.g.
    /// `pan:frames=24,px=0.5` (extra key; absent for still frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<String>,
}

/// The reference the error measures compare against.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// `ssaa`: the whole pipeline at 4×4 supersampling, box-filtered in linear light.
    pub method: String,
    /// Samples per pixel (16).
    pub spp: u32,
}

/// The motion table of one scene's runs (`bench --motion`): a row per run
/// with a [`MotionMeasures`]; `None` when no run has one.
pub fn motion_table(runs: &[&Run], path: Option<&str>) -> Option<String> {
    let moving: Vec<(&Run, &MotionMeasures)> = runs
        .iter()
        .filter_map(|r| r.motion.as_ref().map(|m| (*r, m)))
        .collect();
    let (_, first) = moving.first()?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "In motion (`{}`, {} frames at {:.2} px per frame; the reference is rendered for every frame; \
         docs/motion.md defines each measure): FLIP over the frames, its worst frame, the temporal \
         error (change the reference does not have, or lacks), the thin bars' width jitter, the \
         frames until the error settles, and edge sharpness against the reference (1 as sharp).\n",
        path.unwrap_or("?"),
        first.frames,
        first.px_per_frame
    );
    let _ = writeln!(
        md,
        "| method | samples | AA ms | FLIP mean | worst frame | temporal error | bar jitter px | settle frames | sharpness |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
    for (r, m) in moving {
        let _ = writeln!(
            md,
            "| `{}` | {} | {:.2} | {:.4} | {:.4} (#{}) | {:.5} | {} | {} | {} |",
            r.method,
            r.samples,
            r.ms_aa,
            m.flip_mean,
            m.flip_worst,
            m.flip_worst_frame,
            m.temporal_error,
            m.bar_width_jitter_px
                .map_or("–".to_string(), |j| format!("{j:.3}")),
            m.settle_frames,
            m.sharpness.map_or("–".to_string(), |s| format!("{s:.3}")),
        );
    }
    Some(md)
}

/// The profiles of `runs` (`bench --profile`) as one table, a row per step
/// in the order they ran and a column per profiled run; `None` when no run
/// has one.
pub fn profile_table(runs: &[&Run]) -> Option<String> {
    let profiled: Vec<(&Run, &Vec<ProfileStep>)> = runs
        .iter()
        .filter_map(|r| r.profile.as_ref().map(|p| (*r, p)))
        .collect();
    if profiled.is_empty() {
        return None;
    }
    let mut steps: Vec<&str> = Vec::new();
    for (_, profile) in &profiled {
        for s in profile.iter() {
            if !steps.contains(&s.step.as_str()) {
                steps.push(&s.step);
            }
        }
    }
    let mut md = String::from(
        "Profile (`--profile`): each step's median time in ms, over as many extra frames as were \
         timed, each between two `glFinish` calls (a profiled frame is slower than a plain one: \
         read the steps' shares).\n\n",
    );
    let names: Vec<String> = profiled
        .iter()
        .map(|(r, _)| format!("`{}`", r.method))
        .collect();
    let _ = writeln!(md, "| step | {} |", names.join(" | "));
    let _ = writeln!(md, "|---|{}|", vec!["---:"; names.len()].join("|"));
    for step in steps.iter().copied().chain(["total"]) {
        let cells: Vec<String> = profiled
            .iter()
            .map(|(_, profile)| {
                let ms: Vec<f64> = profile
                    .iter()
                    .filter(|s| step == "total" || s.step == step)
                    .map(|s| s.ms)
                    .collect();
                if ms.is_empty() {
                    "–".into()
                } else {
                    format!("{:.2}", ms.iter().sum::<f64>())
                }
            })
            .collect();
        let _ = writeln!(md, "| {step} | {} |", cells.join(" | "));
    }
    Some(md)
}

/// One step of a profiled frame ([`Run::profile`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProfileStep {
    /// What ran: `resolve`, `second layer: copy in`, …
    pub step: String,
    /// Its median time in milliseconds.
    pub ms: f64,
}

/// One method on one scene at one sample count.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    /// The scene spec (`builtin:NAME` or a path).
    pub scene: String,
    /// The method entry exactly as written (`median:hard`, `none+fxaa`).
    pub method: String,
    /// Whether FXAA ran.
    pub fxaa: bool,
    /// Whether SMAA ran (`smaa`, `+smaa`).
    #[serde(default)]
    pub smaa: bool,
    /// Real samples per pixel of the G-buffer pass (1 for `none`).
    pub samples: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Median frame time over the timed frames, in milliseconds.
    pub ms_total: f64,
    /// Median time the anti-aliasing adds: resolve + FXAA or SMAA (+ lighting beyond
    /// `none`'s for per-sample methods), in milliseconds.
    pub ms_aa: f64,
    /// How times were measured: `gl-time-elapsed` or `finish-wall-clock`.
    pub timer: String,
    /// Mean FLIP error against the reference (0 = identical, 1 = worst).
    pub flip_mean: f64,
    /// PSNR over RGB against the reference in dB (`null` when identical).
    pub psnr_db: Option<f64>,
    /// Pixels brighter than the reference by more than 0.1 in luminance.
    pub halo_pixels: u64,
    /// G-buffer memory the method needs: the single-sample G-buffer, plus
    /// the multisampled twin for MSAA methods.
    pub gbuffer_bytes: u64,
    /// Median resolve time in ms (extra key).
    pub ms_resolve: f64,
    /// Median FXAA time in ms (extra key).
    pub ms_fxaa: f64,
    /// Median time of SMAA's three passes in ms, 0 without SMAA (extra key).
    #[serde(default)]
    pub ms_smaa: f64,
    /// Median time of SMAA's edge pass in ms (extra key).
    #[serde(default)]
    pub ms_smaa_edges: f64,
    /// Median time of SMAA's blending-weight pass in ms (extra key).
    #[serde(default)]
    pub ms_smaa_weights: f64,
    /// Median time of SMAA's neighbourhood-blending pass in ms (extra key).
    #[serde(default)]
    pub ms_smaa_blend: f64,
    /// Median lighting time in ms (extra key).
    pub ms_lighting: f64,
    /// Median time of the resolve's second layer in ms, 0 with one layer:
    /// the retrofit's copies around the second lighting, its stencil mask,
    /// the second lighting and the mix (the second layer's resolve is in
    /// `ms_resolve`; both are in `ms_aa`).
    #[serde(default)]
    pub ms_second_layer: f64,
    /// 95th percentile of the per-pixel FLIP error (extra key).
    pub flip_p95: f64,
    /// Fraction of pixels the method treated as complex in its last frame
    /// ([`Renderer::complex_pixel_fraction`](crate::renderer::Renderer::complex_pixel_fraction)):
    /// for the resolve methods those it took its slow path on (depth keys
    /// not all equal; all of them with `:nofast`), for `complex` those lit
    /// per sample, 1 for `per-sample` (extra key; `null` without multisampling).
    pub complex_fraction: Option<f64>,
    /// With two layers: the share of pixels the second layer covers (its
    /// coverage above 0) in the last frame (extra key; `null` otherwise).
    #[serde(default)]
    pub second_layer_share: Option<f64>,
    /// `sparse`: pixels that fell back to one sample because the block pool
    /// ran out in the last frame (extra key; `null` for other methods).
    #[serde(default)]
    pub sparse_overflow_pixels: Option<u64>,
    /// `sparse`: the bytes of the full layout's multisampled G-buffer at
    /// the same size and sample count, what `sparse` stands in for (extra
    /// key; `null` for other methods).
    #[serde(default)]
    pub full_ms_gbuffer_bytes: Option<u64>,
    /// The requested sample count (extra key; the driver may round it).
    pub samples_requested: u32,
    /// Lights in the scene as rendered, `--lights` included (extra key).
    pub lights: u32,
    /// For a scene that declares thin bars: the mean signed error of the
    /// bars' drawn width against the reference's, in pixels, negative when
    /// drawn thinner ([`bar_width`](super::bar_width); extra key, `null`
    /// for other scenes).
    #[serde(default)]
    pub bar_width_error_px: Option<f64>,
    /// Mean FLIP over the scene's pixels with two or more surface clusters
    /// (silhouettes, creases: the bench's cluster mask; extra key, `null`
    /// without the mask or when it marks no pixel).
    #[serde(default)]
    pub flip_edges: Option<f64>,
    /// Mean FLIP over the other pixels (extra key, `null` without the
    /// mask or when it marks every pixel).
    #[serde(default)]
    pub flip_interior: Option<f64>,
    /// The share of the image the cluster mask marks, 0 to 1: the same for
    /// every run of a scene (extra key, `null` without the mask).
    #[serde(default)]
    pub edge_pixel_share: Option<f64>,
    /// Mean FLIP over the scene's pixels with three or more surface
    /// clusters (a thin bar in front of a crease in front of a wall: where
    /// two layers still share a pixel among more surfaces; extra key,
    /// `null` without the mask or when it marks no pixel).
    #[serde(default)]
    pub flip_three_clusters: Option<f64>,
    /// The share of the image those pixels make, 0 to 1 (extra key, `null`
    /// without the mask).
    #[serde(default)]
    pub three_cluster_share: Option<f64>,
    /// With `bench --profile`, for a method that resolves with the
    /// retrofit: each of the retrofit's steps (and the renderer's own
    /// second-layer passes), timed between two `glFinish` calls over as
    /// many extra frames as were timed, the median of each (extra key;
    /// absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<Vec<ProfileStep>>,
    /// With `bench --motion`: the measures over the camera path's frames
    /// (docs/motion.md; extra key, absent for still frames). The run's
    /// other error fields are then those of the path's middle frame, the
    /// scene's own camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionMeasures>,
}

/// What a run shows along a camera path (docs/motion.md has each formula).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionMeasures {
    /// Frames along the path.
    pub frames: u32,
    /// The mean image motion per frame of the scene's bounds, in pixels, as
    /// the path measures it.
    pub px_per_frame: f64,
    /// The mean over the frames of each frame's mean FLIP against that
    /// frame's reference.
    pub flip_mean: f64,
    /// The first frame's mean FLIP (a temporal filter's, before it has a
    /// history), against which a later frame's growth shows.
    #[serde(default)]
    pub flip_first: f64,
    /// The worst frame's mean FLIP, and its index from 0.
    pub flip_worst: f64,
    /// The index of that frame.
    pub flip_worst_frame: u32,
    /// The mean over pixels and consecutive frame pairs of the HyAB size of
    /// `(I_t − I_{t−1}) − (R_t − R_{t−1})` in CIELAB, over 100: flicker and
    /// crawl the reference does not have, or lag behind it.
    pub temporal_error: f64,
    /// On a scene with thin bars: the mean over the bars of the standard
    /// deviation over the frames of the bar's measured width less the
    /// reference's in that frame, in pixels (`null` without bars).
    #[serde(default)]
    pub bar_width_jitter_px: Option<f64>,
    /// The first frame from which every frame's FLIP stays within 10 % of
    /// the median FLIP of the path's second half: how long a method's error
    /// takes to settle after the path starts (0 for a method without
    /// history, unless its error varies that much along the path).
    pub settle_frames: u32,
    /// The mean over the frames of the run's edge sharpness against that
    /// frame's reference (`compare::edge_sharpness`: 1 as sharp, below 1
    /// blurred; `null` when the reference has no edge).
    #[serde(default)]
    pub sharpness: Option<f64>,
}

impl Report {
    /// The scenes in the order they were run.
    pub fn scenes(&self) -> Vec<&str> {
        let mut scenes: Vec<&str> = Vec::new();
        for r in &self.runs {
            if !scenes.contains(&r.scene.as_str()) {
                scenes.push(&r.scene);
            }
        }
        scenes
    }

    /// The runs of one scene.
    pub fn runs_of<'a>(&'a self, scene: &'a str) -> impl Iterator<Item = &'a Run> + 'a {
        self.runs.iter().filter(move |r| r.scene == scene)
    }

    /// The `none` run of a scene, which the Markdown ratios divide by.
    pub fn baseline(&self, scene: &str) -> Option<&Run> {
        self.runs
            .iter()
            .find(|r| r.scene == scene && r.method == "none")
    }

    /// `report.json`, pretty-printed.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self)
            .map_err(|e| Error::invalid(format!("writing the report as JSON: {e}")))
    }

    /// `report.md`: a header, then per scene a table with ratios to the
    /// scene's `none` run and the methods on the error/time Pareto front.
    pub fn to_markdown(&self) -> String {
        let mut md = String::new();
        let first = self.runs.first();
        let _ = writeln!(md, "# deferred-msaa bench\n");
        let _ = writeln!(
            md,
            "{} · OpenGL {} · {} backend · {} · timer `{}`  ",
            self.renderer,
            self.gl_version,
            self.backend,
            first.map_or("no runs".to_string(), |r| format!(
                "{}x{}",
                r.width, r.height
            )),
            first.map_or("-", |r| r.timer.as_str()),
        );
        let _ = writeln!(
            md,
            "Reference: `{}` ({} samples per pixel, box-filtered in linear light). \
             Times: median of {} frames after {} warm-up frames, methods interleaved frame by frame. \
             Layout: {}. Extra lights: {}.\n",
            self.reference.method,
            self.reference.spp,
            self.frames,
            self.warmup,
            self.layout,
            self.extra_lights
        );
        if let Some(path) = &self.motion {
            let _ = writeln!(
                md,
                "In motion, along `{path}`: the times are over the path's frames, each scene's \
                 table below is its middle frame's (the scene's own camera), and the motion table \
                 after it is over the whole path.\n"
            );
        }
        let _ = writeln!(
            md,
            "Ratios (×) are to `none` on the same scene in the same run. \
             FLIP: mean error against the reference, lower is better. \
             Halo: pixels brighter than the reference by more than 0.1 in luminance. \
             ★: on the Pareto front of error against frame time.\n"
        );
        for scene in self.scenes() {
            let runs: Vec<&Run> = self.runs_of(scene).collect();
            let base = self.baseline(scene);
            let ratio = |v: f64, b: Option<f64>| match b {
                Some(b) if b > 0.0 && v.is_finite() => format!("{:.2}", v / b),
                _ => "–".to_string(),
            };
            let front = pareto_front(
                &runs
                    .iter()
                    .map(|r| (r.ms_total, r.flip_mean))
                    .collect::<Vec<_>>(),
            );
            let _ = writeln!(md, "## `{scene}`\n");
            let _ = writeln!(
                md,
                "{} lights. Complex %: the pixels a method treated as complex (the resolve's slow path; \
                 `complex`: lit per sample). G-buffer: single-sample textures plus the twins \
                 (`:full`: every attachment of the layout, else the scene-adaptive plan's).\n",
                runs.first().map_or(0, |r| r.lights)
            );
            // The edge split and the bar width get columns only where a run
            // of the scene has them: old reports and scenes without bars have none.
            let edge_columns = runs
                .iter()
                .any(|r| r.flip_edges.is_some() || r.flip_interior.is_some());
            let bar_column = runs.iter().any(|r| r.bar_width_error_px.is_some());
            let layer_column = runs.iter().any(|r| r.second_layer_share.is_some());
            let three_column = runs.iter().any(|r| r.flip_three_clusters.is_some());
            if let Some(share) = runs.iter().find_map(|r| r.edge_pixel_share) {
                let _ = writeln!(
                    md,
                    "FLIP edges, FLIP interior: mean FLIP over the pixels the bench's cluster mask \
                     marks as holding two or more surface clusters (silhouettes, creases), \
                     {:.1} % of this scene's, and over the rest.\n",
                    share * 100.0
                );
            }
            if let Some(share) = runs
                .iter()
                .filter(|_| three_column)
                .find_map(|r| r.three_cluster_share)
            {
                let _ = writeln!(
                    md,
                    "FLIP 3+ clusters: mean FLIP over the pixels holding three or more surface \
                     clusters (where two layers still share a pixel among more surfaces), \
                     {:.3} % of this scene's.\n",
                    share * 100.0
                );
            }
            if layer_column {
                let _ = writeln!(
                    md,
                    "Second layer %: with two layers, the pixels the second layer covers (two or \
                     more clusters of samples) in the run's last frame.\n"
                );
            }
            if bar_column {
                let _ = writeln!(
                    md,
                    "Bar width error: the mean signed error of the drawn width of the scene's thin \
                     bars against the reference, in pixels (negative: drawn thinner).\n"
                );
            }
            let mut header = vec![
                "method",
                "samples",
                "ms total",
                "× none",
                "ms AA",
                "FLIP mean",
                "× none",
            ];
            if edge_columns {
                header.extend(["FLIP edges", "FLIP interior"]);
            }
            if three_column {
                header.push("FLIP 3+ clusters");
            }
            if bar_column {
                header.push("bar width error px");
            }
            if layer_column {
                header.push("second layer %");
            }
            header.extend(["PSNR dB", "halo px", "complex %", "G-buffer MiB", "× none"]);
            let mut align = vec!["---"];
            align.resize(header.len(), "---:");
            let _ = writeln!(md, "| {} |", header.join(" | "));
            let _ = writeln!(md, "|{}|", align.join("|"));
            for (run, on_front) in runs.iter().zip(&front) {
                let mut cells = vec![
                    format!("`{}`{}", run.method, if *on_front { " ★" } else { "" }),
                    run.samples.to_string(),
                    format!("{:.2}", run.ms_total),
                    ratio(run.ms_total, base.map(|b| b.ms_total)),
                    format!("{:.2}", run.ms_aa),
                    format!("{:.4}", run.flip_mean),
                    ratio(run.flip_mean, base.map(|b| b.flip_mean)),
                ];
                if edge_columns {
                    cells.push(cell(run.flip_edges, |v| format!("{v:.4}")));
                    cells.push(cell(run.flip_interior, |v| format!("{v:.4}")));
                }
                if three_column {
                    cells.push(cell(run.flip_three_clusters, |v| format!("{v:.4}")));
                }
                if bar_column {
                    cells.push(cell(run.bar_width_error_px, |v| format!("{v:+.3}")));
                }
                if layer_column {
                    cells.push(cell(run.second_layer_share, |v| {
                        format!("{:.1}", v * 100.0)
                    }));
                }
                cells.extend([
                    run.psnr_db.map_or("∞".to_string(), |p| format!("{p:.2}")),
                    run.halo_pixels.to_string(),
                    cell(run.complex_fraction, |c| format!("{:.1}", c * 100.0)),
                    format!("{:.1}", run.gbuffer_bytes as f64 / (1024.0 * 1024.0)),
                    ratio(
                        run.gbuffer_bytes as f64,
                        base.map(|b| b.gbuffer_bytes as f64),
                    ),
                ]);
                let _ = writeln!(md, "| {} |", cells.join(" | "));
            }
            let _ = writeln!(md);
            if let Some(line) = lighting_orderings(&runs) {
                let _ = writeln!(md, "{line}\n");
            }
            if let Some(line) = smaa_standing(&runs) {
                let _ = writeln!(md, "{line}\n");
            }
            if let Some(table) = motion_table(&runs, self.motion.as_deref()) {
                let _ = writeln!(md, "{table}");
            }
            if let Some(table) = profile_table(&runs) {
                let _ = writeln!(md, "{table}");
            }
            for run in runs.iter().filter(|r| r.full_ms_gbuffer_bytes.is_some()) {
                let full = run.full_ms_gbuffer_bytes.unwrap_or(0);
                let _ = writeln!(
                    md,
                    "`{}` {}x: its G-buffer (heads, first blocks, pool, multisampled depth) takes \
                     {:.1} MiB against {:.1} MiB for the full {}x multisampled G-buffer ({} ×); \
                     {} pixels fell back to one sample (block pool ran out).\n",
                    run.method,
                    run.samples,
                    run.gbuffer_bytes as f64 / (1024.0 * 1024.0),
                    full as f64 / (1024.0 * 1024.0),
                    run.samples,
                    ratio(run.gbuffer_bytes as f64, Some(full as f64)),
                    run.sparse_overflow_pixels
                        .map_or("–".to_string(), |n| n.to_string()),
                );
            }
        }
        md
    }

    /// Write `report.json` and `report.md` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let json = dir.join("report.json");
        std::fs::write(&json, self.to_json()?).map_err(|e| Error::io(&json, e))?;
        let md = dir.join("report.md");
        std::fs::write(&md, self.to_markdown()).map_err(|e| Error::io(&md, e))?;
        Ok(())
    }
}

/// Where `median:layers=2` stands against SMAA on one scene (the post
/// filter engines ship, alone as `smaa` and after the resolve as
/// `median+smaa`, FreeSpace Open's pipeline), in FLIP and in frame time,
/// and what SMAA's three passes cost: `None` without a `smaa` or
/// `median+smaa` run.
pub fn smaa_standing(runs: &[&Run]) -> Option<String> {
    let find = |method: &str| runs.iter().find(|r| r.method == method);
    let smaa_runs: Vec<&&Run> = ["smaa", "median+smaa"]
        .iter()
        .filter_map(|m| find(m))
        .collect();
    if smaa_runs.is_empty() {
        return None;
    }
    let mut parts = Vec::new();
    if let Some(layers) = find("median:layers=2") {
        for other in &smaa_runs {
            parts.push(format!(
                "`median:layers=2` against `{}`: FLIP {:.4} against {:.4} ({:.2} ×), {:.2} ms against {:.2} ms ({:.2} ×)",
                other.method,
                layers.flip_mean,
                other.flip_mean,
                layers.flip_mean / other.flip_mean.max(f64::MIN_POSITIVE),
                layers.ms_total,
                other.ms_total,
                layers.ms_total / other.ms_total.max(f64::MIN_POSITIVE),
            ));
        }
    }
    for run in &smaa_runs {
        parts.push(format!(
            "SMAA's passes in `{}`: edges {:.2} ms, blending weights {:.2} ms, neighbourhood blending {:.2} ms",
            run.method, run.ms_smaa_edges, run.ms_smaa_weights, run.ms_smaa_blend
        ));
    }
    Some(format!("{}.", parts.join("; ")))
}

/// The orderings of one scene's lighting times the bench is about, and
/// whether this run's measurements kept them: lighting every sample costs
/// more than lighting the resolved G-buffer (`per-sample` above `median`),
/// and lighting only the complex pixels' samples sits between the two.
/// Times vary with the machine's load, so no test asserts these; the report
/// states them. `None` without both a `median` and a `per-sample` run.
pub fn lighting_orderings(runs: &[&Run]) -> Option<String> {
    let lighting = |method: &str| {
        runs.iter()
            .find(|r| r.method == method)
            .map(|r| r.ms_lighting)
    };
    let held = |ok: bool| if ok { "held" } else { "did not hold" };
    let (median, per_sample) = (lighting("median")?, lighting("per-sample")?);
    let mut line = format!(
        "Lighting-time orderings (measured, not asserted): `per-sample` > `median`: {} \
         ({per_sample:.2} > {median:.2} ms)",
        held(per_sample > median)
    );
    if let Some(complex) = lighting("complex") {
        let _ = write!(
            line,
            "; `median` < `complex` < `per-sample`: {} ({median:.2} < {complex:.2} < {per_sample:.2} ms)",
            held(median < complex && complex < per_sample)
        );
    }
    line.push('.');
    Some(line)
}

/// A table cell: the formatted value, or a dash without one.
fn cell(value: Option<f64>, format: impl Fn(f64) -> String) -> String {
    value.map_or("–".to_string(), format)
}

/// Which points of (time, error) pairs are on the Pareto front: no other
/// point is at least as fast and at least as good and better in one of the
/// two. Points with a non-finite coordinate are never on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            t.is_finite()
                && e.is_finite()
                && !points.iter().any(|&(t2, e2)| {
                    t2.is_finite() && e2.is_finite() && t2 <= t && e2 <= e && (t2 < t || e2 < e)
                })
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn the_pareto_front_keeps_the_undominated() {
        let pts = [
            (1.0, 0.5),
            (2.0, 0.2),
            (3.0, 0.3),
            (2.0, 0.2),
            (0.5, f64::NAN),
        ];
        assert_eq!(pareto_front(&pts), [true, true, false, true, false]);
    }

    pub(crate) fn run(method: &str, ms_lighting: f64) -> Run {
        Run {
            scene: "builtin:halo".into(),
            method: method.into(),
            fxaa: false,
            smaa: false,
            samples: 4,
            width: 96,
            height: 54,
            ms_total: 2.0,
            ms_aa: 0.5,
            timer: "finish-wall-clock".into(),
            flip_mean: 0.1,
            psnr_db: Some(30.0),
            halo_pixels: 0,
            gbuffer_bytes: 1 << 20,
            ms_resolve: 0.1,
            ms_fxaa: 0.0,
            ms_smaa: 0.0,
            ms_smaa_edges: 0.0,
            ms_smaa_weights: 0.0,
            ms_smaa_blend: 0.0,
            ms_lighting,
            ms_second_layer: 0.0,
            flip_p95: 0.2,
            complex_fraction: None,
            sparse_overflow_pixels: None,
            second_layer_share: None,
            full_ms_gbuffer_bytes: None,
            samples_requested: 4,
            lights: 7,
            bar_width_error_px: None,
            flip_edges: None,
            flip_interior: None,
            edge_pixel_share: None,
            flip_three_clusters: None,
            three_cluster_share: None,
            profile: None,
            motion: None,
        }
    }

    pub(crate) fn report(runs: Vec<Run>) -> Report {
        Report {
            renderer: "llvmpipe".into(),
            gl_version: "4.5".into(),
            reference: Reference {
                method: "ssaa".into(),
                spp: 16,
            },
            runs,
            backend: "egl".into(),
            frames: 3,
            warmup: 1,
            extra_lights: 0,
            layout: "recommended".into(),
            motion: None,
        }
    }

    /// A report written before the edge split and the bar width loads,
    /// with those keys `null`, and its Markdown has no columns for them;
    /// a run that has them gets its columns, and the scene its share line.
    #[test]
    fn the_profile_table_has_a_row_per_step_and_a_column_per_profiled_run() {
        let none = run("none", 1.0);
        assert_eq!(profile_table(&[&none]), None);
        let step = |step: &str, ms: f64| ProfileStep {
            step: step.into(),
            ms,
        };
        let mut one = run("median", 1.0);
        one.profile = Some(vec![step("resolve", 2.0)]);
        let mut two = run("median:layers=2", 1.0);
        two.profile = Some(vec![step("resolve", 3.0), step("second layer: mix", 1.25)]);
        let table = profile_table(&[&none, &one, &two]).unwrap();
        let rows: Vec<&str> = table.lines().filter(|l| l.starts_with('|')).collect();
        assert_eq!(rows[0], "| step | `median` | `median:layers=2` |");
        assert_eq!(rows[2], "| resolve | 2.00 | 3.00 |");
        assert_eq!(rows[3], "| second layer: mix | – | 1.25 |");
        assert_eq!(rows[4], "| total | 2.00 | 4.25 |");
    }

    #[test]
    fn edge_and_bar_columns_appear_only_where_runs_have_them() {
        let old = report(vec![run("none", 1.0), run("median", 1.0)]);
        let mut json: serde_json::Value = serde_json::from_str(&old.to_json().unwrap()).unwrap();
        for r in json["runs"].as_array_mut().unwrap() {
            let r = r.as_object_mut().unwrap();
            for key in [
                "bar_width_error_px",
                "flip_edges",
                "flip_interior",
                "edge_pixel_share",
                "flip_three_clusters",
                "three_cluster_share",
            ] {
                assert!(r.remove(key).is_some(), "{key}");
            }
        }
        let loaded: Report = serde_json::from_value(json).expect("an old report loads");
        assert_eq!(loaded, old);
        let md = old.to_markdown();
        assert!(
            !md.contains("FLIP edges") && !md.contains("bar width"),
            "{md}"
        );
        let header = md.lines().find(|l| l.starts_with("| method")).unwrap();
        let align = md.lines().find(|l| l.starts_with("|---")).unwrap();
        assert_eq!(header.matches('|').count(), align.matches('|').count());

        let mut new = old.clone();
        for r in &mut new.runs {
            r.flip_edges = Some(0.25);
            r.flip_interior = Some(0.0125);
            r.edge_pixel_share = Some(0.034);
        }
        new.runs[1].bar_width_error_px = Some(-0.4321);
        let md = new.to_markdown();
        assert!(
            md.contains("| FLIP edges | FLIP interior | bar width error px |"),
            "{md}"
        );
        assert!(md.contains("3.4 % of this scene's"), "{md}");
        let median = md.lines().find(|l| l.starts_with("| `median`")).unwrap();
        assert!(median.contains("| 0.2500 | 0.0125 | -0.432 |"), "{median}");
        assert!(!md.contains("3+ clusters"), "{md}");
        let mut three = new.clone();
        three.runs[1].flip_three_clusters = Some(0.0451);
        three.runs[1].three_cluster_share = Some(0.00047);
        let md3 = three.to_markdown();
        assert!(md3.contains("0.047 % of this scene's"), "{md3}");
        let median = md3.lines().find(|l| l.starts_with("| `median`")).unwrap();
        assert!(
            median.contains("| 0.2500 | 0.0125 | 0.0451 | -0.432 |"),
            "{median}"
        );
        let none = md.lines().find(|l| l.starts_with("| `none`")).unwrap();
        assert!(none.contains("| 0.0125 | – |"), "{none}");
        let header = md.lines().find(|l| l.starts_with("| method")).unwrap();
        let align = md.lines().find(|l| l.starts_with("|---")).unwrap();
        for row in md.lines().filter(|l| l.starts_with("| `")).chain([align]) {
            assert_eq!(
                row.matches('|').count(),
                header.matches('|').count(),
                "{row}"
            );
        }
    }

    #[test]
    fn the_smaa_line_sets_two_layers_against_smaa_in_error_and_time() {
        let mut layers = run("median:layers=2", 1.0);
        layers.flip_mean = 0.01;
        layers.ms_total = 30.0;
        let mut smaa = run("smaa", 1.0);
        smaa.flip_mean = 0.02;
        smaa.ms_total = 20.0;
        smaa.ms_smaa_weights = 1.5;
        let runs = [&layers, &smaa];
        let line = smaa_standing(&runs).expect("a line");
        assert!(
            line.contains("FLIP 0.0100 against 0.0200 (0.50 ×)"),
            "{line}"
        );
        assert!(
            line.contains("30.00 ms against 20.00 ms (1.50 ×)"),
            "{line}"
        );
        assert!(line.contains("blending weights 1.50 ms"), "{line}");
        assert!(smaa_standing(&[&layers]).is_none());
        let md = report(vec![layers.clone(), smaa.clone()]).to_markdown();
        assert!(md.contains("`median:layers=2` against `smaa`"), "{md}");
    }

    #[test]
    fn the_lighting_orderings_say_whether_they_held() {
        let (median, complex, per_sample) = (
            run("median", 1.0),
            run("complex", 2.0),
            run("per-sample", 3.0),
        );
        assert_eq!(
            lighting_orderings(&[&median, &complex, &per_sample]).as_deref(),
            Some(
                "Lighting-time orderings (measured, not asserted): `per-sample` > `median`: held \
                 (3.00 > 1.00 ms); `median` < `complex` < `per-sample`: held (1.00 < 2.00 < 3.00 ms)."
            )
        );
        let slow_complex = run("complex", 4.0);
        let line = lighting_orderings(&[&per_sample, &slow_complex, &median]).unwrap();
        assert!(line.contains("`per-sample` > `median`: held"), "{line}");
        assert!(
            line.contains("`complex` < `per-sample`: did not hold"),
            "{line}"
        );
        let line = lighting_orderings(&[&run("median", 3.0), &run("per-sample", 1.0)]).unwrap();
        assert!(
            line.contains("`median`: did not hold") && !line.contains("complex"),
            "{line}"
        );
        assert_eq!(lighting_orderings(&[&median, &complex]), None);
    }
}
