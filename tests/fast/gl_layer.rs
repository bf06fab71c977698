//! The GL resource layer on real contexts, both backends: multisample
//! framebuffers, per-sample reads, leak counters, and typed errors.

use crate::common;

use deferred_msaa::Error;
use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::gl::{
    Attachment, Capabilities, ExtraFns, Format, Framebuffer, GlObject, GpuTimer, Handle, Made,
    Program, ShaderStage, Texture2d, Texture2dMultisample, TextureRef, VertexArray, destroy_object,
    live_objects, preamble, sample_positions,
};
use deferred_msaa_lab::readback::Readback;
use glow::HasContext;

fn contexts() -> Vec<HeadlessContext> {
    Backend::all()
        .iter()
        .filter_map(|&b| common::context(b))
        .collect()
}

#[test]
fn multisample_framebuffers_with_float_colour_and_depth_textures_are_complete() {
    for ctx in contexts() {
        let gl = ctx.gl();
        let before = live_objects();
        for depth_format in [Format::Depth24, Format::Depth32f, Format::Depth24Stencil8] {
            let colour =
                Texture2dMultisample::new(gl, "colour", Format::Rgba16f, 32, 16, 4).unwrap();
            let depth = Texture2dMultisample::new(gl, "depth", depth_format, 32, 16, 4).unwrap();
            assert!(colour.samples >= 4 && colour.samples == depth.samples);
            let fbo = Framebuffer::new(
                gl,
                "ms",
                &[
                    (Attachment::Color(0), TextureRef::from(&colour)),
                    (
                        Attachment::for_depth_format(depth_format),
                        TextureRef::from(&depth),
                    ),
                ],
                &[Some(0)],
            )
            .unwrap_or_else(|e| panic!("{}: {e}", ctx.backend()));
            fbo.destroy(gl);
            colour.destroy(gl);
            depth.destroy(gl);
        }
        assert_eq!(live_objects(), before, "{}", ctx.backend());
    }
}

#[test]
fn the_real_sample_count_is_read_back() {
    for ctx in contexts() {
        let gl = ctx.gl();
        let offered = Capabilities::sample_counts_for(gl, Format::Rgba16f);
        assert!(!offered.is_empty());
        for requested in 1..=offered[offered.len() - 1] {
            let t = Texture2dMultisample::new(gl, "t", Format::Rgba16f, 4, 4, requested).unwrap();
            let real = unsafe {
                gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(t.raw()));
                gl.get_tex_level_parameter_i32(
                    glow::TEXTURE_2D_MULTISAMPLE,
                    0,
                    glow::TEXTURE_SAMPLES,
                )
            };
            assert_eq!(t.samples, real as u32);
            assert!(t.samples >= requested, "{requested} became {}", t.samples);
            assert!(offered.contains(&t.samples));
            t.destroy(gl);
        }
        let too_many = offered[offered.len() - 1] * 16;
        let e = Texture2dMultisample::new(gl, "t", Format::Rgba16f, 4, 4, too_many).unwrap_err();
        match &e {
            Error::UnsupportedSampleCount { supported, .. } => assert_eq!(supported, &offered),
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("offers"), "{e}");
        let (n, positions) =
            sample_positions(gl, &ExtraFns::load(gl, |s| ctx.get_proc_address(s)), 4).unwrap();
        assert_eq!(positions.len(), n as usize);
        assert!(
            positions
                .iter()
                .all(|p| (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]))
        );
    }
}

const TRIANGLE_VERT: &str = "
void main() {
    vec2 corners[3] = vec2[3](vec2(-0.9, -0.8), vec2(0.7, -0.9), vec2(-0.2, 0.95));
    gl_Position = vec4(corners[gl_VertexID], 0.0, 1.0);
}
";
const WHITE_FRAG: &str = "
out vec4 o_colour;
void main() { o_colour = vec4(1.0); }
";

