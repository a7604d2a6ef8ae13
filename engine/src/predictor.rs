//! From a recording to a verdict, once for every front end: `classify`, the
//! console's Predict, the replay browser's list and the end of a scan
//! followed live all ask a [`Predictor`], so they cannot disagree.
//!
//! A predictor is a trained [`Model`] with the analysis it was trained
//! under. It decides three things no caller decides for itself:
//! - **whole or sub-windows**: under `[analysis] windows` a recording is
//!   classified by the vote of its sub-windows, else by its one feature
//!   vector ([`Query`]);
//! - **leave-out**: a recording that is one of the model's training
//!   examples is predicted by the model trained again without it (so a
//!   training scan is not its own nearest neighbour); when that leaves no
//!   example of its texture, there is no answer that could be right and the
//!   predictor says so ([`PredictError::NoOtherScans`]) instead of
//!   guessing another texture;
//! - **incomplete scans**: one is classified when its samples cover the
//!   analysis, and the answer says it was incomplete; when they do not, the
//!   one error says both things.
//!
//! Never prints; errors are [`PredictError`].

use std::path::Path;

use thiserror::Error;

use crate::analysis::FeatureExtractor;
use crate::classify::{ClassifyError, Model, Prediction, RecordingPrediction};
use crate::dataset::{self, DatasetError};
use crate::profile::Method;
use crate::recording::Recording;

/// Why there is no answer for a recording.
#[derive(Debug, Error)]
pub enum PredictError {
    /// The recording's features could not be made (with the reason it was
    /// incomplete, when it was).
    #[error("{source}{}", incomplete_suffix(.incomplete))]
    Features {
        source: DatasetError,
        incomplete: Option<String>,
    },
    #[error(transparent)]
    Classify(#[from] ClassifyError),
    #[error(
        "this scan is the model's only training scan, and a scan is predicted \
         with itself left out: store scans of other textures and train again"
    )]
    OnlyScan,
    #[error(
        "{label} has no other scans: this scan is one of the model's training scans and is \
         predicted with itself left out, so no answer could be right; store more scans of \
         {label} and train again"
    )]
    NoOtherScans { label: String },
    #[error("the model votes over sub-windows but the profile has no [analysis] windows")]
    NoSubWindows,
    /// The answer would take more value operations than
    /// [`crate::classify::MAX_COMPARISONS`] ([`answer_work`]); `what`
    /// says which and what to do.
    #[error("{file}: {what}")]
    TooMuchWork { file: String, what: String },
}

fn incomplete_suffix(incomplete: &Option<String>) -> String {
    incomplete
        .as_ref()
        .map_or(String::new(), |why| format!(" (incomplete scan: {why})"))
}

impl PredictError {
    /// Whether the user can fix it (exit code 2) rather than a runtime failure.
    pub fn is_bad_input(&self) -> bool {
        match self {
            PredictError::Features { source, .. } => source.is_bad_input(),
            _ => true,
        }
    }

    /// Whether the recording simply has no possible answer (left out of a
    /// model that then lacks its texture), rather than a failure.
    pub fn is_unanswerable(&self) -> bool {
        matches!(
            self,
            PredictError::OnlyScan | PredictError::NoOtherScans { .. }
        )
    }
}

/// What a recording is classified by: its feature vector, or its
/// sub-windows' feature vectors (under `[analysis] windows`).
#[derive(Debug, Clone, PartialEq)]
pub enum Features {
    Whole(Vec<f64>),
    Windows(Vec<Vec<f64>>),
}

/// A recording made ready to classify: its features as the analysis says,
/// and why it was incomplete, if it was.
#[derive(Debug, Clone, PartialEq)]
pub struct Query {
    pub features: Features,
    pub incomplete: Option<String>,
}

/// Why a recording is incomplete (`None` when it is complete).
pub fn incomplete_reason(rec: &Recording) -> Option<String> {
    (!rec.is_complete()).then(|| rec.aborted().unwrap_or("no end marker").to_string())
}

impl Query {
    /// The recording's features under the extractor's analysis: its
    /// sub-windows' when the analysis cuts them, else the whole window's.
    pub fn of(
        rec: &Recording,
        file: &Path,
        ex: &mut FeatureExtractor,
    ) -> Result<Query, PredictError> {
        let incomplete = incomplete_reason(rec);
        let features = if ex.settings().windows.is_some() {
            dataset::window_features_of(rec, file, ex).map(Features::Windows)
        } else {
            dataset::features_of(rec, file, ex).map(Features::Whole)
        };
        match features {
            Ok(features) => Ok(Query {
                features,
                incomplete,
            }),
            Err(source) => Err(PredictError::Features { source, incomplete }),
        }
    }
}

