//! The measurement behind `scripts/gpu-bench`: native sample counts checked
//! against the CPU reference, then the resolve timed against the hardware
//! resolve, for FreeSpace Open's G-buffer and the crate's recommended one.
//!
//! 1. Check. For each of 2, 4, 8 and 16 samples and both layouts, a small
//!    scene (random triangles over a background triangle that leaves one
//!    corner empty) is drawn into the retrofit's multisampled twins; the real
//!    count is read back (`GL_SAMPLES`), every sample of every attachment and
//!    of depth is read back, the GL resolve runs through `MsaaRetrofit`
//!    (fast path on and off), and every resolved value is compared with
//!    `resolve::cpu::CpuResolve` on the same samples, within the tolerances
//!    of `tests/fast/retrofit/` (FP16 storage `1e-5 + 1.2e-3·|x|`, FP32
//!    `1e-4·(1 + |x|)`, depth `1e-6`; 8-bit attachments one step, 1/255).
//!    A count the driver refuses or rounds to another is "not offered".
//! 2. Time. At 1920x1080 (`--quick`: 640x360), for each offered count (4x
//!    first, the others while `--budget-s` allows) and both layouts: the
//!    resolve with the fast path on and off, and the hardware resolve (one
//!    `glBlitFramebuffer` per colour attachment plus one for depth),
//!    interleaved round-robin, each run timed by `GL_TIME_ELAPSED` (where
//!    `GpuTimer` trusts it) and by `glFinish`-bracketed wall time.
//!
//! ```text
//! cargo bench --bench gpu_bench -- [--out DIR] [--quick] [--size WxH] [--runs K]
//!                                  [--warmup N] [--budget-s S] [--seed N]
//! ```
//! Writes `DIR/gpu-bench.json` and `DIR/gpu-bench.md` (default DIR:
//! `target/gpu-bench`). Exits 1 when no context can be made, when a check
//! fails or when a timed case errs (the reports are still written then).

mod common;

use common::{parse_size, quantile};
use deferred_msaa::gbuffer::GBufferLayout;
use deferred_msaa::gl::{Capabilities, Format, GpuTimer, TextureRef, TimerKind, check_error};
use deferred_msaa::readback::{Readback, SampleImage};
use deferred_msaa::resolve::cpu::{CpuKeySource, CpuResolve, PixelSamples};
use deferred_msaa::resolve::{KeySource, ResolveSettings, ResolveSlot};
use deferred_msaa::{ColorAttachment, Error, Frame, MsaaRetrofit, RetrofitOptions};
use deferred_msaa_headless::{Backend, HeadlessContext};
use deferred_msaa_testkit::projection::{self, perspective};
use deferred_msaa_testkit::scene::RandomScene;
use deferred_msaa_testkit::{Host, Output};
use glow::HasContext;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// The counts checked and, where offered, timed.
const COUNTS: [u32; 4] = [2, 4, 8, 16];
/// The count always timed, whatever the budget says.
const HEADLINE_SAMPLES: u32 = 4;
const CHECK_WIDTH: u32 = 64;
const CHECK_HEIGHT: u32 = 48;
const CHECK_TRIANGLES: usize = 40;
/// As `tests/fast/retrofit/` asks: the slow path must really run.
const MIN_COMPLEX_PIXELS: usize = 30;
const TIMING_TRIANGLES: usize = 600;

const FOV_Y: f32 = 0.9;
const NEAR: f32 = 0.5;
const FAR: f32 = 200.0;
const BACKGROUND_Z: f32 = 120.0;

struct Args {
    out: PathBuf,
    quick: bool,
    width: u32,
    height: u32,
    runs: usize,
    warmup: usize,
    /// Seconds this process may take before optional timed counts are skipped.
    budget_s: f64,
    seed: u64,
}

/// The command line (see the module docs).
#[derive(clap::Parser)]
#[command(
    name = "gpu_bench",
    about = "Native resolves against the CPU reference, and timed against the blits"
)]
struct Cli {
    /// Where gpu-bench.json and gpu-bench.md go (default target/gpu-bench).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// 640x360 and fewer runs instead of 1920x1080.
    #[arg(long)]
    quick: bool,
    /// Timed image size, WIDTHxHEIGHT (default by --quick).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Timed runs per method (default 30, --quick 20).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    runs: Option<u64>,
    /// Untimed rounds first (default 5, --quick 3).
    #[arg(long)]
    warmup: Option<u64>,
    /// Seconds this process may take before optional timed counts are skipped.
    #[arg(long = "budget-s", default_value_t = 420.0)]
    budget_s: f64,
    /// The random scene's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Passed by `cargo bench` to every bench target.
    #[arg(long, hide = true)]
    bench: bool,
}

fn parse_args() -> Args {
    let cli = <Cli as clap::Parser>::parse();
    let quick = cli.quick;
    let (width, height) = cli
        .size
        .unwrap_or(if quick { (640, 360) } else { (1920, 1080) });
    Args {
        out: cli
            .out
            .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/gpu-bench")),
        quick,
        width,
        height,
        runs: cli.runs.map_or(if quick { 20 } else { 30 }, |r| r as usize),
        warmup: cli.warmup.map_or(if quick { 3 } else { 5 }, |w| w as usize),
        budget_s: cli.budget_s.max(0.0),
        seed: cli.seed,
    }
}

/// A scene's vertices and the lens it is seen through.
struct Model {
    vertices: Vec<f32>,
    projection: [f64; 16],
    width: u32,
    height: u32,
}

impl Model {
    /// The random scene of `count` triangles at `width` x `height`; with
    /// `open_corner` the background leaves the top-right corner empty, so
    /// that the check meets cleared samples too.
    fn new(width: u32, height: u32, count: usize, seed: u64, open_corner: bool) -> Model {
        let aspect = width as f32 / height as f32;
        let scene = RandomScene {
            aspect,
            fov_y: FOV_Y,
            background_z: BACKGROUND_Z,
            count,
            seed,
            open_corner,
        };
        Model {
            vertices: scene.vertices(),
            projection: perspective(FOV_Y.into(), aspect.into(), NEAR.into(), Some(FAR.into())),
            width,
            height,
        }
    }

