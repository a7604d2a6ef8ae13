//! What one evaluation runs on and how: the recordings loaded once
//! ([`Recordings`], through [`crate::dataset::load`] on every core), the
//! validation asked for ([`Plan`]: holdout, k-fold, leave-one-out, grouped
//! folds; from the profile's `[evaluation]` and the command's
//! [`Overrides`]), and [`validate`], which runs it into a [`CvReport`].
//! With `[analysis] windows`, [`validate`] splits by recording and
//! classifies each test recording by its sub-windows' vote
//! ([`super::windows`]); [`validate_with_votes`] also hands back the votes.
//! Like the rest of `evaluate`, this never prints and knows no front end.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Serialize;

use super::cv::{self, CvReport};
use super::windows::{self as win, RecordingVote};
use super::{EvaluateError, Report};
use crate::analysis::FeatureExtractor;
use crate::classify::{KFallback, Model, TrainingExample};
use crate::dataset::Unusable;
use crate::dataset::{self, Entry, Keep, Options, Skipped};
use crate::folds::{Segment, Shared};
use crate::profile::{Analysis, Method, Profile, SplitMethod};

fn bad(m: impl std::fmt::Display) -> EvaluateError {
    EvaluateError::Input(m.to_string())
}

/// What the command line sets over the profile's `[evaluation]` (each
/// `None`/`false` leaves the profile's choice).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// k-fold with this many folds.
    pub folds: Option<usize>,
    /// Leave-one-out (leave-one-group-out with a group key).
    pub loo: bool,
    pub group_by: Option<String>,
    pub seed: Option<u64>,
    /// Worker threads (default: one per core).
    pub threads: Option<usize>,
}

/// The recordings of one evaluation, loaded once ([`dataset::load`]): their
/// feature vectors under the profile's analysis ([`Keep::Features`]), or,
/// for a sweep over an `[analysis]` key, the columns the analysis reads
/// ([`Keep::Samples`]) so features are extracted again per value.
#[derive(Debug, Clone)]
pub struct Recordings {
    pub scans: Vec<Entry>,
    /// Recordings left out (incomplete), in file-name order.
    pub skipped: Vec<Skipped>,
    /// The analysis the features were made under ([`Keep::Features`]).
    analysis: Analysis,
    keep: Keep,
}

impl Recordings {
    /// Read every recording under `paths` on `threads` threads, keeping
    /// what `keep` says. Incomplete recordings are listed, not kept; a
    /// malformed one is an error.
    pub fn load(
        paths: &[PathBuf],
        analysis: &Analysis,
        keep: Keep,
        threads: usize,
    ) -> Result<Recordings, EvaluateError> {
        let options = Options {
            keep,
            unusable: Unusable::Fail,
            threads,
        };
        // Finding no recordings is the user's to fix, as in every command.
        let files = dataset::find(paths).map_err(bad)?;
        Recordings::load_files(&files, analysis, options, &|| {})
    }

    /// The recordings in `files`, loaded as `options` say; `progress`
    /// hears each file.
    pub fn load_files(
        files: &[PathBuf],
        analysis: &Analysis,
        options: Options,
        progress: &(dyn Fn() + Sync),
    ) -> Result<Recordings, EvaluateError> {
        let loaded = dataset::load(files, analysis, options, progress)?;
        Ok(Recordings {
            scans: loaded.entries,
            skipped: loaded.skipped,
            analysis: analysis.clone(),
            keep: options.keep,
        })
    }

