//! Evaluation, the engine behind `hapticlab evaluate` (whose arguments and
//! printing are in `commands/evaluate.rs`): here the per-class train/test
//! split, the confusion matrix, the success and error rates (section 4.5,
//! Table 4.1) and their report as JSON (`evaluate --json`) and as plain
//! text; `evaluate/cv.rs` the folds (k-fold, leave-one-out, grouped) and
//! the pooled [`cv::CvReport`]; `evaluate/plan.rs` the recordings loaded
//! once and the validation asked for ([`plan::validate`]); `evaluate/sweep.rs`
//! the parameter sweeps, over recordings or simulated datasets.
//!
//! This module classifies with a [`Model`] and counts; reading recordings
//! goes through [`crate::dataset`]. It never prints and knows no front end:
//! errors are [`EvaluateError`], which the command maps to exit codes.

pub mod cv;
pub mod plan;
pub mod request;
pub mod sweep;
pub mod windows;

use std::collections::BTreeMap;
use std::fmt::Write as _;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use thiserror::Error;

use crate::acquire::AcquireError;
use crate::classify::{ClassifyError, Model, TrainingExample};
use crate::dataset::DatasetError;
use crate::profile::Evaluation;

#[derive(Debug, Clone, PartialEq)]
pub struct Split {
    pub train: Vec<TrainingExample>,
    pub test: Vec<TrainingExample>,
}

#[derive(Debug, Error)]
pub enum EvaluateError {
    #[error("there are no examples to split")]
    NoExamples,
    #[error(
        "class {label:?} has {have} example(s) but the split needs {needed} \
         ({train} to train{between} and {test} to test)",
        needed = train + gap + test,
        between = if *gap > 0 { format!(", {gap} left out between") } else { String::new() }
    )]
    NotEnough {
        label: String,
        have: usize,
        train: usize,
        /// Left out between the training and the test ones (`gap_per_class`).
        gap: usize,
        test: usize,
    },
    /// Every test recording would be called the one label there is: a
    /// score of 100 % that says nothing of the classifier.
    #[error(
        "every recording is labelled {label:?} ({file}, …): an evaluation needs recordings \
         of at least two textures to tell apart; add another texture's recordings"
    )]
    OneLabel { label: String, file: String },
    #[error("there are no test examples")]
    NoTest,
    #[error("cannot make the folds: {0}")]
    Folds(String),
    #[error(transparent)]
    Classify(#[from] ClassifyError),
    /// Bad input met while planning or sweeping: a sweep's key or values,
    /// a missing group key, no recordings found.
    #[error("{0}")]
    Input(String),
    #[error("cannot make a temporary folder for the simulated scans: {0}")]
    Scratch(String),
    #[error("the recordings were loaded for other analysis settings (features only)")]
    FeaturesOnly,
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    #[error(transparent)]
    Acquire(#[from] AcquireError),
}

impl EvaluateError {
    /// Whether the user can fix it (exit code 2) rather than a runtime failure.
    pub fn is_bad_input(&self) -> bool {
        match self {
            EvaluateError::Scratch(_) | EvaluateError::FeaturesOnly => false,
            EvaluateError::Dataset(e) => e.is_bad_input(),
            EvaluateError::Acquire(e) => e.is_bad_input(),
            _ => true,
        }
    }
}

/// The seed of one class's shuffle: the evaluation seed mixed with the
/// label (FNV-1a), so a class's split does not depend on which other
/// classes there are.
fn class_seed(seed: u64, label: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in label.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    seed ^ h
}

/// Refuses examples that all share one label ([`EvaluateError::OneLabel`]).
pub fn check_two_labels(examples: &[TrainingExample]) -> Result<(), EvaluateError> {
    match examples.first() {
        Some(first) if examples.iter().all(|e| e.label == first.label) => {
            Err(EvaluateError::OneLabel {
                label: first.label.clone(),
                file: first.file.clone(),
            })
        }
        _ => Ok(()),
    }
}

/// Split the examples per class (label): in the order given (callers sort
/// by file name), or shuffled when `shuffle_seed` is set (each class by its
/// own ChaCha8 generator seeded with the seed and the label), the first
/// `train_per_class` go to training, the next `gap_per_class` are left out
/// and the next `test_per_class` go to test; any more are left out. Classes
/// come out in label order.
pub fn split(examples: Vec<TrainingExample>, eval: &Evaluation) -> Result<Split, EvaluateError> {
    if examples.is_empty() {
        return Err(EvaluateError::NoExamples);
    }
    let mut by_class: BTreeMap<String, Vec<TrainingExample>> = BTreeMap::new();
    for ex in examples {
        by_class.entry(ex.label.clone()).or_default().push(ex);
    }
    let (n_train, gap, n_test) = (
        eval.train_per_class,
        eval.gap_per_class,
        eval.test_per_class,
    );
    let mut out = Split {
        train: Vec::with_capacity(n_train * by_class.len()),
        test: Vec::with_capacity(n_test * by_class.len()),
    };
    for (label, mut class) in by_class {
        if class.len() < n_train + gap + n_test {
            return Err(EvaluateError::NotEnough {
                label,
                have: class.len(),
                train: n_train,
                gap,
                test: n_test,
            });
        }
        if let Some(seed) = eval.shuffle_seed {
            class.shuffle(&mut ChaCha8Rng::seed_from_u64(class_seed(seed, &label)));
        }
        let mut rest = class.into_iter();
        out.train.extend(rest.by_ref().take(n_train));
        out.test.extend(rest.skip(gap).take(n_test));
    }
    Ok(out)
}

/// An evaluation's result; its JSON is the `evaluate --json` contract.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The union of the training and test labels, sorted.
    pub labels: Vec<String>,
    /// `confusion[true][classified as]`, indexed like `labels`.
    pub confusion: Vec<Vec<usize>>,
    /// Correct / tested, 0..1.
    pub accuracy: f64,
    pub per_class: Vec<ClassRate>,
    /// The training files, in the model's order.
    pub train: Vec<String>,
    /// The test files, in the order tested.
    pub test: Vec<String>,
    pub predictions: Vec<PredictionRow>,
}

