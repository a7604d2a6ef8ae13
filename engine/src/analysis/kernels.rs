//! Random convolutional kernel features, as MiniRocket (Dempster, Schmidt
//! and Webb, KDD 2021) describes them, written from the paper.
//!
//! What is fixed (a function of the window's length and the feature count
//! alone, [`KernelLayout`]):
//! - the 84 kernels of length 9: weights −1 everywhere except three
//!   positions of weight 2 (every choice of 3 of the 9 positions, in
//!   lexicographic order), so each kernel's weights sum to zero;
//! - the dilations `⌊2^e⌋` for `e` evenly spaced from 0 to
//!   `log2((L − 1) / 8)` (at most 32 values, duplicates merged), each
//!   getting features in proportion to how often it came up, so that every
//!   kernel has `features / 84` features in all;
//! - the padding, alternating over the kernel/dilation combinations: the
//!   combination of dilation `i` and kernel `k` is padded (zeros beyond the
//!   window, an output for every point) when `i + k` is even, and otherwise
//!   takes only the outputs whose nine taps all lie in the window.
//!
//! What is fitted ([`KernelTransform::fit`]): the biases. For each
//! kernel/dilation a training window is drawn at random and the biases of
//! its features are quantiles of that window's (padded) convolution
//! output, the quantiles `{f·φ} = f·φ mod 1` (φ the golden ratio, `f` the
//! feature's number from 1), a low-discrepancy sequence. A model carries the
//! biases; they must come from training windows only, never from a window
//! the model will be tested on.
//!
//! The feature is the proportion of positive values (PPV) of the output
//! minus the bias. Each channel is transformed on its own with its own
//! biases, and the channels' features are concatenated (the simple
//! multichannel form, not the paper's channel-mixing variant).
//!
//! Computed as the paper suggests: per dilation, the sum of the nine
//! shifted windows (the −1 part, shared by every kernel) and three times
//! each shifted window; a kernel's output is the first plus three of the
//! others, `((base + 3x_a) + 3x_b) + 3x_c` in that order. The transform
//! works through the window in blocks of 256 points kept in the L1 cache:
//! per dilation and block the shifted rows once, the sums with a kernel's
//! first one and two weights of 2 once for the kernels that share them,
//! and each kernel's output counted against all its biases at that
//! dilation while it is in a register (four biases a pass, vectorised;
//! AVX2 when the processor has it). The PPV counting is most of the work:
//! about 9 million comparisons for 9996 features of a 1000-point window.
//!
//! The convolution and the counting are in single precision (`f32`, as
//! aeon's MiniRocket computes them): eight points a register where double
//! precision holds four, which halves the counting. The window (detrended
//! by the analysis first, unless the profile says `detrend = "none"`) is
//! rounded to `f32` once; the fit rounds each bias to `f32`, so the fit
//! and the transform compare the same numbers, and a model file's biases
//! are those numbers exactly (a model written before, with biases in
//! double precision, loads and has them rounded). A feature differs from
//! a double-precision one only where an output lies within rounding
//! (about 10⁻⁷ of the window's largest values) of its bias: on the
//! generated sets no search's choice or outer estimate changed. Every
//! output is summed in the same order as the fit sums it, so the features
//! are the same to the bit as one kernel at a time would give. Never
//! allocates per call beyond the scratch made once ([`Convolution`]).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::quantiles::quantiles_unsorted;
use crate::profile::families;

/// Taps of every kernel.
pub const KERNEL_LENGTH: usize = 9;
/// The kernels: every choice of 3 of the 9 positions.
pub const KERNEL_COUNT: usize = families::KERNEL_COUNT;
/// At most this many dilations per kernel.
pub const MAX_DILATIONS: usize = 32;
/// The features asked for by default (9996 made: a multiple of 84).
pub const DEFAULT_FEATURES: usize = families::DEFAULT_KERNEL_FEATURES;
/// The fewest points a window may have: one kernel's span.
pub const MIN_POINTS: usize = families::KERNEL_MIN_POINTS;
/// The most features that may be asked for, per channel.
pub const MAX_FEATURES: usize = families::KERNEL_FEATURES_RANGE[1];
/// The draws of the training window behind each kernel/dilation's biases.
const SEED: u64 = 0x006b_6572_6e65_6c73;

/// The golden ratio, whose multiples modulo 1 give the quantiles.
const PHI: f64 = 1.618_033_988_749_895;

/// The 84 kernels, each as the positions of its three weights of 2, in
/// lexicographic order.
pub fn kernels() -> Vec<[usize; 3]> {
    let mut all = Vec::with_capacity(KERNEL_COUNT);
    for a in 0..KERNEL_LENGTH {
        for b in a + 1..KERNEL_LENGTH {
            for c in b + 1..KERNEL_LENGTH {
                all.push([a, b, c]);
            }
        }
    }
    all
}

/// The kernel's nine weights (−1, and 2 at its three positions).
pub fn weights(kernel: [usize; 3]) -> [f64; KERNEL_LENGTH] {
    let mut w = [-1.0; KERNEL_LENGTH];
    for p in kernel {
        w[p] = 2.0;
    }
    w
}

