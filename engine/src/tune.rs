//! `tune`: an honest search over the analysis and classifier options by
//! nested validation, as scikit-learn's user guide describes it.
//!
//! The outer split is the profile's `[evaluation]` (the plan `evaluate`
//! makes): a holdout's test part, or each fold of k-fold and leave-one-out.
//! Inside each outer training part, every setting of the search
//! ([`space::space`], sampled by [`Options::budget`]) is scored by 5-fold
//! cross-validation over that part only: recordings, never sub-windows,
//! are dealt into the inner folds, as the outer split deals them
//! ([`InnerSplit`]): forward in time under a time split, whole groups with
//! `group_by`, blocks in time over overlapping trials, stratified and
//! shuffled otherwise; the score is the mean of the folds' accuracies. The
//! best setting (equal accuracies to the wider margin, then the larger
//! share of true votes, measured in the same folds, then the simplest,
//! [`space::Setting::simplicity`]) is then trained on the whole outer
//! training part and tested once on its outer test part; the outer
//! accuracy, pooled over the outer test parts, is the estimate reported,
//! never an inner score. For k-fold and leave-one-out the setting written
//! to the profile is chosen by one more search over every recording
//! (scikit-learn's refit): the outer estimate is of that procedure.
//!
//! Speed: the recordings are read once; each grid (window, spacing,
//! sub-windows) two or more feature settings share is resampled once for
//! them all; feature vectors are made once per distinct feature setting and
//! serve every outer and inner fold and every k, metric, vote weighting and
//! standardisation ([`score`]). The budget
//! samples feature settings (seeded), each scored with every classifier
//! setting, since those cost almost nothing once the features exist.
//! Under a time split the random kernels are fitted once per part, on the
//! trials every forward inner fold trains on, and each recording is
//! transformed once for all the folds.
//! Before any work, the settings `evaluate` would refuse on these
//! recordings and the kernel settings estimated over
//! [`Options::max_minutes`] of CPU are left out, and the report says so
//! ([`cost`]).
//! Like the rest of the engine this never prints: progress goes to a
//! callback.

pub mod cost;
pub mod parts;
pub mod score;
pub mod space;
#[cfg(test)]
mod tests;
pub mod text;

pub use parts::{InnerSplit, inner_parts, outer_parts};

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use thiserror::Error;

use crate::classify::{ClassifyError, Model, TrainingExample, plural};
use crate::dataset::{DatasetError, Entry};
use crate::evaluate::plan::{Fits, Overrides, Plan};
use crate::evaluate::{EvaluateError, PredictionRow, Report, count};
use crate::profile::options::same_grid;
use crate::profile::tuned::{TunedOn, fingerprint};
use crate::profile::{Analysis, FeatureFamily, Method, Metric, Profile, SplitMethod};
use score::{
    Fold, Pairwise, RESAMPLED_MOST, Resampled, Voting, extract, extract_resampled, par_map,
    resample, resampled_points, score_fold,
};
use space::{Described, Setting, grid};

/// Inner folds (fewer when the training part has fewer recordings or groups).
pub const INNER_FOLDS: usize = 5;

/// Why a search cannot run.
#[derive(Debug, Error)]
pub enum TuneError {
    /// A plan that cannot test, or a setting the data does not fit: the
    /// user's to change (exit code 2).
    #[error("{0}")]
    Plan(String),
    #[error(transparent)]
    Evaluate(#[from] EvaluateError),
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    #[error(transparent)]
    Classify(#[from] ClassifyError),
}

impl TuneError {
    pub fn is_bad_input(&self) -> bool {
        match self {
            TuneError::Evaluate(e) => e.is_bad_input(),
            TuneError::Dataset(e) => e.is_bad_input(),
            _ => true,
        }
    }
}

fn plan_error(m: impl std::fmt::Display) -> TuneError {
    TuneError::Plan(m.to_string())
}

/// How to search.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Settings scored at most (all of the grid when it is no larger).
    pub budget: usize,
    /// Seeds the sampling of the grid and the inner folds.
    pub seed: u64,
    pub threads: usize,
    /// CPU minutes (estimated, [`cost`]) a costly feature setting (random
    /// kernels fitted fold by fold, competing kernels) may take over the
    /// whole search; costlier ones are left out.
    pub max_minutes: f64,
}

/// The CPU minutes a costly feature setting may take by default, half a
/// minute: on the generated 200-trial fingertip set (6 s at 2.2 kHz) the
/// random kernels take seconds a setting and the competing kernels most
/// of a minute, more than the rest of the search together; on 5-second
/// clips at 44.1 kHz under leave-one-out the random kernels take hours.
pub const MAX_MINUTES: f64 = 0.5;

/// A setting with its inner scores ([`InnerScore`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scored {
    /// The feature family and the classifier: `spectrum + knn`.
    pub family: String,
    pub options: Described,
    /// Mean accuracy over the inner folds (0..1).
    pub inner_accuracy: f64,
    /// Mean margin of the inner folds' test windows (-1..1): how much
    /// nearer the nearest of their own label than of another.
    pub inner_margin: f64,
    /// Mean share of the neighbour votes the inner folds' test recordings
    /// gave their own label (0..1).
    pub inner_true_votes: f64,
}

