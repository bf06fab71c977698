//! The C API from C (`crates/capi`): the libraries cargo built for this
//! test binary (the lab's dev-dependency on `deferred-msaa-capi`) are
//! installed by `scripts/capi-install` into a prefix under the target's
//! temporary folder, and C programs are compiled with the system `cc`
//! against that prefix alone: its header and its static library, or,
//! through `pkg-config`, its shared library.
//!
//! - `tutorial_host.c`, the LearnOpenGL deferred-shading engine with the
//!   two calls and the second layer's three: its lit image is closer
//!   (FLIP mean) to its own 16x supersampled image with the retrofit and
//!   with two layers than without MSAA; the GL state around every call is
//!   unchanged, nothing of the library's is left after `dmsaa_destroy`,
//!   and the host's frame afterwards is its frame before, bit for bit.
//!   Its second lighting masked by `dmsaa_second_layer_selection`'s stencil
//!   (which marks some pixels, not all, with 0 or 1 only) gives the same
//!   two-layer image, bit for bit.
//! - `bad_calls.c`: every bad call returns an error status with a one-line
//!   message, and the process keeps running.
//! - `minimal_host.c`, a host outside the repository, built with only
//!   `pkg-config --cflags --libs deferred-msaa`, retrofits a tutorial
//!   G-buffer through the five calls.
//!
//! Without a C compiler the test is skipped with a reason (`scripts/setup`
//! installs gcc, the EGL and GL headers and pkgconf).

use crate::common;
use deferred_msaa_lab::compare::flip;
use deferred_msaa_lab::context::Backend;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// What the static library needs beside it (`rustc --print
/// native-static-libs`, as the pkg-config file's `Libs.private` says).
const NATIVE_LIBS: &[&str] = &[
    "-lgcc_s",
    "-lutil",
    "-lrt",
    "-lpthread",
    "-lm",
    "-ldl",
    "-lc",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn sources() -> PathBuf {
    root().join("crates/capi/tests/c")
}

/// The library cargo built for this binary, newest first among the
/// builds in its folder (`target/<profile>/deps`), as `kind` (`a`, `so`).
fn built_library(kind: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let deps = exe.parent().expect("the test binary's folder");
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(deps)
        .expect("reading the test binary's folder")
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.starts_with("libdeferred_msaa_capi") && name.ends_with(&format!(".{kind}"))
        })
        .filter_map(|p| Some((p.metadata().ok()?.modified().ok()?, p)))
        .collect();
    found.sort();
    found
        .pop()
        .map(|(_, p)| p)
        .unwrap_or_else(|| panic!("no libdeferred_msaa_capi*.{kind} in {}", deps.display()))
}

fn run(command: &mut Command, what: &str) -> Output {
    let out = command.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
    out
}

/// `cc` with the project's warnings as errors.
fn cc() -> Command {
    let mut c = Command::new("cc");
    c.args(["-std=c99", "-O1", "-Wall", "-Wextra", "-Werror"]);
    c
}

/// The raw RGBA8 image `name` the C host wrote.
fn image(dir: &Path, name: &str, width: u32, height: u32) -> image::RgbaImage {
    let bytes = std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    image::RgbaImage::from_raw(width, height, bytes)
        .unwrap_or_else(|| panic!("{name} is not {width}x{height} RGBA8"))
}