/// A recording's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Answer {
    /// The prediction. For a vote over sub-windows: the label and, as
    /// votes, the sub-windows that chose each class; no neighbours (they
    /// are per sub-window).
    pub prediction: Prediction,
    /// The vote over sub-windows, with its tally and each one's outcome.
    pub windows: Option<RecordingPrediction>,
    /// The recording was one of the training examples and was left out.
    pub left_out: bool,
    /// Why the recording was incomplete, when it was (classified anyway).
    pub incomplete: Option<String>,
}

impl Answer {
    fn of_windows(p: RecordingPrediction) -> Answer {
        Answer {
            prediction: Prediction {
                label: p.label.clone(),
                votes: p
                    .tally
                    .iter()
                    .map(|t| (t.label.clone(), t.windows))
                    .collect(),
                neighbours: Vec::new(),
            },
            windows: Some(p),
            left_out: false,
            incomplete: None,
        }
    }
}

/// A trained model and its analysis, answering for recordings (see the
/// module documentation).
#[derive(Debug, Clone, Copy)]
pub struct Predictor<'m> {
    model: &'m Model,
}

impl<'m> Predictor<'m> {
    pub fn new(model: &'m Model) -> Predictor<'m> {
        Predictor { model }
    }

    pub fn model(&self) -> &'m Model {
        self.model
    }

    /// An extractor for the model's analysis.
    pub fn extractor(&self) -> FeatureExtractor {
        FeatureExtractor::new(&self.model.analysis)
    }

    /// The answer for a recording read from `file`.
    pub fn answer_recording(
        &self,
        rec: &Recording,
        file: &Path,
        ex: &mut FeatureExtractor,
    ) -> Result<Answer, PredictError> {
        let q = Query::of(rec, file, ex)?;
        self.answer(&q, file)
    }

    /// The answer for a recording's features (made by [`Query::of`] under
    /// the model's analysis), `file` naming it for the leave-out.
    pub fn answer(&self, q: &Query, file: &Path) -> Result<Answer, PredictError> {
        // Which of the model's examples are this recording's, asked once
        // (a name comparison, or two paths made canonical, per example).
        let same = self.same_recording(file, q);
        let own: Vec<bool> = self.model.examples.iter().map(|e| same(&e.file)).collect();
        self.check_work(q, file, own.iter().filter(|&&o| o).count())?;
        match (&q.features, self.model.analysis.windows.is_some()) {
            (Features::Whole(_), true) => return Err(PredictError::NoSubWindows),
            // A model of whole windows classifies the first sub-window's
            // features only if they were its own: they are not.
            (Features::Windows(_), false) => {
                return Err(ClassifyError::Settings(
                    "the recording was cut into sub-windows but the model was not".into(),
                )
                .into());
            }
            _ => {}
        }
        let reduced = if own.contains(&true) {
            Some(self.without(&own)?)
        } else {
            None
        };
        let model = reduced.as_ref().unwrap_or(self.model);
        let mut a = match &q.features {
            Features::Windows(w) => Answer::of_windows(model.classify_windows(w)?),
            Features::Whole(f) => Answer {
                prediction: model.classify(f)?,
                windows: None,
                left_out: false,
                incomplete: None,
            },
        };
        a.left_out = reduced.is_some();
        a.incomplete.clone_from(&q.incomplete);
        Ok(a)
    }

    /// Refuses a query whose answer would take more than
    /// [`crate::classify::MAX_COMPARISONS`] value operations
    /// ([`answer_work`]), before any is made; `own` is how many of the
    /// model's examples are the recording's (left out first).
    fn check_work(&self, q: &Query, file: &Path, own: usize) -> Result<(), PredictError> {
        let queries = match &q.features {
            Features::Whole(_) => 1,
            Features::Windows(w) => w.len(),
        };
        let work = answer_work(self.model, queries, own);
        if work.classify <= crate::classify::MAX_COMPARISONS {
            return Ok(());
        }
        Err(PredictError::TooMuchWork {
            file: file.display().to_string(),
            what: work.describe(self.model, queries),
        })
    }

    /// Whether `file` is one of the model's training recordings (the same
    /// name, or the same file on disk).
    pub fn trained_on(&self, file: &Path) -> bool {
        let same = same_file(file);
        self.model.examples.iter().any(|e| same(&e.file))
    }

    /// "Names the same recording as `file`": by its name, or, moved since
    /// training, by its features ([`Self::moved_here`]).
    fn same_recording(&self, file: &Path, q: &Query) -> impl Fn(&str) -> bool {
        let named = same_file(file);
        let moved = self.moved_here(q);
        move |f: &str| named(f) || moved.as_deref() == Some(f)
    }

