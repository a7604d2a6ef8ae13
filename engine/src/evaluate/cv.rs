//! Cross-validation: k-fold, leave-one-out and grouped folds, stratified
//! and seeded, and the report that pools their test predictions.
//!
//! Folds are lists of example indices to test; every other example trains.
//! Without groups, k-fold is stratified: each class's examples are shuffled
//! (ChaCha8, seeded with the seed and the label) and dealt round-robin into
//! the folds, continuing from where the previous class stopped, so every
//! fold holds each class in proportion. With groups (a metadata value per
//! example: `session`, `trial`, …), whole groups are dealt instead, shuffled
//! with the seed and stratified as far as the groups allow: each goes to the
//! fold whose class mix it keeps closest to the dataset's (see
//! [`stratified_groups`]); leave-one-out with groups leaves one group out.
//! No group ever sits on both sides of a split. Like the rest of `evaluate`, this never reads files and
//! never prints.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::{EvaluateError, Report, class_rates, class_seed, evaluate};
use crate::classify::{KFallback, Model, TrainingExample, plural};
use crate::folds::Shared;
use crate::profile::{Analysis, Classifier, SplitMethod};

/// The test indices of each fold.
pub type Folds = Vec<Vec<usize>>;

/// Folds as a cross-validation runs them: each fold's test items, and the
/// items left out of its training because they share samples with one it
/// tests (overlapping segments of one recording: [`Shared`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Dealt {
    pub folds: Folds,
    /// Per fold, the items its training leaves out besides its test ones:
    /// those sharing samples with a tested one, and, forward in time
    /// ([`deal_forward`]), the later ones.
    pub purged: Vec<Vec<usize>>,
    /// Whether segments of one recording were dealt as blocks in time.
    pub in_time: bool,
}

impl Dealt {
    /// `folds` with nothing left out of any training part.
    pub fn plain(folds: Folds) -> Dealt {
        let purged = vec![Vec::new(); folds.len()];
        Dealt {
            folds,
            purged,
            in_time: false,
        }
    }
}

/// The folds of [`make_folds`] for items some of which are segments of one
/// recording (`shared`): without groups, k-fold deals each recording's
/// segments into the folds as consecutive blocks in time; under every
/// method the segments overlapping a tested one are left out of that
/// fold's training; a fold that then has nothing of a tested label to
/// train on is refused in one line.
pub fn deal(
    labels: &[&str],
    groups: Option<&[String]>,
    shared: &Shared,
    method: SplitMethod,
    folds: usize,
    seed: u64,
) -> Result<Dealt, EvaluateError> {
    let in_time = groups.is_none() && method == SplitMethod::KFold && shared.has_segments();
    let f = if in_time {
        let n = labels.len();
        if folds < 2 || folds > n {
            return make_folds(labels, None, method, folds, seed).map(Dealt::plain);
        }
        every_label_testable(labels, None)?;
        let all: Vec<usize> = (0..n).collect();
        shared.time_blocks(&all, folds, |loose| {
            let l: Vec<&str> = loose.iter().map(|&i| labels[i]).collect();
            match make_folds(&l, None, SplitMethod::KFold, folds.min(loose.len()), seed) {
                Ok(f) => f
                    .into_iter()
                    .map(|f| f.into_iter().map(|j| loose[j]).collect())
                    .collect(),
                Err(_) => loose.iter().map(|&i| vec![i]).collect(),
            }
        })
    } else {
        make_folds(labels, groups, method, folds, seed)?
    };
    let purged = shared.purge(&f);
    // Only a fold that left something out can have lost a label's every
    // training recording (without it, `every_label_testable` holds).
    let total = label_counts(labels, 0..labels.len());
    for (k, (test, gone)) in f.iter().zip(&purged).enumerate() {
        if !gone.is_empty() {
            check_trainable(labels, &total, test, gone, (k, f.len()))?;
        }
    }
    Ok(Dealt {
        folds: f,
        purged,
        in_time,
    })
}

/// How many of `items` carry each label.
fn label_counts<'a>(
    labels: &[&'a str],
    items: impl IntoIterator<Item = usize>,
) -> BTreeMap<&'a str, usize> {
    let mut total: BTreeMap<&str, usize> = BTreeMap::new();
    for i in items {
        *total.entry(labels[i]).or_default() += 1;
    }
    total
}

