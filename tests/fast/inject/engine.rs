//! The C engine of `engine.h` (six colour attachments, the camera in a
//! std140 uniform block written each frame, the G-buffer cleared through
//! another framebuffer with `glClearBufferfv` before it is bound, an
//! `RGBA16F` radiance target tonemapped into an 8-bit screen), run as an
//! unmodified C program (`engine_program.c`) on a surfaceless EGL context
//! with no swap, linked with libEGL and loading GL through
//! `eglGetProcAddress` by name, under `inject`:
//!
//! - with no profile, retrofitted with one layer from its second frame on:
//!   the camera found in its uniform block by the matrices written there,
//!   the clears replayed, its two-channel (octahedral) normals taken from
//!   one sample; no worse than none against its 16x image; `--check`
//!   clean;
//! - with a second camera block (a spot light's, `--shadow-block`) nothing
//!   is guessed: one line names both, `--learn` a `?` line; so too, one
//!   line each and the program's own frame, with its camera written by
//!   mapping, as a forward renderer, with a second G-buffer read alike (a
//!   mirror's view), and on Mesa's off-screen renderer;
//! - `--learn` writes the block's binding and offsets, the signature;
//! - that profile as a user completes it (the attachments' meanings and
//!   rules, two layers, the tonemap as a curve): the frame of the same
//!   program built with the retrofit in its source, bit for bit, and at
//!   most 0.7x its no-MSAA FLIP against its own 16x image (0.6x over the
//!   edge pixels of its frame); the same bit for bit with its lighting
//!   tested against the G-buffer's depth (`--depth-tested-lighting`).

use super::runs::{clean_check, completed, inject, run_ok, said};
use super::{capi, frame};
use crate::common;
use deferred_msaa_lab::context::Backend;
use std::ffi::{OsStr, OsString};
use std::path::Path;
use std::process::Command;

/// The learned profile as a user completes it from docs/hosts.md's row for
/// this style: the octahedral normals named and selected, the packed byte
/// selected, two layers, the radiance's tonemap (exposure 0.8, then clamp)
/// as the curve.
fn engine_profile(learned: &str) -> String {
    completed(
        learned,
        &[
            (
                1,
                "meaning = \"normal\"\nencoding = \"octahedral-unorm\"\nrule = \"select\"\n",
            ),
            (2, "rule = \"select\"\n"),
            (3, "rule = \"select\"\n"),
        ],
        "[retrofit]\nlayers = 2\nlayer_mix = \"curve\"\nlayer_mix_curve = \"\"\"\n\
         vec3 dmsaa_curve(vec3 x) { return clamp(x * 0.8, 0.0, 1.0); }\n\
         vec3 dmsaa_curve_inverse(vec3 y) { return y / 0.8; }\n\"\"\"\n",
    )
}

