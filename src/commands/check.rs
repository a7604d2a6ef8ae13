//! `hapticlab check`: parse and validate profiles, one line each.

use std::path::PathBuf;

use clap::Args;

use crate::acquire;
use crate::profile::LoadedProfile;
use crate::support::{Failure, bad};

#[derive(Debug, Args)]
pub struct CheckArgs {
    #[arg(required = true, value_name = "PROFILE")]
    pub profiles: Vec<PathBuf>,
}

pub fn run(a: CheckArgs) -> Result<(), Failure> {
    check(&a.profiles)
}

fn check(profiles: &[PathBuf]) -> Result<(), Failure> {
    let mut errors = Vec::new();
    for p in profiles {
        match LoadedProfile::load(p) {
            Ok(lp) => crate::outln!(
                "{}: ok — profile {:?}, device {}, {} waypoints, {} textures, {} features, k = {}{}",
                p.display(),
                lp.profile.name,
                lp.profile.device.kind.name(),
                lp.profile.path.waypoints_m.len(),
                lp.profile.textures.len(),
                lp.profile.analysis.feature_count(),
                lp.profile.classifier.k_text(),
                acquire::injected_faults(&lp)
                    .map(|f| format!("; injects faults: {f}"))
                    .unwrap_or_default()
            ),
            Err(e) => errors.push(e.to_string()),
        }
    }
    // One line per invalid profile, each a whole message; the last is the failure.
    match errors.split_last() {
        None => Ok(()),
        Some((last, rest)) => {
            for e in rest {
                crate::errln!("hapticlab: error: {e}");
            }
            Err(bad(last))
        }
    }
}
