//! Interval quantile features, as QUANT (Dempster, Schmidt and Webb, 2024)
//! describes them, written from the paper.
//!
//! A window of `n` points gives four series: the signal, its first and
//! second differences, and its magnitude spectrum (`|X_k|`, `k = 0..=n/2`,
//! the DFT unnormalised). Over each series, dyadic intervals (the whole,
//! halves, quarters, … down to depth 6, and at each level below the first
//! the same intervals shifted by half an interval;
//! [`crate::profile::families::quantile_intervals`]); over each interval of
//! `w` values, `q = 1 + ⌊(w − 1)/4⌋` quantiles at `0, 1/(q−1), …, 1`
//! (linear interpolation between order statistics; the median when `q` is
//! 1; the value when `w` is 1), and every second one (the 2nd, 4th, …) less
//! the interval's mean. Each channel's features in turn, concatenated.
//!
//! Nothing is fitted: a window's features depend on that window alone, so
//! they are made once per recording like the spectrum's. After
//! [`Quantiles::new`] it allocates nothing per window.

use crate::profile::families::{
    QUANTILE_DEPTH, level_ends, quantile_feature_count, quantile_intervals, quantile_levels,
    quantile_series, quantiles_in,
};

use super::spectrum::MagnitudeSpectrum;

/// The order statistics at `q · (n − 1)` (`q` from 0 to 1) either side,
/// and how far between them.
fn position(n: usize, q: f64) -> (usize, usize, f64) {
    let pos = q.clamp(0.0, 1.0) * (n - 1) as f64;
    let lo = (pos.floor() as usize).min(n - 1);
    (lo, (lo + 1).min(n - 1), pos - lo as f64)
}

/// The `q` quantile (0 to 1) of sorted values, by linear interpolation
/// between the order statistics at `q · (n − 1)` (numpy's default).
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    if n == 1 {
        return sorted[0];
    }
    let (lo, hi, frac) = position(n, q);
    if frac == 0.0 {
        sorted[lo]
    } else {
        sorted[lo] + frac * (sorted[hi] - sorted[lo])
    }
}

/// [`quantile_sorted`] of `values` in any order at each of `qs`, into
/// `out` in their order: the same numbers to the bit, selecting only the
/// order statistics they need, each within the part the last selection
/// left it in (about `n · log₂ m` comparisons for `m` of them, not a sort).
/// Leaves `values` reordered.
pub fn quantiles_unsorted(values: &mut [f64], qs: &[f64], out: &mut Vec<f64>) {
    let n = values.len();
    if n <= 1 {
        out.extend(
            qs.iter()
                .map(|_| values.first().copied().unwrap_or(f64::NAN)),
        );
        return;
    }
    let mut ranks: Vec<usize> = qs
        .iter()
        .flat_map(|&q| {
            let (lo, hi, frac) = position(n, q);
            [lo, if frac == 0.0 { lo } else { hi }]
        })
        .collect();
    ranks.sort_unstable();
    ranks.dedup();
    select_ranks(values, &ranks, 0);
    out.extend(qs.iter().map(|&q| {
        let (lo, hi, frac) = position(n, q);
        if frac == 0.0 {
            values[lo]
        } else {
            values[lo] + frac * (values[hi] - values[lo])
        }
    }));
}

/// Puts the order statistic of every rank of `ranks` (sorted, distinct,
/// counted from `offset`) in its place in `values`: the middle one
/// selected, then the smaller ranks among the values below it and the
/// larger among those above.
fn select_ranks(values: &mut [f64], ranks: &[usize], offset: usize) {
    if ranks.is_empty() {
        return;
    }
    let mid = ranks.len() / 2;
    let at = ranks[mid] - offset;
    let (below, _, above) = values.select_nth_unstable_by(at, f64::total_cmp);
    select_ranks(below, &ranks[..mid], offset);
    select_ranks(above, &ranks[mid + 1..], offset + at + 1);
}

/// The interval quantile transform of windows of one length.
#[derive(Clone)]
pub struct Quantiles {
    points: usize,
    /// Per series, its intervals.
    intervals: [Vec<[usize; 2]>; 4],
    /// Per series, per interval, where its values come sorted from.
    source: [Vec<Source>; 4],
    /// Per series, per level, its intervals' ends.
    ends: [Vec<Vec<usize>>; 4],
    /// Per series, per level, the series with each of the level's
    /// intervals sorted in place.
    levels: [Vec<Vec<f64>>; 4],
    spectrum: MagnitudeSpectrum,
    /// The four series, one after another.
    series: [Vec<f64>; 4],
    sorted: Vec<f64>,
}

