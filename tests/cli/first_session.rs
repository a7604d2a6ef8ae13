//! A first training session gives a sound model, or says why not: with
//! fewer scans per texture than the profile's k, `train` and `evaluate`
//! choose k by cross-validation inside the training part and say so in one
//! line; the profile's k stays wherever the data supports it; a model
//! trained under other classifier settings is never used silently.

use std::fs;
use std::path::{Path, PathBuf};

use hapticlab::classify::{Model, TrainingExample};
use hapticlab::evaluate::cv::{cross_validate, make_folds};
use hapticlab::profile::{Classifier, Metric, SplitMethod};
use serde_json::Value;

use crate::common::{REPO, analysis, p};

fn knn(k: usize) -> Classifier {
    Classifier {
        k,
        metric: Metric::Euclidean,
        ..Classifier::default()
    }
}

/// Four textures in a row, `per_class` scans each, a little spread: each
/// texture's nearest strangers are its neighbours in the row.
fn four_textures(per_class: usize) -> Vec<TrainingExample> {
    let mut out = Vec::new();
    for (c, label) in ["S1", "S2", "S3", "S4"].iter().enumerate() {
        for i in 0..per_class {
            let jitter = (i as f64 * 0.37).sin();
            out.push(TrainingExample {
                file: format!("{label}/{label}_{i:03}.csv"),
                label: label.to_string(),
                features: vec![10.0 * c as f64 + jitter, 0.5 * jitter],
            });
        }
    }
    out
}

fn loo_accuracy(examples: &[TrainingExample], k: usize) -> (f64, Option<String>) {
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    let folds = make_folds(&labels, None, SplitMethod::LeaveOneOut, 0, 0).unwrap();
    let r = cross_validate(
        examples,
        &hapticlab::evaluate::cv::Dealt::plain(folds.clone()),
        "t",
        &analysis(2),
        &knn(k),
        "leave-one-out",
        0,
        2,
    )
    .unwrap();
    (r.accuracy, r.k_notice())
}

#[test]
fn five_scans_per_texture_and_k_10_give_a_sound_model_and_say_why() {
    // With the profile's k = 10, each left-out scan has 4 of its own and
    // 5 of a neighbour's among its 10 nearest: every one would be wrong.
    let (accuracy, notice) = loo_accuracy(&four_textures(5), 10);
    assert!(accuracy >= 0.9, "leave-one-out accuracy {accuracy}");
    assert_eq!(
        notice.as_deref(),
        Some(
            "k = 10 needs at least 10 scans per texture, S1 has 4 in a training part: \
             k chosen by 5-fold CV inside each such part (k = 1 in 20 folds)"
        )
    );

    let m = Model::train_adapting_k("t", &analysis(2), &knn(10), four_textures(5)).unwrap();
    assert_eq!(m.classifier.k, 1);
    assert_eq!(
        m.k_notice().as_deref(),
        Some(
            "k = 10 needs at least 10 scans per texture, S1 has 5: using k = 1, chosen by 5-fold CV"
        )
    );
    // The choice is made among the k each texture can support.
    let tried: Vec<usize> = m
        .k_selection
        .as_ref()
        .unwrap()
        .iter()
        .map(|s| s.k)
        .collect();
    assert_eq!(tried, [1, 3, 5]);
}

#[test]
fn the_profiles_k_stays_where_every_texture_has_enough_scans() {
    let m = Model::train_adapting_k("t", &analysis(2), &knn(10), four_textures(10)).unwrap();
    assert_eq!(m.classifier.k, 10);
    assert_eq!(m.k_fallback, None);
    assert_eq!(m.k_selection, None);
    assert_eq!(m.k_notice(), None);
    let (_, notice) = loo_accuracy(&four_textures(11), 10);
    assert_eq!(notice, None);
}

