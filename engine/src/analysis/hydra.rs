//! Competing random kernels, as Hydra (Dempster, Schmidt and Webb,
//! "Hydra: competing convolutional kernels for fast and accurate time
//! series classification", Data Mining and Knowledge Discovery, 2023)
//! describes them.
//!
//! [`HYDRA_GROUPS`] groups of [`HYDRA_KERNELS`] kernels of 9 taps, each
//! tap drawn from a standard normal, then the kernel's mean taken away
//! and its taps divided by the sum of their magnitudes. Half of the
//! groups convolve the window, half its first difference, at every
//! dilation 1, 2, 4, … up to a kernel spanning the window
//! ([`hydra_dilations`]), with zeros beyond the series' ends, so every
//! point has an output. At each point the kernels of a group compete: the
//! one responding most wins its response (a soft count), the one
//! responding least a count of one (a hard count). A kernel's two
//! features are its wins summed and its losses counted over the series,
//! each divided by the series' points (so whole windows and sub-windows
//! of one length read alike), then the square root of what is above zero,
//! so that a few kernels winning often do not swamp a linear classifier.
//!
//! The kernels come from a fixed seed: every run and every model has the
//! same, and nothing is fitted on training windows (unlike the MiniRocket
//! kernels' biases, [`super::kernels`]). Several channels are each
//! transformed alike and their features concatenated.
//!
//! Per dilation, [`LANES`] points at a time: their nine shifted inputs are
//! loaded once, then every group's kernels respond and compete in
//! registers. The responses are in single precision (`f32`, eight points a
//! register; the taps and the series rounded to it once), the wins summed
//! in double. Never allocates per call beyond the scratch made once
//! ([`Hydra::new`]).

use std::sync::LazyLock;

use rand::{RngCore, SeedableRng};

use super::kernels::single;
use rand_chacha::ChaCha8Rng;

use crate::profile::families::{
    HYDRA_GROUPS, HYDRA_KERNELS, HYDRA_LENGTH, hydra_dilations, hydra_feature_count,
};

/// The draws of every kernel's taps.
const SEED: u64 = 0x0068_7964_7261_0001;

/// Points made at once: one AVX2 register of `f32`s. The nine shifted
/// inputs of a run of points are loaded once and serve every group.
const LANES: usize = 8;

/// One kernel's taps.
pub type Taps = [f64; HYDRA_LENGTH];

/// One kernel's taps in single precision, as the transform computes.
type SingleTaps = [f32; HYDRA_LENGTH];

/// Every kernel's taps, group after group ([`HYDRA_GROUPS`] ×
/// [`HYDRA_KERNELS`]), drawn once for the process ([`draw_taps`]).
pub fn kernel_taps() -> &'static [Taps] {
    static TAPS: LazyLock<Vec<Taps>> = LazyLock::new(draw_taps);
    &TAPS
}

/// [`kernel_taps`] in single precision, as the transform computes.
fn single_taps() -> &'static [SingleTaps] {
    static TAPS: LazyLock<Vec<SingleTaps>> =
        LazyLock::new(|| kernel_taps().iter().map(|w| w.map(|v| v as f32)).collect());
    &TAPS
}

