//! The README's motion lines: reads a `bench --motion` report and prints
//! `deferred_msaa_lab::bench::motion::motion_summary`, a line per scene.
//!
//! ```sh
//! cargo run --release --example motion_summary -- target/docs/motion/report.json
//! ```

use deferred_msaa_lab::bench::layers::load_report;
use deferred_msaa_lab::bench::motion::motion_summary;
use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("motion_summary: give the report.json of a bench --motion run");
        return ExitCode::from(2);
    };
    match load_report(std::path::Path::new(&path)) {
        Ok(report) if report.motion.is_some() => {
            print!("{}", motion_summary(&report));
            ExitCode::SUCCESS
        }
        Ok(_) => {
            eprintln!(
                "motion_summary: {} is a report of still frames (no --motion)",
                std::path::Path::new(&path).display()
            );
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("motion_summary: {e}");
            ExitCode::FAILURE
        }
    }
}