#[test]
fn a_chosen_k_survives_the_model_file_and_is_checked_against_the_profile() {
    let m = Model::train_adapting_k("t", &analysis(2), &knn(10), four_textures(5)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    m.save(&path, &[], hapticlab::io::Existing::Keep).unwrap();
    let back = Model::load(&path).unwrap();
    assert_eq!(back, m);
    assert_eq!(back.k_notice(), m.k_notice());
    // Under the profile it was trained with, the model fits; under k = 3 it
    // does not, although it happens to classify with k = 1.
    back.check_classifier(&knn(10)).unwrap();
    let err = back.check_classifier(&knn(3)).unwrap_err().to_string();
    assert_eq!(
        err,
        "the model was trained with classifier.k = 10 but the profile has classifier.k = 3; \
         retrain the model under this profile"
    );
    let mut cosine = knn(10);
    cosine.metric = Metric::Cosine;
    let err = back.check_classifier(&cosine).unwrap_err().to_string();
    assert!(err.contains("classifier.metric = \"euclidean\""), "{err}");
    // A model trained with the profile's k as is.
    let plain = Model::train_adapting_k("t", &analysis(2), &knn(3), four_textures(5)).unwrap();
    plain.check_classifier(&knn(3)).unwrap();
    assert!(plain.check_classifier(&knn(10)).is_err());
}

fn hapticlab(args: &[&str]) -> (i32, String, String) {
    let out = crate::common::hapticlab()
        .args(args)
        .output()
        .expect("run hapticlab");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn simulate(out: &Path, per_class: usize, seed: u64) {
    let (code, stdout, stderr) = hapticlab(&[
        "simulate",
        "--out",
        p(out),
        "--per-class",
        &per_class.to_string(),
        "--seed",
        &seed.to_string(),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
}

fn csv_files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(csv_files(&path));
        } else if path.extension().is_some_and(|e| e == "csv") {
            found.push(path);
        }
    }
    found.sort();
    found
}

#[test]
fn five_simulated_scans_per_texture_name_fresh_scans_right() {
    let dir = tempfile::tempdir().unwrap();
    let (s5, fresh, model) = (
        dir.path().join("s5"),
        dir.path().join("fresh"),
        dir.path().join("m.json"),
    );
    simulate(&s5, 5, 7);
    simulate(&fresh, 3, 99);

    // Leave-one-out with the thesis profile (k = 10): the JSON on standard
    // output stays JSON, the notice goes to standard error.
    let (code, stdout, stderr) = hapticlab(&["evaluate", p(&s5), "--loo", "--json"]);
    assert_eq!(code, 0, "{stderr}");
    let r: Value = serde_json::from_str(&stdout).expect("evaluate --json prints JSON only");
    let accuracy = r["accuracy"].as_f64().unwrap();
    assert!(accuracy >= 0.9, "leave-one-out accuracy {accuracy}");
    let notes: Vec<&str> = stderr.lines().filter(|l| l.starts_with("note: ")).collect();
    assert_eq!(notes.len(), 1, "{stderr}");
    assert!(
        notes[0].starts_with(
            "note: k = 10 needs at least 10 scans per texture, S1 has 4 in a training part: \
             k chosen by 5-fold CV inside each such part (k = "
        ),
        "{stderr}"
    );

    let (code, stdout, stderr) = hapticlab(&["train", p(&s5), "--out", p(&model)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("note: k = 10 needs at least 10 scans per texture, S1 has 5: using k = "),
        "{stderr}"
    );
    assert!(stdout.contains("on 20 recordings of 4 classes"), "{stdout}");

    let files = csv_files(&fresh);
    assert_eq!(files.len(), 12);
    let mut args = vec!["classify", "--json", "--model", p(&model)];
    args.extend(files.iter().map(|f| p(f)));
    let (code, stdout, stderr) = hapticlab(&args);
    assert_eq!(code, 0, "{stderr}");
    let rows: Value = serde_json::from_str(&stdout).unwrap();
    let rows = rows.as_array().unwrap();
    let right = rows.iter().filter(|r| r["label"] == r["predicted"]).count();
    assert!(
        right * 10 >= rows.len() * 9,
        "{right} of {} right",
        rows.len()
    );

    // The same model under a profile with k = 3 is used, but not silently.
    let text = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let k3 = dir.path().join("k3.toml");
    fs::write(&k3, text.replace("\nk = 10\n", "\nk = 3\n")).unwrap();
    let (code, _, stderr) = hapticlab(&[
        "classify",
        "--profile",
        p(&k3),
        "--model",
        p(&model),
        p(&files[0]),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains(
            "the model was trained with classifier.k = 10 but the profile has classifier.k = 3"
        ),
        "{stderr}"
    );
}
