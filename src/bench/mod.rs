//! The error-against-run-time benchmark behind `deferred-msaa bench`.
//!
//! For every scene it renders a reference — the whole pipeline at 4×4
//! supersampling (16 samples per pixel, tonemapped per sample, box-filtered
//! in linear light) — and then times every method entry ([`methods`]) at
//! every requested sample count, interleaved round-robin frame by frame so
//! that machine noise hits all methods alike: `warmup` untimed rounds, then
//! `frames` timed ones, whose median is reported. The last frame of each
//! method is compared with the reference (FLIP mean, PSNR, halo pixels),
//! its FLIP also split into the mean over the scene's edge pixels (those
//! holding two or more surface clusters, a mask made once per scene) and
//! over the rest, and, for a scene that declares thin bars, the error of
//! the bars' drawn width ([`bar_width`]).
//!
//! Methods whose switch changes nothing on the GPU (the resolve methods and
//! their options) share one [`Renderer`]; `none`, `+fxaa` and each sample
//! count get their own, so no frame pays for re-allocated targets.
//!
//! With [`BenchConfig::motion`] (`bench --motion SPEC`) every method
//! renders a camera path instead, against the reference of every frame
//! ([`motion`]; docs/motion.md).
//!
//! Outputs ([`write_outputs`]): `report.json` and `report.md`
//! ([`report`]), `error_vs_time.png` (FLIP mean against frame time per
//! scene, Pareto front marked) and `crops.png` (the same crop of every method
//! beside the reference). The plots need a TrueType font at run time:
//! Debian's `fonts-dejavu-core` (`/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf`),
//! or any `.ttf` named by the `DEFERRED_MSAA_FONT` environment variable.
//!
//! ```no_run
//! use deferred_msaa_lab::bench::{self, BenchConfig};
//! let config = BenchConfig { width: 320, height: 180, ..BenchConfig::default() };
//! let out = std::path::Path::new("target/bench");
//! bench::prepare_output_dir(out)?;
//! let output = bench::run(&config)?;
//! bench::write_outputs(&output, out)?;
//! # Ok::<(), deferred_msaa_lab::Error>(())
//! ```

pub mod bar_width;

mod animation;
mod crops;
pub mod layers;
pub mod methods;
pub mod motion;
mod plot;
pub mod report;

pub use methods::{MethodEntry, default_methods, parse_methods};
use methods::{adds_geometry, adds_lighting};
pub use report::{MotionMeasures, ProfileStep, Reference, Report, Run, pareto_front};

use crate::compare::{self, srgb_to_linear};
use crate::context::{Backend, GlVersion, HeadlessContext};
use crate::gbuffer::GBufferLayout;
use crate::gl::TimerKind;
use crate::renderer::technique::Sparse;
use crate::renderer::{AaMode, FrameTimings, RenderOptions, Renderer};
use crate::resolve::{ResolveMethod, ResolveSettings};
use crate::scene::{Aabb, Light, MotionSpec, Scene};
use crate::{Error, Result};
use bar_width::BarGauge;
use glam::Vec3;
use glow::HasContext;
use image::{GrayImage, RgbImage, RgbaImage};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;

/// The scenes benchmarked when none is named: the two the report's claims
/// are about, `hull` (detail inside a model, where the depth-aware resolve
/// blends) and `halo` (the paper's Figure 4, where averaging lights the gap
/// behind an edge).
pub const DEFAULT_SCENES: &[&str] = &["builtin:hull", "builtin:halo"];

/// The reference renders at this many times the width and the height.
pub const REFERENCE_SCALE: u32 = 4;

/// The luminance excess over the reference that makes a halo pixel.
pub const HALO_THRESHOLD: f32 = 0.1;

