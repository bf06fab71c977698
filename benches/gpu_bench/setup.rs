//! The bench's command line, its scene and hosts, and the layouts and
//! options it checks and times.

use crate::common::parse_size;
use deferred_msaa::gbuffer::GBufferLayout;
use deferred_msaa::gl::check_error;
use deferred_msaa::resolve::{KeySource, ResolveSettings, ResolveSlot};
use deferred_msaa::{ColorAttachment, Error, Frame, RetrofitOptions};
use deferred_msaa_testkit::projection::{self, perspective};
use deferred_msaa_testkit::scene::RandomScene;
use deferred_msaa_testkit::{Host, Output};
use glow::HasContext;
use std::path::PathBuf;

/// The counts checked and, where offered, timed.
pub(crate) const COUNTS: [u32; 4] = [2, 4, 8, 16];
/// The count always timed, whatever the budget says.
pub(crate) const HEADLINE_SAMPLES: u32 = 4;
pub(crate) const CHECK_WIDTH: u32 = 64;
pub(crate) const CHECK_HEIGHT: u32 = 48;
pub(crate) const CHECK_TRIANGLES: usize = 40;
/// As `tests/fast/retrofit/` asks: the slow path must really run.
pub(crate) const MIN_COMPLEX_PIXELS: usize = 30;
pub(crate) const TIMING_TRIANGLES: usize = 600;

pub(crate) const FOV_Y: f32 = 0.9;
pub(crate) const NEAR: f32 = 0.5;
pub(crate) const FAR: f32 = 200.0;
pub(crate) const BACKGROUND_Z: f32 = 120.0;

pub(crate) struct Args {
    pub(crate) out: PathBuf,
    pub(crate) quick: bool,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) runs: usize,
    pub(crate) warmup: usize,
    /// Seconds this process may take before optional timed counts are skipped.
    pub(crate) budget_s: f64,
    pub(crate) seed: u64,
}

/// The command line (see the module docs).
#[derive(clap::Parser)]
#[command(
    name = "gpu_bench",
    about = "Native resolves against the CPU reference, and timed against the blits"
)]
pub(crate) struct Cli {
    /// Where gpu-bench.json and gpu-bench.md go (default target/gpu-bench).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// 640x360 and fewer runs instead of 1920x1080.
    #[arg(long)]
    pub(crate) quick: bool,
    /// Timed image size, WIDTHxHEIGHT (default by --quick).
    #[arg(long, value_parser = parse_size)]
    pub(crate) size: Option<(u32, u32)>,
    /// Timed runs per method (default 30, --quick 20).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) runs: Option<u64>,
    /// Untimed rounds first (default 5, --quick 3).
    #[arg(long)]
    pub(crate) warmup: Option<u64>,
    /// Seconds this process may take before optional timed counts are skipped.
    #[arg(long = "budget-s", default_value_t = 420.0)]
    pub(crate) budget_s: f64,
    /// The random scene's seed.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Passed by `cargo bench` to every bench target.
    #[arg(long, hide = true)]
    pub(crate) bench: bool,
}

pub(crate) fn parse_args() -> Args {
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
pub(crate) struct Model {
    pub(crate) vertices: Vec<f32>,
    pub(crate) projection: [f64; 16],
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl Model {
    /// The random scene of `count` triangles at `width` x `height`; with
    /// `open_corner` the background leaves the top-right corner empty, so
    /// that the check meets cleared samples too.
    pub(crate) fn new(
        width: u32,
        height: u32,
        count: usize,
        seed: u64,
        open_corner: bool,
    ) -> Model {
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

    pub(crate) fn frame(&self) -> Frame {
        projection::frame(&self.projection, false)
    }
}

/// A host engine of `layout` (the test kit's toy host, its G-buffer in the
/// layout's formats) with `model`'s triangles.
pub(crate) fn host_for(
    gl: &glow::Context,
    layout: &GBufferLayout,
    model: &Model,
) -> Result<Host, Error> {
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
pub(crate) fn draw_into(
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
pub(crate) fn layouts() -> [(&'static str, &'static str, GBufferLayout); 2] {
    [
        (
            "freespace-open",
            "FreeSpace Open",
            GBufferLayout::freespace_open(),
        ),
        ("recommended", "recommended", GBufferLayout::recommended()),
    ]
}

pub(crate) fn describe_layout(layout: &GBufferLayout) -> Vec<String> {
    let mut v: Vec<String> = layout
        .colors
        .iter()
        .map(|a| format!("{} {} {}", a.name, a.format.name(), a.rule))
        .collect();
    v.push(format!("depth {}", layout.depth.name()));
    v
}

/// The retrofit a host of `layout` asks for: the layout's rules and key.
pub(crate) fn options_for(
    layout: &GBufferLayout,
    samples: u32,
    fast_path: bool,
) -> RetrofitOptions {
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
pub(crate) fn framebuffer_samples(gl: &glow::Context, fbo: glow::Framebuffer) -> u32 {
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        let n = gl.get_parameter_i32(glow::SAMPLES);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        n.max(0) as u32
    }
}
