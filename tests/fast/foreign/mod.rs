//! A Rust host on the previous glow release (0.17, the glow of three-d and
//! Fyrox when this was written) retrofitted through
//! `deferred_msaa::foreign::ForeignRetrofit`: its G-buffer, shaders and
//! lighting are glow 0.17 calls only, its loader is the lab's headless EGL
//! context's `get_proc_address`, and only raw GL names cross to the crate.
//! With one layer and with two:
//!
//! - every call succeeds, leaves no GL error and leaves the host's GL state
//!   as it was (the snapshot of `common::gl_state`, read around each call);
//! - with two layers the second lighting runs and the mix changes the lit
//!   image at some pixels;
//! - a second frame runs the other calls (`begin_frame`, the second layer
//!   lit into the crate's own target, the forward target with nothing
//!   drawn, which leaves the lit image bit for bit), under the same checks;
//! - no GL object of the crate's is left after `destroy`;
//! - the lit image is closer (FLIP mean) to the host's own 16x supersampled
//!   image (the host drawn at 4x the width and height, averaged 4x4) than
//!   the host's image without MSAA, and two layers closer than one (on
//!   both frames).
//!
//! And a loader that lacks a function the crate calls is refused as
//! `Error::Unsupported` naming it, with nothing made and no GL error.
//!
//! `cargo test --test fast foreign -- --nocapture` prints the FLIP figures.

mod host;

use crate::common;
use crate::common::gl_state::GlState;
use deferred_msaa::foreign::ForeignRetrofit;
use deferred_msaa::resolve::NormalEncoding;
use deferred_msaa::{ColorAttachment, Frame, LayerMix, NormalAttachment, RetrofitOptions};
use deferred_msaa_lab::compare::flip;
use glow017::HasContext;
use host::*;
use image::RgbaImage;

