//! The fast path of the search: feature vectors made once per feature
//! setting ([`extract`]), and one fold scored for every classifier setting
//! that shares a metric and a standardisation from one table of
//! neighbours ([`fold_correct`]): each test window's training windows
//! ranked once, nearest first, serve every k and both vote weights. The
//! vote is the classifier's own ([`crate::classify::rank_classes`]) and a
//! recording's sub-windows vote as in [`crate::classify::vote`], so a
//! fold's count is what training a model on its training part and
//! classifying its test part would give.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::analysis::FeatureExtractor;
use crate::classify::{Scaling, dot, rank_classes, rank_value};
use crate::dataset::{DatasetError, Entry};
use crate::profile::{Analysis, Metric, Weights};

/// Every recording's feature vectors under one analysis: per recording,
/// one per sub-window (one without sub-windows).
pub type Features = Vec<Vec<Vec<f64>>>;

/// `f` over `items` on up to `threads` threads, results in item order.
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads.clamp(1, items.len().max(1)) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    if let Ok(mut o) = out.lock() {
                        o[i] = Some(r);
                    }
                }
            });
        }
    });
    out.into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

/// The feature vectors of every scan (kept samples) under `analysis`, on
/// `threads` threads, each with its own extractor.
pub fn extract(
    scans: &[Entry],
    analysis: &Analysis,
    threads: usize,
) -> Result<Features, DatasetError> {
    let fx = FeatureExtractor::try_new(analysis).map_err(DatasetError::Settings)?;
    let chunk = scans.len().div_ceil(threads.max(1)).max(1);
    let chunks: Vec<&[Entry]> = scans.chunks(chunk).collect();
    let parts = par_map(&chunks, threads, |part| {
        let mut fx = fx.clone();
        part.iter()
            .map(|s| s.window_features_with(&mut fx))
            .collect::<Result<Vec<_>, _>>()
    });
    let mut out = Vec::with_capacity(scans.len());
    for p in parts {
        out.extend(p?);
    }
    Ok(out)
}

/// One fold to score: recordings (indices into the features) that train
/// and that test.
pub struct Fold<'a> {
    pub train: &'a [usize],
    pub test: &'a [usize],
}

