//! `deferred-msaa render` and `deferred-msaa dump`.

use super::CommonArgs;
use crate::context::HeadlessContext;
use crate::gbuffer::GBufferLayout;
use crate::gl::TextureRef;
use crate::readback::{Readback, SampleImage};
use crate::renderer::{AaMode, DepthMode, RenderOptions, Renderer};
use crate::resolve::{ResolveMethod, ResolveSettings, Window};
use crate::scene::Scene;
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Options shared by `render` and `dump`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// `builtin:NAME` or a path to a .gltf/.glb file.
    #[arg(long, default_value = "builtin:greebles")]
    scene: String,
    /// Framebuffer size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel (the driver's real count is used and reported).
    #[arg(long, default_value_t = 4)]
    samples: u32,
    /// none, average, front, median or back.
    #[arg(long, default_value = "median")]
    method: String,
    /// Closeness window: hard or smooth.
    #[arg(long, default_value = "smooth")]
    window: String,
    /// Outer window width in pixel footprints.
    #[arg(long, default_value_t = 5.0)]
    c: f64,
    /// Inner width of the smooth window.
    #[arg(long = "c-in", default_value_t = 2.5)]
    c_in: f64,
    /// Resolve uniform pixels the slow way too.
    #[arg(long)]
    no_fast_path: bool,
    /// Apply the crate's FXAA after tonemapping.
    #[arg(long)]
    fxaa: bool,
    /// Use FreeSpace Open's G-buffer layout (FP16 position, D24) instead of the recommended one.
    #[arg(long)]
    fso_layout: bool,
    /// What to write: final, an attachment name, depth.
    #[arg(long, default_value = "final")]
    view: String,
}

/// Arguments of `render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderCmd {
    #[command(flatten)]
    render: RenderArgs,
    /// The PNG to write (default: target/deferred-msaa/render.png).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Arguments of `dump`.
#[derive(Debug, Clone, clap::Args)]
pub struct DumpCmd {
    #[command(flatten)]
    render: RenderArgs,
    /// The folder to write the arrays, final.png and meta.json into.
    #[arg(long)]
    out: PathBuf,
}

impl RenderCmd {
    /// `render` with every option at its default.
    pub fn default_scene() -> Result<Self> {
        use clap::Parser;
        #[derive(Parser)]
        struct Only {
            #[command(flatten)]
            cmd: RenderCmd,
        }
        // Parsing no arguments yields exactly the documented defaults.
        Only::try_parse_from(["render"])
            .map(|o| o.cmd)
            .map_err(|e| Error::invalid(e.to_string()))
    }
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: width is not a number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: height is not a number"))?;
    if w == 0 || h == 0 {
        return Err(format!("`{s}`: width and height must be at least 1"));
    }
    Ok((w, h))
}

const METHODS: &str = "none, average, front, median, back";

impl RenderArgs {
    fn options(&self) -> Result<RenderOptions> {
        let aa = if self.method == "none" {
            AaMode::None
        } else {
            let method: ResolveMethod = self.method.parse().map_err(|_| {
                Error::invalid(format!(
                    "unknown method `{}`; available: {METHODS}",
                    self.method
                ))
            })?;
            let window: Window = self.window.parse()?;
            let settings = ResolveSettings {
                method,
                window,
                c: self.c,
                c_in: self.c_in,
                fast_path: !self.no_fast_path,
                blend_depth: false,
            };
            settings.validate()?;
            AaMode::Resolve(settings)
        };
        if self.samples == 0 {
            return Err(Error::invalid("--samples must be at least 1"));
        }
        Ok(RenderOptions {
            width: self.size.0,
            height: self.size.1,
            samples: self.samples,
            aa,
            fxaa: self.fxaa,
            layout: if self.fso_layout {
                GBufferLayout::freespace_open()
            } else {
                GBufferLayout::recommended()
            },
            depth_mode: DepthMode::Auto,
        })
    }
}