    fn frame(&self) -> Frame {
        projection::frame(&self.projection, false)
    }
}

/// A host engine of `layout` (the test kit's toy host, its G-buffer in the
/// layout's formats) with `model`'s triangles.
fn host_for(gl: &glow::Context, layout: &GBufferLayout, model: &Model) -> Result<Host, Error> {
    let mut outputs = Vec::with_capacity(layout.colors.len());
    for a in &layout.colors {
        let Some(output) = Output::from_name(&a.name) else {
            return Err(Error::invalid(format!(
                "the host shader writes no `{}` attachment",
                a.name
            )));
        };
        outputs.push((output, a.format));
    }
    let mut host = Host::with_outputs(gl, model.width, model.height, &outputs, layout.depth)?;
    if let Err(e) = host.set_triangles(gl, &model.vertices) {
        host.destroy(gl);
        return Err(e);
    }
    Ok(host)
}

/// The host's geometry pass into `fbo` (the retrofit's twin).
fn draw_into(
    gl: &glow::Context,
    host: &Host,
    fbo: glow::Framebuffer,
    model: &Model,
) -> Result<(), Error> {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
    }
    host.draw(gl, &model.projection, false);
    unsafe {
        gl.disable(glow::DEPTH_TEST);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
    check_error(gl, "drawing the scene")
}

/// The two layouts measured: a key for reports, a label, the layout.
fn layouts() -> [(&'static str, &'static str, GBufferLayout); 2] {
    [
        (
            "freespace-open",
            "FreeSpace Open",
            GBufferLayout::freespace_open(),
        ),
        ("recommended", "recommended", GBufferLayout::recommended()),
    ]
}

fn describe_layout(layout: &GBufferLayout) -> Vec<String> {
    let mut v: Vec<String> = layout
        .colors
        .iter()
        .map(|a| format!("{} {} {}", a.name, a.format.name(), a.rule))
        .collect();
    v.push(format!("depth {}", layout.depth.name()));
    v
}

/// The retrofit a host of `layout` asks for: the layout's rules and key.
fn options_for(layout: &GBufferLayout, samples: u32, fast_path: bool) -> RetrofitOptions {
    RetrofitOptions {
        samples,
        rules: layout
            .colors
            .iter()
            .enumerate()
            .map(|(k, a)| (ColorAttachment(k as u32), a.rule))
            .collect(),
        position_attachment: match layout.key {
            KeySource::Position(ResolveSlot(k)) => Some(ColorAttachment(k as u32)),
            _ => None,
        },
        resolve: ResolveSettings {
            fast_path,
            ..ResolveSettings::default()
        },
        ..RetrofitOptions::default()
    }
}

/// `GL_SAMPLES` of a framebuffer, as the driver reports it.
fn framebuffer_samples(gl: &glow::Context, fbo: glow::Framebuffer) -> u32 {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        let n = gl.get_parameter_i32(glow::SAMPLES);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        n.max(0) as u32
    }
}

// ---------------------------------------------------------------- check

/// The comparison of one resolve with the CPU reference.
struct Comparison {
    fast_path: bool,
    pixels: usize,
    complex: usize,
    ambiguous: usize,
    values: usize,
    mismatches: usize,
    max_abs_error: f64,
    max_over_tolerance: f64,
    worst: String,
    first_mismatches: Vec<String>,
    /// Why the comparison fails, when it does.
    failure: Option<String>,
}

enum Offer {
    /// The driver refused the count or gave another one.
    NotOffered(String),
    Checked {
        samples: u32,
        gl_samples: u32,
        comparisons: Vec<Comparison>,
    },
    Failed(String),
}

struct CheckEntry {
    requested: u32,
    layout: &'static str,
    offer: Offer,
}

impl CheckEntry {
    fn passed(&self) -> bool {
        match &self.offer {
            Offer::NotOffered(_) => true,
            Offer::Failed(_) => false,
            Offer::Checked { comparisons, .. } => comparisons.iter().all(|c| c.failure.is_none()),
        }
    }
}

/// The storage tolerance of a resolved value of `format` (see the module docs).
fn tolerance(format: Format, cpu: f64) -> f64 {
    match format {
        Format::R16f | Format::Rg16f | Format::Rgb16f | Format::Rgba16f | Format::R11fG11fB10f => {
            1e-5 + 1.2e-3 * cpu.abs()
        }
        Format::R32f | Format::Rg32f | Format::Rgb32f | Format::Rgba32f => 1e-4 * (1.0 + cpu.abs()),
        _ => 1.0 / 255.0,
    }
}

/// The error of `gpu` against `cpu`, and whether it is within `tol`
/// (non-finite references must be matched exactly).
fn judge(gpu: f32, cpu: f64, tol: f64) -> (bool, f64) {
    let g = gpu as f64;
    if cpu.is_nan() {
        return if g.is_nan() {
            (true, 0.0)
        } else {
            (false, f64::INFINITY)
        };
    }
    if cpu.is_infinite() {
        return if g == cpu {
            (true, 0.0)
        } else {
            (false, f64::INFINITY)
        };
    }
    let err = (g - cpu).abs();
    if err.is_nan() {
        return (false, f64::INFINITY);
    }
    (err <= tol, err)
}

