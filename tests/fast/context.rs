//! Headless context creation, rendering and threading, for every backend.
//!
//! A backend whose system library is missing is skipped (with `skipped:
//! <reason>` on stderr), never failed; once its library loads, every failure
//! is a real one.

use std::sync::{Arc, Barrier};
use std::thread;

use deferred_msaa_lab::context::Error;
use deferred_msaa_lab::context::{Backend, ContextRequest, GlVersion, HeadlessContext};
use glow::HasContext;

use crate::common;

/// Whether `backend`'s library is installed; prints `skipped: ...` if not.
fn available(backend: Backend) -> bool {
    match backend.check_library() {
        Ok(()) => true,
        Err(e) => {
            common::skip(&e.to_string());
            false
        }
    }
}

/// A context, or `None` (after printing why) when the backend's library is
/// missing. Any other failure fails the test.
fn context(backend: Backend) -> Option<HeadlessContext> {
    context_with(backend, &ContextRequest::default())
}

fn context_with(backend: Backend, req: &ContextRequest) -> Option<HeadlessContext> {
    if !available(backend) {
        return None;
    }
    match HeadlessContext::with_request(backend, req) {
        Ok(ctx) => Some(ctx),
        Err(e) => panic!("creating a {backend} context ({req:?}) failed: {e}"),
    }
}

/// Clears a small RGBA8 renderbuffer FBO to `color` and reads it back; every
/// pixel must be the same. The context must be current.
fn clear_and_read(gl: &glow::Context, color: [f32; 4]) -> [u8; 4] {
    const SIZE: i32 = 8;
    // SAFETY: the caller's context is current; every object is deleted again.
    unsafe {
        let rb = gl.create_renderbuffer().expect("renderbuffer");
        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
        gl.renderbuffer_storage(glow::RENDERBUFFER, glow::RGBA8, SIZE, SIZE);
        let fbo = gl.create_framebuffer().expect("framebuffer");
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_renderbuffer(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::RENDERBUFFER,
            Some(rb),
        );
        assert_eq!(
            gl.check_framebuffer_status(glow::FRAMEBUFFER),
            glow::FRAMEBUFFER_COMPLETE
        );
        gl.viewport(0, 0, SIZE, SIZE);
        gl.clear_color(color[0], color[1], color[2], color[3]);
        gl.clear(glow::COLOR_BUFFER_BIT);
        let mut pixels = vec![0u8; (SIZE * SIZE * 4) as usize];
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.read_pixels(
            0,
            0,
            SIZE,
            SIZE,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelPackData::Slice(Some(&mut pixels)),
        );
        assert_eq!(gl.get_error(), glow::NO_ERROR);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.delete_framebuffer(fbo);
        gl.delete_renderbuffer(rb);
        let first = [pixels[0], pixels[1], pixels[2], pixels[3]];
        for (i, px) in pixels.chunks_exact(4).enumerate() {
            assert_eq!(px, first, "pixel {i} differs from pixel 0");
        }
        first
    }
}

/// The bytes a clear to `color` should give, within one step of rounding.
fn assert_color(got: [u8; 4], color: [f32; 4]) {
    for (g, c) in got.iter().zip(color) {
        let want = (c * 255.0).round();
        assert!(
            (f32::from(*g) - want).abs() <= 1.0,
            "read back {got:?}, expected about {color:?} * 255"
        );
    }
}

fn check_basic(backend: Backend) {
    let Some(ctx) = context(backend) else { return };
    assert_eq!(ctx.backend(), backend);
    let v = ctx.version();
    assert!(v.at_least(3, 2), "{backend}: {v:?}");
    assert!(v.glsl_at_least(1, 50), "{backend}: {v:?}");
    assert!(!v.renderer.is_empty());
    assert!(!v.vendor.is_empty());
    // SAFETY: the context is current on this thread since creation.
    let renderer = unsafe { ctx.gl().get_parameter_string(glow::RENDERER) };
    assert!(!renderer.is_empty());
    assert_eq!(renderer, v.renderer);
    // A core context: no compatibility bit.
    // SAFETY: as above.
    let profile = unsafe { ctx.gl().get_parameter_i32(glow::CONTEXT_PROFILE_MASK) };
    assert_eq!(
        profile as u32 & glow::CONTEXT_CORE_PROFILE_BIT,
        glow::CONTEXT_CORE_PROFILE_BIT,
        "{backend}: not a core profile context"
    );
    assert_eq!(GlVersion::query(ctx.gl()), v);

    let color = [0.25, 0.5, 0.75, 1.0];
    assert_color(clear_and_read(ctx.gl(), color), color);

    assert!(!ctx.get_proc_address("glGetMultisamplefv").is_null());
    assert!(!ctx.get_proc_address("glClear").is_null());
    assert!(ctx.get_proc_address("glClear\0junk").is_null());
    eprintln!("{backend}: {v}");
}

#[test]
fn egl_creates_a_usable_core_context() {
    check_basic(Backend::Egl);
}

