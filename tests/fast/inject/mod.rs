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
//! (the lighting pass recorded and replayed), its light cubes drawn after
//! the lighting going into the forward target as the in-source build's
//! `--forward` draws them; the library's check finds no
//! GL state value changed and no GL error around any of its calls, and the
//! frame differs from the program's own without MSAA (and two layers from
//! one). The same after a resize and after the G-buffer is remade; and for
//! the program built on SDL2 (GLX, EGL) and linked with libGL directly.
//! A forward bloom program is left untouched without a profile.

mod engine;
mod habits;
mod left_alone;
mod runs;
mod rust_engine;

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

/// How the tutorial program is built: its window library and how it
/// reaches GL.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Flavour {
    /// GLFW, GL through `glfwGetProcAddress`.
    Glfw,
    /// SDL2, GL through `SDL_GL_GetProcAddress`.
    Sdl,
    /// GLFW, GL through libGL's symbols (linked with `-lGL`).
    LinkedGl,
}

impl Flavour {
    fn name(self) -> &'static str {
        match self {
            Flavour::Glfw => "glfw",
            Flavour::Sdl => "sdl",
            Flavour::LinkedGl => "linked-gl",
        }
    }

    /// The defines and libraries of the flavour.
    fn flags(self) -> Vec<String> {
        match self {
            Flavour::Glfw => vec!["-lglfw".into()],
            Flavour::LinkedGl => vec!["-DTUTORIAL_LINK_GL".into(), "-lglfw".into(), "-lGL".into()],
            Flavour::Sdl => {
                let out = Command::new("pkg-config")
                    .args(["--cflags", "--libs", "sdl2"])
                    .output()
                    .expect("pkg-config sdl2");
                let mut flags = vec!["-DTUTORIAL_SDL".to_string()];
                flags.extend(
                    String::from_utf8_lossy(&out.stdout)
                        .split_whitespace()
                        .map(String::from),
                );
                flags
            }
        }
    }
}

/// Builds the two programs of `flavour` into `build`: (in source, plain).
fn build_tutorial(build: &Path, prefix: &Path, flavour: Flavour) -> (PathBuf, PathBuf) {
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in [
        "inject_tutorial.cpp",
        "tutorial_program.hpp",
        "tutorial_dsa.hpp",
    ] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying the C++ sources");
    }
    let name = flavour.name();
    let in_source = build.join(format!("tutorial-{name}-in-source"));
    capi::run(
        cxx()
            .arg("-DDMSAA_IN_SOURCE")
            .arg("-I")
            .arg(prefix.join("include"))
            .arg(src.join("inject_tutorial.cpp"))
            .arg("-o")
            .arg(&in_source)
            .arg(prefix.join("lib/libdeferred_msaa_capi.a"))
            .args(flavour.flags())
            .args(capi::NATIVE_LIBS),
        &format!("compiling inject_tutorial.cpp ({name}) with the retrofit in its source"),
    );
    // No include path or library of the retrofit's: nothing of it.
    let plain = build.join(format!("tutorial-{name}"));
    capi::run(
        cxx()
            .arg(src.join("inject_tutorial.cpp"))
            .arg("-o")
            .arg(&plain)
            .args(flavour.flags()),
        &format!("compiling inject_tutorial.cpp ({name}) as it is"),
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

/// One comparison: the in-source program and the plain one under
/// `inject --check`, the same arguments.
struct Run<'a> {
    what: String,
    out: &'a Path,
    display: String,
    /// The program's arguments after its output file (`--egl`).
    args: &'a [&'a str],
    /// The in-source build's further arguments.
    in_source_args: &'a [&'a str],
    profile: Option<&'a Path>,
    /// Frames the library resolves (the first frame is drawn as it is).
    resolves: u32,
    /// Calls into the library the check must have counted, as it prints
    /// them (`dmsaa_refresh 1`).
    calls: &'a [&'a str],
}

