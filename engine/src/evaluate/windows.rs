//! Evaluation with sub-windows (`[analysis] windows`): every method splits
//! by recording, never by window, and a test recording is classified by
//! the vote of its sub-windows ([`Model::classify_windows`]).
//!
//! The splits are made over recordings with the same functions as without
//! windows ([`super::split`] for a holdout, [`super::cv::make_folds`] for
//! k-fold, leave-one-out and grouped folds), one entry per recording, so a
//! seed gives the same recordings on each side as it would with one
//! feature vector per recording. Only then are the training recordings
//! expanded into one example per sub-window ([`window_examples`]). Like
//! the rest of `evaluate`, this never reads files and never prints.

use serde::Serialize;

use super::cv::{CvReport, Dealt, Folds, deal, fold_runs, pool};
use super::{EvaluateError, PredictionRow, Report, count};
use crate::classify::{Model, RecordingPrediction, TrainingExample};
use crate::dataset::Entry;
use crate::folds::Shared;
use crate::profile::{Analysis, Classifier, Evaluation, SplitMethod};

/// One recording with the feature vectors of its sub-windows.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowedRecording {
    pub file: String,
    pub label: String,
    /// The `group_by` metadata value, when grouping.
    pub group: Option<String>,
    /// One feature vector per sub-window, in window order.
    pub windows: Vec<Vec<f64>>,
}

/// The recordings of [`crate::dataset::load`]'s entries (one per sub-window,
/// consecutive per file, as it gives them), in the same order, each with
/// its `group_by` value when one is named (an entry without it: `None`).
pub fn recordings(entries: &[Entry], group_by: Option<&str>) -> Vec<WindowedRecording> {
    let mut out: Vec<WindowedRecording> = Vec::new();
    for e in entries {
        match out.last_mut() {
            Some(r) if r.file == e.file && e.window.is_some_and(|w| w > 0) => {
                r.windows.push(e.features.clone());
            }
            _ => out.push(WindowedRecording {
                file: e.file.clone(),
                label: e.label.clone(),
                group: group_by.and_then(|k| e.meta_text(k)),
                windows: vec![e.features.clone()],
            }),
        }
    }
    out
}

/// The recordings of examples as [`crate::dataset`] gives them under
/// `[analysis] windows` (one per sub-window, a recording's consecutive and
/// named by its file), in the same order. `groups`, when given, holds the
/// `group_by` value of each example or of each recording; a recording's
/// sub-windows share their recording's value. Any other count of groups is
/// an error.
pub fn recordings_of(
    examples: Vec<TrainingExample>,
    groups: Option<&[String]>,
) -> Result<Vec<WindowedRecording>, EvaluateError> {
    let n_examples = examples.len();
    let mut out: Vec<WindowedRecording> = Vec::new();
    let mut first_example = Vec::new();
    for (i, e) in examples.into_iter().enumerate() {
        match out.last_mut() {
            Some(r) if r.file == e.file => r.windows.push(e.features),
            _ => {
                first_example.push(i);
                out.push(WindowedRecording {
                    file: e.file,
                    label: e.label,
                    group: None,
                    windows: vec![e.features],
                });
            }
        }
    }
    if let Some(g) = groups {
        let pick: Vec<usize> = if g.len() == n_examples {
            first_example
        } else if g.len() == out.len() {
            (0..out.len()).collect()
        } else {
            return Err(EvaluateError::Input(format!(
                "{} group values for {} recordings ({} windows)",
                g.len(),
                out.len(),
                n_examples
            )));
        };
        for (r, i) in out.iter_mut().zip(pick) {
            r.group = Some(g[i].clone());
        }
    }
    Ok(out)
}

/// One training example per sub-window of each recording, recording by
/// recording, each named by its recording's file.
pub fn window_examples<'a>(
    recs: impl IntoIterator<Item = &'a WindowedRecording>,
) -> Vec<TrainingExample> {
    recs.into_iter()
        .flat_map(|r| {
            r.windows.iter().map(|f| TrainingExample {
                file: r.file.clone(),
                label: r.label.clone(),
                features: f.clone(),
            })
        })
        .collect()
}