#[test]
fn osmesa_creates_a_usable_core_context() {
    check_basic(Backend::OsMesa);
}

#[test]
fn version_floor() {
    let exact_32 = std::env::var("MESA_GL_VERSION_OVERRIDE").is_ok_and(|v| v == "3.2");
    let glsl_150 = std::env::var("MESA_GLSL_VERSION_OVERRIDE").is_ok_and(|v| v == "150");
    for backend in Backend::all() {
        let Some(ctx) = context(backend) else {
            continue;
        };
        let v = ctx.version();
        assert!(v.at_least(3, 2), "{backend}: {v:?}");
        if exact_32 {
            assert_eq!((v.major, v.minor), (3, 2), "{backend}: {v:?}");
        }
        if glsl_150 {
            assert_eq!((v.glsl_major, v.glsl_minor), (1, 50), "{backend}: {v:?}");
        }
    }
}

#[test]
fn requests_below_the_floor_are_refused() {
    let req = ContextRequest {
        major: 3,
        minor: 1,
        debug: false,
    };
    for backend in Backend::all() {
        match HeadlessContext::with_request(backend, &req) {
            Err(Error::InvalidArgument(msg)) => assert!(msg.contains("3.2"), "{msg}"),
            other => panic!("{backend}: expected InvalidArgument, got {other:?}"),
        }
    }
}

#[test]
fn contexts_in_sequence() {
    for backend in Backend::all() {
        for (i, color) in [
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0, 1.0],
            [0.0, 0.0, 1.0, 1.0],
        ]
        .into_iter()
        .enumerate()
        {
            let Some(ctx) = context(backend) else { return };
            assert_color(clear_and_read(ctx.gl(), color), color);
            drop(ctx);
            eprintln!("{backend}: context {i} created, used and dropped");
        }
    }
}

#[test]
fn two_contexts_on_one_thread() {
    for backend in Backend::all() {
        let Some(a) = context(backend) else { continue };
        let Some(b) = context(backend) else { continue };
        let (ca, cb) = ([0.2, 0.4, 0.6, 1.0], [0.8, 0.6, 0.4, 1.0]);
        // `b` is current since its creation.
        assert_color(clear_and_read(b.gl(), cb), cb);
        a.make_current().unwrap();
        assert_color(clear_and_read(a.gl(), ca), ca);
        b.make_current().unwrap();
        assert_color(clear_and_read(b.gl(), cb), cb);
        // Releasing a context that is not current changes nothing.
        a.release_current().unwrap();
        assert_color(clear_and_read(b.gl(), cb), cb);
        // Dropping `a` (not current) leaves `b` current.
        drop(a);
        assert_color(clear_and_read(b.gl(), cb), cb);
        b.release_current().unwrap();
        b.make_current().unwrap();
        assert_color(clear_and_read(b.gl(), cb), cb);
    }
}

/// Each thread creates its own context and clears its own colour many times
/// while the other does the same.
fn two_threads_at_once(backends: [Backend; 2]) {
    if !backends.iter().all(|b| available(*b)) {
        return;
    }
    let barrier = Arc::new(Barrier::new(2));
    let colors = [[1.0, 0.5, 0.0, 1.0], [0.0, 0.25, 1.0, 0.5]];
    let handles: Vec<_> = backends
        .into_iter()
        .zip(colors)
        .map(|(backend, color)| {
            let barrier = Arc::clone(&barrier);
            thread::spawn(move || {
                let ctx = context(backend).expect("library checked above");
                barrier.wait();
                for _ in 0..100 {
                    assert_color(clear_and_read(ctx.gl(), color), color);
                }
                barrier.wait();
                drop(ctx);
            })
        })
        .collect();
    for h in handles {
        h.join().expect("a rendering thread panicked");
    }
}

#[test]
fn egl_two_threads_at_once() {
    two_threads_at_once([Backend::Egl, Backend::Egl]);
}

#[test]
fn osmesa_two_threads_at_once() {
    two_threads_at_once([Backend::OsMesa, Backend::OsMesa]);
}

#[test]
fn egl_and_osmesa_threads_at_once() {
    two_threads_at_once([Backend::Egl, Backend::OsMesa]);
}

/// Contexts created and dropped on several threads at once, so that the
/// shared EGL display is terminated and initialised again while other threads
/// create theirs.
#[test]
fn contexts_come_and_go_on_many_threads() {
    for backend in Backend::all() {
        if !available(backend) {
            continue;
        }
        let handles: Vec<_> = (0..4)
            .map(|t| {
                thread::spawn(move || {
                    let color = [0.2 * t as f32, 1.0 - 0.2 * t as f32, 0.5, 1.0];
                    for _ in 0..8 {
                        let ctx = context(backend).expect("library checked above");
                        assert_color(clear_and_read(ctx.gl(), color), color);
                    }
                })
            })
            .collect();
        for h in handles {
            h.join().expect("a thread panicked");
        }
    }
}

