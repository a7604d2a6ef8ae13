//! The k-nearest-neighbour classifier (section 3.3.2) and its model file.
//!
//! A [`Model`] is the training examples themselves plus the settings that
//! made their features: classifying a scan analysed with other settings is
//! refused ([`Model::check_settings`]). The model file is pretty-printed JSON
//! with a `format` tag; saving, loading and checking it are in
//! `classify/model_file.rs`. This module knows nothing of recordings or devices:
//! examples come in as feature vectors with their file name and label.
//!
//! With `method = "ridge"` or `"lda"` the model also carries a linear
//! classifier fitted on its examples (`classify/ridge.rs`, `classify/lda.rs`),
//! which answers in the neighbours' place: the class of the largest score,
//! one vote.
//!
//! Classification: the distance (Euclidean, Manhattan or cosine) to every
//! training example, the `k` nearest vote (one vote each, or `1/distance`
//! each with `weights = "distance"`; then an exact match outvotes the rest),
//! the most votes win. A tie between classes goes to the class whose
//! neighbours' distances add up to less, then to the class whose label sorts
//! first. Neighbours at equal distance keep the training order.
//!
//! With `standardize`, every feature is shifted and scaled by the training
//! examples' mean and standard deviation (stored in the model as `scaling`)
//! before any distance; the examples themselves are stored as measured.
//! With `k = "auto"`, [`Model::train`] picks k among the candidates by
//! stratified 5-fold cross-validation inside the training examples only
//! (the best mean accuracy; a tie goes to the smaller k) and stores the
//! scores as `k_selection`.
//!
//! [`Model::train_adapting_k`] is how the lab trains: it keeps the profile's
//! k wherever every texture has at least k training scans, and otherwise
//! chooses k as `k = "auto"` does (among the candidates no larger than the
//! smallest texture's count), recording why in `k_fallback`. With fewer own
//! scans than k, a texture's scans are outvoted by their neighbours' (with
//! 4 of a texture and k = 10, six votes go elsewhere), so the profile's k
//! would make a model that names almost nothing right.

use std::cmp::Ordering;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::analysis;

pub mod live;
use crate::analysis::kernels::KernelTransform;
use crate::profile::{Analysis, Classifier, FeatureFamily, Method, Metric, Weights};
use lda::LdaFit;
use ridge::RidgeFit;

mod distance;
mod k_choice;
pub mod lda;
pub(crate) use distance::{dot, rank_table, rank_value, to_distance};
mod linear;
mod model_file;
pub mod ridge;
use k_choice::{inner_folds, recording_numbers, select_k, smallest_class};
mod vote;
pub use vote::{RecordingPrediction, WindowTally, WindowVote, vote};

/// The `format` tag of a model file this version reads and writes: a
/// k-NN over features made without fitting (the spectrum's, the
/// quantiles'), as every version has written it.
pub const MODEL_FORMAT: &str = "hapticlab model v1";
/// The `format` tag of a model that carries what it fitted beyond its
/// examples: random kernels' biases ([`Model::kernels`]), a ridge
/// ([`Model::ridge`]) or a linear discriminant ([`Model::lda`]). A v1 file
/// has none of them and still loads.
pub const MODEL_FORMAT_V2: &str = "hapticlab model v2";

/// One labelled feature vector, named by the recording it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingExample {
    pub file: String,
    pub label: String,
    pub features: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// Always [`MODEL_FORMAT`].
    pub format: String,
    /// The hapticlab version that trained it, with its commit
    /// ([`crate::version::VERSION`]; models from before say `0.1.0`).
    pub software_version: String,
    /// The name of the profile it was trained under.
    pub profile: String,
    pub analysis: Analysis,
    pub classifier: Classifier,
    /// The distinct labels of the examples, sorted.
    pub labels: Vec<String>,
    pub examples: Vec<TrainingExample>,
    /// The standardisation fitted on the examples (`classifier.standardize`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scaling: Option<Scaling>,
    /// How `k = "auto"` chose `classifier.k`: each candidate's inner
    /// cross-validated accuracy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_selection: Option<Vec<KScore>>,
    /// Why the profile's k was not used (a texture had fewer training
    /// scans than k); `classifier.k` was then chosen as by `k = "auto"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_fallback: Option<KFallback>,
    /// `features = "kernels"`: the random kernels, their biases fitted on
    /// the examples (the training windows) only. Every window, the
    /// examples' and a query's, is transformed by them before the
    /// classifier sees it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernels: Option<KernelTransform>,
    /// `method = "ridge"`: the ridge fitted on the (transformed) examples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ridge: Option<RidgeFit>,
    /// `method = "lda"`: the linear discriminant fitted on the
    /// (transformed) examples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lda: Option<LdaFit>,
    /// The examples' features as the distance sees them (scaled), row-major.
    #[serde(skip)]
    matrix: Vec<f64>,
    /// Per example: its Euclidean norm (cosine metric only) and class index.
    #[serde(skip)]
    norms: Vec<f64>,
    #[serde(skip)]
    classes: Vec<usize>,
}