/// Refuses fold `k` of `of` when a label it tests has no item left to train
/// on once its test items and `gone` (those overlapping one it tests) are
/// out of the `total` it could train on. Counted per label, so
/// leave-one-out over thousands stays linear per fold.
fn check_trainable(
    labels: &[&str],
    total: &BTreeMap<&str, usize>,
    test: &[usize],
    gone: &[usize],
    (k, of): (usize, usize),
) -> Result<(), EvaluateError> {
    let away = label_counts(labels, test.iter().chain(gone).copied());
    match test
        .iter()
        .find(|&&t| away[labels[t]] >= total.get(labels[t]).copied().unwrap_or(0))
    {
        Some(&t) => Err(EvaluateError::Folds(format!(
            "fold {} of {of}: every {:?} recording it could train on overlaps one it tests \
             (trials cut from one recording share samples), so nothing of {:?} is left to \
             learn from: import with a --split-hop of --split or more, use fewer folds, or \
             record more",
            k + 1,
            labels[t],
            labels[t]
        ))),
        None => Ok(()),
    }
}

/// Folds forward in time, as a time split tests (and as scikit-learn's
/// `TimeSeriesSplit`, stratified): each label's items, in the order given
/// (the earliest first), are cut into `folds + 1` consecutive blocks; fold
/// `j` tests block `j` of every label and trains on the blocks before it
/// only. `purged` holds, per fold, every item its training leaves out: the
/// later blocks, and the earlier items that overlap one it tests
/// ([`Shared`]). Fewer folds when a label has too few items, or when
/// overlapping items would leave a fold nothing of a label to train on
/// (larger blocks reach further back); refused when even one fold cannot.
pub fn deal_forward(
    labels: &[&str],
    shared: &Shared,
    folds: usize,
) -> Result<Dealt, EvaluateError> {
    let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, l) in labels.iter().enumerate() {
        by.entry(l).or_default().push(i);
    }
    let fewest = by.values().map(Vec::len).min().unwrap_or(0);
    if fewest < 2 {
        return Err(EvaluateError::Folds(format!(
            "folds forward in time need at least 2 recordings of each label to train on one \
             and test the next, and {} has {}",
            by.iter()
                .find(|(_, v)| v.len() == fewest)
                .map_or(String::new(), |(l, _)| format!("{l:?}")),
            fewest
        )));
    }
    let most = folds.clamp(1, fewest - 1);
    let mut refused = None;
    for m in (1..=most).rev() {
        match forward_blocks(labels, &by, shared, m) {
            Ok(d) => return Ok(d),
            Err(e) => refused = refused.or(Some(e)),
        }
    }
    Err(refused.unwrap_or(EvaluateError::NoExamples))
}

/// [`deal_forward`]'s `m` folds over `by` (each label's items in time order).
fn forward_blocks(
    labels: &[&str],
    by: &BTreeMap<&str, Vec<usize>>,
    shared: &Shared,
    m: usize,
) -> Result<Dealt, EvaluateError> {
    let mut block = vec![0usize; labels.len()];
    for items in by.values() {
        let n = items.len();
        for (p, &i) in items.iter().enumerate() {
            block[i] = p * (m + 1) / n;
        }
    }
    let total = label_counts(labels, 0..labels.len());
    let mut out = Dealt {
        folds: Vec::with_capacity(m),
        purged: Vec::with_capacity(m),
        in_time: true,
    };
    for j in 1..=m {
        let test: Vec<usize> = (0..labels.len()).filter(|&i| block[i] == j).collect();
        let mut gone: Vec<usize> = (0..labels.len()).filter(|&i| block[i] > j).collect();
        // What overlaps a tested item and would otherwise train.
        let near: Vec<usize> = shared
            .neighbours(&test)
            .into_iter()
            .filter(|&i| block[i] < j)
            .collect();
        if !near.is_empty() {
            check_trainable(
                labels,
                &total,
                &test,
                &[&gone[..], &near[..]].concat(),
                (j - 1, m),
            )?;
            gone.extend(near);
            gone.sort_unstable();
        }
        out.folds.push(test);
        out.purged.push(gone);
    }
    Ok(out)
}

