//! `afg <command>`: see [`afg_cli`].

use clap::Parser;

/// See the `mimalloc` feature in Cargo.toml.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Exit status 0 on success, 1 after one line `error: …` on stderr, 2 for a usage error.
fn main() -> std::process::ExitCode {
    afg_eval::report::exit_code(afg_cli::Cli::parse().command.run())
}
