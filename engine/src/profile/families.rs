//! The feature families `[analysis] features` chooses between, and the
//! arithmetic on their settings that the analysis and the checks share
//! (how many features a window gives): the signal processing itself is in
//! `crate::analysis` (`kernels`, `quantiles`), which uses this, never the
//! reverse.

use serde::{Deserialize, Serialize};

/// What a window's features are.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, PartialOrd, Ord, Default)]
#[serde(rename_all = "kebab-case")]
pub enum FeatureFamily {
    /// A spectrum's bins, bands or cepstra (the thesis's).
    #[default]
    Spectrum,
    /// Random convolutional kernels with PPV pooling (MiniRocket): the
    /// window's points go to the model, which fits the kernels' biases on
    /// its training windows and transforms every window it sees.
    Kernels,
    /// Quantiles over dyadic intervals of the signal, its differences and
    /// its magnitude spectrum (QUANT): fixed, nothing fitted.
    Quantiles,
    /// Competing random kernels (Hydra): in each group of kernels, how
    /// often each wins (responds most) and loses (least) along the signal
    /// and its first difference. Fixed, nothing fitted.
    Hydra,
}

impl FeatureFamily {
    /// Whether the model fits part of the features on its training windows.
    pub fn is_fitted(self) -> bool {
        self == FeatureFamily::Kernels
    }
}

/// Random kernels: the features asked for per channel by default.
pub const DEFAULT_KERNEL_FEATURES: usize = 10_000;
/// Random kernels: the fewest and most features that may be asked for.
pub const KERNEL_FEATURES_RANGE: [usize; 2] = [84, 100_000];
/// Random kernels: their number (every choice of 3 of 9 positions).
pub const KERNEL_COUNT: usize = 84;
/// Random kernels: the fewest points a window may have (one kernel's span).
pub const KERNEL_MIN_POINTS: usize = 9;

/// Competing kernels: groups of kernels, half over the signal and half
/// over its first difference (Hydra's default, 64).
pub const HYDRA_GROUPS: usize = 64;
/// Competing kernels: the kernels of a group, which compete at each point
/// (Hydra's default, 8).
pub const HYDRA_KERNELS: usize = 8;
/// Competing kernels: taps of every kernel.
pub const HYDRA_LENGTH: usize = 9;
/// Competing kernels: the fewest points a window may have (its first
/// difference then spans one kernel).
pub const HYDRA_MIN_POINTS: usize = HYDRA_LENGTH + 1;

/// Competing kernels: the dilations for a window of `points`, 1, 2, 4, …
/// up to the largest whose kernel spans the window (`8·d ≤ points − 1`);
/// none below [`HYDRA_MIN_POINTS`].
pub fn hydra_dilations(points: usize) -> Vec<usize> {
    if points < HYDRA_MIN_POINTS {
        return Vec::new();
    }
    let most = (points - 1) / (HYDRA_LENGTH - 1);
    (0..=most.ilog2()).map(|e| 1usize << e).collect()
}

/// Competing-kernel features of one channel's window of `points`: per
/// dilation, per group and kernel, its wins and its losses.
pub fn hydra_feature_count(points: usize) -> usize {
    hydra_dilations(points).len() * HYDRA_GROUPS * HYDRA_KERNELS * 2
}

/// The deepest level of dyadic intervals (QUANT's default).
pub const QUANTILE_DEPTH: usize = 6;
/// One quantile per this many points of an interval (QUANT's default).
pub const QUANTILE_DIVISOR: usize = 4;

/// How many levels of dyadic intervals a series of `n` values has (at
/// most `depth`).
pub fn quantile_levels(n: usize, depth: usize) -> usize {
    if n == 0 {
        0
    } else {
        depth.min(n.ilog2() as usize + 1)
    }
}

/// The ends of level `k`'s `2^k` intervals over `n` values: `⌊i·n / 2^k⌋`,
/// `i = 0..=2^k`. Each of them is an end of the next level's too, so an
/// interval is the next level's two below it.
pub fn level_ends(n: usize, k: usize) -> Vec<usize> {
    let m = 1usize << k;
    (0..=m).map(|i| i * n / m).collect()
}