#[test]
fn c_hosts_build_against_the_installed_library_and_run() {
    if Command::new("cc").arg("--version").output().is_err() {
        common::skip("no C compiler: `cc` is not on PATH (scripts/setup installs gcc)");
        return;
    }
    if let Err(e) = Backend::Egl.check_library() {
        common::skip(&e.to_string());
        return;
    }
    let build = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-build");
    let _ = std::fs::remove_dir_all(&build);
    let staged = build.join("built");
    std::fs::create_dir_all(&staged).expect("making the build folder");
    for kind in ["a", "so"] {
        std::fs::copy(
            built_library(kind),
            staged.join(format!("libdeferred_msaa_capi.{kind}")),
        )
        .expect("staging the built library");
    }
    let prefix = build.join("prefix");
    run(
        Command::new(root().join("scripts/capi-install"))
            .arg(&prefix)
            .arg(&staged),
        "scripts/capi-install",
    );
    // The hosts' sources beside nothing of the repository's: only the
    // prefix's header and libraries are on the compiler's paths.
    let src = build.join("src");
    std::fs::create_dir_all(&src).expect("making the source folder");
    for f in [
        "tutorial_host.c",
        "bad_calls.c",
        "minimal_host.c",
        "egl_gl.h",
    ] {
        std::fs::copy(sources().join(f), src.join(f)).expect("copying a C source");
    }
    let include = prefix.join("include");
    let static_lib = prefix.join("lib/libdeferred_msaa_capi.a");
    let link_static = |name: &str| -> PathBuf {
        let exe = build.join(name);
        run(
            cc().arg("-I")
                .arg(&include)
                .arg(src.join(format!("{name}.c")))
                .arg("-o")
                .arg(&exe)
                .arg(&static_lib)
                .arg("-lEGL")
                .args(NATIVE_LIBS),
            &format!("compiling {name}.c"),
        );
        exe
    };

    // The tutorial's engine, against the static library.
    let tutorial = link_static("tutorial_host");
    let images = build.join("images");
    std::fs::create_dir_all(&images).expect("making the image folder");
    let out = run(Command::new(&tutorial).arg(&images), "tutorial_host");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    eprint!("{stdout}");
    assert!(stdout.contains("GL state unchanged: yes"), "{stdout}");
    assert!(
        stdout.contains("live objects after dmsaa_destroy: 0"),
        "{stdout}"
    );
    let (w, h) = stdout
        .lines()
        .find_map(|l| l.strip_prefix("image "))
        .and_then(|s| s.split_once('x'))
        .map(|(w, h)| (w.parse::<u32>().unwrap(), h.parse::<u32>().unwrap()))
        .expect("the host prints its image size");
    let reference = image(&images, "reference.rgba", w, h);
    let none = image(&images, "none.rgba", w, h);
    let msaa = image(&images, "msaa.rgba", w, h);
    let layers = image(&images, "layers.rgba", w, h);
    let layers_masked = image(&images, "layers-masked.rgba", w, h);
    let after = image(&images, "after.rgba", w, h);
    assert!(
        after == none,
        "the host's frame after dmsaa_destroy differs from its frame before the retrofit"
    );
    assert!(
        layers_masked == layers,
        "the second lighting masked by dmsaa_second_layer_selection changed the mixed image"
    );
    let error = |test: &image::RgbaImage| flip(&reference, test).expect("same sizes").mean;
    let (e_none, e_msaa, e_layers) = (error(&none), error(&msaa), error(&layers));
    eprintln!(
        "tutorial host, FLIP mean against its 16x supersampled image: none {e_none:.4}, \
         retrofit {e_msaa:.4}, two layers {e_layers:.4}"
    );
    assert!(
        e_msaa < e_none,
        "the retrofit ({e_msaa:.4}) is not closer to the 16x image than no MSAA ({e_none:.4})"
    );
    assert!(
        e_layers < e_none,
        "two layers ({e_layers:.4}) are not closer to the 16x image than no MSAA ({e_none:.4})"
    );

    // The bad calls, against the static library.
    let bad = link_static("bad_calls");
    let out = run(&mut Command::new(&bad), "bad_calls");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("bad call: "))
        .collect();
    for required in [
        "null options",
        "null handle (resolve)",
        "zero FBO",
        "FBO without depth",
        "finish without begin",
        "loader without glGetBooleani_v",
        "a name that is no framebuffer",
    ] {
        assert!(
            lines
                .iter()
                .any(|l| l.starts_with(&format!("bad call: {required}: "))),
            "bad_calls made no `{required}` call:\n{stdout}"
        );
    }
    assert!(stdout.ends_with("ok\n"), "{stdout}");

    // A host outside the repository, through pkg-config and the shared
    // library.
    let flags = match Command::new("pkg-config")
        .args(["--cflags", "--libs", "deferred-msaa"])
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig"))
        .output()
    {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout).to_string(),
        Ok(out) => panic!(
            "pkg-config does not find the installed deferred-msaa.pc: {}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(_) => {
            common::skip("no pkg-config (scripts/setup installs pkgconf)");
            return;
        }
    };
    let minimal = build.join("minimal_host");
    run(
        cc().arg(src.join("minimal_host.c"))
            .arg("-o")
            .arg(&minimal)
            .args(flags.split_whitespace())
            .arg("-lEGL"),
        "compiling minimal_host.c with pkg-config's flags",
    );
    let out = run(
        Command::new(&minimal).env("LD_LIBRARY_PATH", prefix.join("lib")),
        "minimal_host",
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.ends_with("ok\n"), "{stdout}");
}
