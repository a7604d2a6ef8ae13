//! Recordings → labelled feature vectors, once: the one way from a recording
//! to what the classifier sees, shared by `features`, `train`, `classify`,
//! `evaluate` (every method and sweep), `inspect`, `plot` and the console's
//! Predict, train and replay.
//!
//! [`find`] lists the recordings under some paths (plain `*.csv` and
//! `*.csv.gz`, folders walked, hidden entries skipped) in file-name order.
//! [`load`] reads them on every core and hands back, in that same order, one
//! [`Entry`] per usable recording: its label (the `label` metadata, else its
//! folder's name), its metadata, and either its feature vector under the
//! profile's `[analysis]` ([`Keep::Features`]: a few hundred bytes per
//! recording, whatever its length) or the columns the analysis reads
//! ([`Keep::Samples`], for sweeps that change the analysis and extract
//! again). Incomplete recordings (no `# end samples` trailer) are skipped and
//! listed in [`Loaded::skipped`]; with [`Unusable::Skip`] so are recordings
//! that cannot be read or analysed, each with its reason, and otherwise the
//! first of those in file-name order is the error.
//!
//! With `[analysis] windows` set, [`Keep::Features`] gives one [`Entry`] per
//! sub-window instead, each naming its recording and its window index, in
//! file-name order and then window order ([`Keep::Samples`] still gives one
//! per recording).
//!
//! [`features_of`] is the one place that picks the analysis's columns out of
//! a recording: the axis, then `channel`, then each of `channels`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use thiserror::Error;

use crate::analysis::{AnalysisError, FeatureExtractor};
use crate::classify::TrainingExample;
use crate::profile::Analysis;
use crate::recording::{self, Recording, RecordingError};

/// Why recordings could not become examples.
#[derive(Debug, Error)]
pub enum DatasetError {
    #[error("no recordings (*.csv, *.csv.gz) found in {0}")]
    NoRecordings(String),
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("{file}: no column `{column}` (the recording has {has})")]
    MissingColumn {
        file: String,
        column: String,
        has: String,
    },
    #[error("{file}: no `label` in the metadata and no folder to name it")]
    NoLabel { file: String },
    #[error("{file}: {source}")]
    Analysis { file: String, source: AnalysisError },
    #[error("the analysis settings cannot be used: {0}")]
    Settings(AnalysisError),
    /// More feature vectors or values than any run should hold ([`check_size`]).
    #[error(
        "{recordings} recording(s) × {per_recording} sub-window(s) = {vectors} feature vectors of {features} features ({values} values): over the limit of {MAX_VECTORS} vectors and {MAX_VALUES} values, which keeps a run within memory and time; use a longer windows.hop or a shorter windows.length (fewer sub-windows), fewer bins, or fewer recordings"
    )]
    TooLarge {
        recordings: usize,
        per_recording: usize,
        vectors: usize,
        features: usize,
        values: usize,
    },
}

/// At most this many feature vectors (sub-windows over the dataset) are
/// made in one run: the thesis set gives 120, its three-window variant
/// 360, a day of 10 kHz fingertip scans cut every 10 ms a few thousand.
pub const MAX_VECTORS: usize = 200_000;
/// At most this many feature values (vectors × features: 256 MB as
/// numbers, under 0.9 GB as a model file). 20 M until 2026-11-29, which
/// left the interval quantiles of whole 6 s, 2.2 kHz trials out of a
/// 200-trial set (23 M values); with them `tune` scored 96.25 % on the
/// generated fingertip sets where it scored 95.0 % (BENCHMARKS.md).
pub const MAX_VALUES: usize = 32_000_000;

/// Refuses, before any work, a dataset of `recordings` that `analysis`
/// would turn into more than [`MAX_VECTORS`] feature vectors or
/// [`MAX_VALUES`] values.
pub fn check_size(recordings: usize, analysis: &Analysis) -> Result<(), DatasetError> {
    let per_recording = if analysis.windows.is_some() {
        analysis.sub_windows().len()
    } else {
        1
    };
    let vectors = recordings.saturating_mul(per_recording);
    // Random kernels' features are made by the model, but held all the same.
    let features = analysis
        .feature_count()
        .max(analysis.fitted_feature_count());
    let values = vectors.saturating_mul(features);
    if vectors > MAX_VECTORS || values > MAX_VALUES {
        return Err(DatasetError::TooLarge {
            recordings,
            per_recording,
            vectors,
            features,
            values,
        });
    }
    Ok(())
}

