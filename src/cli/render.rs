//! `deferred-msaa render` and `deferred-msaa dump`.

use super::common::CommonArgs;
use crate::context::HeadlessContext;
use crate::gbuffer::{GBufferLayout, MemoryBudget};
use crate::gl::TextureRef;
use crate::readback::{Readback, SampleImage};
use crate::renderer::plan::{Plan, PlanContext};
use crate::renderer::technique::{self, Gbaa};
use crate::renderer::{AaMode, DepthMode, RenderOptions, Renderer, SmaaOptions, SparseOptions};
use crate::resolve::{Region, ResolveMethod, ResolveSettings, Selection, Window};
use crate::scene::{Aabb, CameraPath, MotionSpec, Scene};
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
    /// none, average, front, median, back, upper-median, per-sample, complex, gbaa,
    /// sparse or smaa (`none` with --smaa).
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
    /// Resolved layers per pixel for front, median and back: 2 also resolves
    /// each pixel's second cluster of samples (silhouettes, creases), lights
    /// it with the unchanged lighting pass and mixes the two by coverage.
    #[arg(long, default_value_t = 1)]
    layers: u32,
    /// Selective anti-aliasing for the resolve methods and sparse: only pixels inside
    /// this region are resolved, the others take one sample;
    /// `rect:X,Y,W,H` or `ellipse:CX,CY,RX,RY` in pixels from the top-left.
    #[arg(long, value_parser = parse_region)]
    aa_region: Option<Region>,
    /// Selective anti-aliasing: pixels with no geometry nearer than this
    /// view-space distance take one sample.
    #[arg(long)]
    aa_max_depth: Option<f64>,
    /// Apply the crate's FXAA after tonemapping.
    #[arg(long)]
    fxaa: bool,
    /// Apply SMAA 1x after tonemapping, with options `preset=low|medium|high|ultra`
    /// (default high) and `edges=luma|color|depth` (default luma), joined by
    /// colons: `--smaa`, `--smaa preset=ultra:edges=color`.
    #[arg(long, value_name = "OPTIONS", num_args = 0..=1, default_missing_value = "", value_parser = parse_smaa)]
    smaa: Option<SmaaOptions>,
    /// Use FreeSpace Open's G-buffer layout (FP16 position, D24) instead of the recommended one.
    #[arg(long)]
    fso_layout: bool,
    /// Keep every attachment of the layout instead of leaving out what the
    /// scene does not need (the scene-adaptive plan, see --explain).
    #[arg(long)]
    full_layout: bool,
    /// Draw the transparent objects into the retrofit's multisampled
    /// forward target (forward MSAA; resolve, per-sample and complex
    /// methods), instead of single-sampled into the lit image.
    #[arg(long)]
    forward_msaa: bool,
    /// Memory budget for the G-buffer, e.g. 512MiB or 2GiB (default: half
    /// the free video memory the driver reports, else 1GiB); over it the
    /// sample count steps down with a warning.
    #[arg(long, value_parser = parse_budget)]
    memory_budget: Option<u64>,
    /// Refuse, instead of stepping the sample count down, when the G-buffer
    /// would exceed the memory budget.
    #[arg(long)]
    strict_memory: bool,
    /// What to write: final, an attachment name, depth, complex (the pixels
    /// the method treated as complex), layers (with --layers 2: the second
    /// layer's coverage, black where a pixel has one cluster), or (with
    /// --method gbaa) edges.
    #[arg(long, default_value = "final")]
    view: String,
}

/// Arguments of `render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderCmd {
    #[command(flatten)]
    render: RenderArgs,
    /// The PNG to write (default: target/deferred-msaa/render.png); with
    /// --motion, the folder to write the frames into (default:
    /// target/deferred-msaa/motion), as frame-000.png, frame-001.png, ...
    #[arg(long)]
    out: Option<PathBuf>,
    /// Render a camera path around the scene's camera, a frame per
    /// camera: `pan`, `orbit` or `dolly`, with `:frames=N` and `px=F`
    /// (mean image motion per frame), e.g. `orbit:frames=48,px=0.5`.
    #[arg(long, value_name = "SPEC", value_parser = parse_motion, conflicts_with = "explain")]
    motion: Option<MotionSpec>,
    /// Print the scene-adaptive plan (attachments, passes, what is left out
    /// and why, G-buffer bytes) instead of rendering.
    #[arg(long)]
    explain: bool,
    /// With --explain: print the plan as JSON.
    #[arg(long, requires = "explain")]
    json: bool,
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