/// The quantile whose value becomes feature `f`'s bias (`f` from 0).
pub fn bias_quantile(f: usize) -> f64 {
    ((f + 1) as f64 * PHI).fract()
}

/// Whether the combination of dilation `i` and kernel `k` is padded.
pub fn padded(dilation_index: usize, kernel_index: usize) -> bool {
    (dilation_index + kernel_index).is_multiple_of(2)
}

/// The features made of `asked`: a multiple of 84 (none below 84).
pub fn features_made(asked: usize) -> usize {
    (asked / KERNEL_COUNT) * KERNEL_COUNT
}

/// The fixed part of the transform: the dilations and how many features
/// each gives per kernel, for windows of `points`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelLayout {
    pub points: usize,
    pub dilations: Vec<usize>,
    /// Features per kernel at each dilation (the same for every kernel).
    pub features_per_dilation: Vec<usize>,
}

impl KernelLayout {
    /// The layout for windows of `points` (at least 9) and `asked`
    /// features per channel (84 to [`MAX_FEATURES`]).
    pub fn new(points: usize, asked: usize) -> Result<KernelLayout, String> {
        if points < MIN_POINTS {
            return Err(format!(
                "random kernels need windows of at least {MIN_POINTS} points, got {points}"
            ));
        }
        if !(families::KERNEL_FEATURES_RANGE[0]..=MAX_FEATURES).contains(&asked) {
            return Err(format!(
                "must be {KERNEL_COUNT} to {MAX_FEATURES} features, got {asked}"
            ));
        }
        let per_kernel = asked / KERNEL_COUNT;
        let steps = per_kernel.min(MAX_DILATIONS);
        let top = ((points - 1) as f64 / (KERNEL_LENGTH - 1) as f64).log2();
        let mut dilations: Vec<usize> = Vec::new();
        let mut counts: Vec<usize> = Vec::new();
        for s in 0..steps {
            let e = if steps == 1 {
                0.0
            } else {
                top * s as f64 / (steps - 1) as f64
            };
            // The largest dilation keeps the kernel's span within the window.
            let d = (2f64.powf(e).floor() as usize).clamp(1, (points - 1) / (KERNEL_LENGTH - 1));
            match dilations.last() {
                Some(&last) if last == d => *counts.last_mut().expect("a count per dilation") += 1,
                _ => {
                    dilations.push(d);
                    counts.push(1);
                }
            }
        }
        // In proportion to how often each came up, the remainder one each
        // from the smallest dilation on.
        let share = per_kernel as f64 / steps as f64;
        let mut features_per_dilation: Vec<usize> = counts
            .iter()
            .map(|&c| (c as f64 * share).floor() as usize)
            .collect();
        let mut left = per_kernel - features_per_dilation.iter().sum::<usize>();
        let mut i = 0;
        while left > 0 {
            features_per_dilation[i] += 1;
            left -= 1;
            i = (i + 1) % features_per_dilation.len();
        }
        Ok(KernelLayout {
            points,
            dilations,
            features_per_dilation,
        })
    }

    /// Features per channel: 84 × the features per kernel.
    pub fn feature_count(&self) -> usize {
        KERNEL_COUNT * self.features_per_dilation.iter().sum::<usize>()
    }

    /// The padding of dilation `d` (half the kernel's span).
    fn padding(d: usize) -> usize {
        (KERNEL_LENGTH - 1) * d / 2
    }
}

/// Points per block of the transform: a block's nine shifted rows and its
/// three working rows (12 × 256 values, 24 KiB) stay in the L1 cache.
const BLOCK: usize = 256;

/// Rows of a block: the nine shifted windows, then the −1 sum, the sum with
/// a kernel's first weight of 2 and with its first two.
const BLOCK_ROWS: usize = KERNEL_LENGTH + 3;

/// The scratch of the transform (and of the fit), for windows of a given
/// length; made once, reused for every window.
#[derive(Debug, Clone)]
pub struct Convolution {
    points: usize,
    /// `−Σ_j x[t + (j − 4)·d]`: every kernel's −1 part (the fit's).
    base: Vec<f32>,
    /// One kernel's output (the fit's).
    output: Vec<f32>,
    /// The channel being transformed with zeros either side, as many as
    /// the largest dilation's padding, so a shifted window is a slice.
    padded: Vec<f32>,
    /// One block of points: [`BLOCK_ROWS`] rows of [`BLOCK`] values.
    block: Vec<f32>,
    /// The biases of the channel being transformed, in single precision.
    biases: Vec<f32>,
}

impl Convolution {
    pub fn new(points: usize) -> Convolution {
        let margin = Convolution::margin(points);
        Convolution {
            points,
            base: vec![0.0; points],
            output: vec![0.0; points],
            padded: vec![0.0; points + 2 * margin],
            block: vec![0.0; BLOCK_ROWS * BLOCK],
            biases: Vec::new(),
        }
    }

    /// The zeros either side of [`Convolution::padded`]: the padding of
    /// the largest dilation a window of `points` may have.
    fn margin(points: usize) -> usize {
        KernelLayout::padding((points.saturating_sub(1) / (KERNEL_LENGTH - 1)).max(1))
    }

