//! Detrending, tapers and the spectrum of a resampled window (magnitude,
//! power, log-power, Welch). Owns the FFT plan and its buffers (made once);
//! never allocates per call.

use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use crate::profile::{Detrend, LOG_FLOOR, SpectrumKind, Taper};

/// Remove the window's trend in place: nothing, its mean, or its
/// least-squares straight line (against the sample index, which is the
/// grid position up to scale).
pub fn detrend(kind: Detrend, x: &mut [f64]) {
    let n = x.len();
    if n == 0 {
        return;
    }
    match kind {
        Detrend::None => {}
        Detrend::Mean => {
            let mean = x.iter().sum::<f64>() / n as f64;
            x.iter_mut().for_each(|v| *v -= mean);
        }
        Detrend::Linear => {
            // With t centred on the window, the intercept is the mean and the
            // slope is Σ t·x / Σ t².
            let mean = x.iter().sum::<f64>() / n as f64;
            let centre = (n as f64 - 1.0) / 2.0;
            let (mut stx, mut stt) = (0.0, 0.0);
            for (j, &v) in x.iter().enumerate() {
                let t = j as f64 - centre;
                stx += t * v;
                stt += t * t;
            }
            let slope = if stt > 0.0 { stx / stt } else { 0.0 };
            for (j, v) in x.iter_mut().enumerate() {
                *v -= mean + slope * (j as f64 - centre);
            }
        }
    }
}

/// `|X_k|`, `k = 0..=n/2`, of a real window of `n` points, unnormalised
/// (Matlab's `fft`: `X_k = Σ_j x_j e^{−2πi jk/n}`).
#[derive(Clone)]
pub(crate) struct MagnitudeSpectrum {
    fft: Arc<dyn Fft<f64>>,
    buffer: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl MagnitudeSpectrum {
    pub(crate) fn new(n: usize) -> Self {
        let fft = FftPlanner::new().plan_fft_forward(n);
        let scratch = vec![Complex::default(); fft.get_inplace_scratch_len()];
        MagnitudeSpectrum {
            fft,
            buffer: vec![Complex::default(); n],
            scratch,
        }
    }

    /// `x` has `n` values, `out` has `n/2 + 1`.
    pub(crate) fn compute(&mut self, x: &[f64], out: &mut [f64]) {
        self.transform(x, out.len());
        for (o, b) in out.iter_mut().zip(&self.buffer) {
            *o = b.norm();
        }
    }

    /// `|X_k|²`, as [`Self::compute`] squared but without the square root
    /// (`hypot`) that a power spectrum would undo.
    pub(crate) fn compute_squared(&mut self, x: &[f64], out: &mut [f64]) {
        self.transform(x, out.len());
        for (o, b) in out.iter_mut().zip(&self.buffer) {
            *o = b.norm_sqr();
        }
    }

    fn transform(&mut self, x: &[f64], out_len: usize) {
        debug_assert_eq!(x.len(), self.buffer.len());
        debug_assert_eq!(out_len, self.buffer.len() / 2 + 1);
        for (b, &v) in self.buffer.iter_mut().zip(x) {
            *b = Complex::new(v, 0.0);
        }
        self.fft
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
    }
}

/// The taper's weights for `m` points (periodic Hann: `0.5 − 0.5 cos(2π j / m)`).
pub fn taper_weights(taper: Taper, m: usize) -> Vec<f64> {
    match taper {
        Taper::None => vec![1.0; m],
        Taper::Hann => (0..m)
            .map(|j| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * j as f64 / m as f64).cos())
            .collect(),
    }
}

/// `c_k / Σ w_j²` of bin `k` of an `m`-point DFT (`c_k` = 2 for bins with a
/// mirror image).
fn power_scale(m: usize, weight_energy: f64, k: usize) -> f64 {
    let mirrored = k > 0 && !(m.is_multiple_of(2) && k == m / 2);
    (if mirrored { 2.0 } else { 1.0 }) / weight_energy
}

/// A window's one-sided spectrum (`m/2 + 1` values, `m` the DFT length) of
/// the kind the settings name:
/// - magnitude: `|X_k|` of the tapered window (unnormalised, the thesis's);
/// - power: `c_k |X_k|² / Σ w_j²` with `c_k = 2` for the bins that have a
///   mirror image (not DC, not Nyquist), else 1; without a taper the bins
///   add up to the window's energy `Σ x_j²` (Parseval);
/// - log-power: `log10(max(power, LOG_FLOOR))`;
/// - Welch: the power of each segment of `m` points (segment mean removed
///   unless the detrend is `none`, then tapered), averaged over the segments
///   that fit with the overlap; white noise of variance σ² gives 2σ² per bin;
/// - log-Welch: `log10(max(welch, LOG_FLOOR))`.
#[derive(Clone)]
pub(crate) struct Spectrum {
    kind: SpectrumKind,
    detrend_segments: bool,
    m: usize,
    step: usize,
    weights: Vec<f64>,
    weight_energy: f64,
    /// [`power_scale`] of every bin, made once.
    scales: Vec<f64>,
    magnitude: MagnitudeSpectrum,
    segment: Vec<f64>,
    one: Vec<f64>,
}

