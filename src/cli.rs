//! The command line's top (clap derive): the program's name, help and
//! version, and its [`Command`]. Each command's arguments live with the
//! command in `commands/<name>.rs`.

use clap::Parser;

pub use crate::commands::Command;

#[derive(Debug, Parser)]
#[command(
    name = "hapticlab",
    version,
    about = "Haptic texture classification with a Novint Falcon (or its simulation)",
    long_about = "Haptic texture classification with a Novint Falcon (or its physical simulation): \
                  stroke a texture along a waypoint path, record the probe's trace, and name the \
                  texture from its Fourier spectrum with k-NN.\n\n\
                  Without a command, hapticlab opens the lab console on the built-in thesis profile \
                  and the simulated Falcon.",
    after_help = "Examples:\n  hapticlab simulate --out recordings/my-sim\n  hapticlab evaluate recordings/thesis-sim\n  hapticlab check profiles/thesis.toml"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}
