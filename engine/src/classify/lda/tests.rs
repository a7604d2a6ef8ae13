use super::*;

// The reference numbers below are scikit-learn 1.9.1's (numpy 2.4.6), made
// by this script on the same formulas:
//
//     import numpy as np
//     from sklearn.covariance import ledoit_wolf
//     from sklearn.discriminant_analysis import LinearDiscriminantAnalysis as LDA
//     from sklearn.preprocessing import StandardScaler
//     def lw_matrix(n, p, k):
//         return np.array([[np.sin((i*5 + j*3 + k) * 0.41) + 0.2*j*(i % 2)
//                           for j in range(p)] for i in range(n)])
//     def lda_data(n, p, classes, constant):
//         x = np.zeros((n, p))
//         for i in range(n):
//             c = classes[i]; a, b = np.sin(i * 1.3), np.cos(i * 0.7)
//             for j in range(p):
//                 x[i, j] = (a * np.cos(j * 0.5) + b * np.sin(j * 0.3 + c)
//                            + 0.3 * np.sin((i * 7 + j * 3) * 0.37) + 0.8 * (j % 3 == c))
//                 if constant and c == 2 and j == 3: x[i, j] = 0.5
//         return x
//     def queries(t, p):
//         return np.array([[np.cos((s*5 + j*11) * 0.23) for j in range(p)] for s in range(t)])
//     for (n, p, k) in [(6, 4, 0), (5, 8, 1)]:
//         X = lw_matrix(n, p, k); Xc = X - X.mean(0)
//         print(ledoit_wolf(X)[1], np.trace(Xc.T @ Xc / n) / p)
//     for classes, p, constant in [([0, 1, 2] * 4 + [0, 0, 1], 4, True),
//                                  ([0, 1, 2, 0, 1, 2, 0, 1, 2, 0], 14, False)]:
//         classes = np.array(classes); X = lda_data(len(classes), p, classes, constant)
//         Q = queries(4, p)
//         clf = LDA(solver="lsqr", shrinkage="auto").fit(X, classes)
//         d = clf.decision_function(Q)
//         print([ledoit_wolf(StandardScaler().fit_transform(X[classes == c]))[1]
//                for c in range(3)])
//         print(clf.predict(Q), d - d[:, :1])
//
// (`solver="eigen"` gives the same differences to 3e-14.) The differences
// from class 0's score are compared, as this module's scores are the
// textbook ones less an amount that is the same for every class.

fn lw_matrix(n: usize, p: usize, k: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            (0..p)
                .map(|j| {
                    ((i * 5 + j * 3 + k) as f64 * 0.41).sin() + 0.2 * j as f64 * (i % 2) as f64
                })
                .collect()
        })
        .collect()
}

fn lda_data(classes: &[usize], p: usize, constant: bool) -> Vec<Vec<f64>> {
    classes
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let (a, b) = ((i as f64 * 1.3).sin(), (i as f64 * 0.7).cos());
            (0..p)
                .map(|j| {
                    if constant && c == 2 && j == 3 {
                        return 0.5;
                    }
                    a * (j as f64 * 0.5).cos()
                        + b * (j as f64 * 0.3 + c as f64).sin()
                        + 0.3 * ((i * 7 + j * 3) as f64 * 0.37).sin()
                        + if j % 3 == c { 0.8 } else { 0.0 }
                })
                .collect()
        })
        .collect()
}

fn queries(t: usize, p: usize) -> Vec<Vec<f64>> {
    (0..t)
        .map(|s| {
            (0..p)
                .map(|j| ((s * 5 + j * 11) as f64 * 0.23).cos())
                .collect()
        })
        .collect()
}

