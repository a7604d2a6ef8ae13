//! The classifier's options: metrics, distance-weighted votes,
//! standardisation fitted on the training part, `k = "auto"`.

use hapticlab::classify::{Model, TrainingExample};
use hapticlab::profile::{Classifier, K_AUTO, Metric, Weights};

use crate::common::{analysis, ex};

fn knn(k: usize, metric: Metric) -> Classifier {
    Classifier {
        k,
        metric,
        ..Classifier::default()
    }
}

#[test]
fn manhattan_and_cosine_distances() {
    let train = vec![ex("a", "A", &[3.0, 0.0]), ex("b", "B", &[2.0, 2.0])];
    let q = [0.0, 0.0];
    // Euclidean: a at 3, b at 2.83 → B. Manhattan: a at 3, b at 4 → A.
    let e = Model::train("t", &analysis(2), &knn(1, Metric::Euclidean), train.clone()).unwrap();
    assert_eq!(e.classify(&q).unwrap().label, "B");
    let m = Model::train("t", &analysis(2), &knn(1, Metric::Manhattan), train.clone()).unwrap();
    let p = m.classify(&q).unwrap();
    assert_eq!(p.label, "A");
    assert_eq!(p.neighbours[0].distance, 3.0);
    // Cosine looks at direction only: [10, 1] points along a.
    let c = Model::train("t", &analysis(2), &knn(1, Metric::Cosine), train).unwrap();
    let p = c.classify(&[10.0, 1.0]).unwrap();
    assert_eq!(p.label, "A");
    let want = 1.0 - 10.0 / 101f64.sqrt();
    assert!((p.neighbours[0].distance - want).abs() < 1e-12);
}

#[test]
fn distance_weighted_votes_let_one_close_neighbour_win() {
    let train = vec![
        ex("a", "A", &[0.1]),
        ex("b1", "B", &[1.0]),
        ex("b2", "B", &[1.1]),
    ];
    let mut c = knn(3, Metric::Euclidean);
    let uniform = Model::train("t", &analysis(1), &c, train.clone()).unwrap();
    assert_eq!(uniform.classify(&[0.0]).unwrap().label, "B");
    c.weights = Weights::Distance;
    let weighted = Model::train("t", &analysis(1), &c, train).unwrap();
    let p = weighted.classify(&[0.0]).unwrap();
    assert_eq!(p.label, "A");
    assert_eq!(p.votes[0], ("A".to_string(), 1));
}

#[test]
fn standardisation_is_fitted_on_the_training_part_and_saved() {
    // Feature 0 separates the classes but is tiny; feature 1 is large noise.
    let train = vec![
        ex("a1", "A", &[0.001, 100.0]),
        ex("a2", "A", &[0.0012, -100.0]),
        ex("b1", "B", &[0.003, -60.0]),
        ex("b2", "B", &[0.0032, 60.0]),
    ];
    let q = [0.001, -100.0];
    let raw = Model::train("t", &analysis(2), &knn(1, Metric::Euclidean), train.clone()).unwrap();
    assert_eq!(raw.classify(&q).unwrap().neighbours[0].file, "a2");
    let mut c = knn(1, Metric::Euclidean);
    c.standardize = true;
    let m = Model::train("t", &analysis(2), &c, train).unwrap();
    let s = m.scaling.as_ref().unwrap();
    assert!((s.mean[0] - 0.0021).abs() < 1e-12 && s.mean[1] == 0.0);
    assert!((s.scale[1] - 6800f64.sqrt()).abs() < 1e-9);
    // Standardised, the large noisy feature no longer drowns the small one.
    let q2 = [0.0031, 95.0];
    assert_eq!(raw.classify(&q2).unwrap().label, "A");
    assert_eq!(m.classify(&q2).unwrap().label, "B");
    // The scaling survives the model file.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    m.save(&path, &[], hapticlab::io::Existing::Keep).unwrap();
    let back = Model::load(&path).unwrap();
    assert_eq!(back, m);
    assert_eq!(back.classify(&q2).unwrap().label, "B");
}

