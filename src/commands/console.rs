//! `hapticlab console` (and hapticlab without a command): the lab console,
//! [`crate::console::run`]. Without `--dataset` the session folder is
//! chosen by [`crate::console::session::choose`]; without `--profile`, the
//! profile is the one that folder names, else the built-in thesis profile.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use clap::Args;

use crate::console::session;
use crate::profile::LoadedProfile;
use crate::support::Failure;

#[derive(Debug, Args, Default, Clone)]
pub struct ConsoleArgs {
    /// Experiment profile (TOML); `thesis` names the built-in thesis profile.
    /// By default, the profile the session's folder was recorded under
    /// (its session.toml), else thesis.
    #[arg(long, short = 'p', value_name = "PROFILE")]
    pub profile: Option<PathBuf>,
    /// Folder where stored scans go, one subfolder per label. By default
    /// today's recordings/session-<date>, or the most recent session folder
    /// used in the last 7 days (S in the console lists them).
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
}

/// How a profile is written in session.toml: `thesis`, or the file's full
/// path (a session may be resumed from another folder).
fn profile_name(p: &Path) -> String {
    if p.as_os_str() == "thesis" && !p.exists() {
        return "thesis".into();
    }
    std::fs::canonicalize(p)
        .unwrap_or_else(|_| p.to_path_buf())
        .display()
        .to_string()
}

pub fn run(a: ConsoleArgs) -> Result<(), Failure> {
    let (dataset, resumed) = match a.dataset {
        Some(d) => (d, None),
        None => session::choose(Path::new(session::SESSIONS_ROOT), SystemTime::now()),
    };
    let remembered = session::profile_of(&dataset);
    let (profile, from_session) = match (a.profile, remembered) {
        (Some(p), _) => (p, false),
        (None, Some(p)) => (p, true),
        (None, None) => (PathBuf::from("thesis"), false),
    };
    let lp = LoadedProfile::load(&profile).map_err(|e| {
        Failure::BadInput(if from_session {
            format!(
                "{e} (the profile {} names; give another with --profile)",
                dataset.join(session::SESSION_FILE).display()
            )
        } else {
            e.to_string()
        })
    })?;
    crate::console::run(
        lp,
        crate::console::Opening {
            dataset,
            resumed,
            profile: profile_name(&profile),
        },
    )
}
