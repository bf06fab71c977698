//! Engines' own habits around their G-buffer, which no GL state tells the
//! crate: clearing it through another framebuffer with values of their
//! own, wrapping the crate's framebuffer in a render target that deletes
//! it when dropped, a geometry pass whose bind failed. Each gets the right
//! frame or a returned error, never a silent black or frozen one.

use crate::common;

use deferred_msaa::{ColorAttachment, Error, TwinClear};
use deferred_msaa_lab::gl::{Attachment, Format, Framebuffer, TextureRef, live_objects};
use deferred_msaa_lab::readback::Readback;
use deferred_msaa_lab::retrofit::{MsaaRetrofit, RetrofitOptions};
use deferred_msaa_testkit::Host;
use deferred_msaa_testkit::projection::perspective;
use deferred_msaa_testkit::scene::triangle;
use glow::HasContext;

const W: u32 = 48;
const H: u32 = 32;

fn projection() -> [f64; 16] {
    perspective(0.8, W as f64 / H as f64, 0.5, Some(100.0))
}

fn frame() -> deferred_msaa::Frame {
    deferred_msaa_testkit::projection::frame(&projection(), false)
}

fn host(gl: &glow::Context) -> Host {
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
    let mut host = Host::new(gl, W, H, Format::Rgba32f, Format::Depth32f).unwrap();
    host.set_triangles(gl, &v).unwrap();
    host
}

/// The engine's clear framebuffer: its G-buffer's textures and one more
/// target of its own, each attachment cleared with its own value.
struct ClearTarget {
    extra: deferred_msaa_lab::gl::Texture2d,
    fbo: Framebuffer,
}

impl ClearTarget {
    fn new(gl: &glow::Context, host: &Host) -> Self {
        let extra = deferred_msaa_lab::gl::Texture2d::new(
            gl,
            "engine's other target",
            Format::Rgba16f,
            W,
            H,
        )
        .unwrap();
        let mut attachments: Vec<(Attachment, TextureRef)> = host
            .colors
            .iter()
            .enumerate()
            .map(|(k, (_, t))| (Attachment::Color(k as u32), TextureRef::from(t)))
            .collect();
        attachments.push((
            Attachment::Color(host.colors.len() as u32),
            TextureRef::from(&extra),
        ));
        attachments.push((Attachment::Depth, TextureRef::from(&host.depth)));
        let draw: Vec<Option<u32>> = (0..=host.colors.len() as u32).map(Some).collect();
        let fbo = Framebuffer::new(gl, "engine clear target", &attachments, &draw).unwrap();
        ClearTarget { extra, fbo }
    }

    /// Clear each attachment with the engine's value: position far away.
    fn clear(&self, gl: &glow::Context) {
        unsafe {
            self.fbo.bind(gl);
            gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 0.0]);
            gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0, 0.0, -65504.0, 1.0]);
            gl.clear_buffer_f32_slice(glow::COLOR, 2, &[0.0, 0.0, 1.0, 0.0]);
            gl.clear_buffer_f32_slice(glow::COLOR, 3, &[0.5, 0.5, 0.5, 1.0]);
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.extra.destroy(gl);
    }
}

