//! The depth-aware resolve against the hardware resolve, measured in one run.
//!
//! A host G-buffer (RGBA16F colour, RGBA16F view-space position, RGBA16F
//! normal, DEPTH32F) is retrofitted with MSAA; its multisampled twin is drawn
//! once with a scene of a few hundred small-to-medium triangles over a big
//! background triangle, and then these are timed, interleaved round-robin so
//! that machine noise hits every method alike:
//!
//! 1. `MsaaRetrofit::resolve`, median, smooth window, fast path on (with the
//!    opt-in uniformity test when one is asked for);
//! 2. the same with the exact uniformity test (the same as 1 without an
//!    opt-in test: then the pair shows the run's noise);
//! 3. the same with the fast path off (every pixel takes the slow path);
//! 4. three `glBlitFramebuffer` calls (twin → host, one per colour
//!    attachment) plus one depth blit: what a hardware resolve costs, and
//!    the same without the depth blit;
//! 5. the floors of a one-pass resolve at 0 % complex pixels: a pass that
//!    reads only what the exact uniformity test needs (every depth and
//!    position sample) and writes sample 0, and one that reads what the
//!    opt-in position test needs (every position sample, depth sample 0);
//! 6. a trivial full-screen pass writing the three attachments, for scale.
//!
//! `--summarize DIR` measures nothing and prints a markdown table of the
//! reports in DIR (`scripts/resolve-cost` runs every case and calls it).
//!
//! ```text
//! cargo bench --bench resolve_vs_blit [-- --size 640x360 --samples 4 --runs 30]
//! ```
//! Other options: `--warmup N`, `--triangles N`, `--seed N`, `--scene S`
//! (a built-in scene or glTF file seen through its camera instead of the
//! random triangles, drawn by the same host shader),
//! `--timer auto|query|wall`, `--key position|depth` (the depth key: what a
//! host without a position attachment gets), `--plane-uniformity` (the
//! fast path with the opt-in plane test), `--position-uniformity` (the opt-in
//! position test), `--json FILE` (where the report goes). Each run is timed both by a `GL_TIME_ELAPSED`
//! query (where the context has one) and by `glFinish`-bracketed wall time;
//! `auto` reports the query, except on software renderers, whose query does
//! not span the pass (llvmpipe restarts it at every tile a thread rasterises).
//! Results also go to `target/resolve_vs_blit.json`.

mod common;

use common::{parse_size, quantile};
use deferred_msaa::{ColorAttachment, Frame};
use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::gl::FULLSCREEN_VERT;
use deferred_msaa_lab::gl::{
    Format, GpuTimer, Program, ShaderStage, TimerKind, VertexArray, check_error, preamble,
};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::cpu::{CpuKeySource, CpuResolve, PixelSamples};
use deferred_msaa_lab::resolve::{
    DepthProjection, KeySource, ResolveParams, ResolveRule, ResolveSettings,
};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::scene::{Camera, Scene};
use deferred_msaa_testkit::Host as ToyHost;
use deferred_msaa_testkit::projection;
use deferred_msaa_testkit::scene::RandomScene;
use glow::HasContext;
use std::path::PathBuf;
use std::process::ExitCode;

const FOV_Y: f32 = 0.9;
const NEAR: f32 = 0.5;
const FAR: f32 = 200.0;
/// Distance of the background triangle.
const BACKGROUND_Z: f32 = 120.0;

/// The floors of the one-pass resolve at 0 % complex pixels: full-screen
/// passes that read only what a uniformity test needs (every depth and
/// position sample for the exact test; every position sample and depth
/// sample 0 for the opt-in position test) and write sample 0 of every
/// attachment and of depth. No resolve that makes that test can cost less.
const FLOOR_FRAG: &str = "
uniform sampler2DMS u_depth;
uniform sampler2DMS u_color;
uniform sampler2DMS u_position;
uniform sampler2DMS u_normal;
uniform float u_clear_depth;
out vec4 o_color;
out vec4 o_position;
out vec4 o_normal;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d0 = texelFetch(u_depth, p, 0).r;
    vec4 k0 = texelFetch(u_position, p, 0);
    bool same = true;
    for (int i = 1; i < NUM_SAMPLES; ++i) {
        vec4 k = texelFetch(u_position, p, i);
#ifdef EXACT_TEST
        bool bg0 = d0 == u_clear_depth;
        bool bg = texelFetch(u_depth, p, i).r == u_clear_depth;
        same = same && bg == bg0 && (bg0 || k.z == k0.z);
#else
        same = same && k == k0;
#endif
    }
    // A pixel that fails the test is marked, so the test is not optimised away.
    o_color = same ? texelFetch(u_color, p, 0) : vec4(1.0, 0.0, 1.0, 1.0);
    o_position = k0;
    o_normal = texelFetch(u_normal, p, 0);
    gl_FragDepth = d0;
}
";
/// The scale pass: a full-screen triangle writing constants to the three attachments.
const TRIVIAL_FRAG: &str = "
out vec4 o_color;
out vec4 o_position;
out vec4 o_normal;
void main() {
    o_color = vec4(0.25, 0.5, 0.75, 1.0);
    o_position = vec4(0.0, 0.0, -1.0, 1.0);
    o_normal = vec4(0.0, 0.0, 1.0, 0.5);
}
";

