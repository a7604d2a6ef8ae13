//! `hapticlab check`: parse and validate profiles, one line each.

use std::path::PathBuf;

use clap::Args;

use crate::acquire;
use crate::profile::{FeatureFamily, LoadedProfile, Method};
use crate::support::{Failure, bad};

#[derive(Debug, Args)]
pub struct CheckArgs {
    #[arg(required = true, value_name = "PROFILE")]
    pub profiles: Vec<PathBuf>,
}

pub fn run(a: CheckArgs) -> Result<(), Failure> {
    check(&a.profiles)
}

/// What the profile holds, and for an analysis-only one what it can be used for.
fn summary(lp: &LoadedProfile) -> String {
    let p = &lp.profile;
    let a = &p.analysis;
    let features = match a.features {
        FeatureFamily::Spectrum => format!("{} features", a.feature_count()),
        FeatureFamily::Quantiles => format!("{} interval-quantile features", a.feature_count()),
        FeatureFamily::Hydra => format!("{} competing-kernel features", a.feature_count()),
        FeatureFamily::Kernels => format!(
            "{} random-kernel features ({} asked, a multiple of 84 per channel) of {} points",
            a.fitted_feature_count(),
            a.kernel_features_asked(),
            a.feature_count()
        ),
    };
    let classifier = match p.classifier.method {
        Method::Knn => format!("k = {}", p.classifier.k_text()),
        other => other.name().into(),
    };
    let analysis = format!("{features}, {classifier}");
    match lp.rig() {
        Ok(rig) => format!(
            "profile {:?}, device {}, {} waypoints, {} textures, {analysis}{}",
            p.name,
            rig.device.kind.name(),
            rig.path.waypoints_m.len(),
            p.textures.len(),
            acquire::injected_faults(lp)
                .map(|f| format!("; injects faults: {f}"))
                .unwrap_or_default()
        ),
        Err(missing) => format!(
            "profile {:?}, analysis only (no {} section): {analysis}, channel{} {} along {}; \
             for features, train, classify, evaluate, inspect, plot and replay of recorded scans, \
             not for scan, simulate, doctor or the live console",
            p.name,
            missing.sections(),
            if p.analysis.channels.is_empty() {
                ""
            } else {
                "s"
            },
            p.analysis.all_channels().collect::<Vec<_>>().join(", "),
            p.analysis.axis
        ),
    }
}

fn check(profiles: &[PathBuf]) -> Result<(), Failure> {
    let mut errors = Vec::new();
    for p in profiles {
        match LoadedProfile::load(p) {
            Ok(lp) => crate::outln!("{}: ok — {}", p.display(), summary(&lp)),
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
