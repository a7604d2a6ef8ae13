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

/// Every recording's sub-windows resampled (per recording, per
/// sub-window, per channel): one grid serves every feature setting that
/// resamples onto it ([`crate::profile::options::same_grid`]).
pub type Resampled = Vec<Vec<Vec<Vec<f64>>>>;

/// Every scan (kept samples) resampled onto `analysis`'s grids, on
/// `threads` threads.
pub fn resample(
    scans: &[Entry],
    analysis: &Analysis,
    threads: usize,
) -> Result<Resampled, DatasetError> {
    let fx = FeatureExtractor::try_new(analysis).map_err(DatasetError::Settings)?;
    by_chunks(scans, threads, |part| {
        let mut fx = fx.clone();
        part.iter()
            .map(|s| {
                let signals: Vec<&[f64]> = s.signals.iter().map(Vec::as_slice).collect();
                fx.resample_windows(&s.axis, &signals)
                    .map_err(|source| DatasetError::Analysis {
                        file: s.file.clone(),
                        source,
                    })
            })
            .collect()
    })
}

/// The feature vectors of every scan under `analysis` from the scans
/// resampled onto its grid, on `threads` threads: what
/// [`Entry::window_features_with`] gives, without resampling again.
pub fn extract_resampled(
    scans: &[Entry],
    resampled: &Resampled,
    analysis: &Analysis,
    threads: usize,
) -> Result<Features, DatasetError> {
    let fx = FeatureExtractor::try_new(analysis).map_err(DatasetError::Settings)?;
    let pairs: Vec<(&Entry, &Vec<Vec<Vec<f64>>>)> = scans.iter().zip(resampled).collect();
    by_chunks(&pairs, threads, |part| {
        let mut fx = fx.clone();
        part.iter()
            .map(|(s, windows)| {
                windows
                    .iter()
                    .map(|channels| fx.features_of_resampled(channels).map(<[f64]>::to_vec))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|source| DatasetError::Analysis {
                        file: s.file.clone(),
                        source,
                    })
            })
            .collect()
    })
}

/// The feature vectors of every scan (kept samples) under `analysis`, on
/// `threads` threads, each scan resampled and transformed in turn (no
/// grid kept).
pub fn extract(
    scans: &[Entry],
    analysis: &Analysis,
    threads: usize,
) -> Result<Features, DatasetError> {
    let fx = FeatureExtractor::try_new(analysis).map_err(DatasetError::Settings)?;
    by_chunks(scans, threads, |part| {
        let mut fx = fx.clone();
        part.iter()
            .map(|s| s.window_features_with(&mut fx))
            .collect()
    })
}

/// The most points a kept grid ([`Resampled`]) holds (64 MiB of values);
/// above that, each feature setting resamples again ([`extract`]).
pub const RESAMPLED_MOST: usize = 8 << 20;

/// How many points resampling every scan onto `analysis`'s grids gives
/// (sub-windows × points × channels per scan).
pub fn resampled_points(scans: &[Entry], analysis: &Analysis) -> usize {
    let channels = 1 + analysis.channels.len();
    scans.len() * analysis.sub_windows().len() * analysis.points() * channels
}

/// `f` over `items` in one chunk per thread, results in item order.
fn by_chunks<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&[T]) -> Result<Vec<R>, DatasetError> + Sync,
) -> Result<Vec<R>, DatasetError> {
    let chunk = items.len().div_ceil(threads.max(1)).max(1);
    let chunks: Vec<&[T]> = items.chunks(chunk).collect();
    let mut out = Vec::with_capacity(items.len());
    for p in par_map(&chunks, threads, |part| f(part)) {
        out.extend(p?);
    }
    Ok(out)
}

/// The rank values between every two windows of some recordings under
/// one metric, unscaled: made once per feature setting, they serve every
/// outer and inner fold that does not standardise (leave-one-out would
/// otherwise compute each pair again in every one of its searches). The
/// values are bit for bit those a fold computes ([`rank_value`] is
/// symmetric), so a fold counts the same with or without the table.
pub struct Pairwise {
    /// Each recording's first window in the table (`None`: not in it).
    first: Vec<Option<usize>>,
    n: usize,
    values: Vec<f64>,
}

