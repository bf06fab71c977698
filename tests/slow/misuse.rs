//! The C API's misuse fuzzer (`tests/common/misuse/`) over thousands of
//! random call sequences, each in a child process of this test binary: a
//! crash (a signal, an abort) or a hang (no progress for
//! `HANG_SECONDS`) is that sequence's, and the next child goes on from the
//! sequence after it. Every failure is printed with the sequence shrunk
//! to the calls that still fail and the command that replays it:
//! `DEFERRED_MSAA_MISUSE_REPLAY=SEED:i,j,k cargo test --test slow
//! misuse -- --ignored --nocapture`. `DEFERRED_MSAA_MISUSE_SEQUENCES` sets
//! how many (5000 by default).

use crate::common;
use crate::common::misuse::{Api, Sequence, replay_value, run_sequence, shrink, take_call_count};
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const TEST: &str = "misuse::random_call_sequences_keep_the_hosts_state_in_child_processes";
/// A child runs `start:end`.
const CHILD: &str = "DEFERRED_MSAA_MISUSE_CHILD";
const REPLAY: &str = "DEFERRED_MSAA_MISUSE_REPLAY";
const SEQUENCES: &str = "DEFERRED_MSAA_MISUSE_SEQUENCES";
const HANG_SECONDS: u64 = 120;
/// `crash:SEED` or `hang:SEED`: the child aborts or sleeps at that
/// sequence, for the test of the runner itself.
const INJECT: &str = "DEFERRED_MSAA_MISUSE_INJECT";

/// `SEED:i,j,k` → the seed and the calls kept.
fn parse_replay(value: &str) -> (u64, Option<Vec<usize>>) {
    let (seed, keep) = value.split_once(':').unwrap_or((value, ""));
    let seed = seed.trim().parse().expect("SEED:i,j,k");
    let keep = (!keep.is_empty()).then(|| {
        keep.split(',')
            .map(|i| i.trim().parse().expect("SEED:i,j,k"))
            .collect()
    });
    (seed, keep)
}

fn sequence_of(value: &str) -> Sequence {
    let (seed, keep) = parse_replay(value);
    let s = Sequence::generate(seed);
    match keep {
        Some(keep) => s.only(&keep),
        None => s,
    }
}

/// In a child: run `start..end`, a line as each begins and ends; a failing
/// one is shrunk here and printed.
fn child(range: &str) {
    let (start, end) = range.split_once(':').expect("start:end");
    let (start, end): (u64, u64) = (start.parse().expect("start"), end.parse().expect("end"));
    let ctx = common::egl_context().expect("an EGL context in the child");
    let inject = std::env::var(INJECT).unwrap_or_default();
    for seed in start..end {
        println!("misuse begin {seed}");
        if inject == format!("crash:{seed}") {
            std::process::abort();
        }
        if inject == format!("hang:{seed}") {
            std::thread::sleep(Duration::from_secs(3600));
        }
        let s = Sequence::generate(seed);
        let failures = run_sequence(&ctx, &s);
        println!("misuse calls {}", take_call_count());
        if failures.is_empty() {
            println!("misuse end {seed} ok");
            continue;
        }
        let (keep, shrunk) = shrink(&ctx, &s);
        // The shrinking's calls are not the next sequence's.
        let _ = take_call_count();
        let report = format!(
            "sequence {seed} failed: {}\nshrunk to {} call(s):\n{}{}\nreplay: {REPLAY}={} cargo test --test slow misuse -- --ignored --nocapture",
            failures.first().map_or("", String::as_str),
            keep.len(),
            s.only(&keep).describe(),
            shrunk.join("\n"),
            replay_value(seed, &keep)
        );
        for line in report.lines() {
            println!("misuse report {seed} {line}");
        }
        println!("misuse end {seed} failed");
    }
}

/// A child on `start:end`, and its output line by line.
fn spawn(range: &str, inject: &str) -> (Child, mpsc::Receiver<String>) {
    let exe = std::env::current_exe().expect("the test binary's path");
    let mut child = Command::new(exe)
        .args(["--exact", TEST, "--include-ignored", "--nocapture"])
        .args(["--test-threads", "1"])
        .env(CHILD, range)
        .env(INJECT, inject)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawning a child");
    let stdout = child.stdout.take().expect("the child's stdout");
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                return;
            }
        }
    });
    (child, receive)
}