/// Folds for k-fold (`folds` of them) or leave-one-out, over examples with
/// these labels and (optionally) groups. Deterministic for a seed.
pub fn make_folds(
    labels: &[&str],
    groups: Option<&[String]>,
    method: SplitMethod,
    folds: usize,
    seed: u64,
) -> Result<Folds, EvaluateError> {
    let n = labels.len();
    if n == 0 {
        return Err(EvaluateError::NoExamples);
    }
    if method != SplitMethod::Holdout {
        every_label_testable(labels, groups)?;
    }
    match (method, groups) {
        (SplitMethod::Holdout, _) => Err(EvaluateError::Folds(
            "a holdout split has no folds".to_string(),
        )),
        (SplitMethod::LeaveOneOut, None) => Ok((0..n).map(|i| vec![i]).collect()),
        (SplitMethod::LeaveOneOut, Some(g)) => {
            let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
            for (i, key) in g.iter().enumerate() {
                by.entry(key).or_default().push(i);
            }
            if by.len() < 2 {
                return Err(EvaluateError::Folds(
                    "leave-one-group-out needs at least 2 groups".into(),
                ));
            }
            Ok(by.into_values().collect())
        }
        (SplitMethod::KFold, None) => {
            if folds < 2 || folds > n {
                return Err(EvaluateError::Folds(format!(
                    "k-fold cross-validation takes 2 to {} (one per example at most), not {folds}",
                    plural(n, "fold", "folds")
                )));
            }
            let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
            for (i, l) in labels.iter().enumerate() {
                by.entry(l).or_default().push(i);
            }
            let mut out = vec![Vec::new(); folds];
            let mut next = 0;
            for (label, mut idx) in by {
                idx.shuffle(&mut ChaCha8Rng::seed_from_u64(class_seed(seed, label)));
                for i in idx {
                    out[next % folds].push(i);
                    next += 1;
                }
            }
            for f in &mut out {
                f.sort_unstable();
            }
            Ok(out)
        }
        (SplitMethod::KFold, Some(g)) => {
            let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
            for (i, key) in g.iter().enumerate() {
                by.entry(key).or_default().push(i);
            }
            if folds < 2 || folds > by.len() {
                return Err(EvaluateError::Folds(format!(
                    "{} need at least {}, and there {} {}",
                    plural(folds, "grouped fold", "grouped folds"),
                    plural(folds, "group", "groups"),
                    if by.len() == 1 { "is" } else { "are" },
                    by.len()
                )));
            }
            let groups: Vec<Vec<usize>> = by.into_values().collect();
            Ok(stratified_groups(labels, groups, folds, seed))
        }
    }
}

/// Refuses folds in which a label could be tested but never trained: a
/// label with a single recording (or a single group) is tested with
/// nothing of its own to learn from, and always missed.
fn every_label_testable(labels: &[&str], groups: Option<&[String]>) -> Result<(), EvaluateError> {
    let mut by: BTreeMap<&str, std::collections::BTreeSet<usize>> = BTreeMap::new();
    let mut names: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, l) in labels.iter().enumerate() {
        let key = match groups {
            Some(g) => {
                let next = names.len();
                *names.entry(g[i].as_str()).or_insert(next)
            }
            None => i,
        };
        by.entry(l).or_default().insert(key);
    }
    let Some((label, _)) = by.iter().find(|(_, v)| v.len() < 2) else {
        return Ok(());
    };
    let what = if groups.is_some() {
        "one group (`group_by`)"
    } else {
        "one recording"
    };
    Err(EvaluateError::Folds(format!(
        "label {label:?} has only {what}: it would be tested with nothing of it left to train on; \
         record more of it, or cut long recordings into trials with `hapticlab import FILES --split SECONDS`"
    )))
}

