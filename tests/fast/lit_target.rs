//! The contract between the retrofit and a host's lit target (issue 33):
//! a second lighting the host's own depth test rejects is an error, never
//! a silent one-layer frame; the crate's own target for the second
//! lighting gives the right image whatever depth the first lighting left;
//! the mix follows how the host wrote its lit values (through the sRGB
//! encoding or as they are); and the forward target gives what a host
//! draws after lighting per-sample coverage, leaving the rest untouched.

use crate::common;
use crate::common::srgb::{decode, encode};

use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Error, LayerMix, NormalAttachment};
use deferred_msaa_lab::gl::{
    Attachment, Format, Framebuffer, Program, ShaderSource, ShaderStage, Texture2d, TextureRef,
    VertexArray, draw_fullscreen_triangle, live_objects,
};
use deferred_msaa_lab::readback::{Readback, SampleImage};
use deferred_msaa_lab::resolve::ResolveSettings;
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;
use glow::HasContext;

const W: u32 = 64;
const H: u32 = 48;

fn projection() -> [f64; 16] {
    perspective(0.8, W as f64 / H as f64, 0.5, Some(100.0))
}

fn frame() -> deferred_msaa::Frame {
    deferred_msaa_testkit::projection::frame(&projection(), false)
}

/// A far wall and two overlapping panels in front of it: silhouettes with
/// a second layer.
fn host(gl: &glow::Context) -> Host {
    let mut v = Vec::new();
    triangle(
        &mut v,
        [
            [-60.0, -40.0, -60.0],
            [60.0, -40.0, -60.0],
            [0.0, 50.0, -60.0],
        ],
        [0.2, 0.3, 0.8],
    );
    triangle(
        &mut v,
        [[-4.0, -3.0, -10.0], [3.0, -2.5, -10.0], [-1.0, 3.0, -10.0]],
        [0.9, 0.4, 0.1],
    );
    triangle(
        &mut v,
        [[1.0, -3.0, -8.0], [5.0, -3.0, -20.0], [3.0, 3.0, -14.0]],
        [0.8, 0.8, 0.8],
    );
    let mut host = Host::new(gl, W, H, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    host.set_triangles(gl, &v)
        .expect("the toy host's triangles");
    host
}

fn options(layers: u32, layer_mix: LayerMix) -> RetrofitOptions {
    RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        resolve: ResolveSettings {
            layers,
            ..ResolveSettings::default()
        },
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        layer_mix,
        ..RetrofitOptions::default()
    }
}

/// A lit target of the host's: a colour texture of `format` and, with
/// `depth`, a depth texture.
struct LitTarget {
    color: Texture2d,
    depth: Option<Texture2d>,
    fbo: Framebuffer,
}

impl LitTarget {
    fn new(gl: &glow::Context, format: Format, depth: bool) -> Self {
        let color = Texture2d::new(gl, "lit colour", format, W, H).unwrap();
        let depth = depth.then(|| Texture2d::new(gl, "lit depth", Format::Depth24, W, H).unwrap());
        let mut attachments = vec![(Attachment::Color(0), TextureRef::from(&color))];
        if let Some(d) = &depth {
            attachments.push((Attachment::Depth, TextureRef::from(d)));
        }
        let fbo = Framebuffer::new(gl, "lit target", &attachments, &[Some(0)]).unwrap();
        LitTarget { color, depth, fbo }
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.color.destroy(gl);
        if let Some(d) = self.depth {
            d.destroy(gl);
        }
    }
}

/// The host's lighting as the most-copied tutorial draws it: a screen quad
/// at z = 0 with its depth test on (LESS) and depth writes, reading the
/// G-buffer's colour times a gain. Draws into whatever is bound.
struct DepthTestedLighting {
    program: Program,
    vao: VertexArray,
}