/// A holdout split of recordings (whole recordings on each side), made by
/// [`super::split`] over one entry per recording: the same recordings it
/// would pick without windows. Files must be distinct.
pub fn split_recordings(
    recs: &[WindowedRecording],
    eval: &Evaluation,
) -> Result<(Vec<WindowedRecording>, Vec<WindowedRecording>), EvaluateError> {
    let proxies: Vec<TrainingExample> = recs
        .iter()
        .map(|r| TrainingExample {
            file: r.file.clone(),
            label: r.label.clone(),
            features: Vec::new(),
        })
        .collect();
    let split = super::split(proxies, eval)?;
    let find = |p: &TrainingExample| {
        recs.iter()
            .find(|r| r.file == p.file)
            .cloned()
            .expect("a proxy names one of the recordings")
    };
    Ok((
        split.train.iter().map(find).collect(),
        split.test.iter().map(find).collect(),
    ))
}

/// Folds over recordings (indices into `recs`) for k-fold, leave-one-out
/// or, when every recording has a group, grouped folds:
/// [`make_folds`] with one entry per recording.
pub fn recording_folds(
    recs: &[WindowedRecording],
    shared: &Shared,
    method: SplitMethod,
    folds: usize,
    seed: u64,
) -> Result<Dealt, EvaluateError> {
    let labels: Vec<&str> = recs.iter().map(|r| r.label.as_str()).collect();
    let groups: Option<Vec<String>> = recs.iter().map(|r| r.group.clone()).collect();
    let grouped = recs.first().is_some_and(|r| r.group.is_some());
    deal(
        &labels,
        if grouped { groups.as_deref() } else { None },
        shared,
        method,
        folds,
        seed,
    )
}

/// Recording folds turned into folds over [`window_examples`] of all
/// `recs` (in order): each recording's sub-windows go where it went.
pub fn window_folds(recording_folds: &Folds, recs: &[WindowedRecording]) -> Folds {
    let mut first = Vec::with_capacity(recs.len());
    let mut at = 0;
    for r in recs {
        first.push(at);
        at += r.windows.len();
    }
    recording_folds
        .iter()
        .map(|fold| {
            fold.iter()
                .flat_map(|&i| first[i]..first[i] + recs[i].windows.len())
                .collect()
        })
        .collect()
}

/// A recording's prediction row with the vote of its sub-windows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingVote {
    pub file: String,
    pub label: String,
    #[serde(flatten)]
    pub prediction: RecordingPrediction,
}

/// [`Report`] over recordings classified by their sub-windows' vote: its
/// JSON keeps every key of `evaluate --json` (`predictions[].votes` are the
/// per-class sub-window counts) and adds `windows`, per test recording in
/// test order, each sub-window's outcome and the tally.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowReport {
    #[serde(flatten)]
    pub report: Report,
    pub windows: Vec<RecordingVote>,
}

/// Classify each test recording by its sub-windows' vote and count.
pub fn evaluate_recordings(
    model: &Model,
    test: &[WindowedRecording],
) -> Result<WindowReport, EvaluateError> {
    if test.is_empty() {
        return Err(EvaluateError::NoTest);
    }
    let mut predictions = Vec::with_capacity(test.len());
    let mut windows = Vec::with_capacity(test.len());
    for r in test {
        let p = model.classify_windows(&r.windows)?;
        predictions.push(PredictionRow {
            file: r.file.clone(),
            label: r.label.clone(),
            predicted: p.label.clone(),
            votes: p
                .tally
                .iter()
                .map(|t| (t.label.clone(), t.windows))
                .collect(),
        });
        windows.push(RecordingVote {
            file: r.file.clone(),
            label: r.label.clone(),
            prediction: p,
        });
    }
    // One training file per recording, not per sub-window.
    let mut train: Vec<String> = model.examples.iter().map(|e| e.file.clone()).collect();
    train.dedup();
    Ok(WindowReport {
        report: count(&model.labels, train, predictions),
        windows,
    })
}

