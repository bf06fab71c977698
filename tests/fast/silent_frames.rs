//! Hosts that got a wrong frame with every status OK (issue 47), each
//! written in its engine's style: a read-back right after a finish; a
//! lighting that depth-tests against the G-buffer's depth, lit into the
//! crate's own target; a sky left to the lit target's clear while the
//! last `glClearColor` was another target's; a render-target wrapper that
//! deletes the own and forward targets; a host that makes its G-buffer
//! anew under a new framebuffer name. Each gets the right image or a
//! returned error naming the fix.

use crate::common;

use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Error, LayerMix, NormalAttachment};
use deferred_msaa_lab::gl::{
    Attachment, Format, Framebuffer, Program, ShaderSource, ShaderStage, Texture2d, TextureRef,
    VertexArray, draw_fullscreen_triangle, live_objects,
};
use deferred_msaa_lab::resolve::ResolveSettings;
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;
use glow::HasContext;

const W: u32 = 64;
const H: u32 = 48;
const SKY: [f32; 4] = [0.25, 0.5, 0.875, 1.0];

fn projection() -> [f64; 16] {
    perspective(0.8, W as f64 / H as f64, 0.5, Some(100.0))
}

fn frame() -> deferred_msaa::Frame {
    deferred_msaa_testkit::projection::frame(&projection(), false)
}

/// Two overlapping panels, with sky around them: silhouettes against each
/// other and against the sky, so the second layer holds both.
fn host(gl: &glow::Context, width: u32) -> Host {
    let mut v = Vec::new();
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
    let mut host =
        Host::new(gl, width, H, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    host.set_triangles(gl, &v)
        .expect("the toy host's triangles");
    host
}

fn options(layers: u32) -> RetrofitOptions {
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
        layer_mix: LayerMix::Linear,
        ..RetrofitOptions::default()
    }
}

/// The engine's lit target: an `RGBA8` colour texture and, with
/// `depth`, that depth image attached as its depth (the G-buffer's own, for
/// an engine whose lighting tests it).
struct LitTarget {
    color: Texture2d,
    fbo: Framebuffer,
}

impl LitTarget {
    fn new(gl: &glow::Context, depth: Option<&Texture2d>) -> Self {
        let color = Texture2d::new(gl, "lit colour", Format::Rgba8, W, H).unwrap();
        let mut attachments = vec![(Attachment::Color(0), TextureRef::from(&color))];
        if let Some(d) = depth {
            attachments.push((Attachment::Depth, TextureRef::from(d)));
        }
        let fbo = Framebuffer::new(gl, "lit target", &attachments, &[Some(0)]).unwrap();
        LitTarget { color, fbo }
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.color.destroy(gl);
    }
}

/// A full-screen pass of the engine's: a triangle at `z` in clip space
/// (w = 1) with a fragment body of its own.
struct Pass {
    program: Program,
    vao: VertexArray,
}

impl Pass {
    fn new(gl: &glow::Context, label: &str, z: f32, fragment: &str) -> Self {
        let vertex = ShaderSource::new().part(
            "screen triangle",
            &format!(
                "void main() {{\n\
                     vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);\n\
                     gl_Position = vec4(p, {z:.1}, 1.0);\n\
                 }}\n"
            ),
        );
        let fragment = ShaderSource::new().part(label, fragment);
        let program = Program::from_sources(
            gl,
            label,
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Fragment, &fragment),
            ],
            &[("o_color", 0)],
        )
        .unwrap();
        let vao = VertexArray::new(gl, label).unwrap();
        Pass { program, vao }
    }

    /// Draw into the bound framebuffer, the G-buffer's colour on unit 0
    /// and its depth on unit 1.
    fn draw(&self, gl: &glow::Context, host: &Host) {
        unsafe {
            gl.viewport(0, 0, W as i32, H as i32);
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, Some(host.depth.raw()));
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(host.color().raw()));
        }
        self.program.bind(gl);
        self.program.set_i32(gl, "u_color", 0);
        self.program.set_i32(gl, "u_depth", 1);
        draw_fullscreen_triangle(gl, &self.vao);
        unsafe {
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.use_program(None);
        }
    }

    fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
        self.vao.destroy(gl);
    }
}