#[allow(clippy::too_many_arguments)]
fn compare(
    cpu: &CpuResolve,
    names: &[String],
    formats: &[Format],
    samples: &[SampleImage],
    depth: &SampleImage,
    resolved: &[SampleImage],
    resolved_depth: &SampleImage,
) -> Comparison {
    let mut c = Comparison {
        fast_path: cpu.settings.fast_path,
        pixels: 0,
        complex: 0,
        ambiguous: 0,
        values: 0,
        mismatches: 0,
        max_abs_error: 0.0,
        max_over_tolerance: 0.0,
        worst: String::new(),
        first_mismatches: Vec::new(),
        failure: None,
    };
    let n = depth.samples;
    // `what` names the value; it is formatted only for the reports.
    let note = |c: &mut Comparison, what: &dyn Fn() -> String, got: f32, want: f64, tol: f64| {
        let (ok, err) = judge(got, want, tol);
        c.values += 1;
        c.max_abs_error = c.max_abs_error.max(err);
        let ratio = err / tol;
        if ratio > c.max_over_tolerance || c.worst.is_empty() {
            c.max_over_tolerance = c.max_over_tolerance.max(ratio);
            c.worst = format!("{}: gpu {got} cpu {want}", what());
        }
        if !ok {
            c.mismatches += 1;
            if c.first_mismatches.len() < 6 {
                c.first_mismatches.push(format!(
                    "{}: gpu {got} cpu {want} (tolerance {tol:.3e})",
                    what()
                ));
            }
        }
    };
    for y in 0..depth.height {
        for x in 0..depth.width {
            let px = PixelSamples {
                depth: (0..n).map(|s| depth.get(s, x, y)[0] as f64).collect(),
                attachments: samples
                    .iter()
                    .map(|a| (0..n).map(|s| a.get(s, x, y).map(f64::from)).collect())
                    .collect(),
            };
            let want = cpu.resolve_pixel(&px);
            c.pixels += 1;
            c.complex += usize::from(want.complex);
            // Within rounding of a window edge or a depth tie: either answer is right.
            if want.ambiguous {
                c.ambiguous += 1;
                continue;
            }
            for (k, image) in resolved.iter().enumerate() {
                let got = image.get(0, x, y);
                for (ch, (&g, &w)) in got.iter().zip(&want.attachments[k]).enumerate() {
                    let what = || format!("({x},{y}) {}[{ch}]", names[k]);
                    note(&mut c, &what, g, w, tolerance(formats[k], w));
                }
            }
            let d = resolved_depth.get(0, x, y)[0];
            note(&mut c, &|| format!("({x},{y}) depth"), d, want.depth, 1e-6);
        }
    }
    c.failure = if c.mismatches > 0 {
        Some(format!(
            "{} of {} values outside tolerance",
            c.mismatches, c.values
        ))
    } else if c.ambiguous * 10 >= c.pixels {
        Some(format!(
            "{} of {} pixels ambiguous (at most 10 % may be)",
            c.ambiguous, c.pixels
        ))
    } else if c.complex < MIN_COMPLEX_PIXELS {
        Some(format!(
            "only {} complex pixels: the scene did not exercise the slow path",
            c.complex
        ))
    } else {
        None
    };
    c
}

/// Check one requested count for one layout; `checked` holds the real counts
/// this layout has already been checked at.
fn check_count(
    gl: &glow::Context,
    readback: &mut Readback,
    layout: &GBufferLayout,
    requested: u32,
    model: &Model,
    checked: &mut Vec<u32>,
) -> Result<Offer, Error> {
    let host = host_for(gl, layout, model)?;
    let result = match MsaaRetrofit::new(gl, host.fbo.raw(), &options_for(layout, requested, true))
    {
        Ok(mut msaa) => {
            let r = check_retrofit(
                gl, readback, layout, &host, &mut msaa, model, requested, checked,
            );
            msaa.destroy(gl);
            r
        }
        Err(Error::UnsupportedSampleCount { supported, .. }) => Ok(Offer::NotOffered(format!(
            "refused; the driver offers {}",
            counts_text(&supported)
        ))),
        Err(e) => Err(e),
    };
    host.destroy(gl);
    result
}

#[allow(clippy::too_many_arguments)]
fn check_retrofit(
    gl: &glow::Context,
    readback: &mut Readback,
    layout: &GBufferLayout,
    host: &Host,
    msaa: &mut MsaaRetrofit,
    model: &Model,
    requested: u32,
    checked: &mut Vec<u32>,
) -> Result<Offer, Error> {
    let samples = msaa.samples();
    let gl_samples = framebuffer_samples(gl, msaa.framebuffer());
    if gl_samples != samples {
        return Ok(Offer::Failed(format!(
            "the twins' textures have {samples} samples but the framebuffer's GL_SAMPLES is {gl_samples}"
        )));
    }
    // A rounded count is checked where it is asked for itself.
    if samples != requested && (COUNTS.contains(&samples) || checked.contains(&samples)) {
        return Ok(Offer::NotOffered(format!("the driver gave {samples}x")));
    }
    checked.push(samples);
    draw_into(gl, host, msaa.framebuffer(), model)?;
    let (depth_ref, color_refs, _) = msaa.inputs()?;
    let inputs = color_refs
        .iter()
        .map(|t| readback.read(gl, *t, 1))
        .collect::<Result<Vec<_>, Error>>()?;
    let depth = readback.read(gl, depth_ref, 1)?;
    let frame = model.frame();
    let (projection, fov_y) = frame.depth_terms()?;
    let key_source = match msaa.key() {
        KeySource::Position(ResolveSlot(k)) => CpuKeySource::Position(k),
        KeySource::Depth => CpuKeySource::Depth(projection),
        KeySource::WorldPosition(_) => {
            return Err(Error::invalid("a world-space key is not measured here"));
        }
    };
    let formats: Vec<Format> = msaa.host().colors.iter().map(|a| a.format).collect();
    let names: Vec<String> = layout.colors.iter().map(|a| a.name.clone()).collect();
    let mut comparisons = Vec::new();
    for fast_path in [true, false] {
        msaa.set_options(gl, &options_for(layout, requested, fast_path))?;
        msaa.resolve(gl, &frame)?;
        let resolved = host
            .colors
            .iter()
            .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1))
            .collect::<Result<Vec<_>, Error>>()?;
        let resolved_depth = readback.read(gl, TextureRef::from(&host.depth), 1)?;
        let cpu = CpuResolve {
            settings: msaa.options().resolve,
            rules: msaa.rules().to_vec(),
            key_source,
            clear_depth: projection.clear_depth,
            footprint: (fov_y / model.height as f64).tan(),
            normal: None,
        };
        comparisons.push(compare(
            &cpu,
            &names,
            &formats,
            &inputs,
            &depth,
            &resolved,
            &resolved_depth,
        ));
    }
    Ok(Offer::Checked {
        samples,
        gl_samples,
        comparisons,
    })
}