/// QUANT's intervals `[start, end)` over a series of `n` values: at level
/// `k = 0, 1, …` (up to `depth` levels, and no more than `⌊log2 n⌋ + 1`),
/// `2^k` intervals with ends `⌊i·n / 2^k⌋`; below the first level, when the
/// intervals' median length is over 1, the same intervals but the last
/// shifted right by `⌈n / 2^k / 2⌉`.
pub fn quantile_intervals(n: usize, depth: usize) -> Vec<[usize; 2]> {
    if n == 0 {
        return Vec::new();
    }
    let mut all = Vec::new();
    for k in 0..quantile_levels(n, depth) {
        let m = 1usize << k;
        let ends = level_ends(n, k);
        let level: Vec<[usize; 2]> = ends.windows(2).map(|w| [w[0], w[1]]).collect();
        let mut lengths: Vec<usize> = level.iter().map(|[a, b]| b - a).collect();
        lengths.sort_unstable();
        // The lower middle value, as a median of an even count is taken.
        let median = lengths[(lengths.len() - 1) / 2];
        all.extend_from_slice(&level);
        if m > 1 && median > 1 {
            let shift = n.div_ceil(2 * m);
            all.extend(
                level[..m - 1]
                    .iter()
                    .map(|[a, b]| [a + shift, (b + shift).min(n)]),
            );
        }
    }
    all
}

/// Quantiles taken over an interval of `width` values: one per
/// [`QUANTILE_DIVISOR`] (at least one; a single value is itself).
pub fn quantiles_in(width: usize) -> usize {
    if width <= 1 {
        1
    } else {
        1 + (width - 1) / QUANTILE_DIVISOR
    }
}

/// The lengths of QUANT's four series for a window of `points`: the
/// signal, its first and second differences, its magnitude spectrum.
pub fn quantile_series(points: usize) -> [usize; 4] {
    [
        points,
        points.saturating_sub(1),
        points.saturating_sub(2),
        points / 2 + 1,
    ]
}

/// Interval-quantile features of one channel's window of `points`.
pub fn quantile_feature_count(points: usize) -> usize {
    quantile_series(points)
        .iter()
        .map(|&n| {
            quantile_intervals(n, QUANTILE_DEPTH)
                .iter()
                .map(|[a, b]| quantiles_in(b - a))
                .sum::<usize>()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_are_dyadic_plus_shifted() {
        // 16 values: levels of 1, 2, 4, 8 and 16 intervals (5 = log2 16 + 1).
        let i = quantile_intervals(16, 6);
        assert_eq!(&i[..3], &[[0, 16], [0, 8], [8, 16]]);
        // Level 1 shifted by 4: [4, 12].
        assert_eq!(i[3], [4, 12]);
        // Level 2: four of 4, three shifted by 2.
        assert_eq!(
            &i[4..11],
            &[[0, 4], [4, 8], [8, 12], [12, 16], [2, 6], [6, 10], [10, 14]]
        );
        // Level 4 (16 of length 1): no shifted copies.
        let last: Vec<_> = i.iter().rev().take(16).collect();
        assert!(last.iter().all(|[a, b]| b - a == 1));
        assert_eq!(i.len(), 1 + 3 + 7 + 15 + 16);
        // Depth 6 caps a long series at 6 levels.
        let long = quantile_intervals(1000, 6);
        assert_eq!(
            long.len(),
            1 + (2 + 1) + (4 + 3) + (8 + 7) + (16 + 15) + (32 + 31)
        );
        assert!(long.iter().all(|&[a, b]| a < b && b <= 1000));
        // Uneven lengths: the ends are floors of i·n/m.
        assert_eq!(&quantile_intervals(10, 2)[1..3], &[[0, 5], [5, 10]]);
        assert_eq!(
            &quantile_intervals(7, 3)[4..8],
            &[[0, 1], [1, 3], [3, 5], [5, 7]]
        );
    }

    #[test]
    fn a_quantile_per_four_values() {
        assert_eq!(quantiles_in(1), 1);
        assert_eq!(quantiles_in(2), 1);
        assert_eq!(quantiles_in(5), 2);
        assert_eq!(quantiles_in(8), 2);
        assert_eq!(quantiles_in(9), 3);
        assert_eq!(quantiles_in(100), 25);
        assert_eq!(quantile_series(100), [100, 99, 98, 51]);
        assert!(quantile_feature_count(100) > 100);
    }

    #[test]
    fn competing_kernels_dilate_until_one_spans_the_window() {
        // 8·d ≤ points − 1.
        assert!(hydra_dilations(9).is_empty());
        assert_eq!(hydra_dilations(10), [1]);
        assert_eq!(hydra_dilations(16), [1]);
        assert_eq!(hydra_dilations(17), [1, 2]);
        assert_eq!(hydra_dilations(199), [1, 2, 4, 8, 16]);
        assert_eq!(hydra_feature_count(199), 5 * 1024);
        assert_eq!(hydra_feature_count(9), 0);
    }
}