    /// `x[t + (j − 4)·d]` for every `t` of the window last loaded (zero
    /// beyond it): the nine shifted windows of dilation `d` are slices.
    fn shifted(&self, j: usize, d: usize) -> &[f32] {
        let from = Convolution::margin(self.points) - KernelLayout::padding(d) + j * d;
        &self.padded[from..from + self.points]
    }

    /// Takes `x` as the window the fit convolves next.
    fn load(&mut self, x: &[f64]) {
        let margin = Convolution::margin(self.points);
        single(x, &mut self.padded[margin..margin + self.points]);
    }

    /// The −1 part of every kernel at dilation `d` for the window loaded:
    /// the nine shifted windows subtracted from zero one after another.
    fn dilate(&mut self, d: usize) {
        let mut base = std::mem::take(&mut self.base);
        base.fill(0.0);
        for j in 0..KERNEL_LENGTH {
            for (b, &v) in base.iter_mut().zip(self.shifted(j, d)) {
                *b -= v;
            }
        }
        self.base = base;
    }

    /// The output of `kernel` at the dilation last dilated, all `points`
    /// of it (padded): `((base + 3x_a) + 3x_b) + 3x_c`.
    fn convolve(&mut self, kernel: [usize; 3], d: usize) -> &mut [f32] {
        let mut output = std::mem::take(&mut self.output);
        let [a, b, c] = kernel.map(|p| self.shifted(p, d));
        for ((((o, &u), &a), &b), &c) in output.iter_mut().zip(&self.base).zip(a).zip(b).zip(c) {
            *o = u + 3.0 * a + 3.0 * b + 3.0 * c;
        }
        self.output = output;
        &mut self.output
    }

    /// One channel's features: `x` its points, `biases` and `out` its
    /// features (the biases rounded to single precision into
    /// [`Convolution::biases`] first). On x86-64 compiled a second time for
    /// AVX2 and that copy taken when the processor has it (the same
    /// operations in the same order: the same results to the bit).
    fn channel(&mut self, layout: &KernelLayout, x: &[f64], biases: &[f64], out: &mut [f64]) {
        self.biases.clear();
        self.biases.extend(biases.iter().map(|&b| b as f32));
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2, just checked.
                unsafe { self.channel_avx2(layout, x, out) };
                return;
            }
        }
        self.channel_portable(layout, x, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn channel_avx2(&mut self, layout: &KernelLayout, x: &[f64], out: &mut [f64]) {
        self.channel_portable(layout, x, out);
    }

    /// [`Convolution::channel`], block by block: per dilation and block of
    /// [`BLOCK`] points, the nine shifted windows times 3 and their
    /// negated sum (the −1 part) once; a kernel `(a, b, c)`'s output is
    /// `((base + 3x_a) + 3x_b) + 3x_c`, the sum of its first two terms
    /// shared by the kernels that begin alike, its last term added as the
    /// output is counted against every bias of the kernel at this dilation.
    /// Each value is summed in the order [`Convolution::convolve`] sums it,
    /// so the outputs, and the counts, are the same to the bit.
    #[inline(always)]
    fn channel_portable(&mut self, layout: &KernelLayout, x: &[f64], out: &mut [f64]) {
        let n = self.points;
        let margin = Convolution::margin(n);
        single(x, &mut self.padded[margin..margin + n]);
        let padded_x = &self.padded[..];
        let biases = &self.biases[..];
        let (rows, work) = self.block.split_at_mut(KERNEL_LENGTH * BLOCK);
        let (base, work) = work.split_at_mut(BLOCK);
        let (first, second) = work.split_at_mut(BLOCK);
        let mut f0 = 0;
        for (i, (&d, &count)) in layout
            .dilations
            .iter()
            .zip(&layout.features_per_dilation)
            .enumerate()
        {
            let pad = KernelLayout::padding(d);
            let sums = &mut out[f0..f0 + KERNEL_COUNT * count];
            let biases = &biases[f0..f0 + KERNEL_COUNT * count];
            sums.fill(0.0);
            for t0 in (0..n).step_by(BLOCK) {
                let len = BLOCK.min(n - t0);
                // The outputs of an unpadded kernel kept in this block.
                let lo = pad.saturating_sub(t0).min(len);
                let hi = (n - pad).saturating_sub(t0).min(len);
                // padded_x[from + j·d + t] is x[t0 + t + (j − 4)·d].
                let from = margin - pad + t0;
                let base = &mut base[..len];
                base.fill(0.0);
                for j in 0..KERNEL_LENGTH {
                    let src = &padded_x[from + j * d..from + j * d + len];
                    let row = &mut rows[j * BLOCK..j * BLOCK + len];
                    for ((r, b), &v) in row.iter_mut().zip(base.iter_mut()).zip(src) {
                        *r = 3.0 * v;
                        *b -= v;
                    }
                }
                let row = |j: usize| &rows[j * BLOCK..j * BLOCK + len];
                let mut k = 0;
                for a in 0..KERNEL_LENGTH - 2 {
                    let first = &mut first[..len];
                    for ((s, &u), &v) in first.iter_mut().zip(base.iter()).zip(row(a)) {
                        *s = u + v;
                    }
                    for b in a + 1..KERNEL_LENGTH - 1 {
                        let second = &mut second[..len];
                        for ((s, &u), &v) in second.iter_mut().zip(first.iter()).zip(row(b)) {
                            *s = u + v;
                        }
                        for c in b + 1..KERNEL_LENGTH {
                            let (lo, hi) = if padded(i, k) { (0, len) } else { (lo, hi) };
                            if lo < hi {
                                count_above(
                                    &second[lo..hi],
                                    &row(c)[lo..hi],
                                    &biases[k * count..(k + 1) * count],
                                    &mut sums[k * count..(k + 1) * count],
                                );
                            }
                            k += 1;
                        }
                    }
                }
            }
            for (k, sums) in sums.chunks_exact_mut(count).enumerate() {
                let seen = if padded(i, k) { n } else { n - 2 * pad };
                let len = seen as f64;
                for s in sums {
                    *s /= len;
                }
            }
            f0 += KERNEL_COUNT * count;
        }
    }
}