/// For each `(k, weights)`, how many of the fold's test recordings the
/// k-NN with `metric` (on features standardised by the training windows'
/// mean and deviation when `standardize`) trained on the fold's training
/// recordings classifies right, each recording by its sub-windows' vote.
pub fn fold_correct(
    features: &Features,
    classes: &[usize],
    n_classes: usize,
    fold: &Fold,
    metric: Metric,
    standardize: bool,
    voters: &[(usize, Weights)],
) -> Vec<usize> {
    let mut rows: Vec<&[f64]> = Vec::new();
    let mut row_class: Vec<usize> = Vec::new();
    for &r in fold.train {
        for w in &features[r] {
            rows.push(w);
            row_class.push(classes[r]);
        }
    }
    let d = rows.first().map_or(0, |r| r.len());
    let scaling = standardize.then(|| Scaling::fit(&rows));
    let mut matrix = vec![0.0; rows.len() * d];
    for (out, row) in matrix.chunks_exact_mut(d.max(1)).zip(&rows) {
        match &scaling {
            Some(s) => s.apply(row, out),
            None => out.copy_from_slice(row),
        }
    }
    let norms: Vec<f64> = if metric == Metric::Cosine {
        matrix
            .chunks_exact(d.max(1))
            .map(|r| dot(r, r).sqrt())
            .collect()
    } else {
        vec![0.0; rows.len()]
    };
    let k_most = voters
        .iter()
        .map(|v| v.0)
        .max()
        .unwrap_or(1)
        .clamp(1, rows.len().max(1));
    let mut correct = vec![0usize; voters.len()];
    let mut q = vec![0.0; d];
    let mut ranked: Vec<(f64, usize)> = Vec::with_capacity(rows.len());
    // Per voter: sub-windows won and neighbour votes, per class.
    let mut won = vec![vec![0usize; n_classes]; voters.len()];
    let mut votes = vec![vec![0usize; n_classes]; voters.len()];
    for &t in fold.test {
        for v in won.iter_mut().chain(votes.iter_mut()) {
            v.iter_mut().for_each(|x| *x = 0);
        }
        for window in &features[t] {
            match &scaling {
                Some(s) => s.apply(window, &mut q),
                None => q.copy_from_slice(window),
            }
            let q_norm = if metric == Metric::Cosine {
                dot(&q, &q).sqrt()
            } else {
                0.0
            };
            ranked.clear();
            ranked.extend(
                matrix
                    .chunks_exact(d.max(1))
                    .zip(&norms)
                    .enumerate()
                    .map(|(i, (row, &n))| (rank_value(metric, &q, q_norm, row, n), i)),
            );
            // The k nearest, ties in training order, as the model's search.
            let by = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if k_most < ranked.len() {
                ranked.select_nth_unstable_by(k_most, by);
                ranked.truncate(k_most);
            }
            ranked.sort_unstable_by(by);
            for (v, &(k, weights)) in voters.iter().enumerate() {
                let k = k.clamp(1, ranked.len().max(1));
                let (order, count) =
                    rank_classes(metric, weights, &ranked[..k], &row_class, n_classes);
                won[v][order[0]] += 1;
                for (c, n) in count.iter().enumerate() {
                    votes[v][c] += n;
                }
            }
        }
        for v in 0..voters.len() {
            // Most sub-windows, then most neighbour votes, then the first label.
            let best = (0..n_classes)
                .max_by(|&a, &b| {
                    won[v][a]
                        .cmp(&won[v][b])
                        .then(votes[v][a].cmp(&votes[v][b]))
                        .then(b.cmp(&a))
                })
                .unwrap_or(0);
            if best == classes[t] {
                correct[v] += 1;
            }
        }
    }
    correct
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classify::{Model, TrainingExample};
    use crate::profile::{Classifier, Metric, Weights};

    /// The fast fold gives, for every k, metric, weights and scaling, the
    /// count a trained model gives on the same split, with sub-windows.
    #[test]
    fn a_fold_counts_what_a_trained_model_counts() {
        let mut seed = 7u64;
        let mut noise = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let labels = ["a", "b", "c"];
        let classes: Vec<usize> = (0..18).map(|i| i % 3).collect();
        let features: Features = classes
            .iter()
            .map(|&c| {
                (0..3)
                    .map(|_| (0..5).map(|j| (c * j) as f64 * 0.3 + noise()).collect())
                    .collect()
            })
            .collect();
        let train: Vec<usize> = (0..12).collect();
        let test: Vec<usize> = (12..18).collect();
        let voters: Vec<(usize, Weights)> = [1, 3, 5, 40]
            .into_iter()
            .flat_map(|k| [(k, Weights::Uniform), (k, Weights::Distance)])
            .collect();
        let examples: Vec<TrainingExample> = train
            .iter()
            .flat_map(|&r| {
                let label = labels[classes[r]];
                features[r].iter().map(move |w| TrainingExample {
                    file: format!("r{r}"),
                    label: label.to_string(),
                    features: w.clone(),
                })
            })
            .collect();
        let analysis = Analysis {
            bins: [1, 5],
            window: [0.0, 0.0033],
            ..Analysis::default()
        };
        for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Cosine] {
            for standardize in [false, true] {
                let fold = Fold {
                    train: &train,
                    test: &test,
                };
                let got = fold_correct(&features, &classes, 3, &fold, metric, standardize, &voters);
                for (v, &(k, weights)) in voters.iter().enumerate() {
                    let c = Classifier {
                        k: k.min(examples.len()),
                        metric,
                        weights,
                        standardize,
                        k_candidates: None,
                    };
                    let mut a = analysis.clone();
                    a.bins = [1, 5];
                    let model = Model::train("t", &a, &c, examples.clone());
                    let Ok(model) = model else {
                        // The analysis's feature count must match; skip a
                        // settings mismatch rather than hide it.
                        panic!("{model:?}");
                    };
                    let want = test
                        .iter()
                        .filter(|&&t| {
                            model.classify_windows(&features[t]).unwrap().label
                                == labels[classes[t]]
                        })
                        .count();
                    assert_eq!(
                        got[v], want,
                        "{metric:?} std {standardize} k {k} {weights:?}"
                    );
                }
            }
        }
    }
}