fn parse_smaa(s: &str) -> std::result::Result<SmaaOptions, String> {
    s.parse().map_err(|e: Error| e.to_string())
}

fn parse_motion(s: &str) -> std::result::Result<MotionSpec, String> {
    s.parse().map_err(|e: Error| e.to_string())
}

fn parse_region(s: &str) -> std::result::Result<Region, String> {
    s.parse().map_err(|e: deferred_msaa::Error| e.to_string())
}

fn parse_budget(s: &str) -> std::result::Result<u64, String> {
    crate::gbuffer::parse_bytes(s).map_err(|e| e.to_string())
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

impl RenderArgs {
    fn options(&self) -> Result<RenderOptions> {
        // `smaa` is `none` with SMAA after the tonemap.
        let smaa_method = self.method == "smaa";
        let smaa = match (smaa_method, self.smaa) {
            (true, None) => Some(SmaaOptions::default()),
            (_, given) => given,
        };
        let method = if smaa_method { "none" } else { &self.method };
        let known = AaMode::method_names().contains(&method);
        let aa: AaMode = method.parse().ok().filter(|_| known).ok_or_else(|| {
            Error::invalid(format!(
                "unknown method `{}`; available: {}, smaa",
                self.method,
                AaMode::method_names().join(", ")
            ))
        })?;
        let selective = matches!(aa, AaMode::Resolve(_) | AaMode::Sparse(_));
        if !selective && (self.aa_region.is_some() || self.aa_max_depth.is_some()) {
            return Err(Error::invalid(format!(
                "--aa-region and --aa-max-depth select pixels for the resolve methods (average, front, median, back, upper-median) and sparse, not `{}`",
                self.method
            )));
        }
        if self.layers != 1 && !matches!(aa, AaMode::Resolve(_)) {
            return Err(Error::invalid(format!(
                "--layers is an option of the resolve methods (front, median, back, upper-median), not `{}`",
                self.method
            )));
        }
        let aa = match aa {
            AaMode::Sparse(sparse) => AaMode::Sparse(SparseOptions {
                region: self.aa_region,
                max_depth: self.aa_max_depth.map(|d| d as f32),
                ..sparse
            }),
            AaMode::Resolve(parsed) => {
                let method = parsed.method;
                let window: Window = self.window.parse()?;
                let settings = ResolveSettings {
                    method,
                    window,
                    c: self.c,
                    c_in: self.c_in,
                    fast_path: !self.no_fast_path,
                    blend_depth: false,
                    plane_uniformity: false,
                    position_uniformity: false,
                    selection: Selection {
                        region: self.aa_region,
                        max_depth: self.aa_max_depth,
                        flag: None,
                    },
                    layers: self.layers,
                    ..ResolveSettings::default()
                };
                if self.layers == 2 && method == ResolveMethod::Average {
                    return Err(Error::invalid(
                        "--layers 2 needs front, median, back or upper-median: average weighs every sample, so it has one cluster",
                    ));
                }
                if !(self.c.is_finite() && self.c > 0.0) {
                    return Err(Error::invalid(format!(
                        "--c must be a finite number above 0, got {}",
                        self.c
                    )));
                }
                if !(self.c_in.is_finite() && self.c_in >= 0.0 && self.c_in < self.c) {
                    return Err(Error::invalid(format!(
                        "--c-in must be at least 0 and below --c ({}), got {}",
                        self.c, self.c_in
                    )));
                }
                settings.validate()?;
                AaMode::Resolve(settings)
            }
            other => other,
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
            smaa,
            layout: if self.fso_layout {
                GBufferLayout::freespace_open()
            } else {
                GBufferLayout::recommended()
            },
            depth_mode: DepthMode::Auto,
            adaptive: !self.full_layout,
            forward_msaa: self.forward_msaa,
            layer_mix: None,
            memory_budget: MemoryBudget {
                bytes: self.memory_budget,
                strict: self.strict_memory,
            },
        })
    }
}