/// Adds to `sums[j]` how many of `u[t] + v[t]` exceed `biases[j]`, four
/// biases a pass (then the three, two or one left in one more pass), so
/// each output is made once per pass and compared with every bias of the
/// pass while in a register; the loops over `t` are vectorised.
#[inline(always)]
fn count_above(u: &[f32], v: &[f32], biases: &[f32], sums: &mut [f64]) {
    let mut bs = biases.chunks_exact(4);
    let mut ss = sums.chunks_exact_mut(4);
    for (b, s) in (&mut bs).zip(&mut ss) {
        count_pass::<4>(u, v, b, s);
    }
    let (b, s) = (bs.remainder(), ss.into_remainder());
    match b.len() {
        3 => count_pass::<3>(u, v, b, s),
        2 => count_pass::<2>(u, v, b, s),
        1 => count_pass::<1>(u, v, b, s),
        _ => {}
    }
}

/// One pass of [`count_above`] over `N` biases.
#[inline(always)]
fn count_pass<const N: usize>(u: &[f32], v: &[f32], biases: &[f32], sums: &mut [f64]) {
    let b: [f32; N] = std::array::from_fn(|j| biases[j]);
    let mut n = [0u32; N];
    for (&p, &q) in u.iter().zip(&v[..u.len()]) {
        let y = p + q;
        for j in 0..N {
            n[j] += u32::from(y > b[j]);
        }
    }
    for j in 0..N {
        sums[j] += f64::from(n[j]);
    }
}

/// `x` in single precision, into `to` (as long).
pub(super) fn single(x: &[f64], to: &mut [f32]) {
    for (t, &v) in to.iter_mut().zip(x) {
        *t = v as f32;
    }
}

/// The fitted transform: the layout and each channel's biases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelTransform {
    pub layout: KernelLayout,
    /// `biases[c][f]`: channel `c`'s feature `f`.
    pub biases: Vec<Vec<f64>>,
}

impl KernelTransform {
    /// Fits the biases on training windows, each `channels` × `points`
    /// values (channel after channel), for `asked` features per channel.
    pub fn fit(
        windows: &[&[f64]],
        points: usize,
        channels: usize,
        asked: usize,
    ) -> Result<KernelTransform, String> {
        let layout = KernelLayout::new(points, asked)?;
        if windows.is_empty() {
            return Err("no training windows to fit the kernels' biases on".into());
        }
        if let Some(w) = windows.iter().find(|w| w.len() != points * channels) {
            return Err(format!(
                "a training window has {} values, not {channels} channel(s) of {points} points",
                w.len()
            ));
        }
        let kernels = kernels();
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let mut conv = Convolution::new(points);
        let (mut qs, mut got, mut output) = (Vec::new(), Vec::new(), Vec::new());
        let mut biases = Vec::with_capacity(channels);
        for c in 0..channels {
            let mut own = vec![0.0; layout.feature_count()];
            let mut f0 = 0;
            for (&d, &count) in layout.dilations.iter().zip(&layout.features_per_dilation) {
                // Each kernel's training window, drawn in kernel order; the
                // kernels that drew the same one convolve it after one
                // loading and one −1 part.
                let drawn: Vec<usize> = kernels
                    .iter()
                    .map(|_| rng.random_range(0..windows.len()))
                    .collect();
                let mut order: Vec<usize> = (0..kernels.len()).collect();
                order.sort_by_key(|&k| drawn[k]);
                let mut loaded = None;
                for k in order {
                    if loaded != Some(drawn[k]) {
                        conv.load(&windows[drawn[k]][c * points..(c + 1) * points]);
                        conv.dilate(d);
                        loaded = Some(drawn[k]);
                    }
                    let first = f0 + k * count;
                    qs.clear();
                    qs.extend((first..first + count).map(bias_quantile));
                    got.clear();
                    output.clear();
                    output.extend(conv.convolve(kernels[k], d).iter().map(|&v| f64::from(v)));
                    quantiles_unsorted(&mut output, &qs, &mut got);
                    // Single precision, as the outputs it is compared with.
                    for (b, &q) in own[first..first + count].iter_mut().zip(&got) {
                        *b = f64::from(q as f32);
                    }
                }
                f0 += KERNEL_COUNT * count;
            }
            biases.push(own);
        }
        Ok(KernelTransform { layout, biases })
    }