impl DatasetError {
    /// True when the recordings or settings are at fault (exit code 2),
    /// false for an I/O failure (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        match self {
            DatasetError::Recording(e) => e.is_bad_input(),
            _ => true,
        }
    }
}

/// The recordings under `paths` (files as given, folders walked), in
/// file-name order; finding none is an error.
pub fn find(paths: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    let files = recording::collect_files(paths)?;
    if files.is_empty() {
        return Err(DatasetError::NoRecordings(
            paths
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ));
    }
    Ok(files)
}

/// The label of a recording: its `label` metadata, else its folder's name.
pub fn label_of(rec: &Recording, file: &Path) -> Result<String, DatasetError> {
    if let Some(l) = rec.label() {
        return Ok(l.to_string());
    }
    file.parent()
        .and_then(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| DatasetError::NoLabel {
            file: file.display().to_string(),
        })
}

/// The columns the analysis reads, axis first: `axis`, `channel`, then each
/// of `channels`.
pub fn columns_of<'r>(
    rec: &'r Recording,
    file: &Path,
    analysis: &Analysis,
) -> Result<(&'r [f64], Vec<&'r [f64]>), DatasetError> {
    let missing = |c: &str| DatasetError::MissingColumn {
        file: file.display().to_string(),
        column: c.to_string(),
        has: rec.columns.join(", "),
    };
    let axis = rec
        .column(&analysis.axis)
        .ok_or_else(|| missing(&analysis.axis))?;
    let signals = analysis
        .all_channels()
        .map(|c| rec.column(c).ok_or_else(|| missing(c)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((axis, signals))
}

/// The feature vector of one recording under the extractor's settings.
pub fn features_of(
    rec: &Recording,
    file: &Path,
    ex: &mut FeatureExtractor,
) -> Result<Vec<f64>, DatasetError> {
    let (axis, signals) = columns_of(rec, file, ex.settings())?;
    ex.features_of_channels(axis, &signals)
        .map(<[f64]>::to_vec)
        .map_err(|source| DatasetError::Analysis {
            file: file.display().to_string(),
            source,
        })
}

/// The feature vectors of each of a recording's sub-windows, in window
/// order (the window alone without `[analysis] windows`).
pub fn window_features_of(
    rec: &Recording,
    file: &Path,
    ex: &mut FeatureExtractor,
) -> Result<Vec<Vec<f64>>, DatasetError> {
    let (axis, signals) = columns_of(rec, file, ex.settings())?;
    ex.all_window_features(axis, &signals)
        .map_err(|source| DatasetError::Analysis {
            file: file.display().to_string(),
            source,
        })
}

/// One recording as a labelled example.
pub fn example_of(
    rec: &Recording,
    file: &Path,
    ex: &mut FeatureExtractor,
) -> Result<TrainingExample, DatasetError> {
    Ok(TrainingExample {
        file: file.display().to_string(),
        label: label_of(rec, file)?,
        features: features_of(rec, file, ex)?,
    })
}

/// What [`load`] keeps of each recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// The feature vector only.
    Features,
    /// The columns the analysis reads (and the feature vector is left
    /// empty): for sweeps that extract again under other settings.
    Samples,
}

/// What [`load`] does with a recording it cannot read or analyse.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unusable {
    /// The first one (in file-name order) is the error.
    Fail,
    /// It is skipped and listed with its reason.
    Skip,
}

/// How to load.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    pub keep: Keep,
    pub unusable: Unusable,
    /// Reader threads (at least 1; at most one per recording).
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            keep: Keep::Features,
            unusable: Unusable::Fail,
            threads: cores(),
        }
    }
}