/// What to benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchConfig {
    /// The context backend.
    pub backend: Backend,
    /// Scene specs: `builtin:NAME` or `.gltf`/`.glb` paths.
    pub scenes: Vec<String>,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Requested sample counts for the multisampled methods (each is run at
    /// every count; `none` runs once, at 1).
    pub samples: Vec<u32>,
    /// The method entries, in report order.
    pub methods: Vec<MethodEntry>,
    /// Point lights to add to each scene ([`extra_lights`]).
    pub lights: u32,
    /// Timed frames per run (the median is reported); at least 1.
    pub frames: u32,
    /// Untimed rounds before them.
    pub warmup: u32,
    /// The G-buffer layout.
    pub layout: GBufferLayout,
    /// Show a progress bar on stderr (drawn only when stderr is a terminal).
    pub progress: bool,
    /// After the timed frames, render `frames` more of each method that
    /// resolves with the retrofit profiling its steps (`glFinish` around
    /// each), and report each step's median ([`Run::profile`]).
    pub profile: bool,
    /// Render a camera path instead of still frames (`--motion`): every
    /// method renders each of its frames, measured against the reference
    /// of every frame ([`Run::motion`]); `frames` does not apply.
    pub motion: Option<MotionSpec>,
}

impl Default for BenchConfig {
    /// The default scenes and methods at 640×360, 4x, 9 frames after 3
    /// warm-up rounds, no extra lights, the recommended layout, EGL.
    fn default() -> Self {
        BenchConfig {
            backend: Backend::Egl,
            scenes: DEFAULT_SCENES.iter().map(|s| s.to_string()).collect(),
            width: 640,
            height: 360,
            samples: vec![4],
            methods: default_methods(),
            lights: 0,
            frames: 9,
            warmup: 3,
            layout: GBufferLayout::recommended(),
            progress: false,
            profile: false,
            motion: None,
        }
    }
}

impl BenchConfig {
    /// Check everything that can be checked without a context: sizes,
    /// counts, and that every scene names a built-in or an existing file.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(format!(
                "the image size must be at least 1x1, got {}x{}",
                self.width, self.height
            )));
        }
        if self.scenes.is_empty() {
            return Err(Error::invalid("bench needs at least one scene"));
        }
        if self.methods.is_empty() {
            return Err(Error::invalid("bench needs at least one method"));
        }
        if self.samples.is_empty() || self.samples.contains(&0) {
            return Err(Error::invalid(
                "--samples must be at least 1 (use the `none` method for no multisampling)",
            ));
        }
        if self.frames == 0 {
            return Err(Error::invalid("--frames must be at least 1"));
        }
        for spec in &self.scenes {
            check_scene_spec(spec)?;
        }
        Ok(self.layout.validate()?)
    }
}

/// Fail early on a scene spec that cannot load: an unknown built-in or a
/// missing file (parse errors surface when the scene is loaded).
fn check_scene_spec(spec: &str) -> Result<()> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        if !Scene::builtin_names().contains(&name) {
            return Err(Error::Scene {
                path: spec.into(),
                reason: format!(
                    "no built-in scene named `{name}`; the built-ins are {}",
                    Scene::builtin_names().join(", ")
                ),
            });
        }
        return Ok(());
    }
    if !Path::new(spec).is_file() {
        let hint = if Scene::builtin_names().contains(&spec) {
            format!("; did you mean `builtin:{spec}`?")
        } else {
            String::new()
        };
        return Err(Error::Scene {
            path: spec.into(),
            reason: format!("no such file{hint}"),
        });
    }
    Ok(())
}

/// Parse `WIDTHxHEIGHT` (both at least 1).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = |why: &str| {
        Error::invalid(format!(
            "`{s}` is not a size: {why} (expected WIDTHxHEIGHT, e.g. 640x360)"
        ))
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| bad("no `x`"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| bad("the width is not a number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| bad("the height is not a number"))?;
    if w == 0 || h == 0 {
        return Err(bad("width and height must be at least 1"));
    }
    Ok((w, h))
}

/// `n` point lights placed deterministically around `bounds`: on a
/// Fibonacci sphere of 1.25 times the bounding radius about its centre,
/// with colours cycling through a small palette, a range of 4 radii, and
/// intensities that together add about as much light as two of the default
/// rig's point lights (so the image stays exposed while the lighting cost
/// grows with `n`).
pub fn extra_lights(bounds: &Aabb, n: u32) -> Vec<Light> {
    if n == 0 {
        return Vec::new();
    }
    let c = bounds.center();
    let r = bounds.radius().max(1e-3);
    let total = 2.0 * (1.6 * r) * (1.6 * r) * 1.2;
    let each = total / n as f32;
    let palette = [
        Vec3::new(1.0, 0.85, 0.7),
        Vec3::new(0.7, 0.85, 1.0),
        Vec3::new(1.0, 0.7, 0.85),
        Vec3::new(0.8, 1.0, 0.75),
    ];
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let ring = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * i as f32;
            let dir = Vec3::new(ring * phi.cos(), y, ring * phi.sin());
            Light::point(
                c + dir * 1.25 * r,
                palette[i as usize % palette.len()],
                each,
                Some(4.0 * r),
            )
        })
        .collect()
}

