//! `hapticlab doctor`: its arguments; the checks live in [`crate::doctor`].

use std::path::PathBuf;

use clap::Args;

use crate::support::{Failure, ProfileArg};

#[derive(Debug, Args)]
pub struct DoctorArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// The dataset folder to check (default: the console's, recordings/session-<date>).
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
    /// Print JSON for scripts: {checks: [{name, status, finding, fix}], ok}.
    #[arg(long)]
    pub json: bool,
    /// Print the Falcon's udev rule (to install: `hapticlab doctor
    /// --udev-rule | sudo tee /etc/udev/rules.d/70-novint-falcon.rules`)
    /// and check nothing.
    #[arg(long, conflicts_with_all = ["json", "dataset"])]
    pub udev_rule: bool,
}

pub fn run(a: DoctorArgs) -> Result<(), Failure> {
    if a.udev_rule {
        crate::outp!("{}", crate::device::falcon::usb::UDEV_RULE);
        return Ok(());
    }
    crate::doctor::run(&a.profile, a.dataset, a.json)
}
