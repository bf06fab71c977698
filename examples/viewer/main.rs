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

mod controls;
mod present;
mod view;

use std::error::Error;
use std::process::ExitCode;

use deferred_msaa_lab::cli::{Printed, parse_args};
use deferred_msaa_lab::scene::Scene;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::WindowId;

type AnyResult<T> = Result<T, Box<dyn Error>>;
use controls::*;
use view::*;

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
