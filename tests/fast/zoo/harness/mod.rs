//! What every zoo host is put through, written once: the three renders
//! (the host as it is, the host with the two-line retrofit, the host at 4x
//! width and height box-filtered down), the read-backs, the GL state
//! snapshot around the retrofit's calls and the checks.
//!
//! Nothing here is host code: the hosts in the sibling modules are written
//! the way their engines are, with raw glow calls; this module only drives
//! them through [`ZooHost`].

mod halo;
mod planes;

pub use crate::common::gl_state::GlState;
use deferred_msaa::gl::live_objects;
use deferred_msaa::{Frame, MsaaRetrofit, NormalAttachment, RetrofitOptions};
use deferred_msaa_lab::bench::{HALO_THRESHOLD, downsample_srgb};
use deferred_msaa_lab::compare::{flip, halo_pixels};
use deferred_msaa_lab::context::HeadlessContext;
use glow::HasContext;
use image::RgbaImage;
pub use planes::{
    Channel, Check, Plane, Read, program, program_with_locations, read_framebuffer, read_image,
    read_texture, read_texture_layers,
};

/// The test image size (the supersampled reference is [`SS`] times each way).
pub const W: u32 = 96;
/// The test image height.
pub const H: u32 = 64;
/// The supersampling factor of the reference, each way (16 samples a pixel).
pub const SS: u32 = 4;

/// `options` with `layers` resolved layers, clusters split by the host's
/// normal attachment `normal` (its integrator names it, as a host names
/// its position attachment and as docs/resolve.md asks of every host,
/// with one layer as with two).
pub fn with_layers(
    options: RetrofitOptions,
    layers: u32,
    normal: NormalAttachment,
) -> RetrofitOptions {
    let mut options = options;
    options.resolve.layers = layers;
    options.normal_attachment = Some(normal);
    options
}

/// A run's name: the host's, with the layer count when it is not 1.
pub fn name(host: &str, layers: u32) -> String {
    if layers == 1 {
        host.to_string()
    } else {
        format!("{host} ({layers} layers)")
    }
}

/// A host engine in the zoo, as the harness drives it.
pub trait ZooHost: Sized {
    /// Its G-buffer at `width` x `height`, its programs, its scene upload.
    /// It binds the G-buffer textures its lighting reads to texture units
    /// here, once.
    fn new(gl: &glow::Context, width: u32, height: u32) -> Self;
    /// The host's G-buffer framebuffer.
    fn gbuffer(&self) -> glow::Framebuffer;
    /// The framebuffer its lighting writes (8-bit RGBA colour attachment 0).
    fn screen(&self) -> glow::Framebuffer;
    /// Texture units `0..units()` are the host's: the harness leaves them alone.
    fn units(&self) -> u32;
    /// The unchanged geometry pass, into `fbo` (its own, or the retrofit's).
    fn geometry_pass(&self, gl: &glow::Context, fbo: glow::Framebuffer);
    /// The unchanged lighting pass, into [`ZooHost::screen`].
    fn lighting_pass(&self, gl: &glow::Context);
    /// Every G-buffer attachment, read back in its own format.
    fn read_gbuffer(&self, gl: &glow::Context) -> Vec<Plane>;
    /// Delete everything the host made.
    fn destroy(self, gl: &glow::Context);
    /// The OpenGL version the host's own code needs (its shaders'
    /// `#version`): most are written for 3.3.
    fn needs_gl() -> (u32, u32) {
        (3, 3)
    }
}

/// The harness's own textures, bound to units the host does not use so
/// that the state check covers every target on every unit.
struct Clutter {
    texture_2d: glow::Texture,
    array: glow::Texture,
    multisample: glow::Texture,
}