/// The machine's cores (1 when it cannot be told).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// A metadata value as text: strings as they are, others in TOML (a group
/// key, a sweep value).
pub fn meta_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// `file: reason`, or the reason alone when it already starts with the
/// file's name (a reader's error names its file and line).
pub fn named_once(file: &str, reason: &str) -> String {
    if reason.starts_with(file) {
        reason.to_string()
    } else {
        format!("{file}: {reason}")
    }
}

/// One usable recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub file: String,
    pub label: String,
    pub meta: Vec<(String, toml::Value)>,
    /// Empty with [`Keep::Samples`].
    pub features: Vec<f64>,
    /// The analysis's axis with [`Keep::Samples`], else empty.
    pub axis: Vec<f64>,
    /// `channel`, then `channels`, with [`Keep::Samples`], else empty.
    pub signals: Vec<Vec<f64>>,
    /// The sub-window these features are of (0, 1, … along the window),
    /// when `[analysis] windows` is set and features are kept.
    pub window: Option<usize>,
}

impl Entry {
    pub fn example(&self) -> TrainingExample {
        TrainingExample {
            file: self.file.clone(),
            label: self.label.clone(),
            features: self.features.clone(),
        }
    }

    /// A metadata value, as text (strings as they are, others in TOML).
    pub fn meta_text(&self, key: &str) -> Option<String> {
        self.meta
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| meta_text(v))
    }

    /// The feature vector of a kept scan ([`Keep::Samples`]) under other
    /// analysis settings with the same channels.
    pub fn features_with(&self, ex: &mut FeatureExtractor) -> Result<Vec<f64>, DatasetError> {
        let signals: Vec<&[f64]> = self.signals.iter().map(Vec::as_slice).collect();
        ex.features_of_channels(&self.axis, &signals)
            .map(<[f64]>::to_vec)
            .map_err(|source| DatasetError::Analysis {
                file: self.file.clone(),
                source,
            })
    }

    /// The feature vectors of each sub-window of a kept scan
    /// ([`Keep::Samples`]) under other analysis settings with the same
    /// channels, in window order (the window alone without `windows`).
    pub fn window_features_with(
        &self,
        ex: &mut FeatureExtractor,
    ) -> Result<Vec<Vec<f64>>, DatasetError> {
        let signals: Vec<&[f64]> = self.signals.iter().map(Vec::as_slice).collect();
        ex.all_window_features(&self.axis, &signals)
            .map_err(|source| DatasetError::Analysis {
                file: self.file.clone(),
                source,
            })
    }
}

/// A recording [`load`] left out, and why.
#[derive(Debug, Clone, PartialEq)]
pub enum Skipped {
    /// No `# end samples` trailer; `torn` when its last row was cut short.
    Incomplete { file: String, torn: bool },
    /// It could not be read or analysed ([`Unusable::Skip`]).
    Unusable {
        file: String,
        reason: String,
        /// The file is not a readable recording (rather than one the
        /// analysis cannot use).
        unreadable: bool,
    },
}

impl Skipped {
    pub fn file(&self) -> &str {
        match self {
            Skipped::Incomplete { file, .. } | Skipped::Unusable { file, .. } => file,
        }
    }
}

impl std::fmt::Display for Skipped {
    /// The one warning line for a skipped recording.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Skipped::Incomplete { file, torn } => write!(
                f,
                "{file}: incomplete scan (no `# end samples` trailer{}), skipped",
                if *torn {
                    "; its last row was cut short and left out"
                } else {
                    ""
                }
            ),
            Skipped::Unusable { file, reason, .. } => {
                write!(f, "{}, skipped", named_once(file, reason))
            }
        }
    }
}

/// The usable recordings, in file-name order, and those left out.
#[derive(Debug, Clone, Default)]
pub struct Loaded {
    pub entries: Vec<Entry>,
    pub skipped: Vec<Skipped>,
}

impl Loaded {
    /// The labelled feature vectors ([`Keep::Features`]).
    pub fn examples(&self) -> Vec<TrainingExample> {
        self.entries.iter().map(Entry::example).collect()
    }