impl Spectrum {
    /// `m` the DFT length, `overlap` used by Welch only.
    pub(crate) fn new(
        kind: SpectrumKind,
        taper: Taper,
        detrend: Detrend,
        m: usize,
        overlap: f64,
    ) -> Self {
        let weights = taper_weights(taper, m);
        let weight_energy = weights
            .iter()
            .map(|w| w * w)
            .sum::<f64>()
            .max(f64::MIN_POSITIVE);
        let step = ((m as f64 * (1.0 - overlap)).round() as usize).max(1);
        Spectrum {
            kind,
            detrend_segments: detrend != Detrend::None,
            m,
            step,
            weights,
            weight_energy,
            scales: (0..m / 2 + 1)
                .map(|k| power_scale(m, weight_energy, k))
                .collect(),
            magnitude: MagnitudeSpectrum::new(m),
            segment: vec![0.0; m],
            one: vec![0.0; m / 2 + 1],
        }
    }

    /// Values in the output: `m/2 + 1`.
    pub(crate) fn len(&self) -> usize {
        self.m / 2 + 1
    }

    /// Welch segments that fit in `n` points (1 for the other kinds).
    pub(crate) fn segments(&self, n: usize) -> usize {
        match self.kind {
            SpectrumKind::Welch | SpectrumKind::LogWelch if n >= self.m => {
                1 + (n - self.m) / self.step
            }
            SpectrumKind::Welch | SpectrumKind::LogWelch => 0,
            _ => 1,
        }
    }

    fn power_scale(&self, k: usize) -> f64 {
        power_scale(self.m, self.weight_energy, k)
    }

    /// `x` is the (detrended) window, `out` has [`Self::len`] values.
    pub(crate) fn compute(&mut self, x: &[f64], out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.len());
        match self.kind {
            SpectrumKind::Welch | SpectrumKind::LogWelch => {
                out.fill(0.0);
                let count = self.segments(x.len());
                for s in 0..count {
                    let seg = &x[s * self.step..s * self.step + self.m];
                    let mean = if self.detrend_segments {
                        seg.iter().sum::<f64>() / self.m as f64
                    } else {
                        0.0
                    };
                    for ((o, &v), w) in self.segment.iter_mut().zip(seg).zip(&self.weights) {
                        *o = (v - mean) * w;
                    }
                    self.magnitude.compute_squared(&self.segment, &mut self.one);
                    for ((o, a2), scale) in out.iter_mut().zip(&self.one).zip(&self.scales) {
                        *o += a2 * scale;
                    }
                }
                let inv = 1.0 / count.max(1) as f64;
                out.iter_mut().for_each(|o| *o *= inv);
                if self.kind == SpectrumKind::LogWelch {
                    out.iter_mut().for_each(|o| *o = o.max(LOG_FLOOR).log10());
                }
            }
            kind => {
                for ((o, &v), w) in self.segment.iter_mut().zip(x).zip(&self.weights) {
                    *o = v * w;
                }
                if kind == SpectrumKind::Magnitude {
                    self.magnitude.compute(&self.segment, out);
                } else {
                    self.magnitude.compute_squared(&self.segment, out);
                    for (k, o) in out.iter_mut().enumerate() {
                        *o *= self.power_scale(k);
                        if kind == SpectrumKind::LogPower {
                            *o = o.max(LOG_FLOOR).log10();
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_detrend_removes_the_mean_only() {
        let mut x = vec![1.0, 2.0, 3.0, 10.0];
        detrend(Detrend::Mean, &mut x);
        assert_eq!(x, vec![-3.0, -2.0, -1.0, 6.0]);
    }

    #[test]
    fn linear_detrend_removes_a_line_and_keeps_the_rest() {
        // A line plus a zig-zag that is orthogonal to both the constant and
        // the ramp (symmetric about the centre, zero sum): only the line goes.
        let zig = [1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0];
        let mut x: Vec<f64> = zig
            .iter()
            .enumerate()
            .map(|(j, z)| 3.0 - 0.5 * j as f64 + z)
            .collect();
        detrend(Detrend::Linear, &mut x);
        for (a, b) in x.iter().zip(zig) {
            assert!((a - b).abs() < 1e-12, "{x:?}");
        }
        let mut line: Vec<f64> = (0..7).map(|j| 2.0 * j as f64 - 4.0).collect();
        detrend(Detrend::Linear, &mut line);
        assert!(line.iter().all(|v| v.abs() < 1e-12), "{line:?}");
    }

    #[test]
    fn no_detrend_and_degenerate_windows() {
        let mut x = vec![5.0, 6.0];
        detrend(Detrend::None, &mut x);
        assert_eq!(x, vec![5.0, 6.0]);
        let mut one = vec![4.0];
        detrend(Detrend::Linear, &mut one);
        assert_eq!(one, vec![0.0]);
        detrend(Detrend::Linear, &mut []);
    }

    #[test]
    fn magnitudes_match_a_naive_dft() {
        for n in [4, 5, 100, 101] {
            let x: Vec<f64> = (0..n).map(|j| ((j * 7919) % 13) as f64 - 6.0).collect();
            let mut s = MagnitudeSpectrum::new(n);
            let mut out = vec![0.0; n / 2 + 1];
            s.compute(&x, &mut out);
            for (k, &got) in out.iter().enumerate() {
                let (mut re, mut im) = (0.0, 0.0);
                for (j, &v) in x.iter().enumerate() {
                    let a = -2.0 * std::f64::consts::PI * (j * k) as f64 / n as f64;
                    re += v * a.cos();
                    im += v * a.sin();
                }
                assert!((got - re.hypot(im)).abs() < 1e-9, "n {n} k {k}");
            }
        }
    }
}