    /// The feature vectors under `analysis`: the kept ones when it is the
    /// analysis they were made under, else extracted again from the kept
    /// columns (whose channels must be `analysis`'s). With `[analysis]
    /// windows`, one per sub-window, a recording's consecutive (as
    /// [`dataset::load`] gives them).
    pub fn examples(&self, analysis: &Analysis) -> Result<Vec<TrainingExample>, EvaluateError> {
        if self.keep == Keep::Features {
            if *analysis != self.analysis {
                return Err(EvaluateError::FeaturesOnly);
            }
            return Ok(self.scans.iter().map(Entry::example).collect());
        }
        let mut fx = FeatureExtractor::try_new(analysis).map_err(bad)?;
        if analysis.windows.is_some() {
            let mut out = Vec::new();
            for s in &self.scans {
                for features in s.window_features_with(&mut fx)? {
                    out.push(TrainingExample {
                        file: s.file.clone(),
                        label: s.label.clone(),
                        features,
                    });
                }
            }
            return Ok(out);
        }
        self.scans
            .iter()
            .map(|s| {
                Ok(TrainingExample {
                    file: s.file.clone(),
                    label: s.label.clone(),
                    features: s.features_with(&mut fx)?,
                })
            })
            .collect()
    }

    /// The recordings held (each counted once, however many sub-windows it
    /// has) and the feature vectors (one per sub-window with `[analysis]
    /// windows` and [`Keep::Features`], else one per recording).
    pub fn counts(&self) -> (usize, usize) {
        let recordings = self
            .scans
            .iter()
            .enumerate()
            .filter(|(i, s)| *i == 0 || self.scans[i - 1].file != s.file)
            .count();
        (recordings, self.scans.len())
    }

    /// The segment each recording is of a longer one (`import --split`),
    /// by file: what every split asks to keep overlapping segments apart.
    pub fn segments(&self) -> Segments {
        self.scans
            .iter()
            .filter_map(|s| Segment::of(|k| s.meta_text(k)).map(|g| (s.file.clone(), g)))
            .collect()
    }

    /// Each scan's value of a metadata key; a scan without it is an error.
    pub fn groups(&self, key: &str) -> Result<Vec<String>, EvaluateError> {
        self.scans
            .iter()
            .map(|s| {
                s.meta_text(key).ok_or_else(|| {
                    bad(format!(
                        "{}: no metadata key `{key}` to group by (--group-by)",
                        s.file
                    ))
                })
            })
            .collect()
    }
}

/// Recordings that are segments of a longer one, by file.
pub type Segments = std::collections::HashMap<String, Segment>;

/// How the examples a validation deals are related beside their labels:
/// the group each belongs to (`group_by`: one value per example or per
/// recording), and which are segments of one recording ([`Segments`], by
/// file): a split keeps a group on one side and leaves the segments that
/// overlap a tested one out of its training.
#[derive(Debug, Clone, Copy, Default)]
pub struct Related<'a> {
    pub groups: Option<&'a [String]>,
    pub segments: Option<&'a Segments>,
}

impl<'a> Related<'a> {
    pub fn new(groups: Option<&'a [String]>, segments: &'a Segments) -> Related<'a> {
        Related {
            groups,
            segments: Some(segments),
        }
    }

    /// The segments of the items named by `files`, in their order.
    pub fn shared<'f>(&self, files: impl Iterator<Item = &'f str>) -> Shared {
        match self.segments {
            Some(s) if !s.is_empty() => Shared::new(files.map(|f| s.get(f).cloned()).collect()),
            _ => Shared::none(files.count()),
        }
    }
}

/// The validation the arguments and the profile ask for.
#[derive(Debug, Clone)]
pub struct Plan {
    pub method: SplitMethod,
    pub folds: usize,
    pub group_by: Option<String>,
    pub seed: u64,
    /// For a holdout: shuffle each class with this seed, else take the
    /// recordings in file-name order (as plain `evaluate` does).
    pub holdout_shuffle: Option<u64>,
    pub threads: usize,
    /// What the command line set, kept so a sweep of an `[evaluation]` key
    /// can plan each point again ([`Plan::for_profile`]).
    pub overrides: Overrides,
}

impl Plan {
    pub fn new(p: &Profile, args: &Overrides) -> Plan {
        let e = &p.evaluation;
        let method = if args.loo {
            SplitMethod::LeaveOneOut
        } else if args.folds.is_some()
            || (args.group_by.is_some() && e.method == SplitMethod::Holdout)
        {
            SplitMethod::KFold
        } else {
            e.method
        };
        Plan {
            method,
            folds: args.folds.or(e.folds).unwrap_or(10),
            group_by: args.group_by.clone().or_else(|| e.group_by.clone()),
            seed: args.seed.or(e.shuffle_seed).unwrap_or(0),
            holdout_shuffle: args.seed.or(e.shuffle_seed),
            threads: args
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            overrides: args.clone(),
        }
    }