#[test]
fn single_samples_read_with_texel_fetch_differ_along_a_triangle_edge() {
    for ctx in contexts() {
        let gl = ctx.gl();
        let before = live_objects();
        let colour = Texture2dMultisample::new(gl, "colour", Format::Rgba16f, 24, 24, 4).unwrap();
        let fbo = Framebuffer::new(
            gl,
            "ms",
            &[(Attachment::Color(0), TextureRef::from(&colour))],
            &[Some(0)],
        )
        .unwrap();
        let program = Program::build(
            gl,
            "triangle",
            &preamble(&[], &[]),
            &[
                (ShaderStage::Vertex, "triangle.vert", TRIANGLE_VERT),
                (ShaderStage::Fragment, "white.frag", WHITE_FRAG),
            ],
            &[("o_colour", 0)],
        )
        .unwrap();
        let vao = VertexArray::new(gl, "empty").unwrap();
        fbo.bind(gl);
        unsafe {
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            program.bind(gl);
            vao.bind(gl);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
        }
        let mut readback = Readback::new(gl).unwrap();
        let samples = readback.read(gl, TextureRef::from(&colour), 1).unwrap();
        let n = samples.samples;
        let (mut mixed, mut inside, mut outside) = (0, 0, 0);
        for y in 0..24 {
            for x in 0..24 {
                let covered = (0..n).filter(|&s| samples.get(s, x, y)[0] == 1.0).count() as u32;
                match covered {
                    0 => outside += 1,
                    c if c == n => inside += 1,
                    _ => mixed += 1,
                }
            }
        }
        assert!(
            mixed > 10 && inside > 50 && outside > 50,
            "{}: mixed {mixed} inside {inside} outside {outside}",
            ctx.backend()
        );
        readback.destroy(gl);
        vao.destroy(gl);
        program.destroy(gl);
        fbo.destroy(gl);
        colour.destroy(gl);
        assert_eq!(
            live_objects(),
            before,
            "{}: live objects after destroy",
            ctx.backend()
        );
        assert_eq!(live_objects().total(), 0);
    }
}

/// A constructor that fails half-way through `Made::build` leaves nothing:
/// what it kept is deleted (the GL names are gone, the counters back where
/// they were), and a constructor that succeeds keeps everything.
#[test]
fn a_failed_constructor_frees_what_it_made() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let mut names = None;
    let result = Made::build(gl, |made| {
        let texture = made.keep(Texture2d::new(gl, "kept", Format::Rgba8, 8, 8)?);
        let fbo = made.keep(Framebuffer::new(
            gl,
            "kept",
            &[(Attachment::Color(0), TextureRef::from(&texture))],
            &[Some(0)],
        )?);
        names = Some((texture.raw(), fbo.raw()));
        assert_ne!(live_objects(), before);
        Err::<(Texture2d, Framebuffer), _>(Error::invalid("the step after them failed"))
    });
    assert!(result.is_err());
    assert_eq!(live_objects(), before, "a failed constructor leaks nothing");
    let (texture, fbo) = names.expect("the constructor ran");
    unsafe {
        assert!(
            !gl.is_texture(texture),
            "the texture's name is still in use"
        );
        assert!(
            !gl.is_framebuffer(fbo),
            "the framebuffer's name is still in use"
        );
    }
    let (texture, fbo) = Made::build(gl, |made| {
        let texture = made.keep(Texture2d::new(gl, "kept", Format::Rgba8, 8, 8)?);
        let fbo = made.keep(Framebuffer::new(
            gl,
            "kept",
            &[(Attachment::Color(0), TextureRef::from(&texture))],
            &[Some(0)],
        )?);
        Ok::<_, Error>((texture, fbo))
    })
    .expect("a working constructor");
    assert!(unsafe { gl.is_texture(texture.raw()) });
    fbo.destroy(gl);
    texture.destroy(gl);
    assert_eq!(live_objects(), before);
}

