//! `afg <command>`: see [`afg_cli`].

use clap::Parser;

/// See the `mimalloc` feature in Cargo.toml.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Exit status 0 on success, 1 after one line `error: …` on stderr, 2 for a usage error.
/// A reader that stops reading (`afg … | head`) ends the command quietly, as Unix
/// tools do, instead of printing's panic on the closed pipe.
fn main() -> std::process::ExitCode {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info.payload().downcast_ref::<String>();
        if message.is_some_and(|m| m.contains("Broken pipe")) {
            std::process::exit(0);
        }
        report(info);
    }));
    afg_eval::report::exit_code(afg_cli::Cli::parse().command.run())
}