/// The host retrofitted through `ForeignRetrofit` with `layers` layers,
/// two frames: its lit image with the second layer lit into its own
/// target, then with it lit into the crate's own target (and the forward
/// target run with nothing drawn), and what went wrong, call by call.
fn retrofitted(
    ctx: &deferred_msaa_lab::context::HeadlessContext,
    gl: &glow017::Context,
    layers: u32,
    layer_mix: LayerMix,
) -> (RgbaImage, RgbaImage, Vec<String>) {
    let state = ctx.gl(); // the lab's glow 0.18, for the state snapshot only
    let mut failures = Vec::new();
    let checked = |what: &str, before: &GlState, failures: &mut Vec<String>| {
        for d in before.differences(&GlState::capture(state)) {
            failures.push(format!("{what} changed the host's state: {d}"));
        }
        let error = unsafe { gl.get_error() };
        if error != glow017::NO_ERROR {
            failures.push(format!("{what} left GL error 0x{error:04X}"));
        }
    };
    let live_before = deferred_msaa::gl::live_objects().total();
    let host = Host017::new(gl, W, H);
    let mut options = RetrofitOptions {
        samples: 4,
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(1),
            encoding: NormalEncoding::Xyz,
        }),
        layer_mix,
        ..RetrofitOptions::default()
    };
    options.resolve.layers = layers;

    let before = GlState::capture(state);
    // SAFETY: the headless context is current on this thread, and its
    // loader gives its entry points.
    let made = unsafe {
        ForeignRetrofit::new(|name| ctx.get_proc_address(name), host.gbuffer.0, &options)
    };
    let mut msaa = match made {
        Ok(m) => m,
        Err(e) => panic!("the retrofit refuses the glow 0.17 host's G-buffer: {e}"),
    };
    checked("ForeignRetrofit::new", &before, &mut failures);

    // The geometry pass into the retrofit's framebuffer, named in glow 0.17.
    let before = GlState::capture(state);
    let fbo = match msaa.begin_frame() {
        Ok(f) => f,
        Err(e) => {
            failures.push(format!("begin_frame: {e}"));
            msaa.framebuffer()
        }
    };
    checked("begin_frame", &before, &mut failures);
    host.geometry_pass(gl, glow017::NativeFramebuffer(fbo));
    let before = GlState::capture(state);
    if let Err(e) = msaa.resolve(&Frame::from_matrix(projection())) {
        failures.push(format!("resolve: {e}"));
    }
    checked("resolve", &before, &mut failures);
    host.lighting_pass(gl);
    let first = host.read_lit(gl);

    let output = Some(host.lit_fbo.0);
    let before = GlState::capture(state);
    let began = msaa.begin_second_layer(output);
    checked("begin_second_layer", &before, &mut failures);
    match (layers, began) {
        (1, Ok(false)) => {}
        (2, Ok(true)) => {
            host.lighting_pass(gl); // the engine's lighting, unchanged, again
            let before = GlState::capture(state);
            if let Err(e) = msaa.finish_second_layer(output) {
                failures.push(format!("finish_second_layer: {e}"));
            }
            checked("finish_second_layer", &before, &mut failures);
        }
        (_, Ok(began)) => failures.push(format!(
            "begin_second_layer with {layers} layer(s) said {began}"
        )),
        (_, Err(e)) => failures.push(format!("begin_second_layer: {e}")),
    }
    let image = host.read_lit(gl);
    if layers == 2 {
        let mixed = first
            .pixels()
            .zip(image.pixels())
            .filter(|(a, b)| a != b)
            .count();
        println!("foreign: two layers: the mix changed {mixed} pixels");
        if mixed == 0 {
            failures.push("the second layer changed no pixel of the lit image".into());
        }
    }

    // A second frame through the other calls: the second layer lit into
    // the crate's own target, and the forward target with
    // no forward object drawn, which must leave the lit image as it was.
    let frame_fbo = match msaa.begin_frame() {
        Ok(f) => f,
        Err(e) => {
            failures.push(format!("begin_frame: {e}"));
            msaa.framebuffer()
        }
    };
    if frame_fbo != msaa.framebuffer() {
        failures.push("begin_frame gave another framebuffer than framebuffer()".into());
    }
    host.geometry_pass(gl, glow017::NativeFramebuffer(frame_fbo));
    let before = GlState::capture(state);
    if let Err(e) = msaa.resolve(&Frame::from_matrix(projection())) {
        failures.push(format!("second frame: resolve: {e}"));
    }
    checked("second frame: resolve", &before, &mut failures);
    host.lighting_pass(gl);
    let before = GlState::capture(state);
    let own = msaa.begin_second_layer_own_target(output);
    checked("begin_second_layer_own_target", &before, &mut failures);
    match (layers, own) {
        (1, Ok(None)) => {}
        (2, Ok(Some(target))) => {
            host.lighting_into(gl, glow017::NativeFramebuffer(target));
            let before = GlState::capture(state);
            if let Err(e) = msaa.finish_second_layer(output) {
                failures.push(format!("second frame: finish_second_layer: {e}"));
            }
            // The one change: the output bound where the engine left the
            // own target, as if it had lit into it.
            let bound = |pname| unsafe { gl.get_parameter_i32(pname) } as u32;
            for pname in [
                glow017::DRAW_FRAMEBUFFER_BINDING,
                glow017::READ_FRAMEBUFFER_BINDING,
            ] {
                if bound(pname) != host.lit_fbo.0.get() {
                    failures.push(format!(
                        "second frame: finish_second_layer left framebuffer {} bound (0x{pname:04x}), not the output {}",
                        bound(pname),
                        host.lit_fbo.0
                    ));
                }
            }
            unsafe {
                gl.bind_framebuffer(
                    glow017::FRAMEBUFFER,
                    Some(glow017::NativeFramebuffer(target)),
                )
            };
            checked("second frame: finish_second_layer", &before, &mut failures);
        }
        (_, Ok(own)) => failures.push(format!(
            "begin_second_layer_own_target with {layers} layer(s) gave {own:?}"
        )),
        (_, Err(e)) => failures.push(format!("begin_second_layer_own_target: {e}")),
    }
    let own_image = host.read_lit(gl);
    let before = GlState::capture(state);
    let forward = msaa.begin_forward(output);
    checked("begin_forward", &before, &mut failures);
    match forward {
        Ok(_) => {
            let before = GlState::capture(state);
            if let Err(e) = msaa.finish_forward(output) {
                failures.push(format!("finish_forward: {e}"));
            }
            checked("finish_forward", &before, &mut failures);
        }
        Err(e) => failures.push(format!("begin_forward: {e}")),
    }
    let changed = own_image
        .pixels()
        .zip(host.read_lit(gl).pixels())
        .filter(|(a, b)| a != b)
        .count();
    if changed != 0 {
        failures.push(format!(
            "the forward target with nothing drawn changed {changed} pixels of the lit image"
        ));
    }

    // The end of the frame: the host binds its window's framebuffer (one
    // of the crate's left bound would fall back to 0 when destroy frees it,
    // as glDeleteFramebuffers does).
    unsafe { gl.bind_framebuffer(glow017::FRAMEBUFFER, None) };
    let before = GlState::capture(state);
    msaa.destroy();
    checked("destroy", &before, &mut failures);
    let live = deferred_msaa::gl::live_objects().total();
    if live != live_before {
        failures.push(format!(
            "{} GL objects of the crate's left after destroy",
            live - live_before
        ));
    }
    host.destroy(gl);
    (image, own_image, failures)
}