    /// The same command line's plan under another profile (a sweep's
    /// point, whose `[evaluation]` may differ).
    pub fn for_profile(&self, p: &Profile) -> Plan {
        Plan {
            threads: self.threads,
            ..Plan::new(p, &self.overrides)
        }
    }

    /// The small-data fallback, a policy the caller asks for: when the
    /// profile's holdout split needs more scans of a texture than
    /// `examples` have (or k-fold more recordings than there are), evaluate
    /// by stratified 5-fold cross-validation (when every texture has at
    /// least 5 recordings) or else leave-one-out, ungrouped. Returns why,
    /// when it fell back; the plan is left as it is otherwise.
    pub fn fall_back(&mut self, p: &Profile, examples: &[TrainingExample]) -> Option<String> {
        let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
        // Recordings, not sub-windows: with `[analysis] windows` a
        // recording's examples are consecutive and share its file.
        for (i, e) in examples.iter().enumerate() {
            if i == 0 || examples[i - 1].file != e.file {
                *counts.entry(e.label.as_str()).or_default() += 1;
            }
        }
        let (label, fewest) =
            counts
                .iter()
                .fold(None, |b: Option<(&str, usize)>, (l, n)| match b {
                    Some((_, m)) if m <= *n => b,
                    _ => Some((l, *n)),
                })?;
        let recordings: usize = counts.values().sum();
        let e = &p.evaluation;
        let why = match self.method {
            SplitMethod::Holdout if fewest < e.holdout_needs() => format!(
                "the holdout split needs {} per texture ({}), {label} has {fewest}",
                crate::classify::scans(e.holdout_needs()),
                e.holdout_parts()
            ),
            SplitMethod::KFold if self.group_by.is_none() && self.folds > recordings => format!(
                "{}-fold cross-validation needs at least {}, there are {}",
                self.folds,
                crate::classify::plural(self.folds, "recording", "recordings"),
                recordings
            ),
            _ => return None,
        };
        self.group_by = None;
        let how = if fewest >= 5 {
            self.method = SplitMethod::KFold;
            self.folds = 5;
            "stratified 5-fold cross-validation"
        } else {
            self.method = SplitMethod::LeaveOneOut;
            "leave-one-out"
        };
        Some(format!("{why}: evaluating by {how} instead"))
    }

    pub fn describe(&self) -> String {
        let g = self
            .group_by
            .as_ref()
            .map_or(String::new(), |g| format!(", grouped by {g}"));
        match self.method {
            SplitMethod::Holdout => match self.holdout_shuffle {
                Some(s) => format!("holdout split (shuffled, seed {s})"),
                None => "holdout split (file-name order)".into(),
            },
            SplitMethod::KFold => format!(
                "{}-fold cross-validation{g}, seed {}",
                self.folds, self.seed
            ),
            SplitMethod::LeaveOneOut if self.group_by.is_some() => {
                format!("leave-one-group-out{g}")
            }
            SplitMethod::LeaveOneOut => "leave-one-out".into(),
        }
    }
}

/// A validation's report and, with `[analysis] windows`, each test
/// recording's sub-window votes (in test order). Its JSON is the
/// [`CvReport`]'s, plus `windows` when there are sub-windows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Validated {
    #[serde(flatten)]
    pub report: CvReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub windows: Option<Vec<RecordingVote>>,
}

/// Validate `profile`'s classifier on `examples` as `plan` says. With
/// `[analysis] windows` the examples are sub-windows ([`Recordings::examples`])
/// and `groups` holds one value per example or per recording: every split
/// is made over recordings and each test recording is classified by its
/// sub-windows' vote, as [`validate_with_votes`] does.
pub fn validate(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    related: Related,
    plan: &Plan,
) -> Result<CvReport, EvaluateError> {
    validate_with_votes(profile, examples, related, plan).map(|v| v.report)
}

