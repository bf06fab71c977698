//! An interactive viewer: any glTF file or built-in scene in a real window
//! (glutin + winit, an OpenGL 3.2+ core context through GLX or EGL on X11),
//! rendered by the crate's deferred renderer with live switching of every
//! anti-aliasing option. Switching never restarts anything and never shows a
//! black frame: [`Renderer::set_options`] builds the new resources before it
//! frees the old ones, and the next frame is drawn with them.
//!
//! ```sh
//! cargo run --release --example viewer -- [SCENE] [--size 960x540] [--samples N]
//!     [--method none|average|front|median|back|taa|per-sample] [--layers 1|2] [--fxaa | --smaa]
//!     [--frames N --screenshot FILE.png] [--keys KEYS]
//! ```
//! `SCENE` is `builtin:NAME` (default `builtin:greebles`) or a `.gltf`/`.glb` path.
//!
//! Keys (the title bar shows the method, sample count, view and frame time):
//!
//! | key | what |
//! |---|---|
//! | `M` / `Shift+M` | next / previous method: none, average, front, median, back, taa, per-sample |
//! | `0` … `6` | none, average, front, median, back, taa (temporal anti-aliasing: orbit to see its lag and smear), per-sample (every sample lit: the cost the resolve avoids) |
//! | `T` | the second resolved layer on / off (front, median and back; `:layers=2`: the lighting runs twice, the second time only where a pixel has a second surface) |
//! | `N` | next sample count the driver really offers for every G-buffer format |
//! | `F` | FXAA on / off (turns SMAA off) |
//! | `S` | SMAA 1x (preset high) on / off (turns FXAA off) |
//! | `V` / `Shift+V` | next / previous view: final image, each G-buffer attachment, depth, complex pixels |
//! | arrows (or `H` `J` `K` `L`), mouse drag | orbit the camera |
//! | `+` / `-`, mouse wheel | zoom |
//! | `R` | reset the camera |
//! | `P` | save what the window shows as a PNG (the `--screenshot` path, else `target/viewer.png`) |
//! | `?` | print this list |
//! | `Esc`, `Q` | quit |
//!
//! `--frames N --screenshot FILE` renders N frames, saves the last one as the
//! window shows it (read from the back buffer) and exits; with `--keys KEYS`
//! the characters of `KEYS` are pressed one per frame first. In that mode any
//! blank frame (every pixel the same) is an error.

use std::error::Error;
use std::ffi::CString;
use std::num::NonZeroU32;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use deferred_msaa_lab::cli::{Printed, parse_args};
use deferred_msaa_lab::gl::{
    Capabilities, FullscreenPass, Made, ShaderSource, VertexArray, check_error,
    draw_fullscreen_triangle,
};
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer, SmaaOptions};
use deferred_msaa_lab::resolve::{
    COMPLEX_GLSL, COMPLEX_GLSL_NAME, DepthProjection, KeySource, ResolveSlot,
};
use deferred_msaa_lab::scene::{Aabb, Camera, Scene};
use glam::Vec3;
use glow::HasContext;
use glutin::config::{Config, ConfigTemplateBuilder, GlConfig};
use glutin::context::{
    ContextApi, ContextAttributesBuilder, GlProfile, NotCurrentGlContext, PossiblyCurrentContext,
    Version,
};
use glutin::display::{Display, DisplayApiPreference, GlDisplay};
use glutin::surface::{GlSurface, Surface, SurfaceAttributesBuilder, SwapInterval, WindowSurface};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowAttributes, WindowId};

type AnyResult<T> = Result<T, Box<dyn Error>>;

/// Frames of a scripted run after which resident memory is the baseline.
const WARMUP_FRAMES: u32 = 100;

/// The methods, in key order (`0` … `5`), as method specs.
const METHODS: [&str; 7] = [
    "none",
    "average",
    "front",
    "median",
    "back",
    "taa",
    "per-sample",
];

fn main() -> ExitCode {
    let args = match parse_args::<Cli>() {
        Ok(cli) => Args::from(cli),
        Err(Printed::Help) => return ExitCode::SUCCESS,
        Err(Printed::UsageError) => return ExitCode::FAILURE,
    };
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("viewer: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> AnyResult<()> {
    let scene = Scene::load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("viewer: {}: {w}", args.scene);
    }
    let event_loop = EventLoop::new().map_err(|e| {
        // winit's message names its own source file first; keep the reason.
        let text = e.to_string();
        let reason = text
            .rsplit_once(".rs:")
            .and_then(|(_, rest)| rest.split_once(": "))
            .map_or(text.as_str(), |(_, reason)| reason);
        let display = std::env::var("DISPLAY").unwrap_or_else(|_| "unset".into());
        format!(
            "cannot open a window: {} (DISPLAY={display})",
            reason.trim_end_matches('.')
        )
    })?;
    let mut app = App {
        args,
        scene: Some(scene),
        viewer: None,
        error: None,
    };
    let scripted = app.args.frames.is_some();
    event_loop.run_app(&mut app)?;
    if let Some(e) = app.error {
        return Err(e.into());
    }
    if scripted {
        // The whole run's resources are gone: reported for the long-run test.
        let live = deferred_msaa_lab::gl::live_objects();
        println!(
            "viewer: live GL objects at exit: {} ({live:?})",
            live.total()
        );
    }
    Ok(())
}

