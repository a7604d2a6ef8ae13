//! One scan as the Surface trace, Spectrum and Prediction panels show it:
//! its trace (signal against the analysis axis), the analysis window, the
//! feature bins and, once asked for, the prediction.
//!
//! [`analyse`] does the work once, when a scan is saved or a recording is
//! opened; the panels only read the result. It never touches the screen.

use std::path::{Path, PathBuf};

use crate::analysis::FeatureExtractor;
use crate::classify::{Model, Prediction};
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
    /// The feature bins (|X_k| for k = first_bin..), or why there are none.
    pub features: Result<Vec<f64>, String>,
    pub first_bin: usize,
    /// Set by `p`, or by the replay browser.
    pub prediction: Option<Result<PredictionView, String>>,
    /// Stored into the dataset (its final path), or still unsaved.
    pub stored: Option<PathBuf>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct PredictionView {
    pub prediction: Prediction,
    /// The recording was one of the training examples and was left out.
    pub left_out: bool,
}

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
    // analysis reads, through the one loader's `features_of`.
    let features = crate::dataset::features_of(rec, path, ex).map_err(|e| e.to_string());
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
        first_bin: s.bins[0],
        prediction: None,
        stored: None,
    }
}

/// The newest scan an earlier session left in `<dataset>/.unsaved/`,
/// analysed, so the console can show and store it; `None` when there is
/// none or it cannot be read (it stays where it is either way).
pub fn newest_unsaved(dataset: &Path, ex: &mut FeatureExtractor) -> Option<ScanView> {
    let dir = dataset.join(super::dataset::UNSAVED_DIR);
    let newest = std::fs::read_dir(&dir)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.modified().ok()?, p)))
        .max()?
        .1;
    let rec = crate::recording::read(&newest).ok()?;
    Some(analyse(&rec, &newest, ex))
}

/// Classify features with `model`; a recording that is one of the model's
/// training examples is left out of it first (leave-one-out), so replaying
/// a training set does not find each scan as its own nearest neighbour.
pub fn predict(model: &Model, features: &[f64], file: &Path) -> Result<PredictionView, String> {
    let name = file.display().to_string();
    let canonical = std::fs::canonicalize(file).ok();
    let same = |f: &str| {
        f == name
            || canonical
                .as_ref()
                .is_some_and(|c| std::fs::canonicalize(f).ok().as_ref() == Some(c))
    };
    if model.examples.iter().any(|e| same(&e.file)) {
        let rest: Vec<_> = model
            .examples
            .iter()
            .filter(|e| !same(&e.file))
            .cloned()
            .collect();
        // k as the profile asked, chosen again without this recording
        // where the profile's k needed choosing: no leak of the test scan.
        let reduced = Model::train_adapting_k(
            &model.profile,
            &model.analysis,
            &model.asked_classifier(),
            rest,
        )
        .map_err(|e| e.to_string())?;
        let prediction = reduced.classify(features).map_err(|e| e.to_string())?;
        return Ok(PredictionView {
            prediction,
            left_out: true,
        });
    }
    let prediction = model.classify(features).map_err(|e| e.to_string())?;
    Ok(PredictionView {
        prediction,
        left_out: false,
    })
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