impl Clutter {
    fn new(gl: &glow::Context) -> Clutter {
        unsafe {
            let previous = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0 + 31);
            let texture_2d = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D, Some(texture_2d));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                4,
                4,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow::TEXTURE_2D, None);
            let array = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, Some(array));
            gl.tex_image_3d(
                glow::TEXTURE_2D_ARRAY,
                0,
                glow::RGBA8 as i32,
                4,
                4,
                2,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, None);
            let multisample = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(multisample));
            gl.tex_image_2d_multisample(
                glow::TEXTURE_2D_MULTISAMPLE,
                4,
                glow::RGBA8 as i32,
                4,
                4,
                true,
            );
            gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            gl.active_texture(previous);
            Clutter {
                texture_2d,
                array,
                multisample,
            }
        }
    }

    /// Leave the state a busy engine leaves when it calls the resolve:
    /// nothing a correct resolve may depend on, everything it must restore.
    fn apply(&self, ctx: &HeadlessContext, host: &impl ZooHost) {
        let gl = ctx.gl();
        let base = host.units();
        assert!(base <= 10, "the host uses units below 10");
        unsafe {
            // Distinct read and draw bindings: the draw one is the geometry pass's.
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(host.screen()));
            for (unit, target, texture) in [
                (12, glow::TEXTURE_2D_ARRAY, self.array),
                (13, glow::TEXTURE_2D_MULTISAMPLE, self.multisample),
                (14, glow::TEXTURE_2D, self.texture_2d),
                (15, glow::TEXTURE_2D_ARRAY, self.array),
                (15, glow::TEXTURE_2D_MULTISAMPLE, self.multisample),
                (15, glow::TEXTURE_2D, self.texture_2d),
            ] {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(target, Some(texture));
            }
            gl.active_texture(glow::TEXTURE0 + 11);
            gl.scissor(1, 2, 7, 5);
            gl.clear_color(0.125, 0.25, 0.375, 0.5);
            gl.clear_depth_f64(0.75);
            gl.clear_stencil(5);
            gl.enable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.enable(glow::SAMPLE_MASK);
            sample_mask(ctx, 0xFFFF_FFFF);
            gl.blend_func_separate(
                glow::SRC_ALPHA,
                glow::ONE_MINUS_SRC_ALPHA,
                glow::ONE,
                glow::ZERO,
            );
            if !gl.is_enabled(glow::STENCIL_TEST) {
                gl.stencil_func_separate(glow::FRONT, glow::GEQUAL, 3, 0x7F);
                gl.stencil_func_separate(glow::BACK, glow::LESS, 2, 0x3F);
                gl.stencil_op_separate(glow::FRONT, glow::KEEP, glow::INCR, glow::INVERT);
                gl.stencil_op_separate(glow::BACK, glow::DECR, glow::ZERO, glow::REPLACE);
                gl.stencil_mask_separate(glow::FRONT, 0xF0);
                gl.stencil_mask_separate(glow::BACK, 0x0F);
            }
        }
    }

    /// Put back GL's defaults for what [`Clutter::apply`] set, so that the
    /// next host's geometry pass starts as the first one did.
    fn reset(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
            for unit in 12..16 {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, None);
                gl.bind_texture(glow::TEXTURE_2D_ARRAY, None);
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
            }
            gl.active_texture(glow::TEXTURE0);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear_stencil(0);
            gl.disable(glow::SAMPLE_ALPHA_TO_COVERAGE);
            gl.disable(glow::SAMPLE_MASK);
            gl.blend_func(glow::ONE, glow::ZERO);
            gl.stencil_func(glow::ALWAYS, 0, 0xFF);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
            gl.stencil_mask(0xFF);
        }
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_texture(self.texture_2d);
            gl.delete_texture(self.array);
            gl.delete_texture(self.multisample);
        }
    }
}

/// `glSampleMaski(0, mask)` (glow has no wrapper for it).
fn sample_mask(ctx: &HeadlessContext, mask: u32) {
    let f = ctx.get_proc_address("glSampleMaski");
    assert!(!f.is_null(), "glSampleMaski");
    // SAFETY: glSampleMaski's signature, from a GL 3.2+ core context.
    let f: extern "system" fn(u32, u32) = unsafe { std::mem::transmute(f) };
    f(0, mask);
}

