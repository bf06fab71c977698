//! The one-layer table for docs/bench.md: reads bench reports (one per
//! image size) and prints the Markdown table of
//! `deferred_msaa_lab::bench::one_layer::one_layer_table`.
//!
//! ```sh
//! cargo run --release --example one_layer_table -- target/docs/one-layer-320/report.json target/docs/one-layer-640/report.json
//! ```

use deferred_msaa_lab::bench::layers::load_report;
use deferred_msaa_lab::bench::one_layer::one_layer_table;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let paths: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        eprintln!("one_layer_table: give one or more report.json files");
        return ExitCode::from(2);
    }
    let mut reports = Vec::new();
    for p in &paths {
        match load_report(p) {
            Ok(r) => reports.push(r),
            Err(e) => {
                eprintln!("one_layer_table: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    let refs: Vec<_> = reports.iter().collect();
    print!("{}", one_layer_table(&refs));
    ExitCode::SUCCESS
}