/// Per feature: `(x − mean) / scale`; `scale` is the standard deviation, or
/// 1 where that is zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scaling {
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
}

impl Scaling {
    pub fn fit(rows: &[&[f64]]) -> Scaling {
        let d = rows.first().map_or(0, |r| r.len());
        let n = rows.len().max(1) as f64;
        let mut mean = vec![0.0; d];
        for r in rows {
            for (m, v) in mean.iter_mut().zip(*r) {
                *m += v / n;
            }
        }
        let mut var = vec![0.0; d];
        for r in rows {
            for ((s, v), m) in var.iter_mut().zip(*r).zip(&mean) {
                *s += (v - m) * (v - m) / n;
            }
        }
        let scale = var
            .into_iter()
            .map(|v| if v > 0.0 { v.sqrt() } else { 1.0 })
            .collect();
        Scaling { mean, scale }
    }

    pub fn apply(&self, x: &[f64], out: &mut [f64]) {
        for (((o, v), m), s) in out.iter_mut().zip(x).zip(&self.mean).zip(&self.scale) {
            *o = (v - m) / s;
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KScore {
    pub k: usize,
    pub accuracy: f64,
}

/// The profile asked for `asked` neighbours, but texture `label` had only
/// `scans` training scans; k was chosen by `folds`-fold cross-validation
/// inside the training examples among the candidates up to `scans`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KFallback {
    pub asked: usize,
    pub label: String,
    pub scans: usize,
    pub folds: usize,
}

/// At most this many value operations in one run: feature-value
/// comparisons of k-NN (query vectors × training vectors × features), or
/// the multiply-adds of one ridge or LDA fit ([`linear_fit_work`]); 10^10
/// is seconds on one core. `evaluate` (every vector against every other,
/// or each fold's fit) and a prediction (a recording's sub-windows against
/// the model's examples, or scored by a ridge or LDA:
/// [`crate::predictor::answer_work`]) both refuse more,
/// before any is made. The thesis set's validation costs 7·10^5.
pub const MAX_COMPARISONS: f64 = 1e10;

/// The feature-value comparisons of classifying `queries` vectors against
/// `examples` training vectors of `features` features.
pub fn comparisons(queries: usize, examples: usize, features: usize) -> f64 {
    queries as f64 * examples as f64 * features as f64
}

/// The multiply-adds of fitting a ridge or an LDA on `n` vectors of `p`
/// features: about `n·p·min(n, p)` (the Gram or covariance matrix; its
/// eigendecomposition, `min(n, p)³`, is smaller).
pub fn linear_fit_work(n: usize, p: usize) -> f64 {
    let (n, p) = (n as f64, p as f64);
    n * p * n.min(p)
}

/// "S1 has 5 scans" in words: "1 scan", "5 scans".
pub fn scans(n: usize) -> String {
    plural(n, "scan", "scans")
}

/// `n` and the noun in the number it needs.
pub fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The outcome of classifying one feature vector.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Prediction {
    pub label: String,
    /// Every class of the model with its votes, most votes first (ties in
    /// the order that decides the prediction), so `votes[0].0 == label`.
    /// Serialised as `[["S2", 9], ["S3", 1], …]`.
    pub votes: Vec<(String, usize)>,
    /// The k nearest training examples, nearest first.
    pub neighbours: Vec<Neighbour>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Neighbour {
    pub file: String,
    pub label: String,
    pub distance: f64,
}

#[derive(Debug, Error)]
pub enum ClassifyError {
    #[error("there are no training examples")]
    NoExamples,
    #[error("the recording has no sub-window to classify")]
    NoWindows,
    #[error("classifier.k must be at least 1")]
    KZero,
    #[error("classifier.k = {k} but there are only {examples} training examples")]
    KTooLarge { k: usize, examples: usize },
    #[error("{file}: has {found} features, but the analysis settings give {expected}")]
    FeatureLength {
        file: String,
        expected: usize,
        found: usize,
    },
    #[error("{file}: feature {index} is not a finite number ({value})")]
    NonFinite {
        file: String,
        index: usize,
        value: f64,
    },
    #[error("{file}: the label is empty")]
    EmptyLabel { file: String },
    #[error("{file}: label {label:?} is not among the model's labels")]
    UnknownLabel { file: String, label: String },
    #[error("the scan has {found} features but the model expects {expected}")]
    QueryLength { expected: usize, found: usize },
    #[error("feature {number} of the scan is not a finite number ({value})", number = .index + 1)]
    QueryNonFinite { index: usize, value: f64 },
    #[error(
        "the distance to training example {file} is not a finite number: the scan's \
         features are too far from the model's range"
    )]
    Unmeasurable { file: String },
    #[error(
        "the {method}'s score for {label} is not a finite number: the scan's features are too \
         far from the model's range"
    )]
    ScoreNotFinite { method: &'static str, label: String },
    #[error("the model's analysis settings are unusable: {0}")]
    Settings(String),
    /// The ridge or the LDA could not be fitted on these examples.
    #[error("{0}")]
    Fit(String),
    #[error(
        "the model was trained with {field} = {model} but the profile has {field} = {profile}; \
         retrain the model under this profile"
    )]
    SettingsDiffer {
        field: &'static str,
        model: String,
        profile: String,
    },
    #[error("{}: {}", path.display(), crate::io::said(source))]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}:{line}:{column}: not valid JSON: {message}", path.display())]
    Malformed {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{}: not a hapticlab model (no \"format\" field)", path.display())]
    NotAModel { path: PathBuf },
    #[error("{}: model format {found:?} is not {MODEL_FORMAT:?}, which this version reads", path.display())]
    WrongFormat { path: PathBuf, found: String },
    #[error("{}:{line}:{column}: not a valid model: {message}", path.display())]
    Schema {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{}: not a valid model: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
}