/// Deal whole groups into `folds` folds so that each fold's class mix
/// follows the dataset's as closely as the groups allow (after
/// scikit-learn's `StratifiedGroupKFold`): the groups are shuffled with the
/// seed, then taken purest first (largest spread of their class counts),
/// each into the fold where it leaves the per-class shares of the folds
/// least spread (mean over classes of the standard deviation across folds
/// of fold count / class count); ties go to the fold with fewest examples,
/// then the first. A fold that would otherwise stay empty takes a group.
fn stratified_groups(
    labels: &[&str],
    mut groups: Vec<Vec<usize>>,
    folds: usize,
    seed: u64,
) -> Folds {
    let classes: Vec<&str> = {
        let mut c: Vec<&str> = labels.to_vec();
        c.sort_unstable();
        c.dedup();
        c
    };
    let class_of = |i: usize| classes.binary_search(&labels[i]).unwrap_or(0);
    let mut class_total = vec![0usize; classes.len()];
    for &l in labels {
        class_total[classes.binary_search(&l).unwrap_or(0)] += 1;
    }
    groups.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let counts: Vec<Vec<usize>> = groups
        .iter()
        .map(|g| {
            let mut c = vec![0usize; classes.len()];
            for &i in g {
                c[class_of(i)] += 1;
            }
            c
        })
        .collect();
    let spread = |c: &[usize]| {
        let x: Vec<f64> = c.iter().map(|&v| v as f64).collect();
        mean_std(&x).1
    };
    let mut order: Vec<usize> = (0..groups.len()).collect();
    // Stable: equal spreads keep the shuffled order.
    order.sort_by(|&a, &b| spread(&counts[b]).total_cmp(&spread(&counts[a])));

    let mut per_fold = vec![vec![0usize; classes.len()]; folds];
    let mut out: Folds = vec![Vec::new(); folds];
    // The cost of the folds' class counts: how unevenly each class is shared.
    let cost = |per_fold: &[Vec<usize>]| -> f64 {
        (0..classes.len())
            .map(|c| {
                let shares: Vec<f64> = per_fold
                    .iter()
                    .map(|f| f[c] as f64 / class_total[c] as f64)
                    .collect();
                let (m, _) = mean_std(&shares);
                // Population spread (the folds are all there is).
                (shares.iter().map(|s| (s - m) * (s - m)).sum::<f64>() / folds as f64).sqrt()
            })
            .sum::<f64>()
            / classes.len() as f64
    };
    for (left, &g) in order.iter().enumerate().map(|(i, g)| (order.len() - i, g)) {
        let empty = out.iter().filter(|f| f.is_empty()).count();
        let candidates: Vec<usize> = if left <= empty {
            (0..folds).filter(|&f| out[f].is_empty()).collect()
        } else {
            (0..folds).collect()
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for f in candidates {
            for (c, n) in counts[g].iter().enumerate() {
                per_fold[f][c] += n;
            }
            let score = cost(&per_fold);
            for (c, n) in counts[g].iter().enumerate() {
                per_fold[f][c] -= n;
            }
            let key = (score, out[f].len(), f);
            let better = match best {
                None => true,
                Some((s, len, idx)) => {
                    score < s - 1e-12 || ((score - s).abs() <= 1e-12 && (key.1, key.2) < (len, idx))
                }
            };
            if better {
                best = Some(key);
            }
        }
        let f = best.map_or(0, |b| b.2);
        for (c, n) in counts[g].iter().enumerate() {
            per_fold[f][c] += n;
        }
        out[f].extend(groups[g].iter().copied());
    }
    for f in &mut out {
        f.sort_unstable();
    }
    out
}

/// One fold's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoldResult {
    pub tested: usize,
    pub accuracy: f64,
    /// The k used (chosen by the inner cross-validation when k = "auto").
    pub k: usize,
    /// Why this fold's training part did not use the profile's k.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_fallback: Option<KFallback>,
    /// Recordings left out of this fold's training: they overlap one it
    /// tests (segments of one recording).
    #[serde(skip_serializing_if = "is_zero")]
    pub left_out: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One line saying in how many folds the profile's k gave way to a k
/// chosen by CV inside the training part, and which k they chose; `None`
/// when every fold used the profile's k.
pub fn k_notice(folds: &[FoldResult]) -> Option<String> {
    let fell: Vec<(&FoldResult, &KFallback)> = folds
        .iter()
        .filter_map(|f| f.k_fallback.as_ref().map(|k| (f, k)))
        .collect();
    let (_, worst) = fell.iter().min_by_key(|(_, k)| k.scans)?;
    let mut chosen: BTreeMap<usize, usize> = BTreeMap::new();
    for (f, _) in &fell {
        *chosen.entry(f.k).or_default() += 1;
    }
    let chosen: Vec<String> = chosen
        .iter()
        .map(|(k, n)| format!("k = {k} in {}", plural(*n, "fold", "folds")))
        .collect();
    let head = format!(
        "k = {} needs at least {} per texture, {} has {}",
        worst.asked,
        crate::classify::scans(worst.asked),
        worst.label,
        worst.scans
    );
    if folds.len() == 1 {
        return Some(format!(
            "{head} in the training part: using k = {}, chosen by {}-fold CV inside it",
            fell[0].0.k, worst.folds
        ));
    }
    let others = folds.len() - fell.len();
    let others = if others > 0 {
        format!(", the profile's k in the other {others}")
    } else {
        String::new()
    };
    Some(format!(
        "{head} in a training part: k chosen by {}-fold CV inside each such part ({}{others})",
        worst.folds,
        chosen.join(", ")
    ))
}

/// A cross-validation's result. Its JSON keeps the `evaluate --json`
/// contract's keys (pooled over the folds: every example is tested once)
/// and adds the method, the per-fold accuracies, their mean and spread, and
/// the macro-F1.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CvReport {
    /// Pooled over the folds: correct / tested over all of them; `train`
    /// holds every file that trained in some fold, `test` every file
    /// tested, fold by fold.
    #[serde(flatten)]
    pub report: Report,
    pub method: String,
    pub seed: u64,
    pub folds: Vec<FoldResult>,
    /// Mean and sample standard deviation of the folds' accuracies.
    pub accuracy_mean: f64,
    pub accuracy_std: f64,
    /// Mean over the classes (with test examples) of F1 = 2PR / (P + R).
    pub macro_f1: f64,
    /// Per class, in `labels` order (NaN, `null` in JSON, for no test example).
    pub f1: Vec<f64>,
    /// Whether segments of one recording were dealt into the folds as
    /// blocks in time ([`deal`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub in_time: bool,
}

