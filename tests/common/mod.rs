//! What both tiers (`tests/fast`, `tests/slow`) share beside the
//! `deferred-msaa-testkit` crate (the toy host, the generator, projections):
//! contexts and the skip rule, a test run alone (`alone`), the examples
//! built and found (`examples`), goldens (`golden`),
//! the GL state snapshot (`gl_state`), the property test over random host
//! G-buffers (`property`), the C API's misuse fuzzer (`misuse`), the sRGB
//! transfer function in f64 (`srgb`).
#![allow(dead_code)]

pub mod examples;
pub mod gl_state;
pub mod golden;
pub mod misuse;
pub mod property;
pub mod srgb;
pub mod xvfb;

use deferred_msaa_lab::context::{Backend, HeadlessContext};

/// An EGL context, or `None` (with a printed reason) when the system library is absent.
pub fn egl_context() -> Option<HeadlessContext> {
    context(Backend::Egl)
}

/// A context on `backend`, or `None` (with a printed reason) when its system
/// library is absent. Any other failure fails the test.
pub fn context(backend: Backend) -> Option<HeadlessContext> {
    if let Err(e) = backend.check_library() {
        skip(&e.to_string());
        return None;
    }
    match HeadlessContext::new(backend) {
        Ok(c) => {
            // As a Rust host does: the crate's per-draw-buffer queries, and
            // the snapshot's own.
            deferred_msaa_lab::gl::load_state_functions(|name| c.get_proc_address(name))
                .expect("glIsEnabledi and glGetBooleani_v");
            gl_state::load(|name| c.get_proc_address(name));
            Some(c)
        }
        Err(e) => panic!("creating a {backend} context failed: {e}"),
    }
}

/// Report a test skipped for a missing system package; under the README's
/// test command (`DEFERRED_MSAA_REQUIRE_ALL=1`) nothing may skip, so it fails.
pub fn skip(reason: &str) {
    if std::env::var_os("DEFERRED_MSAA_REQUIRE_ALL").is_some() {
        panic!("required but missing: {reason}");
    }
    eprintln!("skipped: {reason}");
}

/// Whether the calling test runs its body here: in a child process of the
/// test binary that runs that test and nothing else. A measure of the whole
/// process (its resident memory) then sees that test alone, not the other
/// tests the tier's one binary runs beside it on other threads. In the
/// parent it runs the child, fails with the child's output if the child
/// fails, and returns `false`. `module` is the caller's `module_path!()`.
pub fn alone(module: &str, test: &str) -> bool {
    const VAR: &str = "DEFERRED_MSAA_TEST_ALONE";
    // Test names leave out the crate: `reliability::name`, not `fast::reliability::name`.
    let module = module.split_once("::").map_or("", |(_, m)| m);
    let name = if module.is_empty() {
        test.to_string()
    } else {
        format!("{module}::{test}")
    };
    if std::env::var_os(VAR).is_some_and(|v| v == name.as_str()) {
        return true;
    }
    let exe = std::env::current_exe().expect("the test binary's path");
    let out = std::process::Command::new(exe)
        .args(["--exact", &name, "--include-ignored", "--nocapture"])
        .args(["--test-threads", "1"])
        .env(VAR, &name)
        .output()
        .expect("running the test alone");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprint!("{stderr}");
    assert!(
        out.status.success(),
        "{name}, run alone, failed:\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains("1 passed"),
        "{name} did not run alone:\n{stdout}"
    );
    false
}

/// The `deferred-msaa` binary on a real OpenGL 3.2 core / GLSL 1.50
/// context (Mesa's version overrides, as CI's floor run sets them).
pub fn floor_command() -> std::process::Command {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_deferred-msaa"));
    command
        .env("MESA_GL_VERSION_OVERRIDE", "3.2")
        .env("MESA_GLSL_VERSION_OVERRIDE", "150");
    command
}

/// Runs `deferred-msaa ARGS` on the floor ([`floor_command`]), after
/// checking once that `info` reports a 3.2 context there.
pub fn floor_cli() -> impl Fn(&[&str]) -> std::process::Output {
    let info = floor_command()
        .args(["info", "--json"])
        .output()
        .expect("running deferred-msaa info");
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).expect("info JSON");
    let version = info["gl_version"].as_str().unwrap_or("");
    assert!(version.starts_with("3.2"), "not a 3.2 context: {version}");
    |args| {
        floor_command()
            .args(args)
            .output()
            .expect("running deferred-msaa")
    }
}