/// Checks everything `train` and `load` need of a model's parts.
fn check_parts(
    analysis: &Analysis,
    classifier: &Classifier,
    examples: &[TrainingExample],
) -> Result<(), ClassifyError> {
    analysis::check_settings(analysis).map_err(ClassifyError::Settings)?;
    if examples.is_empty() {
        return Err(ClassifyError::NoExamples);
    }
    if classifier.method != Method::Knn {
        // k is not used (a ridge's or an LDA's k, 10 when left out, is
        // not held against a small training set either).
    } else if classifier.k == 0 {
        return Err(ClassifyError::KZero);
    } else if classifier.k > examples.len() {
        return Err(ClassifyError::KTooLarge {
            k: classifier.k,
            examples: examples.len(),
        });
    }
    let expected = analysis.feature_count();
    for ex in examples {
        if ex.label.is_empty() {
            return Err(ClassifyError::EmptyLabel {
                file: ex.file.clone(),
            });
        }
        if ex.features.len() != expected {
            return Err(ClassifyError::FeatureLength {
                file: ex.file.clone(),
                expected,
                found: ex.features.len(),
            });
        }
        if let Some((index, &value)) = ex.features.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(ClassifyError::NonFinite {
                file: ex.file.clone(),
                index,
                value,
            });
        }
    }
    Ok(())
}

fn sorted_labels(examples: &[TrainingExample]) -> Vec<String> {
    let mut labels: Vec<String> = examples.iter().map(|e| e.label.clone()).collect();
    labels.sort();
    labels.dedup();
    labels
}

/// The `k` smallest `(rank value, row)`, ascending, by bounded insertion: a
/// later row at an equal value goes after the earlier one.
fn nearest_rows(
    metric: Metric,
    q: &[f64],
    matrix: &[f64],
    norms: &[f64],
    rows: impl Iterator<Item = usize>,
    k: usize,
    nearest: &mut Vec<(f64, usize)>,
) {
    nearest.clear();
    let d = q.len();
    let q_norm = if metric == Metric::Cosine {
        dot(q, q).sqrt()
    } else {
        0.0
    };
    for index in rows {
        let row = &matrix[index * d..(index + 1) * d];
        let r = rank_value(
            metric,
            q,
            q_norm,
            row,
            norms.get(index).copied().unwrap_or(0.0),
        );
        if nearest.len() == k {
            if r >= nearest[k - 1].0 {
                continue;
            }
            nearest.pop();
        }
        let at = nearest.partition_point(|&(v, _)| v <= r);
        nearest.insert(at, (r, index));
    }
}

/// The classes in the order that decides the vote (most weight first, then
/// the smaller summed distance, then the label order), with vote counts.
pub(crate) fn rank_classes(
    metric: Metric,
    weights: Weights,
    nearest: &[(f64, usize)],
    classes_of: &[usize],
    classes: usize,
) -> (Vec<usize>, Vec<usize>) {
    let mut count = vec![0usize; classes];
    let mut weight = vec![0.0f64; classes];
    let mut summed = vec![0.0f64; classes];
    let exact = weights == Weights::Distance && nearest.iter().any(|&(r, _)| r == 0.0);
    for &(r, index) in nearest {
        let c = classes_of[index];
        let distance = to_distance(metric, r);
        count[c] += 1;
        summed[c] += distance;
        weight[c] += match weights {
            Weights::Uniform => 1.0,
            Weights::Distance if exact => f64::from(u8::from(distance == 0.0)),
            Weights::Distance => 1.0 / distance,
        };
    }
    let mut order: Vec<usize> = (0..classes).collect();
    order.sort_by(|&a, &b| {
        weight[b]
            .total_cmp(&weight[a])
            .then_with(|| {
                if count[a] > 0 && count[b] > 0 {
                    summed[a].total_cmp(&summed[b])
                } else {
                    Ordering::Equal
                }
            })
            .then(a.cmp(&b))
    });
    (order, count)
}