/// At most this many value operations in a validation: feature-value
/// comparisons for k-NN (vectors² × features), multiply-adds of the fits
/// for ridge and LDA ([`validation_work`]). The classifier's limit.
pub const MAX_COMPARISONS: f64 = crate::classify::MAX_COMPARISONS;

/// How a validation splits the recordings: the models it fits and the
/// most recordings one of them trains on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fits {
    /// The recordings validated.
    pub recordings: usize,
    /// Models fitted: one for a holdout, one per fold, one per recording
    /// (or group) left out.
    pub fits: usize,
    /// The most recordings one model trains on.
    pub train: usize,
}

impl Fits {
    /// The fits `plan` makes over `per_label` recordings of each label:
    /// a holdout trains on `train_per_class` of each label once; k-fold
    /// on all but a fold, `folds` times (all but one recording with
    /// `group_by`, whose folds may be uneven); leave-one-out on all but
    /// one, once per recording (a bound on the groups).
    pub fn of(plan: &Plan, train_per_class: usize, per_label: &[usize]) -> Fits {
        let recordings: usize = per_label.iter().sum();
        let (fits, train) = match plan.method {
            SplitMethod::Holdout => (1, per_label.iter().map(|&n| n.min(train_per_class)).sum()),
            SplitMethod::KFold => {
                let folds = plan.folds.clamp(1, recordings.max(1));
                let train = if plan.group_by.is_some() {
                    recordings.saturating_sub(1)
                } else {
                    recordings - recordings / folds
                };
                (folds, train)
            }
            SplitMethod::LeaveOneOut => (recordings, recordings.saturating_sub(1)),
        };
        Fits {
            recordings,
            fits,
            train,
        }
    }

    /// Recordings of each label, in label order, as `of` counts them.
    pub fn per_label<'a>(labels: impl IntoIterator<Item = (&'a str, &'a str)>) -> Vec<usize> {
        let mut files: BTreeMap<&str, std::collections::BTreeSet<&str>> = BTreeMap::new();
        for (label, file) in labels {
            files.entry(label).or_default().insert(file);
        }
        files.values().map(|f| f.len()).collect()
    }
}

/// The value operations the limit counts in validating `method` on
/// `vectors` feature vectors of `features`, split as `fits` says. k-NN
/// compares every test vector with every training one: vectors² ×
/// features at most, over the whole validation. Ridge and LDA compare
/// nothing; they fit a model on each training part
/// ([`crate::classify::linear_fit_work`]) and score each test vector in
/// `p` per class: the largest fit is counted, which is never more than
/// k-NN's count for the same vectors, so nothing validated before this
/// count is refused by it.
pub fn validation_work(method: Method, vectors: usize, features: usize, fits: Fits) -> f64 {
    match method {
        Method::Knn => crate::classify::comparisons(vectors, vectors, features),
        Method::Ridge | Method::Lda => {
            crate::classify::linear_fit_work(training_vectors(vectors, fits), features)
        }
    }
}

/// The most vectors one fit trains on: `fits.train` recordings' share of
/// `vectors` (never more than all of them).
fn training_vectors(vectors: usize, fits: Fits) -> usize {
    (fits.train * vectors.div_ceil(fits.recordings.max(1))).min(vectors)
}

/// Refuses a validation of more than [`MAX_COMPARISONS`] value operations
/// ([`validation_work`]), before any is made.
pub fn check_validation(
    method: Method,
    vectors: usize,
    features: usize,
    fits: Fits,
) -> Result<(), EvaluateError> {
    let work = validation_work(method, vectors, features, fits);
    if work <= MAX_COMPARISONS {
        return Ok(());
    }
    let fewer = "use a longer windows.hop or a shorter windows.length (fewer sub-windows), fewer bins, or fewer recordings";
    Err(bad(match method {
        Method::Knn => format!(
            "validating {vectors} feature vectors of {features} features compares each with every other: {work:.1e} value comparisons, over the limit of {MAX_COMPARISONS:.0e} that keeps evaluate within seconds; {fewer} (at most about {} vectors of {features} features)",
            (MAX_COMPARISONS / features.max(1) as f64).sqrt() as usize
        ),
        Method::Ridge | Method::Lda => format!(
            "validating {} on {vectors} feature vectors of {features} features fits it {} on up to {} of them: about {work:.1e} multiply-adds a fit, over the limit of {MAX_COMPARISONS:.0e} that keeps evaluate within seconds; {fewer}",
            crate::profile::options::plain_word(&method),
            plural_times(fits.fits),
            training_vectors(vectors, fits)
        ),
    }))
}