/// How a range went: its reports, and the sequences that crashed or hung.
#[derive(Default)]
struct Outcome {
    passed: u64,
    /// Library calls checked.
    calls: u64,
    /// Each failed sequence's report, by seed.
    reports: std::collections::BTreeMap<u64, String>,
    crashed: Vec<(u64, String)>,
    hung: Vec<u64>,
}

/// Run `start..end` in children, one after another, past crashes and
/// hangs (no line for `hang`); `inject` is passed to the children
/// ([`INJECT`]).
fn run_range(start: u64, end: u64, hang: Duration, inject: &str, outcome: &mut Outcome) {
    let mut next = start;
    while next < end {
        let (mut child, lines) = spawn(&format!("{next}:{end}"), inject);
        let mut current: Option<u64> = None;
        let mut last = Instant::now();
        let mut take = |line: &str, current: &mut Option<u64>, next: &mut u64| {
            if let Some(seed) = line.strip_prefix("misuse begin ") {
                *current = seed.parse().ok();
            } else if let Some(rest) = line.strip_prefix("misuse end ") {
                let (seed, verdict) = rest.split_once(' ').unwrap_or((rest, ""));
                let seed: u64 = seed.parse().expect("a seed");
                if verdict == "ok" {
                    outcome.passed += 1;
                }
                *current = None;
                *next = seed + 1;
            } else if let Some(calls) = line.strip_prefix("misuse calls ") {
                outcome.calls += calls.parse::<u64>().unwrap_or(0);
            } else if let Some(report) = line.strip_prefix("misuse report ") {
                let (seed, text) = report.split_once(' ').unwrap_or((report, ""));
                let seed: u64 = seed.parse().expect("a seed");
                let entry = outcome.reports.entry(seed).or_default();
                entry.push_str(text);
                entry.push('\n');
            }
        };
        let ended = loop {
            match lines.recv_timeout(Duration::from_secs(1)) {
                Ok(line) => {
                    last = Instant::now();
                    take(&line, &mut current, &mut next);
                }
                // Its output closed: it is exiting.
                Err(mpsc::RecvTimeoutError::Disconnected) => break child.wait().ok(),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if last.elapsed() > hang {
                        let _ = child.kill();
                        let _ = child.wait();
                        break None;
                    }
                }
            }
        };
        match (ended, current) {
            (None, Some(seed)) => {
                outcome.hung.push(seed);
                next = seed + 1;
            }
            (None, None) => panic!("a child went quiet between sequences, at {next}"),
            (Some(status), Some(seed)) => {
                outcome.crashed.push((seed, status.to_string()));
                next = seed + 1;
            }
            (Some(status), None) if next < end => {
                panic!("a child exited ({status}) between sequences, at {next}")
            }
            (Some(_), None) => {}
        }
    }
}

/// Whether `sequence` crashes or hangs a child: run as a replay.
fn crashes(value: &str) -> bool {
    let exe = std::env::current_exe().expect("the test binary's path");
    let mut child = Command::new(exe)
        .args(["--exact", TEST, "--include-ignored", "--nocapture"])
        .args(["--test-threads", "1"])
        .env(REPLAY, value)
        .env("DEFERRED_MSAA_MISUSE_REPLAY_CRASH_ONLY", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawning a replay");
    let started = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return !status.success(),
            Ok(None) if started.elapsed() > Duration::from_secs(HANG_SECONDS) => {
                let _ = child.kill();
                let _ = child.wait();
                return true;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(50)),
            Err(_) => return true,
        }
    }
}

/// The calls of `seed` that still crash or hang a child, dropped one at a
/// time.
fn shrink_crash(seed: u64) -> Vec<usize> {
    let mut keep: Vec<usize> = (0..Sequence::generate(seed).ops.len()).collect();
    let mut i = keep.len();
    while i > 0 {
        i -= 1;
        let mut fewer = keep.clone();
        fewer.remove(i);
        if crashes(&replay_value(seed, &fewer)) {
            keep = fewer;
        }
    }
    keep
}