/// Resident set size in bytes (Linux; 0 elsewhere).
fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    pages * 4096
}

/// The command line.
#[derive(Debug)]
struct Args {
    scene: String,
    width: u32,
    height: u32,
    samples: u32,
    method: usize,
    layers: u32,
    fxaa: bool,
    smaa: bool,
    frames: Option<u32>,
    screenshot: Option<PathBuf>,
    keys: Vec<char>,
}

/// The command line, as clap reads it.
#[derive(clap::Parser)]
#[command(name = "viewer", about = "The demo renderer in a window, its methods switched live", after_help = KEYS)]
struct Cli {
    /// A built-in scene (`builtin:NAME`) or a glTF file.
    #[arg(default_value = "builtin:greebles")]
    scene: String,
    /// The window's size, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel asked for (the driver's real count is used).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    samples: u32,
    /// The method to start with.
    #[arg(long, default_value = "median", value_parser = METHODS)]
    method: String,
    /// Resolved layers of front, median and back to start with (`T` toggles).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=2))]
    layers: u32,
    /// Start with FXAA on.
    #[arg(long, conflicts_with = "smaa")]
    fxaa: bool,
    /// Start with SMAA 1x on.
    #[arg(long)]
    smaa: bool,
    /// Render this many frames, then quit (1 with --screenshot alone).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Save the last frame's window here.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Keys to press, one a frame, as if typed (see below).
    #[arg(long, default_value = "")]
    keys: String,
}

impl From<Cli> for Args {
    fn from(cli: Cli) -> Args {
        Args {
            scene: cli.scene,
            width: cli.size.0,
            height: cli.size.1,
            samples: cli.samples,
            // clap admitted only the methods' names.
            method: METHODS.iter().position(|m| *m == cli.method).unwrap_or(3),
            layers: cli.layers,
            fxaa: cli.fxaa,
            smaa: cli.smaa,
            frames: cli.frames.or_else(|| cli.screenshot.as_ref().map(|_| 1)),
            screenshot: cli.screenshot,
            keys: cli.keys.chars().collect(),
        }
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    text.split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .filter(|&(w, h)| (1..=16384).contains(&w) && (1..=16384).contains(&h))
        .ok_or_else(|| format!("expected WIDTHxHEIGHT such as 960x540, got `{text}`"))
}

/// The keys, for `--help` and `?`.
const KEYS: &str = "keys: M/Shift+M method, 0-6 none/average/front/median/back/taa/per-sample, T second layer, N sample count, F FXAA, S SMAA, \
V/Shift+V view, arrows/HJKL or drag orbit, +/- or wheel zoom, R reset camera, P screenshot, ? keys, Esc/Q quit";

fn print_keys() {
    println!("{KEYS}");
}

/// What a key press or a scripted key does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Action {
    Method(usize),
    StepMethod(isize),
    ToggleLayers,
    NextSamples,
    ToggleFxaa,
    ToggleSmaa,
    StepView(isize),
    Orbit(f32, f32),
    Zoom(f32),
    ResetCamera,
    Screenshot,
    Help,
    Quit,
}

fn action_for_char(c: char) -> Option<Action> {
    const STEP: f32 = 0.15;
    Some(match c {
        'm' => Action::StepMethod(1),
        'M' => Action::StepMethod(-1),
        '0'..='6' => Action::Method(c as usize - '0' as usize),
        't' | 'T' => Action::ToggleLayers,
        'n' | 'N' => Action::NextSamples,
        'f' | 'F' => Action::ToggleFxaa,
        's' | 'S' => Action::ToggleSmaa,
        'v' => Action::StepView(1),
        'V' => Action::StepView(-1),
        'h' | 'H' => Action::Orbit(-STEP, 0.0),
        'l' | 'L' => Action::Orbit(STEP, 0.0),
        'k' | 'K' => Action::Orbit(0.0, STEP),
        'j' | 'J' => Action::Orbit(0.0, -STEP),
        '+' | '=' => Action::Zoom(1.0 / 1.15),
        '-' | '_' => Action::Zoom(1.15),
        'r' | 'R' => Action::ResetCamera,
        'p' | 'P' => Action::Screenshot,
        '?' => Action::Help,
        'q' | 'Q' => Action::Quit,
        _ => return None,
    })
}

