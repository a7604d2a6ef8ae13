//! The session's dataset folder as the console sees it, and the slow work
//! on it (training, evaluating, listing recordings with their predictions),
//! which runs on worker threads so the screen keeps moving.
//!
//! Results come back through a channel that the console polls once per
//! frame, like telemetry. Nothing here prints: the headless commands' loader
//! draws progress bars on standard error, which would corrupt the screen,
//! so recordings are loaded quietly here and incomplete ones counted.

use std::path::{Path, PathBuf};

use crossbeam_channel::{Receiver, Sender, unbounded};

use crate::analysis::FeatureExtractor;
use crate::classify::{Model, TrainingExample};
use crate::evaluate::{self, Report};
use crate::profile::LoadedProfile;
use crate::recording;

/// The model file the console writes into (and reads from) a dataset folder.
pub const MODEL_FILE: &str = "model.json";
/// Where scans are recorded while they run, inside the dataset folder.
pub const UNSAVED_DIR: &str = ".unsaved";

#[derive(Debug, Clone, Default, PartialEq)]
pub struct DatasetView {
    pub dir: PathBuf,
    /// Recordings per label folder.
    pub counts: Vec<(String, usize)>,
    /// Scans waiting in `.unsaved/`.
    pub unsaved: usize,
    pub model: Option<ModelInfo>,
    pub report: Option<Report>,
    /// Work in progress ("training on 120 recordings…").
    pub busy: Option<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    pub examples: usize,
    pub labels: Vec<String>,
    pub k: usize,
    /// Where it came from or was saved.
    pub file: Option<PathBuf>,
}

impl ModelInfo {
    pub fn of(model: &Model, file: Option<PathBuf>) -> ModelInfo {
        ModelInfo {
            examples: model.examples.len(),
            labels: model.labels.clone(),
            k: model.classifier.k,
            file,
        }
    }
}

impl DatasetView {
    pub fn total(&self) -> usize {
        self.counts.iter().map(|(_, n)| n).sum()
    }
}

fn is_recording(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.ends_with(".csv") || n.ends_with(".csv.gz")
}

fn count_files(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |rd| {
        rd.filter_map(Result::ok)
            .filter(|e| is_recording(&e.file_name().to_string_lossy()))
            .count()
    })
}

/// Recordings per label folder under `dir` (label folders sorted), and the
/// number waiting in `.unsaved/`. A missing folder is an empty dataset.
pub fn count(dir: &Path) -> (Vec<(String, usize)>, usize) {
    let mut counts = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.filter_map(Result::ok) {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || !e.path().is_dir() {
                continue;
            }
            let n = count_files(&e.path());
            if n > 0 {
                counts.push((name, n));
            }
        }
    }
    counts.sort();
    (counts, count_files(&dir.join(UNSAVED_DIR)))
}

/// Complete recordings under `dir` as training examples, quietly; the
/// number of incomplete ones skipped.
pub fn load_examples(
    dir: &Path,
    ex: &mut FeatureExtractor,
) -> Result<(Vec<TrainingExample>, usize), String> {
    let files = recording::collect_files(&[dir.to_path_buf()]).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(files.len());
    let mut skipped = 0;
    for f in &files {
        let rec = recording::read(f).map_err(|e| e.to_string())?;
        if !rec.is_complete() {
            skipped += 1;
            continue;
        }
        out.push(crate::commands::example_of(&rec, f, ex).map_err(|e| e.message().to_string())?);
    }
    if out.is_empty() {
        return Err(format!(
            "no complete recordings in {} to train on",
            dir.display()
        ));
    }
    Ok((out, skipped))
}

/// A recording in the replay browser's list.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayEntry {
    pub path: PathBuf,
    pub label: Option<String>,
    pub predicted: Option<String>,
}

impl ReplayEntry {
    /// Whether the prediction matched the label, when both are known.
    pub fn right(&self) -> Option<bool> {
        Some(self.label.as_ref()? == self.predicted.as_ref()?)
    }
}

/// What a worker reports.
#[derive(Debug)]
pub enum JobResult {
    Trained {
        model: Box<Model>,
        skipped: usize,
        saved: Result<PathBuf, String>,
        then_predict: bool,
    },
    Evaluated(Box<Report>),
    Listed {
        entries: Vec<ReplayEntry>,
        /// The model the predictions came from, when one was trained for it.
        model: Option<Box<Model>>,
    },
    Failed {
        what: &'static str,
        error: String,
    },
}

/// Worker threads and the channel their results come back on.
pub struct Jobs {
    tx: Sender<JobResult>,
    rx: Receiver<JobResult>,
}

impl Default for Jobs {
    fn default() -> Self {
        let (tx, rx) = unbounded();
        Jobs { tx, rx }
    }
}

impl Jobs {
    fn spawn(&self, f: impl FnOnce() -> JobResult + Send + 'static) {
        let tx = self.tx.clone();
        let spawned = std::thread::Builder::new()
            .name("console-job".into())
            .spawn(move || {
                let _ = tx.send(f());
            });
        if let Err(e) = spawned {
            let _ = self.tx.send(JobResult::Failed {
                what: "start a worker",
                error: e.to_string(),
            });
        }
    }