/// A rendered frame, kept alive with its context.
struct Session {
    ctx: HeadlessContext,
    renderer: Option<Renderer>,
    /// The scene's bounds, for camera paths.
    bounds: Aabb,
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
        // A temporal method's still image is the one it settles on.
        for _ in 0..=options.aa.warmup_frames() {
            renderer.render(ctx.gl())?;
        }
        Ok(Session {
            ctx,
            renderer: Some(renderer),
            bounds: scene.bounds,
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
    if view == "edges" {
        let edges = renderer
            .technique::<Gbaa>()
            .map_or(Ok(None), |g| g.read_edges(gl));
        return edges?.ok_or_else(|| {
            Error::invalid("the `edges` view shows gbaa's edge buffers; use it with --method gbaa")
        });
    }
    let gbuffer = renderer.gbuffer();
    let layout = renderer.layout();
    let aa = renderer.effective_options().aa;
    if !technique::kind_of(&aa).fills_gbuffer() && layout.index_of(view).is_some() {
        let method = aa.name();
        return Err(Error::invalid(format!(
            "view `{view}` shows a G-buffer attachment, which method `{method}` leaves empty \
             (its G-buffer pass does not fill it); with {method}: final, depth"
        )));
    }
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
            "unknown view `{view}`; available: final, {}, depth, complex, edges (with --method gbaa)",
            names.join(", ")
        )));
    };
    let mut readback = Readback::new(gl)?;
    let img = readback.read(gl, texture, 1);
    readback.destroy(gl);
    Ok(view_image(&img?, view, channels))
}

/// The `complex` view: which pixels the method treated as complex (the
/// resolve's slow path; `complex`'s per-sample pixels), white on black.
fn complex_view(session: &mut Session) -> Result<image::RgbaImage> {
    let Session { ctx, renderer, .. } = session;
    let renderer = renderer
        .as_mut()
        .ok_or_else(|| Error::invalid("the renderer is gone"))?;
    let mask = renderer.read_complex_pixels(ctx.gl())?.ok_or_else(|| {
        Error::invalid(format!(
            "the `complex` view needs a multisampled method (average, front, median, back, upper-median, per-sample or complex); this frame ran `{}`",
            renderer.effective_options().aa.name()
        ))
    })?;
    Ok(image::RgbaImage::from_fn(
        mask.width(),
        mask.height(),
        |x, y| {
            let v = mask.get_pixel(x, y)[0];
            image::Rgba([v, v, v, 255])
        },
    ))
}

/// The `layers` view: the second layer's coverage `α` as grey (black
/// where a pixel has one cluster of samples).
fn layers_view(session: &mut Session) -> Result<image::RgbaImage> {
    let Session { ctx, renderer, .. } = session;
    let renderer = renderer
        .as_mut()
        .ok_or_else(|| Error::invalid("the renderer is gone"))?;
    let coverage = renderer.read_second_layer_coverage(ctx.gl())?.ok_or_else(|| {
        Error::invalid(
            "the `layers` view shows the second layer's coverage; use it with --layers 2 and front, median, back or upper-median",
        )
    })?;
    Ok(image::RgbaImage::from_fn(
        coverage.width(),
        coverage.height(),
        |x, y| {
            let v = coverage.get_pixel(x, y)[0];
            image::Rgba([v, v, v, 255])
        },
    ))
}

/// Run `render --explain`: the plan, as text or JSON, without rendering.
fn run_explain(cmd: &RenderCmd) -> Result<()> {
    let args = &cmd.render;
    let options = args.options()?;
    let scene = Scene::load(&args.scene)?;
    for w in &scene.warnings {
        log::warn!("{}: {w}", args.scene);
    }
    let ctx = HeadlessContext::new(args.common.backend)?;
    let context = PlanContext::query(ctx.gl(), &options.layout);
    let plan = Plan::for_scene(&scene, &context, &options)?;
    for w in &plan.warnings {
        log::warn!("{w}");
    }
    if cmd.json {
        let text = serde_json::to_string_pretty(&plan.to_json())
            .map_err(|e| Error::invalid(e.to_string()))?;
        println!("{text}");
    } else {
        print!("{}", plan.to_text());
    }
    Ok(())
}

/// Run `render`.
pub fn run_render(cmd: &RenderCmd) -> Result<()> {
    if cmd.explain {
        return run_explain(cmd);
    }
    if let Some(motion) = cmd.motion {
        return run_motion(cmd, motion);
    }
    let mut session = Session::open(&cmd.render)?;
    let img = view(&mut session, &cmd.render.view)?;
    let out = cmd
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("target/deferred-msaa/render.png"));
    save_png(&img, &out)?;
    let renderer = session.renderer()?;
    let samples = renderer.samples();
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

/// The image `--view` names of the session's last frame.
fn view(session: &mut Session, name: &str) -> Result<image::RgbaImage> {
    match name {
        "complex" => complex_view(session),
        "layers" => layers_view(session),
        _ => resolved_view(session, name),
    }
}