struct Args {
    width: u32,
    height: u32,
    samples: u32,
    runs: usize,
    warmup: usize,
    triangles: usize,
    seed: u64,
    timer: TimerChoice,
    /// A scene (`builtin:NAME` or a glTF path) instead of random triangles.
    scene: Option<String>,
    /// Where the depth key comes from: the position attachment, or (as for
    /// a host without one) the depth buffer.
    key_from_depth: bool,
    /// The opt-in plane test on the fast path (`ResolveSettings::plane_uniformity`).
    plane_uniformity: bool,
    /// The opt-in position test (`ResolveSettings::position_uniformity`).
    position_uniformity: bool,
    /// Where the JSON report goes (default `target/resolve_vs_blit.json`).
    json: Option<PathBuf>,
    /// Measure nothing: print a markdown table of the reports in this folder.
    summarize: Option<PathBuf>,
}

/// Which timer's numbers are the headline (both are always taken).
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum TimerChoice {
    /// `GL_TIME_ELAPSED` where it is trustworthy, else wall time.
    Auto,
    /// `GL_TIME_ELAPSED`.
    Query,
    /// Wall time between `glFinish` calls.
    Wall,
}

/// Where the depth key comes from.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum KeyChoice {
    /// The view-space position attachment.
    Position,
    /// The depth buffer, linearised (a host without a position attachment).
    Depth,
}

/// The command line (see the module docs).
#[derive(clap::Parser)]
#[command(
    name = "resolve_vs_blit",
    about = "The depth-aware resolve against the hardware resolve"
)]
struct Cli {
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel asked for (the context's real count is used).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    samples: u32,
    /// Timed runs per method.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u64).range(1..))]
    runs: u64,
    /// Untimed rounds first.
    #[arg(long, default_value_t = 5)]
    warmup: u64,
    /// Random triangles over the background.
    #[arg(long, default_value_t = 600)]
    triangles: u64,
    /// The random scene's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Which timer is the headline.
    #[arg(long, value_enum, default_value_t = TimerChoice::Auto)]
    timer: TimerChoice,
    /// A scene (`builtin:NAME` or a glTF path) seen through its camera
    /// instead of the random triangles.
    #[arg(long, value_name = "S")]
    scene: Option<String>,
    /// Where the depth key comes from.
    #[arg(long, value_enum, default_value_t = KeyChoice::Position)]
    key: KeyChoice,
    /// The fast path with the opt-in plane test.
    #[arg(long)]
    plane_uniformity: bool,
    /// The fast path with the opt-in position test.
    #[arg(long)]
    position_uniformity: bool,
    /// Where the JSON report goes (default `target/resolve_vs_blit.json`).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Measure nothing: print a markdown table of the reports in DIR.
    #[arg(long, value_name = "DIR")]
    summarize: Option<PathBuf>,
    /// Passed by `cargo bench` to every bench target.
    #[arg(long, hide = true)]
    bench: bool,
}

fn parse_args() -> Args {
    let cli = <Cli as clap::Parser>::parse();
    Args {
        width: cli.size.0,
        height: cli.size.1,
        samples: cli.samples,
        runs: cli.runs as usize,
        warmup: cli.warmup as usize,
        triangles: cli.triangles as usize,
        seed: cli.seed,
        timer: cli.timer,
        scene: cli.scene,
        key_from_depth: cli.key == KeyChoice::Depth,
        plane_uniformity: cli.plane_uniformity,
        position_uniformity: cli.position_uniformity,
        json: cli.json,
        summarize: cli.summarize,
    }
}

/// The synthetic scene's lens: GL's standard perspective projection.
fn synthetic_camera() -> Camera {
    Camera {
        view: glam::Mat4::IDENTITY,
        fov_y: FOV_Y,
        near: NEAR,
        far: Some(FAR),
    }
}

/// Interleaved `[x, y, z, r, g, b]` view-space vertices of a real scene's
/// opaque triangles seen through its camera, coloured by base colour.
fn scene_vertices(spec: &str) -> Result<(Vec<f32>, Camera), String> {
    let scene = Scene::load(spec).map_err(|e| e.to_string())?;
    let mut v = Vec::new();
    for object in &scene.objects {
        let material = scene.material_of(object);
        let to_view = scene.camera.view * object.transform;
        for &i in &object.indices {
            let p = to_view.transform_point3(glam::Vec3::from(object.positions[i as usize]));
            v.extend_from_slice(&p.to_array());
            v.extend_from_slice(&material.base_color[..3]);
        }
    }
    Ok((v, scene.camera))
}

/// The synthetic scene: the test kit's random triangles (see
/// [`RandomScene`]) behind one far triangle that covers the whole view.
fn scene(args: &Args) -> Vec<f32> {
    RandomScene {
        aspect: args.width as f32 / args.height as f32,
        fov_y: FOV_Y,
        background_z: BACKGROUND_Z,
        count: args.triangles,
        seed: args.seed,
        open_corner: false,
    }
    .vertices()
}

/// The host engine (the test kit's toy host: RGBA16F colour, position and
/// normal, 32-bit float depth) and the camera it draws with.
struct Host {
    engine: ToyHost,
    camera: Camera,
    /// The camera's projection as the engine uploads it.
    projection: [f64; 16],
}

impl Host {
    fn new(gl: &glow::Context, args: &Args) -> deferred_msaa::Result<Host> {
        let (data, camera) = match &args.scene {
            Some(spec) => scene_vertices(spec).map_err(deferred_msaa::Error::invalid)?,
            None => (scene(args), synthetic_camera()),
        };
        let (w, h) = (args.width, args.height);
        let mut engine = ToyHost::new(gl, w, h, Format::Rgba16f, Format::Depth32f)?;
        if let Err(e) = engine.set_triangles(gl, &data) {
            engine.destroy(gl);
            return Err(e);
        }
        let projection = camera
            .projection(w as f32 / h as f32)
            .to_cols_array()
            .map(f64::from);
        Ok(Host {
            engine,
            camera,
            projection,
        })
    }