    /// The labelled feature vectors, consuming the entries.
    pub fn into_examples(self) -> Vec<TrainingExample> {
        self.entries
            .into_iter()
            .map(|e| TrainingExample {
                file: e.file,
                label: e.label,
                features: e.features,
            })
            .collect()
    }
}

/// The window index of each row of [`load`]'s examples (in its order: a
/// recording's sub-windows are consecutive, window 0 first): 0, 1, … within
/// each run of rows from one file. For `features --out`'s `window` column.
pub fn window_indices(examples: &[TrainingExample]) -> Vec<usize> {
    let mut out = Vec::with_capacity(examples.len());
    for (i, e) in examples.iter().enumerate() {
        let j = match i.checked_sub(1) {
            Some(p) if examples[p].file == e.file => out[p] + 1,
            _ => 0,
        };
        out.push(j);
    }
    out
}

enum Outcome {
    /// One entry, or one per sub-window.
    Usable(Vec<Entry>),
    Skipped(Skipped),
    Failed(DatasetError),
}

fn load_one(
    file: &Path,
    analysis: &Analysis,
    ex: &mut FeatureExtractor,
    keep: Keep,
    unusable: Unusable,
) -> Outcome {
    let name = || file.display().to_string();
    let give_up = |e: DatasetError, unreadable: bool| match unusable {
        Unusable::Fail => Outcome::Failed(e),
        Unusable::Skip => Outcome::Skipped(Skipped::Unusable {
            file: name(),
            reason: e.to_string(),
            unreadable,
        }),
    };
    // Only the analysis's columns are converted (the others still checked).
    let wanted: Vec<&str> = std::iter::once(analysis.axis.as_str())
        .chain(analysis.all_channels())
        .collect();
    let rec = match recording::read_columns(file, &wanted) {
        Ok(r) => r,
        // Only a walk finds one (a file named is refused by `find`): a
        // FIFO or device named like a recording is passed over, never read.
        Err(RecordingError::Io { source, .. }) if crate::io::not_regular(&source) => {
            return Outcome::Skipped(Skipped::Unusable {
                file: name(),
                reason: source.to_string(),
                unreadable: true,
            });
        }
        Err(e) => return give_up(e.into(), true),
    };
    if !rec.is_complete() {
        return Outcome::Skipped(Skipped::Incomplete {
            file: name(),
            torn: rec.torn_last_row,
        });
    }
    let label = match label_of(&rec, file) {
        Ok(l) => l,
        Err(e) => return give_up(e, false),
    };
    if keep == Keep::Features && analysis.windows.is_some() {
        let windows = match window_features_of(&rec, file, ex) {
            Ok(w) => w,
            Err(e) => return give_up(e, false),
        };
        let file = name();
        return Outcome::Usable(
            windows
                .into_iter()
                .enumerate()
                .map(|(j, features)| Entry {
                    file: file.clone(),
                    label: label.clone(),
                    meta: rec.meta.clone(),
                    features,
                    axis: vec![],
                    signals: vec![],
                    window: Some(j),
                })
                .collect(),
        );
    }
    let (features, axis, signals) = match keep {
        Keep::Features => match features_of(&rec, file, ex) {
            Ok(f) => (f, vec![], vec![]),
            Err(e) => return give_up(e, false),
        },
        Keep::Samples => match columns_of(&rec, file, analysis) {
            Ok((axis, signals)) => (
                vec![],
                axis.to_vec(),
                signals.into_iter().map(<[f64]>::to_vec).collect(),
            ),
            Err(e) => return give_up(e, false),
        },
    };
    Outcome::Usable(vec![Entry {
        file: name(),
        label,
        meta: rec.meta,
        features,
        axis,
        signals,
        window: None,
    }])
}

