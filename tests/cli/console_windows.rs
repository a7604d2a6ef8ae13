//! The console's Predict with `[analysis] windows`: the scan on screen is
//! classified by its sub-windows' vote through the path `classify` takes,
//! so the console and `classify --json` agree on the label, the window
//! votes, the tally and every sub-window's outcome — for a held-out scan,
//! and for a training scan (left out of the model, as `classify` with a
//! model trained without it).

use std::fs;
use std::path::Path;

use serde_json::Value;
use tempfile::TempDir;

use hapticlab::analysis::FeatureExtractor;
use hapticlab::classify::Model;
use hapticlab::console::scan;
use hapticlab::profile::LoadedProfile;

use crate::common::{REPO, p, run};

/// `classify --json` of one file: its row.
fn classify_row(profile: &Path, model: &Path, file: &Path) -> Value {
    let r = run(&[
        "classify",
        "--profile",
        p(profile),
        "--model",
        p(model),
        "--json",
        p(file),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v: Value = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    v.as_array().unwrap()[0].clone()
}

/// The console's prediction agrees with the row in every part `classify`
/// reports.
fn assert_same(pv: &scan::PredictionView, row: &Value) {
    let w = pv.windows.as_ref().expect("a vote over sub-windows");
    assert_eq!(row["predicted"].as_str(), Some(w.label.as_str()), "{row}");
    assert_eq!(pv.prediction.label, w.label);
    assert_eq!(
        row["votes"],
        serde_json::to_value(&pv.prediction.votes).unwrap(),
        "{row}"
    );
    assert_eq!(
        row["tally"],
        serde_json::to_value(&w.tally).unwrap(),
        "{row}"
    );
    assert_eq!(
        row["windows"],
        serde_json::to_value(&w.windows).unwrap(),
        "{row}"
    );
}

#[test]
fn the_consoles_predict_votes_over_sub_windows_as_classify_does() {
    let dir = TempDir::new().unwrap();
    let thesis = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    // Four 14.7 mm sub-windows every 5 mm of the 29.7 mm window.
    let text = thesis.replace(
        "\nbins = [1, 49]\n",
        "\nbins = [1, 24]\nwindows = { length = 0.0147, hop = 0.005 }\n",
    );
    assert_ne!(text, thesis, "the thesis profile keeps bins 1..49");
    let profile = dir.path().join("windows.toml");
    fs::write(&profile, text).unwrap();
    // Three scans of each texture to train on; the fourth of S3 held out.
    let shipped = Path::new(REPO).join("recordings/thesis-sim");
    let data = dir.path().join("D");
    for label in ["S1", "S2", "S3", "S4"] {
        fs::create_dir_all(data.join(label)).unwrap();
        for i in 1..=3 {
            let name = format!("{label}_00{i}.csv.gz");
            fs::copy(
                shipped.join(label).join(&name),
                data.join(label).join(&name),
            )
            .unwrap();
        }
    }
    let train = |data: &Path, out: &Path| {
        let r = run(&["train", "--profile", p(&profile), p(data), "--out", p(out)]);
        assert_eq!(r.code, Some(0), "{r:?}");
    };
    let model_path = dir.path().join("M.json");
    train(&data, &model_path);
    let lp = LoadedProfile::load(&profile).unwrap();
    let model = Model::load(&model_path).unwrap();
    assert_eq!(
        model.examples.len(),
        4 * 3 * 4,
        "four sub-windows of 12 scans"
    );
    let mut ex = FeatureExtractor::new(&lp.profile.analysis);

    // A held-out scan, opened as the console opens it.
    let held = shipped.join("S3").join("S3_004.csv.gz");
    let rec = hapticlab::recording::read(&held).unwrap();
    let view = scan::analyse(&rec, &held, &mut ex);
    assert_eq!(view.windows.as_ref().unwrap().as_ref().unwrap().len(), 4);
    let pv = scan::predict_view(&model, &view).unwrap().unwrap();
    assert!(!pv.left_out);
    assert_eq!(pv.windows.as_ref().unwrap().windows.len(), 4);
    assert_same(&pv, &classify_row(&profile, &model_path, &held));
    // The replay browser's list says the same.
    let listed = scan::predict_recording(&model, &rec, &held, &mut ex).unwrap();
    assert_eq!(listed, pv);

    // A training scan: every one of its sub-windows left out, as a model
    // trained without the scan classifies it.
    let first = data.join("S2").join("S2_001.csv.gz");
    let rec = hapticlab::recording::read(&first).unwrap();
    let view = scan::analyse(&rec, &first, &mut ex);
    let pv = scan::predict_view(&model, &view).unwrap().unwrap();
    assert!(pv.left_out);
    let without = dir.path().join("D-without");
    for label in ["S1", "S2", "S3", "S4"] {
        fs::create_dir_all(without.join(label)).unwrap();
        for f in fs::read_dir(data.join(label)).unwrap() {
            let f = f.unwrap().path();
            if f != first {
                fs::copy(&f, without.join(label).join(f.file_name().unwrap())).unwrap();
            }
        }
    }
    let reduced = dir.path().join("M-without.json");
    train(&without, &reduced);
    assert_same(&pv, &classify_row(&profile, &reduced, &first));
}
