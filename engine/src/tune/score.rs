//! The fast path of the search: feature vectors made once per feature
//! setting ([`extract`]), and one fold scored for every classifier setting
//! that shares a metric and a standardisation from one table of
//! neighbours ([`score_fold`]): each test window's training windows
//! ranked once, nearest first, serve every k and both vote weights. The
//! vote is the classifier's own ([`crate::classify::rank_classes`]) and a
//! recording's sub-windows vote as in [`crate::classify::vote`], so a
//! fold's count is what training a model on its training part and
//! classifying its test part would give.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::analysis::FeatureExtractor;
use crate::classify::{Scaling, dot, rank_classes, rank_table, to_distance};
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

/// The most points a kept grid ([`Resampled`]) holds: as many as a
/// dataset's feature values ([`crate::dataset::MAX_VALUES`], 256 MB);
/// above that, each feature setting resamples again ([`extract`]).
pub const RESAMPLED_MOST: usize = crate::dataset::MAX_VALUES;

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

/// Rows of the table computed together.
const PAIRWISE_BAND: usize = 32;

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
        // Bands of rows, each against every row up to its last (the
        // largest bands first, for the threads to finish together).
        let bands: Vec<usize> = (0..n.div_ceil(PAIRWISE_BAND)).rev().collect();
        let lower = par_map(&bands, threads, |&b| {
            let (from, to) = (b * PAIRWISE_BAND, ((b + 1) * PAIRWISE_BAND).min(n));
            let mut out = vec![0.0; (to - from) * to];
            rank_table(
                metric,
                &rows[from..to],
                &norms[from..to],
                &rows[..to],
                &norms[..to],
                &mut out,
            );
            (from, to, out)
        });
        let mut values = vec![0.0; n * n];
        for (from, to, band) in lower {
            for (i, row) in (from..to).zip(band.chunks_exact(to)) {
                for (j, &v) in row[..=i].iter().enumerate() {
                    values[i * n + j] = v;
                    values[j * n + i] = v;
                }
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

/// What a fold says of one classifier setting: how many of its test
/// recordings it classifies right, and two finer scores summed over them,
/// which break ties between settings whose counts are equal (saturated
/// inner folds) by how clearly they were right rather than by sampling
/// luck: the margin of each test window (how much nearer its nearest
/// training window of its own label is than the nearest of another,
/// relative to both: -1 to 1; the mean over its sub-windows), and the
/// share of its neighbour votes (over all its sub-windows) that went to
/// its own label.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FoldScore {
    pub correct: usize,
    pub margin: f64,
    pub true_share: f64,
}

/// A test window's margin: `(other - own) / (other + own)` of the distances
/// to its nearest training window of its own label and of another (1 with
/// none of another, -1 with none of its own, 0 when both are at distance 0).
fn margin(metric: Metric, ranked: &[(f64, usize)], class: &[usize], truth: usize) -> f64 {
    let (mut own, mut other) = (f64::INFINITY, f64::INFINITY);
    for &(r, i) in ranked {
        let d = to_distance(metric, r);
        if class[i] == truth {
            own = own.min(d);
        } else {
            other = other.min(d);
        }
    }
    match (own.is_finite(), other.is_finite()) {
        (true, true) if own + other > 0.0 => (other - own) / (other + own),
        (true, true) => 0.0,
        (true, false) => 1.0,
        (false, _) => -1.0,
    }
}

/// The labels a fold is scored against and how its k-NN measures.
pub struct Voting<'a> {
    /// Each recording's class (an index below `n_classes`).
    pub classes: &'a [usize],
    pub n_classes: usize,
    pub metric: Metric,
    /// Features standardised by the training windows' mean and deviation.
    pub standardize: bool,
}

/// A fold's training windows, as the k-NN searches them.
struct TrainingRows<'a> {
    rows: Vec<&'a [f64]>,
    class: Vec<usize>,
    /// Each row's index in the table, when the table serves every
    /// training and test window (`None` otherwise).
    table: Option<(&'a Pairwise, Vec<usize>)>,
}