/// `features = "kernels"`: the kernels fitted on the examples' windows
/// (every channel's points, as the analysis hands them on).
pub fn fit_kernels(
    analysis: &Analysis,
    examples: &[TrainingExample],
) -> Result<Option<KernelTransform>, ClassifyError> {
    if analysis.features != FeatureFamily::Kernels {
        return Ok(None);
    }
    let windows: Vec<&[f64]> = examples.iter().map(|e| e.features.as_slice()).collect();
    KernelTransform::fit(
        &windows,
        analysis.points(),
        1 + analysis.channels.len(),
        analysis.kernel_features_asked(),
    )
    .map(Some)
    .map_err(ClassifyError::Settings)
}

/// Each example's index in the sorted `labels`.
fn class_indices(labels: &[String], examples: &[TrainingExample]) -> Vec<usize> {
    examples
        .iter()
        .map(|e| labels.binary_search(&e.label).unwrap_or(0))
        .collect()
}

/// What every classifier trained on the same examples shares.
struct Shared {
    kernels: Option<KernelTransform>,
    labels: Vec<String>,
    classes: Vec<usize>,
}

/// The examples transformed by the kernels `k` (on every core): the rows the
/// classifier sees of a kernel model.
pub fn transformed_rows(k: &KernelTransform, examples: &[TrainingExample]) -> Vec<Vec<f64>> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(examples.len().max(1));
    let per = examples.len().div_ceil(threads.max(1)).max(1);
    std::thread::scope(|s| {
        let parts: Vec<_> = examples
            .chunks(per)
            .map(|chunk| {
                s.spawn(move || {
                    let mut conv = k.convolution();
                    chunk
                        .iter()
                        .map(|e| {
                            let mut out = vec![0.0; k.feature_count()];
                            k.transform(&e.features, &mut conv, &mut out);
                            out
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        parts
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    })
}

/// The examples as the classifier sees them: `transformed` (by the
/// kernels) when there are some, else the examples' own features,
/// borrowed, not copied.
fn row_refs<'a>(
    transformed: Option<&'a [Vec<f64>]>,
    examples: &'a [TrainingExample],
) -> Vec<&'a [f64]> {
    match transformed {
        Some(rows) => rows.iter().map(Vec::as_slice).collect(),
        None => examples.iter().map(|e| e.features.as_slice()).collect(),
    }
}

/// What one classifier fits on the rows it sees: the scaling, the
/// ridge's or LDA's weights, and for k-NN the distance-ready copy of the
/// rows ([`prepare`]).
struct Parts {
    scaling: Option<Scaling>,
    ridge: Option<RidgeFit>,
    lda: Option<LdaFit>,
    matrix: Vec<f64>,
    norms: Vec<f64>,
}

impl Parts {
    fn fit(
        classifier: &Classifier,
        rows: &[&[f64]],
        classes: &[usize],
        labels: usize,
    ) -> Result<Parts, ClassifyError> {
        let mut parts = Parts {
            scaling: None,
            ridge: None,
            lda: None,
            matrix: Vec::new(),
            norms: Vec::new(),
        };
        match classifier.method {
            Method::Knn => {
                parts.scaling = classifier.standardize.then(|| Scaling::fit(rows));
                (parts.matrix, parts.norms) =
                    prepare(rows, parts.scaling.as_ref(), classifier.metric);
            }
            Method::Ridge => {
                parts.ridge =
                    Some(RidgeFit::fit(rows, classes, labels).map_err(ClassifyError::Fit)?);
            }
            Method::Lda => {
                parts.lda = Some(LdaFit::fit(rows, classes, labels).map_err(ClassifyError::Fit)?);
            }
        }
        Ok(parts)
    }
}

/// Rows of a row-major matrix of feature vectors, scaled as the model
/// does, and their norms under the cosine metric.
fn prepare(rows: &[&[f64]], scaling: Option<&Scaling>, metric: Metric) -> (Vec<f64>, Vec<f64>) {
    let d = rows.first().map_or(0, |r| r.len());
    let mut matrix = vec![0.0; d * rows.len()];
    for (row, features) in matrix.chunks_exact_mut(d.max(1)).zip(rows) {
        match scaling {
            Some(s) => s.apply(features, row),
            None => row.copy_from_slice(features),
        }
    }
    let norms = if metric == Metric::Cosine {
        matrix
            .chunks_exact(d.max(1))
            .map(|r| dot(r, r).sqrt())
            .collect()
    } else {
        Vec::new()
    };
    (matrix, norms)
}

/// Training values (examples × features) from which one query is searched
/// on several threads.
const PARALLEL_SEARCH_VALUES: usize = 1 << 20;

/// The default candidates of `k = "auto"`.
pub const AUTO_K_CANDIDATES: [usize; 8] = [1, 3, 5, 7, 9, 11, 13, 15];

impl Model {
    pub fn train(
        profile_name: &str,
        analysis: &Analysis,
        classifier: &Classifier,
        examples: Vec<TrainingExample>,
    ) -> Result<Model, ClassifyError> {
        Model::train_each(
            profile_name,
            analysis,
            std::slice::from_ref(classifier),
            examples,
        )?
        .pop()
        .unwrap_or(Err(ClassifyError::NoExamples))
    }

    /// [`Model::train`] for each of `classifiers` on the same examples,
    /// what they share (the kernels' biases and transform) fitted once:
    /// each model the one [`Model::train`] makes. The outer error is the
    /// shared part's, the inner each classifier's.
    #[allow(clippy::type_complexity)]
    pub fn train_each(
        profile_name: &str,
        analysis: &Analysis,
        classifiers: &[Classifier],
        examples: Vec<TrainingExample>,
    ) -> Result<Vec<Result<Model, ClassifyError>>, ClassifyError> {
        Model::train_each_with(profile_name, analysis, classifiers, examples, None)
    }

    /// [`Model::train_each`] with kernels the caller fitted before, on
    /// training windows only (tune's forward inner folds: the windows every
    /// fold trains on), and `rows` each example's window transformed by
    /// them; nothing is fitted or transformed again.
    #[allow(clippy::type_complexity)]
    pub fn train_each_transformed(
        profile_name: &str,
        analysis: &Analysis,
        classifiers: &[Classifier],
        examples: Vec<TrainingExample>,
        kernels: &KernelTransform,
        rows: &[&[f64]],
    ) -> Result<Vec<Result<Model, ClassifyError>>, ClassifyError> {
        Model::train_each_with(
            profile_name,
            analysis,
            classifiers,
            examples,
            Some((kernels, rows)),
        )
    }

    #[allow(clippy::type_complexity)]
    fn train_each_with(
        profile_name: &str,
        analysis: &Analysis,
        classifiers: &[Classifier],
        examples: Vec<TrainingExample>,
        given: Option<(&KernelTransform, &[&[f64]])>,
    ) -> Result<Vec<Result<Model, ClassifyError>>, ClassifyError> {
        let classifiers: Vec<(Classifier, bool)> = classifiers
            .iter()
            .map(|c| {
                let mut c = c.clone();
                let auto = c.k_is_auto() && c.method == Method::Knn;
                if auto {
                    c.k = 1;
                }
                (c, auto)
            })
            .collect();
        let checked: Vec<Result<(), ClassifyError>> = classifiers
            .iter()
            .map(|(c, _)| check_parts(analysis, c, &examples))
            .collect();
        if !checked.is_empty() && !checked.iter().any(Result::is_ok) {
            // None can train: each says why.
            return Ok(checked
                .into_iter()
                .filter_map(Result::err)
                .map(Err)
                .collect());
        }
        let (kernels, made);
        let rows = match given {
            Some((k, rows)) => {
                if rows.len() != examples.len() || rows.iter().any(|r| r.len() != k.feature_count())
                {
                    return Err(ClassifyError::Settings(
                        "the transformed windows do not match the examples".into(),
                    ));
                }
                kernels = Some(k.clone());
                rows.to_vec()
            }
            None => {
                // Fitted on these examples only: the caller's training part.
                kernels = fit_kernels(analysis, &examples)?;
                made = kernels.as_ref().map(|k| transformed_rows(k, &examples));
                row_refs(made.as_deref(), &examples)
            }
        };
        let labels = sorted_labels(&examples);
        let classes = class_indices(&labels, &examples);
        // Every classifier's fit first, on rows that may borrow the
        // examples; then the examples move into the models.
        let fits: Vec<Result<Parts, ClassifyError>> = classifiers
            .iter()
            .zip(checked)
            .map(|((c, _), check)| {
                check.and_then(|()| Parts::fit(c, &rows, &classes, labels.len()))
            })
            .collect();
        drop(rows);
        let mut out = Vec::with_capacity(classifiers.len());
        let last = classifiers.len().saturating_sub(1);
        let mut examples = Some(examples);
        for (i, ((classifier, auto), parts)) in classifiers.into_iter().zip(fits).enumerate() {
            let own = if i == last {
                examples.take().unwrap_or_default()
            } else {
                examples.clone().unwrap_or_default()
            };
            out.push(parts.map(|parts| {
                Model::of_parts(
                    profile_name,
                    analysis,
                    classifier,
                    auto,
                    own,
                    Shared {
                        kernels: kernels.clone(),
                        labels: labels.clone(),
                        classes: classes.clone(),
                    },
                    parts,
                )
            }));
        }
        Ok(out)
    }

    /// One classifier's model from what it fitted and what every
    /// classifier shares; k chosen by inner cross-validation when asked.
    fn of_parts(
        profile_name: &str,
        analysis: &Analysis,
        classifier: Classifier,
        auto: bool,
        examples: Vec<TrainingExample>,
        shared: Shared,
        parts: Parts,
    ) -> Model {
        let Shared {
            kernels,
            labels,
            classes,
        } = shared;
        let Parts {
            scaling,
            ridge,
            lda,
            matrix,
            norms,
        } = parts;
        let format = if kernels.is_some() || ridge.is_some() || lda.is_some() {
            MODEL_FORMAT_V2
        } else {
            MODEL_FORMAT
        };
        let mut model = Model {
            format: format.to_string(),
            software_version: crate::version::VERSION.to_string(),
            profile: profile_name.to_string(),
            analysis: analysis.clone(),
            classifier,
            labels,
            examples,
            scaling,
            k_selection: None,
            k_fallback: None,
            kernels,
            ridge,
            lda,
            matrix,
            norms,
            classes,
        };
        if auto {
            let recording_of = recording_numbers(&model.examples);
            let scores = select_k(
                &model.classifier,
                &model.matrix,
                &model.norms,
                &model.classes,
                &recording_of,
                model.labels.len(),
            );
            let best = scores
                .iter()
                .filter(|s| s.k <= model.examples.len())
                .fold(None::<&KScore>, |b, s| match b {
                    Some(b)
                        if b.accuracy >= s.accuracy && (b.accuracy > s.accuracy || b.k < s.k) =>
                    {
                        Some(b)
                    }
                    _ => Some(s),
                })
                .map_or(1, |s| s.k);
            model.classifier.k = best;
            model.k_selection = Some(scores);
        }
        model
    }

    /// Train as the lab does: with the classifier's k where every texture has
    /// at least k training examples; otherwise k is chosen by inner
    /// cross-validation on these examples only (as `k = "auto"`, among the
    /// candidates no larger than the smallest texture's count) and
    /// `k_fallback` says why. `k = "auto"` trains as [`Model::train`].
    pub fn train_adapting_k(
        profile_name: &str,
        analysis: &Analysis,
        classifier: &Classifier,
        examples: Vec<TrainingExample>,
    ) -> Result<Model, ClassifyError> {
        let Some((label, fewest)) = smallest_class(&examples) else {
            return Model::train(profile_name, analysis, classifier, examples);
        };
        if classifier.method != Method::Knn
            || classifier.k_is_auto()
            || classifier.k == 0
            || fewest >= classifier.k
        {
            return Model::train(profile_name, analysis, classifier, examples);
        }
        let mut candidates: Vec<usize> = classifier
            .k_candidates
            .clone()
            .unwrap_or_else(|| AUTO_K_CANDIDATES.to_vec())
            .into_iter()
            .filter(|&k| k <= fewest)
            .collect();
        if candidates.is_empty() {
            candidates.push(1);
        }
        let mut auto = classifier.clone();
        auto.k = crate::profile::K_AUTO;
        auto.k_candidates = Some(candidates);
        let folds = inner_folds(examples.len());
        let mut model = Model::train(profile_name, analysis, &auto, examples)?;
        // The model keeps the profile's settings; only k was chosen.
        model.classifier.k_candidates = classifier.k_candidates.clone();
        model.k_fallback = Some(KFallback {
            asked: classifier.k,
            label,
            scans: fewest,
            folds,
        });
        Ok(model)
    }

    /// The classifier settings the model was asked to train with: the
    /// profile's k (or `auto`) rather than the k it chose.
    pub fn asked_classifier(&self) -> Classifier {
        let mut c = self.classifier.clone();
        if let Some(f) = &self.k_fallback {
            c.k = f.asked;
        } else if self.k_selection.is_some() {
            c.k = crate::profile::K_AUTO;
        }
        c
    }

    /// One line saying that (and why) the profile's k was not used, or
    /// `None` when it was.
    pub fn k_notice(&self) -> Option<String> {
        let f = self.k_fallback.as_ref()?;
        let chosen = match self.k_selection.as_deref() {
            Some(s) if s.len() > 1 => format!(", chosen by {}-fold CV", f.folds),
            _ => ", the largest it supports".to_string(),
        };
        Some(format!(
            "k = {} needs at least {} per texture, {} has {}: using k = {}{chosen}",
            f.asked,
            scans(f.asked),
            f.label,
            f.scans,
            self.classifier.k
        ))
    }

    /// Using the model under a profile whose classifier settings differ
    /// from the ones it was trained with is an error naming the first
    /// field that differs (k as the profile gives it, not as chosen).
    pub fn check_classifier(&self, classifier: &Classifier) -> Result<(), ClassifyError> {
        let (m, p) = (&self.asked_classifier(), classifier);
        let differ = |field: &'static str, model: String, profile: String| {
            Err(ClassifyError::SettingsDiffer {
                field,
                model,
                profile,
            })
        };
        if m.method != p.method {
            return differ("classifier.method", json(&m.method), json(&p.method));
        }
        if m.method != Method::Knn {
            // Ridge and LDA: k, metric, weights and standardize are not used.
            return Ok(());
        }
        if m.k != p.k {
            return differ("classifier.k", m.k_text(), p.k_text());
        }
        if m.metric != p.metric {
            return differ("classifier.metric", json(&m.metric), json(&p.metric));
        }
        if m.weights != p.weights {
            return differ("classifier.weights", json(&m.weights), json(&p.weights));
        }
        if m.standardize != p.standardize {
            return differ(
                "classifier.standardize",
                json(&m.standardize),
                json(&p.standardize),
            );
        }
        if (m.k_is_auto() || self.k_fallback.is_some()) && m.k_candidates != p.k_candidates {
            return differ(
                "classifier.k_candidates",
                json(&m.k_candidates),
                json(&p.k_candidates),
            );
        }
        Ok(())
    }

    /// Builds the distance-ready copy of the examples (a loaded model's:
    /// transformed again by its kernels); none for a ridge or an LDA,
    /// which need only their weights.
    fn prepare(&mut self) {
        self.classes = class_indices(&self.labels, &self.examples);
        (self.matrix, self.norms) = (Vec::new(), Vec::new());
        if self.ridge.is_some() || self.lda.is_some() {
            return;
        }
        let made = self
            .kernels
            .as_ref()
            .map(|k| transformed_rows(k, &self.examples));
        let rows = row_refs(made.as_deref(), &self.examples);
        let (matrix, norms) = prepare(&rows, self.scaling.as_ref(), self.classifier.metric);
        drop(rows);
        (self.matrix, self.norms) = (matrix, norms);
    }

    /// The classifier in a few words: `k-NN (k = 3)`, `ridge`, `LDA`.
    pub fn classifier_name(&self) -> String {
        match self.classifier.method {
            Method::Knn => format!("{} (k = {})", Method::Knn.name(), self.classifier.k),
            other => other.name().into(),
        }
    }

    /// Features the classifier sees per window: the kernels' when the
    /// model has them, else the query's.
    pub fn fitted_feature_count(&self) -> usize {
        self.kernels
            .as_ref()
            .map_or(self.feature_count(), KernelTransform::feature_count)
    }

    /// A ridge's or an LDA's answer from its scores: the classes by
    /// score, the best first (a tie to the label first in order); one
    /// vote for the best.
    fn score_prediction(
        &self,
        method: &'static str,
        scores: Vec<f64>,
    ) -> Result<Prediction, ClassifyError> {
        if let Some(i) = scores.iter().position(|s| !s.is_finite()) {
            return Err(ClassifyError::ScoreNotFinite {
                method,
                label: self.labels[i].clone(),
            });
        }
        let mut order: Vec<usize> = (0..scores.len()).collect();
        order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
        let votes: Vec<(String, usize)> = order
            .iter()
            .enumerate()
            .map(|(rank, &c)| (self.labels[c].clone(), usize::from(rank == 0)))
            .collect();
        Ok(Prediction {
            label: votes[0].0.clone(),
            votes,
            neighbours: Vec::new(),
        })
    }

    /// The first example whose distance-ready features, squared and
    /// summed, are not finite (a distance to it could overflow to NaN).
    fn unmeasurable_example(&self) -> Option<&str> {
        let d = self.fitted_feature_count().max(1);
        self.matrix
            .chunks_exact(d)
            .zip(&self.examples)
            .find(|(row, _)| !dot(row, row).is_finite())
            .map(|(_, ex)| ex.file.as_str())
    }

    /// Number of features a query must have.
    pub fn feature_count(&self) -> usize {
        self.analysis.feature_count()
    }

    pub fn classify(&self, features: &[f64]) -> Result<Prediction, ClassifyError> {
        self.classify_as(features, false)
    }

    /// [`Model::classify`] of a window the model's kernels have already
    /// transformed (as [`Model::train_each_transformed`]'s rows).
    fn classify_as(
        &self,
        features: &[f64],
        transformed: bool,
    ) -> Result<Prediction, ClassifyError> {
        let expected = match &self.kernels {
            Some(k) if transformed => k.feature_count(),
            _ => self.feature_count(),
        };
        if features.len() != expected {
            return Err(ClassifyError::QueryLength {
                expected,
                found: features.len(),
            });
        }
        if let Some((index, &value)) = features.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ClassifyError::QueryNonFinite { index, value });
        }
        if self.examples.is_empty() {
            return Err(ClassifyError::NoExamples);
        }
        let made;
        let features = match &self.kernels {
            Some(_) if transformed => features,
            Some(kernels) => {
                let mut out = vec![0.0; kernels.feature_count()];
                kernels.transform(features, &mut kernels.convolution(), &mut out);
                made = out;
                made.as_slice()
            }
            None => features,
        };
        let mut buf = Vec::new();
        if let Some(ridge) = &self.ridge {
            buf.resize(features.len(), 0.0);
            return self.score_prediction(Method::Ridge.name(), ridge.scores(features, &mut buf));
        }
        if let Some(lda) = &self.lda {
            buf.resize(features.len(), 0.0);
            return self.score_prediction(Method::Lda.name(), lda.scores(features, &mut buf));
        }
        let k = self.classifier.k.clamp(1, self.examples.len());
        let mut scaled;
        let q = match &self.scaling {
            Some(sc) => {
                scaled = vec![0.0; features.len()];
                sc.apply(features, &mut scaled);
                scaled.as_slice()
            }
            None => features,
        };
        let metric = self.classifier.metric;
        let mut nearest = Vec::with_capacity(k + 1);
        let n = self.examples.len();
        // A large training set is searched in parallel chunks (the scan is
        // bound by memory bandwidth, which one core does not saturate); the
        // chunks' nearest are merged by (value, row), so ties keep the
        // training order exactly as a single pass would.
        let threads = if n * q.len().max(1) >= PARALLEL_SEARCH_VALUES {
            std::thread::available_parallelism().map_or(1, |t| t.get().min(8))
        } else {
            1
        };
        if threads > 1 {
            let per = n.div_ceil(threads);
            let (matrix, norms) = (&self.matrix, &self.norms);
            let parts: Vec<Vec<(f64, usize)>> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads)
                    .map(|t| {
                        s.spawn(move || {
                            let mut part = Vec::with_capacity(k + 1);
                            let rows = t * per..((t + 1) * per).min(n);
                            nearest_rows(metric, q, matrix, norms, rows, k, &mut part);
                            part
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_default())
                    .collect()
            });
            nearest = parts.concat();
            nearest.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            nearest.truncate(k);
        } else {
            nearest_rows(metric, q, &self.matrix, &self.norms, 0..n, k, &mut nearest);
        }
        if let Some(&(_, index)) = nearest.iter().find(|(r, _)| !r.is_finite()) {
            // NaN sorts last and ties everything: no verdict from it.
            return Err(ClassifyError::Unmeasurable {
                file: self.examples[index].file.clone(),
            });
        }
        let (order, count) = rank_classes(
            metric,
            self.classifier.weights,
            &nearest,
            &self.classes,
            self.labels.len(),
        );
        let neighbours = nearest
            .iter()
            .map(|&(r, index)| {
                let ex = &self.examples[index];
                Neighbour {
                    file: ex.file.clone(),
                    label: ex.label.clone(),
                    distance: to_distance(metric, r),
                }
            })
            .collect();
        let votes: Vec<(String, usize)> = order
            .iter()
            .map(|&c| (self.labels[c].clone(), count[c]))
            .collect();
        Ok(Prediction {
            label: votes[0].0.clone(),
            votes,
            neighbours,
        })
    }

    /// Classify a recording by the vote of its sub-windows' feature vectors
    /// (in window order; see [`vote`]).
    pub fn classify_windows(
        &self,
        windows: &[Vec<f64>],
    ) -> Result<RecordingPrediction, ClassifyError> {
        self.classify_windows_as(windows, false)
    }

    /// [`Model::classify_windows`] of windows the model's kernels have
    /// already transformed.
    pub fn classify_transformed(
        &self,
        windows: &[Vec<f64>],
    ) -> Result<RecordingPrediction, ClassifyError> {
        self.classify_windows_as(windows, true)
    }

    fn classify_windows_as(
        &self,
        windows: &[Vec<f64>],
        transformed: bool,
    ) -> Result<RecordingPrediction, ClassifyError> {
        let votes = windows
            .iter()
            .enumerate()
            .map(|(window, f)| {
                self.classify_as(f, transformed).map(|p| WindowVote {
                    window,
                    label: p.label,
                    votes: p.votes,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        vote(votes).ok_or(ClassifyError::NoWindows)
    }
}

/// A settings value as it is written in JSON (strings quoted, arrays bracketed).
fn json<T: Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_else(|e| format!("<{e}>"))
}