/// Read `files` on `options.threads` threads and turn each into an
/// [`Entry`], in the order given. `progress` is called once per file done
/// (from any of the threads).
pub fn load(
    files: &[PathBuf],
    analysis: &Analysis,
    options: Options,
    progress: &(dyn Fn() + Sync),
) -> Result<Loaded, DatasetError> {
    FeatureExtractor::try_new(analysis).map_err(DatasetError::Settings)?;
    if options.keep == Keep::Features {
        check_size(files.len(), analysis)?;
    }
    let threads = options.threads.clamp(1, files.len().max(1));
    // Files are handed out one at a time (they differ in length), and each
    // result lands in its own slot, so the order is the files' whatever the
    // threads do.
    let next = AtomicUsize::new(0);
    let work = || {
        let mut ex = FeatureExtractor::new(analysis);
        let mut done = Vec::new();
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(f) = files.get(i) else { break };
            let outcome = load_one(f, analysis, &mut ex, options.keep, options.unusable);
            progress();
            let failed = matches!(outcome, Outcome::Failed(_));
            done.push((i, outcome));
            if failed && options.unusable == Unusable::Fail {
                // The others stop at their next file; the first failure in
                // file order among those read is reported.
                next.store(files.len(), Ordering::Relaxed);
            }
        }
        done
    };
    let mut results: Vec<(usize, Outcome)> = if threads == 1 {
        work()
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..threads).map(|_| s.spawn(work)).collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect()
        })
    };
    results.sort_by_key(|(i, _)| *i);
    let mut out = Loaded::default();
    for (_, r) in results {
        match r {
            Outcome::Usable(e) => out.entries.extend(e),
            Outcome::Skipped(s) => out.skipped.push(s),
            Outcome::Failed(e) => return Err(e),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::LoadedProfile;

    #[test]
    fn a_dataset_cut_into_too_many_sub_windows_is_refused_before_any_work() {
        let mut a = LoadedProfile::thesis().profile.analysis;
        assert!(check_size(120, &a).is_ok(), "the thesis set");
        // 20,001 sub-windows of 30 cm, 0.3 mm apart, 12 recordings.
        a.window = [0.0, 0.3 + 20_000.0 * 0.0003];
        a.windows = Some(crate::profile::Windows {
            length: 0.3,
            hop: 0.0003,
        });
        a.bins = [1, 24];
        let e = check_size(12, &a).unwrap_err();
        assert!(e.is_bad_input());
        let m = e.to_string();
        assert!(
            m.contains("12 recording(s) × 20001 sub-window(s) = 240012 feature vectors")
                && m.contains("windows.hop"),
            "{m}"
        );
        assert!(check_size(9, &a).is_ok(), "180,009 vectors of 24");
        // Fewer vectors, but too many values (180,009 × 400).
        a.bins = [1, 400];
        assert_eq!(a.feature_count(), 400);
        assert!(check_size(9, &a).is_err());
    }

    fn thesis_analysis() -> Analysis {
        LoadedProfile::thesis().profile.analysis
    }

    fn shipped() -> Vec<PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
        find(&[dir]).unwrap()
    }

    #[test]
    fn every_thread_count_gives_the_same_examples_in_file_order() {
        let files: Vec<PathBuf> = shipped().into_iter().step_by(10).collect();
        let a = thesis_analysis();
        let one = load(
            &files,
            &a,
            Options {
                threads: 1,
                ..Options::default()
            },
            &|| {},
        )
        .unwrap();
        assert_eq!(one.entries.len(), files.len());
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        let got: Vec<String> = one.entries.iter().map(|e| e.file.clone()).collect();
        assert_eq!(got, names);
        for threads in [2, 3, 8] {
            let many = load(
                &files,
                &a,
                Options {
                    threads,
                    ..Options::default()
                },
                &|| {},
            )
            .unwrap();
            assert_eq!(many.entries, one.entries, "{threads} threads");
        }
        assert!(one.entries.iter().all(|e| e.features.len() == 49));
    }

    #[test]
    fn samples_kept_give_the_features_read_directly() {
        let files: Vec<PathBuf> = shipped().into_iter().take(3).collect();
        let a = thesis_analysis();
        let feats = load(&files, &a, Options::default(), &|| {}).unwrap();
        let samples = load(
            &files,
            &a,
            Options {
                keep: Keep::Samples,
                ..Options::default()
            },
            &|| {},
        )
        .unwrap();
        let mut ex = FeatureExtractor::new(&a);
        for (f, s) in feats.entries.iter().zip(&samples.entries) {
            assert!(s.features.is_empty());
            assert_eq!(s.features_with(&mut ex).unwrap(), f.features);
        }
    }

    #[test]
    fn incomplete_and_unusable_recordings_are_skipped_or_fail_as_asked() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("S1");
        std::fs::create_dir_all(&dir).unwrap();
        let good = shipped()[0].clone();
        let text = recording::read(&good).unwrap();
        assert!(text.is_complete());
        std::fs::copy(&good, dir.join("a.csv.gz")).unwrap();
        std::fs::write(dir.join("b.csv"), "not a recording\n").unwrap();
        // Complete but short: the window is not covered.
        std::fs::write(
            dir.join("c.csv"),
            "# hapticlab recording v1\nt_s,x_m,y_m\n0.0,0.0,0.0\n0.001,0.001,0.0\n# end samples = 2\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("d.csv"),
            "# hapticlab recording v1\nt_s,x_m,y_m\n0.0,0.0,0.0\n",
        )
        .unwrap();
        let files = find(&[tmp.path().to_path_buf()]).unwrap();
        assert_eq!(files.len(), 4);
        let a = thesis_analysis();
        let skip = load(
            &files,
            &a,
            Options {
                unusable: Unusable::Skip,
                ..Options::default()
            },
            &|| {},
        )
        .unwrap();
        assert_eq!(skip.entries.len(), 1);
        assert_eq!(skip.entries[0].label, "S1");
        let kinds: Vec<String> = skip.skipped.iter().map(ToString::to_string).collect();
        assert_eq!(kinds.len(), 3, "{kinds:?}");
        assert!(
            kinds[0].contains("b.csv:1: not a hapticlab recording"),
            "{kinds:?}"
        );
        assert!(kinds[1].contains("c.csv: the scan covers"), "{kinds:?}");
        assert!(kinds[2].ends_with("d.csv: incomplete scan (no `# end samples` trailer), skipped"));
        let err = load(&files, &a, Options::default(), &|| {}).unwrap_err();
        assert!(err.is_bad_input());
        assert!(err.to_string().contains("b.csv:1"), "{err}");
    }

    #[test]
    fn windows_give_one_example_per_sub_window_in_file_then_window_order() {
        let files: Vec<PathBuf> = shipped().into_iter().step_by(20).collect();
        let mut a = thesis_analysis();
        a.bins = [1, 24];
        a.windows = Some(crate::profile::Windows {
            length: 0.0147,
            hop: 0.0075,
        });
        let one = load(
            &files,
            &a,
            Options {
                threads: 1,
                ..Options::default()
            },
            &|| {},
        )
        .unwrap();
        let many = load(&files, &a, Options::default(), &|| {}).unwrap();
        assert_eq!(one.entries, many.entries);
        assert_eq!(one.entries.len(), 3 * files.len());
        let mut ex = FeatureExtractor::new(&a);
        for (i, f) in files.iter().enumerate() {
            let rec = recording::read(f).unwrap();
            let (axis, signals) = columns_of(&rec, f, &a).unwrap();
            for j in 0..3 {
                let e = &one.entries[3 * i + j];
                assert_eq!(e.file, f.display().to_string());
                assert_eq!(e.window, Some(j));
                assert_eq!(e.features.len(), 24);
                assert_eq!(e.features, ex.window_features(j, axis, &signals).unwrap());
            }
        }
        let idx = window_indices(&one.examples());
        assert_eq!(&idx[..6], &[0, 1, 2, 0, 1, 2]);
        // Without windows: one entry per recording, no window index.
        let plain = load(&files, &thesis_analysis(), Options::default(), &|| {}).unwrap();
        assert!(plain.entries.iter().all(|e| e.window.is_none()));
        assert_eq!(plain.entries.len(), files.len());
    }

    #[test]
    fn nothing_found_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let err = find(&[tmp.path().to_path_buf()]).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("no recordings (*.csv, *.csv.gz) found in ")
        );
    }
}