fn counts_text(counts: &[u32]) -> String {
    if counts.is_empty() {
        return "none".into();
    }
    counts
        .iter()
        .map(|n| format!("{n}x"))
        .collect::<Vec<_>>()
        .join(", ")
}

// ---------------------------------------------------------------- timing

#[derive(Clone, Copy, PartialEq)]
enum Method {
    ResolveFast,
    ResolveNoFast,
    Blit,
}

impl Method {
    const ALL: [Method; 3] = [Method::ResolveFast, Method::ResolveNoFast, Method::Blit];
    fn key(self) -> &'static str {
        match self {
            Method::ResolveFast => "resolve_fast",
            Method::ResolveNoFast => "resolve_nofast",
            Method::Blit => "blit",
        }
    }
    fn label(self, colors: usize) -> String {
        match self {
            Method::ResolveFast => "resolve (median, smooth), fast path on".into(),
            Method::ResolveNoFast => "resolve (median, smooth), fast path off".into(),
            Method::Blit => format!("{colors}x glBlitFramebuffer + depth"),
        }
    }
}

/// One layout's retrofit at one count, ready to time.
struct Timed {
    key: &'static str,
    label: &'static str,
    layout: GBufferLayout,
    host: Host,
    msaa: MsaaRetrofit,
}

/// The hardware resolve: one blit per colour attachment, then depth (a
/// multisampled depth blit takes one sample; GL_NEAREST as required).
fn blit_resolve(gl: &glow::Context, t: &Timed, width: u32, height: u32) {
    let (w, h) = (width as i32, height as i32);
    let colors = t.layout.colors.len() as u32;
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(t.msaa.framebuffer()));
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(t.host.fbo.raw()));
        for k in 0..colors {
            gl.read_buffer(glow::COLOR_ATTACHMENT0 + k);
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0 + k]);
            gl.blit_framebuffer(
                0,
                0,
                w,
                h,
                0,
                0,
                w,
                h,
                glow::COLOR_BUFFER_BIT,
                glow::NEAREST,
            );
        }
        gl.blit_framebuffer(
            0,
            0,
            w,
            h,
            0,
            0,
            w,
            h,
            glow::DEPTH_BUFFER_BIT,
            glow::NEAREST,
        );
        // Both framebuffers' mappings back as their owners made them.
        let all: Vec<u32> = (0..colors).map(|k| glow::COLOR_ATTACHMENT0 + k).collect();
        gl.draw_buffers(&all);
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
}

#[derive(Clone, Copy)]
struct Stats {
    median: f64,
    q1: f64,
    q3: f64,
    min: f64,
    max: f64,
}

fn stats(times: &[f64]) -> Option<Stats> {
    if times.is_empty() {
        return None;
    }
    let mut s = times.to_vec();
    s.sort_by(f64::total_cmp);
    Some(Stats {
        median: quantile(&s, 0.5),
        q1: quantile(&s, 0.25),
        q3: quantile(&s, 0.75),
        min: s[0],
        max: s[s.len() - 1],
    })
}

/// The timings of one (count, layout) case.
struct CaseResult {
    samples: u32,
    layout: &'static str,
    label: &'static str,
    gbuffer: Vec<String>,
    colors: usize,
    /// Per method: wall times, query times.
    wall: Vec<Vec<f64>>,
    query: Vec<Vec<f64>>,
}

impl CaseResult {
    fn stats(&self, kind: TimerKind) -> Vec<Option<Stats>> {
        let all = match kind {
            TimerKind::GlTimeElapsed => &self.query,
            TimerKind::FinishWallClock => &self.wall,
        };
        all.iter().map(|t| stats(t)).collect()
    }
    /// Resolve/blit medians, fast path on and off.
    fn ratios(&self, kind: TimerKind) -> Option<(f64, f64)> {
        let st = self.stats(kind);
        let (fast, nofast, blit) = (st[0]?, st[1]?, st[2]?);
        Some((fast.median / blit.median, nofast.median / blit.median))
    }
}

