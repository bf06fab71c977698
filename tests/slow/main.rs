//! The slow tier of the lab's integration tests, one binary: the bench and
//! the first run as a user runs them, the examples (the viewer under Xvfb, its thousand live
//! mode switches), and the C and Rust APIs' misuse fuzzer over thousands of
//! random call sequences in child processes. Every test here is `#[ignore]`d, so plain `cargo test`
//! only lists them; `scripts/test` runs them with
//! `cargo test --test slow -- --ignored`. The fast tier is `tests/fast`; both
//! share the test kit in `tests/common`.

#[path = "../common/mod.rs"]
mod common;

mod bench;
mod examples;
mod first_run;
mod misuse;
mod property;
