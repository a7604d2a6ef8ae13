//! One scan as the Surface trace, Spectrum and Prediction panels show it:
//! its trace (signal against the analysis axis), the analysis window, the
//! feature bins and, once asked for, the prediction.
//!
//! [`analyse`] does the work once, when a scan is saved or a recording is
//! opened; the panels only read the result. It never touches the screen.

use std::path::{Path, PathBuf};

use crate::analysis::FeatureExtractor;
use crate::classify::Model;
use crate::predictor::{Answer, Features, Predictor, Query};
use crate::recording::Recording;

/// Points kept of the trace for drawing (a scan has ~9000 samples).
const TRACE_POINTS: usize = 1500;

#[derive(Debug, Clone, PartialEq)]
pub struct ScanView {
    /// Where the recording is now (`.unsaved/` until stored).
    pub path: PathBuf,
    /// The label in its metadata.
    pub label: Option<String>,
    pub complete: bool,
    pub aborted: Option<String>,
    pub samples: usize,
    pub duration_s: f64,
    /// The axis and signal columns, e.g. `x_m` and `y_m`.
    pub axis: String,
    pub channel: String,
    /// (distance along the axis from the scan's start, signal), display
    /// units (mm for metres), decimated.
    pub trace: Vec<(f64, f64)>,
    /// The analysis window in the same units.
    pub window: [f64; 2],
    /// The feature vector (of the first sub-window when the analysis cuts
    /// several), or why there is none.
    pub features: Result<Vec<f64>, String>,
    /// The first DFT bin kept (from `bins` or `band`).
    pub first_bin: usize,
    /// What each feature is, for labels.
    pub names: FeatureNames,
    /// The channels whose features follow one another (`channel`, then
    /// `channels`), each `features.len() / channels.len()` long.
    pub channels: Vec<String>,
    /// Each sub-window's feature vector, in window order, when the analysis
    /// has `[analysis] windows` (`None` without): what a model that votes
    /// over sub-windows classifies.
    pub windows: Option<Result<Vec<Vec<f64>>, String>>,
    /// What the engine's [`Predictor`] classifies the scan by (its
    /// sub-windows' features or the whole window's), or why there is none.
    pub query: Result<Query, String>,
    /// Set by `p`, or by the replay browser.
    pub prediction: Option<Result<PredictionView, String>>,
    /// Stored into the dataset (its final path), or still unsaved.
    pub stored: Option<PathBuf>,
}

/// What a scan's features are (the Spectrum panel's labels): declared
/// with the analysis options that decide them.
pub use crate::profile::options::FeatureNames;

/// A prediction as the console holds it: the engine's [`Answer`].
pub type PredictionView = Answer;

/// Display scale and unit of a column: metres as mm, the rest as is.
pub fn unit_of(column: &str) -> (f64, &'static str) {
    if column.ends_with("_m") {
        (1000.0, "mm")
    } else if column.ends_with("_s") {
        (1.0, "s")
    } else if column.ends_with("_n") {
        (1.0, "N")
    } else {
        (1.0, "")
    }
}

/// Analyse a recording under the extractor's settings: the trace shows the
/// first channel, the features are of all of them, as `classify` makes
/// them ([`crate::dataset::features_of`]).
pub fn analyse(rec: &Recording, path: &Path, ex: &mut FeatureExtractor) -> ScanView {
    let s = ex.settings().clone();
    let (ascale, _) = unit_of(&s.axis);
    let (sscale, _) = unit_of(&s.channel);
    let axis = rec.column(&s.axis).unwrap_or(&[]);
    let signal = rec.column(&s.channel).unwrap_or(&[]);
    let n = axis.len().min(signal.len());
    let dir = if n > 1 && axis[n - 1] < axis[0] {
        -1.0
    } else {
        1.0
    };
    let step = n.div_ceil(TRACE_POINTS).max(1);
    let trace = (0..n)
        .step_by(step)
        .map(|j| (dir * (axis[j] - axis[0]) * ascale, signal[j] * sscale))
        .collect();
    // The features `train` and `classify` make: every channel the
    // analysis reads, through the one loader's `features_of`; what is
    // classified, the predictor's query (each sub-window's, with
    // `[analysis] windows`).
    let features = crate::dataset::features_of(rec, path, ex).map_err(|e| e.to_string());
    let query = Query::of(rec, path, ex).map_err(|e| e.to_string());
    let windows = s.windows.is_some().then(|| match &query {
        Ok(Query {
            features: Features::Windows(w),
            ..
        }) => Ok(w.clone()),
        Ok(_) => Err("not cut into sub-windows".to_string()),
        Err(e) => Err(e.clone()),
    });
    let t = rec.column("t_s").unwrap_or(&[]);
    ScanView {
        path: path.to_path_buf(),
        label: rec.label().map(str::to_string),
        complete: rec.is_complete(),
        aborted: rec.aborted().map(str::to_string),
        samples: rec.len(),
        duration_s: t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0),
        axis: s.axis.clone(),
        channel: s.channel.clone(),
        trace,
        window: [s.window[0] * ascale, s.window[1] * ascale],
        features,
        first_bin: s.kept_bins()[0],
        names: FeatureNames::of(&s),
        channels: s.all_channels().map(str::to_string).collect(),
        windows,
        query,
        prediction: None,
        stored: None,
    }
}