impl<'a> TrainingRows<'a> {
    fn gather(
        features: &'a Features,
        voting: &Voting,
        fold: &Fold,
        pairwise: Option<&'a Pairwise>,
    ) -> TrainingRows<'a> {
        let mut rows: Vec<&[f64]> = Vec::new();
        let mut class: Vec<usize> = Vec::new();
        let mut row_at: Vec<usize> = Vec::new();
        let mut table = pairwise.filter(|_| !voting.standardize);
        for &r in fold.train {
            for (w, window) in features[r].iter().enumerate() {
                rows.push(window);
                class.push(voting.classes[r]);
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
        TrainingRows {
            rows,
            class,
            table: table.map(|t| (t, row_at)),
        }
    }
}

/// Each test window's `k_most` nearest training windows, nearest first
/// (ties in training order, as the model's search), and its [`margin`], in
/// test order.
fn nearest_windows(
    features: &Features,
    voting: &Voting,
    fold: &Fold,
    train: &TrainingRows,
    k_most: usize,
) -> Vec<(Vec<(f64, usize)>, f64)> {
    let test_windows: Vec<(usize, usize)> = fold
        .test
        .iter()
        .flat_map(|&t| (0..features[t].len()).map(move |w| (t, w)))
        .collect();
    let by = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let metric = voting.metric;
    let keep_nearest = |mut ranked: Vec<(f64, usize)>, t: usize| {
        let m = margin(metric, &ranked, &train.class, voting.classes[t]);
        if k_most < ranked.len() {
            ranked.select_nth_unstable_by(k_most, by);
            ranked.truncate(k_most);
        }
        ranked.sort_unstable_by(by);
        (ranked, m)
    };
    if let Some((p, row_at)) = &train.table {
        return test_windows
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
                    t,
                )
            })
            .collect();
    }
    let d = train.rows.first().map_or(0, |r| r.len());
    let scaling = voting.standardize.then(|| Scaling::fit(&train.rows));
    // The fold's own copy of its training windows.
    let mut matrix = vec![0.0; train.rows.len() * d];
    for (out, row) in matrix.chunks_exact_mut(d.max(1)).zip(&train.rows) {
        match &scaling {
            Some(s) => s.apply(row, out),
            None => out.copy_from_slice(row),
        }
    }
    let norm = |v: &[f64]| {
        if metric == Metric::Cosine {
            dot(v, v).sqrt()
        } else {
            0.0
        }
    };
    let norms: Vec<f64> = matrix.chunks_exact(d.max(1)).map(norm).collect();
    let rows: Vec<&[f64]> = matrix.chunks_exact(d.max(1)).collect();
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
        let q_norms: Vec<f64> = queries.iter().map(|q| norm(q)).collect();
        // The block against every training window, tile by tile: the
        // same values, a fraction of the memory traffic when the windows
        // are long.
        let q_rows: Vec<&[f64]> = queries.iter().map(Vec::as_slice).collect();
        let mut values = vec![0.0; q_rows.len() * rows.len()];
        rank_table(metric, &q_rows, &q_norms, &rows, &norms, &mut values);
        out.extend(
            values
                .chunks_exact(rows.len().max(1))
                .zip(block)
                .map(|(v, &(t, _))| keep_nearest(v.iter().copied().zip(0..).collect(), t)),
        );
    }
    out
}

