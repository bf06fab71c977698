//! The bench's command line, its scene, the host G-buffer it resolves
//! and the passes it times beside the resolve.

use crate::common::parse_size;
use deferred_msaa::Frame;
use deferred_msaa_lab::gl::{Format, Program, VertexArray};
use deferred_msaa_lab::resolve::{DepthProjection, ResolveParams, ResolveSettings};
use deferred_msaa_lab::retrofit::MsaaRetrofit;
use deferred_msaa_lab::scene::{Camera, Scene};
use deferred_msaa_testkit::Host as ToyHost;
use deferred_msaa_testkit::projection;
use deferred_msaa_testkit::scene::RandomScene;
use glow::HasContext;
use std::path::PathBuf;

pub(crate) const FOV_Y: f32 = 0.9;
pub(crate) const NEAR: f32 = 0.5;
pub(crate) const FAR: f32 = 200.0;
/// Distance of the background triangle.
pub(crate) const BACKGROUND_Z: f32 = 120.0;

/// The floors of the one-pass resolve at 0 % complex pixels: full-screen
/// passes that read only what a uniformity test needs (every depth and
/// position sample for the exact test; every position sample and depth
/// sample 0 for the opt-in position test) and write sample 0 of every
/// attachment and of depth. No resolve that makes that test can cost less.
pub(crate) const FLOOR_FRAG: &str = "
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
pub(crate) const TRIVIAL_FRAG: &str = "
out vec4 o_color;
out vec4 o_position;
out vec4 o_normal;
void main() {
    o_color = vec4(0.25, 0.5, 0.75, 1.0);
    o_position = vec4(0.0, 0.0, -1.0, 1.0);
    o_normal = vec4(0.0, 0.0, 1.0, 0.5);
}
";

pub(crate) struct Args {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) samples: u32,
    pub(crate) runs: usize,
    pub(crate) warmup: usize,
    pub(crate) triangles: usize,
    pub(crate) seed: u64,
    pub(crate) timer: TimerChoice,
    /// A scene (`builtin:NAME` or a glTF path) instead of random triangles.
    pub(crate) scene: Option<String>,
    /// Where the depth key comes from: the position attachment, or (as for
    /// a host without one) the depth buffer.
    pub(crate) key_from_depth: bool,
    /// The opt-in plane test on the fast path (`ResolveSettings::plane_uniformity`).
    pub(crate) plane_uniformity: bool,
    /// The opt-in position test (`ResolveSettings::position_uniformity`).
    pub(crate) position_uniformity: bool,
    /// Where the JSON report goes (default `target/resolve_vs_blit.json`).
    pub(crate) json: Option<PathBuf>,
    /// Measure nothing: print a markdown table of the reports in this folder.
    pub(crate) summarize: Option<PathBuf>,
}

/// Which timer's numbers are the headline (both are always taken).
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum TimerChoice {
    /// `GL_TIME_ELAPSED` where it is trustworthy, else wall time.
    Auto,
    /// `GL_TIME_ELAPSED`.
    Query,
    /// Wall time between `glFinish` calls.
    Wall,
}

/// Where the depth key comes from.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum KeyChoice {
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
pub(crate) struct Cli {
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    pub(crate) size: (u32, u32),
    /// Samples per pixel asked for (the context's real count is used).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) samples: u32,
    /// Timed runs per method.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) runs: u64,
    /// Untimed rounds first.
    #[arg(long, default_value_t = 5)]
    pub(crate) warmup: u64,
    /// Random triangles over the background.
    #[arg(long, default_value_t = 600)]
    pub(crate) triangles: u64,
    /// The random scene's seed.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Which timer is the headline.
    #[arg(long, value_enum, default_value_t = TimerChoice::Auto)]
    pub(crate) timer: TimerChoice,
    /// A scene (`builtin:NAME` or a glTF path) seen through its camera
    /// instead of the random triangles.
    #[arg(long, value_name = "S")]
    pub(crate) scene: Option<String>,
    /// Where the depth key comes from.
    #[arg(long, value_enum, default_value_t = KeyChoice::Position)]
    pub(crate) key: KeyChoice,
    /// The fast path with the opt-in plane test.
    #[arg(long)]
    pub(crate) plane_uniformity: bool,
    /// The fast path with the opt-in position test.
    #[arg(long)]
    pub(crate) position_uniformity: bool,
    /// Where the JSON report goes (default `target/resolve_vs_blit.json`).
    #[arg(long, value_name = "FILE")]
    pub(crate) json: Option<PathBuf>,
    /// Measure nothing: print a markdown table of the reports in DIR.
    #[arg(long, value_name = "DIR")]
    pub(crate) summarize: Option<PathBuf>,
    /// Passed by `cargo bench` to every bench target.
    #[arg(long, hide = true)]
    pub(crate) bench: bool,
}

pub(crate) fn parse_args() -> Args {
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
pub(crate) fn synthetic_camera() -> Camera {
    Camera {
        view: glam::Mat4::IDENTITY,
        fov_y: FOV_Y,
        near: NEAR,
        far: Some(FAR),
    }
}

/// Interleaved `[x, y, z, r, g, b]` view-space vertices of a real scene's
/// opaque triangles seen through its camera, coloured by base colour.
pub(crate) fn scene_vertices(spec: &str) -> Result<(Vec<f32>, Camera), String> {
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
pub(crate) fn scene(args: &Args) -> Vec<f32> {
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
pub(crate) struct Host {
    pub(crate) engine: ToyHost,
    pub(crate) camera: Camera,
    /// The camera's projection as the engine uploads it.
    pub(crate) projection: [f64; 16],
}

impl Host {
    pub(crate) fn new(gl: &glow::Context, args: &Args) -> deferred_msaa::Result<Host> {
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
    pub(crate) fn draw(&self, gl: &glow::Context) {
        self.engine.draw(gl, &self.projection, false);
    }

    pub(crate) fn params(&self, settings: ResolveSettings) -> ResolveParams {
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
    pub(crate) fn frame(&self) -> Frame {
        projection::frame(&self.projection, false)
    }

    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.engine.destroy(gl);
    }
}

/// The hardware resolve of the three colour attachments, one blit each, and
/// with `depth` of the depth attachment too (the attachments the resolve
/// writes; a multisampled depth blit takes one sample, GL_NEAREST).
pub(crate) fn blit_resolve(gl: &glow::Context, twin: glow::Framebuffer, host: &Host, depth: bool) {
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
pub(crate) fn floor_pass(
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

pub(crate) fn trivial_pass(gl: &glow::Context, program: &Program, vao: &VertexArray, host: &Host) {
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
