//! Running a test program, as it is or under `deferred-msaa inject`, and
//! reading what the library said: shared by the engines' tests.

use super::{capi, cli};
use std::ffi::OsStr;
use std::path::Path;
use std::process::{Command, Output};

/// The lines the library said, but `--check`'s summary.
pub(super) fn said(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("deferred-msaa inject: ") && !l.contains("inject: check: "))
        .collect()
}

/// The check's summary line; asserts it is clean with `resolves` frames
/// resolved.
pub(super) fn clean_check<'a>(stderr: &'a str, what: &str, resolves: u32) -> &'a str {
    let check = stderr
        .lines()
        .find(|l| l.starts_with("deferred-msaa inject: check: "))
        .unwrap_or_else(|| panic!("{what}: no check summary:\n{stderr}"));
    assert!(
        check.contains(&format!(
            " 0 changed, 0 GL errors left by the library, 0 left pending by the program; {resolves} frames resolved"
        )),
        "{what}: {check}"
    );
    check
}

/// `command`, a test program that prints `ok` last when all its checks
/// held.
pub(super) fn run_ok(command: &mut Command, what: &str) -> Output {
    let output = capi::run(command, what);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.ends_with("ok\n"), "{what}: {stdout}");
    output
}

/// `program` with `args` under `deferred-msaa inject` (the preloaded
/// `library`, `flags` before the `--`: `--check`, `--profile F`,
/// `--learn F`); the program's checks must hold. Its stderr, printed.
pub(super) fn inject<F, A>(library: &Path, flags: F, program: &Path, args: A, what: &str) -> String
where
    F: IntoIterator,
    F::Item: AsRef<OsStr>,
    A: IntoIterator,
    A::Item: AsRef<OsStr>,
{
    let output = run_ok(
        cli()
            .args(["inject", "--library"])
            .arg(library)
            .args(flags)
            .arg("--")
            .arg(program)
            .args(args),
        &format!("deferred-msaa inject, {what}"),
    );
    let stderr = String::from_utf8_lossy(&output.stderr).to_string();
    eprint!("{what}:\n{stderr}");
    stderr
}

/// A learned profile completed as a user completes it: each `(index,
/// keys)` put under that attachment's `index = N` line, `tables` (TOML)
/// appended. Every line the file holds is kept.
pub(super) fn completed(learned: &str, keys: &[(u32, &str)], tables: &str) -> String {
    let mut text = String::new();
    for line in learned.lines() {
        text.push_str(line);
        text.push('\n');
        for (index, more) in keys {
            if line == format!("index = {index}") {
                text.push_str(more);
            }
        }
    }
    text.push('\n');
    text.push_str(tables);
    text
}