    /// The geometry pass, into whatever framebuffer is bound.
    fn draw(&self, gl: &glow::Context) {
        self.engine.draw(gl, &self.projection, false);
    }

    fn params(&self, settings: ResolveSettings) -> ResolveParams {
        let p = self.projection;
        ResolveParams {
            settings,
            projection: DepthProjection {
                p22: p[10],
                p23: p[14],
                zero_to_one: false,
                clear_depth: 1.0,
            },
            fov_y: self.camera.fov_y as f64,
            height_px: self.engine.height,
            view_row: None,
        }
    }

    /// The frame the resolve is given: the camera's projection as drawn.
    fn frame(&self) -> Frame {
        projection::frame(&self.projection, false)
    }

    fn destroy(self, gl: &glow::Context) {
        self.engine.destroy(gl);
    }
}

/// The hardware resolve of the three colour attachments, one blit each, and
/// with `depth` of the depth attachment too (the attachments the resolve
/// writes; a multisampled depth blit takes one sample, GL_NEAREST).
fn blit_resolve(gl: &glow::Context, twin: glow::Framebuffer, host: &Host, depth: bool) {
    let (w, h) = (host.engine.width as i32, host.engine.height as i32);
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(twin));
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(host.engine.fbo.raw()));
        for k in 0..3 {
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
        if depth {
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
        }
        // Put both framebuffers' mappings back as their owners set them.
        gl.draw_buffers(&[
            glow::COLOR_ATTACHMENT0,
            glow::COLOR_ATTACHMENT1,
            glow::COLOR_ATTACHMENT2,
        ]);
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
}

/// A full-screen triangle writing constants into the host's three attachments.
/// One floor pass (`FLOOR_FRAG`) from the twin's textures into the host's.
fn floor_pass(
    gl: &glow::Context,
    program: &Program,
    vao: &VertexArray,
    host: &Host,
    msaa: &MsaaRetrofit,
) -> deferred_msaa::Result<()> {
    let (depth, colors, _) = msaa.inputs()?;
    unsafe {
        host.engine.fbo.bind(gl);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::ALWAYS);
        gl.depth_mask(true);
        gl.disable(glow::BLEND);
        program.bind(gl);
        depth.bind(gl, 0);
        program.set_i32(gl, "u_depth", 0);
        for (k, name) in ["u_color", "u_position", "u_normal"].iter().enumerate() {
            if let Some(t) = colors.get(k) {
                t.bind(gl, 1 + k as u32);
                program.set_i32(gl, name, 1 + k as i32);
            }
        }
        program.set_f32(gl, "u_clear_depth", 1.0);
        vao.bind(gl);
        gl.draw_arrays(glow::TRIANGLES, 0, 3);
        gl.bind_vertex_array(None);
        gl.use_program(None);
        gl.disable(glow::DEPTH_TEST);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
    Ok(())
}