impl DepthTestedLighting {
    fn new(gl: &glow::Context) -> Self {
        let vertex = ShaderSource::new().part(
            "quad at z = 0",
            "void main() {\n\
                 vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);\n\
                 gl_Position = vec4(p, 0.0, 1.0);\n\
             }\n",
        );
        let fragment = ShaderSource::new().part(
            "lighting",
            "uniform sampler2D u_color;\nuniform float u_gain;\nout vec4 o_color;\n\
             void main() { o_color = vec4(texelFetch(u_color, ivec2(gl_FragCoord.xy), 0).rgb * u_gain, 1.0); }\n",
        );
        let program = Program::from_sources(
            gl,
            "depth-tested lighting",
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, &fragment),
            ],
            &[("o_color", 0)],
        )
        .unwrap();
        let vao = VertexArray::new(gl, "lighting quad").unwrap();
        DepthTestedLighting { program, vao }
    }

    /// Light `host`'s G-buffer into the bound framebuffer; `clear` first
    /// clears its colour and depth, as the tutorial's lighting does.
    fn light(&self, gl: &glow::Context, host: &Host, clear: bool, gain: f32) {
        unsafe {
            gl.viewport(0, 0, W as i32, H as i32);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            if clear {
                gl.clear_color(0.0, 0.0, 0.0, 1.0);
                gl.clear_depth_f64(1.0);
                gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            }
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(host.color().raw()));
        }
        self.program.bind(gl);
        self.program.set_i32(gl, "u_color", 0);
        self.program.set_f32(gl, "u_gain", gain);
        draw_fullscreen_triangle(gl, &self.vao);
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.use_program(None);
        }
    }

    fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
        self.vao.destroy(gl);
    }
}

/// The geometry pass into the retrofit and its resolve.
fn geometry(gl: &glow::Context, host: &Host, msaa: &mut MsaaRetrofit) -> deferred_msaa::Result<()> {
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame())
}

fn read(gl: &glow::Context, readback: &mut Readback, texture: &Texture2d) -> SampleImage {
    readback.read(gl, TextureRef::from(texture), 1).unwrap()
}

/// The second lighting left to the tutorial's depth test: the error says
/// so at once; a later such frame is reported at its finish or, where the
/// result was not in yet, at the next resolve; the crate's own target and
/// a host that repeats its clear give the same right image, bit for bit,
/// with or without the selection stencil.
#[test]
fn a_second_lighting_the_depth_test_rejects_is_an_error_not_a_silent_frame() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let lighting = DepthTestedLighting::new(gl);
    let lit = LitTarget::new(gl, Format::Rgba8, true);
    let mut readback = Readback::new(gl).unwrap();
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2, LayerMix::Auto)).unwrap();
    let bind =
        |fbo: glow::Framebuffer| unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };

    // What the tutorial's code invites: the quad again, no clear.
    let naive = |msaa: &mut MsaaRetrofit| -> deferred_msaa::Result<()> {
        geometry(gl, &host, msaa)?;
        bind(lit.fbo.raw());
        lighting.light(gl, &host, true, 2.0);
        assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw()))?);
        bind(lit.fbo.raw());
        lighting.light(gl, &host, false, 2.0);
        msaa.finish_second_layer(gl, Some(lit.fbo.raw()))
    };
    match naive(&mut msaa) {
        Err(Error::SecondLighting(message)) => {
            assert!(
                message.contains("depth or stencil test") && message.contains("glClear"),
                "the message names neither the cause nor the fix: {message}"
            );
            assert!(!message.contains('\n'), "not one line: {message}");
        }
        other => panic!("a second lighting the depth test rejected gave {other:?}"),
    }
    // Later frames: the result is read when it is there, else at the next
    // resolve; either way the host hears of it.
    let later = naive(&mut msaa);
    let next_resolve = geometry(gl, &host, &mut msaa);
    assert!(
        matches!(later, Err(Error::SecondLighting(_)))
            || matches!(next_resolve, Err(Error::SecondLighting(_))),
        "a second frame's rejected lighting went unreported: finish {later:?}, next resolve {next_resolve:?}"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);

    // The host repeating its clear: the right image.
    geometry(gl, &host, &mut msaa).unwrap();
    bind(lit.fbo.raw());
    lighting.light(gl, &host, true, 2.0);
    let one_layer = read(gl, &mut readback, &lit.color);
    assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw())).unwrap());
    bind(lit.fbo.raw());
    lighting.light(gl, &host, true, 2.0);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let cleared = read(gl, &mut readback, &lit.color);
    assert!(
        cleared.data != one_layer.data,
        "the second layer changed nothing"
    );

    // The crate's own target, the lighting unchanged (no clear, depth test
    // on), with and without the selection stencil test.
    for stencil_test in [false, true] {
        geometry(gl, &host, &mut msaa).unwrap();
        bind(lit.fbo.raw());
        lighting.light(gl, &host, true, 2.0);
        let target = msaa
            .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
            .unwrap()
            .expect("two layers give a target");
        bind(target);
        if stencil_test {
            unsafe {
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(
                    glow::EQUAL,
                    i32::from(deferred_msaa::second_layer::SECOND_LAYER_SELECTED),
                    0xFF,
                );
                gl.stencil_mask(0);
            }
        }
        lighting.light(gl, &host, false, 2.0);
        unsafe {
            gl.disable(glow::STENCIL_TEST);
            gl.stencil_mask(0xFF);
        }
        msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
        let own = read(gl, &mut readback, &lit.color);
        assert!(
            own.data == cleared.data,
            "the crate's own target (stencil test {stencil_test}) gave another image than the host's repeated clear"
        );
    }
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    readback.destroy(gl);
    lit.destroy(gl);
    lighting.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// An 8-bit value read back as a float (decoded where `srgb`), as stored.