/// A search's outcome; its JSON is `tune --json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TuneReport {
    /// Settings scored in each search.
    pub configurations: usize,
    /// Settings in the whole grid (those the data fits and the search can
    /// afford).
    pub grid: usize,
    /// Settings the data fits that the search left out before any work,
    /// by family and reason ([`cost::affordable`]).
    pub left_out: Vec<cost::LeftOut>,
    /// Distinct feature settings computed.
    pub feature_settings: usize,
    /// Each of them: the feature options' values (`contrib/tune_reference.py`
    /// searches the same settings).
    pub feature_settings_scored: Vec<Described>,
    /// The outer validation: "holdout", "5-fold", "leave-one-out", …
    pub method: String,
    pub inner_folds: usize,
    /// How the inner folds were made.
    pub inner_split: InnerSplit,
    /// Whether the inner folds were in time: forward (under a time split)
    /// or blocks with the trials that overlap a test one left out of
    /// training (trials cut with a `--split-hop` below `--split`).
    pub inner_folds_in_time: bool,
    /// The outer estimate: the chosen settings tested on what each search
    /// never saw, pooled (0..1).
    pub outer_accuracy: f64,
    /// The outer test predictions, counted (labels, confusion, per class).
    pub outer: Report,
    /// The setting written to the profile.
    pub chosen: Scored,
    /// The best settings of the search that chose it, best first.
    pub table: Vec<Scored>,
    /// The best setting of each family and classifier searched
    /// (`spectrum + knn`, `kernels + ridge`, …) in the search that chose,
    /// best first: which family won, and by how much.
    pub families: Vec<Scored>,
    /// For k-fold and leave-one-out: each outer fold's own choice and its
    /// test accuracy.
    pub outer_folds: Vec<OuterFold>,
    /// What was searched, as the tuned profile records it (its mark).
    pub tuned_on: TunedOn,
    #[serde(skip)]
    pub chosen_setting: Option<Setting>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OuterFold {
    pub chosen: Scored,
    pub tested: usize,
    pub accuracy: f64,
}

/// Training and test recordings of one outer part (indices into the scans).
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub train: Vec<usize>,
    pub test: Vec<usize>,
}

/// The recordings' labels (sorted, distinct), each scan's class index and
/// its group (with `group_by`).
struct Data<'a> {
    scans: &'a [Entry],
    labels: Vec<String>,
    classes: Vec<usize>,
    groups: Option<Vec<String>>,
}