/// The most entries a [`Pairwise`] table holds (64 MiB of values); above
/// that, folds compute their own distances.
const PAIRWISE_MOST: usize = 8 << 20;

impl Pairwise {
    /// The table over `recordings`' windows, or `None` when it would hold
    /// more than [`PAIRWISE_MOST`] entries.
    pub fn new(
        features: &Features,
        recordings: &[usize],
        metric: Metric,
        threads: usize,
    ) -> Option<Pairwise> {
        let mut first = vec![None; features.len()];
        let mut rows: Vec<&[f64]> = Vec::new();
        for &r in recordings {
            if first[r].is_none() {
                first[r] = Some(rows.len());
                rows.extend(features[r].iter().map(Vec::as_slice));
            }
        }
        let n = rows.len();
        if n.checked_mul(n)? > PAIRWISE_MOST {
            return None;
        }
        let norms: Vec<f64> = rows
            .iter()
            .map(|r| {
                if metric == Metric::Cosine {
                    dot(r, r).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let index: Vec<usize> = (0..n).collect();
        let lower = par_map(&index, threads, |&i| {
            (0..=i)
                .map(|j| rank_value(metric, rows[i], norms[i], rows[j], norms[j]))
                .collect::<Vec<f64>>()
        });
        let mut values = vec![0.0; n * n];
        for (i, row) in lower.into_iter().enumerate() {
            for (j, v) in row.into_iter().enumerate() {
                values[i * n + j] = v;
                values[j * n + i] = v;
            }
        }
        Some(Pairwise { first, n, values })
    }

    /// The table's index of recording `r`'s window `w`.
    fn at(&self, r: usize, w: usize) -> Option<usize> {
        self.first.get(r).copied().flatten().map(|f| f + w)
    }
}

/// Test windows whose distances are computed together, each training
/// window read once for them all.
const QUERY_BLOCK: usize = 32;

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
/// `pairwise`, the metric's table over (at least) the fold's recordings,
/// serves a fold that does not standardise.
#[allow(clippy::too_many_arguments)]
pub fn fold_correct(
    features: &Features,
    classes: &[usize],
    n_classes: usize,
    fold: &Fold,
    metric: Metric,
    standardize: bool,
    voters: &[(usize, Weights)],
    pairwise: Option<&Pairwise>,
) -> Vec<usize> {
    let mut rows: Vec<&[f64]> = Vec::new();
    let mut row_class: Vec<usize> = Vec::new();
    // Each training window's index in the table, when the table serves.
    let mut row_at: Vec<usize> = Vec::new();
    let mut table = pairwise.filter(|_| !standardize);
    for &r in fold.train {
        for (w, window) in features[r].iter().enumerate() {
            rows.push(window);
            row_class.push(classes[r]);
            if let Some(t) = table {
                match t.at(r, w) {
                    Some(i) => row_at.push(i),
                    None => table = None,
                }
            }
        }
    }
    if fold
        .test
        .iter()
        .any(|&t| table.is_some_and(|p| p.at(t, 0).is_none()))
    {
        table = None;
    }
    let d = rows.first().map_or(0, |r| r.len());
    let scaling = standardize.then(|| Scaling::fit(&rows));
    // The fold's own copy of its training windows, when no table serves.
    let copies = if table.is_some() { 0 } else { rows.len() };
    let mut matrix = vec![0.0; copies * d];
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
    // Each test window's k_most nearest training windows, nearest first
    // (ties in training order, as the model's search), in test order.
    let test_windows: Vec<(usize, usize)> = fold
        .test
        .iter()
        .flat_map(|&t| (0..features[t].len()).map(move |w| (t, w)))
        .collect();
    let by = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let keep_nearest = |mut ranked: Vec<(f64, usize)>| {
        if k_most < ranked.len() {
            ranked.select_nth_unstable_by(k_most, by);
            ranked.truncate(k_most);
        }
        ranked.sort_unstable_by(by);
        ranked
    };
    let nearest: Vec<Vec<(f64, usize)>> = match table {
        Some(p) => test_windows
            .iter()
            .map(|&(t, w)| {
                let q_at = p.at(t, w).unwrap_or(0);
                let from = &p.values[q_at * p.n..(q_at + 1) * p.n];
                keep_nearest(
                    row_at
                        .iter()
                        .enumerate()
                        .map(|(i, &at)| (from[at], i))
                        .collect(),
                )
            })
            .collect(),
        None => {
            let mut out = Vec::with_capacity(test_windows.len());
            for block in test_windows.chunks(QUERY_BLOCK) {
                let queries: Vec<Vec<f64>> = block
                    .iter()
                    .map(|&(t, w)| {
                        let window = &features[t][w];
                        match &scaling {
                            Some(s) => {
                                let mut q = vec![0.0; d];
                                s.apply(window, &mut q);
                                q
                            }
                            None => window.clone(),
                        }
                    })
                    .collect();
                let q_norms: Vec<f64> = queries
                    .iter()
                    .map(|q| {
                        if metric == Metric::Cosine {
                            dot(q, q).sqrt()
                        } else {
                            0.0
                        }
                    })
                    .collect();
                // Each training window once per block of queries, rather
                // than once per query: the same values, a fraction of the
                // memory traffic when the windows are long spectra.
                let mut ranked: Vec<Vec<(f64, usize)>> =
                    vec![Vec::with_capacity(rows.len()); queries.len()];
                for (i, (row, &n)) in matrix.chunks_exact(d.max(1)).zip(&norms).enumerate() {
                    for ((q, &q_norm), r) in queries.iter().zip(&q_norms).zip(ranked.iter_mut()) {
                        r.push((rank_value(metric, q, q_norm, row, n), i));
                    }
                }
                out.extend(ranked.into_iter().map(keep_nearest));
            }
            out
        }
    };
    let mut correct = vec![0usize; voters.len()];
    // Per voter: sub-windows won and neighbour votes, per class.
    let mut won = vec![vec![0usize; n_classes]; voters.len()];
    let mut votes = vec![vec![0usize; n_classes]; voters.len()];
    let mut at = 0;
    for &t in fold.test {
        for v in won.iter_mut().chain(votes.iter_mut()) {
            v.iter_mut().for_each(|x| *x = 0);
        }
        for _ in 0..features[t].len() {
            let ranked = &nearest[at];
            at += 1;
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
        // 60 test windows: more than one block of queries.
        let classes: Vec<usize> = (0..60).map(|i| i % 3).collect();
        let features: Features = classes
            .iter()
            .map(|&c| {
                (0..3)
                    .map(|_| (0..5).map(|j| (c * j) as f64 * 0.3 + noise()).collect())
                    .collect()
            })
            .collect();
        let train: Vec<usize> = (0..40).collect();
        let test: Vec<usize> = (40..60).collect();
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
                let got = fold_correct(
                    &features,
                    &classes,
                    3,
                    &fold,
                    metric,
                    standardize,
                    &voters,
                    None,
                );
                // A table of every pair (or of more recordings than the
                // fold's) counts the same.
                let all: Vec<usize> = (0..60).rev().collect();
                let table = Pairwise::new(&features, &all, metric, 2).unwrap();
                let tabled = fold_correct(
                    &features,
                    &classes,
                    3,
                    &fold,
                    metric,
                    standardize,
                    &voters,
                    Some(&table),
                );
                assert_eq!(got, tabled, "{metric:?} std {standardize}");
                for (v, &(k, weights)) in voters.iter().enumerate() {
                    let c = Classifier {
                        k: k.min(examples.len()),
                        metric,
                        weights,
                        standardize,
                        k_candidates: None,
                        method: crate::profile::Method::Knn,
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