/// Everything one zoo run measured.
#[derive(Debug)]
pub struct Outcome {
    /// The host's name.
    pub host: String,
    /// FLIP mean of the host's no-MSAA image against the reference.
    pub flip_none: f32,
    /// FLIP mean of the retrofitted image against the reference.
    pub flip_resolved: f32,
    /// Halo pixels (halo.rs: beyond coverage quantisation) of the no-MSAA image.
    pub halos_none: usize,
    /// Halo pixels of the retrofitted image.
    pub halos_resolved: usize,
    /// Halo pixels of the retrofitted image where the no-MSAA image has none.
    pub new_halos: usize,
    /// Pixels of the retrofitted image over the 16x image by more than the
    /// threshold, halo or coverage quantisation (halo.rs tells them apart).
    pub over_reference: usize,
    /// Inside-face pixels compared.
    pub inside: usize,
    /// Distinct faces (by their constant planes) with inside pixels.
    pub faces: usize,
    /// Every failed check but the halo check, one line each.
    pub failures: Vec<String>,
    /// The halo check's failure: new halo pixels, if any.
    pub halo_failure: Option<String>,
    /// Why the host was not run, when its own code needs a newer context.
    pub not_run: Option<String>,
}

impl Outcome {
    fn not_run(host: &str, why: String) -> Self {
        Outcome {
            host: host.into(),
            flip_none: 0.0,
            flip_resolved: 0.0,
            halos_none: 0,
            halos_resolved: 0,
            new_halos: 0,
            over_reference: 0,
            inside: 0,
            faces: 0,
            failures: Vec::new(),
            halo_failure: None,
            not_run: Some(why),
        }
    }

    /// Print the numbers and panic with every failure.
    pub fn assert_ok(&self) {
        if let Some(why) = &self.not_run {
            eprintln!("{}: {why}", self.host);
            return;
        }
        eprintln!(
            "{}: FLIP none {:.4} resolved {:.4} (reference 0); halos none {} resolved {} new {} ({} over the 16x image, quantisation included); {} inside pixels over {} faces",
            self.host,
            self.flip_none,
            self.flip_resolved,
            self.halos_none,
            self.halos_resolved,
            self.new_halos,
            self.over_reference,
            self.inside,
            self.faces
        );
        assert!(
            self.failures.is_empty(),
            "{}: {} failed checks:\n{}",
            self.host,
            self.failures.len(),
            self.failures.join("\n")
        );
    }
}

/// The key of pixel `(x, y)`: the bytes of every constant plane there.
fn face_key(planes: &[Plane], x: u32, y: u32) -> Vec<u8> {
    planes
        .iter()
        .filter(|p| p.check == Check::Constant)
        .flat_map(|p| p.texel(x, y).to_vec())
        .collect()
}

/// Pixels whose 3x3 neighbourhood is one face in the no-MSAA render, and
/// how many faces that covers.
fn inside_pixels(planes: &[Plane]) -> (Vec<(u32, u32)>, usize) {
    let (w, h) = (planes[0].width, planes[0].height);
    let mut inside = Vec::new();
    let mut keys = std::collections::HashSet::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let k = face_key(planes, x, y);
            let same = (0..9).all(|i| face_key(planes, x + i % 3 - 1, y + i / 3 - 1) == k);
            if same {
                inside.push((x, y));
                keys.insert(k);
            }
        }
    }
    (inside, keys.len())
}

