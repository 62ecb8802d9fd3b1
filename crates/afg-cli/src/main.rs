//! `afg <command>`: see [`afg_cli`].

use clap::Parser;

/// See the `mimalloc` feature in Cargo.toml.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    afg_cli::Cli::parse().command.run()
}
