//! What every command shares, below the commands themselves: [`Failure`]
//! (bad input, exit code 2, or a runtime failure, exit code 1), loading the
//! profile named by `--profile`, and progress bars on standard error.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::acquire;
use crate::cli::ProfileArg;
use crate::profile::LoadedProfile;

/// A command that failed: bad input (exit 2) or a runtime failure (exit 1).
#[derive(Debug)]
pub enum Failure {
    BadInput(String),
    Runtime(String),
}

impl Failure {
    pub fn exit_code(&self) -> i32 {
        match self {
            Failure::BadInput(_) => 2,
            Failure::Runtime(_) => 1,
        }
    }
    pub fn message(&self) -> &str {
        match self {
            Failure::BadInput(m) | Failure::Runtime(m) => m,
        }
    }
}

impl From<acquire::AcquireError> for Failure {
    fn from(e: acquire::AcquireError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

impl From<crate::dataset::DatasetError> for Failure {
    fn from(e: crate::dataset::DatasetError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

pub(crate) fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

pub(crate) fn runtime(m: impl std::fmt::Display) -> Failure {
    Failure::Runtime(m.to_string())
}

pub fn load_profile(arg: &ProfileArg) -> Result<LoadedProfile, Failure> {
    LoadedProfile::load(&arg.profile).map_err(bad)
}

/// A progress bar on a terminal; nothing when standard error is piped.
pub(crate) fn progress_bar(total: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    }
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed}, ETA {eta})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}