#[test]
fn a_context_moves_to_another_thread() {
    for backend in Backend::all() {
        let Some(ctx) = context(backend) else {
            continue;
        };
        let color = [0.1, 0.9, 0.3, 1.0];
        ctx.release_current().unwrap();
        let ctx = thread::spawn(move || {
            ctx.make_current().unwrap();
            assert_color(clear_and_read(ctx.gl(), color), color);
            ctx.release_current().unwrap();
            ctx
        })
        .join()
        .expect("the other thread panicked");
        ctx.make_current().unwrap();
        assert_color(clear_and_read(ctx.gl(), color), color);
    }
}

#[test]
fn make_current_fails_while_current_elsewhere() {
    // OSMesa does not check this (it is the caller's duty); EGL refuses.
    for backend in [Backend::Egl] {
        let Some(ctx) = context(backend) else {
            continue;
        };
        let ctx = Arc::new(std::sync::Mutex::new(ctx));
        // Current on this thread; another thread must be refused.
        let c2 = Arc::clone(&ctx);
        let result = thread::spawn(move || {
            let guard = c2.lock().unwrap();
            guard.make_current().map_err(|e| e.to_string())
        })
        .join()
        .expect("thread panicked");
        let err = result.expect_err("EGL made a context current on two threads");
        assert!(err.contains("EGL_BAD_ACCESS"), "{err}");
    }
}

#[test]
fn debug_context_delivers_messages_and_drops_cleanly() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let req = ContextRequest {
        debug: true,
        ..ContextRequest::default()
    };
    for backend in Backend::all() {
        let Some(mut ctx) = context_with(backend, &req) else {
            continue;
        };
        if backend == Backend::Egl {
            // SAFETY: current context.
            let flags = unsafe { ctx.gl().get_parameter_i32(glow::CONTEXT_FLAGS) };
            assert_ne!(
                flags as u32 & glow::CONTEXT_FLAG_DEBUG_BIT,
                0,
                "{backend}: not a debug context"
            );
        }
        if !ctx.gl().supports_debug() {
            common::skip(&format!("{backend} context offers no debug output"));
            continue;
        }
        let seen = Arc::new(AtomicUsize::new(0));
        let counter = Arc::clone(&seen);
        // SAFETY: current context; the callback is Send + Sync.
        unsafe {
            let gl = ctx.gl_mut();
            gl.enable(glow::DEBUG_OUTPUT);
            gl.enable(glow::DEBUG_OUTPUT_SYNCHRONOUS);
            gl.debug_message_callback(move |_source, _ty, id, _severity, msg| {
                if id == 4242 && msg == "hello" {
                    counter.fetch_add(1, Ordering::SeqCst);
                }
            });
            ctx.gl().debug_message_insert(
                glow::DEBUG_SOURCE_APPLICATION,
                glow::DEBUG_TYPE_MARKER,
                4242,
                glow::DEBUG_SEVERITY_NOTIFICATION,
                "hello",
            );
        }
        assert_eq!(
            seen.load(Ordering::SeqCst),
            1,
            "{backend}: callback not called"
        );
        // Drop it while another context is current: the callback must be
        // unset on its own context, and the other one stay current.
        let Some(other) = context(backend) else {
            continue;
        };
        drop(ctx);
        let color = [0.5, 0.5, 0.5, 1.0];
        assert_color(clear_and_read(other.gl(), color), color);
    }
}

#[test]
fn backend_names_round_trip() {
    assert_eq!(Backend::all(), [Backend::Egl, Backend::OsMesa]);
    assert_eq!(Backend::default(), Backend::Egl);
    for b in Backend::all() {
        assert_eq!(b.to_string(), b.name());
        assert_eq!(b.name().parse::<Backend>().unwrap(), b);
    }
    assert_eq!("OSMesa".parse::<Backend>().unwrap(), Backend::OsMesa);
    assert_eq!(" EGL ".parse::<Backend>().unwrap(), Backend::Egl);
    let err = "glx".parse::<Backend>().unwrap_err();
    assert!(matches!(err, Error::InvalidArgument(_)));
    assert_eq!(
        err.to_string(),
        "unknown backend `glx`: expected `egl` or `osmesa`"
    );
}

#[test]
fn default_request_is_3_2_core() {
    let r = ContextRequest::default();
    assert_eq!((r.major, r.minor, r.debug), (3, 2, false));
}

#[test]
fn error_messages_are_one_clear_line() {
    let e = Error::BackendUnavailable {
        backend: "osmesa",
        reason: "cannot load libOSMesa.so.8 (libOSMesa.so.8: cannot open shared object file: No such file or directory); install the Debian package libosmesa6".into(),
    };
    let text = e.to_string();
    assert!(!text.contains('\n'));
    assert!(text.starts_with("osmesa backend unavailable: cannot load libOSMesa.so.8"));
    assert!(text.contains("libosmesa6"));

    let e = Error::GlVersionTooLow {
        found: "3.1 Mesa 22.3.6".into(),
    };
    let text = e.to_string();
    assert!(!text.contains('\n'));
    assert!(
        text.contains("3.1 Mesa 22.3.6") && text.contains("3.2"),
        "{text}"
    );
}
