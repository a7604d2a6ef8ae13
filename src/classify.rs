//! The k-nearest-neighbour classifier (section 3.3.2) and its model file.
//!
//! A [`Model`] is the training examples themselves plus the settings that
//! made their features: classifying a scan analysed with other settings is
//! refused ([`Model::check_settings`]). The model file is pretty-printed JSON
//! with a `format` tag. This module knows nothing of recordings or devices:
//! examples come in as feature vectors with their file name and label.
//!
//! Classification: Euclidean distance to every training example, the `k`
//! nearest vote, the majority wins. A tie between classes goes to the class
//! whose neighbours' distances add up to less, then to the class whose label
//! sorts first. Neighbours at equal distance keep the training order.

use std::cmp::Ordering;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::analysis;
use crate::profile::{Analysis, Classifier};

/// The `format` tag of a model file this version reads and writes.
pub const MODEL_FORMAT: &str = "hapticlab model v1";

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
    /// The hapticlab version that trained it.
    pub software_version: String,
    /// The name of the profile it was trained under.
    pub profile: String,
    pub analysis: Analysis,
    pub classifier: Classifier,
    /// The distinct labels of the examples, sorted.
    pub labels: Vec<String>,
    pub examples: Vec<TrainingExample>,
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
    #[error("feature {index} of the scan is not a finite number ({value})")]
    QueryNonFinite { index: usize, value: f64 },
    #[error("the model's analysis settings are unusable: {0}")]
    Settings(String),
    #[error(
        "the model was trained with {field} = {model} but the profile has {field} = {profile}; \
         retrain the model under this profile"
    )]
    SettingsDiffer {
        field: &'static str,
        model: String,
        profile: String,
    },
    #[error("{}: {source}", path.display())]
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
    if classifier.k == 0 {
        return Err(ClassifyError::KZero);
    }
    if classifier.k > examples.len() {
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

/// Squared Euclidean distance; four partial sums let the compiler vectorise.
fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            let d = x[l] - y[l];
            acc[l] += d * d;
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        let d = x - y;
        tail += d * d;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

impl Model {
    pub fn train(
        profile_name: &str,
        analysis: &Analysis,
        classifier: &Classifier,
        examples: Vec<TrainingExample>,
    ) -> Result<Model, ClassifyError> {
        check_parts(analysis, classifier, &examples)?;
        Ok(Model {
            format: MODEL_FORMAT.to_string(),
            software_version: env!("CARGO_PKG_VERSION").to_string(),
            profile: profile_name.to_string(),
            analysis: analysis.clone(),
            classifier: classifier.clone(),
            labels: sorted_labels(&examples),
            examples,
        })
    }

    /// Number of features a query must have.
    pub fn feature_count(&self) -> usize {
        self.analysis.feature_count()
    }

    pub fn classify(&self, features: &[f64]) -> Result<Prediction, ClassifyError> {
        let expected = self.feature_count();
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
        let k = self.classifier.k.clamp(1, self.examples.len());

        // The k smallest squared distances, ascending, by bounded insertion:
        // a later example at an equal distance goes after the earlier one.
        let mut nearest: Vec<(f64, usize)> = Vec::with_capacity(k);
        for (index, ex) in self.examples.iter().enumerate() {
            let d2 = squared_distance(features, &ex.features);
            if nearest.len() == k {
                if d2 >= nearest[k - 1].0 {
                    continue;
                }
                nearest.pop();
            }
            let at = nearest.partition_point(|&(d, _)| d <= d2);
            nearest.insert(at, (d2, index));
        }

        let classes = self.labels.len();
        let mut count = vec![0usize; classes];
        let mut summed = vec![0.0f64; classes];
        let mut neighbours = Vec::with_capacity(k);
        for &(d2, index) in &nearest {
            let ex = &self.examples[index];
            let class =
                self.labels
                    .binary_search(&ex.label)
                    .map_err(|_| ClassifyError::UnknownLabel {
                        file: ex.file.clone(),
                        label: ex.label.clone(),
                    })?;
            let distance = d2.sqrt();
            count[class] += 1;
            summed[class] += distance;
            neighbours.push(Neighbour {
                file: ex.file.clone(),
                label: ex.label.clone(),
                distance,
            });
        }

        // Most votes first; among equal votes the smaller summed distance,
        // then the label order (classes with no vote have nothing to sum).
        let mut order: Vec<usize> = (0..classes).collect();
        order.sort_by(|&a, &b| {
            count[b]
                .cmp(&count[a])
                .then_with(|| {
                    if count[a] > 0 {
                        summed[a].total_cmp(&summed[b])
                    } else {
                        Ordering::Equal
                    }
                })
                .then(a.cmp(&b))
        });
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

    /// Write the model as pretty-printed JSON.
    pub fn save(&self, path: &Path) -> Result<(), ClassifyError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| ClassifyError::Invalid {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        text.push('\n');
        std::fs::write(path, text).map_err(|source| ClassifyError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Read and check a model file.
    pub fn load(path: &Path) -> Result<Model, ClassifyError> {
        let text = std::fs::read_to_string(path).map_err(|source| ClassifyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// Parse a model from its JSON text; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Model, ClassifyError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| ClassifyError::Malformed {
                path: path.to_path_buf(),
                line: e.line(),
                column: e.column(),
                message: strip_position(&e),
            })?;
        match value.get("format") {
            Some(serde_json::Value::String(f)) if f == MODEL_FORMAT => {}
            Some(serde_json::Value::String(f)) => {
                return Err(ClassifyError::WrongFormat {
                    path: path.to_path_buf(),
                    found: f.clone(),
                });
            }
            _ => {
                return Err(ClassifyError::NotAModel {
                    path: path.to_path_buf(),
                });
            }
        }
        // Parse the text again (not the value) so schema errors carry a line and column.
        let model: Model = serde_json::from_str(text).map_err(|e| ClassifyError::Schema {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: strip_position(&e),
        })?;
        let invalid = |reason: String| ClassifyError::Invalid {
            path: path.to_path_buf(),
            reason,
        };
        check_parts(&model.analysis, &model.classifier, &model.examples)
            .map_err(|e| invalid(e.to_string()))?;
        if model.labels != sorted_labels(&model.examples) {
            return Err(invalid(
                "its labels are not the sorted distinct labels of its examples".to_string(),
            ));
        }
        Ok(model)
    }

    /// Using the model on features made with other analysis settings is an
    /// error naming the first field that differs.
    pub fn check_settings(&self, analysis: &Analysis) -> Result<(), ClassifyError> {
        let (m, p) = (&self.analysis, analysis);
        let differ = |field: &'static str, model: String, profile: String| {
            Err(ClassifyError::SettingsDiffer {
                field,
                model,
                profile,
            })
        };
        if m.channel != p.channel {
            return differ("analysis.channel", json(&m.channel), json(&p.channel));
        }
        if m.axis != p.axis {
            return differ("analysis.axis", json(&m.axis), json(&p.axis));
        }
        if m.window != p.window {
            return differ("analysis.window", json(&m.window), json(&p.window));
        }
        if m.spacing != p.spacing {
            return differ("analysis.spacing", json(&m.spacing), json(&p.spacing));
        }
        if m.detrend != p.detrend {
            return differ("analysis.detrend", json(&m.detrend), json(&p.detrend));
        }
        if m.spectrum != p.spectrum {
            return differ("analysis.spectrum", json(&m.spectrum), json(&p.spectrum));
        }
        if m.bins != p.bins {
            return differ("analysis.bins", json(&m.bins), json(&p.bins));
        }
        Ok(())
    }
}

/// serde_json's message without its trailing " at line L column C" (we
/// print the position in front, compiler style).
fn strip_position(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// A settings value as it is written in JSON (strings quoted, arrays bracketed).
fn json<T: Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_else(|e| format!("<{e}>"))
}