/// The newest complete scan an earlier session left in `<dataset>/.unsaved/`,
/// analysed, so the console can show and store it; `None` when there is
/// none or it cannot be read (it stays where it is either way).
pub fn newest_unsaved(dataset: &Path, ex: &mut FeatureExtractor) -> Option<ScanView> {
    let dir = dataset.join(super::dataset::UNSAVED_DIR);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.modified().ok()?, p)))
        .collect();
    files.sort();
    // An aborted scan is not offered as if it were good: the replay
    // browser lists it, labelled incomplete.
    files.into_iter().rev().find_map(|(_, p)| {
        let rec = crate::recording::read(&p).ok()?;
        rec.is_complete().then(|| analyse(&rec, &p, ex))
    })
}

/// Classify the scan on screen as `classify` classifies its recording:
/// the engine's [`Predictor`] decides sub-windows or the whole window and
/// leaves a training scan out. `None` when the scan has no features (the
/// view says why).
pub fn predict_view(model: &Model, view: &ScanView) -> Option<Result<PredictionView, String>> {
    match &view.query {
        Ok(q) => Some(
            Predictor::new(model)
                .answer(q, &view.path)
                .map_err(|e| e.to_string()),
        ),
        // A scan without features shows why in the Spectrum panel; one
        // whose sub-windows alone failed says it here.
        Err(e) if view.features.is_ok() => Some(Err(e.clone())),
        Err(_) => None,
    }
}

/// Classify a stored recording (for the replay browser's list), as
/// [`predict_view`] does its view.
pub fn predict_recording(
    model: &Model,
    rec: &Recording,
    file: &Path,
    ex: &mut FeatureExtractor,
) -> Result<PredictionView, String> {
    Predictor::new(model)
        .answer_recording(rec, file, ex)
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_newest_unsaved_scan_of_an_earlier_session_is_found() {
        let d = tempfile::tempdir().unwrap();
        let lp = crate::profile::LoadedProfile::thesis();
        let mut ex = FeatureExtractor::new(&lp.profile.analysis);
        assert!(newest_unsaved(d.path(), &mut ex).is_none(), "no folder");
        let dir = d.path().join(crate::console::dataset::UNSAVED_DIR);
        std::fs::create_dir_all(&dir).unwrap();
        assert!(newest_unsaved(d.path(), &mut ex).is_none(), "empty");
        let text = "# hapticlab recording v1\n# label = \"S1\"\nt_s,x_m,y_m\n0.000,0.0,0.0\n0.001,0.0001,0.0\n# end samples = 2\n";
        std::fs::write(dir.join("scan-001.csv"), text).unwrap();
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(60);
        std::fs::File::options()
            .write(true)
            .open(dir.join("scan-001.csv"))
            .unwrap()
            .set_modified(old)
            .unwrap();
        std::fs::write(dir.join("scan-002.csv"), text.replace("S1", "S4")).unwrap();
        std::fs::write(dir.join("notes.txt"), "not a scan").unwrap();
        let v = newest_unsaved(d.path(), &mut ex).unwrap();
        assert_eq!(v.path, dir.join("scan-002.csv"));
        assert_eq!(v.label.as_deref(), Some("S4"));
        assert_eq!(v.samples, 2);
        assert!(v.stored.is_none());
    }

    /// `p` on the one scan a model was trained on says why there is no
    /// prediction (it is left out, so nothing is left), not "no training
    /// examples".
    #[test]
    fn predicting_the_models_only_scan_says_it_is_left_out() {
        let lp = crate::profile::LoadedProfile::thesis();
        let a = &lp.profile.analysis;
        let features = vec![1.0; a.feature_count()];
        let example = crate::classify::TrainingExample {
            file: "session/S1/S1_001.csv".into(),
            label: "S1".into(),
            features: features.clone(),
        };
        let model =
            Model::train_adapting_k("thesis", a, &lp.profile.classifier, vec![example]).unwrap();
        let mut view = crate::console::fixtures::scan_view(false);
        view.query = Ok(Query {
            features: crate::predictor::Features::Whole(features),
            incomplete: None,
        });
        view.path = "session/S1/S1_001.csv".into();
        let e = predict_view(&model, &view).unwrap().unwrap_err();
        assert!(
            e.contains("only training scan") && e.contains("left out"),
            "{e}"
        );
        // Another scan (other samples: the same features would be this
        // one moved, and left out) is predicted by that one.
        view.path = "session/S2/S2_001.csv".into();
        view.query = Ok(Query {
            features: crate::predictor::Features::Whole(vec![1.5; a.feature_count()]),
            incomplete: None,
        });
        let p = predict_view(&model, &view).unwrap().unwrap();
        assert_eq!(p.prediction.label, "S1");
    }

    #[test]
    fn a_synthetic_scan_has_its_peak_at_bin_7() {
        let v = crate::console::fixtures::scan_view(false);
        let f = v.features.as_ref().unwrap();
        assert_eq!(f.len(), 49);
        let peak = f
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap()
            .0
            + v.first_bin;
        assert_eq!(peak, 7);
        assert_eq!(v.window, [60.0, 89.7]);
        assert!(v.trace.len() <= TRACE_POINTS);
        assert!((v.trace.last().unwrap().0 - 89.7).abs() < 0.1);
    }
}