impl Run<'_> {
    /// Runs both; asserts the injected frame is the in-source one, the
    /// check clean, and the frame not `own`'s. Returns the injected frame.
    fn compare(&self, in_source: &Path, plain: &Path, own: &[u8], api: &str) -> Vec<u8> {
        let (injected, expected) = self.both(in_source, plain, api);
        let what = &self.what;
        assert!(
            injected == expected,
            "{what}: the injected frame differs from the frame of the program retrofitted in its source"
        );
        assert!(
            injected != own,
            "{what}: the injected frame is the program's own (no MSAA)"
        );
        injected
    }

    /// Runs both, as [`Run::compare`], for a camera the library derives
    /// (rounded otherwise than the in-source build's matrices): the frames
    /// differ in at most `share` of the pixels, each channel by at most
    /// `most` but in at most `turned` of the pixels (a crease's tie given
    /// to its other face: the crease rule's threshold is on quantities the
    /// projection gives, so a pixel within the matrices' rounding of it may
    /// fall either way),
    /// and the injected one is not `own`.
    #[allow(clippy::too_many_arguments)]
    fn compare_within(
        &self,
        in_source: &Path,
        plain: &Path,
        own: &[u8],
        api: &str,
        share: f64,
        most: u8,
        turned: f64,
    ) {
        let (injected, expected) = self.both(in_source, plain, api);
        let what = &self.what;
        let pixels = injected.len() / 4;
        let differing = injected
            .chunks(4)
            .zip(expected.chunks(4))
            .filter(|(a, b)| a != b)
            .count();
        let beyond = injected
            .chunks(4)
            .zip(expected.chunks(4))
            .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > most))
            .count();
        let largest = injected
            .iter()
            .zip(&expected)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        eprintln!(
            "{what}: {differing} of {pixels} pixels differ from the in-source frame, by at most \
             {largest}; {beyond} by more than {most}"
        );
        assert!(
            differing as f64 <= share * pixels as f64 && beyond as f64 <= turned * pixels as f64,
            "{what}: {differing} of {pixels} pixels differ from the in-source frame, by up to \
             {largest}, {beyond} by more than {most}"
        );
        assert!(
            injected != own,
            "{what}: the injected frame is the program's own (no MSAA)"
        );
    }

    /// The injected frame and the in-source one, the check read.
    fn both(&self, in_source: &Path, plain: &Path, api: &str) -> (Vec<u8>, Vec<u8>) {
        let what = &self.what;
        let file = what.replace([' ', ','], "-");
        let expected = self.out.join(format!("{file}-in-source.rgba"));
        // Under inject the light cubes drawn after the lighting go into the
        // forward target (its default): the in-source build draws them so.
        capi::run(
            Command::new(in_source)
                .arg(&expected)
                .args(self.args)
                .args(self.in_source_args)
                .arg("--forward")
                .env("DISPLAY", &self.display),
            &format!("the program retrofitted in its source, {what}"),
        );
        let injected = self.out.join(format!("{file}-injected.rgba"));
        let mut command = cli();
        command
            .args(["inject", "--check", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"));
        if let Some(p) = self.profile {
            command.arg("--profile").arg(p);
        }
        command
            .arg("--")
            .arg(plain)
            .arg(&injected)
            .args(self.args)
            .env("DISPLAY", &self.display);
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
        let resolves = self.resolves;
        assert!(
            check.contains(&format!(
                " 0 changed, 0 GL errors left by the library, 0 left pending by the program; {resolves} frames resolved"
            )),
            "{what}: {check}"
        );
        for call in self.calls {
            assert!(check.contains(call), "{what}: no `{call}` in {check}");
        }
        (frame(&injected), frame(&expected))
    }
}

/// The frame size of `inject_tutorial.cpp`.
const FRAME: (u32, u32) = (160, 120);
/// How much the figure magnifies each frame.
const MAGNIFY: u32 = 3;

/// The README's figure: the program's own frame (left) and the frame under
/// `inject` (right), each magnified `MAGNIFY` times (nearest), written to
/// `path`, and also to `$DMSAA_INJECT_FIGURE` where it is set
/// (`scripts/inject-figure` sets it to docs/inject-before-after.png).
fn before_and_after(before: &[u8], after: &[u8], path: &Path) {
    let (w, h) = FRAME;
    let gap = 4;
    let mut figure = image::RgbaImage::from_pixel(
        2 * w * MAGNIFY + gap,
        h * MAGNIFY,
        image::Rgba([255, 255, 255, 255]),
    );
    for (k, frame) in [before, after].into_iter().enumerate() {
        let x0 = k as u32 * (w * MAGNIFY + gap);
        for y in 0..h * MAGNIFY {
            for x in 0..w * MAGNIFY {
                // The frames' rows are bottom-up, as glReadPixels gives them.
                let i = (((h - 1 - y / MAGNIFY) * w + x / MAGNIFY) * 4) as usize;
                let p = &frame[i..i + 4];
                figure.put_pixel(x0 + x, y, image::Rgba([p[0], p[1], p[2], 255]));
            }
        }
    }
    figure
        .save(path)
        .expect("writing the before-and-after figure");
    if let Some(docs) = std::env::var_os("DMSAA_INJECT_FIGURE") {
        figure
            .save(&docs)
            .expect("writing the before-and-after figure to $DMSAA_INJECT_FIGURE");
    }
}

/// The program's own frame and its frame under inject with two layers (the
/// tutorial profile at two layers, the light cubes in the forward target)
/// against the program's 16x image (`--reference`, which also writes its
/// edge pixels): two layers at most 0.7x the own frame's FLIP, and 0.6x
/// over the edge pixels.
fn against_16x(plain: &Path, out: &Path, display: &str, own: &[u8], two_layers: &[u8]) {
    let reference = out.join("reference.rgba");
    capi::run(
        Command::new(plain)
            .arg(out.join("reference-run.rgba"))
            .arg("--reference")
            .arg(&reference)
            .env("DISPLAY", display),
        "the program as it is, with its 16x image",
    );
    let (w, h) = FRAME;
    let image = |bytes: Vec<u8>| image::RgbaImage::from_raw(w, h, bytes).expect("a 160x120 frame");
    let edges = image::GrayImage::from_raw(w, h, frame(&out.join("reference.rgba.edges")))
        .expect("a 160x120 edge mask");
    let reference = image(frame(&reference));
    let error = |bytes: &[u8]| {
        let test = image(bytes.to_vec());
        let all = deferred_msaa_lab::compare::flip(&reference, &test)
            .expect("same sizes")
            .mean;
        let over_edges = deferred_msaa_lab::compare::flip_by_mask(&reference, &test, &edges)
            .expect("same sizes")
            .marked
            .expect("edge pixels");
        (all, over_edges)
    };
    let ((none, none_edges), (two, two_edges)) = (error(own), error(two_layers));
    eprintln!(
        "the tutorial program under inject, FLIP against its 16x image (over its edge pixels): own {none:.4} \
         ({none_edges:.4}), two layers {two:.4} ({two_edges:.4}): {:.2}x ({:.2}x)",
        two / none,
        two_edges / none_edges
    );
    capi::assert_two_layer_gain(
        "the tutorial program under inject",
        (none, none_edges),
        (two, two_edges),
    );
}

/// The program's own frame, without MSAA.
fn own_frame(plain: &Path, out: &Path, name: &str, args: &[&str], display: &str) -> Vec<u8> {
    let own = out.join(format!("{name}-own.rgba"));
    capi::run(
        Command::new(plain)
            .arg(&own)
            .args(args)
            .env("DISPLAY", display),
        &format!("the program as it is, {name}"),
    );
    frame(&own)
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
    let (in_source, plain) = build_tutorial(&build, &prefix, Flavour::Glfw);
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
        let args: &[&str] = if api == "EGL" { &["--egl"] } else { &[] };
        let own = own_frame(&plain, &out, api, args, &xvfb.display());
        let variants: [(&str, Option<&Path>, &[&str]); 3] = [
            ("default", None, &[]),
            ("tutorial", Some(&profile), &["--tutorial-options"]),
            (
                "tutorial two layers",
                Some(&two_layers),
                &["--tutorial-options", "--two-layers"],
            ),
        ];
        let mut one_layer = Vec::new();
        for (options, profile, in_source_args) in variants {
            let two = options == "tutorial two layers";
            let run = Run {
                what: format!("GLFW {api}, {options} options"),
                out: &out,
                display: xvfb.display(),
                args,
                in_source_args,
                profile,
                resolves: 2,
                calls: if two {
                    &[
                        "dmsaa_retrofit_new 1",
                        "the second layer (begin, the replayed lighting, finish) 2",
                    ]
                } else {
                    &["dmsaa_retrofit_new 1"]
                },
            };
            let injected = run.compare(&in_source, &plain, &own, api);
            match options {
                "tutorial" => one_layer = injected,
                "tutorial two layers" => {
                    assert!(
                        injected != one_layer,
                        "{api}: two layers drew the one-layer frame"
                    );
                    if api == "GLX" {
                        before_and_after(&own, &injected, &build.join("before-after.png"));
                        against_16x(&plain, &out, &xvfb.display(), &own, &injected);
                    }
                }
                _ => {}
            }
        }
    }
    // Engines' habits: light volumes, lighting in two passes, the camera in
    // a uniform block or one view-projection uniform.
    habits::run(&habits::Setup {
        build: &build,
        out: &out,
        in_source: &in_source,
        plain: &plain,
        display: xvfb.display(),
        text: &text,
        two_layers: &two_layers,
    });
    // `--learn`: the program untouched, a first profile written with the
    // G-buffer's signature; that profile as it is (every attachment
    // "other", the matrix uniforms seen) gives the default options' frame.
    let learned = build.join("learned.toml");
    let untouched = out.join("learn.rgba");
    let output = capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--learn")
            .arg(&learned)
            .arg("--")
            .arg(&plain)
            .arg(&untouched)
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject --learn",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !stderr.contains("retrofitting"),
        "--learn retrofitted:\n{stderr}"
    );
    let own = own_frame(&plain, &out, "GLX-learn", &[], &xvfb.display());
    assert!(
        frame(&untouched) == own,
        "--learn changed the program's frame"
    );
    let profile_text = std::fs::read_to_string(&learned).expect("--learn wrote no profile");
    eprint!("the learned profile:\n{profile_text}");
    for line in [
        "<- the G-buffer",
        "colour_textures = 3",
        "formats = [\"float16\", \"float16\", \"unorm8\"]",
        "uniform = \"projection\"",
        "view_uniform = \"view\"",
    ] {
        assert!(
            profile_text.contains(line),
            "no `{line}` in the learned profile"
        );
    }
    Run {
        what: "GLFW GLX, the learned profile".into(),
        out: &out,
        display: xvfb.display(),
        args: &[],
        in_source_args: &[],
        profile: Some(&learned),
        resolves: 2,
        calls: &["dmsaa_retrofit_new 1"],
    }
    .compare(&in_source, &plain, &own, "GLX");
    // A pass between the G-buffer and the lighting (`--pre-pass`): two
    // layers replay the lighting where the profile says it is the second
    // pass after the resolve, and the in-source frame comes out; left to
    // the default (the first pass), the replay is the wrong pass.
    let second_pass = build.join("tutorial-two-layers-lighting-second.toml");
    let two_text = std::fs::read_to_string(&two_layers).expect("the two-layer profile");
    std::fs::write(&second_pass, format!("{two_text}\n[lighting]\npass = 2\n"))
        .expect("writing the profile with the lighting's pass");
    let pre_pass: &[&str] = &["--pre-pass"];
    let own = own_frame(&plain, &out, "GLX-pre-pass", pre_pass, &xvfb.display());
    let run = Run {
        what: "GLFW GLX, pre-pass, tutorial two layers, lighting pass 2".into(),
        out: &out,
        display: xvfb.display(),
        args: pre_pass,
        in_source_args: &["--tutorial-options", "--two-layers"],
        profile: Some(&second_pass),
        resolves: 2,
        calls: &["the second layer (begin, the replayed lighting, finish) 2"],
    };
    run.compare(&in_source, &plain, &own, "GLX");
    let expected = out.join(format!(
        "{}-in-source.rgba",
        run.what.replace([' ', ','], "-")
    ));
    let first_pass = out.join("pre-pass-lighting-first.rgba");
    capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--profile")
            .arg(&two_layers)
            .arg("--")
            .arg(&plain)
            .arg(&first_pass)
            .args(pre_pass)
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject, pre-pass, the lighting left as the first pass",
    );
    assert!(
        frame(&first_pass) != frame(&expected),
        "with a pass before the lighting, replaying the first pass after the resolve drew the in-source frame: the pre-pass proves nothing"
    );
    // A resize (new textures attached to the G-buffer before the last
    // frame, the retrofit made by then: `dmsaa_refresh`), and a G-buffer
    // deleted and made again before the second frame (the new one found,
    // read and retrofitted; the program's delete of it at exit frees that
    // retrofit: `dmsaa_destroy`).
    for (event, resolves, calls) in [
        ("--resize", 2, ["dmsaa_retrofit_new 1", "dmsaa_refresh 1"]),
        ("--recreate", 1, ["dmsaa_retrofit_new 1", "dmsaa_destroy 1"]),
    ] {
        let args: &[&str] = &[event];
        let own = own_frame(&plain, &out, event, args, &xvfb.display());
        Run {
            what: format!("GLFW GLX, default options, {event}"),
            out: &out,
            display: xvfb.display(),
            args,
            in_source_args: &[],
            profile: None,
            resolves,
            calls: &calls,
        }
        .compare(&in_source, &plain, &own, "GLX");
    }
}

