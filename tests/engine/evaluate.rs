//! Splits, the confusion matrix, the rates and the reports.

use hapticlab::classify::{Model, TrainingExample};
use hapticlab::evaluate::{EvaluateError, evaluate, split};
use hapticlab::profile::{Classifier, Evaluation, Metric};

use crate::common::{analysis, ex};

/// `per_class` examples of each label, interleaved, files named `<label>/<i>.csv`.
fn recordings(labels: &[&str], per_class: usize) -> Vec<TrainingExample> {
    (0..per_class)
        .flat_map(|i| {
            labels
                .iter()
                .map(move |l| ex(&format!("{l}/{i:02}.csv"), l, &[i as f64]))
        })
        .collect()
}

fn eval(train: usize, test: usize, seed: Option<u64>) -> Evaluation {
    Evaluation {
        train_per_class: train,
        test_per_class: test,
        shuffle_seed: seed,
        ..Evaluation::default()
    }
}

fn files(x: &[TrainingExample]) -> Vec<&str> {
    x.iter().map(|e| e.file.as_str()).collect()
}

#[test]
fn split_takes_each_class_in_the_given_order() {
    let s = split(recordings(&["S2", "S1"], 5), &eval(2, 2, None)).unwrap();
    assert_eq!(
        files(&s.train),
        ["S1/00.csv", "S1/01.csv", "S2/00.csv", "S2/01.csv"]
    );
    assert_eq!(
        files(&s.test),
        ["S1/02.csv", "S1/03.csv", "S2/02.csv", "S2/03.csv"]
    );
}

#[test]
fn a_gap_leaves_recordings_out_between_training_and_test() {
    let gapped = Evaluation {
        gap_per_class: 1,
        ..eval(2, 2, None)
    };
    let s = split(recordings(&["S1", "S2"], 5), &gapped).unwrap();
    assert_eq!(
        files(&s.train),
        ["S1/00.csv", "S1/01.csv", "S2/00.csv", "S2/01.csv"]
    );
    assert_eq!(
        files(&s.test),
        ["S1/03.csv", "S1/04.csv", "S2/03.csv", "S2/04.csv"]
    );
    let e = split(recordings(&["S1", "S2"], 4), &gapped).unwrap_err();
    assert!(
        e.to_string()
            .contains("needs 5 (2 to train, 1 left out between and 2 to test)"),
        "{e}"
    );
}

#[test]
fn a_seeded_shuffle_is_repeatable_and_depends_on_the_seed() {
    let all = recordings(&["S1", "S2", "S3"], 30);
    let a = split(all.clone(), &eval(20, 10, Some(7))).unwrap();
    let b = split(all.clone(), &eval(20, 10, Some(7))).unwrap();
    let c = split(all.clone(), &eval(20, 10, Some(8))).unwrap();
    assert_eq!(a, b);
    assert_ne!(files(&a.train), files(&c.train));
    assert_ne!(a, split(all.clone(), &eval(20, 10, None)).unwrap());
    // Still 20 + 10 distinct recordings of each class.
    for label in ["S1", "S2", "S3"] {
        let mut mine: Vec<&str> = a
            .train
            .iter()
            .chain(&a.test)
            .filter(|e| e.label == label)
            .map(|e| e.file.as_str())
            .collect();
        assert_eq!(a.train.iter().filter(|e| e.label == label).count(), 20);
        mine.sort();
        mine.dedup();
        assert_eq!(mine.len(), 30);
    }
    // A class's split does not depend on the other classes.
    let only_s2 = split(recordings(&["S2"], 30), &eval(20, 10, Some(7))).unwrap();
    let s2_train: Vec<&str> = files(&a.train)
        .into_iter()
        .filter(|f| f.starts_with("S2"))
        .collect();
    assert_eq!(files(&only_s2.train), s2_train);
}

#[test]
fn a_class_short_of_examples_is_named() {
    let mut all = recordings(&["S1", "S2"], 30);
    all.retain(|e| !(e.label == "S2" && e.features[0] >= 25.0));
    let err = split(all, &eval(20, 10, None)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "class \"S2\" has 25 example(s) but the split needs 30 (20 to train and 10 to test)"
    );
    assert!(matches!(
        split(vec![], &eval(1, 1, None)),
        Err(EvaluateError::NoExamples)
    ));
}

/// S1 near 0, S2 near 10, k = 1; four tests: one right S1, one S1 taken for
/// S2, one right S2, and one of S3, a class the model never saw.
fn hand_made() -> (Model, Vec<TrainingExample>) {
    let train = vec![
        ex("s1a", "S1", &[0.0]),
        ex("s1b", "S1", &[0.1]),
        ex("s2a", "S2", &[10.0]),
        ex("s2b", "S2", &[10.1]),
    ];
    let classifier = Classifier {
        k: 1,
        metric: Metric::Euclidean,
        ..Classifier::default()
    };
    let model = Model::train("t", &analysis(1), &classifier, train).unwrap();
    let test = vec![
        ex("t1", "S1", &[0.05]),
        ex("t2", "S1", &[9.9]),
        ex("t3", "S2", &[10.05]),
        ex("t4", "S3", &[0.0]),
    ];
    (model, test)
}