#[test]
fn a_composite_is_destroyed_by_what_it_lists() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    // A composite of composites, as the renderer's targets are: a vector, an
    // option and a pair, freed by one call through their handles.
    let parts = Made::build(gl, |made| {
        let textures = made.keep(vec![
            Texture2d::new(gl, "listed", Format::Rgba8, 8, 8)?,
            Texture2d::new(gl, "listed", Format::R32f, 8, 8)?,
        ]);
        let fbo = made.keep(Some(Framebuffer::new(
            gl,
            "listed",
            &[(Attachment::Color(0), TextureRef::from(&textures[0]))],
            &[Some(0)],
        )?));
        let vao = made.keep(VertexArray::new(gl, "listed")?);
        Ok::<_, Error>((textures, fbo, vao))
    })
    .expect("a working constructor");
    let names: Vec<_> = parts.0.iter().map(|t| t.raw()).collect();
    assert_ne!(live_objects(), before);
    struct Parts((Vec<Texture2d>, Option<Framebuffer>, VertexArray));
    impl GlObject for Parts {
        fn handles(&self, out: &mut Vec<Handle>) {
            let (textures, fbo, vao) = &self.0;
            textures.handles(out);
            fbo.handles(out);
            vao.handles(out);
        }
    }
    destroy_object(gl, Parts(parts));
    assert_eq!(live_objects(), before, "everything listed is freed");
    for t in names {
        assert!(
            !unsafe { gl.is_texture(t) },
            "a texture's name is still in use"
        );
    }
}

#[test]
fn a_broken_shader_names_its_stage_and_line() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let body = "out vec4 o_colour;\nvoid main() {\n    o_colour = vec4(undeclared_thing);\n}\n";
    let e = Program::build(
        gl,
        "broken",
        &preamble(&[], &[("SOMETHING".into(), "1".into())]),
        &[
            (ShaderStage::Vertex, "triangle.vert", TRIANGLE_VERT),
            (ShaderStage::Fragment, "broken.frag", body),
        ],
        &[("o_colour", 0)],
    )
    .unwrap_err();
    match &e {
        Error::ShaderCompile {
            stage,
            name,
            excerpt,
            log,
        } => {
            assert_eq!((*stage, name.as_str()), ("fragment", "broken.frag"));
            assert!(
                excerpt.contains("> broken.frag:   3 |     o_colour = vec4(undeclared_thing);"),
                "{excerpt}\n{log}"
            );
        }
        other => panic!("{other}"),
    }
    assert_eq!(live_objects(), before, "a failed build leaks nothing");
}

#[test]
fn incomplete_framebuffers_and_bad_sizes_are_typed_errors() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let ms = Texture2dMultisample::new(gl, "ms", Format::Rgba16f, 16, 16, 4).unwrap();
    let single = Texture2d::new(gl, "single", Format::Rgba16f, 16, 16).unwrap();
    let e = Framebuffer::new(
        gl,
        "mixed",
        &[
            (Attachment::Color(0), TextureRef::from(&ms)),
            (Attachment::Color(1), TextureRef::from(&single)),
        ],
        &[Some(0), Some(1)],
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE")
            && e.to_string().contains("mixed"),
        "{e}"
    );
    ms.destroy(gl);
    single.destroy(gl);
    let max = Capabilities::query(gl).max_texture_size;
    for (w, h) in [(0, 0), (0, 8), (max + 1, 1)] {
        let e = Texture2d::new(gl, "bad", Format::Rgba8, w, h).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument(_)), "{e}");
        assert!(e.to_string().contains(&format!("{w}x{h}")), "{e}");
    }
    assert_eq!(live_objects(), before);
}

#[test]
fn timers_measure_something() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let mut timer = GpuTimer::new(gl, false).unwrap();
    timer.begin(gl);
    unsafe { gl.clear(glow::COLOR_BUFFER_BIT) };
    let ms = timer.end(gl);
    assert!(ms.is_finite() && ms >= 0.0);
    timer.destroy(gl);
}