fn centred(rows: &[Vec<f64>]) -> Mat<f64> {
    let (n, p) = (rows.len(), rows[0].len());
    let mean: Vec<f64> = (0..p)
        .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / n as f64)
        .collect();
    Mat::from_fn(n, p, |i, j| rows[i][j] - mean[j])
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[test]
fn ledoit_wolf_intensity_matches_scikit_learn() {
    // (n, p, k, shrinkage, m): more examples than features (the p × p
    // form) and fewer (the Gram form).
    let cases = [
        (6, 4, 0, 0.3822538242290569, 0.535374186169632),
        (5, 8, 1, 0.5310413116691317, 0.6492157883043563),
    ];
    for (n, p, k, want_s, want_m) in cases {
        let (s, m) = ledoit_wolf(&centred(&lw_matrix(n, p, k)));
        assert!(
            close(s, want_s, 1e-12),
            "{n}x{p}: shrinkage {s} vs {want_s}"
        );
        assert!(close(m, want_m, 1e-12), "{n}x{p}: m {m} vs {want_m}");
    }
    // Two rows: b̄² = 0, no shrinkage; identical rows: nothing to estimate.
    let two = centred(&lw_matrix(2, 5, 0));
    assert_eq!(ledoit_wolf(&two).0, 0.0);
    let same = centred(&[vec![1.0, 2.0, 3.0], vec![1.0, 2.0, 3.0]]);
    assert_eq!(ledoit_wolf(&same), (0.0, 0.0));
}

/// The LDA's scores against scikit-learn's, as differences from class 0.
fn matches_scikit_learn(
    classes: &[usize],
    p: usize,
    constant: bool,
    shrinkage: [f64; 3],
    predicted: [usize; 4],
    differences: [[f64; 2]; 4],
) {
    let rows = lda_data(classes, p, constant);
    let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
    let fit = LdaFit::fit(&refs, classes, 3).unwrap();
    for (c, (&got, want)) in fit.shrinkage.iter().zip(shrinkage).enumerate() {
        assert!(close(got, want, 1e-10), "class {c}: {got} vs {want}");
    }
    let mut buf = vec![0.0; p];
    for (t, q) in queries(4, p).iter().enumerate() {
        let s = fit.scores(q, &mut buf);
        for c in 1..3 {
            let (got, want) = (s[c] - s[0], differences[t][c - 1]);
            assert!(
                close(got, want, 1e-9),
                "query {t} class {c}: {got} vs {want}"
            );
        }
        let best = (0..3).max_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap();
        assert_eq!(best, predicted[t], "query {t}");
    }
    assert!(fit.check(p, 3).is_ok());
}

#[test]
fn decision_scores_match_scikit_learn_with_fewer_features_than_examples() {
    // 15 examples (6, 5 and 4 of a class: unequal priors), 4 features, one
    // of them constant in class 2.
    let mut classes = [0, 1, 2].repeat(4);
    classes.extend([0, 0, 1]);
    matches_scikit_learn(
        &classes,
        4,
        true,
        [0.4473257685047536, 0.06996288687176577, 0.12722960275398523],
        [0, 2, 1, 1],
        [
            [-10.23047730158831, -1.6120761512349997],
            [-2.85074295470546, 7.037716594113536],
            [8.927423461297645, 8.314804018688443],
            [11.170155229576459, 0.7083596210397927],
        ],
    );
}

#[test]
fn decision_scores_match_scikit_learn_with_more_features_than_examples() {
    // 10 examples, 14 features: solved by Woodbury's identity.
    matches_scikit_learn(
        &[0, 1, 2, 0, 1, 2, 0, 1, 2, 0],
        14,
        false,
        [0.32177057453945757, 0.3170944092902176, 0.38348298349851806],
        [2, 1, 0, 0],
        [
            [2.737293844073408, 4.2224554815480735],
            [0.5900988431793728, 0.13163376012832195],
            [-4.095713508966441, -2.67324483310595],
            [-5.776709500455276, -0.8739384687682854],
        ],
    );
}

fn data(n: usize, p: usize, classes: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<usize>) {
    crate::classify::linear::separable(n, p, classes, seed, |j| 3.0 * j as f64)
}