#[test]
fn glow017_host_retrofits_through_the_foreign_entry_point() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    // The host's own glow, made from the same loader.
    // SAFETY: the context is current on this thread.
    let gl = unsafe { glow017::Context::from_loader_function(|name| ctx.get_proc_address(name)) };

    let reference = host_image(&gl, 4);
    let none = host_image(&gl, 1);
    let mut failures = Vec::new();
    let mut flips = Vec::new();
    let mut own_flips = Vec::new();
    for layers in [1, 2] {
        // Nothing declared: an RGBA8 target, inferred as the display values
        // the engine's shader encodes (docs/hosts.md).
        let (image, own_image, f) = retrofitted(&ctx, &gl, layers, LayerMix::Auto);
        failures.extend(f.into_iter().map(|f| format!("{layers} layer(s): {f}")));
        flips.push(flip(&reference, &image).expect("flip").mean);
        own_flips.push(flip(&reference, &own_image).expect("flip").mean);
    }
    let flip_none = flip(&reference, &none).expect("flip").mean;
    // Over the frame's edge pixels, two layers against no MSAA.
    let mask = edges(&gl);
    let (none_edges, two_edges) = {
        let two = retrofitted(&ctx, &gl, 2, LayerMix::Auto).0;
        let by = |i: &RgbaImage| {
            deferred_msaa_lab::compare::flip_by_mask(&reference, i, &mask)
                .expect("sizes")
                .marked
                .expect("edge pixels")
        };
        (by(&none), by(&two))
    };
    println!(
        "foreign: over the edge pixels ({:.1} % of the frame): none {none_edges:.4}, two layers {two_edges:.4} ({:.2}x); whole frame {:.2}x",
        100.0 * mask.pixels().filter(|p| p[0] != 0).count() as f64 / f64::from(W * H),
        two_edges / none_edges,
        flips[1] / flip_none
    );
    if flips[1] > 0.7 * flip_none {
        failures.push(format!(
            "two layers {:.4} above 0.7x no MSAA's {flip_none:.4}",
            flips[1]
        ));
    }
    if two_edges > 0.6 * none_edges {
        failures.push(format!(
            "two layers over edges {two_edges:.4} above 0.6x no MSAA's {none_edges:.4}"
        ));
    }
    println!(
        "foreign: FLIP against the host's 16x image: none {flip_none:.4}, one layer {:.4}, two layers {:.4}; second frame (the crate's own target): one layer {:.4}, two layers {:.4}",
        flips[0], flips[1], own_flips[0], own_flips[1]
    );
    if own_flips[1] >= own_flips[0] {
        failures.push(format!(
            "two layers lit into the crate's own target are no closer to the 16x image than one: {:.4} vs {:.4}",
            own_flips[1], own_flips[0]
        ));
    }
    if flips[0] >= flip_none {
        failures.push(format!(
            "one layer is no closer to the 16x image than no MSAA: {:.4} vs {flip_none:.4}",
            flips[0]
        ));
    }
    if flips[1] >= flips[0] {
        failures.push(format!(
            "two layers are no closer to the 16x image than one: {:.4} vs {:.4}",
            flips[1], flips[0]
        ));
    }
    let error = unsafe { gl.get_error() };
    if error != glow017::NO_ERROR {
        failures.push(format!("GL error 0x{error:04X} at the end"));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_loader_without_a_function_the_crate_calls_is_refused_naming_it() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    // SAFETY: the context is current on this thread.
    let gl = unsafe { glow017::Context::from_loader_function(|name| ctx.get_proc_address(name)) };
    let host = Host017::new(&gl, W, H);
    let live_before = deferred_msaa::gl::live_objects().total();
    let missing = "glBlitFramebuffer";
    assert!(deferred_msaa_lab::gl::REQUIRED_FUNCTIONS.contains(&missing));
    let loader = |name: &str| {
        if name == missing {
            std::ptr::null()
        } else {
            ctx.get_proc_address(name)
        }
    };
    // SAFETY: as above; the null entry is the point of the test.
    let made = unsafe { ForeignRetrofit::new(loader, host.gbuffer.0, &RetrofitOptions::default()) };
    match made {
        Err(e @ deferred_msaa::Error::Unsupported { .. }) => {
            assert!(e.to_string().contains(missing), "{e}")
        }
        Err(e) => panic!("refused, but not as Unsupported: {e}"),
        Ok(m) => {
            m.destroy();
            panic!("a loader without {missing} was accepted");
        }
    }
    assert_eq!(deferred_msaa::gl::live_objects().total(), live_before);
    assert_eq!(unsafe { gl.get_error() }, glow017::NO_ERROR);
    host.destroy(&gl);
}

