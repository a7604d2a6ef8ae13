//! `hapticlab classify`: recordings named by a trained model, one line (or
//! a JSON row) each, with the votes and the nearest neighbour. The answer
//! is the engine's [`Predictor`]'s: a recording the model was trained on
//! is predicted with itself left out, as the console's Predict does.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::classify::Model;
use crate::dataset::DatasetError;
use crate::predictor::{Answer, Predictor};
use crate::recording;
use crate::support::{
    Failure, ProfileArg, bad, find_recordings, load_profile, runtime, warn_skipped,
};

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
    let predictor = Predictor::new(&model);
    let mut ex = predictor.extractor();
    let files = find_recordings(files)?;
    let mut rows = Vec::new();
    for f in &files {
        let rec = match recording::read(f) {
            Ok(rec) => rec,
            // Found in a folder (one named is refused by `find`): passed over.
            Err(recording::RecordingError::Io { source, .. })
                if crate::io::not_regular(&source) =>
            {
                warn_skipped(&[crate::dataset::Skipped::Unusable {
                    file: f.display().to_string(),
                    reason: source.to_string(),
                    unreadable: true,
                }]);
                continue;
            }
            Err(e) => return Err(DatasetError::from(e).into()),
        };
        let answer = match predictor.answer_recording(&rec, f, &mut ex) {
            Ok(a) => a,
            // Left out of a model that then lacks its texture: said, and
            // the other recordings go on.
            Err(e) if e.is_unanswerable() => {
                if !json {
                    crate::outln!("{}: no prediction: {e}", f.display());
                }
                rows.push(serde_json::json!({
                    "file": f.display().to_string(),
                    "label": rec.label(),
                    "predicted": null,
                    "left_out": true,
                    "reason": e.to_string(),
                }));
                continue;
            }
            Err(e) if e.is_bad_input() => return Err(bad(e)),
            Err(e) => return Err(runtime(e)),
        };
        if let Some(why) = &answer.incomplete {
            crate::errln!(
                "warning: {}: incomplete scan: {why}; classified anyway",
                f.display()
            );
        }
        if !json {
            crate::outln!("{}", line(f, rec.label(), &answer));
        }
        rows.push(row(f, rec.label(), &answer));
    }
    if json {
        crate::outln!("{}", serde_json::Value::Array(rows));
    }
    Ok(())
}

/// One recording's line: the prediction, right or wrong against its
/// label, and the votes (of the neighbours, or of the sub-windows).
fn line(f: &Path, label: Option<&str>, a: &Answer) -> String {
    let p = &a.prediction;
    let truth = label.map_or(String::new(), |l| {
        format!(
            " (recorded as {l}{}{})",
            if l == p.label { ", right" } else { ", WRONG" },
            if a.left_out {
                "; left out of the model"
            } else {
                ""
            }
        )
    });
    let votes: Vec<String> = p.votes.iter().map(|(l, v)| format!("{l}:{v}")).collect();
    match &a.windows {
        Some(w) => format!(
            "{}: {}{} — {} of {} windows, window votes {}",
            f.display(),
            p.label,
            truth,
            w.tally[0].windows,
            w.windows.len(),
            votes.join(" ")
        ),
        // A ridge or an LDA has no neighbours: its vote is the best score.
        None => format!(
            "{}: {}{} — votes {}{}",
            f.display(),
            p.label,
            truth,
            votes.join(" "),
            p.neighbours
                .first()
                .map_or(String::new(), |n| format!(", nearest {:.3e}", n.distance))
        ),
    }
}

/// One recording's JSON row; a vote over sub-windows adds the tally and
/// each sub-window's vote.
fn row(f: &Path, label: Option<&str>, a: &Answer) -> serde_json::Value {
    let p = &a.prediction;
    let mut row = serde_json::json!({
        "file": f.display().to_string(),
        "label": label,
        "predicted": p.label,
        "votes": p.votes,
    });
    let o = row.as_object_mut().expect("an object");
    match &a.windows {
        Some(w) => {
            o.insert("tally".into(), serde_json::json!(w.tally));
            o.insert("windows".into(), serde_json::json!(w.windows));
        }
        None => {
            o.insert("neighbours".into(), serde_json::json!(p.neighbours));
        }
    }
    if a.left_out {
        o.insert("left_out".into(), true.into());
    }
    row
}