/// Time both layouts at `samples`, interleaved round-robin over every
/// (layout, method) pair; each round starts one pair later.
#[allow(clippy::too_many_arguments)]
fn time_count(
    gl: &glow::Context,
    samples: u32,
    layouts_here: &[(&'static str, &'static str, GBufferLayout)],
    model: &Model,
    args: &Args,
    wall: &mut GpuTimer,
    query: &mut Option<GpuTimer>,
    started: Instant,
) -> Result<Vec<CaseResult>, Error> {
    let mut timed: Vec<Timed> = Vec::new();
    let built = (|| -> Result<(), Error> {
        for (key, label, layout) in layouts_here {
            let host = host_for(gl, layout, model)?;
            let msaa =
                match MsaaRetrofit::new(gl, host.fbo.raw(), &options_for(layout, samples, false)) {
                    Ok(m) => m,
                    Err(e) => {
                        host.destroy(gl);
                        return Err(e);
                    }
                };
            let t = Timed {
                key,
                label,
                layout: layout.clone(),
                host,
                msaa,
            };
            // Both permutations compiled now, so switching later only picks one.
            let ready = draw_into(gl, &t.host, t.msaa.framebuffer(), model).and_then(|()| {
                let real = t.msaa.samples();
                if real == samples {
                    Ok(())
                } else {
                    Err(Error::invalid(format!("asked for {samples}x, got {real}x")))
                }
            });
            timed.push(t);
            ready?;
            let last = timed.len() - 1;
            let fast = options_for(&timed[last].layout, samples, true);
            timed[last].msaa.set_options(gl, &fast)?;
        }
        Ok(())
    })();
    let result = built.and_then(|()| {
        let frame = model.frame();
        let items: Vec<(usize, Method)> = (0..timed.len())
            .flat_map(|l| Method::ALL.iter().map(move |&m| (l, m)))
            .collect();
        let mut once =
            |timed: &mut [Timed], (l, m): (usize, Method)| -> Result<(f64, Option<f64>), Error> {
                let t = &mut timed[l];
                let want_fast = m == Method::ResolveFast;
                if m != Method::Blit && t.msaa.options().resolve.fast_path != want_fast {
                    let o = options_for(&t.layout, samples, want_fast);
                    t.msaa.set_options(gl, &o)?;
                }
                wall.begin(gl);
                if let Some(q) = query.as_mut() {
                    q.begin(gl);
                }
                let ran = match m {
                    Method::ResolveFast | Method::ResolveNoFast => t.msaa.resolve(gl, &frame),
                    Method::Blit => {
                        blit_resolve(gl, t, model.width, model.height);
                        Ok(())
                    }
                };
                // The query is ended even on an error, so the next count can begin one.
                let q_ms = query.as_mut().map(|q| q.end(gl));
                let w_ms = wall.end(gl);
                ran?;
                check_error(gl, &format!("{} {} at {samples}x", t.key, m.key()))?;
                Ok((w_ms, q_ms))
            };
        for _ in 0..args.warmup {
            for &item in &items {
                once(&mut timed, item)?;
            }
        }
        let mut wall_ms = vec![Vec::with_capacity(args.runs); items.len()];
        let mut query_ms = vec![Vec::with_capacity(args.runs); items.len()];
        let every = (args.runs / 4).max(1);
        for round in 0..args.runs {
            for i in 0..items.len() {
                let k = (round + i) % items.len();
                let (w, q) = once(&mut timed, items[k])?;
                wall_ms[k].push(w);
                if let Some(q) = q {
                    query_ms[k].push(q);
                }
            }
            if (round + 1) % every == 0 || round + 1 == args.runs {
                eprintln!(
                    "[time] {samples}x: round {}/{} ({:.0} s)",
                    round + 1,
                    args.runs,
                    started.elapsed().as_secs_f64()
                );
            }
        }
        Ok(timed
            .iter()
            .enumerate()
            .map(|(l, t)| {
                let of = |all: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
                    Method::ALL
                        .iter()
                        .map(|&m| {
                            items
                                .iter()
                                .position(|&it| it == (l, m))
                                .map(|k| all[k].clone())
                                .unwrap_or_default()
                        })
                        .collect()
                };
                CaseResult {
                    samples,
                    layout: t.key,
                    label: t.label,
                    gbuffer: describe_layout(&t.layout),
                    colors: t.layout.colors.len(),
                    wall: of(&wall_ms),
                    query: of(&query_ms),
                }
            })
            .collect())
    });
    for t in timed {
        t.msaa.destroy(gl);
        t.host.destroy(gl);
    }
    result
}

// ---------------------------------------------------------------- report

fn stats_json(s: Option<Stats>, runs: &[f64]) -> Value {
    match s {
        Some(s) => json!({
            "median_ms": s.median,
            "q1_ms": s.q1,
            "q3_ms": s.q3,
            "min_ms": s.min,
            "max_ms": s.max,
            "runs_ms": runs,
        }),
        None => Value::Null,
    }
}

fn ms(s: Option<Stats>) -> String {
    s.map_or("–".into(), |s| format!("{:.3}", s.median))
}

fn md_escape(s: &str) -> String {
    s.replace('|', "\\|")
}

struct TimingOutcome {
    cases: Vec<CaseResult>,
    /// Counts not timed, and why.
    skipped: Vec<(u32, String)>,
    /// Counts whose timing failed, and the error.
    errors: Vec<(u32, String)>,
}

fn timer_name(k: TimerKind) -> &'static str {
    match k {
        TimerKind::GlTimeElapsed => "GL_TIME_ELAPSED query",
        TimerKind::FinishWallClock => "wall time between glFinish calls",
    }
}

