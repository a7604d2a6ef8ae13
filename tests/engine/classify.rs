//! k-NN votes, tie-breaking, neighbour order, model files and their errors.

use hapticlab::classify::{ClassifyError, MODEL_FORMAT, Model, TrainingExample};
use hapticlab::profile::{Classifier, Detrend, Metric};

use crate::common::{analysis, ex};

fn knn(k: usize) -> Classifier {
    Classifier {
        k,
        metric: Metric::Euclidean,
        ..Classifier::default()
    }
}

fn two_clusters() -> Vec<TrainingExample> {
    vec![
        ex("b1", "B", &[10.0, 10.0]),
        ex("a1", "A", &[0.0, 0.0]),
        ex("a2", "A", &[0.0, 1.0]),
        ex("b2", "B", &[10.0, 11.0]),
        ex("a3", "A", &[1.0, 0.0]),
    ]
}

#[test]
fn the_majority_of_the_k_nearest_wins() {
    let m = Model::train("t", &analysis(2), &knn(3), two_clusters()).unwrap();
    assert_eq!(m.labels, vec!["A", "B"]);
    assert_eq!(m.format, MODEL_FORMAT);
    let p = m.classify(&[0.2, 0.2]).unwrap();
    assert_eq!(p.label, "A");
    assert_eq!(p.votes, vec![("A".to_string(), 3), ("B".to_string(), 0)]);
    // With k = 5 the three A's still outvote the two B's, even near B.
    let m = Model::train("t", &analysis(2), &knn(5), two_clusters()).unwrap();
    let p = m.classify(&[9.0, 9.0]).unwrap();
    assert_eq!(p.label, "A");
    assert_eq!(p.votes[0], ("A".to_string(), 3));
    assert_eq!(p.votes[1], ("B".to_string(), 2));
}

#[test]
fn neighbours_come_nearest_first_and_keep_training_order_on_ties() {
    let m = Model::train("t", &analysis(2), &knn(4), two_clusters()).unwrap();
    let p = m.classify(&[0.0, 0.0]).unwrap();
    let files: Vec<&str> = p.neighbours.iter().map(|n| n.file.as_str()).collect();
    // a2 and a3 are both at distance 1; a2 comes first in training.
    assert_eq!(files, vec!["a1", "a2", "a3", "b1"]);
    let d: Vec<f64> = p.neighbours.iter().map(|n| n.distance).collect();
    assert_eq!(d[..3], [0.0, 1.0, 1.0]);
    assert!((d[3] - 200f64.sqrt()).abs() < 1e-12);
    assert_eq!(p.neighbours[3].label, "B");
}

#[test]
fn a_tie_goes_to_the_closer_class_then_to_label_order() {
    // One vote each; B's neighbour is nearer, so B wins although A sorts first.
    let examples = vec![ex("a", "A", &[2.0]), ex("b", "B", &[-1.0])];
    let m = Model::train("t", &analysis(1), &knn(2), examples).unwrap();
    let p = m.classify(&[0.0]).unwrap();
    assert_eq!(p.label, "B");
    assert_eq!(p.votes, vec![("B".to_string(), 1), ("A".to_string(), 1)]);

    // Two votes each; B holds the nearest example but its summed distance
    // (0.5 + 3.9 = 4.4) exceeds A's (2 + 2 = 4), so A wins.
    let examples = vec![
        ex("a1", "A", &[2.0]),
        ex("a2", "A", &[-2.0]),
        ex("b1", "B", &[0.5]),
        ex("b2", "B", &[-3.9]),
        ex("c1", "C", &[100.0]),
    ];
    let m = Model::train("t", &analysis(1), &knn(4), examples).unwrap();
    let p = m.classify(&[0.0]).unwrap();
    assert_eq!(p.label, "A");
    assert_eq!(p.neighbours[0].file, "b1");
    assert_eq!(
        p.votes,
        vec![
            ("A".to_string(), 2),
            ("B".to_string(), 2),
            ("C".to_string(), 0)
        ]
    );

    // A complete tie (same votes, same distances): label order.
    let examples = vec![ex("b", "B", &[1.0]), ex("a", "A", &[-1.0])];
    let m = Model::train("t", &analysis(1), &knn(2), examples).unwrap();
    assert_eq!(m.classify(&[0.0]).unwrap().label, "A");
}

#[test]
fn queries_of_the_wrong_length_or_not_finite_are_errors() {
    let m = Model::train("t", &analysis(2), &knn(3), two_clusters()).unwrap();
    assert!(matches!(
        m.classify(&[1.0]),
        Err(ClassifyError::QueryLength {
            expected: 2,
            found: 1
        })
    ));
    assert!(matches!(
        m.classify(&[1.0, f64::NAN]),
        Err(ClassifyError::QueryNonFinite { index: 1, .. })
    ));
}