/// Per-class F1 from a confusion matrix (rows true, columns classified as).
pub fn f1_scores(confusion: &[Vec<usize>]) -> Vec<f64> {
    let n = confusion.len();
    (0..n)
        .map(|i| {
            let tp = confusion[i][i] as f64;
            let actual: usize = confusion[i].iter().sum();
            let predicted: usize = confusion.iter().map(|r| r[i]).sum();
            if actual == 0 {
                return f64::NAN;
            }
            let (p, r) = (tp / predicted.max(1) as f64, tp / actual as f64);
            if p + r == 0.0 {
                0.0
            } else {
                2.0 * p * r / (p + r)
            }
        })
        .collect()
}

pub fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = if x.len() > 1 {
        x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt())
}

/// Train on all but each fold, test on the fold, pool the counts. The folds
/// run on up to `threads` threads; the result does not depend on how many.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate(
    examples: &[TrainingExample],
    folds: &Dealt,
    profile_name: &str,
    analysis: &Analysis,
    classifier: &Classifier,
    method: &str,
    seed: u64,
    threads: usize,
) -> Result<CvReport, EvaluateError> {
    let runs = fold_runs(
        examples,
        folds,
        (profile_name, analysis, classifier),
        threads,
        |train| train.into_iter().cloned().collect(),
        evaluate,
    )?;
    let labels: Vec<String> = examples.iter().map(|e| e.label.clone()).collect();
    let train = examples.iter().map(|e| e.file.clone()).collect();
    Ok(pool(labels, train, runs, folds, method, seed))
}

/// One fold's outcome: its report, the k it used, and why k was lowered.
pub(super) type FoldRun<R> = (R, usize, Option<KFallback>);

/// The fold loop of every cross-validation, over `items` (examples, or
/// recordings with their sub-windows): for each fold, a model trained
/// (k adapted to the training part) on the `examples` of the items outside
/// it, then `test` of the fold's items. The folds run on up to `threads`
/// threads; the results come in fold order whatever their number, and the
/// first fold's error (in fold order) is the one returned.
pub(super) fn fold_runs<T: Clone + Sync, R: Send>(
    items: &[T],
    folds: &Dealt,
    (profile_name, analysis, classifier): (&str, &Analysis, &Classifier),
    threads: usize,
    examples: impl Fn(Vec<&T>) -> Vec<TrainingExample> + Sync,
    test: impl Fn(&Model, &[T]) -> Result<R, EvaluateError> + Sync,
) -> Result<Vec<FoldRun<R>>, EvaluateError> {
    let run = |f: usize| -> Result<FoldRun<R>, EvaluateError> {
        let test_idx = &folds.folds[f];
        // Tested, or left out beside a tested one: not trained on.
        let mut is_test = vec![false; items.len()];
        for &i in test_idx.iter().chain(&folds.purged[f]) {
            is_test[i] = true;
        }
        let train = examples(
            items
                .iter()
                .zip(&is_test)
                .filter(|(_, t)| !**t)
                .map(|(item, _)| item)
                .collect(),
        );
        let tested: Vec<T> = test_idx.iter().map(|&i| items[i].clone()).collect();
        let model = Model::train_adapting_k(profile_name, analysis, classifier, train)?;
        Ok((test(&model, &tested)?, model.classifier.k, model.k_fallback))
    };
    run_folds(folds.folds.len(), threads, run)
        .into_iter()
        .collect()
}

