use std::path::Path;

use super::*;
use crate::classify::TrainingExample;
use crate::profile::LoadedProfile;

fn example(file: &str, label: &str, x: f64, n: usize) -> TrainingExample {
    TrainingExample {
        file: file.into(),
        label: label.into(),
        features: vec![x; n],
    }
}

fn model(examples: Vec<TrainingExample>) -> Model {
    let lp = LoadedProfile::thesis();
    Model::train_adapting_k(
        "thesis",
        &lp.profile.analysis,
        &lp.profile.classifier,
        examples,
    )
    .unwrap()
}

fn whole(x: f64, n: usize) -> Query {
    Query {
        features: Features::Whole(vec![x; n]),
        incomplete: None,
    }
}

#[test]
fn a_recording_not_trained_on_is_answered_by_the_whole_model() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let m = model(vec![
        example("d/S1/a.csv", "S1", 0.0, n),
        example("d/S2/b.csv", "S2", 10.0, n),
    ]);
    let a = Predictor::new(&m)
        .answer(&whole(1.0, n), Path::new("d/S1/new.csv"))
        .unwrap();
    assert_eq!(a.prediction.label, "S1");
    assert!(!a.left_out);
    assert!(a.windows.is_none());
}

#[test]
fn a_training_recording_is_left_out_of_the_model() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    // Left in, a.csv would be its own nearest neighbour (S1); left out,
    // the nearest is b.csv (S2).
    let m = model(vec![
        example("d/S1/a.csv", "S1", 0.0, n),
        example("d/S1/c.csv", "S1", 100.0, n),
        example("d/S2/b.csv", "S2", 1.0, n),
    ]);
    let a = Predictor::new(&m)
        .answer(&whole(0.0, n), Path::new("d/S1/a.csv"))
        .unwrap();
    assert!(a.left_out);
    assert_eq!(a.prediction.label, "S2");
    assert!(Predictor::new(&m).trained_on(Path::new("d/S1/a.csv")));
    assert!(!Predictor::new(&m).trained_on(Path::new("d/S1/z.csv")));
}

#[test]
fn a_textures_only_scan_has_no_answer_that_could_be_right() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let m = model(vec![
        example("d/S1/a.csv", "S1", 0.0, n),
        example("d/S1/c.csv", "S1", 1.0, n),
        example("d/S4/only.csv", "S4", 10.0, n),
    ]);
    let e = Predictor::new(&m)
        .answer(&whole(10.0, n), Path::new("d/S4/only.csv"))
        .unwrap_err();
    assert!(
        matches!(&e, PredictError::NoOtherScans { label } if label == "S4"),
        "{e}"
    );
    assert!(e.is_unanswerable());
    assert!(e.to_string().contains("S4 has no other scans"), "{e}");
}

#[test]
fn the_models_only_scan_says_it_is_left_out() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let m = model(vec![example("d/S1/a.csv", "S1", 0.0, n)]);
    let e = Predictor::new(&m)
        .answer(&whole(0.0, n), Path::new("d/S1/a.csv"))
        .unwrap_err();
    assert!(matches!(e, PredictError::OnlyScan), "{e}");
    assert!(e.to_string().contains("only training scan"), "{e}");
}

#[test]
fn an_incomplete_scan_is_answered_and_says_so() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let m = model(vec![
        example("d/S1/a.csv", "S1", 0.0, n),
        example("d/S2/b.csv", "S2", 10.0, n),
    ]);
    let mut q = whole(9.0, n);
    q.incomplete = Some("stopped by the user".into());
    let a = Predictor::new(&m)
        .answer(&q, Path::new("d/S2/new.csv"))
        .unwrap();
    assert_eq!(a.prediction.label, "S2");
    assert_eq!(a.incomplete.as_deref(), Some("stopped by the user"));
}

