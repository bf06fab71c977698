//! The host's GL state kept exactly through the C API's calls, under
//! misuse too (`tests/common/misuse/`, whose fuzzer the slow tier runs
//! over thousands of sequences): one named sequence per way it was lost,
//! and a few hundred random sequences.
//!
//! - Per-buffer blend enables and colour masks (`glEnablei`,
//!   `glColorMaski`), which a non-indexed save and restore collapsed to
//!   buffer 0's.
//! - The stencil references with framebuffer 0 bound (no stencil bits on a
//!   surfaceless context), which a query clamps to 0.
//! - A loader that returns null for one function: `UNSUPPORTED` naming it,
//!   nothing changed or left allocated, for every function the library
//!   calls.
//! - A framebuffer id that is no framebuffer: a message saying so, no GL
//!   error left.
//! - A host that re-allocates one attachment at another size, has
//!   `set_options` and `refresh` refused, and puts its G-buffer back: the
//!   handle refreshes and resolves the right frame.

use crate::common;
use crate::common::misuse::{
    Api, Fbo, Op, Options, Projection, Sequence, Setting, Which, loader_names, run_sequence,
};

const H: Which = Which::Slot(0);

/// A sequence over a host of `colors` attachments and depth with or
/// without stencil, through the C API.
fn sequence(colors: usize, stencil: bool, ops: Vec<Op>) -> Sequence {
    on(Api::C, colors, stencil, ops)
}

/// The same through `api`.
fn on(api: Api, colors: usize, stencil: bool, ops: Vec<Op>) -> Sequence {
    Sequence {
        seed: 0,
        api,
        colors,
        stencil,
        ops,
    }
}

fn new(fbo: Fbo, options: &[(u8, i64)]) -> Op {
    Op::New {
        fbo,
        options: Options(options.to_vec()),
        missing: None,
    }
}

/// Every call a frame with two layers makes, with the settings left
/// behind before each.
fn every_call(settings: &[Setting]) -> Vec<Op> {
    let set = || settings.iter().map(|s| Op::Set(*s));
    let mut ops: Vec<Op> = set().collect();
    for op in [
        new(Fbo::Host, &[]),
        Op::Draw(H),
        Op::Resolve(H, Projection::Perspective, false),
        Op::SetOptions(H, Options(vec![(1, 2)])),
        Op::Draw(H),
        Op::Resolve(H, Projection::Perspective, false),
        Op::Begin(H, Fbo::Light, false),
        Op::Finish(H, Fbo::Light),
        Op::Refresh(H),
        Op::Recover(H),
        Op::Destroy(H),
    ] {
        ops.push(op);
        ops.extend(set());
    }
    ops
}

fn assert_clean(sequence: &Sequence) {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let failures = run_sequence(&ctx, sequence);
    assert!(
        failures.is_empty(),
        "{}\n{}",
        failures.join("\n"),
        sequence.describe()
    );
}

#[test]
fn per_buffer_blend_enables_survive_every_call() {
    for (api, stencil) in [(Api::C, false), (Api::C, true), (Api::Rust, true)] {
        assert_clean(&on(
            api,
            3,
            stencil,
            every_call(&[Setting::BlendOnlyOn(1), Setting::BlendOnlyOn(2)]),
        ));
    }
}

#[test]
fn per_buffer_colour_masks_survive_every_call() {
    for (api, stencil) in [(Api::C, false), (Api::C, true), (Api::Rust, true)] {
        assert_clean(&on(
            api,
            3,
            stencil,
            every_call(&[Setting::MaskOff(1), Setting::MaskOff(5)]),
        ));
    }
}

#[test]
fn stencil_references_survive_with_framebuffer_zero_bound() {
    // With a depth-stencil host the stencil copy and the second layer's
    // selection set the stencil function; with a depth-only one nothing does.
    for (api, stencil) in [(Api::C, true), (Api::C, false), (Api::Rust, true)] {
        assert_clean(&on(
            api,
            2,
            stencil,
            every_call(&[
                Setting::DefaultFramebuffer,
                Setting::StencilReferences(200, 131),
            ]),
        ));
    }
}

