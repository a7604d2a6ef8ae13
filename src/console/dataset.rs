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

use super::app::App;
use super::keymap::Key;
use crate::analysis::FeatureExtractor;
use crate::classify::{Model, TrainingExample};
use crate::dataset;
use crate::evaluate::Report;
use crate::evaluate::request::{self, Evaluation, Request};
use crate::profile::{Analysis, LoadedProfile, Method};
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
    /// Why the model saved in the folder is not used (other settings).
    pub model_note: Option<String>,
    pub report: Option<Report>,
    /// How the last evaluation split the recordings ("leave-one-out").
    pub report_method: Option<String>,
    /// Where the last evaluation's report was written.
    pub report_file: Option<PathBuf>,
    /// Work in progress ("training on 120 recordings…").
    pub busy: Option<String>,
    /// Curating changes since the model was trained (or loaded).
    pub edits: usize,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelInfo {
    pub examples: usize,
    pub labels: Vec<String>,
    pub k: usize,
    /// The classifier: a ridge or an LDA has no k.
    pub method: Method,
    /// Where it came from or was saved.
    pub file: Option<PathBuf>,
    /// Incomplete recordings in the folder that training skipped: with the
    /// examples, the recordings the model accounts for.
    pub skipped: usize,
    /// Why k is not the profile's ([`Model::k_notice`]).
    pub k_notice: Option<String>,
    /// How the folder's recordings differ from those the model was
    /// trained on, when it was saved by an earlier session ("1 added,
    /// 2 gone since"): a curating change in that session, or by hand.
    pub changed: Option<String>,
}

impl ModelInfo {
    pub fn of(model: &Model, file: Option<PathBuf>) -> ModelInfo {
        ModelInfo {
            examples: model.examples.len(),
            labels: model.labels.clone(),
            k: model.classifier.k,
            method: model.classifier.method,
            file,
            skipped: 0,
            k_notice: model.k_notice(),
            changed: None,
        }
    }
}

impl DatasetView {
    pub fn total(&self) -> usize {
        self.counts.iter().map(|(_, n)| n).sum()
    }

    /// "trained on 21 recordings, the dataset has 22" when the folder's
    /// recordings are not the ones the model was trained on (by count).
    pub fn stale_model(&self) -> Option<String> {
        let m = self.model.as_ref()?;
        if self.edits > 0 {
            return Some(format!(
                "trained before {} to the dataset",
                crate::classify::plural(self.edits, "change", "changes")
            ));
        }
        if let Some(c) = &m.changed {
            return Some(c.clone());
        }
        let usable = self.total().saturating_sub(m.skipped);
        (usable != m.examples).then(|| {
            format!(
                "trained on {}, the dataset has {usable}",
                crate::classify::plural(m.examples, "recording", "recordings")
            )
        })
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

/// Complete recordings under `dir` as training examples, read on every
/// core and quietly ([`crate::dataset::load`]); the number of incomplete
/// ones skipped.
pub fn load_examples(
    dir: &Path,
    analysis: &Analysis,
) -> Result<(Vec<TrainingExample>, usize), String> {
    let files = dataset::find(&[dir.to_path_buf()]).map_err(|e| e.to_string())?;
    let loaded = dataset::load(&files, analysis, dataset::Options::default(), &|| {})
        .map_err(|e| e.to_string())?;
    let skipped = loaded.skipped.len();
    let out = loaded.into_examples();
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
    /// Whether the recording ended complete, once read.
    pub complete: Option<bool>,
}

impl ReplayEntry {
    /// The label, or before the list is predicted, the folder's name
    /// (`<label>/<label>_NNN.csv`).
    pub fn label_or_folder(&self) -> String {
        self.label.clone().unwrap_or_else(|| {
            self.path
                .parent()
                .and_then(Path::file_name)
                .map_or(String::new(), |n| n.to_string_lossy().into_owned())
        })
    }

    /// Whether it is a scan not stored yet (in `<dataset>/.unsaved/`).
    pub fn unsaved(&self, dataset: &Path) -> bool {
        self.path.strip_prefix(dataset.join(UNSAVED_DIR)).is_ok()
    }

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
    Evaluated(Box<Evaluated>),
    Listed {
        entries: Vec<ReplayEntry>,
        /// The model the predictions came from, when one was trained for it.
        model: Option<Box<Model>>,
        /// Incomplete recordings that training skipped.
        skipped: usize,
    },
    Failed {
        what: &'static str,
        error: String,
    },
}

/// How much nicer than the console (and its servo) training and evaluating
/// run: the loop keeps its rate on a machine they keep busy.
pub const JOB_NICENESS: i32 = 10;

/// Lower the calling thread's priority by [`JOB_NICENESS`] (Linux: the
/// nice value is per thread, and the threads it starts inherit it). Best
/// effort: a failure leaves the priority as it was.
pub fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: getpriority/setpriority on the calling thread's own id have
    // no memory-safety preconditions.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        let now = libc::getpriority(libc::PRIO_PROCESS, tid);
        libc::setpriority(libc::PRIO_PROCESS, tid, (now + JOB_NICENESS).min(19));
    }
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
                lower_priority();
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
                let saved = model
                    .save(&file, &[], crate::io::Existing::Replace)
                    .map(|()| file)
                    .map_err(|e| e.to_string());
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