#[test]
#[ignore = "slow tier: cargo test --test slow -- --ignored"]
fn random_call_sequences_keep_the_hosts_state_in_child_processes() {
    if let Ok(range) = std::env::var(CHILD) {
        child(&range);
        return;
    }
    if let Ok(value) = std::env::var(REPLAY) {
        let ctx = common::egl_context().expect("an EGL context");
        let s = sequence_of(&value);
        let failures = run_sequence(&ctx, &s);
        if std::env::var_os("DEFERRED_MSAA_MISUSE_REPLAY_CRASH_ONLY").is_some() {
            return;
        }
        assert!(
            failures.is_empty(),
            "{}{}",
            s.describe(),
            failures.join("\n")
        );
        return;
    }
    if common::egl_context().is_none() {
        return;
    }
    let total: u64 = std::env::var(SEQUENCES)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5000);
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 2) as u64;
    let started = Instant::now();
    let outcomes: Vec<Outcome> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (start, end) = (total * w / workers, total * (w + 1) / workers);
                scope.spawn(move || {
                    let mut outcome = Outcome::default();
                    run_range(
                        start,
                        end,
                        Duration::from_secs(HANG_SECONDS),
                        "",
                        &mut outcome,
                    );
                    outcome
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a worker"))
            .collect()
    });
    let mut all = Outcome::default();
    for o in outcomes {
        all.passed += o.passed;
        all.calls += o.calls;
        all.reports.extend(o.reports);
        all.crashed.extend(o.crashed);
        all.hung.extend(o.hung);
    }
    let steps: usize = (0..total).map(|s| Sequence::generate(s).ops.len()).sum();
    let rust = (0..total)
        .filter(|&s| Sequence::generate(s).api == Api::Rust)
        .count();
    eprintln!(
        "misuse fuzzer: {total} sequences ({} through the C API, {rust} through the Rust API; \
         {steps} steps, {} library calls checked) in {:.0} s on {workers} worker(s): \
         {} passed, {} failed, {} crashed, {} hung",
        total as usize - rust,
        all.calls,
        started.elapsed().as_secs_f64(),
        all.passed,
        all.reports.len(),
        all.crashed.len(),
        all.hung.len()
    );
    let mut problems: Vec<String> = all.reports.values().cloned().collect();
    for (seed, status) in &all.crashed {
        let keep = shrink_crash(*seed);
        problems.push(format!(
            "sequence {seed} crashed the child ({status}); shrunk to:\n{}replay: {REPLAY}={} cargo test --test slow misuse -- --ignored --nocapture",
            Sequence::generate(*seed).only(&keep).describe(),
            replay_value(*seed, &keep)
        ));
    }
    for seed in &all.hung {
        problems.push(format!(
            "sequence {seed} hung the child (no progress for {HANG_SECONDS} s):\n{}replay: {REPLAY}={seed} cargo test --test slow misuse -- --ignored --nocapture",
            Sequence::generate(*seed).describe()
        ));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
    assert_eq!(all.passed, total, "sequences that did not report");
}

#[test]
#[ignore = "slow tier: cargo test --test slow -- --ignored"]
fn the_runner_charges_a_crash_and_a_hang_to_their_sequences() {
    if common::egl_context().is_none() {
        return;
    }
    // Sequence 1's child aborts, sequence 3's sleeps: each is charged, and a
    // new child goes on from the next.
    for (inject, crashed, hung) in [("crash:1", vec![1], vec![]), ("hang:3", vec![], vec![3])] {
        let mut outcome = Outcome::default();
        run_range(0, 5, Duration::from_secs(5), inject, &mut outcome);
        assert_eq!(
            outcome.crashed.iter().map(|(s, _)| *s).collect::<Vec<_>>(),
            crashed,
            "{inject}"
        );
        assert_eq!(outcome.hung, hung, "{inject}");
        assert_eq!(outcome.passed, 4, "{inject}");
    }
}
