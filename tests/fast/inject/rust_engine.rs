//! A Rust engine (`examples/inject_rust_engine.rs`, on glow 0.17: a
//! surfaceless EGL context through `khronos-egl` with libEGL loaded at run
//! time, a one-call render that makes its G-buffer of one
//! `GL_TEXTURE_2D_ARRAY`'s layers and deletes it each call, the camera as
//! one `viewProjection` uniform, the sRGB curve written by its lighting
//! shader, thin bars against the sky) under `inject`:
//!
//! - with no profile it is left alone, saying why in one line (a G-buffer
//!   made and deleted within each call) and naming the way out;
//! - `--learn` writes the G-buffer's signature and `view_projection_uniform`;
//! - that profile completed as a user would (the normal layer named and
//!   selected, two layers, the lit values declared display values): each
//!   call's new G-buffer retrofitted (`dmsaa_refresh_with`), the lighting
//!   replayed with the G-buffer's array bound, the frame of the same program
//!   with the retrofit in its source (`--in-source`) bit for bit, and at most
//!   0.7x its own frame's FLIP against its 16x image (0.6x over edges).

use super::runs::{clean_check, completed, inject, run_ok, said};
use super::{capi, frame};
use crate::common;
use deferred_msaa_lab::context::Backend;
use std::ffi::OsStr;
use std::process::Command;

#[test]
fn a_rust_engine_under_inject_draws_its_in_source_two_layers() {
    if let Err(e) = Backend::Egl.check_library() {
        common::skip(&e.to_string());
        return;
    }
    let engine = common::examples::example("inject_rust_engine");
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("inject-rust-engine");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).expect("making the output folder");
    let own = out.join("own.rgba");
    run_ok(
        Command::new(&engine).arg(&own).arg("--reference").arg(&out),
        "the Rust engine as it is",
    );
    let expected = out.join("in-source.rgba");
    run_ok(
        Command::new(&engine).arg(&expected).arg("--in-source"),
        "the Rust engine retrofitted in its source",
    );
    let library = capi::built("libdeferred_msaa_inject", "so");
    let none: [&str; 0] = [];

    // No profile: left alone, one line, its own frame.
    let left = out.join("no-profile.rgba");
    let stderr = inject(
        &library,
        none,
        &engine,
        [&left],
        "the Rust engine, no profile",
    );
    let lines = said(&stderr);
    assert!(
        lines.len() == 1
            && lines[0].contains("was deleted before it was bound for drawing again (3 time(s))")
            && lines[0].contains("give a profile its signature"),
        "no profile: not the one line of a one-call render:\n{stderr}"
    );
    assert!(
        frame(&left) == frame(&own),
        "left alone, yet not the program's own frame"
    );

    // --learn, then the profile completed.
    let learned = out.join("learned.toml");
    inject(
        &library,
        [OsStr::new("--learn"), learned.as_os_str()],
        &engine,
        [out.join("learn.rgba")],
        "--learn, the Rust engine",
    );
    let text = std::fs::read_to_string(&learned).expect("--learn wrote no profile");
    for line in [
        "colour_textures = 2",
        "formats = [\"float16\", \"float16\"]",
        "view_projection_uniform = \"viewProjection\"",
    ] {
        assert!(
            text.contains(line),
            "no `{line}` in the learned profile:\n{text}"
        );
    }
    let profile = out.join("engine.toml");
    std::fs::write(
        &profile,
        completed(
            &text,
            &[(
                1,
                "meaning = \"normal\"\nencoding = \"xyz\"\nrule = \"select\"\n",
            )],
            "[retrofit]\nlayers = 2\nlayer_mix = \"srgb-encoded\"\n",
        ),
    )
    .expect("writing the completed profile");
    let injected = out.join("two-layers.rgba");
    let stderr = inject(
        &library,
        [
            OsStr::new("--check"),
            OsStr::new("--profile"),
            profile.as_os_str(),
        ],
        &engine,
        [&injected],
        "the Rust engine, two layers",
    );
    let lines = said(&stderr);
    assert!(
        lines.len() == 1
            && lines[0].contains("2 layer(s), options from the profile")
            && lines[0].contains("the frame(s) before this one are the program's own"),
        "two layers: not the one line of the retrofit:\n{stderr}"
    );
    // The first call's G-buffer is bound before its camera is set: the
    // retrofit begins at the second call's, and the third call's new one
    // is given to it.
    let check = clean_check(&stderr, "the Rust engine, two layers", 2);
    for needle in [
        "dmsaa_refresh_with 1",
        "the second layer (begin, the replayed lighting, finish) 2",
    ] {
        assert!(check.contains(needle), "no `{needle}` in {check}");
    }
    assert!(
        frame(&injected) == frame(&expected),
        "the injected frame differs from the in-source frame with the same options"
    );

    let images = capi::ReferenceImages::read(&out);
    let (none, none_edges) = images.measure("own.rgba");
    let (two, two_edges) = images.measure("two-layers.rgba");
    eprintln!(
        "Rust engine under inject, FLIP against its 16x image (over its edge pixels): own {none:.4} \
         ({none_edges:.4}), completed learned profile (two layers) {two:.4} ({two_edges:.4}): {:.2}x ({:.2}x)",
        two / none,
        two_edges / none_edges
    );
    capi::assert_two_layer_gain(
        "the Rust engine under inject",
        (none, none_edges),
        (two, two_edges),
    );
}