    pub fn channels(&self) -> usize {
        self.biases.len()
    }

    /// Features of a window: every channel's.
    pub fn feature_count(&self) -> usize {
        self.channels() * self.layout.feature_count()
    }

    /// Values of the windows it transforms.
    pub fn window_len(&self) -> usize {
        self.channels() * self.layout.points
    }

    /// Checks a transform read from a file: the layout is the one its
    /// points and `asked` features give, and every bias is finite.
    pub fn check(&self, points: usize, channels: usize, asked: usize) -> Result<(), String> {
        let want = KernelLayout::new(points, asked)?;
        if self.layout != want {
            return Err(format!(
                "its kernel layout is not the one for {points} points and {asked} features"
            ));
        }
        if self.biases.len() != channels
            || self
                .biases
                .iter()
                .any(|b| b.len() != want.feature_count() || b.iter().any(|v| !v.is_finite()))
        {
            return Err(format!(
                "its kernel biases must be {channels} channel(s) of {} finite numbers",
                want.feature_count()
            ));
        }
        Ok(())
    }

    /// Transforms one window (`window_len()` values) into `out`
    /// (`feature_count()` values), with `conv` made for its points.
    pub fn transform(&self, window: &[f64], conv: &mut Convolution, out: &mut [f64]) {
        let n = self.layout.points;
        let per = self.layout.feature_count();
        debug_assert_eq!(conv.points, n, "a convolution made for other windows");
        for (c, biases) in self.biases.iter().enumerate() {
            conv.channel(
                &self.layout,
                &window[c * n..(c + 1) * n],
                biases,
                &mut out[c * per..(c + 1) * per],
            );
        }
    }