    /// Evaluate on `dir` as the profile's `[evaluation]` says; when its
    /// holdout split cannot be met, by stratified k-fold or leave-one-out.
    pub fn evaluate(&self, lp: &LoadedProfile, dir: &Path) {
        let (lp, dir) = (lp.clone(), dir.to_path_buf());
        self.spawn(move || match evaluate_dataset(&lp, &dir) {
            Ok(e) => JobResult::Evaluated(Box::new(e)),
            Err(error) => JobResult::Failed {
                what: "evaluate",
                error,
            },
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
            let (mut trained, mut skipped) = (None, 0);
            let model = match model {
                Some(m) => Some(m),
                None => train_dir.and_then(|d| train(&lp, &d).ok()).map(|(m, n)| {
                    trained = Some(Box::new(m.clone()));
                    skipped = n;
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
                        (Some(r), Some(m)) => super::scan::predict_recording(m, r, &path, &mut ex)
                            .ok()
                            .map(|p| p.prediction.label),
                        _ => None,
                    };
                    ReplayEntry {
                        path,
                        label,
                        predicted,
                        complete: rec.as_ref().map(recording::Recording::is_complete),
                    }
                })
                .collect();
            JobResult::Listed {
                entries,
                model: trained,
                skipped,
            }
        });
    }
}

/// The console's evaluation of its dataset, as the engine makes it for
/// `hapticlab evaluate DIR --fallback`: the profile's `[evaluation]`, or,
/// when the dataset cannot meet it, the small-data fallback.
#[derive(Debug)]
pub struct Evaluated {
    pub report: Report,
    /// How it was split ("leave-one-out").
    pub method: String,
    /// Why not as the profile says, and why k is not the profile's: one
    /// line, or empty.
    pub note: String,
    /// Where the report was written (text and JSON), or why it was not.
    pub saved: Result<PathBuf, String>,
}

/// The report files `e` writes beside the model: plain text (the
/// command's header and table) and JSON (`evaluate --json --fallback`'s,
/// plus the method, k and dataset state).
pub const REPORT_FILE: &str = "evaluation.txt";
pub const REPORT_JSON: &str = "evaluation.json";

/// Evaluate the complete recordings in `dir` (see [`Evaluated`]) and keep
/// the report in `dir`.
pub fn evaluate_dataset(lp: &LoadedProfile, dir: &Path) -> Result<Evaluated, String> {
    let mut req = Request::of_recordings(vec![dir.to_path_buf()]);
    req.fallback = true;
    let ev = request::run(lp, &req, &request::Quiet).map_err(|e| e.to_string())?;
    let Some(report) = ev.outcome.report().cloned() else {
        return Err("the evaluation gave no report".into());
    };
    let method = ev.plan.describe();
    let note: Vec<String> = ev
        .fell_back
        .clone()
        .into_iter()
        .chain(ev.outcome.k_notice())
        .collect();
    let saved = save_report(lp, dir, &ev).map(|()| dir.join(REPORT_FILE));
    Ok(Evaluated {
        report,
        method,
        note: note.join("; "),
        saved,
    })
}