fn stored(v: f32, srgb: bool) -> f64 {
    if srgb {
        encode(f64::from(v))
    } else {
        f64::from(v) * 255.0
    }
}

/// What the mix does with 8-bit lit values: into an `RGBA8` target, and
/// into an `SRGB8_ALPHA8` one with `GL_FRAMEBUFFER_SRGB` off, the host's
/// values are display values, mixed in linear light (decoded, mixed,
/// encoded) with nothing declared as declared [`LayerMix::SrgbEncoded`],
/// or as stored, declared [`LayerMix::Linear`]; the two targets mix the
/// same bits either way, whatever encoding the target reports; with
/// `GL_FRAMEBUFFER_SRGB` on, GL decodes and encodes, and the mix is in
/// linear light.
#[test]
fn the_mix_follows_whether_the_host_wrote_through_the_srgb_encoding() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    // (target format, GL_FRAMEBUFFER_SRGB while lighting, declaration,
    // mixed in linear light)
    let cases = [
        (Format::Rgba8, false, LayerMix::SrgbEncoded, true),
        (Format::Srgb8Alpha8, false, LayerMix::SrgbEncoded, true),
        (Format::Rgba8, false, LayerMix::Auto, true),
        (Format::Srgb8Alpha8, true, LayerMix::Auto, true),
        (Format::Srgb8Alpha8, true, LayerMix::SrgbEncoded, true),
        (Format::Rgba8, false, LayerMix::Linear, false),
        (Format::Srgb8Alpha8, false, LayerMix::Auto, true),
    ];
    let mut results: Vec<Vec<[u8; 4]>> = Vec::new();
    for (format, framebuffer_srgb, mix, linear_light) in cases.clone() {
        let label = format!(
            "{} with GL_FRAMEBUFFER_SRGB {framebuffer_srgb}, {mix:?}",
            format.name()
        );
        let srgb = format.is_srgb();
        let lit = LitTarget::new(gl, format, false);
        let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2, mix)).unwrap();
        geometry(gl, &host, &mut msaa).unwrap();
        let coverage = readback
            .read(gl, msaa.second_layer_coverage().unwrap(), 1)
            .unwrap();
        let set_srgb = |on: bool| unsafe {
            if on {
                gl.enable(glow::FRAMEBUFFER_SRGB);
            } else {
                gl.disable(glow::FRAMEBUFFER_SRGB);
            }
        };
        // The host lights with GL_FRAMEBUFFER_SRGB as it likes and leaves it
        // so for the calls around its lighting.
        set_srgb(framebuffer_srgb);
        host.light(gl, lit.fbo.raw(), 0.9);
        set_srgb(false);
        let first = read(gl, &mut readback, &lit.color);
        set_srgb(framebuffer_srgb);
        assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw())).unwrap());
        host.light(gl, lit.fbo.raw(), 0.9);
        set_srgb(false);
        let second = read(gl, &mut readback, &lit.color);
        set_srgb(framebuffer_srgb);
        msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
        assert_eq!(
            unsafe { gl.is_enabled(glow::FRAMEBUFFER_SRGB) },
            framebuffer_srgb,
            "{label}: GL_FRAMEBUFFER_SRGB not as the host left it"
        );
        set_srgb(false);
        let mixed = read(gl, &mut readback, &lit.color);
        let (mut bad, mut covered, mut domain_matters) = (Vec::new(), 0, false);
        let mut bytes = Vec::new();
        for y in 0..H {
            for x in 0..W {
                let a = f64::from(coverage.get(0, x, y)[0]);
                let (f, s, got) = (first.get(0, x, y), second.get(0, x, y), mixed.get(0, x, y));
                let got_stored: [f64; 4] = [0, 1, 2, 3].map(|c| stored(got[c], srgb && c < 3));
                bytes.push(got_stored.map(|v| v.round() as u8));
                if a == 0.0 {
                    continue;
                }
                covered += 1;
                for c in 0..3 {
                    let (fs, ss) = (stored(f[c], srgb), stored(s[c], srgb));
                    let as_stored = fs + (ss - fs) * a;
                    let (fl, sl) = (decode(fs.round() as u8), decode(ss.round() as u8));
                    let in_light = encode(fl + (sl - fl) * a);
                    domain_matters |= (as_stored - in_light).abs() >= 2.0;
                    let want = if linear_light { in_light } else { as_stored };
                    if (got_stored[c] - want).abs() > 1.0 {
                        bad.push(format!(
                            "({x},{y}) α {a:.3} channel {c}: {:.1}, want {want:.1} (as stored {as_stored:.1}, in linear light {in_light:.1})",
                            got_stored[c]
                        ));
                    }
                }
            }
        }
        assert!(
            covered >= 20,
            "{label}: only {covered} pixels have a second layer"
        );
        assert!(
            domain_matters,
            "{label}: no pixel where the mix's domain shows"
        );
        assert!(
            bad.is_empty(),
            "{label}: {} channels mixed in the wrong space: {:#?}",
            bad.len(),
            &bad[..bad.len().min(6)]
        );
        results.push(bytes);
        msaa.destroy(gl);
        lit.destroy(gl);
    }
    // The same bits whichever 8-bit target holds them, declared or not.
    for (a, b) in [(0, 1), (0, 2), (2, 6)] {
        assert!(
            results[a] == results[b],
            "{:?} and {:?} mixed differently",
            cases[a],
            cases[b]
        );
    }
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// A flat-coloured forward triangle crossing the scene's silhouettes,
/// drawn with its depth test into the forward target: every pixel it does
/// not touch keeps the lit image bit for bit; every pixel it touches is
/// the lit value and its colour mixed by k of n samples (in the mix's
/// domain), and some edge pixels are strictly between.
#[test]
fn forward_objects_get_per_sample_coverage_and_the_rest_is_untouched() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    let colour = [0.3f32, 2.5, 0.6];
    // A triangle at view depth 12: in front of the wall and the first
    // panel, through the slanted one.
    let mut v = Vec::new();
    triangle(
        &mut v,
        [[-3.5, -2.0, -12.0], [4.0, -1.0, -12.0], [0.5, 2.8, -12.0]],
        colour,
    );
    let vertex = ShaderSource::new().part(
        "forward",
        "in vec3 a_position;\nuniform mat4 u_projection;\n\
         void main() { gl_Position = u_projection * vec4(a_position, 1.0); }\n",
    );
    let fragment = ShaderSource::new().part(
        "forward",
        "uniform vec3 u_colour;\nout vec4 o_color;\nvoid main() { o_color = vec4(u_colour, 1.0); }\n",
    );
    let program = Program::from_sources(
        gl,
        "forward",
        &[
            (ShaderStage::Vertex, &vertex),
            (ShaderStage::Fragment, &fragment),
        ],
        &[("o_color", 0)],
    )
    .unwrap();
    let buffer = unsafe { gl.create_buffer().unwrap() };
    let vao = VertexArray::new(gl, "forward triangle").unwrap();
    unsafe {
        vao.bind(gl);
        gl.bind_buffer(glow::ARRAY_BUFFER, Some(buffer));
        gl.buffer_data_u8_slice(
            glow::ARRAY_BUFFER,
            bytemuck::cast_slice(&v),
            glow::STATIC_DRAW,
        );
        let location = gl
            .get_attrib_location(program.raw(), "a_position")
            .expect("a_position");
        gl.enable_vertex_attrib_array(location);
        // The kit's triangles interleave position and colour.
        gl.vertex_attrib_pointer_f32(location, 3, glow::FLOAT, false, 24, 0);
        gl.bind_vertex_array(None);
        gl.bind_buffer(glow::ARRAY_BUFFER, None);
    }
    type Domain = fn(f64, f64) -> f64;
    let tonemap: (Domain, Domain) = (|c, m| c / (1.0 + m), |t, m| t / (1.0 - m));
    let identity: (Domain, Domain) = (|c, _| c, |t, _| t);
    // IEC 61966-2-1's decode and encode, each clamped to [0, 1] first: a
    // resolve that skipped the decode (or applied it twice) mixes by k of
    // N samples in another domain, which no k fits.
    let srgb: (Domain, Domain) = (
        |c, _| {
            let c = c.clamp(0.0, 1.0);
            if c > 0.04045 {
                ((c + 0.055) / 1.055).powf(2.4)
            } else {
                c / 12.92
            }
        },
        |l, _| {
            let l = l.clamp(0.0, 1.0);
            if l > 0.0031308 {
                1.055 * l.powf(1.0 / 2.4) - 0.055
            } else {
                l * 12.92
            }
        },
    );
    for (format, mix, domain) in [
        (Format::Rgba16f, LayerMix::Tonemapped, tonemap),
        (Format::Rgba16f, LayerMix::Linear, identity),
        (Format::Rgba16f, LayerMix::SrgbEncoded, srgb),
    ] {
        let label = format!("{} {mix:?}", format.name());
        let lit = LitTarget::new(gl, format, false);
        let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(1, mix)).unwrap();
        let n = msaa.samples();
        geometry(gl, &host, &mut msaa).unwrap();
        host.light(gl, lit.fbo.raw(), 1.0);
        let lit_image = read(gl, &mut readback, &lit.color);
        let target = msaa.begin_forward(gl, Some(lit.fbo.raw())).unwrap();
        assert!(
            msaa.begin_forward(gl, Some(lit.fbo.raw())).is_err(),
            "{label}: begin_forward twice"
        );
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(target));
            gl.viewport(0, 0, W as i32, H as i32);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(false);
        }
        program.bind(gl);
        program.set_mat4(
            gl,
            "u_projection",
            &deferred_msaa_testkit::projection::to_f32(&projection()),
        );
        program.set_vec3(gl, "u_colour", colour);
        unsafe {
            vao.bind(gl);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            gl.depth_mask(true);
            gl.use_program(None);
        }
        msaa.finish_forward(gl, Some(lit.fbo.raw())).unwrap();
        assert!(
            msaa.finish_forward(gl, Some(lit.fbo.raw())).is_err(),
            "{label}: finish_forward without begin"
        );
        let got = read(gl, &mut readback, &lit.color);
        let (mut untouched, mut partial, mut full, mut bad) = (0, 0, 0, Vec::new());
        for y in 0..H {
            for x in 0..W {
                let (l, g) = (lit_image.get(0, x, y), got.get(0, x, y));
                if g == l {
                    untouched += 1;
                    continue;
                }
                let rgb = |v: [f32; 4]| [v[0], v[1], v[2]].map(f64::from);
                let (lr, cr) = (rgb(l), colour.map(f64::from));
                let (ml, mc) = (
                    lr[0].max(lr[1]).max(lr[2]).max(0.0),
                    cr[0].max(cr[1]).max(cr[2]).max(0.0),
                );
                // The k of n samples the triangle covers that fits best.
                let fits = (1..=n).map(|k| {
                    let w = f64::from(k) / f64::from(n);
                    let t: [f64; 3] = [0, 1, 2]
                        .map(|c| (domain.0)(lr[c], ml) * (1.0 - w) + (domain.0)(cr[c], mc) * w);
                    let mt = t[0].max(t[1]).max(t[2]);
                    // Every sample covered: one value, kept as stored (the
                    // sRGB round trip would clamp the 2.5).
                    let want = if k == n {
                        cr
                    } else {
                        t.map(|v| (domain.1)(v, mt))
                    };
                    let off = (0..3)
                        .map(|c| (f64::from(g[c]) - want[c]).abs() / (1e-3 + 2e-3 * want[c].abs()))
                        .fold(0.0, f64::max);
                    (off, k)
                });
                let (off, k) = fits.fold((f64::MAX, 0), |a, b| if b.0 < a.0 { b } else { a });
                if off > 1.0 {
                    bad.push(format!("({x},{y}) {g:?}: no k of {n} fits (lit {l:?})"));
                } else if k == n {
                    full += 1;
                } else {
                    partial += 1;
                }
            }
        }
        eprintln!("{label}: {untouched} untouched, {full} covered whole, {partial} partly");
        assert!(
            bad.is_empty(),
            "{label}: {} pixels off: {:#?}",
            bad.len(),
            &bad[..bad.len().min(6)]
        );
        assert!(
            full > 50 && partial > 20,
            "{label}: the triangle covers too little to tell"
        );
        assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
        assert!(msaa.forward_bytes() > 0);
        msaa.destroy(gl);
        lit.destroy(gl);
    }
    unsafe { gl.delete_buffer(buffer) };
    vao.destroy(gl);
    program.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}