/// A rendered frame, kept alive with its context.
struct Session {
    ctx: HeadlessContext,
    renderer: Option<Renderer>,
}

impl Session {
    fn open(args: &RenderArgs) -> Result<Session> {
        let options = args.options()?;
        let scene = Scene::load(&args.scene)?;
        for w in &scene.warnings {
            log::warn!("{}: {w}", args.scene);
        }
        let mut ctx = HeadlessContext::new(args.common.backend)?;
        // Driver messages (KHR_debug) go to the log: RUST_LOG=gl=debug shows them.
        crate::gl::install_debug_log(ctx.gl_mut());
        // The renderer logs its precision warnings (log::warn!) itself.
        let loader = |name: &str| ctx.get_proc_address(name);
        let mut renderer = Renderer::new(ctx.gl(), loader, &scene, &options)?;
        renderer.render(ctx.gl())?;
        Ok(Session {
            ctx,
            renderer: Some(renderer),
        })
    }

    fn renderer(&self) -> Result<&Renderer> {
        self.renderer
            .as_ref()
            .ok_or_else(|| Error::invalid("the renderer is gone"))
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        if let Some(r) = self.renderer.take() {
            r.destroy(self.ctx.gl());
        }
    }
}

/// Map a view's float values to an 8-bit image for looking at.
fn view_image(img: &SampleImage, view: &str, channels: u32) -> image::RgbaImage {
    let (w, h) = (img.width, img.height);
    let plane = img.plane(0);
    let finite = plane.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    image::RgbaImage::from_fn(w, h, |x, y| {
        let i = ((y * w + x) * 4) as usize;
        let v = &plane[i..i + 4];
        let map = |c: f32| -> u8 {
            let t = match view {
                "normal" => c * 0.5 + 0.5,
                "position" | "depth" => {
                    if hi > lo {
                        (c - lo) / (hi - lo)
                    } else {
                        0.0
                    }
                }
                _ => c,
            };
            (t.clamp(0.0, 1.0) * 255.0).round() as u8
        };
        if channels == 1 {
            let g = map(v[0]);
            image::Rgba([g, g, g, 255])
        } else {
            image::Rgba([map(v[0]), map(v[1]), map(v[2]), 255])
        }
    })
}

fn save_png(img: &image::RgbaImage, path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|source| Error::Image {
            path: path.to_path_buf(),
            source,
        })
}

fn resolved_view(session: &Session, view: &str) -> Result<image::RgbaImage> {
    let renderer = session.renderer()?;
    let gl = session.ctx.gl();
    if view == "final" {
        return renderer.read_final(gl);
    }
    let gbuffer = renderer.gbuffer();
    let layout = &renderer.options().layout;
    let (texture, channels) = if view == "depth" {
        (TextureRef::from(&gbuffer.depth), 1)
    } else if let Some(k) = layout.index_of(view) {
        (
            TextureRef::from(&gbuffer.colors[k]),
            layout.colors[k].format.channels(),
        )
    } else {
        let names: Vec<&str> = layout.colors.iter().map(|a| a.name.as_str()).collect();
        return Err(Error::invalid(format!(
            "unknown view `{view}`; available: final, {}, depth",
            names.join(", ")
        )));
    };
    let mut readback = Readback::new(gl)?;
    let img = readback.read(gl, texture, 1);
    readback.destroy(gl);
    Ok(view_image(&img?, view, channels))
}

/// Run `render`.
pub fn run_render(cmd: &RenderCmd) -> Result<()> {
    let session = Session::open(&cmd.render)?;
    let img = resolved_view(&session, &cmd.render.view)?;
    let out = cmd
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("target/deferred-msaa/render.png"));
    save_png(&img, &out)?;
    let renderer = session.renderer()?;
    let samples = renderer.retrofit().map_or(1, |r| r.samples());
    println!(
        "{}: {}x{} {} {}x -> {}",
        cmd.render.scene,
        cmd.render.size.0,
        cmd.render.size.1,
        cmd.render.method,
        samples,
        out.display()
    );
    Ok(())
}