#[allow(clippy::too_many_arguments)]
fn write_reports(
    args: &Args,
    ctx: &HeadlessContext,
    caps: &Capabilities,
    driver_counts: &[(&'static str, Vec<u32>)],
    checks: &[CheckEntry],
    timing: &TimingOutcome,
    headline: TimerKind,
    headline_reason: &str,
    has_query: bool,
    elapsed_s: f64,
    passed: bool,
    warnings: &[String],
) -> Result<(PathBuf, PathBuf), String> {
    let version = ctx.version();
    let other = match (headline, has_query) {
        (TimerKind::GlTimeElapsed, _) => Some(TimerKind::FinishWallClock),
        (TimerKind::FinishWallClock, true) => Some(TimerKind::GlTimeElapsed),
        (TimerKind::FinishWallClock, false) => None,
    };

    // JSON.
    let check_json: Vec<Value> = checks
        .iter()
        .map(|c| {
            let (status, detail) = match &c.offer {
                Offer::NotOffered(why) => ("not-offered", json!({ "reason": why })),
                Offer::Failed(why) => ("error", json!({ "reason": why })),
                Offer::Checked {
                    samples,
                    gl_samples,
                    comparisons,
                } => (
                    if c.passed() { "pass" } else { "fail" },
                    json!({
                        "samples": samples,
                        "gl_samples": gl_samples,
                        "comparisons": comparisons.iter().map(|k| json!({
                            "fast_path": k.fast_path,
                            "pass": k.failure.is_none(),
                            "failure": k.failure,
                            "pixels": k.pixels,
                            "slow_path_pixels": k.complex,
                            "ambiguous_pixels_skipped": k.ambiguous,
                            "values_compared": k.values,
                            "mismatches": k.mismatches,
                            "max_abs_error": k.max_abs_error,
                            "max_error_over_tolerance": k.max_over_tolerance,
                            "worst": k.worst,
                            "first_mismatches": k.first_mismatches,
                        })).collect::<Vec<_>>(),
                    }),
                ),
            };
            json!({
                "requested": c.requested,
                "layout": c.layout,
                "status": status,
                "detail": detail,
            })
        })
        .collect();
    let case_json: Vec<Value> = timing
        .cases
        .iter()
        .map(|c| {
            let methods = |kind: TimerKind| -> Value {
                let all = match kind {
                    TimerKind::GlTimeElapsed => &c.query,
                    TimerKind::FinishWallClock => &c.wall,
                };
                let st = c.stats(kind);
                Value::Array(
                    Method::ALL
                        .iter()
                        .enumerate()
                        .map(|(i, m)| {
                            json!({
                                "method": m.key(),
                                "label": m.label(c.colors),
                                "stats": stats_json(st[i], &all[i]),
                            })
                        })
                        .collect(),
                )
            };
            let ratios = |kind: TimerKind| match c.ratios(kind) {
                Some((f, n)) => {
                    json!({ "resolve_fast_over_blit": f, "resolve_nofast_over_blit": n })
                }
                None => Value::Null,
            };
            json!({
                "samples": c.samples,
                "layout": c.layout,
                "gbuffer": c.gbuffer,
                "timer": headline.name(),
                "methods": methods(headline),
                "ratios": ratios(headline),
                "other_timer": other.map(|o| json!({
                    "timer": o.name(),
                    "methods": methods(o),
                    "ratios": ratios(o),
                })),
            })
        })
        .collect();
    let unix_time = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let report = json!({
        "tool": "gpu_bench",
        "unix_time": unix_time,
        "quick": args.quick,
        "passed": passed,
        "elapsed_s": elapsed_s,
        "warnings": warnings,
        "context": {
            "backend": ctx.backend().name(),
            "renderer": version.renderer,
            "vendor": version.vendor,
            "gl_version": version.version_string,
            "glsl_version": version.glsl_string,
            "max_samples": caps.max_samples,
            "max_color_texture_samples": caps.max_color_texture_samples,
            "max_depth_texture_samples": caps.max_depth_texture_samples,
            "timer_query": caps.timer_query,
            "sample_counts": driver_counts.iter().map(|(k, v)| json!({ "layout": k, "counts": v })).collect::<Vec<_>>(),
        },
        "layouts": layouts().iter().map(|(k, _, l)| json!({ "layout": k, "gbuffer": describe_layout(l) })).collect::<Vec<_>>(),
        "check": {
            "width": CHECK_WIDTH,
            "height": CHECK_HEIGHT,
            "triangles": CHECK_TRIANGLES,
            "seed": args.seed,
            "settings": "median, smooth window, c 5, c_in 2.5; fast path on and off",
            "tolerances": "FP16 storage 1e-5 + 1.2e-3*|x|; FP32 1e-4*(1 + |x|); 8-bit one step (1/255); depth 1e-6",
            "counts": check_json,
        },
        "timing": {
            "width": args.width,
            "height": args.height,
            "triangles": TIMING_TRIANGLES,
            "runs": args.runs,
            "warmup": args.warmup,
            "interleaving": "round-robin over every (layout, method) pair of a count; each round starts one pair later",
            "timer": headline.name(),
            "timer_reason": headline_reason,
            "cases": case_json,
            "skipped": timing.skipped.iter().map(|(n, why)| json!({ "samples": n, "reason": why })).collect::<Vec<_>>(),
            "errors": timing.errors.iter().map(|(n, e)| json!({ "samples": n, "error": e })).collect::<Vec<_>>(),
        },
    });

    // Markdown.
    let mut md = String::new();
    let _ = writeln!(md, "# gpu-bench\n");
    let _ = writeln!(
        md,
        "- renderer: {} ({})\n- GL {} | GLSL {} | {} context\n- result: {}, {:.0} s{}\n",
        md_escape(&version.renderer),
        md_escape(&version.vendor),
        md_escape(&version.version_string),
        md_escape(&version.glsl_string),
        ctx.backend().name(),
        if passed { "pass" } else { "FAIL" },
        elapsed_s,
        if args.quick { ", --quick" } else { "" }
    );
    for w in warnings {
        let _ = writeln!(md, "**Warning:** {}\n", md_escape(w));
    }
    let _ = writeln!(
        md,
        "## Resolve against the CPU reference ({CHECK_WIDTH}x{CHECK_HEIGHT}, real rasterised samples)\n"
    );
    let _ = writeln!(
        md,
        "Median, smooth window. Tolerances: FP16 storage 1e-5 + 1.2e-3·\\|x\\|, FP32 1e-4·(1 + \\|x\\|), 8-bit 1/255, depth 1e-6.\n"
    );
    let _ = writeln!(
        md,
        "| requested | layout | real samples (GL_SAMPLES) | fast path | result | max abs error | worst error / tolerance | slow-path px (CPU) | ambiguous px (skipped) |"
    );
    let _ = writeln!(md, "|---:|---|---:|---|---|---:|---:|---:|---:|");
    for c in checks {
        match &c.offer {
            Offer::NotOffered(why) => {
                let _ = writeln!(
                    md,
                    "| {}x | {} | – | – | not offered ({}) | – | – | – | – |",
                    c.requested,
                    c.layout,
                    md_escape(why)
                );
            }
            Offer::Failed(why) => {
                let _ = writeln!(
                    md,
                    "| {}x | {} | – | – | ERROR: {} | – | – | – | – |",
                    c.requested,
                    c.layout,
                    md_escape(why)
                );
            }
            Offer::Checked {
                gl_samples,
                comparisons,
                ..
            } => {
                for k in comparisons {
                    let _ = writeln!(
                        md,
                        "| {}x | {} | {} | {} | {} | {:.3e} | {:.3} | {} | {} |",
                        c.requested,
                        c.layout,
                        gl_samples,
                        if k.fast_path { "on" } else { "off" },
                        match &k.failure {
                            None => "pass".to_string(),
                            Some(f) => format!("FAIL: {}", md_escape(f)),
                        },
                        k.max_abs_error,
                        k.max_over_tolerance,
                        k.complex,
                        k.ambiguous
                    );
                }
            }
        }
    }
    let _ = writeln!(
        md,
        "\n## Resolve against the hardware blit ({}x{}, {TIMING_TRIANGLES} random triangles + background)\n",
        args.width, args.height
    );
    let _ = writeln!(
        md,
        "Medians of {} runs after {} warm-up rounds, interleaved round-robin. Headline timer: {} ({}).\n",
        args.runs,
        args.warmup,
        timer_name(headline),
        md_escape(headline_reason)
    );
    let table = |md: &mut String, kind: TimerKind| {
        let _ = writeln!(
            md,
            "| samples | layout | resolve, fast path on, ms | resolve, fast path off, ms | blit (colour attachments + depth), ms | fast on / blit | fast off / blit |"
        );
        let _ = writeln!(md, "|---:|---|---:|---:|---:|---:|---:|");
        for c in &timing.cases {
            let st = c.stats(kind);
            let (f, n) = c.ratios(kind).map_or(("–".into(), "–".into()), |(f, n)| {
                (format!("{f:.3}"), format!("{n:.3}"))
            });
            let _ = writeln!(
                md,
                "| {}x | {} | {} | {} | {} ({}x + depth) | {f} | {n} |",
                c.samples,
                c.label,
                ms(st[0]),
                ms(st[1]),
                ms(st[2]),
                c.colors
            );
        }
    };
    table(&mut md, headline);
    if let Some(o) = other {
        let _ = writeln!(md, "\nThe same runs by {}:\n", timer_name(o));
        table(&mut md, o);
    }
    if !timing.skipped.is_empty() || !timing.errors.is_empty() {
        let _ = writeln!(md);
        for (n, why) in &timing.skipped {
            let _ = writeln!(md, "- {n}x not timed: {}", md_escape(why));
        }
        for (n, e) in &timing.errors {
            let _ = writeln!(md, "- {n}x timing failed: {}", md_escape(e));
        }
    }
    let _ = writeln!(md, "\nLayouts:\n");
    for (_, label, l) in layouts() {
        let _ = writeln!(md, "- {label}: {}", describe_layout(&l).join(", "));
    }

    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("creating {}: {e}", args.out.display()))?;
    let json_path = args.out.join("gpu-bench.json");
    let md_path = args.out.join("gpu-bench.md");
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    std::fs::write(&json_path, text + "\n")
        .map_err(|e| format!("writing {}: {e}", json_path.display()))?;
    std::fs::write(&md_path, md).map_err(|e| format!("writing {}: {e}", md_path.display()))?;
    Ok((json_path, md_path))
}

// ---------------------------------------------------------------- main

fn run(args: &Args) -> Result<bool, String> {
    let started = Instant::now();
    Backend::Egl
        .check_library()
        .map_err(|e| format!("no OpenGL context: {e}"))?;
    let ctx = HeadlessContext::new(Backend::Egl)
        .map_err(|e| format!("no OpenGL context could be made (EGL): {e}"))?;
    let gl = ctx.gl();
    let version = ctx.version();
    let caps = Capabilities::query(gl);
    let software = ["llvmpipe", "softpipe", "swrast", "lavapipe"]
        .iter()
        .any(|s| version.renderer.to_lowercase().contains(s));
    let mut warnings = Vec::new();
    // libglvnd hands EGL to Mesa's surfaceless platform when Mesa is
    // installed beside the NVIDIA driver; the numbers would be llvmpipe's.
    if software && std::path::Path::new("/dev/nvidia0").exists() {
        warnings.push(
            "software renderer although /dev/nvidia0 exists: EGL chose Mesa, not the NVIDIA driver \
             (scripts/gpu-bench restricts EGL to NVIDIA's vendor library when it finds it)"
                .to_string(),
        );
    }
    for w in &warnings {
        eprintln!("[gpu_bench] warning: {w}");
    }
    eprintln!(
        "[gpu_bench] {} | GL {} | GLSL {}",
        version.renderer, version.version_string, version.glsl_string
    );
    let driver_counts: Vec<(&'static str, Vec<u32>)> = layouts()
        .iter()
        .map(|(key, _, l)| {
            let mut counts = Capabilities::sample_counts_for(gl, l.depth);
            for a in &l.colors {
                let c = Capabilities::sample_counts_for(gl, a.format);
                counts.retain(|n| c.contains(n));
            }
            (*key, counts)
        })
        .collect();
    for (key, counts) in &driver_counts {
        eprintln!(
            "[gpu_bench] {key}: the driver offers {}",
            counts_text(counts)
        );
    }
    let e = |e: Error| e.to_string();

    // 1. The check.
    let mut readback = Readback::new(gl).map_err(e)?;
    let model = Model::new(CHECK_WIDTH, CHECK_HEIGHT, CHECK_TRIANGLES, args.seed, true);
    let all_layouts = layouts();
    let mut checked: Vec<Vec<u32>> = vec![Vec::new(); all_layouts.len()];
    let mut checks = Vec::new();
    for requested in COUNTS {
        for (l, (key, _, layout)) in all_layouts.iter().enumerate() {
            let offer = check_count(
                gl,
                &mut readback,
                layout,
                requested,
                &model,
                &mut checked[l],
            )
            .unwrap_or_else(|err| Offer::Failed(err.to_string()));
            let entry = CheckEntry {
                requested,
                layout: key,
                offer,
            };
            let line = match &entry.offer {
                Offer::NotOffered(why) => format!("not offered ({why})"),
                Offer::Failed(why) => format!("ERROR: {why}"),
                Offer::Checked {
                    samples,
                    comparisons,
                    ..
                } => comparisons
                    .iter()
                    .map(|c| {
                        format!(
                            "{}x fast path {}: {} (max abs error {:.2e}, {:.2} of tolerance, {} slow-path px)",
                            samples,
                            if c.fast_path { "on" } else { "off" },
                            c.failure.as_deref().unwrap_or("pass"),
                            c.max_abs_error,
                            c.max_over_tolerance,
                            c.complex
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
            };
            eprintln!("[check] {requested}x {key}: {line}");
            checks.push(entry);
        }
    }
    readback.destroy(gl);

    // 2. The timing: what each layout was checked at, the headline count first.
    let mut counts: Vec<u32> = checked.iter().flatten().copied().collect();
    counts.sort_unstable();
    counts.dedup();
    let first = if counts.contains(&HEADLINE_SAMPLES) {
        Some(HEADLINE_SAMPLES)
    } else {
        counts.first().copied()
    };
    if let Some(f) = first {
        counts.retain(|&n| n != f);
        counts.insert(0, f);
    }
    let mut wall = GpuTimer::new(gl, true).map_err(e)?;
    let mut query = match GpuTimer::new(gl, false).map_err(e)? {
        q if q.kind() == TimerKind::GlTimeElapsed => Some(q),
        q => {
            q.destroy(gl);
            None
        }
    };
    let (headline, headline_reason) = match (&query, software) {
        (Some(_), _) => (
            TimerKind::GlTimeElapsed,
            "the context has GL_TIME_ELAPSED queries",
        ),
        (None, true) => (
            TimerKind::FinishWallClock,
            "software renderer: its GL_TIME_ELAPSED restarts at every tile a thread rasterises, so GpuTimer does not use it",
        ),
        (None, false) => (
            TimerKind::FinishWallClock,
            "the context has no GL_TIME_ELAPSED queries",
        ),
    };
    eprintln!(
        "[time] {}x{}, counts {}, timer: {}",
        args.width,
        args.height,
        counts_text(&counts),
        timer_name(headline)
    );
    let mut timing = TimingOutcome {
        cases: Vec::new(),
        skipped: Vec::new(),
        errors: Vec::new(),
    };
    let model = Model::new(args.width, args.height, TIMING_TRIANGLES, args.seed, false);
    // Seconds per sample of the first count's timing, to predict the others.
    let mut per_sample: Option<f64> = None;
    for (i, &n) in counts.iter().enumerate() {
        let here: Vec<_> = all_layouts
            .iter()
            .zip(&checked)
            .filter(|(_, c)| c.contains(&n))
            .map(|(l, _)| l.clone())
            .collect();
        let spent = started.elapsed().as_secs_f64();
        if i > 0 {
            let estimate = per_sample.map_or(0.0, |s| s * n as f64);
            if spent + estimate > args.budget_s {
                let why = format!(
                    "time budget: {spent:.0} s spent, about {estimate:.0} s more needed, budget {:.0} s",
                    args.budget_s
                );
                eprintln!("[time] {n}x skipped ({why})");
                timing.skipped.push((n, why));
                continue;
            }
        }
        eprintln!(
            "[time] {n}x: {} ({:.0} s)",
            here.iter().map(|l| l.0).collect::<Vec<_>>().join(", "),
            spent
        );
        let t0 = Instant::now();
        match time_count(gl, n, &here, &model, args, &mut wall, &mut query, started) {
            Ok(cases) => {
                for c in &cases {
                    if let Some((f, o)) = c.ratios(headline) {
                        eprintln!(
                            "[time] {n}x {}: resolve/blit {f:.3} (fast path on), {o:.3} (off)",
                            c.layout
                        );
                    }
                }
                timing.cases.extend(cases);
            }
            Err(err) => {
                eprintln!("[time] {n}x failed: {err}");
                timing.errors.push((n, err.to_string()));
            }
        }
        if per_sample.is_none() {
            per_sample = Some(t0.elapsed().as_secs_f64() / n as f64);
        }
    }
    let has_query = query.is_some();
    wall.destroy(gl);
    if let Some(q) = query {
        q.destroy(gl);
    }

    let checks_pass = checks.iter().all(CheckEntry::passed);
    let nothing_checked = checked.iter().all(|c| c.is_empty());
    let passed = checks_pass && !nothing_checked && timing.errors.is_empty();
    let elapsed = started.elapsed().as_secs_f64();
    let (json_path, md_path) = write_reports(
        args,
        &ctx,
        &caps,
        &driver_counts,
        &checks,
        &timing,
        headline,
        headline_reason,
        has_query,
        elapsed,
        passed,
        &warnings,
    )?;

    // The summary.
    println!(
        "gpu_bench: {} | GL {} ({:.0} s)",
        version.renderer, version.version_string, elapsed
    );
    for c in &checks {
        let status = match &c.offer {
            Offer::NotOffered(why) => format!("not offered ({why})"),
            Offer::Failed(why) => format!("ERROR ({why})"),
            Offer::Checked { comparisons, .. } => {
                let worst = comparisons
                    .iter()
                    .map(|k| k.max_abs_error)
                    .fold(0.0, f64::max);
                format!(
                    "{} (max abs error {worst:.2e})",
                    if c.passed() { "pass" } else { "FAIL" }
                )
            }
        };
        println!("  check {:>2}x {:<15} {status}", c.requested, c.layout);
    }
    for c in &timing.cases {
        let st = c.stats(headline);
        match c.ratios(headline) {
            Some((f, n)) => println!(
                "  time  {:>2}x {:<15} resolve {} ms (fast path off {} ms), blit {} ms: ratio {f:.3} ({n:.3} off) [{}]",
                c.samples,
                c.layout,
                ms(st[0]),
                ms(st[1]),
                ms(st[2]),
                headline.name()
            ),
            None => println!("  time  {:>2}x {:<15} no timings", c.samples, c.layout),
        }
    }
    for (n, why) in &timing.skipped {
        println!("  time  {n:>2}x skipped: {why}");
    }
    for (n, err) in &timing.errors {
        println!("  time  {n:>2}x ERROR: {err}");
    }
    if nothing_checked {
        println!("  no sample count could be checked");
    }
    println!("wrote {} and {}", json_path.display(), md_path.display());
    Ok(passed)
}

fn main() -> ExitCode {
    let args = parse_args();
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => {
            eprintln!("gpu_bench: a check or a timed case failed (see the report)");
            ExitCode::FAILURE
        }
        Err(msg) => {
            eprintln!("gpu_bench: {msg}");
            ExitCode::FAILURE
        }
    }
}