/// Linear light to an sRGB-encoded 8-bit value.
fn linear_to_srgb(l: f32) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Box-filter `factor`×`factor` blocks of an sRGB-encoded image in linear
/// light (decode, average, encode); the size must divide by `factor`.
pub fn downsample_srgb(img: &RgbaImage, factor: u32) -> Result<RgbaImage> {
    let factor = factor.max(1);
    let (w, h) = img.dimensions();
    if w % factor != 0 || h % factor != 0 {
        return Err(Error::invalid(format!(
            "a {w}x{h} image does not divide into {factor}x{factor} blocks"
        )));
    }
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let n = (factor * factor) as f32;
    Ok(RgbaImage::from_fn(w / factor, h / factor, |x, y| {
        let mut sum = [0f32; 4];
        for dy in 0..factor {
            for dx in 0..factor {
                let p = img.get_pixel(x * factor + dx, y * factor + dy);
                for c in 0..3 {
                    sum[c] += lut[p[c] as usize];
                }
                sum[3] += p[3] as f32;
            }
        }
        image::Rgba([
            linear_to_srgb(sum[0] / n),
            linear_to_srgb(sum[1] / n),
            linear_to_srgb(sum[2] / n),
            (sum[3] / n).round() as u8,
        ])
    }))
}

/// A finished bench: the report and the images it measured.
#[derive(Clone, Debug)]
pub struct BenchOutput {
    /// The report.
    pub report: Report,
    /// Each scene's reference image, in scene order.
    pub references: Vec<(String, RgbaImage)>,
    /// The final image of each run, parallel to [`Report::runs`] (with
    /// `--motion`, its frame at the scene's own camera).
    pub images: Vec<RgbaImage>,
    /// With `--motion`: per scene, the animated crop strip's frames.
    pub animations: Vec<(String, Vec<RgbImage>)>,
}

/// Create the report folder and load the plots' font, so that a bench does
/// not run for minutes only to fail at the end.
pub fn prepare_output_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    plot::load_font()
}

/// Write `report.json`, `report.md`, `error_vs_time.png` and `crops.png`
/// into `dir`; after a motion bench also `temporal_error_vs_time.png` and
/// each scene's animated crop strip, `motion-SCENE.png` (an APNG).
pub fn write_outputs(output: &BenchOutput, dir: &Path) -> Result<()> {
    prepare_output_dir(dir)?;
    output.report.write(dir)?;
    plot::error_vs_time(&output.report, &dir.join("error_vs_time.png"))?;
    if output.report.motion.is_some() {
        plot::temporal_error_vs_time(&output.report, &dir.join("temporal_error_vs_time.png"))?;
    }
    for (scene, frames) in &output.animations {
        animation::write_apng(frames, &dir.join(motion_strip_name(scene)))?;
    }
    crops::crops(output, &dir.join("crops.png"))
}

/// The file name of a scene's animated crop strip.
pub fn motion_strip_name(scene: &str) -> String {
    format!("motion-{}.png", file_stem(scene))
}

/// Write the first run's side-by-side figure: per scene, the reference's
/// and every run's whole frame above the same crop, magnified, each run
/// labelled with its FLIP and frame time.
pub fn write_side_by_side(output: &BenchOutput, path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        prepare_output_dir(dir)?;
    }
    crops::side_by_side(output, path)
}