/// Run `dump`.
pub fn run_dump(cmd: &DumpCmd) -> Result<()> {
    let session = Session::open(&cmd.render)?;
    let renderer = session.renderer()?;
    let gl = session.ctx.gl();
    let dir = &cmd.out;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let layout = renderer.options().layout.clone();
    let gbuffer = renderer.gbuffer();
    let mut readback = Readback::new(gl)?;
    let result = (|| -> Result<serde_json::Value> {
        let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
        // Per-sample sources: the multisampled twins, or the single-sample G-buffer for `none`.
        let (sample_colors, sample_depth): (Vec<TextureRef>, TextureRef) = match renderer.retrofit()
        {
            Some(r) => {
                let (depth, colors) = r.inputs()?;
                (colors, depth)
            }
            None => (
                gbuffer.colors.iter().map(TextureRef::from).collect(),
                TextureRef::from(&gbuffer.depth),
            ),
        };
        let strip = |img: &SampleImage, channels: usize| -> Vec<f32> {
            img.data
                .chunks_exact(4)
                .flat_map(|px| px[..channels].to_vec())
                .collect()
        };
        for (k, a) in layout.colors.iter().enumerate() {
            let c = a.format.channels() as usize;
            let s = readback.read(gl, sample_colors[k], 1)?;
            crate::dump::write_npy(
                &dir.join(format!("{}_samples.npy", a.name)),
                &[s.samples as usize, h, w, c],
                &strip(&s, c),
            )?;
            let r = readback.read(gl, TextureRef::from(&gbuffer.colors[k]), 1)?;
            crate::dump::write_npy(
                &dir.join(format!("{}_resolved.npy", a.name)),
                &[h, w, c],
                &strip(&r, c),
            )?;
        }
        let s = readback.read(gl, sample_depth, 1)?;
        crate::dump::write_npy(
            &dir.join("depth_samples.npy"),
            &[s.samples as usize, h, w],
            &strip(&s, 1),
        )?;
        let r = readback.read(gl, TextureRef::from(&gbuffer.depth), 1)?;
        crate::dump::write_npy(&dir.join("depth_resolved.npy"), &[h, w], &strip(&r, 1))?;
        save_png(&renderer.read_final(gl)?, &dir.join("final.png"))?;

        let camera = renderer.camera();
        let settings = renderer.options().aa.settings().unwrap_or_default();
        let key_source = match layout.key_attachment() {
            Some(a) => a.name.clone(),
            None => "depth".into(),
        };
        Ok(serde_json::json!({
            "width": w,
            "height": h,
            "samples": s.samples,
            "fov_y": camera.fov_y,
            "near": camera.near,
            "far": camera.far,
            "projection": match (renderer.depth_mode(), camera.far.is_some()) {
                (DepthMode::Reversed, true) => "reversed",
                (DepthMode::Reversed, false) => "reversed-infinite",
                (_, true) => "standard",
                (_, false) => "infinite",
            },
            "clear_depth": renderer.clear_depth(),
            "method": cmd.render.method,
            "window": settings.window.name(),
            "c": settings.c,
            "c_in": settings.c_in,
            "fast_path": settings.fast_path,
            "key_source": key_source,
            "attachments": layout.colors.iter().map(|a| serde_json::json!({
                "name": a.name, "format": a.format.name(), "rule": a.rule.name(),
            })).collect::<Vec<_>>(),
        }))
    })();
    readback.destroy(gl);
    let meta = result?;
    let path = dir.join("meta.json");
    let text = serde_json::to_string_pretty(&meta).map_err(|e| Error::invalid(e.to_string()))?;
    std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
    println!("{} -> {}", cmd.render.scene, dir.display());
    Ok(())
}