fn assert_same_fit(a: &LdaFit, b: &LdaFit, what: &str) {
    assert_eq!(a.shrinkage, b.shrinkage, "{what}");
    let largest = a
        .weights
        .iter()
        .flatten()
        .fold(0.0f64, |m, w| m.max(w.abs()));
    for (wa, wb) in a.weights.iter().zip(&b.weights) {
        for (x, y) in wa.iter().zip(wb) {
            assert!((x - y).abs() <= 1e-8 * largest, "{what}: {x} vs {y}");
        }
    }
    for (x, y) in a.intercepts.iter().zip(&b.intercepts) {
        assert!(close(*x, *y, 1e-8), "{what}: intercept {x} vs {y}");
    }
}

#[test]
fn woodbury_agrees_with_the_direct_solve() {
    // More features than examples (what Woodbury is for), fewer, and two
    // examples a class (no class shrunk: the pseudo-inverse of a singular
    // covariance).
    for (n, p, classes) in [(12, 30, 3), (40, 6, 4), (6, 20, 3)] {
        let (rows, labels) = data(n, p, classes, n as u64);
        let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
        let direct = LdaFit::fit_by(&refs, &labels, classes, false).unwrap();
        let woodbury = LdaFit::fit_by(&refs, &labels, classes, true).unwrap();
        let what = format!("n {n} p {p}");
        assert_eq!(
            direct.shrinkage.iter().all(|&s| s == 0.0),
            n == 2 * classes,
            "{what}: {:?}",
            direct.shrinkage
        );
        assert_same_fit(&direct, &woodbury, &what);
        // `fit` takes Woodbury's way exactly when p > n.
        let chosen = LdaFit::fit(&refs, &labels, classes).unwrap();
        assert!(chosen == if p > n { woodbury } else { direct }, "{what}");
    }
}

#[test]
fn separable_classes_are_told_apart_and_follow_their_labels() {
    let (rows, labels) = data(60, 20, 3, 5);
    let refs: Vec<&[f64]> = rows[..45].iter().map(Vec::as_slice).collect();
    let right = |fit: &LdaFit| {
        let mut buf = vec![0.0; 20];
        rows[45..]
            .iter()
            .zip(&labels[45..])
            .filter(|(r, c)| {
                let s = fit.scores(r, &mut buf);
                (0..3).max_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap() == **c
            })
            .count()
    };
    let fit = LdaFit::fit(&refs, &labels[..45], 3).unwrap();
    assert_eq!(right(&fit), 15);
    assert!((fit.priors.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert!(fit.check(20, 3).is_ok());
    assert!(fit.check(21, 3).is_err());
    assert!(fit.check(20, 2).is_err());
    let mut bad = fit.clone();
    bad.shrinkage[1] = 1.5;
    assert!(bad.check(20, 3).is_err());
    // Labels permuted in training: every held-out row goes to the
    // permuted class.
    let shuffled: Vec<usize> = labels.iter().map(|c| (c * 7 + 1) % 3).collect();
    let fit = LdaFit::fit(&refs, &shuffled[..45], 3).unwrap();
    assert_eq!(right(&fit), 0);
    // A class with no example is refused, not fitted; so are classes of
    // one example each, or of examples all alike (no covariance).
    assert!(LdaFit::fit(&refs, &labels[..45], 4).is_err());
    let err = LdaFit::fit(&refs[..3], &labels[..3], 3).unwrap_err();
    assert!(err.contains("no covariance"), "{err}");
    let alike: Vec<&[f64]> = labels[..9].iter().map(|&c| refs[c]).collect();
    assert!(LdaFit::fit(&alike, &labels[..9], 3).is_err());
    let mut one_differs = alike.clone();
    one_differs[3] = refs[3];
    assert!(LdaFit::fit(&one_differs, &labels[..9], 3).is_ok());
}