/// Write [`REPORT_FILE`] and [`REPORT_JSON`] into `dir`, each whole or not
/// at all.
fn save_report(lp: &LoadedProfile, dir: &Path, ev: &Evaluation) -> Result<(), String> {
    use crate::support::evaluation_text::{header, k_text, table};
    let mut text = format!("{}\n{}", header(lp, ev), table(&ev.outcome));
    if let Some(note) = ev.outcome.k_notice() {
        text.push_str(&format!("note: {note}\n"));
    }
    let mut json = serde_json::to_value(&ev.outcome).map_err(|e| e.to_string())?;
    if let Some(o) = json.as_object_mut() {
        o.entry("method")
            .or_insert_with(|| ev.plan.describe().into());
        o.insert("k_used".into(), serde_json::json!(ev.outcome.k_used()));
        o.insert("k".into(), k_text(lp, ev).into());
        o.insert("fallback".into(), serde_json::json!(ev.fell_back));
        let model = dir.join(MODEL_FILE);
        o.insert(
            "dataset".into(),
            serde_json::json!({
                "folder": dir.display().to_string(),
                "profile": lp.profile.name,
                "recordings": ev.recordings,
                "skipped": ev.skipped.iter().map(ToString::to_string).collect::<Vec<_>>(),
                "model": model.exists().then(|| model.display().to_string()),
            }),
        );
    }
    let json = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
    // The console replaces only an evaluation it kept: a file of that name
    // that is none (a user's own, a FIFO) is left as it is.
    if let Err(why) = load_saved_report(dir) {
        return Err(format!(
            "{why}; it is no evaluation the console kept, so neither it nor {REPORT_FILE} was \
             replaced (the evaluation is shown, not kept)"
        ));
    }
    crate::support::write_atomically(
        &dir.join(REPORT_FILE),
        &[],
        crate::io::Existing::Replace,
        text.as_bytes(),
    )
    .and_then(|()| {
        crate::support::write_atomically(
            &dir.join(REPORT_JSON),
            &[],
            crate::io::Existing::Replace,
            json.as_bytes(),
        )
    })
    .map_err(|e| e.message().to_string())
}

fn train(lp: &LoadedProfile, dir: &Path) -> Result<(Model, usize), String> {
    let (examples, skipped) = load_examples(dir, &lp.profile.analysis)?;
    let model = Model::train_adapting_k(
        &lp.profile.name,
        &lp.profile.analysis,
        &lp.profile.classifier,
        examples,
    )
    .map_err(|e| e.to_string())?;
    Ok((model, skipped))
}

/// A model saved in the dataset folder by an earlier session, if it fits
/// the profile's analysis and classifier settings; otherwise why not (no
/// file is not a reason).
pub fn load_saved_model(
    lp: &LoadedProfile,
    dir: &Path,
) -> Result<Option<(Model, PathBuf)>, String> {
    let file = dir.join(MODEL_FILE);
    if !file.exists() {
        return Ok(None);
    }
    let not_used = |e: String| format!("{} not used: {e}", file.display());
    let model = Model::load(&file).map_err(|e| not_used(e.to_string()))?;
    model
        .check_settings(&lp.profile.analysis)
        .and_then(|()| model.check_classifier(&lp.profile.classifier))
        .map_err(|e| not_used(e.to_string()))?;
    Ok(Some((model, file)))
}

/// A kept report is a few lines per test recording: more is not one.
const KEPT_REPORT_MAX: u64 = 256 << 20;

/// The evaluation an earlier `e` kept in `dir` ([`REPORT_JSON`]), as its
/// report and how it was split: `Ok(None)` when there is none, an error
/// saying why when the file is there but not read (not a regular file, not
/// JSON, or a report that does not hold together: ignored with a word, as a
/// stale model is).
pub fn load_saved_report(dir: &Path) -> Result<Option<(Report, String)>, String> {
    #[derive(serde::Deserialize)]
    struct Kept {
        labels: Vec<String>,
        confusion: Vec<Vec<f64>>,
        accuracy: f64,
        per_class: Vec<Rate>,
        #[serde(default)]
        train: Vec<String>,
        #[serde(default)]
        test: Vec<String>,
        #[serde(default)]
        predictions: Vec<Row>,
        method: String,
    }
    #[derive(serde::Deserialize)]
    struct Rate {
        label: String,
        n: usize,
        // A class with no test example has no rate: `null`.
        success_rate: Option<f64>,
        error_rate: Option<f64>,
    }
    #[derive(serde::Deserialize)]
    struct Row {
        file: String,
        label: String,
        predicted: String,
        votes: Vec<(String, usize)>,
    }
    let path = dir.join(REPORT_JSON);
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    let ignored = |why: String| format!("{}: {why}: ignored", path.display());
    let bytes = crate::io::read_input_at_most(&path, KEPT_REPORT_MAX)
        .map_err(|e| ignored(e.to_string()))?;
    let k: Kept = serde_json::from_slice(&bytes)
        .map_err(|e| ignored(format!("not an evaluation kept by the console ({e})")))?;
    if let Some(fault) = crate::evaluate::confusion_fault(&k.labels, &k.confusion, k.accuracy) {
        return Err(ignored(fault));
    }
    if k.per_class.len() != k.labels.len()
        || k.per_class
            .iter()
            .zip(&k.labels)
            .any(|(r, l)| r.label != *l)
    {
        return Err(ignored("its per-class rates name other labels".into()));
    }
    let report = Report {
        labels: k.labels,
        // Whole, non-negative counts: checked above.
        confusion: k
            .confusion
            .iter()
            .map(|r| r.iter().map(|&v| v as usize).collect())
            .collect(),
        accuracy: k.accuracy,
        per_class: k
            .per_class
            .into_iter()
            .map(|r| crate::evaluate::ClassRate {
                label: r.label,
                n: r.n,
                success_rate: r.success_rate.unwrap_or(f64::NAN),
                error_rate: r.error_rate.unwrap_or(f64::NAN),
            })
            .collect(),
        train: k.train,
        test: k.test,
        predictions: k
            .predictions
            .into_iter()
            .map(|r| crate::evaluate::PredictionRow {
                file: r.file,
                label: r.label,
                predicted: r.predicted,
                votes: r.votes,
            })
            .collect(),
    };
    Ok(Some((report, k.method)))
}