    /// A scratch [`Convolution`] for this transform's windows.
    pub fn convolution(&self) -> Convolution {
        let mut conv = Convolution::new(self.layout.points);
        conv.biases.reserve(self.layout.feature_count());
        conv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kernel `kernel` at dilation `d` over `x`, term by term as written:
    /// `Σ_j w_j x[t + (j − 4)d]`, zero beyond the window.
    fn naive_convolution(x: &[f64], kernel: [usize; 3], d: usize) -> Vec<f64> {
        let w = weights(kernel);
        let n = x.len() as isize;
        (0..n)
            .map(|t| {
                (0..KERNEL_LENGTH)
                    .map(|j| {
                        let at = t + (j as isize - 4) * d as isize;
                        if (0..n).contains(&at) {
                            w[j] * x[at as usize]
                        } else {
                            0.0
                        }
                    })
                    .sum()
            })
            .collect()
    }

    /// Windows of small whole numbers: every sum is exact, so the fast
    /// and the naive convolution agree to the bit and so do the counts.
    fn integer_windows(count: usize, len: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..count)
            .map(|_| {
                (0..len)
                    .map(|_| f64::from(rng.random_range(-20i32..=20)))
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_84_kernels_are_every_choice_of_three_positions_summing_to_zero() {
        let k = kernels();
        assert_eq!(k.len(), KERNEL_COUNT);
        let mut seen = std::collections::BTreeSet::new();
        for kernel in &k {
            assert!(kernel[0] < kernel[1] && kernel[1] < kernel[2] && kernel[2] < 9);
            assert!(seen.insert(*kernel));
            assert_eq!(weights(*kernel).iter().sum::<f64>(), 0.0);
        }
        assert_eq!(k[0], [0, 1, 2]);
        assert_eq!(k[83], [6, 7, 8]);
    }

    #[test]
    fn dilations_are_exponential_up_to_a_kernel_spanning_the_window() {
        for (points, asked) in [
            (100, 10_000),
            (9, 10_000),
            (1000, 10_000),
            (50, 84),
            (300, 2000),
        ] {
            let l = KernelLayout::new(points, asked).unwrap();
            assert_eq!(l.feature_count(), features_made(asked), "{points} {asked}");
            assert_eq!(l.dilations[0], 1);
            assert!(l.dilations.windows(2).all(|w| w[0] < w[1]), "{l:?}");
            let top = *l.dilations.last().unwrap();
            assert!(8 * top < points, "{l:?}");
            // With 32 steps the largest is ⌊(L − 1) / 8⌋ up to the floor
            // of the power; a single step is dilation 1 alone.
            if asked >= 32 * KERNEL_COUNT {
                assert!(2 * top > (points - 1) / 8, "{l:?}");
            }
            assert!(l.dilations.len() <= MAX_DILATIONS);
            assert!(l.features_per_dilation.iter().all(|&c| c > 0), "{l:?}");
        }
        // 100 points: 2^e for 32 e from 0 to log2(99/8) = 3.63.
        let l = KernelLayout::new(100, 10_000).unwrap();
        assert_eq!(l.dilations, vec![1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
        assert_eq!(l.features_per_dilation.iter().sum::<usize>(), 119);
        assert_eq!(features_made(10_000), 9996);
        // Windows of 9 points: one dilation, 1.
        assert_eq!(KernelLayout::new(9, 1000).unwrap().dilations, vec![1]);
        assert!(KernelLayout::new(8, 1000).is_err());
        assert!(KernelLayout::new(100, 83).is_err());
    }

    #[test]
    fn half_the_combinations_are_padded_alternately() {
        let l = KernelLayout::new(500, 10_000).unwrap();
        let padded_count = (0..l.dilations.len())
            .flat_map(|i| (0..KERNEL_COUNT).map(move |k| padded(i, k)))
            .filter(|&p| p)
            .count();
        assert_eq!(padded_count, l.dilations.len() * KERNEL_COUNT / 2);
        assert!(padded(0, 0) && !padded(0, 1) && !padded(1, 0) && padded(1, 1));
    }

    #[test]
    fn the_convolution_is_the_direct_sum() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let x: Vec<f64> = (0..61).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut conv = Convolution::new(x.len());
        conv.load(&x);
        for d in [1, 2, 3, 7] {
            conv.dilate(d);
            for kernel in kernels() {
                let fast = conv.convolve(kernel, d).to_vec();
                let naive = naive_convolution(&x, kernel, d);
                for (&a, b) in fast.iter().zip(&naive) {
                    // Single precision: 27 terms of at most 3 each.
                    assert!((f64::from(a) - b).abs() < 1e-5, "d {d} {kernel:?}: {a} {b}");
                }
            }
        }
    }

    #[test]
    fn features_match_the_naive_transform_exactly() {
        for (points, channels, asked, seed) in
            [(100, 1, 10_000, 1), (37, 2, 840, 2), (9, 1, 168, 3)]
        {
            let windows = integer_windows(5, points * channels, seed);
            let refs: Vec<&[f64]> = windows.iter().map(Vec::as_slice).collect();
            let t = KernelTransform::fit(&refs, points, channels, asked).unwrap();
            assert_eq!(t.feature_count(), channels * features_made(asked));
            let mut conv = t.convolution();
            let mut out = vec![f64::NAN; t.feature_count()];
            for w in integer_windows(3, points * channels, seed + 100) {
                t.transform(&w, &mut conv, &mut out);
                assert_eq!(
                    out,
                    reference_features(&t, &w, naive_convolution),
                    "{points} points"
                );
            }
        }
    }

    /// Kernel `kernel` at dilation `d` over `x`, written directly but
    /// summed as the module sums: in single precision, the −1 part over
    /// the nine taps (zeros beyond the window) from the first tap on, then
    /// 3 times each tap of weight 2, the first first.
    fn direct_in_order(x: &[f64], kernel: [usize; 3], d: usize) -> Vec<f64> {
        let n = x.len() as isize;
        let tap = |t: isize, j: usize| {
            let at = t + (j as isize - 4) * d as isize;
            if (0..n).contains(&at) {
                x[at as usize] as f32
            } else {
                0.0
            }
        };
        (0..n)
            .map(|t| {
                let mut y = 0.0f32;
                for j in 0..KERNEL_LENGTH {
                    y -= tap(t, j);
                }
                for p in kernel {
                    y += 3.0 * tap(t, p);
                }
                f64::from(y)
            })
            .collect()
    }

    /// The features by definition, each kernel's output made by `convolve`
    /// (`x`, kernel, dilation), every bias counted on its own.
    fn reference_features(
        t: &KernelTransform,
        window: &[f64],
        convolve: impl Fn(&[f64], [usize; 3], usize) -> Vec<f64>,
    ) -> Vec<f64> {
        let n = t.layout.points;
        let mut out = Vec::new();
        for (c, biases) in t.biases.iter().enumerate() {
            let x = &window[c * n..(c + 1) * n];
            let mut f = 0;
            for (i, (&d, &count)) in t
                .layout
                .dilations
                .iter()
                .zip(&t.layout.features_per_dilation)
                .enumerate()
            {
                for (k, &kernel) in kernels().iter().enumerate() {
                    let y = convolve(x, kernel, d);
                    // Unpadded: only the outputs whose nine taps all lie
                    // in the window.
                    let kept = if padded(i, k) {
                        &y[..]
                    } else {
                        &y[4 * d..n - 4 * d]
                    };
                    for &b in &biases[f..f + count] {
                        let positive = kept.iter().filter(|&&v| v > b).count();
                        out.push(positive as f64 / kept.len() as f64);
                    }
                    f += count;
                }
            }
        }
        out
    }

    /// Windows of real values: noisy sines of random period, amplitude and
    /// offset, channel after channel.
    fn real_windows(count: usize, len: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
        (0..count)
            .map(|_| {
                let period = rng.random_range(3.0..40.0);
                let scale: f64 = 10f64.powi(rng.random_range(-3..4));
                let offset = scale * rng.random_range(-2.0..2.0);
                (0..len)
                    .map(|t| {
                        offset
                            + scale
                                * ((t as f64 / period * std::f64::consts::TAU).sin()
                                    + 0.5 * rng.random_range(-1.0..1.0))
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_block_transform_matches_a_direct_reference_to_the_bit() {
        // Lengths either side of the block (256 points) and of several
        // blocks, unpadded ranges starting and ending inside a block,
        // one to three channels.
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        for (points, channels, asked) in [
            (9, 1, 168),
            (10, 2, 840),
            (33, 3, 840),
            (100, 1, DEFAULT_FEATURES),
            (255, 2, 1680),
            (256, 1, DEFAULT_FEATURES),
            (257, 3, 840),
            (600, 2, 2520),
            (1000, 1, DEFAULT_FEATURES),
            (1300, 2, 840),
        ] {
            let train = real_windows(4, points * channels, &mut rng);
            let refs: Vec<&[f64]> = train.iter().map(Vec::as_slice).collect();
            let t = KernelTransform::fit(&refs, points, channels, asked).unwrap();
            let mut conv = t.convolution();
            let mut out = vec![f64::NAN; t.feature_count()];
            let test = real_windows(3, points * channels, &mut rng);
            // A training window too: its outputs meet some biases exactly
            // (the quantiles that fall on an order statistic).
            for (w, trained) in test.iter().map(|w| (w, false)).chain([(&train[0], true)]) {
                t.transform(w, &mut conv, &mut out);
                let direct = reference_features(&t, w, direct_in_order);
                assert!(
                    out.iter()
                        .zip(&direct)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{points} points, {channels} channel(s)"
                );
                // Summed term by term in double precision (Σ w_j x_j) the
                // outputs differ by single precision's rounding, so a count
                // differs only where an output lies within rounding of a
                // bias: a few features, by a point or two.
                if !trained {
                    let exact = reference_features(&t, w, naive_convolution);
                    let apart: Vec<f64> =
                        out.iter().zip(&exact).map(|(a, b)| (a - b).abs()).collect();
                    let differ = apart.iter().filter(|&&e| e > 0.0).count();
                    assert!(
                        differ * 100 <= out.len()
                            && apart.iter().all(|&e| e * points as f64 <= 2.5),
                        "{points} points, {channels} channel(s), term by term: {differ} differ"
                    );
                }
            }
        }
    }

    #[test]
    fn the_block_transform_matches_one_kernel_at_a_time_on_any_values() {
        // Against the fit's own convolution (every point of one kernel at
        // a time, then counted), on windows with zeros of both signs,
        // infinities, NaN and extremes as well as ordinary values.
        let mut rng = ChaCha8Rng::seed_from_u64(32);
        for (points, channels) in [(40, 1), (300, 2), (700, 1)] {
            let train = real_windows(3, points * channels, &mut rng);
            let refs: Vec<&[f64]> = train.iter().map(Vec::as_slice).collect();
            let t = KernelTransform::fit(&refs, points, channels, 2520).unwrap();
            let mut conv = t.convolution();
            let mut fit_conv = t.convolution();
            let one_at_a_time = |x: &[f64], kernel: [usize; 3], d: usize| {
                let mut c = fit_conv.clone();
                c.load(x);
                c.dilate(d);
                c.convolve(kernel, d)
                    .iter()
                    .map(|&v| f64::from(v))
                    .collect()
            };
            let special = [
                0.0,
                -0.0,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NAN,
                1e300,
                -1e-310,
            ];
            let mut w = real_windows(1, points * channels, &mut rng).remove(0);
            for v in w.iter_mut().step_by(7) {
                *v = special[rng.random_range(0..special.len())];
            }
            let mut out = vec![f64::NAN; t.feature_count()];
            t.transform(&w, &mut conv, &mut out);
            let want = reference_features(&t, &w, one_at_a_time);
            assert!(
                out.iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
            // The portable path (the one without AVX2) gives the same.
            let n = points;
            let per = t.layout.feature_count();
            for (c, biases) in t.biases.iter().enumerate() {
                let mut portable = vec![f64::NAN; per];
                fit_conv.biases = biases.iter().map(|&b| b as f32).collect();
                fit_conv.channel_portable(&t.layout, &w[c * n..(c + 1) * n], &mut portable);
                assert!(
                    portable
                        .iter()
                        .zip(&out[c * per..])
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                );
            }
        }
    }

    /// The fit as first written: per channel, dilation and kernel in turn,
    /// a drawn window's nine shifted rows made afresh, the kernel's whole
    /// output sorted and each bias read from it.
    fn fit_by_sorting(
        windows: &[&[f64]],
        points: usize,
        channels: usize,
        asked: usize,
    ) -> Vec<Vec<f64>> {
        let layout = KernelLayout::new(points, asked).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let mut biases = Vec::new();
        for c in 0..channels {
            let mut own = Vec::new();
            for (&d, &count) in layout.dilations.iter().zip(&layout.features_per_dilation) {
                for kernel in kernels() {
                    let w = windows[rng.random_range(0..windows.len())];
                    let x = &w[c * points..(c + 1) * points];
                    let at = |j: usize, t: usize| {
                        let i = t as isize + (j as isize - 4) * d as isize;
                        (0..points as isize)
                            .contains(&i)
                            .then(|| x[i as usize] as f32)
                    };
                    let mut y: Vec<f64> = (0..points)
                        .map(|t| {
                            let mut base = 0.0f32;
                            for j in 0..KERNEL_LENGTH {
                                if let Some(v) = at(j, t) {
                                    base -= v;
                                }
                            }
                            let row = |j| at(j, t).map_or(0.0, |v| 3.0 * v);
                            f64::from(base + row(kernel[0]) + row(kernel[1]) + row(kernel[2]))
                        })
                        .collect();
                    y.sort_by(f64::total_cmp);
                    for _ in 0..count {
                        let q =
                            super::super::quantiles::quantile_sorted(&y, bias_quantile(own.len()));
                        own.push(f64::from(q as f32));
                    }
                }
            }
            biases.push(own);
        }
        biases
    }

    #[test]
    fn the_fit_selects_the_biases_a_sort_gives_to_the_bit() {
        // Few and many biases per kernel and dilation, one and two
        // channels, windows drawn more than once, zeros of both signs,
        // infinities, NaN and extremes.
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        for (points, channels, asked, count) in [
            (40, 1, 10_000, 3),
            (300, 2, 2520, 5),
            (9, 1, 168, 1),
            (1000, 1, 9996, 2),
        ] {
            let mut train = real_windows(count, points * channels, &mut rng);
            let special = [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e300];
            for (i, v) in special.iter().enumerate() {
                let w = &mut train[i % count];
                let at = (i * 7919) % w.len();
                w[at] = *v;
            }
            let refs: Vec<&[f64]> = train.iter().map(Vec::as_slice).collect();
            let t = KernelTransform::fit(&refs, points, channels, asked).unwrap();
            let want = fit_by_sorting(&refs, points, channels, asked);
            assert_eq!(t.biases.len(), want.len());
            for (got, want) in t.biases.iter().zip(&want) {
                assert_eq!(got.len(), want.len());
                for (f, (a, b)) in got.iter().zip(want).enumerate() {
                    assert!(
                        a.to_bits() == b.to_bits(),
                        "{points} points, feature {f}: {a} {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn biases_are_the_golden_ratio_quantiles_of_a_training_output() {
        // One training window: every bias comes from its padded output.
        let x = integer_windows(1, 40, 9).remove(0);
        let t = KernelTransform::fit(&[&x], 40, 1, 840).unwrap();
        let mut f = 0;
        for (&d, &count) in t
            .layout
            .dilations
            .iter()
            .zip(&t.layout.features_per_dilation)
        {
            for kernel in kernels() {
                let mut y = naive_convolution(&x, kernel, d);
                y.sort_by(f64::total_cmp);
                for _ in 0..count {
                    let q = bias_quantile(f);
                    // Linear interpolation between the order statistics.
                    let pos = q * (y.len() - 1) as f64;
                    let lo = pos.floor() as usize;
                    let hi = (lo + 1).min(y.len() - 1);
                    let want = y[lo] + (pos - lo as f64) * (y[hi] - y[lo]);
                    // Rounded to single precision, as the outputs are.
                    assert!(
                        (t.biases[0][f] - want).abs() <= 1e-7 * want.abs(),
                        "feature {f}"
                    );
                    assert_eq!(t.biases[0][f], f64::from(t.biases[0][f] as f32));
                    f += 1;
                }
            }
        }
        assert_eq!(f, 840);
        assert!((bias_quantile(0) - 0.618_033_988_749_895).abs() < 1e-15);
        assert!((bias_quantile(1) - 0.236_067_977_499_79).abs() < 1e-12);
    }

    #[test]
    fn the_training_windows_decide_the_biases_and_nothing_else_does() {
        let a = integer_windows(4, 50, 11);
        let b = integer_windows(4, 50, 12);
        let fit = |w: &[Vec<f64>]| {
            let refs: Vec<&[f64]> = w.iter().map(Vec::as_slice).collect();
            KernelTransform::fit(&refs, 50, 1, 840).unwrap()
        };
        assert!(fit(&a) == fit(&a));
        assert!(fit(&a).biases != fit(&b).biases);
        // Any one of the training windows may be drawn: with one window
        // each, every bias is that window's.
        let one = fit(&a[..1]);
        assert!(one.biases != fit(&a[1..2]).biases);
    }

    #[test]
    fn bad_training_input_is_refused() {
        let w = vec![0.0; 20];
        assert!(KernelTransform::fit(&[], 20, 1, 840).is_err());
        assert!(KernelTransform::fit(&[&w], 21, 1, 840).is_err());
        let t = KernelTransform::fit(&[&w], 20, 1, 840).unwrap();
        assert!(t.check(20, 1, 840).is_ok());
        assert!(t.check(21, 1, 840).is_err());
        assert!(t.check(20, 2, 840).is_err());
        let mut bad = t.clone();
        bad.biases[0][3] = f64::NAN;
        assert!(bad.check(20, 1, 840).is_err());
    }
}