const COMPOSE: &str = "uniform sampler2D u_color;\nuniform sampler2D u_depth;\nout vec4 o_color;\n\
     void main() { o_color = vec4(texelFetch(u_color, ivec2(gl_FragCoord.xy), 0).rgb, 1.0); }\n";
const BACKGROUND: &str = "uniform sampler2D u_color;\nuniform sampler2D u_depth;\nout vec4 o_color;\n\
     void main() { o_color = vec4(0.25, 0.5, 0.875, 1.0); }\n";
/// The lighting of an engine that leaves its sky to the lit target's
/// clear: background pixels (the G-buffer's depth at 1) are discarded.
const GEOMETRY_ONLY: &str = "uniform sampler2D u_color;\nuniform sampler2D u_depth;\nout vec4 o_color;\n\
     void main() {\n\
         ivec2 p = ivec2(gl_FragCoord.xy);\n\
         if (texelFetch(u_depth, p, 0).r >= 1.0) discard;\n\
         o_color = vec4(texelFetch(u_color, p, 0).rgb, 1.0);\n\
     }\n";

/// The geometry pass into the retrofit and its resolve.
fn geometry(gl: &glow::Context, host: &Host, msaa: &mut MsaaRetrofit) -> deferred_msaa::Result<()> {
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame())
}

/// The bound read framebuffer's pixels as the host reads them back, and
/// the GL error the read raised.
fn read_pixels(gl: &glow::Context) -> (Vec<u8>, u32) {
    let mut bytes = vec![0u8; (W * H * 4) as usize];
    unsafe {
        let _ = gl.get_error();
        gl.read_pixels(
            0,
            0,
            W as i32,
            H as i32,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelPackData::Slice(Some(&mut bytes)),
        );
        (bytes, gl.get_error())
    }
}

/// The lit target's pixels, read through its own framebuffer.
fn lit_pixels(gl: &glow::Context, lit: &LitTarget) -> Vec<u8> {
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(lit.fbo.raw()));
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
    }
    let (bytes, error) = read_pixels(gl);
    assert_eq!(error, glow::NO_ERROR, "reading the lit target");
    bytes
}

fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks(4).zip(b.chunks(4)).filter(|(x, y)| x != y).count()
}