/// Compare the retrofitted planes with the no-MSAA ones.
fn compare_planes(
    none: &[Plane],
    resolved: &[Plane],
    failures: &mut Vec<String>,
) -> (usize, usize) {
    assert_eq!(none.len(), resolved.len());
    let (inside, faces) = inside_pixels(none);
    for (a, b) in none.iter().zip(resolved) {
        let mut bad = 0usize;
        let mut first = None;
        let pixels: Vec<(u32, u32)> = match a.check {
            Check::Untouched => (0..a.height)
                .flat_map(|y| (0..a.width).map(move |x| (x, y)))
                .collect(),
            _ => inside.clone(),
        };
        for &(x, y) in &pixels {
            let ok = match a.check {
                Check::Constant | Check::Untouched => a.texel(x, y) == b.texel(x, y),
                Check::Smooth => {
                    let got = b.values(x, y);
                    (0..a.channels).all(|c| {
                        let around: Vec<f64> = (0..9)
                            .map(|i| a.values(x + i % 3 - 1, y + i / 3 - 1)[c])
                            .collect();
                        let lo = around.iter().copied().fold(f64::INFINITY, f64::min);
                        let hi = around.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        let slack = a.channel.slack(lo.abs().max(hi.abs()));
                        got[c] >= lo - slack && got[c] <= hi + slack
                    })
                }
            };
            if !ok {
                bad += 1;
                first.get_or_insert((x, y));
            }
        }
        if let Some((x, y)) = first {
            let what = match a.check {
                Check::Constant => "bit for bit inside faces",
                Check::Smooth => "within the 3x3 range inside faces",
                Check::Untouched => "untouched everywhere",
            };
            failures.push(format!(
                "{}: {bad} of {} pixels differ from the host's own render ({what}); first at ({x}, {y}) from the bottom: no MSAA {:?} = {:?}, retrofit {:?} = {:?}",
                a.name,
                pixels.len(),
                a.texel(x, y),
                a.values(x, y),
                b.texel(x, y),
                b.values(x, y),
            ));
        }
    }
    (inside.len(), faces)
}

