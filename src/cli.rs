//! The command line's top (clap derive): the program's name, help and
//! version (with the commit it was built from), and its [`Command`]. Each command's arguments live with the
//! command in `commands/<name>.rs`; the console's are also accepted without
//! a command (`hapticlab --dataset DIR`), as the console is the default.

use clap::Parser;

pub use crate::commands::Command;
use crate::commands::console::ConsoleArgs;

#[derive(Debug, Parser)]
#[command(
    name = "hapticlab",
    // With the commit it was built from: `hapticlab 0.1.0 (commit 67c70ce)`.
    version = crate::version::VERSION,
    about = "Haptic texture classification with a Novint Falcon (or its simulation)",
    long_about = "Haptic texture classification with a Novint Falcon (or its physical simulation): \
                  stroke a texture along a waypoint path, record the probe's trace, and name the \
                  texture from its Fourier spectrum with k-NN.\n\n\
                  Without a command, hapticlab opens the lab console (its options as for \
                  `hapticlab console`): on the most recent session folder, the built-in thesis \
                  profile and the simulated Falcon.",
    args_conflicts_with_subcommands = true,
    after_help = "Examples:\n  hapticlab --dataset recordings/my-session\n  hapticlab simulate --out recordings/my-sim\n  hapticlab evaluate recordings/thesis-sim\n  hapticlab check profiles/thesis.toml"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The console's options, for `hapticlab` without a command.
    #[command(flatten)]
    pub console: ConsoleArgs,
}

impl Cli {
    /// The command to run: the console (with the top-level options) by default.
    pub fn command(self) -> Command {
        self.command.unwrap_or(Command::Console(self.console))
    }
}

/// The whole command line's clap definition, for what is generated from it
/// (`hapticlab completions`, `hapticlab man`).
pub fn definition() -> clap::Command {
    <Cli as clap::CommandFactory>::command()
}