impl Quantiles {
    /// For windows of `points` (at least 4).
    pub fn new(points: usize) -> Quantiles {
        let lengths = quantile_series(points);
        let ends = lengths.map(|n| {
            (0..quantile_levels(n, QUANTILE_DEPTH))
                .map(|k| level_ends(n, k))
                .collect::<Vec<_>>()
        });
        let intervals = lengths.map(|n| quantile_intervals(n, QUANTILE_DEPTH));
        let source = std::array::from_fn(|s| {
            intervals[s]
                .iter()
                .map(|&interval| Source::of(interval, &ends[s]))
                .collect()
        });
        Quantiles {
            points,
            levels: std::array::from_fn(|s| vec![vec![0.0; lengths[s]]; ends[s].len()]),
            intervals,
            source,
            ends,
            spectrum: MagnitudeSpectrum::new(points),
            series: lengths.map(|n| vec![0.0; n]),
            sorted: Vec::with_capacity(points),
        }
    }

    /// Each level's intervals sorted in place: the deepest level's
    /// directly, each level above by merging the two below each interval.
    fn sort_levels(&mut self) {
        for ((series, ends), levels) in self.series.iter().zip(&self.ends).zip(&mut self.levels) {
            let Some(deepest) = ends.len().checked_sub(1) else {
                continue;
            };
            levels[deepest].copy_from_slice(series);
            for w in ends[deepest].windows(2) {
                levels[deepest][w[0]..w[1]].sort_unstable_by(f64::total_cmp);
            }
            for k in (0..deepest).rev() {
                let (above, below) = levels.split_at_mut(k + 1);
                let (out, halves) = (&mut above[k], &below[0]);
                for (i, w) in ends[k].windows(2).enumerate() {
                    let mid = ends[k + 1][2 * i + 1];
                    merge(&halves[w[0]..mid], &halves[mid..w[1]], &mut out[w[0]..w[1]]);
                }
            }
        }
    }

    /// Features of one channel's window.
    pub fn len(&self) -> usize {
        quantile_feature_count(self.points)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// One channel's window (`points` values) into `out` (`len()` values).
    pub fn compute(&mut self, x: &[f64], out: &mut [f64]) {
        debug_assert_eq!(x.len(), self.points);
        let [signal, first, second, magnitude] = &mut self.series;
        signal.copy_from_slice(x);
        for (d, w) in first.iter_mut().zip(x.windows(2)) {
            *d = w[1] - w[0];
        }
        for (d, w) in second.iter_mut().zip(first.windows(2)) {
            *d = w[1] - w[0];
        }
        self.spectrum.compute(x, magnitude);
        self.sort_levels();
        let mut f = 0;
        for (s, (series, intervals)) in self.series.iter().zip(&self.intervals).enumerate() {
            for (&[a, b], source) in intervals.iter().zip(&self.source[s]) {
                let part = &series[a..b];
                let q = quantiles_in(part.len());
                let sorted = match *source {
                    Source::Level(k) => &self.levels[s][k][a..b],
                    Source::Merged { level, child } => {
                        let e = &self.ends[s][level];
                        let (ca, mid, cb) = (e[child], e[child + 1], e[child + 2]);
                        let run = &self.levels[s][level];
                        self.sorted.clear();
                        self.sorted.resize(cb - ca, 0.0);
                        merge(&run[ca..mid], &run[mid..cb], &mut self.sorted);
                        refit(&mut self.sorted, series, [ca, cb], [a, b]);
                        &self.sorted[..]
                    }
                    Source::Sorted => {
                        self.sorted.clear();
                        self.sorted.extend_from_slice(part);
                        self.sorted.sort_unstable_by(f64::total_cmp);
                        &self.sorted[..]
                    }
                };
                if part.len() == 1 || q == 1 {
                    out[f] = quantile_sorted(sorted, 0.5);
                    f += 1;
                    continue;
                }
                let mean = part.iter().sum::<f64>() / part.len() as f64;
                for i in 0..q {
                    let v = quantile_sorted(sorted, i as f64 / (q - 1) as f64);
                    out[f] = if i % 2 == 1 { v - mean } else { v };
                    f += 1;
                }
            }
        }
        debug_assert_eq!(f, out.len());
    }
}

/// Where an interval's values come sorted from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Source {
    /// It is one of level `k`'s intervals, sorted with the level.
    Level(usize),
    /// A shifted interval: within two values at each end of `level`'s
    /// intervals `child` and `child + 1`, which are merged and the few
    /// values either side taken out or put in ([`refit`]).
    Merged { level: usize, child: usize },
    /// Neither: sorted on its own.
    Sorted,
}

impl Source {
    /// How the interval `[a, b)` of a series whose levels end at `ends` is
    /// sorted.
    fn of([a, b]: [usize; 2], ends: &[Vec<usize>]) -> Source {
        if let Some(k) = ends
            .iter()
            .position(|e| e.windows(2).any(|w| w[0] == a && w[1] == b))
        {
            return Source::Level(k);
        }
        let near = |x: usize, y: usize| x.abs_diff(y) <= 2;
        for (level, e) in ends.iter().enumerate().rev() {
            let child = e.partition_point(|&end| end + 2 < a);
            if child + 2 < e.len() && near(e[child], a) && near(e[child + 2], b) {
                return Source::Merged { level, child };
            }
        }
        Source::Sorted
    }
}

