//! `deferred-msaa bench`: error against run time for every method, in one run.

use super::common::CommonArgs;
use crate::bench::{self, BenchConfig, DEFAULT_SCENES};
use crate::gbuffer::GBufferLayout;
use crate::scene::MotionSpec;
use crate::{Error, Result};
use std::io::IsTerminal;
use std::path::PathBuf;

/// Arguments of `bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchCmd {
    #[command(flatten)]
    common: CommonArgs,
    /// A scene to measure: `builtin:NAME` or a .gltf/.glb path; repeat for
    /// more (default: builtin:hull and builtin:halo).
    #[arg(long = "scene", value_name = "S")]
    scenes: Vec<String>,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel for the multisampled methods; repeat for more (default 4).
    #[arg(long = "samples", value_name = "N")]
    samples: Vec<u32>,
    /// Comma-separated method entries, e.g. `none,median:hard,median+fxaa`
    /// (default: none,none+fxaa,average,front,median,back,upper-median,median:hard,
    /// median:nofast,median+fxaa,gbaa,smaa,median+smaa, then per-sample, complex and sparse
    /// where the context has what they need). Options: `:hard`, `:c=F`,
    /// `:c_in=F`, `:nofast`, `:full` (the whole layout, not the plan's),
    /// `sparse:pool=N`, `smaa:preset=P:edges=E`; `+fxaa` or `+smaa` (with
    /// the same options) after any entry.
    #[arg(long, value_name = "LIST")]
    methods: Option<String>,
    /// Point lights to add around each scene.
    #[arg(long, default_value_t = 0, value_name = "N")]
    lights: u32,
    /// Timed frames per method (the median is reported).
    #[arg(long, default_value_t = 9, value_name = "K")]
    frames: u32,
    /// Untimed frames per method first.
    #[arg(long, default_value_t = 3, value_name = "W")]
    warmup: u32,
    /// Use FreeSpace Open's G-buffer layout (FP16 position, D24) instead of the recommended one.
    #[arg(long)]
    fso_layout: bool,
    /// Also write every measured image (and the reference) into DIR/images/.
    #[arg(long)]
    images: bool,
    /// After the timed frames, time each step of the retrofit (and the
    /// renderer's second-layer passes) between glFinish calls over as many
    /// frames again, and print each step's median (`profile` in report.json).
    #[arg(long)]
    profile: bool,
    /// Render a camera path around the scene's camera instead of still
    /// frames: `pan`, `orbit` or `dolly`, with `:frames=N` (default 24)
    /// and `px=F`, the mean image motion per frame (default 0.5), e.g.
    /// `orbit:frames=48,px=0.5`. Every method renders every frame against
    /// the reference of each; --frames does not apply (docs/motion.md).
    #[arg(long, value_name = "SPEC", value_parser = parse_motion)]
    motion: Option<MotionSpec>,
    /// The folder to write report.json, report.md, error_vs_time.png and crops.png into.
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

fn parse_motion(s: &str) -> std::result::Result<MotionSpec, String> {
    s.parse().map_err(|e: Error| e.to_string())
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    bench::parse_size(s).map_err(|e| e.to_string())
}

impl BenchCmd {
    fn config(&self) -> Result<BenchConfig> {
        let methods = match &self.methods {
            Some(list) => bench::parse_methods(list)?,
            None => bench::default_methods(),
        };
        let config = BenchConfig {
            backend: self.common.backend,
            scenes: if self.scenes.is_empty() {
                DEFAULT_SCENES.iter().map(|s| s.to_string()).collect()
            } else {
                self.scenes.clone()
            },
            width: self.size.0,
            height: self.size.1,
            samples: if self.samples.is_empty() {
                vec![4]
            } else {
                self.samples.clone()
            },
            methods,
            lights: self.lights,
            frames: self.frames,
            warmup: self.warmup,
            layout: if self.fso_layout {
                GBufferLayout::freespace_open()
            } else {
                GBufferLayout::recommended()
            },
            progress: std::io::stderr().is_terminal(),
            profile: self.profile,
            motion: self.motion,
        };
        config.validate()?;
        Ok(config)
    }
}

/// Run `bench`.
pub fn run(cmd: &BenchCmd) -> Result<()> {
    let dir = cmd.report.clone().ok_or_else(|| {
        Error::invalid(
            "bench needs --report DIR, the folder to write report.json, report.md, \
             error_vs_time.png and crops.png into",
        )
    })?;
    let config = cmd.config()?;
    bench::prepare_output_dir(&dir)?;
    let output = bench::run(&config)?;
    bench::write_outputs(&output, &dir)?;
    if cmd.images {
        bench::write_images(&output, &dir)?;
    }
    for r in &output.report.runs {
        let mut line = format!(
            "{} {} {}x: {:.2} ms (AA {:.2} ms), FLIP {:.4}",
            r.scene, r.method, r.samples, r.ms_total, r.ms_aa, r.flip_mean
        );
        if let (Some(edges), Some(interior)) = (r.flip_edges, r.flip_interior) {
            line.push_str(&format!(" (edges {edges:.4}, interior {interior:.4})"));
        }
        line.push_str(&format!(", halo {}", r.halo_pixels));
        if let Some(error) = r.bar_width_error_px {
            line.push_str(&format!(", bar width {error:+.3} px"));
        }
        if let Some(m) = &r.motion {
            line.push_str(&format!(
                "; in motion: FLIP {:.4} (worst {:.4}), temporal error {:.5}",
                m.flip_mean, m.flip_worst, m.temporal_error
            ));
            if let Some(j) = m.bar_width_jitter_px {
                line.push_str(&format!(", bar jitter {j:.3} px"));
            }
        }
        println!("{line}");
        for step in r.profile.iter().flatten() {
            println!("    {:>8.2} ms  {}", step.ms, step.step);
        }
    }
    let mut written = String::from("report.json, report.md, error_vs_time.png, crops.png");
    if output.report.motion.is_some() {
        written.push_str(", temporal_error_vs_time.png");
        for (scene, _) in &output.animations {
            written.push_str(&format!(", {}", bench::motion_strip_name(scene)));
        }
    }
    println!("report -> {} ({written})", dir.display());
    Ok(())
}