fn trivial_pass(gl: &glow::Context, program: &Program, vao: &VertexArray, host: &Host) {
    unsafe {
        host.engine.fbo.bind(gl);
        gl.disable(glow::DEPTH_TEST);
        gl.disable(glow::BLEND);
        program.bind(gl);
        vao.bind(gl);
        gl.draw_arrays(glow::TRIANGLES, 0, 3);
        gl.bind_vertex_array(None);
        gl.use_program(None);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
}

/// Pixels whose samples differ: by the resolve's own test (the depth key,
/// through the CPU reference) and by the raw depth-buffer samples.
struct Complexity {
    pixels: u64,
    complex_key: u64,
    complex_depth: u64,
    /// With an opt-in test: pixels whose result differs from the exact
    /// resolve's (fast path without the option), and the largest difference
    /// of any attachment component or depth.
    option_changed: u64,
    option_max_difference: f64,
}

fn count_complex(
    gl: &glow::Context,
    msaa: &MsaaRetrofit,
    params: &ResolveParams,
    exact: &ResolveParams,
) -> deferred_msaa::Result<Complexity> {
    let mut readback = Readback::new(gl)?;
    let (depth_ref, color_refs, _) = msaa.inputs()?;
    let read = (|| {
        let colors = color_refs
            .iter()
            .map(|t| readback.read(gl, *t, 1))
            .collect::<deferred_msaa::Result<Vec<_>>>()?;
        let depth = readback.read(gl, depth_ref, 1)?;
        Ok::<_, deferred_msaa::Error>((colors, depth))
    })();
    readback.destroy(gl);
    let (colors, depth) = read?;
    let cpu_for = |params: &ResolveParams| CpuResolve {
        settings: params.settings,
        rules: msaa.rules().to_vec(),
        key_source: match msaa.key() {
            KeySource::Depth => CpuKeySource::Depth(params.projection),
            _ => CpuKeySource::Position(1),
        },
        clear_depth: params.projection.clear_depth,
        footprint: params.footprint(),
        normal: None,
    };
    let cpu = cpu_for(params);
    let cpu_exact = cpu_for(exact);
    let with_option = params.settings != exact.settings;
    let n = depth.samples;
    let mut c = Complexity {
        pixels: 0,
        complex_key: 0,
        complex_depth: 0,
        option_changed: 0,
        option_max_difference: 0.0,
    };
    for y in 0..depth.height {
        for x in 0..depth.width {
            let px = PixelSamples {
                depth: (0..n).map(|s| depth.get(s, x, y)[0] as f64).collect(),
                attachments: colors
                    .iter()
                    .map(|a| (0..n).map(|s| a.get(s, x, y).map(f64::from)).collect())
                    .collect(),
            };
            c.pixels += 1;
            let resolved = cpu.resolve_pixel(&px);
            let complex = resolved.complex;
            if with_option {
                let want = cpu_exact.resolve_pixel(&px);
                let mut worst = (resolved.depth - want.depth).abs();
                for (a, b) in resolved.attachments.iter().zip(&want.attachments) {
                    for (x, y) in a.iter().zip(b) {
                        // NaN stays NaN; only finite differences count.
                        if x.is_finite() && y.is_finite() {
                            worst = worst.max((x - y).abs());
                        }
                    }
                }
                c.option_changed += (worst > 0.0) as u64;
                c.option_max_difference = c.option_max_difference.max(worst);
            }
            c.complex_key += complex as u64;
            c.complex_depth +=
                px.depth
                    .iter()
                    .any(|d| d.to_bits() != px.depth[0].to_bits()) as u64;
        }
    }
    Ok(c)
}

struct Stats {
    median: f64,
    q1: f64,
    q3: f64,
    min: f64,
    max: f64,
}

fn stats(times: &[f64]) -> Stats {
    let mut s = times.to_vec();
    s.sort_by(f64::total_cmp);
    Stats {
        median: quantile(&s, 0.5),
        q1: quantile(&s, 0.25),
        q3: quantile(&s, 0.75),
        min: s.first().copied().unwrap_or(f64::NAN),
        max: s.last().copied().unwrap_or(f64::NAN),
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Method {
    ResolveFast,
    ResolveExact,
    ResolveNoFast,
    Blit,
    BlitColor,
    FloorExact,
    FloorPosition,
    Trivial,
}

impl Method {
    const ALL: [Method; 8] = [
        Method::ResolveFast,
        Method::ResolveExact,
        Method::ResolveNoFast,
        Method::Blit,
        Method::BlitColor,
        Method::FloorExact,
        Method::FloorPosition,
        Method::Trivial,
    ];
    fn key(self) -> &'static str {
        match self {
            Method::ResolveFast => "resolve_median_smooth_fast",
            Method::ResolveExact => "resolve_median_smooth_fast_exact",
            Method::ResolveNoFast => "resolve_median_smooth_nofast",
            Method::Blit => "blit_x3_depth",
            Method::BlitColor => "blit_x3",
            Method::FloorExact => "floor_exact_test",
            Method::FloorPosition => "floor_position_test",
            Method::Trivial => "fullscreen_trivial",
        }
    }
    fn label(self) -> &'static str {
        match self {
            Method::ResolveFast => {
                "resolve median smooth, fast path on (with the opt-in test if asked)"
            }
            Method::ResolveExact => "resolve median smooth, fast path on, exact test",
            Method::ResolveNoFast => "resolve median smooth, fast path off",
            Method::Blit => "3x glBlitFramebuffer + depth (hardware resolve)",
            Method::BlitColor => "3x glBlitFramebuffer, colour only",
            Method::FloorExact => "floor: the exact test's reads, sample 0 written",
            Method::FloorPosition => "floor: the position test's reads, sample 0 written",
            Method::Trivial => "trivial full-screen pass (3 outputs)",
        }
    }
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
}

fn run(args: &Args) -> Result<(), String> {
    Backend::Egl.check_library().map_err(|e| e.to_string())?;
    let ctx = HeadlessContext::new(Backend::Egl).map_err(|e| format!("EGL context: {e}"))?;
    let gl = ctx.gl();
    let version = ctx.version();
    let e = |e: deferred_msaa::Error| e.to_string();

    let host = Host::new(gl, args).map_err(e)?;
    let options = RetrofitOptions {
        samples: args.samples,
        // As the recommended layout resolves normals: the reference sample's.
        rules: vec![(ColorAttachment(2), ResolveRule::Select)],
        position_attachment: (!args.key_from_depth).then_some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.engine.fbo.raw(), &options).map_err(e)?;
    let samples = msaa.samples();
    let twin = msaa.framebuffer();

    // The host's geometry pass, once, into the multisampled twin.
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(twin)) };
    host.draw(gl);
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    check_error(gl, "drawing the scene").map_err(e)?;

    let fast = host.params(ResolveSettings {
        plane_uniformity: args.plane_uniformity,
        position_uniformity: args.position_uniformity,
        ..ResolveSettings::default()
    });
    let exact = host.params(ResolveSettings::default());
    let nofast = host.params(ResolveSettings {
        fast_path: false,
        ..ResolveSettings::default()
    });
    let complexity = count_complex(gl, &msaa, &fast, &exact).map_err(e)?;

    let trivial = Program::build(
        gl,
        "trivial full-screen pass",
        &preamble(&[], &[]),
        &[
            (ShaderStage::Vertex, "fullscreen.vert", FULLSCREEN_VERT),
            (ShaderStage::Fragment, "trivial.frag", TRIVIAL_FRAG),
        ],
        &[("o_color", 0), ("o_position", 1), ("o_normal", 2)],
    )
    .map_err(e)?;
    let floor = |exact: bool| {
        let mut defines = vec![("NUM_SAMPLES".to_string(), samples.to_string())];
        if exact {
            defines.push(("EXACT_TEST".to_string(), "1".to_string()));
        }
        Program::build(
            gl,
            if exact {
                "floor of the exact test"
            } else {
                "floor of the position test"
            },
            &preamble(&[], &defines),
            &[
                (ShaderStage::Vertex, "fullscreen.vert", FULLSCREEN_VERT),
                (ShaderStage::Fragment, "floor.frag", FLOOR_FRAG),
            ],
            &[("o_color", 0), ("o_position", 1), ("o_normal", 2)],
        )
    };
    let floor_exact = floor(true).map_err(e)?;
    let floor_position = floor(false).map_err(e)?;
    let empty_vao = VertexArray::new(gl, "trivial pass vao").map_err(e)?;
    // Every run is timed twice at once: a GL_TIME_ELAPSED query (where the
    // context has one) inside a glFinish-bracketed wall clock.
    let mut wall = GpuTimer::new(gl, true).map_err(e)?;
    let query = GpuTimer::new(gl, false).map_err(e)?;
    let mut query = match query.kind() {
        TimerKind::GlTimeElapsed => Some(query),
        TimerKind::FinishWallClock => {
            query.destroy(gl);
            None
        }
    };
    let software = ["llvmpipe", "softpipe", "swrast", "lavapipe"]
        .iter()
        .any(|name| version.renderer.to_lowercase().contains(name));
    let (primary, reason) = match (args.timer, query.is_some()) {
        (TimerChoice::Wall, _) => (TimerKind::FinishWallClock, "asked for with --timer wall"),
        (TimerChoice::Query, true) => (TimerKind::GlTimeElapsed, "asked for with --timer query"),
        (TimerChoice::Query, false) => {
            return Err("--timer query: this context has no GL_TIME_ELAPSED queries".into());
        }
        (TimerChoice::Auto, false) => (
            TimerKind::FinishWallClock,
            "the context has no GL_TIME_ELAPSED queries",
        ),
        (TimerChoice::Auto, true) if software => (
            TimerKind::FinishWallClock,
            "software renderer: llvmpipe's GL_TIME_ELAPSED restarts at every tile a thread \
             rasterises, so it spans only the last tiles, not the pass",
        ),
        (TimerChoice::Auto, true) => (TimerKind::GlTimeElapsed, "the context has GL_TIME_ELAPSED"),
    };

    let frame = host.frame();
    let with = |resolve: ResolveSettings| RetrofitOptions {
        resolve,
        ..options.clone()
    };
    // The resolve's variants, all compiled now: switching between them
    // (outside the timed region) only picks a cached program.
    let variants = [
        (Method::ResolveFast, with(fast.settings)),
        (Method::ResolveExact, with(exact.settings)),
        (Method::ResolveNoFast, with(nofast.settings)),
    ];
    for (_, v) in &variants {
        msaa.set_options(gl, v).map_err(e)?;
    }
    let mut once = |m: Method| -> deferred_msaa::Result<(f64, Option<f64>)> {
        if let Some((_, v)) = variants.iter().find(|(method, _)| *method == m) {
            msaa.set_options(gl, v)?;
        }
        wall.begin(gl);
        if let Some(q) = query.as_mut() {
            q.begin(gl);
        }
        match m {
            Method::ResolveFast | Method::ResolveExact | Method::ResolveNoFast => {
                msaa.resolve(gl, &frame)?
            }
            Method::Blit => blit_resolve(gl, twin, &host, true),
            Method::BlitColor => blit_resolve(gl, twin, &host, false),
            Method::FloorExact => floor_pass(gl, &floor_exact, &empty_vao, &host, &msaa)?,
            Method::FloorPosition => floor_pass(gl, &floor_position, &empty_vao, &host, &msaa)?,
            Method::Trivial => trivial_pass(gl, &trivial, &empty_vao, &host),
        }
        let q_ms = query.as_mut().map(|q| q.end(gl));
        let w_ms = wall.end(gl);
        check_error(gl, m.label())?;
        Ok((w_ms, q_ms))
    };

    // Warm-up (compiles the resolve permutations too), then K interleaved
    // rounds; each round starts one method later, so none always goes first.
    for _ in 0..args.warmup {
        for m in Method::ALL {
            once(m).map_err(e)?;
        }
    }
    let mut wall_ms: Vec<Vec<f64>> = vec![Vec::with_capacity(args.runs); Method::ALL.len()];
    let mut query_ms: Vec<Vec<f64>> = vec![Vec::with_capacity(args.runs); Method::ALL.len()];
    for round in 0..args.runs {
        for i in 0..Method::ALL.len() {
            let k = (round + i) % Method::ALL.len();
            let (w, q) = once(Method::ALL[k]).map_err(e)?;
            wall_ms[k].push(w);
            if let Some(q) = q {
                query_ms[k].push(q);
            }
        }
    }
    let have_query = query.is_some();
    wall.destroy(gl);
    if let Some(q) = query {
        q.destroy(gl);
    }
    trivial.destroy(gl);
    empty_vao.destroy(gl);
    floor_exact.destroy(gl);
    floor_position.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);

    // Report: the primary timer's table and ratios, then the other timer's.
    let (primary_ms, secondary_ms) = match primary {
        TimerKind::FinishWallClock => (&wall_ms, have_query.then_some(&query_ms)),
        TimerKind::GlTimeElapsed => (&query_ms, Some(&wall_ms)),
    };
    let secondary = match primary {
        TimerKind::FinishWallClock => TimerKind::GlTimeElapsed,
        TimerKind::GlTimeElapsed => TimerKind::FinishWallClock,
    };
    let primary_stats: Vec<Stats> = primary_ms.iter().map(|t| stats(t)).collect();
    let secondary_stats: Option<Vec<Stats>> =
        secondary_ms.map(|all| all.iter().map(|t| stats(t)).collect());
    let ratios = |st: &[Stats]| {
        let median = |m: Method| st[Method::ALL.iter().position(|x| *x == m).unwrap_or(0)].median;
        let blit = median(Method::Blit);
        (
            median(Method::ResolveFast) / blit,
            median(Method::ResolveNoFast) / blit,
        )
    };
    let (ratio_fast, ratio_nofast) = ratios(&primary_stats);
    let frac = |n: u64| n as f64 / complexity.pixels.max(1) as f64;
    let describe = |k: TimerKind| match k {
        TimerKind::GlTimeElapsed => "GL_TIME_ELAPSED query",
        TimerKind::FinishWallClock => "wall time between glFinish calls",
    };

    println!(
        "resolve_vs_blit: {}x{}, {}x MSAA (requested {}), G-buffer 3x RGBA16F + DEPTH32F, {}",
        args.width,
        args.height,
        samples,
        args.samples,
        match &args.scene {
            Some(spec) => format!("scene {spec}"),
            None => format!("{} random triangles + background", args.triangles),
        }
    );
    println!(
        "key: {}{}",
        if args.key_from_depth {
            "the depth buffer, linearised"
        } else {
            "the view-space position attachment"
        },
        match (
            args.plane_uniformity,
            args.position_uniformity && !args.key_from_depth
        ) {
            (_, true) => "; fast path with the opt-in position test",
            (true, false) => "; fast path with the opt-in plane test",
            _ => "",
        }
    );
    println!(
        "context: EGL, {} | GL {} | GLSL {}",
        version.renderer, version.version_string, version.glsl_string
    );
    println!(
        "timer: {} ({}); why: {reason}",
        primary.name(),
        describe(primary)
    );
    println!(
        "complex pixels: {:.2}% ({} of {}; depth keys differ across samples, the fast path's test, via resolve::cpu)",
        100.0 * frac(complexity.complex_key),
        complexity.complex_key,
        complexity.pixels
    );
    println!(
        "                {:.2}% ({}; raw depth-buffer samples differ, tilted interiors included)",
        100.0 * frac(complexity.complex_depth),
        complexity.complex_depth
    );
    println!(
        "{} warm-up rounds, then {} runs per method, interleaved round-robin",
        args.warmup, args.runs
    );
    print_table(&primary_stats);
    if args.plane_uniformity || args.position_uniformity {
        println!(
            "the opt-in test changes {} pixels ({:.2}%) against the exact resolve, by at most {:.3e}",
            complexity.option_changed,
            100.0 * frac(complexity.option_changed),
            complexity.option_max_difference
        );
    }
    println!("ratio resolve/blit (medians, fast path on):  {ratio_fast:.3}");
    println!("ratio resolve/blit (medians, fast path off): {ratio_nofast:.3}");
    println!(
        "ratio resolve fast path on/off (medians):    {:.3}",
        ratio_fast / ratio_nofast
    );
    if let Some(st) = &secondary_stats {
        let (f, n) = ratios(st);
        println!(
            "for comparison, the same runs by {} ({}):",
            secondary.name(),
            describe(secondary)
        );
        print_table(st);
        println!("  ratios resolve/blit: fast path on {f:.3}, off {n:.3}");
    }

    let methods_json = |st: &[Stats], all: &[Vec<f64>]| -> Vec<serde_json::Value> {
        Method::ALL
            .iter()
            .zip(st)
            .zip(all)
            .map(|((m, s), t)| {
                serde_json::json!({
                    "method": m.key(),
                    "label": m.label(),
                    "median_ms": s.median,
                    "q1_ms": s.q1,
                    "q3_ms": s.q3,
                    "iqr_ms": s.q3 - s.q1,
                    "min_ms": s.min,
                    "max_ms": s.max,
                    "runs_ms": t,
                })
            })
            .collect()
    };
    let secondary_json = match (&secondary_stats, secondary_ms) {
        (Some(st), Some(all)) => {
            let (f, n) = ratios(st);
            serde_json::json!({
                "timer": secondary.name(),
                "methods": methods_json(st, all),
                "ratio_resolve_fast_over_blit": f,
                "ratio_resolve_nofast_over_blit": n,
            })
        }
        _ => serde_json::Value::Null,
    };
    let report = serde_json::json!({
        "renderer": version.renderer,
        "gl_version": version.version_string,
        "glsl_version": version.glsl_string,
        "backend": "egl",
        "width": args.width,
        "height": args.height,
        "samples_requested": args.samples,
        "samples": samples,
        "gbuffer": ["RGBA16F color", "RGBA16F position", "RGBA16F normal", "DEPTH32F"],
        "triangles": args.triangles,
        "scene": args.scene,
        "seed": args.seed,
        "key": if args.key_from_depth { "depth" } else { "position" },
        "plane_uniformity": args.plane_uniformity,
        "position_uniformity": args.position_uniformity && !args.key_from_depth,
        "option_changed_pixels": complexity.option_changed,
        "option_max_difference": complexity.option_max_difference,
        "pixels": complexity.pixels,
        "complex_pixels": complexity.complex_key,
        "complex_fraction": frac(complexity.complex_key),
        "depth_differs_pixels": complexity.complex_depth,
        "depth_differs_fraction": frac(complexity.complex_depth),
        "timer": primary.name(),
        "timer_reason": reason,
        "warmup": args.warmup,
        "runs": args.runs,
        "methods": methods_json(&primary_stats, primary_ms),
        "ratio_resolve_fast_over_blit": ratio_fast,
        "ratio_resolve_nofast_over_blit": ratio_nofast,
        "ratio_resolve_fast_over_nofast": ratio_fast / ratio_nofast,
        "other_timer": secondary_json,
    });
    let path = args
        .json
        .clone()
        .unwrap_or_else(|| target_dir().join("resolve_vs_blit.json"));
    let dir = path.parent().map(PathBuf::from).unwrap_or_default();
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(&path, text + "\n"))
        .map_err(|e| format!("writing {}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn print_table(st: &[Stats]) {
    println!(
        "  {:<40} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "method", "median ms", "q1", "q3", "IQR", "min", "max"
    );
    for (m, s) in Method::ALL.iter().zip(st) {
        println!(
            "  {:<40} {:>9.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
            m.label(),
            s.median,
            s.q1,
            s.q3,
            s.q3 - s.q1,
            s.min,
            s.max
        );
    }
}

/// The median of `method` in a report.
fn median_of(report: &serde_json::Value, method: &str) -> Option<f64> {
    report["methods"]
        .as_array()?
        .iter()
        .find(|m| m["method"] == method)?["median_ms"]
        .as_f64()
}

/// A markdown table of every report (`*.json`) in `dir`, in file-name order.
fn summarize(dir: &std::path::Path) -> Result<(), String> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("reading {}: {e}", dir.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(format!("no reports (*.json) in {}", dir.display()));
    }
    println!(
        "| scene | key | opt-in test | complex pixels | resolve, ms | blits, ms | resolve / blits | \
         resolve / always-slow | exact test / blits | always-slow / blits | \
         floor, exact test / blits | floor, position test / blits | changed by the opt-in test |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    let mut renderer = None;
    for path in &paths {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("reading {}: {e}", path.display()))?;
        let r: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a resolve_vs_blit report ({e})", path.display()))?;
        let median = |m: &str| {
            median_of(&r, m).ok_or_else(|| format!("{}: no median for {m}", path.display()))
        };
        let (floor_exact, floor_position) =
            (median("floor_exact_test")?, median("floor_position_test")?);
        let (fast, exact, slow, blit) = (
            median("resolve_median_smooth_fast")?,
            median("resolve_median_smooth_fast_exact")?,
            median("resolve_median_smooth_nofast")?,
            median("blit_x3_depth")?,
        );
        let scene = match r["scene"].as_str() {
            Some(s) => std::path::Path::new(s)
                .file_stem()
                .map_or(s.to_string(), |f| f.to_string_lossy().into_owned()),
            None => format!("{} random triangles", r["triangles"]),
        };
        let option = if r["position_uniformity"] == true {
            "position"
        } else if r["plane_uniformity"] == true {
            "plane"
        } else {
            "none (exact)"
        };
        let changed = if option.starts_with("none") {
            "".to_string()
        } else {
            format!(
                "{} px, by at most {:.2e}",
                r["option_changed_pixels"],
                r["option_max_difference"].as_f64().unwrap_or(f64::NAN)
            )
        };
        println!(
            "| {scene} | {} | {option} | {:.1} % | {fast:.1} | {blit:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {changed} |",
            r["key"].as_str().unwrap_or("?"),
            100.0 * r["complex_fraction"].as_f64().unwrap_or(f64::NAN),
            fast / blit,
            fast / slow,
            exact / blit,
            slow / blit,
            floor_exact / blit,
            floor_position / blit,
        );
        renderer.get_or_insert_with(|| {
            format!(
                "{}x{}, {}x, {} runs each, {}; {}",
                r["width"],
                r["height"],
                r["samples"],
                r["runs"],
                r["timer"].as_str().unwrap_or("?"),
                r["renderer"].as_str().unwrap_or("?")
            )
        });
    }
    if let Some(line) = renderer {
        println!("\n{line}");
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = parse_args();
    let result = match &args.summarize {
        Some(dir) => summarize(dir),
        None => run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("resolve_vs_blit: {msg}");
            ExitCode::FAILURE
        }
    }
}