/// One class's row of Table 4.1's SR and ER, as fractions 0..1. A class with
/// no test example (`n = 0`) has no rate: NaN, written as `null` in JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassRate {
    pub label: String,
    /// Test examples of this class.
    pub n: usize,
    pub success_rate: f64,
    pub error_rate: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictionRow {
    pub file: String,
    pub label: String,
    pub predicted: String,
    /// Every class with its votes, most first, as `[["S2", 9], ["S3", 1], …]`
    /// (a list of pairs keeps the order; Python's `dict(votes)` reads it).
    pub votes: Vec<(String, usize)>,
}

/// Classify every test example and count.
pub fn evaluate(model: &Model, test: &[TrainingExample]) -> Result<Report, EvaluateError> {
    if test.is_empty() {
        return Err(EvaluateError::NoTest);
    }
    let mut predictions = Vec::with_capacity(test.len());
    for ex in test {
        let p = model.classify(&ex.features)?;
        predictions.push(PredictionRow {
            file: ex.file.clone(),
            label: ex.label.clone(),
            predicted: p.label,
            votes: p.votes,
        });
    }
    let train = model.examples.iter().map(|e| e.file.clone()).collect();
    Ok(count(&model.labels, train, predictions))
}

/// The report of a test: the labels (the model's and the tested ones,
/// sorted), the confusion matrix, accuracy and per-class rates counted from
/// `predictions` (one row per tested file, in the order tested).
pub(crate) fn count(
    model_labels: &[String],
    train: Vec<String>,
    predictions: Vec<PredictionRow>,
) -> Report {
    let mut labels: Vec<String> = model_labels
        .iter()
        .chain(predictions.iter().map(|p| &p.label))
        .cloned()
        .collect();
    labels.sort();
    labels.dedup();
    let index = |label: &str| labels.binary_search_by(|l| l.as_str().cmp(label));
    let mut confusion = vec![vec![0usize; labels.len()]; labels.len()];
    for p in &predictions {
        // Both labels are in `labels` by construction.
        if let (Ok(t), Ok(c)) = (index(&p.label), index(&p.predicted)) {
            confusion[t][c] += 1;
        }
    }
    let correct: usize = (0..labels.len()).map(|i| confusion[i][i]).sum();
    let per_class = class_rates(&labels, &confusion);
    Report {
        accuracy: correct as f64 / predictions.len() as f64,
        confusion,
        per_class,
        train,
        test: predictions.iter().map(|p| p.file.clone()).collect(),
        predictions,
        labels,
    }
}