/// `render --motion`: a frame per camera of the path, written as
/// `frame-NNN.png` into the output folder.
fn run_motion(cmd: &RenderCmd, motion: MotionSpec) -> Result<()> {
    let dir = cmd
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("target/deferred-msaa/motion"));
    if dir.exists() && !dir.is_dir() {
        return Err(Error::invalid(format!(
            "--out {}: with --motion, --out names a folder for the frames, and this is a file",
            dir.display()
        )));
    }
    let mut session = Session::open(&cmd.render)?;
    let (w, h) = cmd.render.size;
    let base = *session.renderer()?.camera();
    let path = CameraPath::new(motion, &base, &session.bounds, w, h)?;
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    for (k, camera) in path.cameras.iter().enumerate() {
        if let Session {
            ctx,
            renderer: Some(r),
            ..
        } = &mut session
        {
            r.set_camera(*camera);
            r.render(ctx.gl())?;
        }
        let img = view(&mut session, &cmd.render.view)?;
        save_png(&img, &dir.join(format!("frame-{k:03}.png")))?;
    }
    let measured = path.measured_px(&session.bounds, w, h).unwrap_or(motion.px);
    println!(
        "{}: {}x{} {} {}x, {} ({} frames, {measured:.2} px per frame) -> {}",
        cmd.render.scene,
        w,
        h,
        cmd.render.method,
        session.renderer()?.samples(),
        motion.kind.name(),
        path.cameras.len(),
        dir.display()
    );
    Ok(())
}

/// Run `dump`.
pub fn run_dump(cmd: &DumpCmd) -> Result<()> {
    if cmd.render.method == "sparse" {
        return Err(Error::invalid(
            "dump writes every sample of the multisampled G-buffer, which method `sparse` does \
             not have (its G-buffer is per-pixel lists of blocks); use render",
        ));
    }
    let mut session = Session::open(&cmd.render)?;
    // The fraction of pixels the method treated as complex (the resolve's
    // slow path; `complex`'s per-sample pixels), before the read-only borrows.
    let complex_fraction = match &mut session {
        Session {
            ctx,
            renderer: Some(r),
            ..
        } => r.complex_pixel_fraction(ctx.gl())?,
        Session { renderer: None, .. } => None,
    };
    let renderer = session.renderer()?;
    let gl = session.ctx.gl();
    let dir = &cmd.out;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let layout = renderer.layout().clone();
    let gbuffer = renderer.gbuffer();
    let mut readback = Readback::new(gl)?;
    let result = (|| -> Result<serde_json::Value> {
        let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
        // Per-sample sources: the multisampled twins, or the single-sample G-buffer for `none`.
        let (sample_colors, sample_depth): (Vec<TextureRef>, TextureRef) = match renderer.retrofit()
        {
            Some(r) => {
                let (depth, colors, _) = r.inputs()?;
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
        // With two layers: the second layer's resolved G-buffer, its depth
        // and its coverage, as the second lighting reads them.
        let second_layer = match renderer
            .retrofit()
            .and_then(|r| r.second_layer_gbuffer().zip(r.second_layer_coverage()))
        {
            None => serde_json::Value::Null,
            Some(((colors, depth), coverage)) => {
                let mut files = Vec::with_capacity(layout.colors.len());
                for (k, a) in layout.colors.iter().enumerate() {
                    let c = a.format.channels() as usize;
                    let file = format!("{}_layer2_resolved.npy", a.name);
                    let r = readback.read(gl, colors[k], 1)?;
                    crate::dump::write_npy(&dir.join(&file), &[h, w, c], &strip(&r, c))?;
                    files.push(serde_json::json!({ "name": a.name, "file": file }));
                }
                let r = readback.read(gl, depth, 1)?;
                crate::dump::write_npy(
                    &dir.join("depth_layer2_resolved.npy"),
                    &[h, w],
                    &strip(&r, 1),
                )?;
                let r = readback.read(gl, coverage, 1)?;
                crate::dump::write_npy(&dir.join("layer2_coverage.npy"), &[h, w], &strip(&r, 1))?;
                serde_json::json!({
                    "attachments": files,
                    "depth": "depth_layer2_resolved.npy",
                    "coverage": "layer2_coverage.npy",
                })
            }
        };
        save_png(&renderer.read_final(gl)?, &dir.join("final.png"))?;

        let camera = renderer.camera();
        let settings = renderer
            .effective_options()
            .aa
            .settings()
            .unwrap_or_default();
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
            "layers": settings.layers,
            "second_layer": second_layer,
            "key_source": key_source,
            "complex_fraction": complex_fraction,
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
