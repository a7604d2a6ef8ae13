//! `hapticlab replay`: recordings played back through the console's
//! dashboard, [`crate::console::replay`].

use std::path::PathBuf;

use clap::Args;

use crate::support::{Failure, ProfileArg, load_profile};

#[derive(Debug, Args)]
pub struct ReplayArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// A recording, or a folder of recordings.
    #[arg(value_name = "FILE|DIR")]
    pub path: PathBuf,
    /// Recordings to train the model on (default: the folder replayed,
    /// or the folder above a recording's label folder).
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
}

pub fn run(a: ReplayArgs) -> Result<(), Failure> {
    crate::console::replay(load_profile(&a.profile)?, &a.path, a.dataset)
}