/// The kernels' taps: standard normal draws (Box–Muller over the fixed
/// seed's ChaCha8 stream, so no library's sampler decides them), less
/// their mean, over the sum of their magnitudes.
fn draw_taps() -> Vec<Taps> {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    // A uniform in (0, 1]: 53 random bits.
    let mut uniform = move || ((rng.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64;
    let mut normal = move || {
        let (u, v) = (uniform(), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    (0..HYDRA_GROUPS * HYDRA_KERNELS)
        .map(|_| {
            let mut w: Taps = std::array::from_fn(|_| normal());
            let mean = w.iter().sum::<f64>() / HYDRA_LENGTH as f64;
            w.iter_mut().for_each(|v| *v -= mean);
            let size: f64 = w.iter().map(|v| v.abs()).sum();
            w.iter_mut().for_each(|v| *v /= size);
            w
        })
        .collect()
}

/// The transform and its scratch, for windows of a given length: made
/// once, reused for every window.
#[derive(Debug, Clone)]
pub struct Hydra {
    points: usize,
    dilations: Vec<usize>,
    /// The series being convolved with zeros either side, as many as the
    /// largest dilation's padding, so a shifted series is a slice.
    padded: Vec<f32>,
    /// The window's first difference.
    diff: Vec<f64>,
}

impl Hydra {
    /// The transform of windows of `points` (at least
    /// [`crate::profile::families::HYDRA_MIN_POINTS`] for any feature).
    pub fn new(points: usize) -> Hydra {
        let dilations = hydra_dilations(points);
        let margin = dilations.last().map_or(0, |d| d * (HYDRA_LENGTH / 2));
        Hydra {
            points,
            dilations,
            // A run of points reads up to LANES − 1 beyond the last.
            padded: vec![0.0; points + 2 * margin + LANES],
            diff: vec![0.0; points.saturating_sub(1)],
        }
    }

    /// Features of one channel's window.
    pub fn len(&self) -> usize {
        hydra_feature_count(self.points)
    }

    /// Whether a window gives no features (fewer points than a kernel spans).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The features of one channel's window `x` (`points` values) into
    /// `out` ([`Hydra::len`] values): per dilation, the signal's groups
    /// then the difference's, per group each kernel's wins then losses.
    pub fn compute(&mut self, x: &[f64], out: &mut [f64]) {
        debug_assert_eq!(x.len(), self.points, "a transform made for other windows");
        debug_assert_eq!(out.len(), self.len());
        for (d, w) in self.diff.iter_mut().zip(x.windows(2)) {
            *d = w[1] - w[0];
        }
        let per_series = HYDRA_GROUPS / 2 * HYDRA_KERNELS * 2;
        for (i, &d) in self.dilations.iter().enumerate() {
            for (s, series) in [x, &self.diff[..]].into_iter().enumerate() {
                let at = (2 * i + s) * per_series;
                series_features(
                    &mut self.padded,
                    series,
                    d,
                    s,
                    &mut out[at..at + per_series],
                );
            }
        }
    }
}

/// One series' features at dilation `d` with the groups of half `s` (0
/// the signal's, 1 the difference's), `padded` the scratch it is laid in
/// with zeros either side.
fn series_features(padded: &mut [f32], series: &[f64], d: usize, s: usize, out: &mut [f64]) {
    let m = series.len();
    let pad = d * (HYDRA_LENGTH / 2);
    padded[..pad].fill(0.0);
    single(series, &mut padded[pad..pad + m]);
    padded[pad + m..pad + m + pad + LANES].fill(0.0);
    out.fill(0.0);
    let half = HYDRA_GROUPS / 2 * HYDRA_KERNELS;
    let taps = &single_taps()[s * half..(s + 1) * half];
    points_of(padded, d, m, taps, out);
    let per = m as f64;
    for c in out.iter_mut() {
        *c = (*c / per).max(0.0).sqrt();
    }
}

/// Every group's wins and losses over the `m` points of a series at
/// dilation `d` (`padded[t + j·d]` its point `t + (j − 4)·d`), added to
/// `counts` (per group, each kernel's wins then losses). On x86-64
/// compiled a second time for AVX2 and that copy taken when the processor
/// has it: the same operations in the same order, the same results to
/// the bit.
fn points_of(padded: &[f32], d: usize, m: usize, taps: &[SingleTaps], counts: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, just checked.
            unsafe { points_avx2(padded, d, m, taps, counts) };
            return;
        }
    }
    points_portable(padded, d, m, taps, counts);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn points_avx2(padded: &[f32], d: usize, m: usize, taps: &[SingleTaps], counts: &mut [f64]) {
    points_portable(padded, d, m, taps, counts);
}

/// [`points_of`], [`LANES`] points at a time: their nine shifted inputs
/// loaded once, then for each group its kernels' outputs (each summed tap
/// by tap in order), the best and worst kernel at each point, and the
/// counts. Between equal responses the first kernel counts.
#[inline(always)]
fn points_portable(padded: &[f32], d: usize, m: usize, taps: &[SingleTaps], counts: &mut [f64]) {
    let groups = taps.chunks_exact(HYDRA_KERNELS);
    let counts = &mut counts[..groups.len() * 2 * HYDRA_KERNELS];
    for t in (0..m).step_by(LANES) {
        let used = LANES.min(m - t);
        let x: [[f32; LANES]; HYDRA_LENGTH] =
            std::array::from_fn(|j| std::array::from_fn(|l| padded[t + j * d + l]));
        for (group, counts) in taps
            .chunks_exact(HYDRA_KERNELS)
            .zip(counts.chunks_exact_mut(2 * HYDRA_KERNELS))
        {
            let mut y = [[0.0f32; LANES]; HYDRA_KERNELS];
            for (y, w) in y.iter_mut().zip(group) {
                for (x, &wj) in x.iter().zip(w) {
                    for l in 0..LANES {
                        y[l] += wj * x[l];
                    }
                }
            }
            let (mut best, mut worst) = (y[0], y[0]);
            let (mut best_k, mut worst_k) = ([0.0f32; LANES], [0.0f32; LANES]);
            for (k, y) in y.iter().enumerate().skip(1) {
                let kf = k as f32;
                for l in 0..LANES {
                    let above = y[l] > best[l];
                    best[l] = if above { y[l] } else { best[l] };
                    best_k[l] = if above { kf } else { best_k[l] };
                    let below = y[l] < worst[l];
                    worst[l] = if below { y[l] } else { worst[l] };
                    worst_k[l] = if below { kf } else { worst_k[l] };
                }
            }
            for l in 0..used {
                counts[2 * best_k[l] as usize] += f64::from(best[l]);
                counts[2 * worst_k[l] as usize + 1] += 1.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::families::HYDRA_MIN_POINTS;

    /// The transform one point at a time, as the paper states it (the
    /// responses in single precision, as the transform's).
    fn direct(x: &[f64]) -> Vec<f64> {
        let taps = single_taps();
        let diff: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let mut out = Vec::new();
        for d in hydra_dilations(x.len()) {
            for (s, series) in [x, &diff[..]].into_iter().enumerate() {
                let m = series.len() as i64;
                let at = |t: i64| {
                    if (0..m).contains(&t) {
                        series[t as usize] as f32
                    } else {
                        0.0
                    }
                };
                for g in 0..HYDRA_GROUPS / 2 {
                    let group =
                        &taps[(s * HYDRA_GROUPS / 2 + g) * HYDRA_KERNELS..][..HYDRA_KERNELS];
                    let mut counts = [0.0; 2 * HYDRA_KERNELS];
                    for t in 0..m {
                        let outputs: Vec<f32> = group
                            .iter()
                            .map(|w| {
                                let mut sum = 0.0f32;
                                for (j, wj) in w.iter().enumerate() {
                                    sum += wj * at(t + (j as i64 - 4) * d as i64);
                                }
                                sum
                            })
                            .collect();
                        let (mut hi, mut lo) = (0, 0);
                        for k in 1..HYDRA_KERNELS {
                            if outputs[k] > outputs[hi] {
                                hi = k;
                            }
                            if outputs[k] < outputs[lo] {
                                lo = k;
                            }
                        }
                        counts[2 * hi] += f64::from(outputs[hi]);
                        counts[2 * lo + 1] += 1.0;
                    }
                    out.extend(counts.iter().map(|c| (c / m as f64).max(0.0).sqrt()));
                }
            }
        }
        out
    }

    fn window(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|t| (t as f64 * 0.3).sin() + (rng.next_u32() % 1000) as f64 / 500.0 - 1.0)
            .collect()
    }

    #[test]
    fn the_kernels_are_fixed_zero_mean_and_of_unit_magnitude() {
        let taps = kernel_taps();
        assert_eq!(taps.len(), HYDRA_GROUPS * HYDRA_KERNELS);
        for w in taps {
            assert!(w.iter().sum::<f64>().abs() < 1e-12);
            assert!((w.iter().map(|v| v.abs()).sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // A model names no kernels: they must never change. The first taps
        // as drawn today.
        let first: Vec<String> = taps[0][..3].iter().map(|v| format!("{v:.6}")).collect();
        assert_eq!(first, FIRST_TAPS);
        // Draws, not copies: no two kernels alike.
        assert!(taps.windows(2).all(|p| p[0] != p[1]));
    }

    /// [`kernel_taps`]' first kernel's first three taps, to six places.
    const FIRST_TAPS: [&str; 3] = ["-0.159894", "-0.141411", "0.083446"];

    #[test]
    fn the_blocked_transform_is_the_direct_sum() {
        // Lengths below, at and across blocks, with dilations up to 256.
        for n in [HYDRA_MIN_POINTS, 17, 50, 199, 256, 257, 600, 2100] {
            let x = window(n, n as u64);
            let mut h = Hydra::new(n);
            let mut got = vec![f64::NAN; h.len()];
            h.compute(&x, &mut got);
            let want = direct(&x);
            assert_eq!(got.len(), want.len(), "{n} points");
            for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                    "{n} points, feature {i}: {a} against {b}"
                );
            }
            // Reused, the scratch leaves nothing behind.
            let mut again = vec![0.0; h.len()];
            h.compute(&x, &mut again);
            assert_eq!(got, again);
        }
    }

    #[test]
    fn each_point_has_one_winner_and_one_loser_per_group() {
        let n = 300;
        let x = window(n, 7);
        let mut h = Hydra::new(n);
        let mut f = vec![0.0; h.len()];
        h.compute(&x, &mut f);
        // Losses are hard counts: squared back and summed over a group's
        // kernels, every point's one loss.
        let dilations = hydra_dilations(n).len();
        for (i, group) in f.chunks_exact(2 * HYDRA_KERNELS).enumerate() {
            let losses: f64 = group.iter().skip(1).step_by(2).map(|v| v * v).sum();
            assert!((losses - 1.0).abs() < 1e-12, "group {i}: {losses}");
        }
        assert_eq!(f.len(), dilations * HYDRA_GROUPS * 2 * HYDRA_KERNELS);
        // Scaling the window scales each win by the square root and leaves
        // the losses alone.
        let y: Vec<f64> = x.iter().map(|v| 4.0 * v).collect();
        let mut g = vec![0.0; h.len()];
        h.compute(&y, &mut g);
        for (a, b) in f.chunks_exact(2).zip(g.chunks_exact(2)) {
            assert!((2.0 * a[0] - b[0]).abs() < 1e-9);
            assert!((a[1] - b[1]).abs() < 1e-12);
        }
    }
}