#[test]
fn a_whole_window_query_to_a_sub_window_model_is_refused() {
    let lp = LoadedProfile::thesis();
    let mut an = lp.profile.analysis.clone();
    an.windows = Some(crate::profile::Windows {
        length: 0.0147,
        hop: 0.0075,
    });
    an.bins = [1, 24];
    let n = an.features_per_channel();
    let m = Model::train_adapting_k(
        "thesis",
        &an,
        &lp.profile.classifier,
        vec![
            example("d/S1/a.csv", "S1", 0.0, n),
            example("d/S2/b.csv", "S2", 5.0, n),
        ],
    )
    .unwrap();
    let e = Predictor::new(&m)
        .answer(&whole(0.0, n), Path::new("x.csv"))
        .unwrap_err();
    assert!(matches!(e, PredictError::NoSubWindows), "{e}");
    let q = Query {
        features: Features::Windows(vec![vec![0.0; n], vec![0.1; n], vec![5.0; n]]),
        incomplete: None,
    };
    let a = Predictor::new(&m).answer(&q, Path::new("x.csv")).unwrap();
    assert_eq!(a.prediction.label, "S1");
    assert_eq!(a.windows.as_ref().unwrap().windows.len(), 3);
}

#[test]
fn a_query_over_the_comparison_limit_is_refused_before_any_is_made() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let examples: Vec<_> = (0..10_000)
        .map(|i| {
            example(
                &format!("d/S{}/{i}.csv", i % 2),
                &format!("S{}", i % 2),
                i as f64,
                n,
            )
        })
        .collect();
    let m = model(examples);
    // 20,500 sub-windows × 10,000 examples × 49 features > 10^10.
    let q = Query {
        features: Features::Windows(vec![Vec::new(); 20_500]),
        incomplete: None,
    };
    let e = Predictor::new(&m)
        .answer(&q, Path::new("d/S1/long.csv"))
        .unwrap_err();
    assert!(matches!(e, PredictError::TooMuchWork { .. }), "{e}");
    assert!(e.is_bad_input());
    let text = e.to_string();
    assert!(
        text.starts_with("d/S1/long.csv: ") && text.contains("windows.hop"),
        "{text}"
    );
    // Under the limit, the same model answers (here: a whole window).
    let a = Predictor::new(&m).answer(&whole(1.0, n), Path::new("d/S1/new.csv"));
    assert!(a.is_ok(), "{a:?}");
}

#[test]
fn a_training_recording_of_a_moved_folder_is_still_left_out() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let dir = tempfile::tempdir().unwrap();
    // Trained as day1/S1/a.csv, since moved to day1-copy/S1/a.csv.
    let moved = dir.path().join("day1-copy/S1/a.csv");
    std::fs::create_dir_all(moved.parent().unwrap()).unwrap();
    std::fs::write(&moved, "").unwrap();
    let gone = dir.path().join("day1/S1/a.csv").display().to_string();
    let m = model(vec![
        example(&gone, "S1", 0.0, n),
        example("d/S1/c.csv", "S1", 100.0, n),
        example("d/S2/b.csv", "S2", 1.0, n),
    ]);
    let p = Predictor::new(&m);
    let a = p.answer(&whole(0.0, n), &moved).unwrap();
    assert!(a.left_out, "predicted by itself");
    assert_eq!(a.prediction.label, "S2");
    // A recording of the same name whose trained file still exists is
    // another recording: not left out.
    let kept = dir.path().join("kept/S1/a.csv");
    std::fs::create_dir_all(kept.parent().unwrap()).unwrap();
    std::fs::write(&kept, "").unwrap();
    let m = model(vec![
        example(&kept.display().to_string(), "S1", 0.0, n),
        example("d/S1/c.csv", "S1", 100.0, n),
        example("d/S2/b.csv", "S2", 1.0, n),
    ]);
    let a = Predictor::new(&m).answer(&whole(0.0, n), &moved).unwrap();
    assert!(!a.left_out);
}

/// A training recording relabelled since (moved into another label folder
/// under another name) is found by its features, bit for bit, and left
/// out; a recording that only resembles it is not.
#[test]
fn a_relabelled_training_recording_is_left_out_by_its_features() {
    let n = LoadedProfile::thesis().profile.analysis.feature_count();
    let dir = tempfile::tempdir().unwrap();
    let now = dir.path().join("ds/S2/S2_031.csv");
    std::fs::create_dir_all(now.parent().unwrap()).unwrap();
    std::fs::write(&now, "").unwrap();
    let gone = dir.path().join("ds/S1/S1_001.csv").display().to_string();
    let m = model(vec![
        example(&gone, "S1", 0.5, n),
        example("d/S1/c.csv", "S1", 100.0, n),
        example("d/S2/b.csv", "S2", 1.0, n),
    ]);
    let p = Predictor::new(&m);
    let a = p.answer(&whole(0.5, n), &now).unwrap();
    assert!(a.left_out, "predicted by itself");
    assert_eq!(a.prediction.label, "S2");
    let near = p.answer(&whole(0.5 + 1e-12, n), &now).unwrap();
    assert!(!near.left_out, "a near copy is another recording");
    assert_eq!(near.prediction.label, "S1");
}