/// A screenshot taken the way a program takes one right after the frame:
/// `glReadBuffer` and `glReadPixels` on whatever the last draw left bound.
/// After `finish_forward`, and after `finish_second_layer` with the own
/// target, that is the output, with no GL error.
#[test]
fn a_read_back_right_after_a_finish_reads_the_output() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl, W);
    let lit = LitTarget::new(gl, None);
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2)).unwrap();
    geometry(gl, &host, &mut msaa).unwrap();
    host.light(gl, lit.fbo.raw(), 1.0);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .expect("two layers give a target");
    host.light(gl, own, 1.0);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    // The screenshot: the engine reads what it believes it drew into.
    unsafe { gl.read_buffer(glow::COLOR_ATTACHMENT0) };
    let (shot, error) = read_pixels(gl);
    assert_eq!(
        error,
        glow::NO_ERROR,
        "a read-back after finish_second_layer raised a GL error"
    );
    let mixed = lit_pixels(gl, &lit);
    assert_eq!(
        differing(&shot, &mixed),
        0,
        "the read-back after finish_second_layer is not the mixed output"
    );

    let forward = msaa.begin_forward(gl, Some(lit.fbo.raw())).unwrap();
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(forward));
        // A forward object: a clear of a band, as a particle would cover it.
        gl.enable(glow::SCISSOR_TEST);
        gl.scissor(10, 10, 20, 8);
        gl.clear_color(1.0, 0.0, 1.0, 1.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
        gl.disable(glow::SCISSOR_TEST);
    }
    msaa.finish_forward(gl, Some(lit.fbo.raw())).unwrap();
    unsafe { gl.read_buffer(glow::COLOR_ATTACHMENT0) };
    let (shot, error) = read_pixels(gl);
    assert_eq!(
        error,
        glow::NO_ERROR,
        "a read-back after finish_forward raised a GL error (the crate's multisampled framebuffer left bound)"
    );
    let finished = lit_pixels(gl, &lit);
    assert!(
        differing(&finished, &mixed) >= 20 * 8,
        "the forward band did not reach the output"
    );
    assert_eq!(
        differing(&shot, &finished),
        0,
        "the read-back after finish_forward is not the output"
    );
    // Both bindings are the output's.
    let binding = |pname| unsafe { gl.get_parameter_i32(pname) } as u32;
    assert_eq!(
        binding(glow::DRAW_FRAMEBUFFER_BINDING),
        lit.fbo.raw().0.get()
    );
    assert_eq!(
        binding(glow::READ_FRAMEBUFFER_BINDING),
        lit.fbo.raw().0.get()
    );
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    lit.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// An engine whose lit framebuffer shares the G-buffer's depth: its compose
/// pass is a full-screen triangle at z = 1 tested `GL_GREATER` against it,
/// its background one tested `GL_LEQUAL`, and it clears only colour. Lit
/// into the crate's own target it gives the image its second lighting into
/// the output gives (before, the own target's depth at 1 lit the second
/// layer as sky everywhere).
#[test]
fn a_lighting_tested_against_the_gbuffer_depth_lights_the_own_target_as_the_output() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl, W);
    let lit = LitTarget::new(gl, Some(&host.depth));
    let compose = Pass::new(gl, "compose", 1.0, COMPOSE);
    let background = Pass::new(gl, "background", 1.0, BACKGROUND);
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2)).unwrap();
    let lighting = |target: glow::Framebuffer, clear: bool| unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(target));
        if clear {
            gl.clear_color(0.0, 0.0, 0.0, 1.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
        }
        gl.enable(glow::DEPTH_TEST);
        gl.depth_mask(false);
        gl.depth_func(glow::GREATER);
        compose.draw(gl, &host);
        gl.depth_func(glow::LEQUAL);
        background.draw(gl, &host);
        gl.depth_func(glow::LESS);
        gl.depth_mask(true);
        gl.disable(glow::DEPTH_TEST);
    };

    geometry(gl, &host, &mut msaa).unwrap();
    lighting(lit.fbo.raw(), true);
    let one_layer = lit_pixels(gl, &lit);
    assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw())).unwrap());
    lighting(lit.fbo.raw(), true);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let into_output = lit_pixels(gl, &lit);
    let changed = differing(&into_output, &one_layer);
    assert!(changed > 0, "the second layer changed nothing");

    geometry(gl, &host, &mut msaa).unwrap();
    lighting(lit.fbo.raw(), true);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .expect("two layers give a target");
    lighting(own, false);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let own_image = lit_pixels(gl, &lit);
    let off = differing(&own_image, &into_output);
    eprintln!(
        "G-buffer-depth lighting: the second layer changed {changed} pixels; the own target differs at {off}"
    );
    assert_eq!(
        off, 0,
        "the own target lit the second layer otherwise than the output (as sky?)"
    );

    // The same engine clearing the own target's depth with its colour, as
    // a lighting that clears its target does: the second layer is lit as
    // sky, and the check says so (at that finish where the GPU has the
    // count, else at the next).
    let mut reported = Vec::new();
    for frame_number in 0..2 {
        geometry(gl, &host, &mut msaa).unwrap();
        lighting(lit.fbo.raw(), true);
        let own = msaa
            .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
            .unwrap()
            .unwrap();
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(own));
            gl.clear_depth_f64(1.0);
            gl.clear(glow::DEPTH_BUFFER_BIT);
        }
        lighting(own, true);
        let finished = msaa.finish_second_layer(gl, Some(lit.fbo.raw()));
        let lit_as_sky = lit_pixels(gl, &lit);
        assert!(
            differing(&lit_as_sky, &into_output) > 0,
            "frame {frame_number}: the cleared depth changed nothing: the test shows nothing"
        );
        match finished {
            Err(Error::SecondLighting(message)) => {
                assert!(
                    message.contains("depth") && message.contains("background"),
                    "frame {frame_number}: the message names neither the depth nor the sky: {message}"
                );
                reported.push(frame_number);
            }
            Ok(()) => {}
            other => panic!("frame {frame_number}: {other:?}"),
        }
    }
    eprintln!("a second layer lit as background: reported at the finish of frames {reported:?}");
    assert!(
        reported.contains(&1),
        "two frames with the second layer lit as background, and the second's finish said nothing"
    );
    // And a right frame after it: no error left over.
    geometry(gl, &host, &mut msaa).unwrap();
    lighting(lit.fbo.raw(), true);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .unwrap();
    lighting(own, false);
    let after = msaa.finish_second_layer(gl, Some(lit.fbo.raw()));
    assert!(
        matches!(after, Ok(()) | Err(Error::SecondLighting(_))),
        "{after:?}"
    );
    geometry(gl, &host, &mut msaa).unwrap();
    lighting(lit.fbo.raw(), true);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .unwrap();
    lighting(own, false);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw()))
        .expect("a right frame after the cleared ones");
    assert_eq!(differing(&lit_pixels(gl, &lit), &into_output), 0);
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    compose.destroy(gl);
    background.destroy(gl);
    lit.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// An engine that leaves its sky to its lit target's clear colour and