/// SR and ER of each class (row) of a confusion matrix; NaN for a class
/// with no test examples.
pub fn class_rates(labels: &[String], confusion: &[Vec<usize>]) -> Vec<ClassRate> {
    labels
        .iter()
        .zip(confusion)
        .enumerate()
        .map(|(i, (label, row))| {
            let n: usize = row.iter().sum();
            let success_rate = if n > 0 {
                row[i] as f64 / n as f64
            } else {
                f64::NAN
            };
            ClassRate {
                label: label.clone(),
                n,
                success_rate,
                error_rate: 1.0 - success_rate,
            }
        })
        .collect()
}

/// Why a confusion matrix read back from a kept report (rows the true
/// class) and its accuracy do not hold together, or `None` when they do: a
/// square matrix of whole, non-negative counts, one row per label, that
/// counts some test example, and an accuracy that is its diagonal's share.
/// A report read from a file is checked by this before it is shown or drawn.
pub fn confusion_fault(labels: &[String], confusion: &[Vec<f64>], accuracy: f64) -> Option<String> {
    let n = labels.len();
    if n == 0 {
        return Some("it names no label".into());
    }
    if confusion.len() != n || confusion.iter().any(|r| r.len() != n) {
        let cols = confusion.first().map_or(0, Vec::len);
        return Some(format!(
            "its confusion matrix is {}x{cols} for {n} labels",
            confusion.len()
        ));
    }
    if let Some(v) = confusion
        .iter()
        .flatten()
        .find(|v| !(v.is_finite() && **v >= 0.0 && v.fract() == 0.0))
    {
        return Some(format!("its confusion matrix holds {v}, which is no count"));
    }
    let total: f64 = confusion.iter().flatten().sum();
    if total == 0.0 {
        return Some("its confusion matrix counts no test example".into());
    }
    let diagonal: f64 = (0..n).map(|i| confusion[i][i]).sum();
    if !(accuracy.is_finite() && (accuracy - diagonal / total).abs() <= 1e-6) {
        return Some(format!(
            "its accuracy {accuracy} is not its matrix's ({diagonal} of {total} right)"
        ));
    }
    None
}

impl Report {
    /// Test examples classified correctly.
    pub fn correct(&self) -> usize {
        (0..self.labels.len()).map(|i| self.confusion[i][i]).sum()
    }

    /// Test examples in all.
    pub fn tested(&self) -> usize {
        self.confusion.iter().flatten().sum()
    }

    /// The confusion matrix in Table 4.1's layout: one row per true class,
    /// one column per class classified as, then the SR and ER rows in
    /// percent ("-" for a class with no test example) and the accuracy.
    pub fn table(&self) -> String {
        let percent = |r: f64| {
            if r.is_finite() {
                format!("{:.1}", 100.0 * r)
            } else {
                "-".to_string()
            }
        };
        let sr: Vec<String> = self
            .per_class
            .iter()
            .map(|c| percent(c.success_rate))
            .collect();
        let er: Vec<String> = self
            .per_class
            .iter()
            .map(|c| percent(c.error_rate))
            .collect();
        let head = "Classified as";
        let first = self
            .labels
            .iter()
            .map(|l| l.chars().count())
            .chain([head.len(), "SR(%)".len()])
            .max()
            .unwrap_or(0);
        // All columns as wide as the widest entry, two spaces apart.
        let width = self
            .labels
            .iter()
            .map(|l| l.chars().count())
            .chain(self.confusion.iter().flatten().map(|c| c.to_string().len()))
            .chain(sr.iter().chain(&er).map(String::len))
            .max()
            .unwrap_or(0);
        let mut out = String::new();
        let mut row = |name: &str, cells: &mut dyn Iterator<Item = String>| {
            let mut line = format!("{name:<first$}");
            for cell in cells {
                let _ = write!(line, "  {cell:>width$}");
            }
            out.push_str(line.trim_end());
            out.push('\n');
        };
        row(head, &mut self.labels.iter().cloned());
        for (label, counts) in self.labels.iter().zip(&self.confusion) {
            row(label, &mut counts.iter().map(|c| c.to_string()));
        }
        row("SR(%)", &mut sr.into_iter());
        row("ER(%)", &mut er.into_iter());
        let tested = self.tested();
        let _ = writeln!(
            out,
            "accuracy: {}/{} ({} %)",
            self.correct(),
            tested,
            percent(if tested > 0 {
                self.correct() as f64 / tested as f64
            } else {
                f64::NAN
            })
        );
        out
    }
}
