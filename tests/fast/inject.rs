//! `deferred-msaa inject` (crates/inject, docs/inject.md): the retrofit
//! applied from outside a program that has no line of it.
//!
//! `inject_tutorial.cpp`, the LearnOpenGL deferred-shading program as a
//! render loop, is built twice from one source: with `-DDMSAA_IN_SOURCE`
//! (the retrofit in its source, against the installed static library) and
//! without (no retrofit line, not linked with the library). The second,
//! run by the `deferred-msaa` binary's `inject --check`, draws the first's
//! last frame bit for bit, through GLX and EGL, with the default options,
//! with the shipped tutorial profile, and with that profile at two layers
//! (the lighting pass recorded and replayed); the library's check finds no
//! GL state value changed and no GL error around any of its calls, and the
//! frame differs from the program's own without MSAA (and two layers from
//! one).

use super::capi;
use crate::common;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The `deferred-msaa` binary.
fn cli() -> Command {
    Command::new(env!("CARGO_BIN_EXE_deferred-msaa"))
}

/// The C++ compiler with the project's warnings as errors.
fn cxx() -> Command {
    let mut c = Command::new("c++");
    c.args(["-std=c++17", "-O1", "-Wall", "-Wextra", "-Werror"]);
    c
}

/// The frame a run wrote.
fn frame(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Builds the two programs into `build`: (in source, plain).
fn build_tutorial(build: &Path, prefix: &Path) -> (PathBuf, PathBuf) {
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in ["inject_tutorial.cpp", "tutorial_program.hpp"] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying the C++ sources");
    }
    let in_source = build.join("tutorial-in-source");
    capi::run(
        cxx()
            .arg("-DDMSAA_IN_SOURCE")
            .arg("-I")
            .arg(prefix.join("include"))
            .arg(src.join("inject_tutorial.cpp"))
            .arg("-o")
            .arg(&in_source)
            .arg(prefix.join("lib/libdeferred_msaa_capi.a"))
            .arg("-lglfw")
            .args(capi::NATIVE_LIBS),
        "compiling inject_tutorial.cpp with the retrofit in its source",
    );
    // No include path or library of the retrofit's: nothing of it.
    let plain = build.join("tutorial");
    capi::run(
        cxx()
            .arg(src.join("inject_tutorial.cpp"))
            .arg("-o")
            .arg(&plain)
            .arg("-lglfw"),
        "compiling inject_tutorial.cpp as it is",
    );
    (in_source, plain)
}

/// Whether this machine can build and show the GLFW programs; the reason
/// it was skipped otherwise.
fn can_run_glfw() -> bool {
    if Command::new("c++").arg("--version").output().is_err() {
        common::skip("no C++ compiler: `c++` is not on PATH (scripts/setup installs g++)");
        return false;
    }
    if !Path::new("/usr/include/GLFW/glfw3.h").exists() {
        common::skip("no GLFW headers (scripts/setup installs libglfw3-dev)");
        return false;
    }
    true
}

