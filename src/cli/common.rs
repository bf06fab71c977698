//! What every subcommand shares, in a module of its own so that the
//! subcommands import it without importing `cli/mod.rs`, which imports them.

use crate::context::Backend;

/// Options every subcommand takes.
#[derive(Debug, Clone, clap::Args)]
pub struct CommonArgs {
    /// Headless context backend.
    #[arg(long, default_value = "egl", value_parser = parse_backend)]
    pub backend: Backend,
}

fn parse_backend(s: &str) -> std::result::Result<Backend, String> {
    s.parse::<Backend>().map_err(|e| e.to_string())
}