/// The three renders of host `T` and every check. `options` and the two
/// integration lines are all that differs between the host without MSAA
/// and with it.
pub fn run<T: ZooHost>(
    ctx: &HeadlessContext,
    name: &str,
    options: &RetrofitOptions,
    frame: impl Fn(&T) -> Frame,
) -> Outcome {
    let gl = ctx.gl();
    let version = gl.version();
    if (version.major, version.minor) < T::needs_gl() {
        // The host itself cannot run here (the GL 3.2 floor run): its
        // shaders are GLSL 3.30. The crate's side is covered by the hosts
        // written for 3.2.
        let (major, minor) = T::needs_gl();
        let why = format!(
            "not run: the host needs OpenGL {major}.{minor}, this context is {}.{}",
            version.major, version.minor
        );
        return Outcome::not_run(name, why);
    }
    let clutter = Clutter::new(gl);
    let mut failures = Vec::new();

    // The host's own 16x supersampled image: the same host at 4x each way.
    let reference = {
        let host = T::new(gl, W * SS, H * SS);
        host.geometry_pass(gl, host.gbuffer());
        clutter.apply(ctx, &host);
        host.lighting_pass(gl);
        clutter.reset(gl);
        let big = read_image(gl, host.screen(), W * SS, H * SS);
        host.destroy(gl);
        (downsample_srgb(&big, SS).expect("downsample"), big)
    };
    let (reference, big) = reference;

    // The host as it is.
    let (none_planes, none_image) = {
        let host = T::new(gl, W, H);
        host.geometry_pass(gl, host.gbuffer());
        clutter.apply(ctx, &host);
        let planes = host.read_gbuffer(gl);
        host.lighting_pass(gl);
        clutter.reset(gl);
        let image = read_image(gl, host.screen(), W, H);
        host.destroy(gl);
        (planes, image)
    };

    // The host with the two integration lines.
    let host = T::new(gl, W, H);
    let before_new = GlState::capture(gl);
    let mut msaa = match MsaaRetrofit::new(gl, host.gbuffer(), options) {
        Ok(m) => m,
        Err(e) => {
            host.destroy(gl);
            clutter.destroy(gl);
            panic!("{name}: the retrofit refuses the host's G-buffer: {e}");
        }
    };
    for d in before_new.differences(&GlState::capture(gl)) {
        failures.push(format!("MsaaRetrofit::new changed the host's state: {d}"));
    }
    let samples = msaa.samples();
    let before_begin = GlState::capture(gl);
    let twin = match msaa.begin_frame(gl) {
        Ok(fbo) => fbo,
        Err(e) => {
            failures.push(format!("begin_frame failed: {e}"));
            msaa.framebuffer()
        }
    };
    for d in before_begin.differences(&GlState::capture(gl)) {
        failures.push(format!("begin_frame changed the host's state: {d}"));
    }
    host.geometry_pass(gl, twin);
    clutter.apply(ctx, &host);
    let before = GlState::capture(gl);
    let resolved = msaa.resolve(gl, &frame(&host));
    let after = GlState::capture(gl);
    if let Err(e) = &resolved {
        failures.push(format!("resolve failed: {e}"));
    }
    for d in before.differences(&after) {
        failures.push(format!("resolve changed the host's state: {d}"));
    }
    let planes = host.read_gbuffer(gl);
    host.lighting_pass(gl);
    let mut image = read_image(gl, host.screen(), W, H);
    if options.resolve.layers == 2 {
        image = second_lighting(ctx, &host, &mut msaa, &planes, &image, &mut failures);
    }
    clutter.reset(gl);
    msaa.destroy(gl);
    let live = live_objects();
    if live.total() != 0 {
        failures.push(format!("GL objects left after destroy: {live:?}"));
    }
    host.destroy(gl);
    clutter.destroy(gl);
    let error = unsafe { gl.get_error() };
    if error != glow::NO_ERROR {
        failures.push(format!("GL error 0x{error:04X} at the end"));
    }

    let (inside, faces) = compare_planes(&none_planes, &planes, &mut failures);
    if inside < (W * H / 3) as usize || faces < 5 {
        failures.push(format!(
            "only {inside} inside pixels over {faces} faces: the scene does not test the planes"
        ));
    }

    let flip_none = flip(&reference, &none_image).expect("flip").mean;
    let flip_resolved = flip(&reference, &image).expect("flip").mean;
    if flip_resolved >= flip_none {
        failures.push(format!(
            "the retrofitted image is no closer to the supersampled one than the host's own: FLIP {flip_resolved:.4} vs {flip_none:.4}"
        ));
    }
    // Halo pixels (halo.rs): over the brightest their surfaces give at the
    // twins' coverage steps, not merely over the 16x image.
    let bounds = halo::bounds(&big, SS, samples);
    let (halos_none, _) = halo::count(&bounds, &none_image, &none_image, HALO_THRESHOLD);
    let (halos_resolved, new_halos) = halo::count(&bounds, &image, &none_image, HALO_THRESHOLD);
    let over_reference = halo_pixels(&reference, &image, HALO_THRESHOLD);
    let mut halo_failure = None;
    if new_halos > 0 {
        halo_failure = Some(format!(
            "{new_halos} halo pixels (luminance over the brightest its surfaces give at {samples}x coverage by more than {HALO_THRESHOLD}) that the host's own image does not have"
        ));
    }
    if std::env::var_os("ZOO_DUMP").is_some() {
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("zoo");
        std::fs::create_dir_all(&dir).unwrap();
        reference
            .save(dir.join(format!("{name}-reference.png")))
            .unwrap();
        none_image
            .save(dir.join(format!("{name}-none.png")))
            .unwrap();
        image
            .save(dir.join(format!("{name}-resolved.png")))
            .unwrap();
    }
    Outcome {
        host: name.to_string(),
        flip_none,
        flip_resolved,
        halos_none,
        halos_resolved,
        new_halos,
        over_reference,
        halo_failure,
        not_run: None,
        inside,
        faces,
        failures,
    }
}