/// Take up what an earlier session kept in `dir`: the last evaluation (the
/// Dataset panel shows it, with its age), and the model, or say on the
/// status line and in the Dataset panel why the model is not used.
pub fn adopt_saved_model(app: &mut App, dir: &Path) {
    let kept = if app.dataset.report.is_none() {
        load_saved_report(dir).unwrap_or_else(|why| {
            app.warn(why);
            None
        })
    } else {
        None
    };
    if let Some((report, method)) = kept {
        let file = dir.join(REPORT_FILE);
        let age = std::fs::metadata(dir.join(REPORT_JSON))
            .and_then(|m| m.modified())
            .map(|t| super::session::ago(t, std::time::SystemTime::now()));
        app.dataset.report = Some(report);
        app.dataset.report_method = Some(match age {
            Ok(age) => format!("{method}, {age}"),
            Err(_) => method,
        });
        app.dataset.report_file = Some(file);
    }
    match load_saved_model(&app.profile, dir) {
        Ok(None) => {}
        Ok(Some((m, file))) => {
            let mut info = ModelInfo::of(&m, Some(file));
            let (skipped, changed) = compare_files(&m, dir);
            info.skipped = skipped;
            info.changed = changed;
            app.dataset.model = Some(info);
            app.dataset.model_note = None;
            app.model = Some(m);
        }
        Err(why) => {
            let text = format!("{why} ({} trains a new one)", app.keys.name(Key::Train));
            app.warn(text.clone());
            app.dataset.model_note = Some(text);
        }
    }
}

/// A recording by its label folder and name (`S2/S2_003.csv`): the same
/// file however the folder was spelt when the model was trained.
fn tail(path: &Path) -> PathBuf {
    let mut c: Vec<_> = path.components().rev().take(2).collect();
    c.reverse();
    c.iter().collect()
}

/// The folder's recordings against the model's examples: how many that are
/// not among them are incomplete (training skipped them), and, when the
/// rest differ, how ("2 recordings added, 1 gone since it was trained").
fn compare_files(model: &Model, dir: &Path) -> (usize, Option<String>) {
    let Ok(files) = recording::collect_files(&[dir.to_path_buf()]) else {
        return (0, None);
    };
    let known: std::collections::HashSet<PathBuf> = model
        .examples
        .iter()
        .map(|e| tail(Path::new(&e.file)))
        .collect();
    let here: std::collections::HashSet<PathBuf> = files.iter().map(|f| tail(f)).collect();
    let (mut skipped, mut added) = (0, 0);
    for f in files.iter().filter(|f| !known.contains(&tail(f))) {
        match recording::read(f) {
            Ok(r) if !r.is_complete() => skipped += 1,
            _ => added += 1,
        }
    }
    let gone = known.iter().filter(|k| !here.contains(*k)).count();
    let changed = (added + gone > 0).then(|| {
        let mut parts = Vec::new();
        if added > 0 {
            parts.push(format!(
                "{} added",
                crate::classify::plural(added, "recording", "recordings")
            ));
        }
        if gone > 0 && added > 0 {
            parts.push(format!("{gone} gone"));
        } else if gone > 0 {
            parts.push(format!(
                "{} gone",
                crate::classify::plural(gone, "recording", "recordings")
            ));
        }
        format!("{} since it was trained", parts.join(", "))
    });
    (skipped, changed)
}

#[cfg(test)]
mod tests;