/// The engine clears its G-buffer through a framebuffer of its own (its
/// textures and another target, each attachment with its own value: the
/// position far away), then binds the G-buffer, or the retrofit's
/// framebuffer in its place, and draws without clearing. The twins are
/// never cleared that way: with the values declared
/// (`RetrofitOptions::twin_clear`) and `begin_frame` each frame, the frame
/// is right, frame after frame, and the same as a host that clears through
/// the twins; the clear values land in the twins exactly. Without them,
/// every frame's resolve returns `Error::TwinsNotCleared` naming the fix
/// and writes nothing.
#[test]
fn a_host_clearing_through_another_framebuffer_declares_its_clear_values() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let clear = ClearTarget::new(gl, &host);
    let mut readback = Readback::new(gl).unwrap();
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    // The right frame: a host clearing through the twins.
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    unsafe {
        gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 0.0]);
        gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0, 0.0, -65504.0, 1.0]);
        gl.clear_buffer_f32_slice(glow::COLOR, 2, &[0.0, 0.0, 1.0, 0.0]);
        gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
    }
    host.draw_without_clear(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    let want: Vec<_> = host
        .colors
        .iter()
        .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1).unwrap().data)
        .collect();
    msaa.destroy(gl);

    // The engine's habit, with the values declared.
    let declared = RetrofitOptions {
        twin_clear: Some(TwinClear {
            colors: vec![
                (ColorAttachment(1), [0.0, 0.0, -65504.0, 1.0]),
                (ColorAttachment(2), [0.0, 0.0, 1.0, 0.0]),
            ],
            depth: 1.0,
            stencil: 0,
        }),
        ..options.clone()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &declared).unwrap();
    for n in 0..3 {
        clear.clear(gl);
        let fbo = msaa.begin_frame(gl).unwrap();
        assert_eq!(fbo, msaa.framebuffer());
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
        host.draw_without_clear(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
        for (k, (_, t)) in host.colors.iter().enumerate() {
            let got = readback.read(gl, TextureRef::from(t), 1).unwrap().data;
            assert!(
                got == want[k],
                "frame {n}: attachment {k} differs from the frame of a host clearing through the twins"
            );
        }
    }
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);

    // Without the declaration the twins are never cleared: each frame's
    // resolve says so, naming the fix, and resolves nothing (the host's
    // textures keep what its own clear put there).
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let mut cleared = Vec::new();
    for n in 0..3 {
        clear.clear(gl);
        cleared = host
            .colors
            .iter()
            .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1).unwrap().data)
            .collect::<Vec<_>>();
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw_without_clear(gl, &projection(), false);
        match msaa.resolve(gl, &frame()) {
            Err(e @ Error::TwinsNotCleared { .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains("twin_clear") && text.contains("begin_frame"),
                    "the error names the fix: {text}"
                );
            }
            other => panic!("frame {n}: an uncleared twin resolved as {other:?}"),
        }
        for (k, (_, t)) in host.colors.iter().enumerate() {
            let got = readback.read(gl, TextureRef::from(t), 1).unwrap().data;
            assert!(got == cleared[k], "frame {n}: attachment {k} was written");
        }
    }
    assert!(
        cleared[1] != want[1],
        "the host's cleared positions are the resolved frame's: the test shows nothing"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    readback.destroy(gl);
    clear.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// A Rust engine's render-target wrapper that deletes the framebuffer it
/// wraps when dropped deletes the retrofit's: the next frame's
/// `begin_frame` and `resolve` return an error naming it (no frozen frame
/// of stale samples), and `refresh` makes new twins that work. A geometry
/// pass whose bind failed leaves the host's GL error pending: `resolve`
/// returns it, resolving nothing.
#[test]
fn a_deleted_twin_or_a_failed_bind_is_a_returned_error() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let fbo = msaa.begin_frame(gl).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    // The wrapper drops: the framebuffer is gone.
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.delete_framebuffer(fbo);
    }
    for (what, result) in [
        ("begin_frame", msaa.begin_frame(gl).map(|_| ())),
        ("resolve", msaa.resolve(gl, &frame())),
    ] {
        match result {
            Err(Error::Retrofit { reason, .. }) => {
                assert!(
                    reason.contains("was deleted") && reason.contains("refresh"),
                    "{what}: {reason}"
                );
            }
            other => panic!("{what} after the framebuffer was deleted: {other:?}"),
        }
    }
    // The engine's next geometry pass binds the deleted name: an error the
    // host left pending, returned by the resolve.
    msaa.refresh(gl).unwrap();
    msaa.begin_frame(gl).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
    match msaa.resolve(gl, &frame()) {
        Err(e @ Error::HostGl { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("GL_INVALID_OPERATION") && !text.contains('\n'),
                "{text}"
            );
        }
        other => panic!("a resolve after a failed bind: {other:?}"),
    }
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    // Refreshed, the retrofit works again.
    let fbo = msaa.begin_frame(gl).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo)) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}
