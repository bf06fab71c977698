//! Long runs and concurrency: nothing leaks, memory stays flat, and two
//! contexts on two threads do not disturb each other.

use crate::common;

use deferred_msaa::ColorAttachment;
use deferred_msaa_lab::context::{Backend, HeadlessContext};
use deferred_msaa_lab::gl::{Format, TextureRef, live_objects};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::resolve::{ResolveRule, ResolveSettings};
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;
use glow::HasContext;

fn scene(seed: u32) -> Vec<f32> {
    let mut v = Vec::new();
    let s = seed as f32 * 0.37;
    triangle(
        &mut v,
        [
            [-30.0, -20.0, -40.0],
            [30.0, -20.0, -40.0],
            [0.0, 25.0, -40.0],
        ],
        [0.2, 0.3, 0.9],
    );
    for k in 0..12 {
        let x = ((k as f32 * 1.7 + s).sin()) * 4.0;
        let y = ((k as f32 * 2.3 + s).cos()) * 3.0;
        let z = -8.0 - k as f32 * 0.9;
        triangle(
            &mut v,
            [
                [x - 1.5, y - 1.0, z],
                [x + 1.5, y - 0.8, z - 0.5],
                [x, y + 1.6, z],
            ],
            [0.9, 0.5 + k as f32 * 0.03, 0.1],
        );
    }
    v
}

fn frame(width: u32, height: u32) -> deferred_msaa::Frame {
    deferred_msaa_testkit::projection::frame(
        &perspective(0.9, width as f64 / height as f64, 0.5, Some(100.0)),
        false,
    )
}

/// Resident set size in bytes (Linux).
fn rss_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    pages * 4096
}

#[test]
fn a_thousand_create_resize_resample_destroy_cycles_leak_nothing() {
    // Resident memory is the process's: measure it with no other test beside it.
    if !common::alone(
        module_path!(),
        "a_thousand_create_resize_resample_destroy_cycles_leak_nothing",
    ) {
        return;
    }
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let sizes = [(32u32, 24u32), (17, 9), (40, 30), (1, 1), (24, 40)];
    let mut rss_after_warmup = 0;
    for cycle in 0..1000u32 {
        let (w, h) = sizes[cycle as usize % sizes.len()];
        let mut host =
            Host::new(gl, w, h, Format::Rgba32f, Format::Depth32f).expect("the toy host");
        host.set_triangles(gl, &scene(cycle % 7))
            .expect("the toy host's triangles");
        let options = RetrofitOptions {
            samples: 1 + cycle % 4,
            rules: vec![(ColorAttachment(2), ResolveRule::BlendNormal)],
            position_attachment: Some(ColorAttachment(1)),
            ..RetrofitOptions::default()
        };
        let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(
            gl,
            &perspective(0.9, w as f64 / h as f64, 0.5, Some(100.0)),
            false,
        );
        msaa.resolve(gl, &frame(w, h)).unwrap();
        // Change the sample count at run time, then resize the host and refresh.
        msaa.set_samples(gl, 4).unwrap();
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(
            gl,
            &perspective(0.9, w as f64 / h as f64, 0.5, Some(100.0)),
            false,
        );
        let alternate = RetrofitOptions {
            resolve: ResolveSettings {
                fast_path: cycle % 2 == 0,
                ..ResolveSettings::default()
            },
            ..msaa.options().clone()
        };
        msaa.set_options(gl, &alternate).unwrap();
        msaa.resolve(gl, &frame(w, h)).unwrap();
        unsafe {
            for t in [host.color(), host.normal()] {
                gl.bind_texture(glow::TEXTURE_2D, Some(t.raw()));
                gl.tex_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    glow::RGBA16F as i32,
                    w as i32 + 1,
                    h as i32,
                    0,
                    glow::RGBA,
                    glow::HALF_FLOAT,
                    glow::PixelUnpackData::Slice(None),
                );
            }
            gl.bind_texture(glow::TEXTURE_2D, Some(host.position().raw()));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA32F as i32,
                w as i32 + 1,
                h as i32,
                0,
                glow::RGBA,
                glow::FLOAT,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow::TEXTURE_2D, Some(host.depth.raw()));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::DEPTH_COMPONENT32F as i32,
                w as i32 + 1,
                h as i32,
                0,
                glow::DEPTH_COMPONENT,
                glow::FLOAT,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        msaa.refresh(gl).unwrap();
        assert_eq!(msaa.host().size(), (w + 1, h));
        msaa.destroy(gl);
        host.destroy(gl);
        assert_eq!(live_objects(), before, "cycle {cycle}");
        if cycle == 100 {
            unsafe { gl.finish() };
            rss_after_warmup = rss_bytes();
        }
    }
    unsafe { gl.finish() };
    let growth = rss_bytes().saturating_sub(rss_after_warmup);
    // Allocator noise is a few MiB at most; a leak of even one small texture
    // per cycle would be tens of MiB over 900 cycles.
    assert!(
        growth < 16 << 20,
        "resident memory grew by {} KiB over 900 cycles",
        growth >> 10
    );
}