/// clears another target (a bloom buffer) last: the own target's
/// background is the declared `lit_clear` (then the image is the one a
/// second lighting into the output after the engine's own clear gives),
/// or, undeclared, the lit first layer; never the last `glClearColor`.
#[test]
fn the_own_targets_background_is_declared_never_the_last_clear_colour() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl, W);
    let lit = LitTarget::new(gl, None);
    let bloom = LitTarget::new(gl, None);
    let lighting = Pass::new(gl, "geometry-only lighting", 0.0, GEOMETRY_ONLY);
    // The engine's frame up to the second lighting: its lit target cleared
    // to the sky, lit, then its bloom target cleared to `last`.
    let first = |msaa: &mut MsaaRetrofit, last: [f32; 4]| unsafe {
        geometry(gl, &host, msaa).unwrap();
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(lit.fbo.raw()));
        gl.clear_color(SKY[0], SKY[1], SKY[2], SKY[3]);
        gl.clear(glow::COLOR_BUFFER_BIT);
        lighting.draw(gl, &host);
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(bloom.fbo.raw()));
        gl.clear_color(last[0], last[1], last[2], last[3]);
        gl.clear(glow::COLOR_BUFFER_BIT);
    };
    let own = |msaa: &mut MsaaRetrofit, last: [f32; 4]| {
        first(msaa, last);
        let target = msaa
            .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
            .unwrap()
            .expect("two layers give a target");
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(target)) };
        lighting.draw(gl, &host);
        msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
        lit_pixels(gl, &lit)
    };
    let magenta = [1.0, 0.0, 1.0, 1.0];
    let black = [0.0, 0.0, 0.0, 0.0];

    // Undeclared: the same image whatever the last clear colour.
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2)).unwrap();
    let after_magenta = own(&mut msaa, magenta);
    let after_black = own(&mut msaa, black);
    assert_eq!(
        differing(&after_magenta, &after_black),
        0,
        "the own target's background followed the last glClearColor, another target's"
    );
    msaa.destroy(gl);

    // Declared: the image of the engine's own clear and lighting again.
    let declared = RetrofitOptions {
        lit_clear: Some(SKY),
        ..options(2)
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &declared).unwrap();
    first(&mut msaa, magenta);
    assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw())).unwrap());
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(lit.fbo.raw()));
        gl.clear_color(SKY[0], SKY[1], SKY[2], SKY[3]);
        gl.clear(glow::COLOR_BUFFER_BIT);
    }
    lighting.draw(gl, &host);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let reference = lit_pixels(gl, &lit);
    let with_sky = own(&mut msaa, magenta);
    let off = differing(&with_sky, &reference);
    let sky_pixels = differing(&with_sky, &after_magenta);
    eprintln!(
        "sky left to the clear: declared differs from the reference at {off}, from undeclared at {sky_pixels}"
    );
    assert_eq!(
        off, 0,
        "the declared lit clear did not give the output's image"
    );
    assert!(
        sky_pixels > 0,
        "no second-layer pixel shows the sky: the test shows nothing"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    lighting.destroy(gl);
    bloom.destroy(gl);
    lit.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// The lighting of an engine whose lit target has a depth of its own,
/// cleared before lighting, into which the lighting writes the G-buffer's
/// depth for the forward pass after it.
const DEPTH_WRITING: &str = "uniform sampler2D u_color;\nuniform sampler2D u_depth;\nout vec4 o_color;\n\
     void main() {\n\
         ivec2 p = ivec2(gl_FragCoord.xy);\n\
         gl_FragDepth = texelFetch(u_depth, p, 0).r;\n\
         o_color = vec4(texelFetch(u_color, p, 0).rgb, 1.0);\n\
     }\n";

/// The output's depth after a second lighting into it that clears and
/// writes it: the first lighting's, as a forward pass drawn into the
/// output afterwards tests against (before, the second layer's: the clear
/// depth wherever a pixel has one surface, and forward objects were drawn
/// over nearer surfaces).
#[test]
fn the_outputs_own_depth_is_the_first_lightings_after_the_second() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl, W);
    let depth = Texture2d::new(gl, "lit depth", Format::Depth24, W, H).unwrap();
    let lit = LitTarget::new(gl, Some(&depth));
    let lighting = Pass::new(gl, "depth-writing lighting", 0.0, DEPTH_WRITING);
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2)).unwrap();
    let light = || unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(lit.fbo.raw()));
        gl.clear_color(0.0, 0.0, 0.0, 1.0);
        gl.clear_depth_f64(1.0);
        gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::ALWAYS);
        lighting.draw(gl, &host);
        gl.depth_func(glow::LESS);
        gl.disable(glow::DEPTH_TEST);
    };
    let read_depth = || {
        let mut bytes = vec![0u8; (W * H * 4) as usize];
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(lit.fbo.raw()));
            gl.read_pixels(
                0,
                0,
                W as i32,
                H as i32,
                glow::DEPTH_COMPONENT,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(&mut bytes)),
            );
        }
        bytes
    };
    geometry(gl, &host, &mut msaa).unwrap();
    light();
    let first = read_depth();
    assert!(msaa.begin_second_layer(gl, Some(lit.fbo.raw())).unwrap());
    light();
    let during = read_depth();
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let after = read_depth();
    let reset = differing(&during, &first);
    eprintln!("the output's depth: the second lighting changed {reset} pixels");
    assert!(
        reset > 0,
        "the second lighting left the depth as it was: the test shows nothing"
    );
    assert_eq!(
        differing(&after, &first),
        0,
        "after finish_second_layer the output's depth is not the first lighting's"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    lighting.destroy(gl);
    lit.destroy(gl);
    depth.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// The error a deleted target of the crate's gives: a retrofit error
/// naming the framebuffer and `refresh`.
fn names_deletion(result: deferred_msaa::Result<impl std::fmt::Debug>, fbo: u32, what: &str) {
    match result {
        Err(e @ Error::Retrofit { .. }) => {
            let message = e.to_string();
            assert!(
                message.contains(&format!("framebuffer {fbo}")) && message.contains("refresh"),
                "{what}: the error names neither the framebuffer {fbo} nor refresh: {message}"
            );
        }
        other => panic!("{what}: a deleted target gave {other:?}"),
    }
}

/// An engine's render-target wrapper that deletes what it wraps when
/// dropped, wrapped around the own target and the forward target: the
/// next call says which framebuffer was deleted and that `refresh` makes
/// it anew; after `refresh` the frame is right again.
#[test]
fn a_wrapper_deleting_the_own_and_forward_targets_is_named_with_refresh() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl, W);
    let lit = LitTarget::new(gl, None);
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options(2)).unwrap();
    // The wrapper: draws through the name, then deletes it.
    let wrapped = |fbo: glow::Framebuffer, draw: &dyn Fn(glow::Framebuffer)| {
        draw(fbo);
        unsafe { gl.delete_framebuffer(fbo) };
    };

    geometry(gl, &host, &mut msaa).unwrap();
    host.light(gl, lit.fbo.raw(), 1.0);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .unwrap();
    wrapped(own, &|f| host.light(gl, f, 1.0));
    names_deletion(
        msaa.finish_second_layer(gl, Some(lit.fbo.raw())),
        own.0.get(),
        "finish_second_layer",
    );
    // Every later frame says so until refresh.
    geometry(gl, &host, &mut msaa).unwrap();
    host.light(gl, lit.fbo.raw(), 1.0);
    names_deletion(
        msaa.begin_second_layer_own_target(gl, Some(lit.fbo.raw())),
        own.0.get(),
        "the next begin_second_layer_own_target",
    );
    msaa.refresh(gl).unwrap();

    geometry(gl, &host, &mut msaa).unwrap();
    host.light(gl, lit.fbo.raw(), 1.0);
    let own = msaa
        .begin_second_layer_own_target(gl, Some(lit.fbo.raw()))
        .unwrap()
        .unwrap();
    host.light(gl, own, 1.0);
    msaa.finish_second_layer(gl, Some(lit.fbo.raw())).unwrap();
    let forward = msaa.begin_forward(gl, Some(lit.fbo.raw())).unwrap();
    wrapped(forward, &|_| {});
    names_deletion(
        msaa.finish_forward(gl, Some(lit.fbo.raw())),
        forward.0.get(),
        "finish_forward",
    );
    names_deletion(
        msaa.begin_forward(gl, Some(lit.fbo.raw())),
        forward.0.get(),
        "the next begin_forward",
    );
    msaa.refresh(gl).unwrap();
    geometry(gl, &host, &mut msaa).unwrap();
    host.light(gl, lit.fbo.raw(), 1.0);
    let lit_image = lit_pixels(gl, &lit);
    msaa.begin_forward(gl, Some(lit.fbo.raw())).unwrap();
    msaa.finish_forward(gl, Some(lit.fbo.raw())).unwrap();
    assert_eq!(
        differing(&lit_pixels(gl, &lit), &lit_image),
        0,
        "after refresh the forward target with nothing drawn changed the lit image"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    lit.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// An engine that makes its G-buffer anew on a resize (deletes its
/// framebuffer and textures, generates new ones): the resolve says to give
/// the new framebuffer to `refresh_with`, after which the frame is the one
/// a retrofit made for the new G-buffer gives, bit for bit.
#[test]
fn a_gbuffer_made_anew_under_a_new_name_is_taken_by_refresh_with() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let old = host(gl, W);
    let mut msaa = MsaaRetrofit::new(gl, old.fbo.raw(), &options(1)).unwrap();
    geometry(gl, &old, &mut msaa).unwrap();
    // The new G-buffer, narrower, made before the old one is deleted (GL
    // may give a freed name out again).
    let new = host(gl, W / 2);
    old.destroy(gl);
    match geometry(gl, &new, &mut msaa) {
        Err(e) => assert!(
            e.to_string().contains("refresh_with"),
            "the resolve on a deleted G-buffer does not name refresh_with: {e}"
        ),
        Ok(()) => panic!("a resolve into a deleted G-buffer returned OK"),
    }
    msaa.refresh_with(gl, new.fbo.raw()).unwrap();
    assert_eq!(msaa.host().size(), (W / 2, H));
    geometry(gl, &new, &mut msaa).unwrap();
    let mut readback = deferred_msaa_lab::readback::Readback::new(gl).unwrap();
    let got = readback.read(gl, TextureRef::from(new.color()), 1).unwrap();
    let mut fresh = MsaaRetrofit::new(gl, new.fbo.raw(), &options(1)).unwrap();
    geometry(gl, &new, &mut fresh).unwrap();
    let want = readback.read(gl, TextureRef::from(new.color()), 1).unwrap();
    assert!(
        got.data == want.data,
        "refresh_with resolved otherwise than a retrofit made for the new G-buffer"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    fresh.destroy(gl);
    msaa.destroy(gl);
    readback.destroy(gl);
    new.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}
