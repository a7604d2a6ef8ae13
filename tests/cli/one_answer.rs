//! One answer per recording, whoever asks: for every file of a session
//! folder, `classify`, the console's Predict (`p` on the scan opened) and
//! the replay browser's list give the same prediction, all through the
//! engine's predictor — every training scan left out of the model, and a
//! texture's only scan answered "no other scans" by all three.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde_json::Value;
use tempfile::TempDir;

use hapticlab::classify::Model;
use hapticlab::console::dataset::{JobResult, Jobs};
use hapticlab::console::scan;
use hapticlab::profile::LoadedProfile;

use crate::common::{REPO, p, run};

/// Generous, for a machine whose cores are busy elsewhere.
const PATIENCE: Duration = Duration::from_secs(300);

/// The replay browser's list of `files`: each one's predicted label.
fn listed(
    lp: &LoadedProfile,
    files: &[PathBuf],
    model: &Model,
) -> BTreeMap<PathBuf, Option<String>> {
    let jobs = Jobs::default();
    jobs.list(lp, files.to_vec(), Some(model.clone()), None);
    let since = Instant::now();
    loop {
        if let Some(r) = jobs.poll().into_iter().next() {
            let JobResult::Listed { entries, .. } = r else {
                panic!("not a list: {r:?}");
            };
            return entries.into_iter().map(|e| (e.path, e.predicted)).collect();
        }
        assert!(since.elapsed() < PATIENCE, "the list never came");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn classify_predict_and_the_replay_list_agree_on_every_file_of_a_session() {
    let dir = TempDir::new().unwrap();
    let shipped = Path::new(REPO).join("recordings/thesis-sim");
    let session = dir.path().join("session");
    // Three scans of S1..S3 and one of S4: S4's only scan, left out, has
    // no answer that could be right.
    for (label, n) in [("S1", 3), ("S2", 3), ("S3", 3), ("S4", 1)] {
        fs::create_dir_all(session.join(label)).unwrap();
        for i in 1..=n {
            let name = format!("{label}_00{i}.csv.gz");
            fs::copy(
                shipped.join(label).join(&name),
                session.join(label).join(&name),
            )
            .unwrap();
        }
    }
    let model_path = dir.path().join("model.json");
    let r = run(&["train", p(&session), "--out", p(&model_path)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let r = run(&["classify", "--model", p(&model_path), "--json", p(&session)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let rows: Vec<Value> = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    assert_eq!(rows.len(), 10, "{rows:?}");

    let lp = LoadedProfile::thesis();
    let model = Model::load(&model_path).unwrap();
    let files: Vec<PathBuf> = rows
        .iter()
        .map(|row| PathBuf::from(row["file"].as_str().unwrap()))
        .collect();
    let list = listed(&lp, &files, &model);
    let mut ex = hapticlab::analysis::FeatureExtractor::new(&lp.profile.analysis);
    for (row, file) in rows.iter().zip(&files) {
        let rec = hapticlab::recording::read(file).unwrap();
        let view = scan::analyse(&rec, file, &mut ex);
        let console = scan::predict_view(&model, &view).expect("features");
        assert_eq!(row["left_out"], true, "every file trained the model: {row}");
        if file.to_string_lossy().contains("S4_001") {
            assert_eq!(row["predicted"], Value::Null, "{row}");
            let reason = row["reason"].as_str().unwrap();
            assert!(reason.contains("S4 has no other scans"), "{reason}");
            let e = console.unwrap_err();
            assert_eq!(e, reason);
            assert_eq!(list[file], None);
            continue;
        }
        let console = console.unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(console.left_out);
        let predicted = row["predicted"].as_str().unwrap();
        assert_eq!(console.prediction.label, predicted, "{}", file.display());
        assert_eq!(
            row["votes"],
            serde_json::to_value(&console.prediction.votes).unwrap()
        );
        assert_eq!(list[file].as_deref(), Some(predicted), "{}", file.display());
    }
}

/// The console's `e` and `hapticlab evaluate DIR --fallback` on the same
/// folder: the same method, k and numbers, and both say they fell back.
#[test]
fn the_consoles_e_and_evaluate_fallback_agree() {
    let dir = TempDir::new().unwrap();
    let shipped = Path::new(REPO).join("recordings/thesis-sim");
    let session = dir.path().join("session");
    for label in ["S1", "S2", "S3", "S4"] {
        fs::create_dir_all(session.join(label)).unwrap();
        for i in 1..=5 {
            let name = format!("{label}_00{i}.csv.gz");
            fs::copy(
                shipped.join(label).join(&name),
                session.join(label).join(&name),
            )
            .unwrap();
        }
    }
    let r = run(&["evaluate", p(&session)]);
    assert_eq!(
        r.code,
        Some(2),
        "without --fallback the holdout is refused: {r:?}"
    );
    assert!(r.stderr.contains("--fallback"), "{r:?}");
    let r = run(&["evaluate", p(&session), "--fallback"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let header = r.stdout.lines().next().unwrap();
    assert!(
        header.contains("5-fold cross-validation, seed 0"),
        "{header}"
    );
    assert!(
        header.contains("fallback: the holdout split needs 30"),
        "{header}"
    );
    let cli: Value = {
        let r = run(&["evaluate", p(&session), "--fallback", "--json"]);
        assert_eq!(r.code, Some(0), "{r:?}");
        serde_json::from_str(&r.stdout).unwrap()
    };

    let lp = LoadedProfile::thesis();
    let e = hapticlab::console::dataset::evaluate_dataset(&lp, &session).unwrap();
    assert_eq!(e.method, "5-fold cross-validation, seed 0");
    assert!(
        e.note.contains("evaluating by stratified 5-fold"),
        "{}",
        e.note
    );
    let kept: Value = serde_json::from_str(
        &fs::read_to_string(session.join(hapticlab::console::dataset::REPORT_JSON)).unwrap(),
    )
    .unwrap();
    for key in [
        "labels",
        "confusion",
        "accuracy",
        "per_class",
        "predictions",
        "method",
        "folds",
        "accuracy_mean",
        "macro_f1",
    ] {
        assert_eq!(kept[key], cli[key], "{key}");
    }
    let k_cli: Vec<u64> = cli["folds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["k"].as_u64().unwrap())
        .collect();
    assert!(
        k_cli
            .iter()
            .all(|k| kept["k_used"].as_array().unwrap().contains(&(*k).into()))
    );
    let text = fs::read_to_string(session.join(hapticlab::console::dataset::REPORT_FILE)).unwrap();
    assert_eq!(
        text.lines().next(),
        Some(header),
        "the kept text is the command's"
    );
    assert_eq!(
        e.report.correct(),
        cli["confusion"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .map(|(i, row)| row[i].as_u64().unwrap() as usize)
            .sum::<usize>()
    );
}