/// A file-name-safe form of a scene spec or method entry.
fn file_stem(s: &str) -> String {
    let stem = s.rsplit(['/', '\\']).next().unwrap_or(s);
    stem.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Write every measured image into `dir/images/`: `SCENE-ssaa.png` (the
/// reference) and `SCENE-METHOD-Nx.png` per run, for looking at closely.
pub fn write_images(output: &BenchOutput, dir: &Path) -> Result<()> {
    let dir = dir.join("images");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let save = |img: &RgbaImage, name: String| {
        let path = dir.join(name);
        img.save_with_format(&path, image::ImageFormat::Png)
            .map_err(|source| Error::Image { path, source })
    };
    for (scene, reference) in &output.references {
        save(reference, format!("{}-ssaa.png", file_stem(scene)))?;
    }
    for (run, img) in output.report.runs.iter().zip(&output.images) {
        save(
            img,
            format!(
                "{}-{}-{}x.png",
                file_stem(&run.scene),
                file_stem(&run.method),
                run.samples
            ),
        )?;
    }
    Ok(())
}

/// Run the benchmark (see the [module documentation](self)).
pub fn run(config: &BenchConfig) -> Result<BenchOutput> {
    config.validate()?;
    let ctx = HeadlessContext::new(config.backend)?;
    let gl = ctx.gl();
    let version = GlVersion::query(gl);
    // The default list leaves out what this context cannot run (`sparse`
    // below OpenGL 4.3), with a warning; a list given explicitly fails on it
    // when its renderer is made.
    let trimmed;
    let config = if config.methods == default_methods() {
        let (kept, dropped): (Vec<&MethodEntry>, Vec<&MethodEntry>) = config
            .methods
            .iter()
            .partition(|e| Renderer::check_support(gl, &e.method).is_ok());
        for e in dropped {
            if let Err(why) = Renderer::check_support(gl, &e.method) {
                log::warn!(
                    "bench: `{}` left out of the default methods: {why}",
                    e.label
                );
            }
        }
        trimmed = BenchConfig {
            methods: kept.into_iter().cloned().collect(),
            ..config.clone()
        };
        &trimmed
    } else {
        config
    };
    let rounds = (config.warmup + config.motion.map_or(config.frames, |m| m.frames)) as u64;
    let ms_entries = config
        .methods
        .iter()
        .filter(|e| e.method.takes_samples())
        .count() as u64;
    let ss_entries = config.methods.len() as u64 - ms_entries;
    let jobs_per_scene = ms_entries * config.samples.len() as u64 + ss_entries;
    let per_scene = 1 + jobs_per_scene * rounds + 1;
    let pb = if config.progress {
        ProgressBar::with_draw_target(
            Some(per_scene * config.scenes.len() as u64),
            ProgressDrawTarget::stderr(),
        )
    } else {
        ProgressBar::hidden()
    };
    let style = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:30}] {pos}/{len} frames, eta {eta} · {msg}",
    )
    .map_err(|e| Error::invalid(format!("progress bar template: {e}")))?
    .progress_chars("=> ");
    pb.set_style(style);

    let mut report = Report {
        renderer: version.renderer.clone(),
        gl_version: version.version_string.clone(),
        reference: Reference {
            method: "ssaa".into(),
            spp: REFERENCE_SCALE * REFERENCE_SCALE,
        },
        runs: Vec::new(),
        backend: config.backend.name().to_string(),
        // With a camera path, the timed frames are the path's.
        frames: config.motion.map_or(config.frames, |m| m.frames),
        warmup: config.warmup,
        extra_lights: config.lights,
        motion: config.motion.map(|m| m.to_string()),
        layout: if config.layout == GBufferLayout::freespace_open() {
            "freespace-open".into()
        } else if config.layout == GBufferLayout::recommended() {
            "recommended".into()
        } else {
            "custom".into()
        },
    };
    let mut references = Vec::new();
    let mut images = Vec::new();
    let mut animations = Vec::new();
    for spec in &config.scenes {
        let measured = bench_scene(&ctx, config, spec, &pb, rounds)?;
        references.push((spec.clone(), measured.reference));
        for (run, image) in measured.runs {
            report.runs.push(run);
            images.push(image);
        }
        if let Some(frames) = measured.animation {
            animations.push((spec.clone(), frames));
        }
    }
    pb.finish_and_clear();
    Ok(BenchOutput {
        report,
        references,
        images,
        animations,
    })
}

