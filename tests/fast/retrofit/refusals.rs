//! Host framebuffers the retrofit cannot take: each refusal is a typed
//! error, in one line, that names the attachment and says what GL shows.

use super::*;

#[test]
fn bad_host_framebuffers_are_typed_errors_naming_the_attachment() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let colour = Texture2d::new(gl, "colour", Format::Rgba16f, 32, 32).unwrap();
    let small = Texture2d::new(gl, "small", Format::Rgba16f, 16, 16).unwrap();
    let depth = Texture2d::new(gl, "depth", Format::Depth24, 32, 32).unwrap();
    let attach = |list: &[(Attachment, TextureRef)]| unsafe {
        let fbo = gl.create_framebuffer().unwrap();
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        for (p, t) in list {
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                p.gl_enum(),
                glow::TEXTURE_2D,
                Some(t.raw()),
                0,
            );
        }
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        fbo
    };
    // No depth attachment.
    let fbo = attach(&[(Attachment::Color(0), TextureRef::from(&colour))]);
    let e = introspect(gl, fbo).unwrap_err().to_string();
    assert!(
        e.contains("GL_DEPTH_ATTACHMENT") && e.contains("no depth"),
        "{e}"
    );
    unsafe { gl.delete_framebuffer(fbo) };
    // Different sizes.
    let fbo = attach(&[
        (Attachment::Color(0), TextureRef::from(&colour)),
        (Attachment::Color(1), TextureRef::from(&small)),
        (Attachment::Depth, TextureRef::from(&depth)),
    ]);
    let e = introspect(gl, fbo).unwrap_err().to_string();
    assert!(
        e.contains("GL_COLOR_ATTACHMENT1") && e.contains("16x16"),
        "{e}"
    );
    unsafe { gl.delete_framebuffer(fbo) };
    // An already multisampled renderbuffer (single-sample ones are
    // retrofitted: the host zoo covers them).
    unsafe {
        let rb = gl.create_renderbuffer().unwrap();
        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
        gl.renderbuffer_storage_multisample(glow::RENDERBUFFER, 4, glow::RGBA8, 32, 32);
        let ms_depth = gl.create_renderbuffer().unwrap();
        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(ms_depth));
        gl.renderbuffer_storage_multisample(glow::RENDERBUFFER, 4, glow::DEPTH_COMPONENT24, 32, 32);
        let fbo = gl.create_framebuffer().unwrap();
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_renderbuffer(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::RENDERBUFFER,
            Some(rb),
        );
        gl.framebuffer_renderbuffer(
            glow::FRAMEBUFFER,
            glow::DEPTH_ATTACHMENT,
            glow::RENDERBUFFER,
            Some(ms_depth),
        );
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        let e = MsaaRetrofit::new(gl, fbo, &RetrofitOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("GL_COLOR_ATTACHMENT0") && e.contains("already multisampled"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
        gl.delete_framebuffer(fbo);
        gl.delete_renderbuffer(rb);
        gl.delete_renderbuffer(ms_depth);
    }
    // A format the resolve does not know (RGB565).
    unsafe {
        let tex = gl.create_texture().unwrap();
        gl.bind_texture(glow::TEXTURE_2D, Some(tex));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::RGB565 as i32,
            32,
            32,
            0,
            glow::RGB,
            glow::UNSIGNED_BYTE,
            glow::PixelUnpackData::Slice(None),
        );
        let fbo = attach(&[(Attachment::Depth, TextureRef::from(&depth))]);
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::TEXTURE_2D,
            Some(tex),
            0,
        );
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        let e = introspect(gl, fbo).unwrap_err();
        assert!(matches!(e, Error::UnsupportedFormat { .. }), "{e}");
        // The attachment, and the format by its GL name.
        assert!(e.to_string().contains("GL_COLOR_ATTACHMENT0"), "{e}");
        assert!(e.to_string().contains("GL_RGB565"), "{e}");
        gl.delete_framebuffer(fbo);
        gl.delete_texture(tex);
    }
    // An integer attachment cannot be blended.
    let ids = Texture2d::new(gl, "ids", Format::Rgba8ui, 32, 32).unwrap();
    let fbo = attach(&[
        (Attachment::Color(0), TextureRef::from(&ids)),
        (Attachment::Depth, TextureRef::from(&depth)),
    ]);
    let e = MsaaRetrofit::new(
        gl,
        fbo,
        &RetrofitOptions {
            rules: vec![(ColorAttachment(0), ResolveRule::Blend)],
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("RGBA8UI") && e.contains("selected"), "{e}");
    unsafe { gl.delete_framebuffer(fbo) };
    // Packed normals (RGB10_A2): `blend-normal` and a signed encoding are
    // refused with the way to name them; blended and named `Unorm`, taken.
    let packed = Texture2d::new(gl, "packed normals", Format::Rgb10A2, 32, 32).unwrap();
    let fbo = attach(&[
        (Attachment::Color(0), TextureRef::from(&packed)),
        (Attachment::Depth, TextureRef::from(&depth)),
    ]);
    let named = |encoding| NormalAttachment {
        attachment: ColorAttachment(0),
        encoding,
    };
    let refused = [
        RetrofitOptions {
            rules: vec![(ColorAttachment(0), ResolveRule::BlendNormal)],
            ..Default::default()
        },
        RetrofitOptions {
            normal_attachment: Some(named(NormalEncoding::Xyz)),
            ..Default::default()
        },
        RetrofitOptions {
            normal_attachment: Some(named(NormalEncoding::Octahedral)),
            ..Default::default()
        },
    ];
    for options in &refused {
        let e = MsaaRetrofit::new(gl, fbo, options).unwrap_err();
        assert!(matches!(e, Error::UnsupportedFormat { .. }), "{e}");
        let text = e.to_string();
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(
            text.contains("GL_COLOR_ATTACHMENT0")
                && text.contains("GL_RGB10_A2")
                && text.contains("NormalEncoding::Unorm"),
            "{text}"
        );
    }
    let msaa = MsaaRetrofit::new(
        gl,
        fbo,
        &RetrofitOptions {
            normal_attachment: Some(named(NormalEncoding::Unorm)),
            ..Default::default()
        },
    )
    .unwrap();
    msaa.destroy(gl);
    unsafe { gl.delete_framebuffer(fbo) };
    for t in [colour, small, depth, ids, packed] {
        t.destroy(gl);
    }
    assert_eq!(live_objects(), before);
}