/// [`CvReport`] with each test recording's sub-window votes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowCvReport {
    #[serde(flatten)]
    pub report: CvReport,
    pub windows: Vec<RecordingVote>,
}

/// Cross-validation over recordings: for each fold of [`recording_folds`],
/// train on every sub-window of the other recordings and classify the
/// fold's recordings by vote; the counts are pooled as
/// [`super::cv::cross_validate`] pools them. The folds run on up to
/// `threads` threads; the result does not depend on how many.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate_recordings(
    recs: &[WindowedRecording],
    folds: &Dealt,
    profile_name: &str,
    analysis: &Analysis,
    classifier: &Classifier,
    method: &str,
    seed: u64,
    threads: usize,
) -> Result<WindowCvReport, EvaluateError> {
    let runs = fold_runs(
        recs,
        folds,
        (profile_name, analysis, classifier),
        threads,
        |train| window_examples(train),
        evaluate_recordings,
    )?;
    let mut windows = Vec::new();
    let runs = runs
        .into_iter()
        .map(|(wr, k, k_fallback)| {
            windows.extend(wr.windows);
            (wr.report, k, k_fallback)
        })
        .collect();
    let labels: Vec<String> = recs.iter().map(|r| r.label.clone()).collect();
    let train = recs.iter().map(|r| r.file.clone()).collect();
    Ok(WindowCvReport {
        report: pool(labels, train, runs, folds, method, seed),
        windows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classify::{WindowVote, vote};
    use proptest::prelude::*;
    use std::collections::BTreeSet;

    fn wv(window: usize, label: &str, votes: &[(&str, usize)]) -> WindowVote {
        WindowVote {
            window,
            label: label.into(),
            votes: votes.iter().map(|(l, n)| (l.to_string(), *n)).collect(),
        }
    }

    #[test]
    fn the_vote_is_the_majority_then_neighbour_votes_then_the_first_label() {
        let p = vote(vec![
            wv(0, "B", &[("B", 3)]),
            wv(1, "A", &[("A", 2), ("B", 1)]),
            wv(2, "B", &[("B", 2), ("A", 1)]),
        ])
        .unwrap();
        assert_eq!(p.label, "B");
        assert_eq!((p.tally[0].windows, p.tally[0].neighbour_votes), (2, 6));
        assert!((p.agreement() - 2.0 / 3.0).abs() < 1e-12);
        // Two windows each: A has more neighbour votes in all.
        let p = vote(vec![
            wv(0, "B", &[("B", 2), ("A", 1)]),
            wv(1, "A", &[("A", 3)]),
        ])
        .unwrap();
        assert_eq!(p.label, "A");
        // A full tie: the first label in sorted order.
        let p = vote(vec![
            wv(0, "S3", &[("S3", 2), ("S2", 1)]),
            wv(1, "S2", &[("S2", 2), ("S3", 1)]),
        ])
        .unwrap();
        assert_eq!(p.label, "S2");
        assert!(vote(Vec::new()).is_none());
    }

    fn rec(i: usize, label: usize, windows: usize, group: Option<usize>) -> WindowedRecording {
        WindowedRecording {
            file: format!("L{label}/r{i:03}.csv"),
            label: format!("L{label}"),
            group: group.map(|g| format!("g{g}")),
            windows: (0..windows).map(|j| vec![i as f64, j as f64]).collect(),
        }
    }

    /// Recordings: 2..5 classes with 2..7 recordings each of 1..5 windows,
    /// optionally each in one of 2..4 groups.
    fn dataset() -> impl Strategy<Value = Vec<WindowedRecording>> {
        (
            prop::collection::vec(prop::collection::vec(1usize..5, 2..7), 2..5),
            prop::option::of(2usize..4),
            any::<u64>(),
        )
            .prop_map(|(classes, groups, salt)| {
                let mut out = Vec::new();
                for (c, recs) in classes.iter().enumerate() {
                    for &w in recs {
                        let i = out.len();
                        let g = groups.map(|g| (i + salt as usize % 7) % g);
                        out.push(rec(i, c, w, g));
                    }
                }
                out
            })
    }

    /// The files with windows on each side of a window fold.
    fn sides(examples: &[TrainingExample], fold: &[usize]) -> (BTreeSet<String>, BTreeSet<String>) {
        let test: BTreeSet<usize> = fold.iter().copied().collect();
        let mut a = BTreeSet::new();
        let mut b = BTreeSet::new();
        for (i, e) in examples.iter().enumerate() {
            if test.contains(&i) {
                b.insert(e.file.clone());
            } else {
                a.insert(e.file.clone());
            }
        }
        (a, b)
    }

    proptest! {
        #[test]
        fn no_recording_has_windows_on_both_sides_of_any_split(
            recs in dataset(),
            method in 0usize..3,
            folds in 2usize..5,
            seed in any::<u64>(),
        ) {
            let examples = window_examples(&recs);
            prop_assert_eq!(examples.len(), recs.iter().map(|r| r.windows.len()).sum::<usize>());
            if method == 0 {
                let eval = Evaluation {
                    train_per_class: 1,
                    test_per_class: 1,
                    shuffle_seed: Some(seed),
                    ..Evaluation::default()
                };
                let (train, test) = split_recordings(&recs, &eval).unwrap();
                let tr: BTreeSet<String> = window_examples(&train).into_iter().map(|e| e.file).collect();
                for r in &test {
                    prop_assert!(!tr.contains(&r.file), "{} on both sides", r.file);
                }
                return Ok(());
            }
            let m = if method == 1 { SplitMethod::KFold } else { SplitMethod::LeaveOneOut };
            let Ok(rf) = recording_folds(&recs, &Shared::none(recs.len()), m, folds, seed) else {
                // Too few recordings or groups for these folds: refused, not leaked.
                return Ok(());
            };
            let rf = rf.folds;
            let wf = window_folds(&rf, &recs);
            let mut tested = vec![0usize; examples.len()];
            for (fold, rfold) in wf.iter().zip(&rf) {
                let (train, test) = sides(&examples, fold);
                prop_assert!(train.is_disjoint(&test), "{:?}", train.intersection(&test).collect::<Vec<_>>());
                // Every window of a tested recording is tested with it.
                let want: usize = rfold.iter().map(|&i| recs[i].windows.len()).sum();
                prop_assert_eq!(fold.len(), want);
                for &i in fold {
                    tested[i] += 1;
                }
                // A group never sits on both sides either.
                if recs[0].group.is_some() {
                    let g = |files: &BTreeSet<String>| -> BTreeSet<Option<String>> {
                        recs.iter().filter(|r| files.contains(&r.file)).map(|r| r.group.clone()).collect()
                    };
                    prop_assert!(g(&train).is_disjoint(&g(&test)));
                }
            }
            prop_assert!(tested.iter().all(|&t| t == 1), "{:?}", tested);
        }
    }
}

#[cfg(test)]
mod thesis_tests {
    use super::*;
    use crate::dataset;
    use crate::profile::{LoadedProfile, Windows};
    use std::path::Path;

    /// The thesis's recordings with three sub-windows along each stroke.
    fn thesis_windows() -> (crate::profile::Profile, Vec<WindowedRecording>) {
        let mut profile = LoadedProfile::thesis().profile;
        profile.analysis.bins = [1, 24];
        profile.analysis.windows = Some(Windows {
            length: 0.0147,
            hop: 0.0075,
        });
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
        let files = dataset::find(&[dir]).unwrap();
        let loaded = dataset::load(
            &files,
            &profile.analysis,
            dataset::Options::default(),
            &|| {},
        )
        .unwrap();
        let recs = recordings(&loaded.entries, None);
        assert_eq!(recs.len(), files.len());
        assert!(recs.iter().all(|r| r.windows.len() == 3));
        (profile, recs)
    }

    /// A sweep over an `[analysis]` key keeps the samples and extracts
    /// again: with windows, the same sub-window examples as loading the
    /// features, and `validate` votes over them by recording.
    #[test]
    fn kept_samples_give_the_loaded_sub_windows_and_validate_votes_by_recording() {
        use crate::evaluate::plan::{Overrides, Plan, Recordings, validate_with_votes};
        let (profile, recs) = thesis_windows();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
        let a = &profile.analysis;
        let samples =
            Recordings::load(std::slice::from_ref(&dir), a, dataset::Keep::Samples, 2).unwrap();
        let features = Recordings::load(&[dir], a, dataset::Keep::Features, 2).unwrap();
        assert_eq!(samples.counts(), (recs.len(), recs.len()));
        assert_eq!(features.counts(), (recs.len(), 3 * recs.len()));
        let from_samples = samples.examples(a).unwrap();
        assert_eq!(from_samples, features.examples(a).unwrap());
        assert_eq!(from_samples, window_examples(&recs));
        // Groups given per recording or per sub-window: the same folds.
        let plan = Plan::new(
            &profile,
            &Overrides {
                folds: Some(4),
                group_by: Some("seed".into()),
                ..Overrides::default()
            },
        );
        let related = |g| crate::evaluate::plan::Related {
            groups: Some(g),
            segments: None,
        };
        let per_rec = samples.groups("seed").unwrap();
        let per_window = features.groups("seed").unwrap();
        let one =
            validate_with_votes(&profile, from_samples.clone(), related(&per_rec), &plan).unwrap();
        let two = validate_with_votes(&profile, from_samples.clone(), related(&per_window), &plan)
            .unwrap();
        assert_eq!(one, two);
        assert_eq!(one.report.report.tested(), recs.len());
        assert_eq!(one.windows.as_ref().map(Vec::len), Some(recs.len()));
        assert!(
            validate_with_votes(&profile, from_samples, related(&per_rec[1..]), &plan).is_err()
        );
    }

    #[test]
    fn thesis_holdout_and_folds_by_recording_with_three_windows_per_stroke() {
        let (profile, recs) = thesis_windows();
        let (train, test) = split_recordings(&recs, &profile.evaluation).unwrap();
        let model = Model::train(
            &profile.name,
            &profile.analysis,
            &profile.classifier,
            window_examples(&train),
        )
        .unwrap();
        assert_eq!(model.examples.len(), 3 * train.len());
        let r = evaluate_recordings(&model, &test).unwrap();
        assert_eq!(r.report.tested(), test.len());
        assert_eq!(r.windows.len(), test.len());
        assert!(r.windows.iter().all(|w| w.prediction.windows.len() == 3));
        assert!(r.report.accuracy >= 0.9, "{}", r.report.table());
        // The recordings a seed sends to test are those it would without
        // windows.
        let plain: Vec<TrainingExample> = recs
            .iter()
            .map(|r| TrainingExample {
                file: r.file.clone(),
                label: r.label.clone(),
                features: vec![0.0],
            })
            .collect();
        let s = super::super::split(plain, &profile.evaluation).unwrap();
        let want: Vec<&str> = s.test.iter().map(|e| e.file.as_str()).collect();
        let got: Vec<&str> = test.iter().map(|r| r.file.as_str()).collect();
        assert_eq!(got, want);

        let folds =
            recording_folds(&recs, &Shared::none(recs.len()), SplitMethod::KFold, 5, 7).unwrap();
        let one = cross_validate_recordings(
            &recs,
            &folds,
            &profile.name,
            &profile.analysis,
            &profile.classifier,
            "5-fold",
            7,
            1,
        )
        .unwrap();
        let two = cross_validate_recordings(
            &recs,
            &folds,
            &profile.name,
            &profile.analysis,
            &profile.classifier,
            "5-fold",
            7,
            2,
        )
        .unwrap();
        assert_eq!(one, two);
        assert_eq!(one.report.test.len(), recs.len());
        assert!(one.report.accuracy >= 0.9, "{}", one.report.accuracy);
        let json = serde_json::to_value(&one).unwrap();
        for key in [
            "labels",
            "confusion",
            "accuracy",
            "predictions",
            "folds",
            "windows",
        ] {
            assert!(json.get(key).is_some(), "{key}");
        }
        assert_eq!(json["windows"][0]["windows"].as_array().unwrap().len(), 3);
    }
}