/// What each run of a scene is measured against: the reference, and what
/// the scene gives beyond it.
struct SceneMeasures {
    reference: RgbaImage,
    /// The scene's bars as the reference shows them ([`bar_width`]).
    bars: Option<BarGauge>,
    /// The pixels [`cluster_masks`] marks as holding two or more clusters.
    cluster_mask: Option<GrayImage>,
    /// Those holding three or more.
    three_cluster_mask: Option<GrayImage>,
}

/// One scene's results.
struct SceneResult {
    reference: RgbaImage,
    runs: Vec<(Run, RgbaImage)>,
    /// With `--motion`: the animated crop strip's frames.
    animation: Option<Vec<RgbImage>>,
}

/// One (entry, sample count) to time.
struct Job<'a> {
    entry: &'a MethodEntry,
    /// Hidden jobs are timed (as a lighting baseline) but not reported.
    reported: bool,
    samples_requested: u32,
    options: RenderOptions,
    /// Index into the renderer pool.
    slot: usize,
    samples: u32,
    frames: Vec<FrameTimings>,
    image: Option<RgbaImage>,
    gbuffer_bytes: u64,
    /// The fraction of pixels the method treated as complex in the last
    /// frame ([`Renderer::complex_pixel_fraction`]).
    complex_fraction: Option<f64>,
    /// The share of pixels the second layer covers in the last frame.
    second_layer_share: Option<f64>,
    /// `sparse`: the pixels that fell back to one sample in the last frame.
    sparse_overflow_pixels: Option<u64>,
    /// With `--profile`: the retrofit's steps, median milliseconds each.
    profile: Option<Vec<ProfileStep>>,
}

/// Renderers shared by jobs of the same class, FXAA setting, sample count
/// and layout (adaptive or full).
#[derive(Default)]
struct Pool {
    renderers: Vec<(PoolKey, Renderer)>,
}

/// A pool slot's method class, FXAA, SMAA, requested samples, adaptive layout and forward MSAA.
/// For a method whose frames build on the ones before (`taa`), its entry
/// too: it gets a renderer of its own, whose history no other entry's
/// `set_options` resets between its frames.
type PoolKey = (
    &'static str,
    bool,
    bool,
    u32,
    (bool, bool, Option<String>),
    Option<String>,
);

impl Pool {
    fn slot(
        &mut self,
        ctx: &HeadlessContext,
        scene: &Scene,
        key: PoolKey,
        options: &RenderOptions,
    ) -> Result<usize> {
        if let Some(i) = self.renderers.iter().position(|(k, _)| *k == key) {
            return Ok(i);
        }
        let mut renderer =
            Renderer::new(ctx.gl(), |name| ctx.get_proc_address(name), scene, options)?;
        // The bench reads the lit image alone, as a host whose passes after
        // lighting leave the G-buffer alone would: no first-layer restore.
        if let Err(e) = renderer.set_keep_gbuffer(ctx.gl(), false) {
            renderer.destroy(ctx.gl());
            return Err(e);
        }
        self.renderers.push((key, renderer));
        Ok(self.renderers.len() - 1)
    }

    fn get(&mut self, slot: usize) -> Result<&mut Renderer> {
        self.renderers
            .get_mut(slot)
            .map(|(_, r)| r)
            .ok_or_else(|| Error::invalid("bench: a renderer slot is missing"))
    }