/// The three lines of the second layer around the host's unchanged
/// lighting, called a second time: the host's state around each call, its
/// G-buffer after them (the first layer's again, bit for bit), and the lit
/// image where a pixel has one cluster (the first lighting's, bit for bit).
/// Returns the mixed image.
fn second_lighting<T: ZooHost>(
    ctx: &HeadlessContext,
    host: &T,
    msaa: &mut MsaaRetrofit,
    first_planes: &[Plane],
    first_image: &RgbaImage,
    failures: &mut Vec<String>,
) -> RgbaImage {
    let gl = ctx.gl();
    let before = GlState::capture(gl);
    match msaa.begin_second_layer(gl, Some(host.screen())) {
        Ok(true) => {}
        Ok(false) => failures.push("begin_second_layer did nothing with two layers".into()),
        Err(e) => failures.push(format!("begin_second_layer failed: {e}")),
    }
    for d in before.differences(&GlState::capture(gl)) {
        failures.push(format!("begin_second_layer changed the host's state: {d}"));
    }
    host.lighting_pass(gl);
    let before = GlState::capture(gl);
    if let Err(e) = msaa.finish_second_layer(gl, Some(host.screen())) {
        failures.push(format!("finish_second_layer failed: {e}"));
    }
    for d in before.differences(&GlState::capture(gl)) {
        failures.push(format!("finish_second_layer changed the host's state: {d}"));
    }
    for (first, now) in first_planes.iter().zip(host.read_gbuffer(gl)) {
        if first.raw != now.raw {
            let bpp = first.raw.len() / (first.width * first.height) as usize;
            let differing: Vec<usize> = (0..first.raw.len() / bpp)
                .filter(|&i| first.raw[i * bpp..(i + 1) * bpp] != now.raw[i * bpp..(i + 1) * bpp])
                .collect();
            let at = differing[0];
            failures.push(format!(
                "{}: the first layer is not back in the host's G-buffer after finish_second_layer ({} texels differ; at ({}, {}) {:?} was {:?})",
                first.name,
                differing.len(),
                at as u32 % first.width,
                at as u32 / first.width,
                first.values(at as u32 % first.width, at as u32 / first.width),
                now.values(at as u32 % first.width, at as u32 / first.width)
            ));
        }
    }
    let image = read_image(gl, host.screen(), W, H);
    let Some(coverage) = msaa.second_layer_coverage() else {
        failures.push("no second layer coverage with two layers".into());
        return image;
    };
    let coverage = read_texture(
        gl,
        coverage.raw,
        W,
        H,
        Read {
            name: "second layer coverage",
            format: glow::RED,
            channels: 1,
            channel: Channel::F32,
            check: Check::Smooth,
        },
    );
    let mut two = 0;
    for y in 0..H {
        for x in 0..W {
            // Coverage rows go bottom up, images top down.
            let alpha = coverage.values(x, y)[0];
            let (xi, yi) = (x, H - 1 - y);
            if alpha > 0.0 {
                two += 1;
            } else if image.get_pixel(xi, yi) != first_image.get_pixel(xi, yi) {
                failures.push(format!(
                    "pixel ({xi}, {yi}) has one cluster but the mix changed it: {:?} vs {:?}",
                    image.get_pixel(xi, yi),
                    first_image.get_pixel(xi, yi)
                ));
            }
        }
    }
    if two == 0 {
        failures.push("no pixel has a second layer: the scene does not test it".into());
    }
    image
}

/// Assert a refusal is the one-line typed error the brief asks for: it names
/// `attachment` and the GL enum `gl_enum` by name, never in hex.
pub fn assert_refusal(error: &deferred_msaa::Error, attachment: &str, gl_enum: &str) {
    let text = error.to_string();
    assert_eq!(text.lines().count(), 1, "one line: {text}");
    assert!(text.contains(attachment), "names {attachment}: {text}");
    assert!(text.contains(gl_enum), "names {gl_enum}: {text}");
    assert!(!text.contains("0x"), "no enum in hex: {text}");
}