/// Messages true to what GL shows: a rule, position or normal attachment
/// named at a point that is attached but in none of the draw buffers says
/// so (not "nothing attached"); a framebuffer with nothing attached yet
/// (an engine that attaches its textures on first bind) says that, not
/// "no depth attachment".
#[test]
fn refusals_say_what_gl_shows_of_the_host_framebuffer() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let colour = Texture2d::new(gl, "drawn", Format::Rgba16f, 16, 16).unwrap();
    let undrawn = Texture2d::new(gl, "not drawn", Format::Rgba16f, 16, 16).unwrap();
    let depth = Texture2d::new(gl, "depth", Format::Depth32f, 16, 16).unwrap();
    let fbo = Framebuffer::new(
        gl,
        "a host with a hole",
        &[
            (Attachment::Color(0), TextureRef::from(&colour)),
            (Attachment::Color(1), TextureRef::from(&undrawn)),
            (Attachment::Depth, TextureRef::from(&depth)),
        ],
        &[Some(0), None],
    )
    .unwrap();
    let cases = [
        RetrofitOptions {
            rules: vec![(ColorAttachment(1), ResolveRule::Select)],
            ..RetrofitOptions::default()
        },
        RetrofitOptions {
            position_attachment: Some(ColorAttachment(1)),
            ..RetrofitOptions::default()
        },
        RetrofitOptions {
            normal_attachment: Some(NormalAttachment {
                attachment: ColorAttachment(1),
                encoding: NormalEncoding::Xyz,
            }),
            ..RetrofitOptions::default()
        },
    ];
    for options in &cases {
        let text = MsaaRetrofit::new(gl, fbo.raw(), options)
            .unwrap_err()
            .to_string();
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(
            text.contains("GL_COLOR_ATTACHMENT1")
                && text.contains("none of the host framebuffer's draw buffers")
                && !text.contains("nothing is attached"),
            "{text}"
        );
    }
    // Nothing attached at a point: that is what the message says.
    let text = MsaaRetrofit::new(
        gl,
        fbo.raw(),
        &RetrofitOptions {
            position_attachment: Some(ColorAttachment(3)),
            ..RetrofitOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(text.contains("nothing is attached there"), "{text}");
    // A framebuffer whose engine attaches its images on first bind: before
    // that bind GL has no object of the name; bound once, it has one with
    // nothing attached.
    let empty = unsafe { gl.create_framebuffer().unwrap() };
    let text = MsaaRetrofit::new(gl, empty, &RetrofitOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("never bound") && !text.contains("has no depth attachment"),
        "{text}"
    );
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(empty));
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
    let text = MsaaRetrofit::new(gl, empty, &RetrofitOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("nothing attached at all") && !text.contains("has no depth attachment"),
        "{text}"
    );
    assert_eq!(
        unsafe { gl.get_error() },
        glow::NO_ERROR,
        "a GL error left behind"
    );
    unsafe { gl.delete_framebuffer(empty) };
    fbo.destroy(gl);
    for t in [colour, undrawn, depth] {
        t.destroy(gl);
    }
    assert_eq!(live_objects(), before, "GL objects leaked");
}