    /// Results that have arrived; never waits.
    pub fn poll(&self) -> Vec<JobResult> {
        self.rx.try_iter().collect()
    }

    /// Train on every complete recording in `dir`; save the model there.
    pub fn train(&self, lp: &LoadedProfile, dir: &Path, then_predict: bool) {
        let (lp, dir) = (lp.clone(), dir.to_path_buf());
        self.spawn(move || match train(&lp, &dir) {
            Ok((model, skipped)) => {
                let file = dir.join(MODEL_FILE);
                let saved = model.save(&file).map(|()| file).map_err(|e| e.to_string());
                JobResult::Trained {
                    model: Box::new(model),
                    skipped,
                    saved,
                    then_predict,
                }
            }
            Err(error) => JobResult::Failed {
                what: "train",
                error,
            },
        });
    }

    /// Split `dir` as the profile's `[evaluation]` says, train, test.
    pub fn evaluate(&self, lp: &LoadedProfile, dir: &Path) {
        let (lp, dir) = (lp.clone(), dir.to_path_buf());
        self.spawn(move || {
            let run = || -> Result<Report, String> {
                let mut ex = FeatureExtractor::new(&lp.profile.analysis);
                let (examples, _) = load_examples(&dir, &mut ex)?;
                let split =
                    evaluate::split(examples, &lp.profile.evaluation).map_err(|e| e.to_string())?;
                let model = Model::train(
                    &lp.profile.name,
                    &lp.profile.analysis,
                    &lp.profile.classifier,
                    split.train,
                )
                .map_err(|e| e.to_string())?;
                evaluate::evaluate(&model, &split.test).map_err(|e| e.to_string())
            };
            match run() {
                Ok(r) => JobResult::Evaluated(Box::new(r)),
                Err(error) => JobResult::Failed {
                    what: "evaluate",
                    error,
                },
            }
        });
    }

    /// Label and predict every recording in `files`, with `model` or, when
    /// there is none, one trained on `train_dir` if it can be.
    pub fn list(
        &self,
        lp: &LoadedProfile,
        files: Vec<PathBuf>,
        model: Option<Model>,
        train_dir: Option<PathBuf>,
    ) {
        let lp = lp.clone();
        self.spawn(move || {
            let mut trained = None;
            let model = match model {
                Some(m) => Some(m),
                None => train_dir.and_then(|d| train(&lp, &d).ok()).map(|(m, _)| {
                    trained = Some(Box::new(m.clone()));
                    m
                }),
            };
            let mut ex = FeatureExtractor::new(&lp.profile.analysis);
            let entries = files
                .into_iter()
                .map(|path| {
                    let rec = recording::read(&path).ok();
                    let label = rec.as_ref().and_then(|r| r.label().map(str::to_string));
                    let predicted = match (&rec, &model) {
                        (Some(r), Some(m)) => crate::commands::features_of(r, &path, &mut ex)
                            .ok()
                            .and_then(|f| super::scan::predict(m, &f, &path).ok())
                            .map(|p| p.prediction.label),
                        _ => None,
                    };
                    ReplayEntry {
                        path,
                        label,
                        predicted,
                    }
                })
                .collect();
            JobResult::Listed {
                entries,
                model: trained,
            }
        });
    }
}

fn train(lp: &LoadedProfile, dir: &Path) -> Result<(Model, usize), String> {
    let mut ex = FeatureExtractor::new(&lp.profile.analysis);
    let (examples, skipped) = load_examples(dir, &mut ex)?;
    let model = Model::train(
        &lp.profile.name,
        &lp.profile.analysis,
        &lp.profile.classifier,
        examples,
    )
    .map_err(|e| e.to_string())?;
    Ok((model, skipped))
}

/// A model saved in the dataset folder by an earlier session, if it fits
/// the profile's analysis settings.
pub fn load_saved_model(lp: &LoadedProfile, dir: &Path) -> Option<(Model, PathBuf)> {
    let file = dir.join(MODEL_FILE);
    let model = Model::load(&file).ok()?;
    model.check_settings(&lp.profile.analysis).ok()?;
    Some((model, file))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_label_folders_and_unsaved_scans() {
        let d = tempfile::tempdir().unwrap();
        for (label, n) in [("S2", 3), ("S1", 2)] {
            std::fs::create_dir_all(d.path().join(label)).unwrap();
            for i in 0..n {
                std::fs::write(d.path().join(label).join(format!("{label}_{i}.csv")), "").unwrap();
            }
        }
        std::fs::create_dir_all(d.path().join(UNSAVED_DIR)).unwrap();
        std::fs::write(d.path().join(UNSAVED_DIR).join("scan-001.csv"), "").unwrap();
        let (counts, unsaved) = count(d.path());
        assert_eq!(counts, vec![("S1".into(), 2), ("S2".into(), 3)]);
        assert_eq!(unsaved, 1);
        assert_eq!(count(&d.path().join("missing")), (vec![], 0));
    }
}