/// `sorted`, the values of `series[from[0]..from[1]]` in order, made the
/// values of `series[to[0]..to[1]]` in order: the values of the first
/// range outside the second taken out, then those of the second outside
/// the first put in, each where [`f64::total_cmp`] places it (a value
/// equal to another in that order has the same bits, so which of two
/// equal ones goes does not matter).
fn refit(sorted: &mut Vec<f64>, series: &[f64], from: [usize; 2], to: [usize; 2]) {
    let at = |sorted: &[f64], v: f64| sorted.partition_point(|x| x.total_cmp(&v).is_lt());
    let [ca, cb] = from;
    let [a, b] = to;
    let gone = (ca..a.min(cb)).chain(b.max(ca)..cb);
    for i in gone {
        let j = at(sorted, series[i]);
        sorted.remove(j);
    }
    let new = (a..ca.min(b)).chain(cb.max(a)..b);
    for i in new {
        let j = at(sorted, series[i]);
        sorted.insert(j, series[i]);
    }
}

/// Two sorted runs into `out`, in [`f64::total_cmp`]'s order.
fn merge(a: &[f64], b: &[f64], out: &mut [f64]) {
    let (mut i, mut j) = (0, 0);
    for o in out.iter_mut() {
        let take_a = j == b.len() || (i < a.len() && a[i].total_cmp(&b[j]).is_le());
        if take_a {
            *o = a[i];
            i += 1;
        } else {
            *o = b[j];
            j += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quantile by its definition on unsorted values, for checking.
    fn naive_quantile(values: &[f64], q: f64) -> f64 {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let pos = q * (v.len() - 1) as f64;
        let lo = pos.floor() as usize;
        let hi = pos.ceil() as usize;
        v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
    }

    /// `|X_k|` by the DFT's definition.
    fn naive_magnitude(x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (0..=n / 2)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (j, v) in x.iter().enumerate() {
                    let a = -2.0 * std::f64::consts::PI * (j * k) as f64 / n as f64;
                    re += v * a.cos();
                    im += v * a.sin();
                }
                re.hypot(im)
            })
            .collect()
    }

    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        let v = [1.0, 2.0, 4.0, 8.0];
        assert_eq!(quantile_sorted(&v, 0.0), 1.0);
        assert_eq!(quantile_sorted(&v, 1.0), 8.0);
        assert_eq!(quantile_sorted(&v, 0.5), 3.0);
        assert!((quantile_sorted(&v, 0.25) - 1.75).abs() < 1e-15);
        assert_eq!(quantile_sorted(&[5.0], 0.3), 5.0);
    }

    /// Selecting the order statistics gives what sorting gives, to the
    /// bit: ties, signed zeros, infinities, any length and quantile.
    #[test]
    fn selected_quantiles_are_the_sorted_ones_to_the_bit() {
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            seed >> 33
        };
        for n in [1, 2, 3, 7, 64, 1001] {
            for trial in 0..20 {
                let values: Vec<f64> = (0..n)
                    .map(|_| match next() % 9 {
                        0 => 0.0,
                        1 => -0.0,
                        2 => 3.0,
                        3 if trial % 4 == 0 => f64::INFINITY,
                        _ => (next() % 2001) as f64 / 7.0 - 140.0,
                    })
                    .collect();
                let mut sorted = values.clone();
                sorted.sort_by(f64::total_cmp);
                let qs = [0.0, 1.0, 0.5, 0.618, (next() % 1000) as f64 / 999.0];
                // Each quantile alone, and all of them selected together.
                let mut together = Vec::new();
                quantiles_unsorted(&mut values.clone(), &qs, &mut together);
                for (&q, &c) in qs.iter().zip(&together) {
                    let mut scratch = values.clone();
                    let mut alone = Vec::new();
                    quantiles_unsorted(&mut scratch, &[q], &mut alone);
                    let a = alone[0];
                    let b = quantile_sorted(&sorted, q);
                    assert!(
                        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                        "{n} {q}: {a} {b}"
                    );
                    assert!(
                        c.to_bits() == b.to_bits() || (c.is_nan() && b.is_nan()),
                        "{n} {q} together: {c} {b}"
                    );
                }
            }
        }
    }

    /// The levels sorted by merging give every feature exactly as each
    /// interval sorted on its own does: lengths that halve unevenly,
    /// ties and signed zeros.
    #[test]
    fn merged_levels_give_each_interval_sorted_on_its_own_to_the_bit() {
        for n in [4, 5, 6, 7, 9, 17, 31, 63, 100, 257, 1000, 1023, 13178] {
            let x: Vec<f64> = (0..n)
                .map(|j| match j % 11 {
                    3 => 0.0,
                    7 => -0.0,
                    _ => ((j * 7919) % 97) as f64 / 13.0 - 3.0,
                })
                .collect();
            let mut qt = Quantiles::new(n);
            let mut out = vec![f64::NAN; qt.len()];
            qt.compute(&x, &mut out);
            let mut want = Vec::new();
            for (s, series) in qt.series.iter().enumerate() {
                for &[a, b] in &qt.intervals[s] {
                    let mut sorted = series[a..b].to_vec();
                    sorted.sort_by(f64::total_cmp);
                    let q = quantiles_in(sorted.len());
                    if q == 1 {
                        want.push(quantile_sorted(&sorted, 0.5));
                        continue;
                    }
                    let mean = series[a..b].iter().sum::<f64>() / (b - a) as f64;
                    for i in 0..q {
                        let v = quantile_sorted(&sorted, i as f64 / (q - 1) as f64);
                        want.push(if i % 2 == 1 { v - mean } else { v });
                    }
                }
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out), bits(&want), "{n} points");
            // Some intervals of each series come from the merged levels,
            // and beyond 16 points every shifted one from merging two.
            assert!(
                qt.source
                    .iter()
                    .all(|l| { l.iter().filter(|k| matches!(k, Source::Level(_))).count() > 1 })
            );
            if n > 16 {
                let merged = qt.source.iter().flatten();
                assert!(
                    merged
                        .filter(|k| matches!(k, Source::Merged { .. }))
                        .count()
                        >= 4
                );
                for (s, sources) in qt.source.iter().enumerate() {
                    let levels = qt.ends[s].len();
                    for (&source, &[a, b]) in sources.iter().zip(&qt.intervals[s]) {
                        let shifted_above_deepest = !matches!(source, Source::Level(_))
                            && qt.ends[s][..levels - 1]
                                .iter()
                                .any(|e| e.windows(2).any(|w| w[1] - w[0] == b - a));
                        if shifted_above_deepest {
                            assert!(
                                matches!(source, Source::Merged { .. }),
                                "{n} points, series {s}, [{a}, {b}): {source:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn features_follow_the_definition() {
        let n = 45;
        let x: Vec<f64> = (0..n)
            .map(|j| (j as f64 * 0.7).sin() + 0.3 * (j as f64 * 2.3).cos() + 0.01 * j as f64)
            .collect();
        let mut qt = Quantiles::new(n);
        let mut out = vec![f64::NAN; qt.len()];
        qt.compute(&x, &mut out);
        let d1: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let d2: Vec<f64> = d1.windows(2).map(|w| w[1] - w[0]).collect();
        let series = [x.clone(), d1, d2, naive_magnitude(&x)];
        let mut want = Vec::new();
        for s in &series {
            for [a, b] in quantile_intervals(s.len(), 6) {
                let part = &s[a..b];
                let q = 1 + (part.len() - 1) / 4;
                if q == 1 {
                    want.push(naive_quantile(part, 0.5));
                    continue;
                }
                let mean = part.iter().sum::<f64>() / part.len() as f64;
                for i in 0..q {
                    let v = naive_quantile(part, i as f64 / (q - 1) as f64);
                    want.push(if i % 2 == 1 { v - mean } else { v });
                }
            }
        }
        assert_eq!(out.len(), want.len());
        for (i, (a, b)) in out.iter().zip(&want).enumerate() {
            assert!(
                (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                "feature {i}: {a} {b}"
            );
        }
        // The first features: the whole signal's 12 quantiles (45 values),
        // its minimum first and its maximum, less the mean, last.
        let min = x.iter().copied().fold(f64::INFINITY, f64::min);
        let max = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mean = x.iter().sum::<f64>() / n as f64;
        assert_eq!(out[0], min);
        assert!((out[11] - (max - mean)).abs() < 1e-12);
    }

    #[test]
    fn the_features_of_a_window_depend_on_it_alone_and_see_its_shape() {
        let n = 64;
        let mut qt = Quantiles::new(n);
        let a: Vec<f64> = (0..n).map(|j| (j as f64 * 0.5).sin()).collect();
        let b: Vec<f64> = (0..n).map(|j| (j as f64 * 1.5).sin()).collect();
        let (mut fa, mut fb, mut fa2) = (
            vec![0.0; qt.len()],
            vec![0.0; qt.len()],
            vec![0.0; qt.len()],
        );
        qt.compute(&a, &mut fa);
        qt.compute(&b, &mut fb);
        qt.compute(&a, &mut fa2);
        assert_eq!(fa, fa2);
        assert_ne!(fa, fb);
        assert!(fa.iter().all(|v| v.is_finite()));
    }
}