fn action_for_key(event: &KeyEvent) -> Option<Action> {
    const STEP: f32 = 0.15;
    match &event.logical_key {
        Key::Named(NamedKey::ArrowLeft) => Some(Action::Orbit(-STEP, 0.0)),
        Key::Named(NamedKey::ArrowRight) => Some(Action::Orbit(STEP, 0.0)),
        Key::Named(NamedKey::ArrowUp) => Some(Action::Orbit(0.0, STEP)),
        Key::Named(NamedKey::ArrowDown) => Some(Action::Orbit(0.0, -STEP)),
        Key::Named(NamedKey::PageUp) => Some(Action::Zoom(1.0 / 1.15)),
        Key::Named(NamedKey::PageDown) => Some(Action::Zoom(1.15)),
        Key::Named(NamedKey::Escape) => Some(Action::Quit),
        Key::Character(text) => text.chars().next().and_then(action_for_char),
        _ => None,
    }
}

// ---------------------------------------------------------------------------
// The window and its event loop.

struct App {
    args: Args,
    /// Taken by the viewer when the window opens.
    scene: Option<Scene>,
    viewer: Option<Viewer>,
    error: Option<String>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: impl std::fmt::Display) {
        if self.error.is_none() {
            self.error = Some(error.to_string());
        }
        self.shutdown();
        event_loop.exit();
    }

    fn shutdown(&mut self) {
        if let Some(viewer) = self.viewer.take() {
            viewer.destroy();
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        let Some(scene) = self.scene.take() else {
            return;
        };
        match Viewer::new(event_loop, &self.args, scene) {
            Ok(viewer) => {
                viewer.window.request_redraw();
                self.viewer = Some(viewer);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        match event {
            WindowEvent::CloseRequested => {
                self.shutdown();
                event_loop.exit();
            }
            WindowEvent::Resized(size) => viewer.resize(size),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                if let Some(action) = action_for_key(&event) {
                    if action == Action::Quit {
                        self.shutdown();
                        event_loop.exit();
                        return;
                    }
                    viewer.apply(action);
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => viewer.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => viewer.cursor_moved(position),
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                viewer.apply(Action::Zoom(1.1f32.powf(-lines)));
            }
            WindowEvent::RedrawRequested => match viewer.frame() {
                Ok(FrameOutcome::Continue) => {}
                Ok(FrameOutcome::Done) => {
                    self.shutdown();
                    event_loop.exit();
                }
                Err(e) => self.fail(event_loop, e),
            },
            _ => {}
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.shutdown();
    }
}

enum FrameOutcome {
    Continue,
    Done,
}

/// What is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
enum View {
    /// The final image.
    Final,
    /// Colour attachment `k` of the resolved G-buffer.
    Attachment(usize),
    /// The resolved depth, linearised.
    Depth,
    /// Pixels whose samples differ in depth (the ones the resolve blends).
    Complex,
}

/// An orbit camera around a target point.
#[derive(Clone, Copy, Debug)]
struct Orbit {
    target: Vec3,
    yaw: f32,
    pitch: f32,
    distance: f32,
    /// The scene's own camera, for the lens and for reset.
    base: Camera,
    base_distance: f32,
    radius: f32,
}

impl Orbit {
    fn new(scene: &Scene) -> Orbit {
        let base = scene.camera;
        let eye = base.position();
        let forward = base.forward();
        let radius = if scene.bounds.is_empty() {
            1.0
        } else {
            scene.bounds.radius().max(1e-3)
        };
        let along = (scene.bounds.center() - eye).dot(forward);
        let distance = if along.is_finite() && along > base.near {
            along
        } else {
            radius * 2.0
        };
        let target = eye + forward * distance;
        let offset = (eye - target) / distance;
        Orbit {
            target,
            yaw: offset.x.atan2(offset.z),
            pitch: offset.y.clamp(-1.0, 1.0).asin(),
            distance,
            base,
            base_distance: distance,
            radius,
        }
    }

    fn camera(&self) -> Camera {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let eye = self.target + Vec3::new(cp * sy, sp, cp * cy) * self.distance;
        let scale = self.distance / self.base_distance;
        let near = self.base.near * scale.min(1.0);
        let far = self
            .base
            .far
            .map(|f| f.max(self.distance + 2.0 * self.radius) * scale.max(1.0));
        Camera::look_at(eye, self.target, self.base.fov_y, near, far)
    }

    /// View distances the scene's bounding box covers, for the depth ramps.
    fn depth_range(&self, bounds: &Aabb) -> (f32, f32) {
        let camera = self.camera();
        let (mut near, mut far) = (f32::INFINITY, 0.0f32);
        for corner in bounds.corners() {
            let d = -camera.view.transform_point3(corner).z;
            near = near.min(d);
            far = far.max(d);
        }
        if !(near.is_finite() && far.is_finite()) {
            (near, far) = (self.distance - self.radius, self.distance + self.radius);
        }
        let near = near.max(camera.near);
        (near, far.max(near * 1.01))
    }
}

/// The window, its GL context, the renderer and the viewer's own state.
struct Viewer {
    // Declared (and so dropped) in this order: GL users, then the surface,
    // the context and the window.
    renderer: Renderer,
    presenter: Presenter,
    gl: glow::Context,
    surface: Surface<WindowSurface>,
    context: PossiblyCurrentContext,
    /// The display the context and the surface belong to, kept alive with them.
    _display: Display,
    window: Window,
    scene: Scene,
    options: RenderOptions,
    method: usize,
    /// 1 or 2: the resolved layers front, median and back run with.
    layers: u32,
    sample_counts: Vec<u32>,
    view: View,
    orbit: Orbit,
    camera_changed: bool,
    dragging: bool,
    cursor: Option<PhysicalPosition<f64>>,
    frame_ms: f64,
    frames_left: Option<u32>,
    frame_index: u32,
    /// Resident memory after the warm-up frames of a scripted run.
    resident_after_warmup: Option<u64>,
    screenshot: Option<PathBuf>,
    /// Save the next frame (the `P` key).
    screenshot_requested: bool,
    keys: std::vec::IntoIter<char>,
    last_action: Option<char>,
}

impl Viewer {
    fn new(event_loop: &ActiveEventLoop, args: &Args, scene: Scene) -> AnyResult<Viewer> {
        let raw_display = event_loop.display_handle()?.as_raw();
        // GLX first (needs the Xlib error hook winit installs), EGL on X11 otherwise.
        let preference = DisplayApiPreference::GlxThenEgl(Box::new(
            winit::platform::x11::register_xlib_error_hook,
        ));
        let display = unsafe { Display::new(raw_display, preference)? };
        let template = ConfigTemplateBuilder::new().with_alpha_size(8).build();
        let config: Config = unsafe { display.find_configs(template)? }
            .min_by_key(|c| (c.num_samples(), c.depth_size() + c.stencil_size()))
            .ok_or("the display offers no OpenGL configuration")?;
        let attributes = WindowAttributes::default()
            .with_title("deferred-msaa viewer")
            .with_inner_size(PhysicalSize::new(args.width, args.height));
        let window = glutin_winit::finalize_window(event_loop, attributes, &config)?;
        let raw_window = window.window_handle()?.as_raw();
        let context_attributes = ContextAttributesBuilder::new()
            .with_profile(GlProfile::Core)
            .with_context_api(ContextApi::OpenGl(Some(Version::new(3, 2))))
            .build(Some(raw_window));
        let not_current = unsafe { display.create_context(&config, &context_attributes) }
            .map_err(|e| format!("cannot create an OpenGL 3.2 core context: {e}"))?;
        let size = window.inner_size();
        let (w, h) = (
            NonZeroU32::new(size.width.max(1)).ok_or("zero width")?,
            NonZeroU32::new(size.height.max(1)).ok_or("zero height")?,
        );
        let surface_attributes =
            SurfaceAttributesBuilder::<WindowSurface>::new().build(raw_window, w, h);
        let surface = unsafe { display.create_window_surface(&config, &surface_attributes)? };
        let context = not_current.make_current(&surface)?;
        let interval = if args.frames.is_some() {
            SwapInterval::DontWait
        } else {
            SwapInterval::Wait(NonZeroU32::MIN)
        };
        // Not every driver lets the interval be chosen; the default is fine.
        let _ = surface.set_swap_interval(&context, interval);
        let gl = unsafe {
            glow::Context::from_loader_function_cstr(|name| display.get_proc_address(name))
        };
        let version = gl.version();
        if (version.major, version.minor) < (3, 2) {
            return Err(format!(
                "OpenGL {}.{} is below the 3.2 core floor",
                version.major, version.minor
            )
            .into());
        }

        let mut options = RenderOptions {
            width: w.get(),
            height: h.get(),
            samples: args.samples,
            aa: aa_mode(METHODS[args.method], args.layers),
            fxaa: args.fxaa,
            smaa: args.smaa.then(SmaaOptions::default),
            ..RenderOptions::default()
        };
        let sample_counts = sample_counts(&gl, &options);
        if !sample_counts.is_empty() && !sample_counts.contains(&options.samples) {
            let nearest = sample_counts
                .iter()
                .copied()
                .min_by_key(|&n| n.abs_diff(options.samples))
                .unwrap_or(options.samples);
            eprintln!(
                "viewer: {}x is not offered for every G-buffer format; using {nearest}x (offered: {sample_counts:?})",
                options.samples
            );
            options.samples = nearest;
        }
        let loader = |name: &str| {
            CString::new(name).map_or(std::ptr::null(), |c| display.get_proc_address(&c))
        };
        let renderer = Renderer::new(&gl, loader, &scene, &options)?;
        let presenter = match Presenter::new(&gl) {
            Ok(p) => p,
            Err(e) => {
                renderer.destroy(&gl);
                return Err(e);
            }
        };
        println!(
            "viewer: {} ({} triangles) on {} — press ? for keys",
            scene.name,
            scene.triangle_count(),
            unsafe { gl.get_parameter_string(glow::RENDERER) }
        );
        let orbit = Orbit::new(&scene);
        Ok(Viewer {
            renderer,
            presenter,
            gl,
            surface,
            context,
            _display: display,
            window,
            scene,
            options,
            method: args.method,
            layers: args.layers,
            sample_counts,
            view: View::Final,
            orbit,
            camera_changed: false,
            dragging: false,
            cursor: None,
            frame_ms: 0.0,
            frames_left: args.frames,
            frame_index: 0,
            resident_after_warmup: None,
            screenshot: args.screenshot.clone(),
            screenshot_requested: false,
            keys: args.keys.clone().into_iter(),
            last_action: None,
        })
    }

    fn destroy(self) {
        self.presenter.destroy(&self.gl);
        self.renderer.destroy(&self.gl);
    }

    fn views(&self) -> Vec<View> {
        let mut views = vec![View::Final];
        // The attachments the scene-adaptive plan kept.
        views.extend((0..self.renderer.layout().colors.len()).map(View::Attachment));
        views.extend([View::Depth, View::Complex]);
        views
    }

    fn view_name(&self, view: View) -> String {
        match view {
            View::Final => "final".into(),
            View::Attachment(k) => self.renderer.layout().colors[k].name.clone(),
            View::Depth => "depth".into(),
            View::Complex if self.renderer.retrofit().is_none() => "complex (needs MSAA)".into(),
            View::Complex => "complex".into(),
        }
    }

    /// Apply one user action; a failed option change keeps the old options.
    fn apply(&mut self, action: Action) {
        let mut options = self.options.clone();
        match action {
            Action::Method(i) => {
                self.method = i.min(METHODS.len() - 1);
                options.aa = aa_mode(METHODS[self.method], self.layers);
            }
            Action::StepMethod(step) => {
                self.method =
                    (self.method as isize + step).rem_euclid(METHODS.len() as isize) as usize;
                options.aa = aa_mode(METHODS[self.method], self.layers);
            }
            // Kept across method changes; only the layered methods use it.
            Action::ToggleLayers => {
                self.layers = 3 - self.layers;
                options.aa = aa_mode(METHODS[self.method], self.layers);
            }
            Action::NextSamples => {
                if let Some(i) = self
                    .sample_counts
                    .iter()
                    .position(|&n| n == options.samples)
                {
                    options.samples = self.sample_counts[(i + 1) % self.sample_counts.len()];
                } else if let Some(&first) = self.sample_counts.first() {
                    options.samples = first;
                }
            }
            // One post filter at a time: the renderer refuses both.
            Action::ToggleFxaa => {
                options.fxaa = !options.fxaa;
                options.smaa = None;
            }
            Action::ToggleSmaa => {
                options.smaa = match options.smaa {
                    Some(_) => None,
                    None => Some(SmaaOptions::default()),
                };
                options.fxaa = false;
            }
            Action::StepView(step) => {
                let views = self.views();
                let i = views.iter().position(|v| *v == self.view).unwrap_or(0) as isize;
                self.view = views[(i + step).rem_euclid(views.len() as isize) as usize];
            }
            Action::Orbit(yaw, pitch) => {
                self.orbit.yaw += yaw;
                self.orbit.pitch = (self.orbit.pitch + pitch).clamp(-1.5, 1.5);
                self.camera_changed = true;
            }
            Action::Zoom(factor) => {
                self.orbit.distance = (self.orbit.distance * factor).clamp(
                    self.orbit.base_distance * 0.05,
                    self.orbit.base_distance * 20.0,
                );
                self.camera_changed = true;
            }
            Action::ResetCamera => {
                self.orbit = Orbit::new(&self.scene);
                self.camera_changed = true;
            }
            Action::Screenshot => self.screenshot_requested = true,
            Action::Help => print_keys(),
            Action::Quit => {}
        }
        if options != self.options {
            match self.renderer.set_options(&self.gl, &options) {
                Ok(()) => self.options = options,
                Err(e) => eprintln!("viewer: {e}"),
            }
        }
        self.window.request_redraw();
    }

    fn cursor_moved(&mut self, position: PhysicalPosition<f64>) {
        if let (true, Some(last)) = (self.dragging, self.cursor) {
            let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
            self.apply(Action::Orbit(dx * 0.01, dy * 0.01));
        }
        self.cursor = Some(position);
    }

    fn resize(&mut self, size: PhysicalSize<u32>) {
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else {
            return; // minimised: keep everything as it is
        };
        self.surface.resize(&self.context, w, h);
        let options = RenderOptions {
            width: w.get(),
            height: h.get(),
            ..self.options.clone()
        };
        if options != self.options {
            match self.renderer.set_options(&self.gl, &options) {
                Ok(()) => self.options = options,
                Err(e) => eprintln!("viewer: cannot resize to {}x{}: {e}", w, h),
            }
        }
        self.window.request_redraw();
    }

    /// Point the renderer at the orbit camera. Nothing is rebuilt, so
    /// `taa` reprojects its history from the camera of the frame before,
    /// as it would in a game.
    fn update_camera(&mut self) {
        if !self.camera_changed {
            return;
        }
        self.camera_changed = false;
        self.renderer.set_camera(self.orbit.camera());
    }

    /// Render and present one frame.
    fn frame(&mut self) -> AnyResult<FrameOutcome> {
        if self.frames_left.is_some() {
            if let Some(c) = self.keys.next() {
                let action = action_for_char(c).ok_or_else(|| format!("--keys: no key `{c}`"))?;
                self.apply(action);
                self.last_action = Some(c);
            }
        }
        self.update_camera();
        let start = Instant::now();
        self.renderer.render(&self.gl)?;
        let size = self.window.inner_size();
        let range = self.orbit.depth_range(&self.scene.bounds);
        self.presenter
            .draw(&self.gl, &self.renderer, self.view, range, size)?;
        let elapsed = start.elapsed().as_secs_f64() * 1000.0;
        self.frame_ms = if self.frame_index == 0 {
            elapsed
        } else {
            0.8 * self.frame_ms + 0.2 * elapsed
        };
        self.frame_index += 1;

        let mut outcome = FrameOutcome::Continue;
        let mut save = std::mem::take(&mut self.screenshot_requested);
        if let Some(left) = self.frames_left.as_mut() {
            let image = read_back_buffer(&self.gl, size.width, size.height)?;
            let first = image.get_pixel(0, 0);
            if image.pixels().all(|p| p == first) {
                return Err(format!(
                    "frame {} is blank{}",
                    self.frame_index,
                    self.last_action
                        .map(|c| format!(" (after key `{c}`)"))
                        .unwrap_or_default()
                )
                .into());
            }
            *left -= 1;
            // After every mode has been built once, memory should stay flat.
            if self.frame_index == WARMUP_FRAMES {
                self.resident_after_warmup = Some(resident_bytes());
            }
            if *left == 0 {
                save = self.screenshot.is_some();
                outcome = FrameOutcome::Done;
                if let Some(start) = self.resident_after_warmup {
                    let grown = resident_bytes() as i64 - start as i64;
                    println!(
                        "viewer: resident memory changed by {} KiB from frame {WARMUP_FRAMES} to frame {}",
                        grown / 1024,
                        self.frame_index
                    );
                }
            }
        }
        if save {
            let path = self
                .screenshot
                .clone()
                .unwrap_or_else(|| PathBuf::from("target/viewer.png"));
            let image = read_back_buffer(&self.gl, size.width, size.height)?;
            let written = path
                .parent()
                .map_or(Ok(()), std::fs::create_dir_all)
                .map_err(|e| e.to_string())
                .and_then(|()| image.save(&path).map_err(|e| e.to_string()));
            match written {
                Ok(()) => println!("viewer: {} -> {}", self.title(), path.display()),
                // A failed interactive screenshot is reported, not fatal.
                Err(e) if self.frames_left.is_none() => {
                    eprintln!("viewer: cannot write {}: {e}", path.display())
                }
                Err(e) => return Err(format!("cannot write {}: {e}", path.display()).into()),
            }
        }
        self.surface.swap_buffers(&self.context)?;
        self.window.set_title(&self.title());
        if self.frames_left.is_some() && matches!(outcome, FrameOutcome::Continue) {
            self.window.request_redraw();
        }
        Ok(outcome)
    }

    fn title(&self) -> String {
        let method = self.options.aa.name();
        let layers = if matches!(&self.options.aa, AaMode::Resolve(s) if s.layers == 2) {
            ":layers=2"
        } else {
            ""
        };
        let samples = match self.renderer.samples() {
            1 => String::new(),
            n => format!(" {n}x"),
        };
        let fxaa = if self.options.fxaa {
            " + FXAA"
        } else if self.options.smaa.is_some() {
            " + SMAA"
        } else {
            ""
        };
        format!(
            "deferred-msaa — {} — {method}{layers}{samples}{fxaa} — view: {} — {:.1} ms",
            self.scene.name,
            self.view_name(self.view),
            self.frame_ms
        )
    }
}

/// `method` with `layers` resolved layers where it has a second
/// (front, median and back).
fn aa_mode(method: &str, layers: u32) -> AaMode {
    let layered = matches!(method, "front" | "median" | "back") && layers == 2;
    let spec = if layered {
        format!("{method}:layers=2")
    } else {
        method.to_string()
    };
    // The list holds the registry's own method names, which parse, with
    // an option every resolve method but average takes.
    spec.parse()
        .unwrap_or_else(|e| panic!("the viewer's method `{spec}`: {e}"))
}

/// The sample counts every attachment of the layout really gets.
fn sample_counts(gl: &glow::Context, options: &RenderOptions) -> Vec<u32> {
    let layout = &options.layout;
    let mut formats: Vec<_> = layout.colors.iter().map(|a| a.format).collect();
    formats.push(layout.depth);
    let mut counts = Capabilities::sample_counts_for(gl, layout.depth);
    for format in formats {
        let offered = Capabilities::sample_counts_for(gl, format);
        counts.retain(|n| offered.contains(n));
    }
    counts
}

/// The default framebuffer's back buffer, top row first.
fn read_back_buffer(gl: &glow::Context, width: u32, height: u32) -> AnyResult<image::RgbaImage> {
    let row = width as usize * 4;
    let mut pixels = vec![0u8; row * height as usize];
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        gl.read_buffer(glow::BACK);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.read_pixels(
            0,
            0,
            width as i32,
            height as i32,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelPackData::Slice(Some(&mut pixels)),
        );
        match gl.get_error() {
            glow::NO_ERROR => {}
            code => return Err(format!("GL error 0x{code:04X} reading the window").into()),
        }
    }
    let rows: Vec<u8> = pixels.chunks_exact(row).rev().flatten().copied().collect();
    image::RgbaImage::from_raw(width, height, rows).ok_or_else(|| "window size mismatch".into())
}

// ---------------------------------------------------------------------------
// Drawing a view into the window.

/// One texel of the chosen texture per window pixel, made readable.
const PRESENT_FRAG: &str = r#"
uniform sampler2D u_image;
uniform vec2 u_window;
uniform int u_mode;       // 0 as is, 1 linear colour, 2 position, 3 normal, 4 HDR, 5 depth
uniform vec4 u_depth;     // p22, p23, zero_to_one, clear depth
uniform vec2 u_range;     // view distances mapped to white .. dark grey
out vec4 o_color;

vec3 srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

// Near: warm white, far: dark blue, with a soft band every 1/6 of the range.
vec3 ramp(float dist) {
    float t = clamp((dist - u_range.x) / max(u_range.y - u_range.x, 1e-6), 0.0, 1.0);
    float contour = 0.85 + 0.15 * cos(6.2831853 * 6.0 * t);
    return mix(vec3(1.0, 0.9, 0.7), vec3(0.05, 0.1, 0.4), sqrt(t)) * contour;
}

void main() {
    ivec2 size = textureSize(u_image, 0);
    ivec2 p = clamp(ivec2(gl_FragCoord.xy * vec2(size) / u_window), ivec2(0), size - 1);
    vec4 t = texelFetch(u_image, p, 0);
    vec3 c = t.rgb;
    if (u_mode == 1) {
        c = srgb(t.rgb);
    } else if (u_mode == 2) {
        c = t.w == 0.0 ? vec3(0.0) : ramp(-t.z);
    } else if (u_mode == 3) {
        c = dot(t.xyz, t.xyz) < 0.25 ? vec3(0.0) : normalize(t.xyz) * 0.5 + 0.5;
    } else if (u_mode == 4) {
        vec3 x = max(mix(t.rgb, vec3(0.0), isnan(t.rgb)), vec3(0.0));
        c = srgb(x / (1.0 + x));
    } else if (u_mode == 5) {
        float d = t.r;
        float z_ndc = u_depth.z > 0.5 ? d : 2.0 * d - 1.0;
        c = d == u_depth.w ? vec3(0.0) : ramp(u_depth.y / (z_ndc + u_depth.x));
    }
    o_color = vec4(c, 1.0);
}
"#;

/// The final image in grey, with the pixels whose samples differ in their
/// depth key in orange: where the resolve has work to do. It follows
/// `complex.glsl` ([`COMPLEX_GLSL`]), composed in front of it.
const COMPLEX_FRAG: &str = r#"
uniform sampler2D u_image;
uniform sampler2DMS u_key;
uniform int u_samples;
uniform int u_component;  // 0: depth (r), 2: view-space position (z)
uniform vec2 u_window;
out vec4 o_color;

float key(ivec2 p, int i) {
    vec4 v = texelFetch(u_key, p, i);
    return u_component == 0 ? v.r : v.z;
}

void main() {
    ivec2 size = textureSize(u_image, 0);
    ivec2 p = clamp(ivec2(gl_FragCoord.xy * vec2(size) / u_window), ivec2(0), size - 1);
    bool complex = false;
    float first = key(p, 0);
    for (int i = 1; i < u_samples; ++i) {
        // No depth samples here to tell background by (with a position key),
        // so every sample counts as geometry: the view stays as it was.
        complex = complex || !dmsaa_same_surface(false, key(p, i), false, first);
    }
    vec3 c = texelFetch(u_image, p, 0).rgb;
    float grey = dot(c, vec3(0.299, 0.587, 0.114)) * 0.7;
    o_color = vec4(complex ? vec3(1.0, 0.45, 0.05) : vec3(grey), 1.0);
}
"#;

struct Presenter {
    view: FullscreenPass,
    complex: FullscreenPass,
    vao: VertexArray,
}

impl Presenter {
    fn new(gl: &glow::Context) -> AnyResult<Presenter> {
        let present = ShaderSource::new().part("viewer present.frag", PRESENT_FRAG);
        let complex = ShaderSource::new()
            .part(COMPLEX_GLSL_NAME, COMPLEX_GLSL)
            .part("viewer complex.frag", COMPLEX_FRAG);
        let outputs = [("o_color", 0)];
        let presenter = Made::build(gl, |made| -> deferred_msaa_lab::Result<Presenter> {
            Ok(Presenter {
                view: made.keep(FullscreenPass::new(
                    gl,
                    "viewer present",
                    &present,
                    &outputs,
                )?),
                complex: made.keep(FullscreenPass::new(
                    gl,
                    "viewer complex",
                    &complex,
                    &outputs,
                )?),
                vao: made.keep(VertexArray::new(gl, "viewer vao")?),
            })
        })?;
        Ok(presenter)
    }

    /// Draw `view` of the renderer's last frame into the window's back buffer.
    fn draw(
        &self,
        gl: &glow::Context,
        renderer: &Renderer,
        view: View,
        depth_range: (f32, f32),
        window: PhysicalSize<u32>,
    ) -> AnyResult<()> {
        let gbuffer = renderer.gbuffer();
        let layout = renderer.layout();
        let final_texture = renderer.final_texture().raw();
        // The complex view needs the multisampled key; without MSAA it shows the final image.
        let complex_key = match (view, renderer.retrofit()) {
            (View::Complex, Some(retrofit)) => {
                let (depth, colors, _) = retrofit.inputs()?;
                match retrofit.key() {
                    KeySource::Position(ResolveSlot(k))
                    | KeySource::WorldPosition(ResolveSlot(k)) => {
                        colors.get(k).map(|t| (t.raw(), 2, retrofit.samples()))
                    }
                    KeySource::Depth => Some((depth.raw(), 0, retrofit.samples())),
                }
            }
            _ => None,
        };
        let (texture, mode) = match view {
            View::Final | View::Complex => (final_texture, 0),
            View::Attachment(k) => {
                let mode = match layout.colors[k].name.as_str() {
                    "position" => 2,
                    "normal" => 3,
                    "emissive" => 4,
                    _ => 1,
                };
                (gbuffer.colors[k].raw(), mode)
            }
            View::Depth => (gbuffer.depth.raw(), 5),
        };
        let (near, far) = depth_range;
        let clear = renderer.clear_depth() as f64;
        let depth = DepthProjection::from_matrix(
            &renderer.projection().as_dmat4().to_cols_array(),
            clear == 0.0,
            clear,
        );
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.viewport(0, 0, window.width as i32, window.height as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.color_mask(true, true, true, true);
        }
        let program = if complex_key.is_some() {
            self.complex.program()
        } else {
            self.view.program()
        };
        program.bind(gl);
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(texture));
        }
        program.set_i32(gl, "u_image", 0);
        program.set_vec2(gl, "u_window", [window.width as f32, window.height as f32]);
        if let Some((key, component, samples)) = complex_key {
            unsafe {
                gl.active_texture(glow::TEXTURE1);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(key));
            }
            program.set_i32(gl, "u_key", 1);
            program.set_i32(gl, "u_samples", samples as i32);
            program.set_i32(gl, "u_component", component);
        } else {
            program.set_i32(gl, "u_mode", mode);
            program.set_vec4(
                gl,
                "u_depth",
                [
                    depth.p22 as f32,
                    depth.p23 as f32,
                    depth.zero_to_one as i32 as f32,
                    depth.clear_depth as f32,
                ],
            );
            program.set_vec2(gl, "u_range", [near, far]);
        }
        draw_fullscreen_triangle(gl, &self.vao);
        unsafe {
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.use_program(None);
        }
        Ok(check_error(gl, "drawing the view")?)
    }

    fn destroy(self, gl: &glow::Context) {
        self.view.destroy(gl);
        self.complex.destroy(gl);
        self.vao.destroy(gl);
    }
}
