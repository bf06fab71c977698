//! Programs `inject` leaves alone, and the first resolve's read-back:
//! each run's one line, read (docs/inject.md, "Never silent").

use super::capi;
use super::runs::said;
use super::{can_run_glfw, cli, cxx, frame};
use crate::common;
use std::path::Path;
use std::process::Command;

/// Programs the library leaves alone, each written as such programs are
/// (`inject_oneshot.cpp`: a render call that makes the G-buffer, draws,
/// reads the image back and deletes it all): a screenshot harness that
/// renders one frame and exits, the same with no swap (surfaceless), an
/// and an engine's one-call render called three times, with and without
/// swaps. Each run says exactly one line, naming why; the frame is the
/// program's own, and the library is never called. A G-buffer of one
/// texture array's layers is retrofitted, with and without a profile.
/// The G-buffer kept across frames is retrofitted; cleared with glClear
/// through another framebuffer sharing its textures, the clear is replayed
/// and the frame is the same; cleared there with glClearBufferfv, each
/// call is replayed and the frame is the same again; so too cleared by
/// name (glClearNamedFramebufferfv, GL 4.5), of that framebuffer or of the
/// G-buffer itself. `--learn` on the
/// one-call render writes a profile at the end with the G-buffer's
/// signature, only the keys it saw and the rest marked `?`, and says so;
/// where it cannot write, it says why.
#[test]
fn a_program_left_alone_says_why_in_one_line() {
    if !can_run_glfw() {
        return;
    }
    let Some(xvfb) = common::xvfb::start_xvfb() else {
        return;
    };
    let build = Path::new(env!("CARGO_TARGET_TMPDIR")).join("inject-oneshot-build");
    let _ = std::fs::remove_dir_all(&build);
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in ["inject_oneshot.cpp", "tutorial_program.hpp"] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying the C++ sources");
    }
    let exe = build.join("oneshot");
    capi::run(
        cxx()
            .arg(src.join("inject_oneshot.cpp"))
            .arg("-o")
            .arg(&exe)
            .arg("-lglfw"),
        "compiling inject_oneshot.cpp",
    );
    let library = capi::built("libdeferred_msaa_inject", "so");
    let cases: [(&[&str], &[&str]); 4] = [
        (
            &[],
            &[
                "but it was never bound for drawing again (the program ended after one frame)",
                "a program that renders one frame, as a screenshot harness does, is never retrofitted",
            ],
        ),
        (
            &["--no-swap"],
            &[
                "but it was never bound for drawing again (no frame boundary was seen",
                "a program that renders one frame",
            ],
        ),
        (
            &["--calls", "3"],
            &[
                "was deleted before it was bound for drawing again (2 time(s))",
                "a G-buffer made and deleted within a frame, as a one-call render does, is never retrofitted",
                "2 frames seen",
            ],
        ),
        (
            &["--no-swap", "--calls", "3"],
            &[
                "was deleted before it was bound for drawing again (3 time(s))",
                "a G-buffer made and deleted within a frame",
                "no frame boundary was seen",
            ],
        ),
    ];
    let cases = cases
        .into_iter()
        .map(|(a, n)| (a, n, None::<&std::path::Path>));
    for (args, needles, profile) in cases {
        let own = build.join("own.rgba");
        capi::run(
            Command::new(&exe)
                .arg(&own)
                .args(args)
                .env("DISPLAY", xvfb.display()),
            &format!("the one-shot program as it is, {args:?}"),
        );
        let injected = build.join("injected.rgba");
        let mut command = cli();
        command
            .args(["inject", "--check", "--library"])
            .arg(&library);
        if let Some(p) = profile {
            command.arg("--profile").arg(p);
        }
        let output = capi::run(
            command
                .arg("--")
                .arg(&exe)
                .arg(&injected)
                .args(args)
                .env("DISPLAY", xvfb.display()),
            &format!("deferred-msaa inject on the one-shot program, {args:?}"),
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        eprint!("{args:?}:\n{stderr}");
        let lines = said(&stderr);
        assert_eq!(lines.len(), 1, "{args:?}: not one line:\n{stderr}");
        assert!(
            lines[0].ends_with("leaving the program untouched")
                || lines[0].contains("leaving the program untouched ("),
            "{args:?}: {}",
            lines[0]
        );
        for needle in needles {
            assert!(
                lines[0].contains(needle),
                "{args:?}: no `{needle}` in {}",
                lines[0]
            );
        }
        assert!(
            stderr.contains("check: 0 calls into the library"),
            "{args:?}: the library was called:\n{stderr}"
        );
        assert!(
            frame(&injected) == frame(&own),
            "{args:?}: the frame under inject is not the program's own"
        );
    }
    // The G-buffer kept across frames is retrofitted, and its first
    // resolve read back shows the scene: no warning. Cleared with glClear
    // through a framebuffer of the program's own that shares its textures
    // and depth, the clear is replayed on the retrofit's framebuffer: the
    // same frame, bit for bit. Cleared there per attachment
    // (glClearBufferfv, three colours and the depth a frame), each call is
    // replayed on the attachment it reached, with its value: the same frame
    // again. The check finds no state changed around the replays and the
    // read-back.
    // Through direct state access (GL 4.5), the same clears by name with
    // glClearNamedFramebufferfv, of the clear framebuffer or of the
    // G-buffer itself (never bound for it): replayed alike.
    const SHARED: &str = "a clear through a framebuffer sharing the G-buffer's, replayed";
    const NAMED: &str = "a clear of the G-buffer by name, replayed";
    let dsa = Command::new(&exe)
        .arg(build.join("probe.rgba"))
        .args(["--keep", "--clear-named", "--calls", "1"])
        .env("DISPLAY", xvfb.display())
        .output()
        .expect("running the one-shot program");
    let dsa = match dsa.status.code() {
        Some(0) => true,
        Some(4) => {
            // A context below 4.5 (the floor's): not a missing package.
            eprintln!(
                "not run: the clears by name: {}",
                String::from_utf8_lossy(&dsa.stderr).trim()
            );
            false
        }
        _ => panic!("the one-shot program with --clear-named failed: {dsa:?}"),
    };
    // The program's arguments, and the replays the check must count.
    type Case<'a> = (&'a [&'a str], Option<(&'a str, u32)>);
    let mut cases: Vec<Case> = vec![
        (&["--keep", "--calls", "3"], None),
        // glClear's calls, one per attachment (three colours and the
        // depth), two frames: as the glClearBufferfv case below.
        (
            &["--keep", "--clear-fbo", "--calls", "3"],
            Some((SHARED, 8)),
        ),
        (
            &["--keep", "--clear-fbo", "--clear-buffers", "--calls", "3"],
            Some((SHARED, 8)),
        ),
    ];
    if dsa {
        cases.push((
            &["--keep", "--clear-fbo", "--clear-named", "--calls", "3"],
            Some((SHARED, 8)),
        ));
        cases.push((
            &["--keep", "--clear-named", "--calls", "3"],
            Some((NAMED, 8)),
        ));
    }
    let mut kept_frame = Vec::new();
    for (args, replays) in cases {
        let own = build.join("own.rgba");
        capi::run(
            Command::new(&exe)
                .arg(&own)
                .args(args)
                .env("DISPLAY", xvfb.display()),
            &format!("the one-shot program as it is, {args:?}"),
        );
        let injected = build.join("injected.rgba");
        let output = capi::run(
            cli()
                .args(["inject", "--check", "--library"])
                .arg(&library)
                .arg("--")
                .arg(&exe)
                .arg(&injected)
                .args(args)
                .env("DISPLAY", xvfb.display()),
            &format!("deferred-msaa inject on the one-shot program, {args:?}"),
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        eprint!("{args:?}:\n{stderr}");
        let lines = said(&stderr);
        assert_eq!(lines.len(), 1, "{args:?}: not one line:\n{stderr}");
        assert!(
            lines[0].contains("inject: retrofitting framebuffer 1 "),
            "{args:?}:\n{stderr}"
        );
        assert!(
            stderr.contains("the resolved G-buffer read back 1")
                && stderr.contains(" 0 changed, 0 GL errors left by the library"),
            "{args:?}:\n{stderr}"
        );
        for kind in [SHARED, NAMED] {
            match replays {
                Some((k, n)) if k == kind => assert!(
                    stderr.contains(&format!("{kind} {n}")),
                    "{args:?}: not `{kind} {n}`:\n{stderr}"
                ),
                _ => assert!(!stderr.contains(kind), "{args:?}:\n{stderr}"),
            }
        }
        let injected = frame(&injected);
        assert!(
            injected != frame(&own),
            "{args:?}: the retrofitted frame is the program's own"
        );
        if replays.is_none() {
            kept_frame = injected;
        } else {
            assert!(
                injected == kept_frame,
                "{args:?}: the frame with the clear replayed is not the frame cleared in place"
            );
        }
    }
    // A G-buffer of one texture array's layers (glFramebufferTextureLayer),
    // the lighting reading the array: found as a G-buffer without a
    // profile (its layers read together through the one texture) and with
    // one whose signature it has, and retrofitted, the resolve writing each
    // layer; the check clean, the frame MSAA's, not the program's own.
    let array_profile = build.join("array.toml");
    std::fs::write(
        &array_profile,
        "[framebuffer]\ncolour_textures = 3\nformats = [\"float16\", \"float16\", \"float16\"]\n",
    )
    .expect("writing the array profile");
    let args: &[&str] = &["--array", "--calls", "3"];
    let own = build.join("own-array.rgba");
    capi::run(
        Command::new(&exe)
            .arg(&own)
            .args(args)
            .env("DISPLAY", xvfb.display()),
        "the one-shot program with an array G-buffer, as it is",
    );
    let mut frames = Vec::new();
    for profile in [None, Some(&array_profile)] {
        let injected = build.join("injected-array.rgba");
        let mut command = cli();
        command
            .args(["inject", "--check", "--library"])
            .arg(&library);
        if let Some(p) = profile {
            command.arg("--profile").arg(p);
        }
        let output = capi::run(
            command
                .arg("--")
                .arg(&exe)
                .arg(&injected)
                .args(args)
                .env("DISPLAY", xvfb.display()),
            &format!("deferred-msaa inject on the array G-buffer, profile {profile:?}"),
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        eprint!("array, profile {profile:?}:\n{stderr}");
        let lines = said(&stderr);
        assert_eq!(lines.len(), 1, "{stderr}");
        assert!(
            lines[0].contains("inject: retrofitting framebuffer 1 (3 colour textures (float16, float16, float16) + depth)"),
            "{stderr}"
        );
        assert!(
            stderr.contains("the resolved G-buffer read back 1")
                && stderr.contains(" 0 changed, 0 GL errors left by the library")
                && stderr.contains("2 frames resolved"),
            "{stderr}"
        );
        let injected = frame(&injected);
        assert!(
            injected != frame(&own),
            "the array G-buffer's frame under inject is the program's own"
        );
        frames.push(injected);
    }
    assert!(
        frames[0] == frames[1],
        "the array G-buffer found by its reads and by the profile drew different frames"
    );
    // The one-call render with a profile that gives the G-buffer's
    // signature: each call's new G-buffer is the G-buffer from its bind
    // once the camera is known (the first call sets the projection
    // uniform after its bind, so it is drawn as it is); the retrofit made
    // for the second call's and, kept when the program deletes it, made
    // anew for the third's (`dmsaa_refresh_with`, its programs kept).
    let signature = build.join("signature.toml");
    std::fs::write(
        &signature,
        "[framebuffer]\ncolour_textures = 3\nformats = [\"float16\", \"float16\", \"unorm8\"]\n",
    )
    .expect("writing the signature profile");
    let args: &[&str] = &["--calls", "3"];
    let own = build.join("own-one-call.rgba");
    capi::run(
        Command::new(&exe)
            .arg(&own)
            .args(args)
            .env("DISPLAY", xvfb.display()),
        "the one-call render as it is",
    );
    let injected = build.join("injected-one-call.rgba");
    let output = capi::run(
        cli()
            .args(["inject", "--check", "--library"])
            .arg(&library)
            .arg("--profile")
            .arg(&signature)
            .arg("--")
            .arg(&exe)
            .arg(&injected)
            .args(args)
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject on the one-call render with a signature",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprint!("one-call render, signature:\n{stderr}");
    let lines = said(&stderr);
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains("inject: retrofitting framebuffer "),
        "{stderr}"
    );
    assert!(
        stderr.contains(" 0 changed, 0 GL errors left by the library")
            && stderr.contains("2 frames resolved")
            && stderr.contains("dmsaa_retrofit_new 1")
            && stderr.contains("dmsaa_refresh_with 1"),
        "{stderr}"
    );
    assert!(
        frame(&injected) != frame(&own),
        "the one-call render's frame under inject is its own"
    );
    // `--learn`: no frame with the G-buffer alive at its end, so the file
    // is written when the program's context goes.
    let learned = build.join("learned.toml");
    let output = capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(&library)
            .arg("--learn")
            .arg(&learned)
            .arg("--")
            .arg(&exe)
            .arg(build.join("learn.rgba"))
            .args(["--no-swap", "--calls", "3"])
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject --learn on the one-call render",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines = said(&stderr);
    assert_eq!(lines.len(), 1, "--learn: not one line:\n{stderr}");
    assert!(
        lines[0].contains("wrote a first profile to ") && lines[0].contains("marked `?`"),
        "{}",
        lines[0]
    );
    let text = std::fs::read_to_string(&learned).expect("--learn wrote no profile");
    eprint!("the learned profile:\n{text}");
    for line in [
        "colour_textures = 3",
        "formats = [\"float16\", \"float16\", \"unorm8\"]",
        "uniform = \"projection\"",
        "# meaning = ?",
        "# rule = ?",
        "# [retrofit] ?",
        "The G-buffer was deleted 3 times",
        "and deleted for each image is retrofitted only with this signature",
    ] {
        assert!(text.contains(line), "no `{line}` in the learned profile");
    }
    // Only what was seen is a key: no meaning, rule or retrofit table.
    for key in ["meaning", "rule", "layers", "layer_mix"] {
        assert!(
            !text.lines().any(|l| l.starts_with(key)),
            "the learned profile sets `{key}`, which no GL call shows"
        );
    }
    // The library's own parser takes it, as `inject --profile` checks it
    // before the program runs.
    let checked = cli()
        .args(["inject", "--library"])
        .arg(&library)
        .arg("--profile")
        .arg(&learned)
        .args(["--", "true"])
        .output()
        .expect("running deferred-msaa");
    assert!(
        checked.status.success(),
        "the learned profile is refused: {}",
        String::from_utf8_lossy(&checked.stderr)
    );
    assert_eq!(text.matches("\n[[attachment]]\n").count(), 3);
    assert!(
        !text.contains("\n[retrofit]"),
        "a [retrofit] table was written"
    );
    // Nowhere to write: said, in one line.
    let nowhere = build.join("no-such-folder").join("learned.toml");
    let output = capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(&library)
            .arg("--learn")
            .arg(&nowhere)
            .arg("--")
            .arg(&exe)
            .arg(build.join("learn.rgba"))
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject --learn into a missing folder",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines = said(&stderr);
    assert_eq!(lines.len(), 1, "--learn, nowhere: not one line:\n{stderr}");
    assert!(
        lines[0].contains("cannot write the profile"),
        "{}",
        lines[0]
    );
}