/// "once", "8 times".
fn plural_times(n: usize) -> String {
    if n == 1 {
        "once".into()
    } else {
        format!("{n} times")
    }
}

/// [`validate`], with the sub-window votes of each test recording when the
/// profile cuts recordings into sub-windows.
pub fn validate_with_votes(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    related: Related,
    plan: &Plan,
) -> Result<Validated, EvaluateError> {
    super::check_two_labels(&examples)?;
    let per_label = Fits::per_label(examples.iter().map(|e| (e.label.as_str(), e.file.as_str())));
    check_validation(
        profile.classifier.method,
        examples.len(),
        profile.analysis.fitted_feature_count(),
        Fits::of(plan, profile.evaluation.train_per_class, &per_label),
    )?;
    if plan.method == SplitMethod::Holdout {
        return holdout(profile, examples, related, plan).map(|h| h.pooled(plan.seed));
    }
    if profile.analysis.windows.is_some() {
        return validate_windows(profile, examples, related, plan);
    }
    validate_plain(profile, examples, related, plan).map(|report| Validated {
        report,
        windows: None,
    })
}

/// The holdout split's one run, written once for every caller: per
/// class, the first `train_per_class` recordings (file-name order, or the
/// plan's shuffle) train and the next `test_per_class` test ([`super::split`]);
/// with `[analysis] windows` the split is made over recordings, the model
/// trained on every sub-window of the training ones and each test
/// recording classified by its sub-windows' vote. Its JSON is the
/// `evaluate --json` [`Report`] (plus `windows`, each test recording's
/// votes, with sub-windows).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Holdout {
    #[serde(flatten)]
    pub report: Report,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub windows: Option<Vec<RecordingVote>>,
    /// The k the model used (the profile's, or chosen: see `k_fallback`).
    #[serde(skip)]
    pub k: usize,
    #[serde(skip)]
    pub k_fallback: Option<KFallback>,
    /// What the model says of its k, when it is not the profile's.
    #[serde(skip)]
    pub k_notice: Option<String>,
    /// Training recordings left out: they overlap a tested one (segments
    /// of one recording).
    #[serde(skip_serializing_if = "is_zero")]
    pub left_out: usize,
    /// Every recording split, training ones first: labels and files.
    #[serde(skip)]
    split_labels: Vec<String>,
    #[serde(skip)]
    split_files: Vec<String>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Holdout {
    /// As a one-fold cross-validation's report (what sweeps and the
    /// validated forms show).
    fn pooled(self, seed: u64) -> Validated {
        let run = (self.report, self.k, self.k_fallback);
        let dealt = cv::Dealt {
            folds: vec![Vec::new()],
            purged: vec![(0..self.left_out).collect()],
            in_time: false,
        };
        Validated {
            report: cv::pool(
                self.split_labels,
                self.split_files,
                vec![run],
                &dealt,
                "holdout",
                seed,
            ),
            windows: self.windows,
        }
    }

    /// The report's text: Table 4.1, and what was left out of training.
    pub fn table(&self) -> String {
        let mut t = self.report.table();
        if self.left_out > 0 {
            t.push_str(&format!(
                "segments of one recording: left out of training {} that overlap a tested one \
                 (they share its samples)\n",
                crate::classify::plural(self.left_out, "segment", "segments")
            ));
        }
        t
    }
}