/// `run` on every fold, on up to `threads` threads; the results in fold
/// order, whatever the number of threads.
fn run_folds<R: Send>(folds: usize, threads: usize, run: impl Fn(usize) -> R + Sync) -> Vec<R> {
    let threads = threads.clamp(1, folds.max(1));
    let mut results: Vec<Option<R>> = (0..folds).map(|_| None).collect();
    std::thread::scope(|s| {
        let chunks = results.chunks_mut(folds.div_ceil(threads).max(1));
        let mut start = 0;
        for chunk in chunks {
            let first = start;
            start += chunk.len();
            let run = &run;
            s.spawn(move || {
                for (j, slot) in chunk.iter_mut().enumerate() {
                    *slot = Some(run(first + j));
                }
            });
        }
    });
    results
        .into_iter()
        .map(|r| r.expect("every fold ran"))
        .collect()
}

/// The folds' reports pooled into one: the confusion counts summed over
/// `labels` (every example's label, in any order), the tested files and
/// predictions fold by fold, the per-fold accuracies' mean and spread.
pub(super) fn pool(
    mut labels: Vec<String>,
    train: Vec<String>,
    runs: Vec<FoldRun<Report>>,
    dealt: &Dealt,
    method: &str,
    seed: u64,
) -> CvReport {
    labels.sort();
    labels.dedup();
    let mut confusion = vec![vec![0usize; labels.len()]; labels.len()];
    let mut predictions = Vec::new();
    let mut test = Vec::new();
    let mut fold_results = Vec::new();
    for ((report, k, k_fallback), purged) in runs.into_iter().zip(&dealt.purged) {
        for (i, li) in report.labels.iter().enumerate() {
            for (j, lj) in report.labels.iter().enumerate() {
                let (Ok(a), Ok(b)) = (labels.binary_search(li), labels.binary_search(lj)) else {
                    continue;
                };
                confusion[a][b] += report.confusion[i][j];
            }
        }
        fold_results.push(FoldResult {
            tested: report.tested(),
            accuracy: report.accuracy,
            k,
            k_fallback,
            left_out: purged.len(),
        });
        test.extend(report.test);
        predictions.extend(report.predictions);
    }
    let tested: usize = confusion.iter().flatten().sum();
    let correct: usize = (0..labels.len()).map(|i| confusion[i][i]).sum();
    let per_class = class_rates(&labels, &confusion);
    let f1 = f1_scores(&confusion);
    let present: Vec<f64> = f1.iter().copied().filter(|v| v.is_finite()).collect();
    let macro_f1 = present.iter().sum::<f64>() / present.len().max(1) as f64;
    let accs: Vec<f64> = fold_results.iter().map(|f| f.accuracy).collect();
    let (accuracy_mean, accuracy_std) = mean_std(&accs);
    CvReport {
        report: Report {
            accuracy: correct as f64 / tested.max(1) as f64,
            per_class,
            train,
            test,
            predictions,
            labels,
            confusion,
        },
        method: method.to_string(),
        seed,
        folds: fold_results,
        accuracy_mean,
        accuracy_std,
        macro_f1,
        f1,
        in_time: dealt.in_time,
    }
}

/// A cross-validation's report is a [`Report`] (pooled over the folds) with
/// more: `r.accuracy`, `r.confusion`, … read the pooled one.
impl std::ops::Deref for CvReport {
    type Target = Report;
    fn deref(&self) -> &Report {
        &self.report
    }
}

impl CvReport {
    /// See [`k_notice`].
    pub fn k_notice(&self) -> Option<String> {
        k_notice(&self.folds)
    }