/// The same program with SDL2's window and loader (GLX and EGL), and with
/// GLFW's window but GL called through libGL's symbols (a program linked
/// with `-lGL`, reached through the library's exported wrappers): each
/// under `inject --check` draws its in-source build's frame bit for bit.
#[test]
fn sdl_and_linked_libgl_programs_under_inject_draw_the_in_source_frame() {
    if !can_run_glfw() {
        return;
    }
    let Some(xvfb) = common::xvfb::start_xvfb() else {
        return;
    };
    let (build, prefix) = capi::install("inject-flavours-build");
    let out = build.join("frames");
    std::fs::create_dir_all(&out).expect("making the frame folder");
    let mut flavours = vec![(Flavour::LinkedGl, "GLX")];
    if Path::new("/usr/include/SDL2/SDL.h").exists() {
        flavours.extend([(Flavour::Sdl, "GLX"), (Flavour::Sdl, "EGL")]);
    } else {
        common::skip(
            "no SDL2 headers (scripts/setup installs libsdl2-dev): the SDL2 program is not run",
        );
    }
    for (flavour, api) in flavours {
        let (in_source, plain) = build_tutorial(&build, &prefix, flavour);
        let args: &[&str] = if api == "EGL" { &["--egl"] } else { &[] };
        let name = format!("{}-{api}", flavour.name());
        let own = own_frame(&plain, &out, &name, args, &xvfb.display());
        Run {
            what: format!("{} {api}, default options", flavour.name()),
            out: &out,
            display: xvfb.display(),
            args,
            in_source_args: &[],
            profile: None,
            resolves: 2,
            calls: &["dmsaa_retrofit_new 1"],
        }
        .compare(&in_source, &plain, &own, api);
        if flavour == Flavour::LinkedGl {
            // Linked with libGL, the program loads glBufferSubData and the
            // block calls with glXGetProcAddressARB by name, which reaches
            // the library's own definition: its camera block's writes are
            // seen, the camera found, the in-source frame bit for bit (with
            // libGL's definition reached instead, the writes go unseen and
            // the program is left alone).
            let camera: &[&str] = &["--camera-block"];
            let own = own_frame(
                &plain,
                &out,
                "linked-gl-camera-block",
                camera,
                &xvfb.display(),
            );
            Run {
                what: "linked-gl GLX, camera block, default options".into(),
                out: &out,
                display: xvfb.display(),
                args: camera,
                in_source_args: &[],
                profile: None,
                resolves: 2,
                calls: &["the camera read from its uniform block 2"],
            }
            .compare(&in_source, &plain, &own, "GLX");
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

/// A library error (here `dmsaa_retrofit_new` refusing a profile whose rule
/// names an attachment the G-buffer lacks) is said once, turns the
/// retrofit off, and the program goes on as it is: its own frame, exit 0.
#[test]
fn a_library_error_leaves_the_program_as_it_is() {
    if !can_run_glfw() {
        return;
    }
    let Some(xvfb) = common::xvfb::start_xvfb() else {
        return;
    };
    let build = Path::new(env!("CARGO_TARGET_TMPDIR")).join("inject-error-build");
    let _ = std::fs::remove_dir_all(&build);
    std::fs::create_dir_all(&build).expect("making the build folder");
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in [
        "inject_tutorial.cpp",
        "tutorial_program.hpp",
        "tutorial_dsa.hpp",
    ] {
        std::fs::copy(capi::sources().join(f), src.join(f)).expect("copying the C++ sources");
    }
    let plain = build.join("tutorial");
    capi::run(
        cxx()
            .arg(src.join("inject_tutorial.cpp"))
            .arg("-o")
            .arg(&plain)
            .arg("-lglfw"),
        "compiling inject_tutorial.cpp",
    );
    let own = own_frame(&plain, &build, "own", &[], &xvfb.display());
    let profile = build.join("missing-attachment.toml");
    std::fs::write(&profile, "[[attachment]]\nindex = 5\nrule = \"select\"\n")
        .expect("writing the profile");
    let injected = build.join("injected.rgba");
    let output = capi::run(
        cli()
            .args(["inject", "--check", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--profile")
            .arg(&profile)
            .arg("--")
            .arg(&plain)
            .arg(&injected)
            .env("DISPLAY", xvfb.display()),
        "deferred-msaa inject with a profile the library refuses",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprint!("{stderr}");
    let failed: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("dmsaa_retrofit_new failed"))
        .collect();
    assert_eq!(failed.len(), 1, "not said exactly once:\n{stderr}");
    assert!(
        failed[0].contains("the retrofit is off for the rest of the run"),
        "{}",
        failed[0]
    );
    assert!(
        stderr.contains("0 changed, 0 GL errors left by the library"),
        "{stderr}"
    );
    assert!(
        frame(&injected) == own,
        "after the library's error the program's frame is not its own"
    );
}

/// Bad input to `inject` is a one-line error and exit status 1 before any
/// program runs: a profile that does not parse or has a bad value, a
/// missing profile, library or program.
#[test]
fn inject_refuses_bad_input_in_one_line() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("inject-refusals");
    std::fs::create_dir_all(&dir).expect("making the folder");
    let library = capi::built("libdeferred_msaa_inject", "so");
    let bad_value = dir.join("bad-value.toml");
    std::fs::write(&bad_value, "[retrofit]\nlayers = 3\n").expect("writing");
    let bad_key = dir.join("bad-key.toml");
    std::fs::write(&bad_key, "[retrofit]\nsampels = 4\n").expect("writing");
    let marker = dir.join("ran");
    let _ = std::fs::remove_file(&marker);
    let touch = ["--", "touch"];
    let cases: Vec<(Vec<std::ffi::OsString>, &str)> = vec![
        (
            vec!["--profile".into(), bad_value.clone().into()],
            "layers = 3: 1 or 2",
        ),
        (
            vec!["--profile".into(), bad_key.clone().into()],
            "is not valid",
        ),
        (
            vec!["--profile".into(), dir.join("none.toml").into()],
            "cannot read the profile",
        ),
    ];
    for (args, needle) in cases {
        let out = cli()
            .arg("inject")
            .arg("--library")
            .arg(&library)
            .args(&args)
            .args(touch)
            .arg(&marker)
            .output()
            .expect("running deferred-msaa");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(
            stderr.lines().count(),
            1,
            "{args:?}: not one line: {stderr}"
        );
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!marker.exists(), "{args:?}: the program ran");
    }
    for (args, needle) in [
        (
            vec![
                "--library".to_string(),
                dir.join("none.so").display().to_string(),
            ],
            "the inject library",
        ),
        (
            vec![
                "--library".to_string(),
                library.display().to_string(),
                "--".into(),
                dir.join("no-program").display().to_string(),
            ],
            "cannot run",
        ),
    ] {
        let mut command = cli();
        command.arg("inject").args(&args);
        if !args.iter().any(|a| a == "--") {
            command.args(touch).arg(&marker);
        }
        let out = command.output().expect("running deferred-msaa");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(
            stderr.lines().count(),
            1,
            "{args:?}: not one line: {stderr}"
        );
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    assert!(!marker.exists(), "a refused command ran its program");
}