/// The indices of `train` (into `files`, training ones first, then
/// `tests` of them) that overlap a tested one: left out of a holdout's
/// training.
fn purged_of_holdout(related: Related, files: &[&str], train: usize) -> Vec<usize> {
    let shared = related.shared(files.iter().copied());
    let test: Vec<usize> = (train..files.len()).collect();
    shared.neighbours(&test)
}

/// Refuses a holdout whose training part, once the overlapping segments
/// are left out, holds nothing of a label it tests.
fn check_trainable<'a>(
    train: impl Iterator<Item = &'a str>,
    mut test: impl Iterator<Item = &'a str>,
) -> Result<(), EvaluateError> {
    let trained: std::collections::BTreeSet<&str> = train.collect();
    match test.find(|l| !trained.contains(l)) {
        None => Ok(()),
        Some(l) => Err(EvaluateError::Folds(format!(
            "the holdout's every {l:?} training recording overlaps one it tests (trials cut from \
             one recording share samples), so nothing of {l:?} is left to learn from: set \
             [evaluation] gap_per_class, import with a --split-hop of --split or more, or record more"
        ))),
    }
}

/// Run `profile`'s holdout split on `examples` (see [`Holdout`]).
pub fn holdout(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    related: Related,
    plan: &Plan,
) -> Result<Holdout, EvaluateError> {
    let mut eval = profile.evaluation.clone();
    eval.shuffle_seed = plan.holdout_shuffle;
    let train_model = |train: Vec<TrainingExample>| {
        Model::train_adapting_k(&profile.name, &profile.analysis, &profile.classifier, train)
    };
    let (report, windows, model, split_labels, split_files, left_out) =
        if profile.analysis.windows.is_some() {
            let recs = win::recordings_of(examples, None)?;
            let (mut train, test) = win::split_recordings(&recs, &eval)?;
            let files: Vec<&str> = train.iter().chain(&test).map(|r| r.file.as_str()).collect();
            let gone = purged_of_holdout(related, &files, train.len());
            let left_out = gone.len();
            for &i in gone.iter().rev() {
                train.remove(i);
            }
            check_trainable(
                train.iter().map(|r| r.label.as_str()),
                test.iter().map(|r| r.label.as_str()),
            )?;
            let model = train_model(win::window_examples(&train))?;
            let r = win::evaluate_recordings(&model, &test)?;
            let all = || train.iter().chain(&test);
            let labels = all().map(|r| r.label.clone()).collect();
            let files = all().map(|r| r.file.clone()).collect();
            (r.report, Some(r.windows), model, labels, files, left_out)
        } else {
            let mut split = super::split(examples, &eval)?;
            let files: Vec<&str> = split
                .train
                .iter()
                .chain(&split.test)
                .map(|e| e.file.as_str())
                .collect();
            let gone = purged_of_holdout(related, &files, split.train.len());
            let left_out = gone.len();
            for &i in gone.iter().rev() {
                split.train.remove(i);
            }
            check_trainable(
                split.train.iter().map(|e| e.label.as_str()),
                split.test.iter().map(|e| e.label.as_str()),
            )?;
            let all = || split.train.iter().chain(&split.test);
            let labels = all().map(|e| e.label.clone()).collect();
            let files = all().map(|e| e.file.clone()).collect();
            let model = train_model(split.train)?;
            let report = super::evaluate(&model, &split.test)?;
            (report, None, model, labels, files, left_out)
        };
    Ok(Holdout {
        report,
        windows,
        k: model.classifier.k,
        k_notice: model.k_notice(),
        k_fallback: model.k_fallback,
        left_out,
        split_labels,
        split_files,
    })
}

/// Every method over recordings, never over sub-windows: the splits of
/// [`win::split_recordings`] and [`win::recording_folds`], then
/// [`win::cross_validate_recordings`].
fn validate_windows(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    related: Related,
    plan: &Plan,
) -> Result<Validated, EvaluateError> {
    let recs = win::recordings_of(examples, related.groups)?;
    let shared = related.shared(recs.iter().map(|r| r.file.as_str()));
    let folds = win::recording_folds(&recs, &shared, plan.method, plan.folds, plan.seed)?;
    let r = win::cross_validate_recordings(
        &recs,
        &folds,
        &profile.name,
        &profile.analysis,
        &profile.classifier,
        &plan.describe(),
        plan.seed,
        plan.threads,
    )?;
    Ok(Validated {
        report: r.report,
        windows: Some(r.windows),
    })
}

