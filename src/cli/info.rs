//! `deferred-msaa info`: what the context offers.

use super::common::CommonArgs;
use crate::Result;
use crate::context::{Backend, HeadlessContext};
use crate::gl::{Capabilities, ExtraFns, Format, sample_positions};
use serde_json::{Map, Value, json};
use std::io::Write;

/// Arguments of `info`.
#[derive(Debug, Clone, clap::Args)]
pub struct InfoArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Print JSON (keys: backend, gl_version, glsl_version, renderer, max_samples,
    /// sample_counts, sample_positions).
    #[arg(long)]
    json: bool,
}

impl Default for InfoArgs {
    fn default() -> Self {
        InfoArgs {
            common: CommonArgs {
                backend: Backend::Egl,
            },
            json: false,
        }
    }
}

/// The formats `info` reports sample counts for: the G-buffer's.
const REPORTED_FORMATS: &[Format] = &[
    Format::Rgba8,
    Format::Rgba16f,
    Format::Rgba32f,
    Format::R32f,
    Format::Rgba8ui,
    Format::Depth24,
    Format::Depth32f,
    Format::Depth24Stencil8,
];

/// Gather the report as JSON.
pub fn report(ctx: &HeadlessContext) -> Result<Value> {
    let gl = ctx.gl();
    let caps = Capabilities::query(gl);
    let extra = ExtraFns::load(gl, |name| ctx.get_proc_address(name));
    let mut counts = Map::new();
    let mut all_counts: Vec<u32> = Vec::new();
    for &format in REPORTED_FORMATS {
        let c = Capabilities::sample_counts_for(gl, format);
        for &n in &c {
            if !all_counts.contains(&n) {
                all_counts.push(n);
            }
        }
        counts.insert(format.name().to_string(), json!(c));
    }
    all_counts.sort_unstable();
    let mut positions = Map::new();
    for n in all_counts {
        let (real, pos) = sample_positions(gl, &extra, n)?;
        positions.insert(real.to_string(), json!(pos));
    }
    Ok(json!({
        "backend": ctx.backend().name(),
        "gl_version": caps.gl_version,
        "glsl_version": caps.glsl_version,
        "renderer": caps.renderer,
        "vendor": caps.vendor,
        "max_samples": caps.max_samples,
        "max_texture_size": caps.max_texture_size,
        "timer_query": caps.timer_query,
        "clip_control": caps.clip_control,
        "sample_counts": counts,
        "sample_positions": positions,
    }))
}

/// Run `info`.
pub fn run(args: &InfoArgs) -> Result<()> {
    let mut ctx = HeadlessContext::new(args.common.backend)?;
    // Driver messages (KHR_debug) go to the log: RUST_LOG=gl=debug shows them.
    crate::gl::install_debug_log(ctx.gl_mut());
    let r = report(&ctx)?;
    if args.json {
        let text =
            serde_json::to_string_pretty(&r).map_err(|e| crate::Error::invalid(e.to_string()))?;
        // A closed pipe (`| head`) is not an error worth a message.
        let _ = writeln!(std::io::stdout(), "{text}");
        return Ok(());
    }
    println!("backend       {}", r["backend"].as_str().unwrap_or(""));
    println!("renderer      {}", r["renderer"].as_str().unwrap_or(""));
    println!("GL            {}", r["gl_version"].as_str().unwrap_or(""));
    println!("GLSL          {}", r["glsl_version"].as_str().unwrap_or(""));
    println!("max samples   {}", r["max_samples"]);
    if let Some(counts) = r["sample_counts"].as_object() {
        for (format, c) in counts {
            println!("  {format:<20} {c}");
        }
    }
    if let Some(pos) = r["sample_positions"].as_object() {
        for (n, p) in pos {
            println!("positions {n}x  {p}");
        }
    }
    Ok(())
}