impl<'a> Data<'a> {
    fn new(scans: &'a [Entry], group_by: Option<&str>) -> Result<Data<'a>, TuneError> {
        let mut labels: Vec<String> = scans.iter().map(|s| s.label.clone()).collect();
        labels.sort();
        labels.dedup();
        let classes = scans
            .iter()
            .map(|s| labels.binary_search(&s.label).unwrap_or(0))
            .collect();
        let groups = match group_by {
            Some(key) => Some(
                scans
                    .iter()
                    .map(|s| {
                        s.meta_text(key).ok_or_else(|| {
                            plan_error(format!(
                                "{}: no metadata key `{key}` to group by ([evaluation] group_by)",
                                s.file
                            ))
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?,
            ),
            None => None,
        };
        Ok(Data {
            scans,
            labels,
            classes,
            groups,
        })
    }

    fn label_refs(&self, idx: &[usize]) -> Vec<&str> {
        idx.iter().map(|&i| self.scans[i].label.as_str()).collect()
    }

    fn group_of(&self, idx: &[usize]) -> Option<Vec<String>> {
        self.groups
            .as_ref()
            .map(|g| idx.iter().map(|&i| g[i].clone()).collect())
    }
}

/// Refuse, in one line, a plan that cannot test: one label, a label that
/// leave-one-out would leave with no training recording, fewer
/// recordings (or groups) than folds.
pub fn check_plan(scans: &[Entry], plan: &Plan) -> Result<(), TuneError> {
    let data = Data::new(scans, plan.group_by.as_deref())?;
    if data.labels.len() < 2 {
        return Err(plan_error(format!(
            "the recordings have a single label ({}): there is nothing to tell apart; add recordings of another label",
            data.labels.first().map_or("none", String::as_str)
        )));
    }
    if plan.method == SplitMethod::LeaveOneOut {
        for (c, label) in data.labels.iter().enumerate() {
            let mut units: Vec<&str> = (0..scans.len())
                .filter(|&i| data.classes[i] == c)
                .map(|i| match &data.groups {
                    Some(g) => g[i].as_str(),
                    None => scans[i].file.as_str(),
                })
                .collect();
            units.sort_unstable();
            units.dedup();
            if units.len() < 2 {
                let unit = if data.groups.is_some() {
                    "group"
                } else {
                    "recording"
                };
                return Err(plan_error(format!(
                    "label {label:?} has only one {unit}: leave-one-out would test it with none of its kind to train on; record more of it, or cut its long recordings into shorter trials"
                )));
            }
        }
    }
    if plan.method == SplitMethod::KFold {
        let units = match &data.groups {
            Some(g) => {
                let mut g: Vec<&String> = g.iter().collect();
                g.sort_unstable();
                g.dedup();
                g.len()
            }
            None => scans.len(),
        };
        if units < plan.folds {
            let what = if data.groups.is_some() {
                "groups"
            } else {
                "recordings"
            };
            // Two folds at least: with fewer than two groups no k-fold can test.
            let way = if units < 2 {
                format!(
                    "k-fold needs two {what} at least, and there is {units}: {}",
                    if data.groups.is_some() {
                        "give group_by a key with two values or more, or leave group_by out"
                    } else {
                        "record more"
                    }
                )
            } else {
                format!("set [evaluation] folds to {units} or fewer")
            };
            return Err(plan_error(format!(
                "{} need at least as many {what}, and there are {units}: {way}",
                plural(plan.folds, "fold", "folds")
            )));
        }
    }
    Ok(())
}

/// The settings to score: the whole grid within the budget, else whole
/// feature settings sampled with the seed (each with every classifier
/// setting) up to the budget. In grid order.
///
/// The feature settings are drawn family by family in turn (the spectrum,
/// the quantiles, the kernels, the competing kernels: each a shuffled
/// list), in each turn the family whose next feature setting brings the
/// fewest settings first, so a budget smaller than the grid still tries
/// every family.
fn sample(grid: Vec<Setting>, budget: usize, seed: u64) -> Vec<Setting> {
    if grid.len() <= budget {
        return grid;
    }
    let mut by_features: BTreeMap<Vec<usize>, Vec<Setting>> = BTreeMap::new();
    for s in grid {
        by_features.entry(s.feature_key()).or_default().push(s);
    }
    let mut families: BTreeMap<FeatureFamily, Vec<Vec<Setting>>> = BTreeMap::new();
    for group in by_features.into_values() {
        families
            .entry(group[0].analysis.features)
            .or_default()
            .push(group);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut queues: Vec<std::vec::IntoIter<Vec<Setting>>> = families
        .into_values()
        .map(|mut groups| {
            groups.shuffle(&mut rng);
            groups.into_iter()
        })
        .collect();
    let mut out: Vec<Setting> = Vec::new();
    'draw: loop {
        let mut turn: Vec<Vec<Setting>> = queues.iter_mut().filter_map(Iterator::next).collect();
        if turn.is_empty() {
            break;
        }
        // Stable: between equal sizes, in family order.
        turn.sort_by_key(Vec::len);
        for s in turn.into_iter().flatten() {
            if out.len() == budget {
                break 'draw;
            }
            out.push(s);
        }
    }
    out.sort_by(|a, b| a.values.cmp(&b.values));
    out
}

/// A setting's scores in one search: the mean over the inner folds of each
/// fold's accuracy, and of the finer scores that break ties between equal
/// accuracies (each a mean per tested recording: [`score::FoldScore`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct InnerScore {
    pub accuracy: f64,
    pub margin: f64,
    pub true_share: f64,
}

impl InnerScore {
    /// Better first: the higher accuracy, then the wider margin, then the
    /// larger share of votes for the true label.
    fn better(&self, other: &InnerScore) -> std::cmp::Ordering {
        other
            .accuracy
            .total_cmp(&self.accuracy)
            .then(other.margin.total_cmp(&self.margin))
            .then(other.true_share.total_cmp(&self.true_share))
    }
}

/// The settings in order, best first: the higher inner accuracy; between
/// equal accuracies the simpler family and classifier
/// ([`Setting::family_rank`]: the margins of k nearest neighbours and of a
/// linear classifier's vote are not on one scale), then within one by
/// [`InnerScore::better`], then the simplest ([`Setting::simplicity`]).
fn ranked(settings: &[Setting], scores: &[InnerScore]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..settings.len()).collect();
    order.sort_by(|&a, &b| {
        scores[b]
            .accuracy
            .total_cmp(&scores[a].accuracy)
            .then_with(|| settings[a].family_rank().cmp(&settings[b].family_rank()))
            .then_with(|| scores[a].better(&scores[b]))
            .then_with(|| settings[a].simplicity().cmp(&settings[b].simplicity()))
    });
    order
}

/// The best of scored settings ([`ranked`]'s first).
fn best(settings: &[Setting], scores: &[InnerScore]) -> usize {
    ranked(settings, scores).first().copied().unwrap_or(0)
}

/// One search's inputs shared by every part: the scans, their classes, the
/// settings and each part's inner folds.
struct Search<'a> {
    name: &'a str,
    scans: &'a [Entry],
    data: &'a Data<'a>,
    settings: &'a [Setting],
    inner: &'a [Vec<Part>],
    threads: usize,
}

impl Search<'_> {
    /// Every setting's [`InnerScore`] in every part (`[part][setting]`):
    /// feature settings on one grid one after another, a grid two or more
    /// of them share resampled once and kept while they are scored (unless
    /// it is over [`RESAMPLED_MOST`] points); each feature setting's
    /// vectors made once and scored with every classifier setting.
    fn score_all(
        &self,
        by_features: &BTreeMap<Vec<usize>, Vec<usize>>,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<Vec<InnerScore>>, TuneError> {
        let (scans, settings) = (self.scans, self.settings);
        let mut scores = vec![vec![InnerScore::default(); settings.len()]; self.inner.len()];
        let mut grids: Vec<(&Analysis, usize)> = Vec::new();
        let mut ordered: Vec<(usize, &Vec<usize>)> = by_features
            .values()
            .map(|members| {
                let a = &settings[members[0]].analysis;
                let g = match grids.iter().position(|(g, _)| same_grid(g, a)) {
                    Some(g) => g,
                    None => {
                        grids.push((a, 0));
                        grids.len() - 1
                    }
                };
                grids[g].1 += 1;
                (g, members)
            })
            .collect();
        ordered.sort_by_key(|&(g, _)| g);
        let shared: Vec<bool> = grids
            .iter()
            .map(|&(a, count)| count > 1 && resampled_points(scans, a) <= RESAMPLED_MOST)
            .collect();
        let mut kept: (Option<usize>, Resampled) = (None, Vec::new());
        let mut done = 0;
        progress(0, settings.len());
        for (g, members) in ordered {
            let analysis = &settings[members[0]].analysis;
            let features = if shared[g] {
                if kept.0 != Some(g) {
                    kept.1.clear(); // one grid's points in memory at a time
                    kept = (Some(g), resample(scans, analysis, self.threads)?);
                }
                extract_resampled(scans, &kept.1, analysis, self.threads)?
            } else {
                extract(scans, analysis, self.threads)?
            };
            // k nearest neighbours from one table of neighbours; the
            // linear classifiers fitted fold by fold.
            let (neighbours, linear): (Vec<usize>, Vec<usize>) = members
                .iter()
                .partition(|&&i| settings[i].classifier.method == Method::Knn);
            if !neighbours.is_empty() {
                self.score_feature_setting(&features, &neighbours, &mut scores);
            }
            if !linear.is_empty() {
                self.score_fitted(&features, &linear, &mut scores);
            }
            done += members.len();
            progress(done, settings.len());
        }
        Ok(scores)
    }

    /// Adds to `scores` the inner scores of `members` (settings sharing
    /// these features): one task per (part, inner fold, metric,
    /// standardisation), each k and vote weighting counted from one
    /// ranking of neighbours.
    fn score_feature_setting(
        &self,
        features: &score::Features,
        members: &[usize],
        scores: &mut [Vec<InnerScore>],
    ) {
        let settings = self.settings;
        let mut kinds: Vec<(Metric, bool)> = members
            .iter()
            .map(|&i| {
                let c = &settings[i].classifier;
                (c.metric, c.standardize)
            })
            .collect();
        kinds.sort_by_key(|&(m, s)| (m as u8, s));
        kinds.dedup();
        // Every recording an inner fold trains or tests on.
        let searched = parts::recordings_of(self.inner.iter().flatten());
        // One table of window pairs per metric scored unscaled.
        let tables: Vec<(Metric, Option<Pairwise>)> = kinds
            .iter()
            .filter(|&&(_, standardize)| !standardize)
            .map(|&(m, _)| (m, Pairwise::new(features, &searched, m, self.threads)))
            .collect();
        let table_of = |m| tables.iter().find(|t| t.0 == m).and_then(|t| t.1.as_ref());
        let mut tasks = Vec::new();
        for (p, folds) in self.inner.iter().enumerate() {
            for f in 0..folds.len() {
                for &kind in &kinds {
                    tasks.push((p, f, kind));
                }
            }
        }
        let results = par_map(&tasks, self.threads, |&(p, f, (metric, standardize))| {
            let voters: Vec<usize> = members
                .iter()
                .copied()
                .filter(|&i| {
                    let c = &settings[i].classifier;
                    c.metric == metric && c.standardize == standardize
                })
                .collect();
            let kw: Vec<_> = voters
                .iter()
                .map(|&i| (settings[i].classifier.k, settings[i].classifier.weights))
                .collect();
            let part = &self.inner[p][f];
            let fold = Fold {
                train: &part.train,
                test: &part.test,
            };
            let voting = Voting {
                classes: &self.data.classes,
                n_classes: self.data.labels.len(),
                metric,
                standardize,
            };
            let got = score_fold(features, &voting, &fold, &kw, table_of(metric));
            (p, voters, got, part.test.len().max(1) as f64)
        });
        for (p, voters, got, tested) in results {
            let n_folds = self.inner[p].len() as f64;
            for (i, g) in voters.into_iter().zip(got) {
                let s = &mut scores[p][i];
                s.accuracy += g.correct as f64 / tested / n_folds;
                s.margin += g.margin / tested / n_folds;
                s.true_share += g.true_share / tested / n_folds;
            }
        }
    }
}

impl Search<'_> {
    /// Adds to `scores` the inner scores of `members` whose classifier is
    /// fitted (the linear ones, and whatever the features need fitted:
    /// the kernels' biases): in each inner fold a model is trained on the
    /// fold's training recordings only, as `train` would, and classifies
    /// its test recordings. A recording's finer scores are its windows'
    /// vote: the share for its own label, and the margin of that share
    /// over the largest share of another label (−1 to 1).
    fn score_fitted(
        &self,
        features: &score::Features,
        members: &[usize],
        scores: &mut [Vec<InnerScore>],
    ) {
        let mut tasks = Vec::new();
        for (p, folds) in self.inner.iter().enumerate() {
            for f in 0..folds.len() {
                tasks.push((p, f));
            }
        }
        // Each task trains on every core (the kernels' transform): a few
        // at a time. Its settings share the features, so the kernels are
        // fitted once for all of them.
        let threads = self.threads.clamp(1, 2);
        let settings: Vec<&Setting> = members.iter().map(|&i| &self.settings[i]).collect();
        let shared: Vec<Option<SharedKernels>> = match settings.first() {
            Some(s) if s.analysis.features == FeatureFamily::Kernels => self
                .inner
                .iter()
                .map(|folds| SharedKernels::fit(&s.analysis, self.scans, features, folds))
                .collect(),
            _ => Vec::new(),
        };
        let results = par_map(&tasks, threads, |&(p, f)| {
            let part = &self.inner[p][f];
            let each = predict_part(
                self.name,
                &settings,
                self.scans,
                features,
                shared.get(p).and_then(Option::as_ref),
                (&part.train, &part.test),
            );
            (p, each)
        });
        let each_setting = results.into_iter().flat_map(|(p, each)| {
            // A setting that cannot train in a fold (an LDA on examples
            // that are all alike) scores nothing there; nor do any when
            // what they share cannot be fitted.
            each.unwrap_or_default()
                .into_iter()
                .zip(members)
                .filter_map(move |(rows, &i)| Some((p, i, rows.ok()?)))
        });
        for (p, i, rows) in each_setting {
            let n_folds = self.inner[p].len() as f64;
            let tested = rows.len().max(1) as f64;
            let s = &mut scores[p][i];
            // Summed as the neighbours' scores are, so equal counts give
            // equal accuracies to the last bit.
            let right = rows.iter().filter(|r| r.label == r.predicted).count();
            s.accuracy += right as f64 / tested / n_folds;
            let (share, margin) = rows
                .iter()
                .map(vote_shares)
                .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
            s.margin += margin / tested / n_folds;
            s.true_share += share / tested / n_folds;
        }
    }
}

/// A test recording's share of its windows' votes for its own label, and
/// the margin of that share over the largest of another label's.
fn vote_shares(row: &PredictionRow) -> (f64, f64) {
    let total: usize = row.votes.iter().map(|(_, n)| n).sum();
    let total = total.max(1) as f64;
    let own = row
        .votes
        .iter()
        .filter(|(l, _)| *l == row.label)
        .map(|(_, n)| *n)
        .sum::<usize>() as f64
        / total;
    let other = row
        .votes
        .iter()
        .filter(|(l, _)| *l != row.label)
        .map(|(_, n)| *n)
        .max()
        .unwrap_or(0) as f64
        / total;
    (own, own - other)
}

/// Run the search on the scans (read with [`crate::dataset::Keep::Samples`],
/// one entry per recording). `progress(done, total)` hears each feature
/// setting scored, in settings.
pub fn tune(
    name: &str,
    profile: &Profile,
    scans: &[Entry],
    options: &Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TuneReport, TuneError> {
    let plan = Plan::new(profile, &Overrides::default());
    check_plan(scans, &plan)?;
    let data = Data::new(scans, plan.group_by.as_deref())?;
    let group_by = plan.group_by.as_deref();
    let mut parts = outer_parts(profile, scans, &plan)?;
    // k-fold and leave-one-out: one more search over every recording
    // chooses the setting written (its test part is empty).
    if plan.method != SplitMethod::Holdout {
        parts.push(Part {
            train: (0..scans.len()).collect(),
            test: Vec::new(),
        });
    }
    let split = InnerSplit::of(&plan);
    let (inner, made): (Vec<Vec<Part>>, Vec<InnerSplit>) = parts
        .iter()
        .map(|p| inner_parts(scans, group_by, &p.train, options.seed, split))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    let all = grid((&profile.analysis, &profile.classifier));
    if all.is_empty() {
        return Err(plan_error(
            "no setting of the search fits the analysis window (Welch segments of at least 16 points): widen [analysis] window",
        ));
    }
    let work = cost::Work::of(&parts, &inner);
    let per_label = Fits::per_label(scans.iter().map(|e| (e.label.as_str(), e.file.as_str())));
    let fits = Fits::of(&plan, profile.evaluation.train_per_class, &per_label);
    let (all, left_out) = cost::affordable(all, fits, work, options.max_minutes);
    if all.is_empty() {
        let why: Vec<String> = left_out
            .iter()
            .map(|l| format!("{}: {}", l.family, l.reason))
            .collect();
        return Err(plan_error(format!(
            "every setting of the search is left out on these recordings ({})",
            why.join("; ")
        )));
    }
    let settings = sample(all.clone(), options.budget.max(1), options.seed);
    let mut by_features: BTreeMap<Vec<usize>, Vec<usize>> = BTreeMap::new();
    for (i, s) in settings.iter().enumerate() {
        by_features.entry(s.feature_key()).or_default().push(i);
    }
    let search = Search {
        name,
        scans,
        data: &data,
        settings: &settings,
        inner: &inner,
        threads: options.threads,
    };
    let scores = search.score_all(&by_features, progress)?;
    let scored = |i: usize, p: usize| Scored {
        family: settings[i].family(),
        options: settings[i].describe(),
        inner_accuracy: scores[p][i].accuracy,
        inner_margin: scores[p][i].margin,
        inner_true_votes: scores[p][i].true_share,
    };
    // Each outer part's choice, trained on its training part and tested
    // once on its test part.
    let mut predictions = Vec::new();
    let mut outer_folds = Vec::new();
    let mut made_features: BTreeMap<Vec<usize>, score::Features> = BTreeMap::new();
    for (p, part) in parts.iter().enumerate() {
        if part.test.is_empty() {
            continue;
        }
        let chosen = best(&settings, &scores[p]);
        let setting = &settings[chosen];
        let features = match made_features.entry(setting.feature_key()) {
            std::collections::btree_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::btree_map::Entry::Vacant(e) => {
                e.insert(extract(scans, &setting.analysis, options.threads)?)
            }
        };
        let rows = predict_part(
            name,
            &[setting],
            scans,
            features,
            None,
            (&part.train, &part.test),
        )?
        .pop()
        .unwrap_or(Ok(Vec::new()))?;
        let right = rows.iter().filter(|r| r.label == r.predicted).count();
        outer_folds.push(OuterFold {
            chosen: scored(chosen, p),
            tested: rows.len(),
            accuracy: right as f64 / rows.len().max(1) as f64,
        });
        predictions.extend(rows);
    }
    let final_part = parts.len() - 1;
    let order = ranked(&settings, &scores[final_part]);
    let chosen = order[0];
    let train_files = parts[0]
        .train
        .iter()
        .map(|&i| scans[i].file.clone())
        .collect();
    let outer = count(&data.labels, train_files, predictions);
    let estimate = outer.accuracy;
    let method = match plan.method {
        SplitMethod::Holdout => "holdout".to_string(),
        SplitMethod::KFold => format!("{}-fold", plan.folds),
        SplitMethod::LeaveOneOut if group_by.is_some() => "leave-one-group-out".to_string(),
        SplitMethod::LeaveOneOut => "leave-one-out".to_string(),
    };
    Ok(TuneReport {
        configurations: settings.len(),
        grid: all.len(),
        left_out,
        feature_settings: by_features.len(),
        feature_settings_scored: by_features
            .values()
            .map(|m| settings[m[0]].describe_features())
            .collect(),
        method,
        inner_folds: inner[final_part].len(),
        inner_split: made[final_part],
        inner_folds_in_time: matches!(made[final_part], InnerSplit::Blocks | InnerSplit::Forward),
        outer_accuracy: estimate,
        chosen: scored(chosen, final_part),
        table: order
            .iter()
            .take(10)
            .map(|&i| scored(i, final_part))
            .collect(),
        families: {
            let mut seen: Vec<String> = Vec::new();
            order
                .iter()
                .filter(|&&i| {
                    let f = settings[i].family();
                    let new = !seen.contains(&f);
                    if new {
                        seen.push(f);
                    }
                    new
                })
                .map(|&i| scored(i, final_part))
                .collect()
        },
        outer_folds: if plan.method == SplitMethod::Holdout {
            Vec::new()
        } else {
            outer_folds
        },
        outer,
        tuned_on: TunedOn {
            recordings: scans.len(),
            fingerprint: fingerprint(scans.iter().map(|e| (e.label.as_str(), e.file.as_str()))),
            validation: plan.describe(),
            holdout: plan.method == SplitMethod::Holdout,
            outer_estimate: estimate,
        },
        chosen_setting: Some(settings[chosen].clone()),
    })
}

/// Random kernels fitted once for all of a part's inner folds, on the
/// recordings every one of its folds trains on (under a time split, the
/// earliest block: each forward fold trains on it and none tests it), and
/// every window of the part's folds transformed by them once. Each fold's
/// classifiers are still trained on its own training windows only; the
/// transform, the search's costliest step, is done once instead of once a
/// fold.
struct SharedKernels {
    kernels: crate::analysis::kernels::KernelTransform,
    /// Each recording's windows, transformed (by recording index).
    rows: BTreeMap<usize, Vec<Vec<f64>>>,
}

impl SharedKernels {
    /// `None` when the folds share no training recording (shuffled,
    /// grouped and block folds each test every recording once) or the
    /// kernels cannot be fitted (each fold then fits and says why).
    fn fit(
        analysis: &Analysis,
        scans: &[Entry],
        features: &score::Features,
        folds: &[Part],
    ) -> Option<SharedKernels> {
        let common = parts::trained_on_by_all(folds);
        if common.is_empty() {
            return None;
        }
        let examples = |recordings: &[usize]| examples_of(scans, features, recordings);
        let kernels = crate::classify::fit_kernels(analysis, &examples(&common)).ok()??;
        let used = parts::recordings_of(folds);
        let mut transformed =
            crate::classify::transformed_rows(&kernels, &examples(&used)).into_iter();
        let rows = used
            .iter()
            .map(|&r| (r, transformed.by_ref().take(features[r].len()).collect()))
            .collect();
        Some(SharedKernels { kernels, rows })
    }
}

/// The windows of `recordings` as training examples, recording after
/// recording, each's windows in order.
fn examples_of(
    scans: &[Entry],
    features: &score::Features,
    recordings: &[usize],
) -> Vec<TrainingExample> {
    recordings
        .iter()
        .flat_map(|&r| {
            features[r].iter().map(move |w| TrainingExample {
                file: scans[r].file.clone(),
                label: scans[r].label.clone(),
                features: w.clone(),
            })
        })
        .collect()
}

/// What models of each of `settings` (one analysis, several classifiers)
/// trained on the recordings `train` say of each recording in `test`; the
/// kernels, when there are some, fitted once for them all (or taken with
/// every window's transform from `shared`). The outer error
/// is the shared part's, the inner each setting's.
#[allow(clippy::type_complexity)]
fn predict_part(
    name: &str,
    settings: &[&Setting],
    scans: &[Entry],
    features: &score::Features,
    shared: Option<&SharedKernels>,
    (train, test): (&[usize], &[usize]),
) -> Result<Vec<Result<Vec<PredictionRow>, TuneError>>, TuneError> {
    let examples = examples_of(scans, features, train);
    let classifiers: Vec<crate::profile::Classifier> = settings
        .iter()
        .map(|s| {
            let mut c = s.classifier.clone();
            c.k = c.k.min(examples.len().max(1));
            c
        })
        .collect();
    let Some(analysis) = settings.first().map(|s| &s.analysis) else {
        return Ok(Vec::new());
    };
    let models = match shared {
        Some(sh) => {
            let rows: Vec<&[f64]> = train
                .iter()
                .flat_map(|r| sh.rows.get(r).into_iter().flatten().map(Vec::as_slice))
                .collect();
            Model::train_each_transformed(
                name,
                analysis,
                &classifiers,
                examples,
                &sh.kernels,
                &rows,
            )?
        }
        None => Model::train_each(name, analysis, &classifiers, examples)?,
    };
    Ok(models
        .into_iter()
        .map(|model| {
            let model = model?;
            test.iter()
                .map(|&r| {
                    let p = match shared.and_then(|sh| sh.rows.get(&r)) {
                        Some(rows) => model.classify_transformed(rows)?,
                        None => model.classify_windows(&features[r])?,
                    };
                    Ok(PredictionRow {
                        file: scans[r].file.clone(),
                        label: scans[r].label.clone(),
                        predicted: p.label,
                        votes: p
                            .tally
                            .iter()
                            .map(|t| (t.label.clone(), t.windows))
                            .collect(),
                    })
                })
                .collect()
        })
        .collect())
}