#[test]
fn auto_k_picks_by_inner_cross_validation() {
    // Two classes on a line, each with an isolated mislabelled point among
    // the other: k = 1 copies its label, a larger k votes it down.
    let mut train = Vec::new();
    for i in 0..20 {
        train.push(ex(&format!("a{i}"), "A", &[i as f64 * 0.1]));
        train.push(ex(&format!("b{i}"), "B", &[10.0 + i as f64 * 0.1]));
    }
    for i in 0..4 {
        train.push(ex(&format!("x{i}"), "B", &[0.05 + i as f64 * 0.5]));
        train.push(ex(&format!("y{i}"), "A", &[10.05 + i as f64 * 0.5]));
    }
    let mut c = knn(K_AUTO, Metric::Euclidean);
    c.k_candidates = Some(vec![1, 5, 9]);
    let m = Model::train("t", &analysis(1), &c, train).unwrap();
    let sel = m.k_selection.as_ref().unwrap();
    assert_eq!(sel.iter().map(|s| s.k).collect::<Vec<_>>(), [1, 5, 9]);
    assert!(m.classifier.k > 1, "{sel:?}");
    assert!(sel[0].accuracy < sel[1].accuracy, "{sel:?}");
}

/// With sub-windows, a recording's windows stay in one inner fold: windows
/// of one recording that are copies of each other would otherwise give
/// k = 1 a perfect inner score (each window's nearest is its sibling).
#[test]
fn auto_k_keeps_a_recordings_sub_windows_in_one_inner_fold() {
    // 2 classes x 8 recordings x 4 identical windows; the recordings of the
    // two classes interleave on a line, so across recordings 1-NN is wrong
    // about as often as right.
    let mut train = Vec::new();
    for r in 0..8 {
        for (label, offset) in [("A", 0.0), ("B", 0.5)] {
            for _ in 0..4 {
                train.push(ex(&format!("{label}{r}"), label, &[r as f64 + offset]));
            }
        }
    }
    let mut c = knn(K_AUTO, Metric::Euclidean);
    c.k_candidates = Some(vec![1, 3]);
    let m = Model::train("t", &analysis(1), &c, train).unwrap();
    let sel = m.k_selection.as_ref().unwrap();
    assert!(
        sel[0].accuracy < 0.9,
        "a window scored against its siblings: {sel:?}"
    );
}

#[test]
fn k_auto_reads_and_writes_as_a_string() {
    let c: Classifier =
        toml::from_str("k = \"auto\"\nmetric = \"cosine\"\nweights = \"distance\"").unwrap();
    assert_eq!(c.k, K_AUTO);
    assert_eq!(c.k_text(), "auto");
    assert_eq!(c.metric, Metric::Cosine);
    assert!(toml::to_string(&c).unwrap().contains("k = \"auto\""));
    let err = toml::from_str::<Classifier>("k = \"many\"").unwrap_err();
    assert!(
        err.to_string()
            .contains("k must be a whole number ≥ 1 or \"auto\", got \"many\""),
        "{err}"
    );
}

#[test]
fn a_large_training_set_searched_in_parallel_gives_the_exact_neighbours() {
    // 20,000 x 64 values: above the parallel threshold. Many exact ties
    // (coarse values) check that equal distances keep the training order.
    let mut state = 7u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) % 4) as f64
    };
    let train: Vec<TrainingExample> = (0..20_000)
        .map(|i| {
            ex(
                &format!("{i}"),
                ["A", "B", "C"][i % 3],
                &(0..64).map(|_| next()).collect::<Vec<_>>(),
            )
        })
        .collect();
    let q: Vec<f64> = (0..64).map(|_| next()).collect();
    let m = Model::train(
        "t",
        &analysis(64),
        &knn(25, Metric::Manhattan),
        train.clone(),
    )
    .unwrap();
    let p = m.classify(&q).unwrap();
    let mut all: Vec<(f64, usize)> = train
        .iter()
        .enumerate()
        .map(|(i, e)| {
            (
                e.features.iter().zip(&q).map(|(a, b)| (a - b).abs()).sum(),
                i,
            )
        })
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let want: Vec<String> = all[..25].iter().map(|(_, i)| i.to_string()).collect();
    let got: Vec<String> = p.neighbours.iter().map(|n| n.file.clone()).collect();
    assert_eq!(got, want);
}