/// For each `(k, weights)`, what the k-NN with the voting's metric (on
/// standardised features when it says so) trained on the fold's training
/// recordings scores on its test recordings ([`FoldScore`]), each
/// recording by its sub-windows' vote. `pairwise`, the metric's table over
/// (at least) the fold's recordings, serves a fold that does not
/// standardise.
pub fn score_fold(
    features: &Features,
    voting: &Voting,
    fold: &Fold,
    voters: &[(usize, Weights)],
    pairwise: Option<&Pairwise>,
) -> Vec<FoldScore> {
    let train = TrainingRows::gather(features, voting, fold, pairwise);
    let k_most = voters
        .iter()
        .map(|v| v.0)
        .max()
        .unwrap_or(1)
        .clamp(1, train.rows.len().max(1));
    let nearest = nearest_windows(features, voting, fold, &train, k_most);
    let n_classes = voting.n_classes;
    let mut out = vec![FoldScore::default(); voters.len()];
    // Per voter: sub-windows won and neighbour votes, per class.
    let mut won = vec![vec![0usize; n_classes]; voters.len()];
    let mut votes = vec![vec![0usize; n_classes]; voters.len()];
    let mut at = 0;
    for &t in fold.test {
        for v in won.iter_mut().chain(votes.iter_mut()) {
            v.iter_mut().for_each(|x| *x = 0);
        }
        let windows = features[t].len();
        let mut margins = 0.0;
        for _ in 0..windows {
            let (ranked, m) = &nearest[at];
            margins += m;
            at += 1;
            for (v, &(k, weights)) in voters.iter().enumerate() {
                let k = k.clamp(1, ranked.len().max(1));
                let (order, count) = rank_classes(
                    voting.metric,
                    weights,
                    &ranked[..k],
                    &train.class,
                    n_classes,
                );
                won[v][order[0]] += 1;
                for (c, n) in count.iter().enumerate() {
                    votes[v][c] += n;
                }
            }
        }
        let truth = voting.classes[t];
        for (v, score) in out.iter_mut().enumerate() {
            // Most sub-windows, then most neighbour votes, then the first label.
            let best = (0..n_classes)
                .max_by(|&a, &b| {
                    won[v][a]
                        .cmp(&won[v][b])
                        .then(votes[v][a].cmp(&votes[v][b]))
                        .then(b.cmp(&a))
                })
                .unwrap_or(0);
            if best == truth {
                score.correct += 1;
            }
            score.margin += margins / windows.max(1) as f64;
            let cast: usize = votes[v].iter().sum();
            if cast > 0 {
                score.true_share += votes[v][truth] as f64 / cast as f64;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classify::rank_value;

    /// [`FoldScore`]'s margin and true share summed over `test`, each
    /// window against every training window, unscaled, by brute force.
    fn naive_finer(
        features: &Features,
        classes: &[usize],
        train: &[usize],
        test: &[usize],
        metric: Metric,
        k: usize,
    ) -> (f64, f64) {
        let norm = |v: &[f64]| {
            if metric == Metric::Cosine {
                dot(v, v).sqrt()
            } else {
                0.0
            }
        };
        let (mut margin_sum, mut share_sum) = (0.0, 0.0);
        for &t in test {
            let (mut m, mut own_votes, mut cast) = (0.0, 0, 0);
            for q in &features[t] {
                let mut d: Vec<(f64, usize, usize)> = Vec::new();
                for &r in train {
                    for row in &features[r] {
                        let rv = rank_value(metric, q, norm(q), row, norm(row));
                        d.push((rv, d.len(), classes[r]));
                    }
                }
                let dist = |c: bool| {
                    d.iter()
                        .filter(|x| (x.2 == classes[t]) == c)
                        .map(|x| to_distance(metric, x.0))
                        .fold(f64::INFINITY, f64::min)
                };
                let (own, other) = (dist(true), dist(false));
                m += if own + other > 0.0 {
                    (other - own) / (other + own)
                } else {
                    0.0
                };
                d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let k = k.min(d.len());
                own_votes += d[..k].iter().filter(|x| x.2 == classes[t]).count();
                cast += k;
            }
            margin_sum += m / features[t].len() as f64;
            share_sum += own_votes as f64 / cast as f64;
        }
        (margin_sum, share_sum)
    }

    #[test]
    fn a_margin_says_how_much_nearer_its_own_label_is() {
        let class = [0, 1, 0];
        let m = |r: &[(f64, usize)]| margin(Metric::Manhattan, r, &class, 0);
        assert_eq!(m(&[(1.0, 0), (3.0, 1)]), 0.5);
        assert_eq!(m(&[(3.0, 0), (1.0, 1), (2.0, 2)]), -1.0 / 3.0);
        assert_eq!(m(&[(0.0, 0), (0.0, 1)]), 0.0);
        assert_eq!(m(&[(2.0, 0), (5.0, 2)]), 1.0, "no other label");
        assert_eq!(m(&[(2.0, 1)]), -1.0, "none of its own");
    }
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
                let voting = Voting {
                    classes: &classes,
                    n_classes: 3,
                    metric,
                    standardize,
                };
                let got = score_fold(&features, &voting, &fold, &voters, None);
                // A table of every pair (or of more recordings than the
                // fold's) counts the same.
                let all: Vec<usize> = (0..60).rev().collect();
                let table = Pairwise::new(&features, &all, metric, 2).unwrap();
                let tabled = score_fold(&features, &voting, &fold, &voters, Some(&table));
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
                        got[v].correct, want,
                        "{metric:?} std {standardize} k {k} {weights:?}"
                    );
                    if !standardize {
                        let (margin, share) =
                            naive_finer(&features, &classes, &train, &test, metric, k);
                        assert!(
                            (got[v].margin - margin).abs() < 1e-9
                                && (got[v].true_share - share).abs() < 1e-9,
                            "{metric:?} k {k}: {:?} vs {margin} {share}",
                            got[v]
                        );
                    }
                }
            }
        }
    }
}
