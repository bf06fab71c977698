//! The `deferred-msaa` binary; everything lives in the library's `cli` module.

fn main() {
    std::process::exit(deferred_msaa_lab::cli::main());
}