fn validate_plain(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    related: Related,
    plan: &Plan,
) -> Result<CvReport, EvaluateError> {
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    let shared = related.shared(examples.iter().map(|e| e.file.as_str()));
    let folds = cv::deal(
        &labels,
        related.groups,
        &shared,
        plan.method,
        plan.folds,
        plan.seed,
    )?;
    cv::cross_validate(
        &examples,
        &folds,
        &profile.name,
        &profile.analysis,
        &profile.classifier,
        &plan.describe(),
        plan.seed,
        plan.threads,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(method: SplitMethod, folds: usize) -> Plan {
        Plan {
            method,
            folds,
            group_by: None,
            seed: 0,
            holdout_shuffle: None,
            threads: 1,
            overrides: Overrides::default(),
        }
    }

    /// The generated long IMU set with random kernels in half-second
    /// sub-windows: 5 labels of 30 recordings, 7 sub-windows each, 9996
    /// features. k-NN would compare 1.1e10 values; ridge and LDA under its
    /// 21 + 9 holdout fit once on 735 vectors, 5.4e9 multiply-adds.
    #[test]
    fn ridge_and_lda_are_counted_by_their_fits_and_k_nn_by_its_comparisons() {
        let (vectors, features) = (150 * 7, 9996);
        let holdout = Fits::of(&plan(SplitMethod::Holdout, 10), 21, &[30; 5]);
        assert_eq!(
            holdout,
            Fits {
                recordings: 150,
                fits: 1,
                train: 105
            }
        );
        let knn = check_validation(Method::Knn, vectors, features, holdout);
        assert!(
            knn.as_ref()
                .is_err_and(|e| e.to_string().contains("compares each with every other")),
            "{knn:?}"
        );
        for method in [Method::Ridge, Method::Lda] {
            let work = validation_work(method, vectors, features, holdout);
            assert_eq!(work, 735.0 * 9996.0 * 735.0);
            assert!(check_validation(method, vectors, features, holdout).is_ok());
        }
        // Leave-one-out fits 150 models on 149 recordings each: 1.09e10 a
        // fit, refused, saying so.
        let loo = Fits::of(&plan(SplitMethod::LeaveOneOut, 10), 21, &[30; 5]);
        assert_eq!((loo.fits, loo.train), (150, 149));
        let e = check_validation(Method::Ridge, vectors, features, loo).unwrap_err();
        assert!(
            e.to_string().contains("fits it 150 times on up to 1043"),
            "{e}"
        );
        // k-fold: all but a fold, once a fold: 945 vectors a fit, 8.9e9.
        let kfold = Fits::of(&plan(SplitMethod::KFold, 10), 21, &[30; 5]);
        assert_eq!((kfold.fits, kfold.train), (10, 135));
        assert!(check_validation(Method::Lda, vectors, features, kfold).is_ok());
        // Never more than k-NN's count, whatever the split.
        for fits in [holdout, loo, kfold] {
            for (v, p) in [(1050, 9996), (1050, 49), (7, 100_000), (20_000, 3)] {
                assert!(
                    validation_work(Method::Ridge, v, p, fits)
                        <= validation_work(Method::Knn, v, p, fits)
                );
            }
        }
        // Fewer features than vectors: the covariance, n·p², not n²·p.
        let narrow = validation_work(Method::Lda, 1050, 49, holdout);
        assert_eq!(narrow, 735.0 * 49.0 * 49.0);
        // Recordings of each label, counted once however many windows.
        let pairs = [("a", "1"), ("a", "1"), ("b", "2"), ("a", "3"), ("c", "4")];
        assert_eq!(Fits::per_label(pairs), vec![2, 1, 1]);
    }
}