    fn destroy(self, gl: &glow::Context) {
        for (_, r) in self.renderers {
            r.destroy(gl);
        }
    }
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

fn render_options(config: &BenchConfig, aa: AaMode, fxaa: bool, samples: u32) -> RenderOptions {
    RenderOptions {
        width: config.width,
        height: config.height,
        samples,
        aa,
        fxaa,
        layout: config.layout.clone(),
        ..RenderOptions::default()
    }
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

/// The pixels of `scene` at the bench's size that hold two or more surface
/// clusters (silhouettes, creases), and those that hold three or more, 255
/// where marked and 0 elsewhere: the masks each run's FLIP is split by
/// (`flip_edges` over the first, `flip_interior` over the rest,
/// `flip_three_clusters` over the second), made once per scene and shared
/// by all its runs. Both come from one frame of `median:layers=2` (clusters
/// by depth window and normal) at the first requested sample count: two or
/// more where the second layer covers any of the pixel; three or more where
/// the resolve's CPU reference, over the frame's samples read back, finds
/// samples of neither kept cluster (its `joined`: the resolve's own
/// clusters, by depth window and normal test). `None` when that count gives no
/// multisampling.
fn cluster_masks(
    ctx: &HeadlessContext,
    config: &BenchConfig,
    scene: &Scene,
) -> Result<Option<(GrayImage, GrayImage)>> {
    let gl = ctx.gl();
    let two_layers = AaMode::Resolve(ResolveSettings {
        method: ResolveMethod::Median,
        layers: 2,
        ..ResolveSettings::default()
    });
    let samples = config.samples.first().copied().unwrap_or(1);
    let options = render_options(config, two_layers, false, samples);
    let mut renderer = Renderer::new(gl, |name| ctx.get_proc_address(name), scene, &options)?;
    let masks = (|| {
        renderer.render(gl)?;
        let Some(coverage) = renderer.read_second_layer_coverage(gl)? else {
            return Ok(None);
        };
        let Some(retrofit) = renderer.retrofit() else {
            return Ok(None);
        };
        let cpu = retrofit.cpu_reference(&renderer.resolve_frame())?;
        let (depth, colors, _) = retrofit.inputs()?;
        let mut readback = crate::readback::Readback::new(gl)?;
        let read = (|| {
            let colors = colors
                .iter()
                .map(|t| readback.read(gl, *t, 1))
                .collect::<deferred_msaa::Result<Vec<_>>>()?;
            Ok::<_, deferred_msaa::Error>((colors, readback.read(gl, depth, 1)?))
        })();
        readback.destroy(gl);
        let (colors, depth) = read?;
        let n = depth.samples;
        let three = GrayImage::from_fn(depth.width, depth.height, |x, y| {
            let px = crate::resolve::cpu::PixelSamples {
                depth: (0..n).map(|s| f64::from(depth.get(s, x, y)[0])).collect(),
                attachments: colors
                    .iter()
                    .map(|a| (0..n).map(|s| a.get(s, x, y).map(f64::from)).collect())
                    .collect(),
            };
            // Samples of neither kept cluster, each joined to one of them.
            let joined = cpu.resolve_second_layer_at(&px, None).joined;
            image::Luma([if joined[0] + joined[1] > 0 { 255 } else { 0 }])
        });
        // Two clusters or more: the second layer covers some of the pixel.
        let mut two = coverage;
        two.pixels_mut()
            .for_each(|p| p[0] = if p[0] > 0 { 255 } else { 0 });
        Ok(Some((two, three)))
    })();
    renderer.destroy(gl);
    masks
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

fn bench_scene(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("640x360").unwrap(), (640, 360));
        assert_eq!(parse_size("96X54").unwrap(), (96, 54));
        for bad in ["0x10", "big", "10x", "x10", "-1x5"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn downsampling_averages_in_linear_light() {
        let img = RgbaImage::from_fn(4, 4, |x, _| {
            if x % 2 == 0 {
                image::Rgba([255, 255, 255, 255])
            } else {
                image::Rgba([0, 0, 0, 255])
            }
        });
        let small = downsample_srgb(&img, 2).unwrap();
        assert_eq!(small.dimensions(), (2, 2));
        // Half white in linear light is sRGB 188, not 128.
        assert_eq!(small.get_pixel(0, 0)[0], 188);
        assert!(downsample_srgb(&img, 3).is_err());
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
    }

    #[test]
    fn extra_lights_are_deterministic_and_around_the_bounds() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let a = extra_lights(&b, 10);
        assert_eq!(a, extra_lights(&b, 10));
        assert_eq!(a.len(), 10);
        for l in &a {
            let d = (l.position - b.center()).length();
            assert!((d - 1.25 * b.radius()).abs() < 1e-3);
        }
        assert!(extra_lights(&b, 0).is_empty());
    }

    #[test]
    fn medians() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(vec![]), 0.0);
    }
}