#[test]
fn viewport_arrays_survive_every_call() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    if !common::gl_state::has_viewport_arrays(ctx.gl()) {
        eprintln!("not run: this context has no viewport arrays (GL 4.1)");
        return;
    }
    drop(ctx);
    for (api, stencil) in [(Api::C, true), (Api::Rust, false)] {
        assert_clean(&on(
            api,
            2,
            stencil,
            every_call(&[Setting::Viewport(1), Setting::Viewport(3)]),
        ));
    }
}

#[test]
fn a_loader_without_one_function_is_refused_naming_it() {
    // Every function the library calls, left out one at a time; the fuzzer
    // checks the status, the name in the message, `*out` null, the live
    // objects and the state.
    let ops = (0..loader_names().len())
        .map(|k| Op::New {
            fbo: Fbo::Host,
            options: Options(Vec::new()),
            missing: Some(k),
        })
        .collect();
    assert_clean(&sequence(2, true, ops));
}

#[test]
fn a_name_that_is_no_framebuffer_is_refused_as_such() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let s = sequence(1, false, vec![new(Fbo::NotAFramebuffer, &[])]);
    let failures = run_sequence(&ctx, &s);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let message = crate::common::misuse::last_message();
    assert!(message.contains("is not a framebuffer object"), "{message}");
    // A framebuffer without depth: refused, no GL error left (the fuzzer's
    // check).
    assert_clean(&sequence(1, false, vec![new(Fbo::Light, &[])]));
}

#[test]
fn a_handle_recovers_after_a_size_change() {
    for api in [Api::C, Api::Rust] {
        assert_clean(&on(
            api,
            3,
            true,
            vec![
                new(Fbo::Host, &[]),
                Op::Draw(H),
                Op::Resolve(H, Projection::Perspective, false),
                Op::Reallocate(1),
                Op::SetOptions(H, Options(vec![(1, 2)])),
                Op::Refresh(H),
                Op::Resolve(H, Projection::Perspective, false),
                Op::Reallocate(3),
                Op::Refresh(H),
                Op::Recover(H),
                Op::Delete(0),
                Op::Refresh(H),
                Op::Recover(H),
                Op::Reallocate(0),
                Op::SetOptions(H, Options(vec![(0, 1)])),
                Op::Recover(H),
            ],
        ));
    }
}

#[test]
fn random_call_sequences_keep_the_hosts_state() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let count = 60;
    let mut failed = Vec::new();
    for seed in 0..count {
        let s = Sequence::generate(seed);
        let failures = run_sequence(&ctx, &s);
        if !failures.is_empty() {
            failed.push(format!("{}{}", s.describe(), failures.join("\n")));
        }
    }
    eprintln!(
        "{count} random sequences: {}",
        crate::common::misuse::take_stats()
    );
    assert!(failed.is_empty(), "{}", failed.join("\n\n"));
}

#[test]
fn a_panic_puts_the_state_back_and_frees_what_was_made() {
    use deferred_msaa::gl::{Format, Made, Owned, SetupState, Texture2d, live_objects};
    use glow::HasContext;
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    unsafe {
        gl.enable_draw_buffer(glow::BLEND, 1);
        gl.color_mask_draw_buffer(2, false, true, false, true);
        gl.viewport(1, 2, 30, 40);
    }
    let before = common::gl_state::GlState::capture(gl);
    let live = live_objects().total();
    // A panic in the middle of a call: state changed, objects made, in a
    // constructor and after it.
    let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _host = SetupState::capture(gl).guard(gl);
        unsafe {
            gl.disable(glow::BLEND);
            gl.color_mask(true, true, true, true);
            gl.viewport(0, 0, 4, 4);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
        let kept = Owned::new(
            gl,
            Texture2d::new(gl, "made before the panic", Format::Rgba8, 4, 4).expect("a texture"),
        );
        let _: Result<(), deferred_msaa::Error> = Made::build(gl, |made| {
            made.keep(Texture2d::new(gl, "made inside", Format::Rgba8, 4, 4)?);
            assert_eq!(live_objects().total(), live + 2, "both textures made");
            panic!("deliberately, with texture {} alive", kept.raw().0);
        });
    }));
    assert!(unwound.is_err(), "the closure panics");
    let differences = before.differences(&common::gl_state::GlState::capture(gl));
    assert!(differences.is_empty(), "{}", differences.join("\n"));
    assert_eq!(live_objects().total(), live, "what was made was freed");
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
}
