//! `hapticlab classify`: recordings named by a trained model, one line (or
//! a JSON row) each, with the votes and the nearest neighbour.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::analysis::FeatureExtractor;
use crate::classify::Model;
use crate::dataset::{self, DatasetError};
use crate::recording;
use crate::support::{Failure, ProfileArg, bad, find_recordings, load_profile, warn_skipped};

#[derive(Debug, Args)]
pub struct ClassifyArgs {
    /// The profile whose analysis settings the model must have been trained under.
    #[command(flatten)]
    pub profile: ProfileArg,
    /// The trained model (JSON), as `hapticlab train --out` or the console's `T` writes it.
    #[arg(long, value_name = "MODEL")]
    pub model: PathBuf,
    /// Recordings to classify (*.csv, *.csv.gz), or folders of them.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Print JSON for scripts.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: ClassifyArgs) -> Result<(), Failure> {
    classify(&a.profile, &a.model, &a.files, a.json)
}

fn classify(
    profile: &ProfileArg,
    model_path: &Path,
    files: &[PathBuf],
    json: bool,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let model = Model::load(model_path).map_err(bad)?;
    // The model's stored features were made under its analysis settings;
    // a model whose settings differ from the profile's is refused.
    model
        .check_settings(&lp.profile.analysis)
        .map_err(|e| bad(format!("{}: {e}", model_path.display())))?;
    // Other classifier settings still classify, but never silently.
    if let Err(e) = model.check_classifier(&lp.profile.classifier) {
        crate::errln!(
            "warning: {}: {e}; classifying with the model's settings",
            model_path.display()
        );
    }
    if let Some(note) = model.k_notice() {
        crate::errln!("note: {}: {note}", model_path.display());
    }
    let mut ex = FeatureExtractor::new(&model.analysis);
    let files = find_recordings(files)?;
    let mut rows = Vec::new();
    for f in &files {
        let rec = match recording::read(f) {
            Ok(rec) => rec,
            // Found in a folder (one named is refused by `find`): passed over.
            Err(recording::RecordingError::Io { source, .. })
                if crate::recording::files::not_regular(&source) =>
            {
                warn_skipped(&[dataset::Skipped::Unusable {
                    file: f.display().to_string(),
                    reason: source.to_string(),
                    unreadable: true,
                }]);
                continue;
            }
            Err(e) => return Err(DatasetError::from(e).into()),
        };
        // An incomplete scan is classified when its samples cover the
        // analysis; when they do not, one error says both things.
        let incomplete = (!rec.is_complete()).then(|| {
            format!(
                "incomplete scan: {}",
                rec.aborted().unwrap_or("no end marker")
            )
        });
        let in_context = |e: Failure| match (&incomplete, e) {
            (Some(why), Failure::BadInput(m)) => bad(format!("{m} ({why})")),
            (_, e) => e,
        };
        let warn_incomplete = || {
            if let Some(why) = &incomplete {
                crate::errln!("warning: {}: {why}; classified anyway", f.display());
            }
        };
        if model.analysis.windows.is_some() {
            rows.push(classify_by_windows(&model, &rec, f, &mut ex, json).map_err(in_context)?);
            warn_incomplete();
            continue;
        }
        let feats = dataset::features_of(&rec, f, &mut ex)
            .map_err(Failure::from)
            .map_err(in_context)?;
        warn_incomplete();
        let p = model
            .classify(&feats)
            .map_err(|e| bad(format!("{}: {e}", f.display())))?;
        if !json {
            let votes: Vec<String> = p.votes.iter().map(|(l, v)| format!("{l}:{v}")).collect();
            let truth = rec.label().map_or(String::new(), |l| {
                format!(
                    " (recorded as {l}{})",
                    if l == p.label { ", right" } else { ", WRONG" }
                )
            });
            crate::outln!(
                "{}: {}{} — votes {}, nearest {:.3e}",
                f.display(),
                p.label,
                truth,
                votes.join(" "),
                p.neighbours.first().map_or(f64::NAN, |n| n.distance)
            );
        }
        rows.push(serde_json::json!({
            "file": f.display().to_string(),
            "label": rec.label(),
            "predicted": p.label,
            "votes": p.votes,
            "neighbours": p.neighbours,
        }));
    }
    if json {
        crate::outln!("{}", serde_json::Value::Array(rows));
    }
    Ok(())
}

/// `classify` of one recording by its sub-windows' vote: the line (unless
/// `json`) and the JSON row, which adds the tally and each sub-window's vote.
fn classify_by_windows(
    model: &Model,
    rec: &recording::Recording,
    f: &Path,
    ex: &mut FeatureExtractor,
    json: bool,
) -> Result<serde_json::Value, Failure> {
    let windows = dataset::window_features_of(rec, f, ex)?;
    let p = model
        .classify_windows(&windows)
        .map_err(|e| bad(format!("{}: {e}", f.display())))?;
    let votes: Vec<(String, usize)> = p
        .tally
        .iter()
        .map(|t| (t.label.clone(), t.windows))
        .collect();
    if !json {
        let shown: Vec<String> = votes.iter().map(|(l, v)| format!("{l}:{v}")).collect();
        let truth = rec.label().map_or(String::new(), |l| {
            format!(
                " (recorded as {l}{})",
                if l == p.label { ", right" } else { ", WRONG" }
            )
        });
        crate::outln!(
            "{}: {}{} — {} of {} windows, window votes {}",
            f.display(),
            p.label,
            truth,
            p.tally[0].windows,
            p.windows.len(),
            shown.join(" ")
        );
    }
    Ok(serde_json::json!({
        "file": f.display().to_string(),
        "label": rec.label(),
        "predicted": p.label,
        "votes": votes,
        "tally": p.tally,
        "windows": p.windows,
    }))
}
