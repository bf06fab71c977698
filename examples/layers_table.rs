//! The second layer's table for the README: reads bench reports (one per
//! light setting) and prints the Markdown tables of
//! `deferred_msaa_lab::bench::layers::layers_table`.
//!
//! ```sh
//! cargo run --release --example layers_table -- target/docs/layers/report.json target/docs/layers48/report.json
//! ```

use deferred_msaa_lab::bench::layers::{layers_table, load_report};
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let paths: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        eprintln!("layers_table: give one or more report.json files");
        return ExitCode::from(2);
    }
    let mut reports = Vec::new();
    for p in &paths {
        match load_report(p) {
            Ok(r) => reports.push(r),
            Err(e) => {
                eprintln!("layers_table: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    let refs: Vec<_> = reports.iter().collect();
    print!("{}", layers_table(&refs));
    ExitCode::SUCCESS
}