#[test]
fn training_refuses_bad_examples() {
    let a = analysis(2);
    assert!(matches!(
        Model::train("t", &a, &knn(1), vec![]),
        Err(ClassifyError::NoExamples)
    ));
    let mut bad = two_clusters();
    bad[2].features.push(3.0);
    let err = Model::train("t", &a, &knn(1), bad).unwrap_err();
    assert_eq!(
        err.to_string(),
        "a2: has 3 features, but the analysis settings give 2"
    );
    let mut bad = two_clusters();
    bad[0].features[1] = f64::INFINITY;
    assert!(matches!(
        Model::train("t", &a, &knn(1), bad),
        Err(ClassifyError::NonFinite { index: 1, .. })
    ));
    let err = Model::train("t", &a, &knn(6), two_clusters()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "classifier.k = 6 but there are only 5 training examples"
    );
}

#[test]
fn a_model_survives_a_save_and_load() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    // Features that do not print short in decimal.
    let mut examples = two_clusters();
    examples[0].features = vec![0.1 + 0.2, 1.0 / 3.0];
    let m = Model::train("thesis", &analysis(2), &knn(3), examples).unwrap();
    m.save(&path, &[], hapticlab::io::Existing::Keep).unwrap();
    let back = Model::load(&path).unwrap();
    assert_eq!(back, m);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("\"format\": \"hapticlab model v1\""),
        "{text}"
    );
}

#[test]
fn loading_names_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let missing = dir.path().join("missing.json");
    assert!(matches!(
        Model::load(&missing),
        Err(ClassifyError::Io { .. })
    ));

    let p = write(
        "bad.json",
        "{\n  \"format\": \"hapticlab model v1\",\n  oops\n}\n",
    );
    let err = Model::load(&p).unwrap_err();
    assert!(
        matches!(err, ClassifyError::Malformed { line: 3, .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("bad.json:3:3: not valid JSON"),
        "{err}"
    );

    let p = write("other.json", "{\"name\": \"thesis\"}");
    let err = Model::load(&p).unwrap_err();
    assert!(matches!(err, ClassifyError::NotAModel { .. }), "{err:?}");
    assert!(
        err.to_string()
            .ends_with("not a hapticlab model (no \"format\" field)")
    );
    let p = write("list.json", "[1, 2]");
    assert!(matches!(
        Model::load(&p),
        Err(ClassifyError::NotAModel { .. })
    ));

    let p = write("v9.json", "{\"format\": \"hapticlab model v9\"}");
    let err = Model::load(&p).unwrap_err();
    assert!(
        err.to_string()
            .ends_with("model format \"hapticlab model v9\" is not \"hapticlab model v1\", which this version reads"),
        "{err}"
    );

    let p = write(
        "partial.json",
        "{\n  \"format\": \"hapticlab model v1\",\n  \"profile\": 3\n}",
    );
    let err = Model::load(&p).unwrap_err();
    assert!(matches!(err, ClassifyError::Schema { .. }), "{err:?}");

    // Well-formed but inconsistent: k larger than the examples.
    let m = Model::train("t", &analysis(2), &knn(3), two_clusters()).unwrap();
    let mut text = serde_json::to_value(&m).unwrap();
    text["classifier"]["k"] = 50.into();
    let p = write("k.json", &text.to_string());
    let err = Model::load(&p).unwrap_err();
    assert!(
        err.to_string().ends_with(
            "not a valid model: classifier.k = 50 but there are only 5 training examples"
        ),
        "{err}"
    );
    let mut text = serde_json::to_value(&m).unwrap();
    text["labels"] = serde_json::json!(["B", "A"]);
    let p = write("labels.json", &text.to_string());
    assert!(matches!(
        Model::load(&p),
        Err(ClassifyError::Invalid { .. })
    ));
}

#[test]
fn other_analysis_settings_are_refused_by_name() {
    let a = analysis(2);
    let m = Model::train("t", &a, &knn(3), two_clusters()).unwrap();
    assert!(m.check_settings(&a).is_ok());
    let mut other = a.clone();
    other.window = [0.06, 0.0897];
    let err = m.check_settings(&other).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the model was trained with analysis.window = [0.0,0.0897] but the profile has \
         analysis.window = [0.06,0.0897]; retrain the model under this profile"
    );
    let mut other = a.clone();
    other.detrend = Detrend::Linear;
    assert!(matches!(
        m.check_settings(&other),
        Err(ClassifyError::SettingsDiffer {
            field: "analysis.detrend",
            ..
        })
    ));
    let mut other = a;
    other.channel = "fy_n".into();
    assert!(
        m.check_settings(&other)
            .unwrap_err()
            .to_string()
            .contains("analysis.channel = \"y_m\"")
    );
}