/// Render and resolve one frame on the calling thread; return the resolved colour.
fn render_once(
    ctx: &HeadlessContext,
    seed: u32,
    settings: ResolveSettings,
    frames: u32,
) -> Vec<f32> {
    let gl = ctx.gl();
    let (w, h) = (48, 32);
    let mut host = Host::new(gl, w, h, Format::Rgba32f, Format::Depth32f).expect("the toy host");
    host.set_triangles(gl, &scene(seed))
        .expect("the toy host's triangles");
    let mut msaa = MsaaRetrofit::new(
        gl,
        host.fbo.raw(),
        &RetrofitOptions {
            position_attachment: Some(ColorAttachment(1)),
            resolve: settings,
            ..Default::default()
        },
    )
    .unwrap();
    let mut rb = Readback::new(gl).unwrap();
    let mut out = Vec::new();
    for _ in 0..frames {
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &perspective(0.9, 1.5, 0.5, Some(100.0)), false);
        msaa.resolve(gl, &frame(w, h)).unwrap();
        let frame = rb.read(gl, TextureRef::from(host.color()), 1).unwrap().data;
        if !out.is_empty() {
            assert_eq!(out, frame, "frame changed between identical frames");
        }
        out = frame;
    }
    rb.destroy(gl);
    msaa.destroy(gl);
    host.destroy(gl);
    out
}

#[test]
fn two_contexts_on_two_threads_render_at_once_without_disturbing_each_other() {
    if common::egl_context().is_none() {
        return;
    }
    let configs = [
        (Backend::Egl, 1, ResolveSettings::default()),
        (
            Backend::Egl,
            2,
            ResolveSettings {
                method: deferred_msaa_lab::resolve::ResolveMethod::Front,
                ..ResolveSettings::default()
            },
        ),
    ];
    // Alone first, one after the other.
    let alone: Vec<Vec<f32>> = configs
        .iter()
        .map(|&(b, seed, s)| render_once(&HeadlessContext::new(b).unwrap(), seed, s, 1))
        .collect();
    assert_ne!(
        alone[0], alone[1],
        "the two configurations must differ to prove anything"
    );
    // Then both at once, many frames each.
    let handles: Vec<_> = configs
        .iter()
        .map(|&(b, seed, s)| {
            std::thread::spawn(move || {
                let ctx = HeadlessContext::new(b).unwrap();
                let frame = render_once(&ctx, seed, s, 20);
                assert_eq!(live_objects().total(), 0, "thread leaked GL objects");
                frame
            })
        })
        .collect();
    for (h, want) in handles.into_iter().zip(&alone) {
        let got = h.join().expect("render thread panicked");
        assert_eq!(
            &got, want,
            "a concurrent render differs from the same render alone"
        );
    }
}

/// A texture far beyond memory (16384² RGBA32F, every layer the driver
/// allows: terabytes) is GL_OUT_OF_MEMORY from the driver, which comes back
/// as a typed one-line error naming the texture; nothing is left allocated
/// and the context keeps working.
#[test]
fn gl_out_of_memory_is_a_typed_error_and_the_context_survives() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let (size, layers) = unsafe {
        (
            gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE) as u32,
            gl.get_parameter_i32(glow::MAX_ARRAY_TEXTURE_LAYERS) as u32,
        )
    };
    let bytes = u64::from(size) * u64::from(size) * u64::from(layers) * 16;
    assert!(
        bytes > 1 << 40,
        "the driver's limits allow only {bytes} bytes"
    );
    let err = deferred_msaa_lab::gl::Texture2dArray::new(
        gl,
        "far too big",
        Format::Rgba32f,
        size,
        size,
        layers,
        None,
    )
    .expect_err("terabytes of texture were allocated");
    match &err {
        deferred_msaa::Error::Gl { code_name, .. } => {
            assert_eq!(*code_name, "GL_OUT_OF_MEMORY", "{err}")
        }
        other => panic!("not a GL error: {other}"),
    }
    let message = err.to_string();
    assert!(
        !message.contains('\n') && message.contains("far too big"),
        "{message}"
    );
    assert_eq!(live_objects(), before, "the failed texture was not freed");
    // The context still works.
    let small = deferred_msaa_lab::gl::Texture2d::new(gl, "small", Format::Rgba8, 4, 4)
        .expect("a small texture after the failure");
    small.destroy(gl);
    assert_eq!(live_objects(), before);
}