#[test]
fn an_unmodified_c_engine_under_inject_draws_its_in_source_two_layers() {
    if Command::new("cc").arg("--version").output().is_err() {
        common::skip("no C compiler: `cc` is not on PATH (scripts/setup installs gcc)");
        return;
    }
    if let Err(e) = Backend::Egl.check_library() {
        common::skip(&e.to_string());
        return;
    }
    let (build, prefix) = capi::install("inject-engine-build");
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in [
        "engine_program.c",
        "engine.h",
        "engine_retrofit.h",
        "egl_gl.h",
    ] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying a C source");
    }
    let in_source = build.join("engine-in-source");
    capi::run(
        capi::cc()
            .arg("-DDMSAA_IN_SOURCE")
            .arg("-I")
            .arg(prefix.join("include"))
            .arg(src.join("engine_program.c"))
            .arg("-o")
            .arg(&in_source)
            .arg(prefix.join("lib/libdeferred_msaa_capi.a"))
            .arg("-lEGL")
            .args(capi::NATIVE_LIBS),
        "compiling engine_program.c with the retrofit in its source",
    );
    // No include path or library of the retrofit's: nothing of it.
    let plain = build.join("engine");
    capi::run(
        capi::cc()
            .arg(src.join("engine_program.c"))
            .arg("-o")
            .arg(&plain)
            .args(["-lEGL", "-lm"]),
        "compiling engine_program.c as it is",
    );
    let out = build.join("out");
    std::fs::create_dir_all(&out).expect("making the output folder");
    // The program's own frame, its 16x image and its edges.
    let own = out.join("own.rgba");
    run_ok(
        Command::new(&plain).arg(&own).arg("--reference").arg(&out),
        "the engine as it is",
    );
    let expected = out.join("in-source.rgba");
    run_ok(
        Command::new(&in_source).arg(&expected),
        "the engine retrofitted in its source",
    );
    let library = capi::built("libdeferred_msaa_inject", "so");
    // The engine under `inject --check` (and a profile), its frame `file`.
    let checked = |profile: Option<&Path>, file: &str, what: &str, args: &[&str]| {
        let mut flags = vec![OsString::from("--check")];
        if let Some(p) = profile {
            flags.extend([OsString::from("--profile"), p.into()]);
        }
        let mut all = vec![OsString::from(out.join(file))];
        all.extend(args.iter().map(OsString::from));
        inject(&library, flags, &plain, all, what)
    };

    // No profile: the camera found in its block, one layer, every frame.
    let stderr = checked(None, "no-profile.rgba", "the engine, no profile", &[]);
    let lines = said(&stderr);
    assert!(
        lines.len() == 1
            && lines[0].contains("retrofitting framebuffer ")
            && lines[0].contains("1 layer(s), default options")
            && lines[0].contains("two-channel attachment(s) [1, 2] taken from one sample")
            && lines[0].contains("the frame(s) before this one are the program's own")
            && lines[0].contains(
                "the camera from the uniform block at binding 0 (projection at byte 0, view at byte 64), found by its values"
            ),
        "no profile: not the one line of a retrofit with the block's camera:\n{stderr}"
    );
    // The first frame's clear, made through the other framebuffer before
    // the G-buffer's first bind, is not seen in time: its first frame is
    // the program's own, the next two are resolved.
    let check = clean_check(&stderr, "no profile", 2);
    assert!(
        check.contains("a clear through a framebuffer sharing the G-buffer's, replayed"),
        "{check}"
    );
    let no_profile = frame(&out.join("no-profile.rgba"));
    assert!(
        no_profile != frame(&own),
        "no profile: the frame is the program's own"
    );

    // The camera block given new storage with its values each frame
    // (`--orphan-camera`: glBufferData, as engines orphan a buffer): found
    // the same way, the same frame.
    let orphaned = checked(
        None,
        "orphan-camera.rgba",
        "the engine, camera orphaned",
        &["--orphan-camera"],
    );
    assert!(
        said(&orphaned).len() == 1
            && orphaned.contains(
                "the camera from the uniform block at binding 0 (projection at byte 0, view at byte 64)"
            ),
        "the orphaned camera block was not found:\n{orphaned}"
    );
    assert!(
        frame(&out.join("orphan-camera.rgba")) == no_profile,
        "the orphaned camera block gave another frame than the one written in place"
    );

    // Ways of being left alone, each one line, the frame the program's
    // own: the camera written by mapping (a path not followed), no
    // G-buffer (a forward renderer), two G-buffers read alike (a mirror's
    // view beside the camera's: which to retrofit is the profile's to say),
    // GL reached through Mesa's off-screen renderer.
    for (flag, needles) in [
        (
            "--mapped-camera",
            &["found the G-buffer (framebuffer 1) but no projection matrix"][..],
        ),
        ("--forward-renderer", &["no G-buffer found (looked for"][..]),
        (
            "--two-gbuffers",
            &["framebuffers [1, 5] all look like G-buffers"][..],
        ),
        (
            "--osmesa",
            &[
                "no draw call reached the library",
                "the program looked up OSMesaGetProcAddress",
            ][..],
        ),
    ] {
        if flag == "--osmesa"
            && let Err(e) = Backend::OsMesa.check_library()
        {
            common::skip(&e.to_string());
            continue;
        }
        let file = format!("left-alone{flag}.rgba");
        let own_file = out.join(format!("own{flag}.rgba"));
        run_ok(
            Command::new(&plain).arg(&own_file).arg(flag),
            &format!("the engine as it is, {flag}"),
        );
        let stderr = checked(None, &file, &format!("the engine, {flag}"), &[flag]);
        let lines = said(&stderr);
        assert!(
            lines.len() == 1
                && lines[0].contains("leaving the program untouched")
                && needles.iter().all(|n| lines[0].contains(n)),
            "{flag}: not the one line of a program left alone ({needles:?}):\n{stderr}"
        );
        assert!(
            stderr.contains("check: 0 calls into the library"),
            "{flag}: the library was called:\n{stderr}"
        );
        assert!(
            frame(&out.join(&file)) == frame(&own_file),
            "{flag}: left alone, yet not the program's own frame"
        );
    }

    // A second camera block (`--shadow-block`: a spot light's projection
    // and view at binding 1): no block is guessed; one line names both and
    // the way out, and the frame is the program's own.
    let shadow = out.join("shadow-block.rgba");
    let stderr = inject(
        &library,
        [] as [&str; 0],
        &plain,
        [shadow.as_os_str(), OsStr::new("--shadow-block")],
        "the engine with a shadow camera block",
    );
    let own_shadow = out.join("own-shadow-block.rgba");
    run_ok(
        Command::new(&plain).arg(&own_shadow).arg("--shadow-block"),
        "the engine with a shadow camera block, as it is",
    );
    let lines = said(&stderr);
    assert!(
        lines.len() == 1
            && lines[0]
                .contains("uniform blocks at bindings [0, 1] each hold a perspective projection")
            && lines[0].contains("leaving the program untouched")
            && lines[0].contains("block_binding"),
        "two camera blocks: not one line naming both:\n{stderr}"
    );
    assert!(
        frame(&shadow) == frame(&own_shadow),
        "two camera blocks: left alone, yet not the program's own frame"
    );
    let learned_shadow = out.join("learned-shadow.toml");
    inject(
        &library,
        [OsStr::new("--learn"), learned_shadow.as_os_str()],
        &plain,
        [
            out.join("learn-shadow.rgba").as_os_str(),
            OsStr::new("--shadow-block"),
        ],
        "--learn, the engine with a shadow camera block",
    );
    let text = std::fs::read_to_string(&learned_shadow).expect("--learn wrote no profile");
    assert!(
        text.contains("# block_binding = ?  uniform blocks at bindings 0 (byte 0), 1 (byte 0)")
            && !text.lines().any(|l| l.starts_with("block_binding")),
        "two camera blocks: the learned profile guesses or says nothing:\n{text}"
    );

    // A profile naming a binding point no buffer is bound to: one line, the
    // retrofit off after the first frame (whose geometry is lost), the
    // last frame the program's own, never frames left unresolved.
    let wrong = out.join("wrong-block.toml");
    std::fs::write(
        &wrong,
        "[framebuffer]\ncolour_textures = 6\ndepth = true\n\n[projection]\nblock_binding = 3\noffset = 0\n",
    )
    .expect("writing the wrong-block profile");
    let stderr = checked(
        Some(&wrong),
        "wrong-block.rgba",
        "a profile naming an empty camera block",
        &[],
    );
    let stale = out.join("wrong-block.rgba");
    let lines = said(&stderr);
    assert!(
        lines.len() == 2
            && lines[0].contains("retrofitting framebuffer")
            && lines[1].contains(
                "the camera block (uniform-buffer binding 3, projection at byte 0) holds no matrix"
            )
            && lines[1].contains("the retrofit is off for the rest of the run"),
        "an empty camera block: not said once:\n{stderr}"
    );
    clean_check(&stderr, "an empty camera block", 0);
    assert!(
        frame(&stale) == frame(&own),
        "an empty camera block: the last frame is not the program's own"
    );

    // --learn: the signature and the camera block, as keys.
    let learned = out.join("learned.toml");
    let stderr = inject(
        &library,
        [OsStr::new("--learn"), learned.as_os_str()],
        &plain,
        [out.join("learn.rgba")],
        "--learn, the engine",
    );
    assert!(
        said(&stderr)
            .iter()
            .any(|l| l.contains("wrote a first profile to ")),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&learned).expect("--learn wrote no profile");
    for line in [
        "colour_textures = 6",
        "formats = [\"unorm8\", \"unorm16\", \"unorm16\", \"unorm8\", \"float16\", \"float16\"]",
        "block_binding = 0",
        "offset = 0",
        "view_offset = 64",
        "deleted before this was written",
        "# two channels: an encoded normal",
    ] {
        assert!(
            text.contains(line),
            "no `{line}` in the learned profile:\n{text}"
        );
    }

    // That profile completed: two layers, the in-source frame bit for bit.
    let profile = out.join("engine.toml");
    std::fs::write(&profile, engine_profile(&text)).expect("writing the completed profile");
    let stderr = checked(
        Some(&profile),
        "two-layers.rgba",
        "the engine, two layers",
        &[],
    );
    let lines = said(&stderr);
    assert!(
        lines.len() == 1
            && lines[0].contains("2 layer(s), options from the profile")
            && lines[0].contains("from the program's first frame"),
        "two layers: not the one line of the retrofit:\n{stderr}"
    );
    // With the profile's signature the G-buffer is found at the first
    // clear through the framebuffer sharing its textures: all three frames.
    let check = clean_check(&stderr, "two layers", 3);
    assert!(
        check.contains("the second layer (begin, the replayed lighting, finish) 3"),
        "{check}"
    );
    let injected = frame(&out.join("two-layers.rgba"));
    assert!(
        injected == frame(&expected),
        "the injected frame differs from the in-source frame with the same options"
    );

    // The lighting tested against the G-buffer's depth, which the radiance
    // framebuffer shares (`--depth-tested-lighting`: a quad at the far
    // plane tested GL_GREATER where geometry is, again GL_LEQUAL where the
    // sky is): the replay draws both into the own target, whose depth is
    // the second layer's, each with its depth state: the in-source frame,
    // bit for bit (the same frame as the one-draw lighting's).
    let expected_tested = out.join("in-source-depth-tested.rgba");
    run_ok(
        Command::new(&in_source)
            .arg(&expected_tested)
            .arg("--depth-tested-lighting"),
        "the engine retrofitted in its source, depth-tested lighting",
    );
    let stderr = checked(
        Some(&profile),
        "depth-tested.rgba",
        "the engine, two layers, depth-tested lighting",
        &["--depth-tested-lighting"],
    );
    let check = clean_check(&stderr, "two layers, depth-tested lighting", 3);
    assert!(
        check.contains("the second layer (begin, the replayed lighting, finish) 3"),
        "{check}"
    );
    assert!(
        frame(&out.join("depth-tested.rgba")) == frame(&expected_tested),
        "depth-tested lighting: the injected frame differs from the in-source frame"
    );

    // Against the engine's 16x image.
    let engine = capi::ReferenceImages::read(&out);
    let measure = |name: &str| engine.measure(name);
    let (none, none_edges) = measure("own.rgba");
    let (one, one_edges) = measure("no-profile.rgba");
    let (two, two_edges) = measure("two-layers.rgba");
    eprintln!(
        "C engine under inject, FLIP against its 16x image (over its edge pixels): own {none:.4} ({none_edges:.4}), \
         no profile (one layer) {one:.4} ({one_edges:.4}): {:.2}x ({:.2}x), completed learned profile (two layers) \
         {two:.4} ({two_edges:.4}): {:.2}x ({:.2}x)",
        one / none,
        one_edges / none_edges,
        two / none,
        two_edges / none_edges
    );
    // One layer with nothing declared: no worse than none. (Blending the
    // octahedral normals, as the library's default for a unorm attachment
    // would, measured 1.06x none here, 1.09x over edges.)
    assert!(
        one <= none && one_edges <= none_edges,
        "no profile, one layer {one:.4} ({one_edges:.4} over edges) above none {none:.4} ({none_edges:.4})"
    );
    capi::assert_two_layer_gain(
        "the C engine under inject",
        (none, none_edges),
        (two, two_edges),
    );
}