    /// The model trained again without the examples `own` marks (k as
    /// the profile asked, chosen again without them where it needed
    /// choosing: no leak of the test scan); an error when that leaves no
    /// example of their label, or none at all.
    fn without(&self, own: &[bool]) -> Result<Model, PredictError> {
        let examples = &self.model.examples;
        let mine = examples
            .iter()
            .zip(own)
            .find(|&(_, &o)| o)
            .map(|(e, _)| e)
            .ok_or(PredictError::OnlyScan)?;
        let rest: Vec<_> = examples
            .iter()
            .zip(own)
            .filter(|&(_, &o)| !o)
            .map(|(e, _)| e.clone())
            .collect();
        if rest.is_empty() {
            return Err(PredictError::OnlyScan);
        }
        if !rest.iter().any(|e| e.label == mine.label) {
            return Err(PredictError::NoOtherScans {
                label: mine.label.clone(),
            });
        }
        let m = self.model;
        Ok(Model::train_adapting_k(
            &m.profile,
            &m.analysis,
            &m.asked_classifier(),
            rest,
        )?)
    }

    /// The training recording whose file is gone and whose feature vectors
    /// are the query's, bit for bit: the same samples moved since training
    /// (relabelled into another label folder, say), so the same recording.
    /// Two recordings never give identical vectors; a copy that still
    /// exists is left to [`same_file`].
    fn moved_here(&self, q: &Query) -> Option<String> {
        let wanted: Vec<&[f64]> = match &q.features {
            Features::Whole(f) => vec![f.as_slice()],
            Features::Windows(w) => w.iter().map(Vec::as_slice).collect(),
        };
        self.model
            .examples
            .chunk_by(|a, b| a.file == b.file)
            .find(|own| {
                own.len() == wanted.len()
                    && own.iter().zip(&wanted).all(|(e, w)| e.features == *w)
                    && !Path::new(&own[0].file).exists()
            })
            .map(|own| own[0].file.clone())
    }
}

/// The value operations of answering `queries` feature vectors with a
/// model. When the recording is one of its training recordings the model
/// is trained again without it first; that is not counted: it is the fit
/// `train` made of the model, on fewer examples, so it takes no longer
/// than that did (an LDA of the kernels on 1,043 half-second windows of
/// the long IMU set: 1.5 s, as its `train`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Work {
    /// Classifying: each query against every example classified against
    /// (k-NN), one score a label (ridge, LDA).
    pub classify: f64,
    /// The examples classified against (all but the recording's own).
    pub examples: usize,
    /// Features a vector, as the classifier sees them.
    pub features: usize,
}

impl Work {
    /// What the work is, over the limit, and what to do, in one line.
    fn describe(&self, model: &Model, queries: usize) -> String {
        let Work {
            examples: n,
            features: p,
            ..
        } = *self;
        let limit = crate::classify::MAX_COMPARISONS;
        let fewer = "train the model with a longer windows.hop or a shorter windows.length (fewer sub-windows), or fewer bins";
        let its = if model.analysis.windows.is_some() {
            format!("its {queries} sub-window(s)")
        } else {
            "it".to_string()
        };
        let total = self.classify;
        match model.classifier.method {
            Method::Knn => format!(
                "classifying {its} against the model's {n} training vectors of {p} features compares {total:.1e} values, over the limit of {limit:.0e} that keeps a prediction within seconds; {fewer}"
            ),
            method => format!(
                "scoring {its} ({p} features) for {} labels with the {} takes {total:.1e} multiply-adds, over the limit of {limit:.0e} that keeps a prediction within seconds; {fewer}",
                model.labels.len(),
                method.name()
            ),
        }
    }
}

/// The [`Work`] of answering `queries` feature vectors with `model`, `own`
/// of whose examples are the recording's (left out first when there are
/// any).
pub fn answer_work(model: &Model, queries: usize, own: usize) -> Work {
    let n = model.examples.len().saturating_sub(own);
    let p = model.fitted_feature_count();
    let classify = match model.classifier.method {
        Method::Knn => crate::classify::comparisons(queries, n, p),
        Method::Ridge | Method::Lda => queries as f64 * p as f64 * model.labels.len() as f64,
    };
    Work {
        classify,
        examples: n,
        features: p,
    }
}

/// A test of "names the same recording as `file`": the same text, the same
/// file once both are canonical, or — when the name the model kept no
/// longer exists, its session folder moved or renamed since training — the
/// same label folder and file name (`S1/S1_003.csv`). Without the last, a
/// training scan of a moved folder would be its own nearest neighbour.
fn same_file(file: &Path) -> impl Fn(&str) -> bool {
    let name = file.display().to_string();
    let canonical = std::fs::canonicalize(file).ok();
    let tail = label_and_name(file);
    move |f: &str| {
        f == name
            || canonical
                .as_ref()
                .is_some_and(|c| std::fs::canonicalize(f).ok().as_ref() == Some(c))
            || (tail.is_some() && label_and_name(Path::new(f)) == tail && !Path::new(f).exists())
    }
}

/// A recording's label folder and file name.
fn label_and_name(p: &Path) -> Option<(&std::ffi::OsStr, &std::ffi::OsStr)> {
    Some((p.parent()?.file_name()?, p.file_name()?))
}

#[cfg(test)]
mod tests;