/// A sub-window analysis of 24 features and `count` windows, ten a file,
/// of two labels.
fn sub_window_examples(count: usize) -> (crate::profile::Analysis, Vec<TrainingExample>) {
    let mut an = LoadedProfile::thesis().profile.analysis.clone();
    an.windows = Some(crate::profile::Windows {
        length: 0.0147,
        hop: 0.0075,
    });
    an.bins = [1, 24];
    let n = an.features_per_channel();
    let examples = (0..count)
        .map(|i| {
            let label = i % 2;
            let mut f = vec![10.0 * label as f64; n];
            f[i % n] += 0.5;
            TrainingExample {
                file: format!("d/S{label}/{}.csv", i / 20),
                label: format!("S{label}"),
                features: f,
            }
        })
        .collect();
    (an, examples)
}

#[test]
fn a_ridge_model_is_counted_by_its_scores_not_by_a_k_nn_s_comparisons() {
    let (an, examples) = sub_window_examples(10_000);
    let n = an.features_per_channel();
    // 50,000 sub-windows × 10,000 examples × 24 features > 10^10 for a
    // k-NN; one score a label for a ridge.
    let q = Query {
        features: Features::Windows(vec![vec![10.0; n]; 50_000]),
        incomplete: None,
    };
    let knn = crate::profile::Classifier {
        k: 1,
        ..Default::default()
    };
    let m = Model::train("t", &an, &knn, examples.clone()).unwrap();
    let e = Predictor::new(&m)
        .answer(&q, Path::new("d/S1/long.csv"))
        .unwrap_err();
    assert!(matches!(e, PredictError::TooMuchWork { .. }), "{e}");
    let ridge = crate::profile::Classifier {
        method: Method::Ridge,
        ..Default::default()
    };
    let m = Model::train("t", &an, &ridge, examples).unwrap();
    let a = Predictor::new(&m)
        .answer(&q, Path::new("d/S1/long.csv"))
        .unwrap();
    assert_eq!(a.prediction.label, "S1");
    let w = answer_work(&m, 50_000, 0);
    assert_eq!(w.classify, 50_000.0 * n as f64 * 2.0);
}

#[test]
fn a_training_recording_s_answer_counts_the_examples_left_once_it_is_left_out() {
    let (an, examples) = sub_window_examples(400);
    let n = an.features_per_channel();
    // d/S1/0.csv is 10 of the 400 windows: 390 are left.
    let own = 10;
    for k in [1, crate::profile::K_AUTO] {
        let c = crate::profile::Classifier {
            k,
            ..Default::default()
        };
        let m = Model::train("t", &an, &c, examples.clone()).unwrap();
        let w = answer_work(&m, 3, own);
        assert_eq!(w.classify, 3.0 * 390.0 * n as f64);
        assert_eq!((w.examples, w.features), (390, n));
        assert_eq!(answer_work(&m, 3, 0).classify, 3.0 * 400.0 * n as f64);
    }
    for method in [Method::Ridge, Method::Lda] {
        let c = crate::profile::Classifier {
            method,
            ..Default::default()
        };
        let m = Model::train("t", &an, &c, examples.clone()).unwrap();
        let w = answer_work(&m, 3, own);
        assert_eq!(w.classify, 3.0 * n as f64 * 2.0);
        let text = w.describe(&m, 3);
        assert!(
            text.contains("scoring its 3 sub-window(s) (24 features) for 2 labels"),
            "{text}"
        );
    }
    // A training recording of the model is found and its windows counted.
    let q = Query {
        features: Features::Windows(vec![vec![10.0; n]; 3]),
        incomplete: None,
    };
    let m = model_of(&an, examples);
    let p = Predictor::new(&m);
    let same = p.same_recording(Path::new("d/S1/0.csv"), &q);
    assert_eq!(m.examples.iter().filter(|e| same(&e.file)).count(), own);
}

fn model_of(an: &crate::profile::Analysis, examples: Vec<TrainingExample>) -> Model {
    let c = crate::profile::Classifier {
        k: 1,
        ..Default::default()
    };
    Model::train("t", an, &c, examples).unwrap()
}