#[test]
fn the_confusion_matrix_counts_true_against_classified() {
    let (model, test) = hand_made();
    let r = evaluate(&model, &test).unwrap();
    assert_eq!(r.labels, ["S1", "S2", "S3"]);
    assert_eq!(
        r.confusion,
        vec![vec![1, 1, 0], vec![0, 1, 0], vec![1, 0, 0]]
    );
    assert_eq!(r.accuracy, 0.5);
    let rates: Vec<(usize, f64, f64)> = r
        .per_class
        .iter()
        .map(|c| (c.n, c.success_rate, c.error_rate))
        .collect();
    assert_eq!(rates, [(2, 0.5, 0.5), (1, 1.0, 0.0), (1, 0.0, 1.0)]);
    assert_eq!(r.train, ["s1a", "s1b", "s2a", "s2b"]);
    assert_eq!(r.test, ["t1", "t2", "t3", "t4"]);
    assert_eq!(r.predictions[1].predicted, "S2");
    assert_eq!(
        r.predictions[1].votes,
        vec![("S2".to_string(), 1), ("S1".to_string(), 0)]
    );
    assert!(matches!(evaluate(&model, &[]), Err(EvaluateError::NoTest)));
}

#[test]
fn the_json_report_has_the_documented_shape() {
    let (model, test) = hand_made();
    let r = evaluate(&model, &test).unwrap();
    let v = serde_json::to_value(&r).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    let mut want = vec![
        "labels",
        "confusion",
        "accuracy",
        "per_class",
        "train",
        "test",
        "predictions",
    ];
    want.sort();
    let mut keys = keys;
    keys.sort();
    assert_eq!(keys, want);
    assert_eq!(
        v["per_class"][0],
        serde_json::json!({"label": "S1", "n": 2, "success_rate": 0.5, "error_rate": 0.5})
    );
    assert_eq!(
        v["predictions"][0],
        serde_json::json!({"file": "t1", "label": "S1", "predicted": "S1", "votes": [["S1", 1], ["S2", 0]]})
    );
}

#[test]
fn the_table_follows_table_4_1() {
    let (model, test) = hand_made();
    let r = evaluate(&model, &test).unwrap();
    assert_eq!(
        r.table(),
        "\
Classified as     S1     S2     S3
S1                 1      1      0
S2                 0      1      0
S3                 1      0      0
SR(%)           50.0  100.0    0.0
ER(%)           50.0    0.0  100.0
accuracy: 2/4 (50.0 %)
"
    );
}

#[test]
fn a_class_never_tested_has_no_rate() {
    let (model, mut test) = hand_made();
    test.retain(|t| t.label == "S1");
    let r = evaluate(&model, &test).unwrap();
    assert_eq!(r.labels, ["S1", "S2"]);
    assert_eq!(r.per_class[1].n, 0);
    assert!(r.per_class[1].success_rate.is_nan());
    let v = serde_json::to_value(&r).unwrap();
    assert!(v["per_class"][1]["success_rate"].is_null());
    assert!(
        r.table().contains("SR(%)          50.0     -\n"),
        "{}",
        r.table()
    );
}

#[test]
fn the_thesis_result_prints_like_the_thesis() {
    let labels = ["S1", "S2", "S3", "S4"];
    let train: Vec<TrainingExample> = (0..20)
        .flat_map(|i| {
            labels.iter().enumerate().map(move |(c, l)| {
                ex(
                    &format!("{l}/{i:02}"),
                    l,
                    &[c as f64 * 10.0 + i as f64 * 0.01],
                )
            })
        })
        .collect();
    let test: Vec<TrainingExample> = (0..10)
        .flat_map(|i| {
            labels
                .iter()
                .enumerate()
                .map(move |(c, l)| ex(&format!("{l}/t{i:02}"), l, &[c as f64 * 10.0 + 0.05]))
        })
        .collect();
    let classifier = Classifier {
        k: 10,
        metric: Metric::Euclidean,
        ..Classifier::default()
    };
    let model = Model::train("thesis", &analysis(1), &classifier, train).unwrap();
    let r = evaluate(&model, &test).unwrap();
    assert_eq!(r.accuracy, 1.0);
    assert_eq!(
        r.table(),
        "\
Classified as     S1     S2     S3     S4
S1                10      0      0      0
S2                 0     10      0      0
S3                 0      0     10      0
S4                 0      0      0     10
SR(%)          100.0  100.0  100.0  100.0
ER(%)            0.0    0.0    0.0    0.0
accuracy: 40/40 (100.0 %)
"
    );
}