/// The engine's render-target wrapper takes the framebuffer it is given
/// and deletes it when dropped, as Rust engines' wrappers do: wrapping the
/// crate's framebuffer that way deletes it. The next `begin_frame` and
/// `resolve` return an error naming it, never a frame of stale samples;
/// `refresh` makes new twins, and the frame after is resolved.
#[test]
fn a_wrapper_that_drops_the_crates_framebuffer_is_an_error_then_refresh() {
    struct RenderTarget<'a> {
        gl: &'a glow017::Context,
        fbo: glow017::Framebuffer,
    }
    impl Drop for RenderTarget<'_> {
        fn drop(&mut self) {
            unsafe { self.gl.delete_framebuffer(self.fbo) };
        }
    }
    let Some(ctx) = common::egl_context() else {
        return;
    };
    // SAFETY: the context is current on this thread.
    let gl = unsafe { glow017::Context::from_loader_function(|name| ctx.get_proc_address(name)) };
    let host = Host017::new(&gl, W, H);
    let options = RetrofitOptions::default();
    // SAFETY: as above; the loader gives the context's entry points.
    let mut msaa = unsafe {
        ForeignRetrofit::new(|name| ctx.get_proc_address(name), host.gbuffer.0, &options)
    }
    .expect("the retrofit");
    let frame = Frame::from_matrix(projection());
    {
        let target = RenderTarget {
            gl: &gl,
            fbo: glow017::NativeFramebuffer(msaa.begin_frame().expect("begin_frame")),
        };
        host.geometry_pass(&gl, target.fbo);
        msaa.resolve(&frame).expect("the first frame");
    }
    unsafe { gl.bind_framebuffer(glow017::FRAMEBUFFER, None) };
    let text = msaa
        .begin_frame()
        .expect_err("a deleted framebuffer")
        .to_string();
    assert!(
        text.contains("was deleted") && text.contains("refresh"),
        "{text}"
    );
    let text = msaa
        .resolve(&frame)
        .expect_err("a deleted framebuffer")
        .to_string();
    assert!(text.contains("was deleted"), "{text}");
    msaa.refresh().expect("refresh");
    let fbo = glow017::NativeFramebuffer(msaa.begin_frame().expect("begin_frame after refresh"));
    host.geometry_pass(&gl, fbo);
    msaa.resolve(&frame).expect("the frame after refresh");
    assert_eq!(unsafe { gl.get_error() }, glow017::NO_ERROR);
    msaa.destroy();
    host.destroy(&gl);
    assert_eq!(deferred_msaa::gl::live_objects().total(), 0);
}

/// With nothing declared (`LayerMix::Auto`), two layers come within 1.1x
/// of the best declaration's FLIP against the host's 16x image, over the
/// whole frame and over its edge pixels: the engine's shader encodes sRGB
/// into `RGBA8`, which `Auto` mixes as sRGB-encoded display values.
#[test]
fn glow017_host_mixes_right_with_nothing_declared() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    // SAFETY: the context is current on this thread.
    let gl = unsafe { glow017::Context::from_loader_function(|name| ctx.get_proc_address(name)) };
    let reference = host_image(&gl, 4);
    let none = host_image(&gl, 1);
    let mask = edges(&gl);
    let measure = |i: &RgbaImage| {
        let whole = flip(&reference, i).expect("flip").mean;
        let edge = deferred_msaa_lab::compare::flip_by_mask(&reference, i, &mask)
            .expect("sizes")
            .marked
            .expect("edge pixels");
        (whole, edge)
    };
    let (none_flip, none_edges) = measure(&none);
    println!("foreign, two layers by layer_mix: none {none_flip:.4} ({none_edges:.4} over edges)");
    let mut failures = Vec::new();
    let mut measured = Vec::new();
    for mix in [
        LayerMix::Auto,
        LayerMix::SrgbEncoded,
        LayerMix::Linear,
        LayerMix::Tonemapped,
    ] {
        let (image, _, f) = retrofitted(&ctx, &gl, 2, mix.clone());
        failures.extend(f.into_iter().map(|f| format!("{mix:?}: {f}")));
        let (whole, edge) = measure(&image);
        println!(
            "foreign, two layers, {mix:?}: {whole:.4} ({:.2}x none), over edges {edge:.4} ({:.2}x)",
            whole / none_flip,
            edge / none_edges
        );
        measured.push((mix, whole, edge));
    }
    let (_, auto, auto_edges) = measured[0].clone();
    let best = measured[1..]
        .iter()
        .map(|m| m.1)
        .fold(f32::INFINITY, f32::min);
    let best_edges = measured[1..]
        .iter()
        .map(|m| m.2)
        .fold(f64::INFINITY, f64::min);
    if auto > 1.1 * best {
        failures.push(format!(
            "Auto {auto:.4} is above 1.1x the best declaration's {best:.4}"
        ));
    }
    if auto_edges > 1.1 * best_edges {
        failures.push(format!(
            "Auto over edges {auto_edges:.4} is above 1.1x the best declaration's {best_edges:.4}"
        ));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
