//! The `deferred-msaa` command line: argument parsing and the subcommands.
//! `src/main.rs` only calls [`main`].

mod bench;
mod common;
pub mod first_run;
mod info;
mod inject;
mod render;

pub use common::CommonArgs;

use crate::context::Backend;
use crate::{Error, Result};
use clap::{Parser, Subcommand};

/// Depth-aware MSAA for OpenGL 3.2+ deferred renderers.
#[derive(Debug, Parser)]
#[command(name = "deferred-msaa", version, about)]
pub struct Cli {
    /// What to do (default: the first run: the built-in default scene with
    /// no MSAA, the one-layer resolve and the best method, side by side in
    /// target/deferred-msaa/first-run.png).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Report the context: versions, renderer, real sample counts and positions.
    Info(info::InfoArgs),
    /// Render a scene through the deferred pipeline and write a PNG.
    Render(render::RenderCmd),
    /// Render, then write every sample of every attachment as .npy, final.png and meta.json.
    Dump(render::DumpCmd),
    /// Measure error against run time for every method; write a report with plots.
    Bench(bench::BenchCmd),
    /// Run an unmodified deferred GL program with MSAA injected (docs/inject.md).
    Inject(inject::InjectArgs),
}

/// Run the CLI; returns the process exit code. Errors print as one line on stderr.
pub fn main() -> i32 {
    // A panic is a bug, but even then the user gets one line, not a backtrace.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        let msg = msg.lines().next().unwrap_or("").to_string();
        eprintln!("error: internal error ({msg}); please report it");
    }));
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = match parse_args::<Cli>() {
        Ok(c) => c,
        Err(Printed::Help) => return 0,
        Err(Printed::UsageError) => return 2,
    };
    if let Some(Command::Inject(args)) = &cli.command {
        // The program's own exit status is the command's.
        return match inject::run(args) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("error: {}", one_line(&e));
                1
            }
        };
    }
    match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(())) => 0,
        Ok(Err(e)) => {
            eprintln!("error: {}", one_line(&e));
            1
        }
        Err(_) => 101,
    }
}

/// What [`parse_args`] printed instead of returning the arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Printed {
    /// `--help` or `--version`, on standard output.
    Help,
    /// A usage error, as one line on standard error.
    UsageError,
}

/// Parse the process's arguments into `P` (the `deferred-msaa` binary's and
/// the examples' command lines), printing `--help` and `--version` as clap
/// writes them and a usage error as one line, like every other refusal.
pub fn parse_args<P: Parser>() -> std::result::Result<P, Printed> {
    match P::try_parse() {
        Ok(p) => Ok(p),
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            Err(Printed::Help)
        }
        Err(e) => {
            let text = e.render().to_string();
            let line = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("error: bad arguments");
            eprintln!("{} (see --help)", line.trim_end());
            Err(Printed::UsageError)
        }
    }
}

/// An error's message on one line (shader logs are folded).
pub fn one_line(e: &Error) -> String {
    e.to_string()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" | ")
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Render(cmd)) => render::run_render(&cmd),
        Some(Command::Dump(cmd)) => render::run_dump(&cmd),
        Some(Command::Bench(cmd)) => bench::run(&cmd),
        Some(Command::Inject(args)) => inject::run(&args).map(|_| ()),
        // The first run: what the crate does, shown on the default scene.
        None => first_run::run(Backend::Egl, std::path::Path::new(first_run::FIRST_RUN_DIR)),
    }
}
