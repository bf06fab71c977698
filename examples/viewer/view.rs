//! The viewer's state: the renderer, its options, the orbit camera and the
//! frame loop's outcome, and what each action changes.

use std::error::Error;
use std::ffi::CString;
use std::num::NonZeroU32;
use std::path::PathBuf;
use std::time::Instant;

use deferred_msaa_lab::gl::Capabilities;
use deferred_msaa_lab::renderer::{AaMode, RenderOptions, Renderer, SmaaOptions};
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
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowAttributes};

type AnyResult<T> = Result<T, Box<dyn Error>>;
use crate::controls::*;
use crate::present::*;

pub(crate) enum FrameOutcome {
    Continue,
    Done,
}

/// An orbit camera around a target point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Orbit {
    pub(crate) target: Vec3,
    pub(crate) yaw: f32,
    pub(crate) pitch: f32,
    pub(crate) distance: f32,
    /// The scene's own camera, for the lens and for reset.
    pub(crate) base: Camera,
    pub(crate) base_distance: f32,
    pub(crate) radius: f32,
}

impl Orbit {
    pub(crate) fn new(scene: &Scene) -> Orbit {
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

    pub(crate) fn camera(&self) -> Camera {
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
    pub(crate) fn depth_range(&self, bounds: &Aabb) -> (f32, f32) {
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
pub(crate) struct Viewer {
    // Declared (and so dropped) in this order: GL users, then the surface,
    // the context and the window.
    pub(crate) renderer: Renderer,
    pub(crate) presenter: Presenter,
    pub(crate) gl: glow::Context,
    pub(crate) surface: Surface<WindowSurface>,
    pub(crate) context: PossiblyCurrentContext,
    /// The display the context and the surface belong to, kept alive with them.
    pub(crate) _display: Display,
    pub(crate) window: Window,
    pub(crate) scene: Scene,
    pub(crate) options: RenderOptions,
    pub(crate) method: usize,
    /// 1 or 2: the resolved layers front, median and back run with.
    pub(crate) layers: u32,
    pub(crate) sample_counts: Vec<u32>,
    pub(crate) view: View,
    pub(crate) orbit: Orbit,
    pub(crate) camera_changed: bool,
    pub(crate) dragging: bool,
    pub(crate) cursor: Option<PhysicalPosition<f64>>,
    pub(crate) frame_ms: f64,
    pub(crate) frames_left: Option<u32>,
    pub(crate) frame_index: u32,
    /// Resident memory after the warm-up frames of a scripted run.
    pub(crate) resident_after_warmup: Option<u64>,
    pub(crate) screenshot: Option<PathBuf>,
    /// Save the next frame (the `P` key).
    pub(crate) screenshot_requested: bool,
    pub(crate) keys: std::vec::IntoIter<char>,
    pub(crate) last_action: Option<char>,
}

impl Viewer {
    pub(crate) fn new(
        event_loop: &ActiveEventLoop,
        args: &Args,
        scene: Scene,
    ) -> AnyResult<Viewer> {
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

    pub(crate) fn destroy(self) {
        self.presenter.destroy(&self.gl);
        self.renderer.destroy(&self.gl);
    }

    pub(crate) fn views(&self) -> Vec<View> {
        let mut views = vec![View::Final];
        // The attachments the scene-adaptive plan kept.
        views.extend((0..self.renderer.layout().colors.len()).map(View::Attachment));
        views.extend([View::Depth, View::Complex]);
        views
    }

    pub(crate) fn view_name(&self, view: View) -> String {
        match view {
            View::Final => "final".into(),
            View::Attachment(k) => self.renderer.layout().colors[k].name.clone(),
            View::Depth => "depth".into(),
            View::Complex if self.renderer.retrofit().is_none() => "complex (needs MSAA)".into(),
            View::Complex => "complex".into(),
        }
    }

    /// Apply one user action; a failed option change keeps the old options.
    pub(crate) fn apply(&mut self, action: Action) {
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

    pub(crate) fn cursor_moved(&mut self, position: PhysicalPosition<f64>) {
        if let (true, Some(last)) = (self.dragging, self.cursor) {
            let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
            self.apply(Action::Orbit(dx * 0.01, dy * 0.01));
        }
        self.cursor = Some(position);
    }

    pub(crate) fn resize(&mut self, size: PhysicalSize<u32>) {
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
    pub(crate) fn update_camera(&mut self) {
        if !self.camera_changed {
            return;
        }
        self.camera_changed = false;
        self.renderer.set_camera(self.orbit.camera());
    }

    /// Render and present one frame.
    pub(crate) fn frame(&mut self) -> AnyResult<FrameOutcome> {
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

    pub(crate) fn title(&self) -> String {
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
pub(crate) fn aa_mode(method: &str, layers: u32) -> AaMode {
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
pub(crate) fn sample_counts(gl: &glow::Context, options: &RenderOptions) -> Vec<u32> {
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
pub(crate) fn read_back_buffer(
    gl: &glow::Context,
    width: u32,
    height: u32,
) -> AnyResult<image::RgbaImage> {
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
