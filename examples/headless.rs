//! The shortest path from a glTF file to an anti-aliased PNG, through the
//! library API alone: a headless EGL context, the built-in deferred renderer
//! with 4x depth-aware MSAA (median reference, smooth window), one frame.
//!
//! ```sh
//! cargo run --release --example headless -- MODEL.gltf [OUT.png] [WIDTHxHEIGHT]
//! ```
//! `MODEL` may also be a built-in scene such as `builtin:greebles`. The image
//! goes to `target/headless.png` unless a path is given.

use std::error::Error;
use std::process::ExitCode;

use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::renderer::{RenderOptions, Renderer};
use deferred_msaa_lab::scene::Scene;

fn run() -> Result<(), Box<dyn Error>> {
    // Three positional arguments, read by hand rather than by clap, so that
    // the example stays the shortest path.
    let mut args = std::env::args().skip(1);
    let model = args
        .next()
        .ok_or("usage: headless MODEL.gltf [OUT.png] [WIDTHxHEIGHT]")?;
    let out = args.next().unwrap_or_else(|| "target/headless.png".into());
    let mut options = RenderOptions::default(); // 640x360, 4x MSAA, median resolve
    if let Some(size) = args.next() {
        let parsed = size
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
        (options.width, options.height) =
            parsed.ok_or_else(|| format!("expected a size such as 640x360, got `{size}`"))?;
    }

    let scene = Scene::load(&model)?;
    let context = HeadlessContext::new(Backend::Egl)?;
    let gl = context.gl();
    let mut renderer = Renderer::new(gl, |name| context.get_proc_address(name), &scene, &options)?;
    renderer.render(gl)?;
    let image = renderer.read_final(gl)?;
    let samples = renderer.samples(); // what the driver really gave
    renderer.destroy(gl);

    if let Some(dir) = std::path::Path::new(&out).parent() {
        std::fs::create_dir_all(dir)?;
    }
    image
        .save(&out)
        .map_err(|e| format!("cannot write {out}: {e}"))?;
    println!("{}: {samples}x MSAA -> {out}", scene.name);
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("headless: {e}");
            ExitCode::FAILURE
        }
    }
}
