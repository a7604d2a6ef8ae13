//! `hapticlab console` (and hapticlab without a command): the lab console,
//! [`crate::console::run`].

use std::path::PathBuf;

use clap::Args;

use crate::support::{Failure, ProfileArg, load_profile};

#[derive(Debug, Args, Default)]
pub struct ConsoleArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// Folder where stored scans go, one subfolder per label.
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
}

pub fn run(a: ConsoleArgs) -> Result<(), Failure> {
    crate::console::run(load_profile(&a.profile)?, a.dataset)
}