    /// As [`Report::table`], plus the spread and the macro-F1.
    pub fn table(&self) -> String {
        let mut out = self.report.table();
        out.push_str(&format!(
            "{}: {} folds, accuracy per fold {:.1} ± {:.1} % (mean ± sd), macro-F1 {:.3}\n",
            self.method,
            self.folds.len(),
            100.0 * self.accuracy_mean,
            100.0 * self.accuracy_std,
            self.macro_f1
        ));
        if let Some(note) = self.segments_note() {
            out.push_str(&format!("{note}\n"));
        }
        out
    }

    /// How segments of one recording were kept apart, when they were: one
    /// line, or `None`.
    pub fn segments_note(&self) -> Option<String> {
        let left: usize = self.folds.iter().map(|f| f.left_out).sum();
        let blocks = if self.in_time {
            "each recording's segments were dealt into the folds as blocks in time"
        } else {
            ""
        };
        match (self.in_time, left) {
            (false, 0) => None,
            (_, 0) => Some(format!("segments of one recording: {blocks}")),
            (_, n) => Some(format!(
                "segments of one recording: {}{}left out of training {} beside a tested one \
                 (they share its samples), {:.1} per fold",
                blocks,
                if self.in_time { "; " } else { "" },
                plural(n, "overlapping segment", "overlapping segments"),
                n as f64 / self.folds.len().max(1) as f64
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::folds::Segment;

    #[test]
    fn forward_folds_train_on_earlier_trials_only() {
        // Two labels, 6 trials each, interleaved as files sort.
        let labels: Vec<&str> = (0..12)
            .map(|i| if i % 2 == 0 { "a" } else { "b" })
            .collect();
        let d = deal_forward(&labels, &Shared::none(12), 5).unwrap();
        // 5 folds of 6 blocks of one trial each: fold j tests trial j of
        // each label and trains on trials 0..j.
        assert_eq!(d.folds.len(), 5);
        assert!(d.in_time);
        for (j, (test, gone)) in d.folds.iter().zip(&d.purged).enumerate() {
            let j = j + 1;
            assert_eq!(test, &vec![2 * j, 2 * j + 1]);
            let train: Vec<usize> = (0..12)
                .filter(|i| !test.contains(i) && !gone.contains(i))
                .collect();
            assert_eq!(train, (0..2 * j).collect::<Vec<_>>(), "fold {j}");
        }
        // Fewer folds than asked when a label has few trials.
        let three: Vec<&str> = vec!["a", "a", "a", "b", "b", "b", "b"];
        assert_eq!(
            deal_forward(&three, &Shared::none(7), 5)
                .unwrap()
                .folds
                .len(),
            2
        );
        let e = deal_forward(&["a", "a", "b"], &Shared::none(3), 5).unwrap_err();
        assert!(e.to_string().contains("\"b\" has 1"), "{e}");
    }

    #[test]
    fn forward_folds_leave_out_overlapping_trials_and_widen_blocks() {
        // One source per label, 4 half-overlapping 1 s trials each.
        let seg = |source: &str, t: usize| {
            Some(Segment {
                source: source.into(),
                start: t as f64 * 0.5,
                length: 1.0,
            })
        };
        let labels = ["a", "a", "a", "a", "b", "b", "b", "b"];
        let spans = (0..8).map(|i| seg(labels[i], i % 4)).collect::<Vec<_>>();
        let shared = Shared::new(spans);
        // Three folds (blocks of one trial) would leave fold 1 nothing to
        // train on (its only earlier trial overlaps the tested one): two,
        // the first block two trials long.
        let d = deal_forward(&labels, &shared, 3).unwrap();
        assert_eq!(d.folds, vec![vec![2, 6], vec![3, 7]]);
        // Fold 1 trains on 0 and 4 (1 and 5 overlap 2 and 6; 3 and 7 are
        // later); fold 2 on 0, 1, 4 and 5.
        assert_eq!(d.purged, vec![vec![1, 3, 5, 7], vec![2, 6]]);
        // Two half-overlapping trials each: nothing can be tested forward.
        let two = ["a", "a", "b", "b"];
        let spans = (0..4).map(|i| seg(two[i], i % 2)).collect();
        let e = deal_forward(&two, &Shared::new(spans), 3).unwrap_err();
        assert!(e.to_string().contains("overlaps one it tests"), "{e}");
    }
}