#[test]
fn an_unmodified_glfw_program_under_inject_draws_the_in_source_frame() {
    if !can_run_glfw() {
        return;
    }
    let Some(xvfb) = common::xvfb::start_xvfb() else {
        return;
    };
    let (build, prefix) = capi::install("inject-build");
    let (in_source, plain) = build_tutorial(&build, &prefix);
    let library = capi::built("libdeferred_msaa_inject", "so");
    let profile = capi::root().join("crates/inject/profiles/tutorial.toml");
    let text = std::fs::read_to_string(&profile).expect("the shipped tutorial profile");
    assert!(
        text.contains("\nlayers = 1\n"),
        "the tutorial profile no longer sets layers = 1"
    );
    let two_layers = build.join("tutorial-two-layers.toml");
    std::fs::write(
        &two_layers,
        text.replace("\nlayers = 1\n", "\nlayers = 2\n"),
    )
    .expect("writing the two-layer profile");
    let out = build.join("frames");
    std::fs::create_dir_all(&out).expect("making the frame folder");
    for api in ["GLX", "EGL"] {
        let api_args: &[&str] = if api == "EGL" { &["--egl"] } else { &[] };
        let own = out.join(format!("{api}-own.rgba"));
        capi::run(
            Command::new(&plain)
                .arg(&own)
                .args(api_args)
                .env("DISPLAY", xvfb.display()),
            &format!("the program as it is, {api}"),
        );
        let variants: [(&str, Option<&PathBuf>, &[&str]); 3] = [
            ("default", None, &[]),
            ("tutorial", Some(&profile), &["--tutorial-options"]),
            (
                "tutorial-two-layers",
                Some(&two_layers),
                &["--tutorial-options", "--two-layers"],
            ),
        ];
        for (options, profile, in_source_args) in variants {
            let what = format!("{api}, {options} options");
            let expected = out.join(format!("{api}-{options}-in-source.rgba"));
            let mut command = Command::new(&in_source);
            command
                .arg(&expected)
                .args(api_args)
                .env("DISPLAY", xvfb.display());
            command.args(in_source_args);
            capi::run(
                &mut command,
                &format!("the program retrofitted in its source, {what}"),
            );

            let injected = out.join(format!("{api}-{options}-injected.rgba"));
            let mut command = cli();
            command
                .args(["inject", "--check", "--library"])
                .arg(&library);
            if let Some(p) = profile {
                command.arg("--profile").arg(p);
            }
            command
                .arg("--")
                .arg(&plain)
                .arg(&injected)
                .args(api_args)
                .env("DISPLAY", xvfb.display());
            let output = capi::run(&mut command, &format!("deferred-msaa inject, {what}"));
            let stdout = String::from_utf8_lossy(&output.stdout);
            let stderr = String::from_utf8_lossy(&output.stderr);
            eprint!("{what}:\n{stderr}");
            assert!(
                stdout.contains(&format!("through {api}")),
                "{what}: {stdout}"
            );
            assert!(
                stdout.ends_with("ok\n"),
                "{what}: the program failed a check:\n{stdout}"
            );
            assert!(
                stderr.contains("deferred-msaa inject: retrofitting framebuffer "),
                "{what}: the library did not retrofit the G-buffer:\n{stderr}"
            );
            let check = stderr
                .lines()
                .find(|l| l.starts_with("deferred-msaa inject: check: "))
                .unwrap_or_else(|| panic!("{what}: no check summary:\n{stderr}"));
            assert!(
                check.contains(" 0 changed, 0 GL errors left by the library, 0 left pending by the program; 2 frames resolved"),
                "{what}: {check}"
            );
            assert!(
                frame(&injected) == frame(&expected),
                "{what}: the injected frame differs from the frame of the program retrofitted in its source"
            );
            assert!(
                frame(&injected) != frame(&own),
                "{what}: the injected frame is the program's own (no MSAA)"
            );
            if options == "tutorial-two-layers" {
                let one = out.join(format!("{api}-tutorial-injected.rgba"));
                assert!(
                    frame(&injected) != frame(&one),
                    "{what}: two layers drew the one-layer frame"
                );
            }
        }
    }
}

/// A forward program whose HDR framebuffer has a G-buffer's shape (two
/// colour textures and depth, drawn into, read later one texture at a
/// time: `inject_bloom.cpp`) is left untouched without a profile: its frame
/// under `inject` is its own, bit for bit, the library says once why, and
/// it never calls the retrofit.
#[test]
fn a_forward_bloom_program_is_left_untouched_without_a_profile() {
    if !can_run_glfw() {
        return;
    }
    let Some(xvfb) = common::xvfb::start_xvfb() else {
        return;
    };
    let build = Path::new(env!("CARGO_TARGET_TMPDIR")).join("inject-bloom-build");
    let _ = std::fs::remove_dir_all(&build);
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in ["inject_bloom.cpp", "tutorial_program.hpp"] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying the C++ sources");
    }
    let exe = build.join("bloom");
    capi::run(
        cxx()
            .arg(src.join("inject_bloom.cpp"))
            .arg("-o")
            .arg(&exe)
            .arg("-lglfw"),
        "compiling inject_bloom.cpp",
    );
    let own = build.join("own.rgba");
    capi::run(
        Command::new(&exe).arg(&own).env("DISPLAY", xvfb.display()),
        "the bloom program as it is",
    );
    let injected = build.join("injected.rgba");
    let output = capi::run(
        cli()
            .args(["inject", "--check", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--")
            .arg(&exe)
            .arg(&injected)
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject on the bloom program",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprint!("{stderr}");
    assert!(
        !stderr.contains("retrofitting"),
        "the bloom program was retrofitted:\n{stderr}"
    );
    let said: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("leaving the program untouched"))
        .collect();
    assert_eq!(said.len(), 1, "not said exactly once:\n{stderr}");
    assert!(
        said[0].contains("have the shape of a G-buffer"),
        "{}",
        said[0]
    );
    assert!(
        stderr.contains("check: 0 calls into the library"),
        "the library was called:\n{stderr}"
    );
    assert!(
        frame(&injected) == frame(&own),
        "the bloom program's frame under inject differs from its own"
    );
}
