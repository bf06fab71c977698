//! `deferred-msaa` with no subcommand, as a newcomer's `cargo run --release`
//! meets it: run in an empty working directory, it writes the side-by-side
//! and the summary into `target/deferred-msaa/` there, prints the summary
//! and where it wrote, and shows the point: the best method's error against
//! the reference below no MSAA's.

use crate::common;

use std::process::Command;

/// The methods the first run compares, in its order.
const METHODS: [&str; 3] = ["none", "median 4x", "median:layers=2 4x"];

/// `(method, FLIP)` of each `method: FLIP x, y ms` part of the summary line.
fn flips(line: &str) -> Vec<(String, f64)> {
    line.split(" · ")
        .filter_map(|part| {
            let (method, rest) = part.split_once(": FLIP ")?;
            let flip = rest.split(',').next()?.trim().parse().ok()?;
            Some((method.to_string(), flip))
        })
        .collect()
}

#[test]
#[ignore = "slow tier: scripts/test runs it"]
fn the_first_run_writes_the_side_by_side_and_shows_the_point() {
    if common::egl_context().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("dmsaa-first-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_deferred-msaa"))
        .current_dir(&dir)
        .output()
        .expect("running deferred-msaa");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written = dir.join("target/deferred-msaa");
    let summary = std::fs::read_to_string(written.join("first-run.txt")).expect("first-run.txt");
    let line = summary.trim_end();
    assert_eq!(
        stdout.lines().next(),
        Some(line),
        "the summary is printed first"
    );
    assert!(
        stdout.contains("target/deferred-msaa/first-run.png"),
        "where it wrote: {stdout}"
    );
    assert!(
        line.starts_with("builtin:greebles 640x360 against ssaa 16 spp"),
        "{line}"
    );
    let flips = flips(line);
    let names: Vec<&str> = flips.iter().map(|(m, _)| m.as_str()).collect();
    assert_eq!(names, METHODS, "{line}");
    for part in line.split(" · ").skip(1) {
        assert!(part.ends_with(" ms"), "a frame time per method: {part}");
    }
    let (none, best) = (flips[0].1, flips[2].1);
    assert!(
        best < none,
        "median:layers=2's FLIP {best} is not below none's {none}"
    );
    let figure = image::open(written.join("first-run.png")).expect("first-run.png decodes");
    // Four columns (the reference and the three methods) of at least the
    // overview's width, and the frames above the magnified crops.
    assert!(
        figure.width() >= 4 * 320 && figure.height() >= 180 + 320,
        "{}x{}",
        figure.width(),
        figure.height()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
