//! Band energies and cepstra from a one-sided power spectrum: the power
//! summed over each of `bands`' bins, its log10 for a log spectrum, and the
//! orthonormal DCT-II of the log energies for `cepstra`. Owns its tables
//! (made once); never allocates per call.

use crate::profile::{Analysis, LOG_FLOOR};

#[derive(Clone, Debug)]
pub(crate) struct BandFeatures {
    /// Each band's bins, `[first, end)`.
    bins: Vec<[usize; 2]>,
    /// log10 of the energies (a log spectrum, or cepstra).
    log: bool,
    /// `cepstra × count` DCT-II weights `s_j cos(π j (i + 0.5) / N)`; empty without cepstra.
    dct: Vec<f64>,
    energies: Vec<f64>,
}

impl BandFeatures {
    /// `None` when the settings have no `bands`.
    pub(crate) fn new(settings: &Analysis) -> Option<Self> {
        let b = settings.bands?;
        let n = b.count;
        let m = settings.cepstra.unwrap_or(0);
        let mut dct = Vec::with_capacity(m * n);
        // c_0 (the level) left out with `drop_level`.
        for j in usize::from(settings.drop_level)..m {
            let s = if j == 0 {
                (1.0 / n as f64).sqrt()
            } else {
                (2.0 / n as f64).sqrt()
            };
            for i in 0..n {
                let a = std::f64::consts::PI * j as f64 * (i as f64 + 0.5) / n as f64;
                dct.push(s * a.cos());
            }
        }
        Some(BandFeatures {
            bins: settings.band_bins(),
            log: settings.spectrum.is_log() || m > 0,
            dct,
            energies: vec![0.0; n],
        })
    }

    /// Features out of one linear power spectrum: `count` energies, or
    /// `cepstra` coefficients.
    pub(crate) fn len(&self) -> usize {
        if self.dct.is_empty() {
            self.bins.len()
        } else {
            self.dct.len() / self.bins.len()
        }
    }

    /// `power` is the linear one-sided spectrum (bins `0..=m/2`); `out` has
    /// [`Self::len`] values.
    pub(crate) fn compute(&mut self, power: &[f64], out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.len());
        for (e, &[a, b]) in self.energies.iter_mut().zip(&self.bins) {
            let sum: f64 = power[a.min(power.len())..b.min(power.len())].iter().sum();
            *e = if self.log {
                sum.max(LOG_FLOOR).log10()
            } else {
                sum
            };
        }
        if self.dct.is_empty() {
            out.copy_from_slice(&self.energies);
        } else {
            let n = self.energies.len();
            for (o, row) in out.iter_mut().zip(self.dct.chunks_exact(n)) {
                *o = row.iter().zip(&self.energies).map(|(w, l)| w * l).sum();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::FeatureExtractor;
    use crate::profile::{BandScale, Bands, Detrend, SpectrumKind, Taper};
    use std::f64::consts::PI;

    const RATE: f64 = 8000.0;

    /// A time-axis analysis of `n` points at 8 kHz.
    fn timed(n: usize, kind: SpectrumKind) -> Analysis {
        Analysis {
            channel: "v".into(),
            axis: "t_s".into(),
            window: [0.0, (n - 1) as f64 / RATE],
            spacing: 1.0 / RATE,
            detrend: Detrend::Mean,
            spectrum: kind,
            bins: [0, 0],
            ..Analysis::default()
        }
    }

    /// A signal with a tone, a second tone and pseudo-random broadband noise,
    /// sampled exactly on the grid (2 samples past the window's end).
    fn texture(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let t: Vec<f64> = (0..n + 2).map(|j| j as f64 / RATE).collect();
        let v = t
            .iter()
            .map(|&t| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let noise = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                0.8 * (2.0 * PI * 440.0 * t).sin()
                    + 0.3 * (2.0 * PI * 1730.0 * t).cos()
                    + 0.2 * noise
                    + 0.1
            })
            .collect();
        (t, v)
    }

    /// The one-sided power of `x` (mean removed, tapered by `w`) by a naive DFT.
    fn naive_power(x: &[f64], w: &[f64]) -> Vec<f64> {
        let m = x.len();
        let mean = x.iter().sum::<f64>() / m as f64;
        let energy: f64 = w.iter().map(|w| w * w).sum();
        (0..=m / 2)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (j, (&v, &w)) in x.iter().zip(w).enumerate() {
                    let a = -2.0 * PI * (j * k) as f64 / m as f64;
                    re += (v - mean) * w * a.cos();
                    im += (v - mean) * w * a.sin();
                }
                let c = if k == 0 || (m.is_multiple_of(2) && k == m / 2) {
                    1.0
                } else {
                    2.0
                };
                c * (re * re + im * im) / energy
            })
            .collect()
    }

    /// Welch by the definition: average of the naive powers of the segments.
    fn naive_welch(x: &[f64], m: usize, step: usize, taper: Taper) -> Vec<f64> {
        let w = crate::analysis::taper_weights(taper, m);
        let mut sum = vec![0.0; m / 2 + 1];
        let mut count = 0;
        let mut s = 0;
        while s + m <= x.len() {
            for (a, p) in sum.iter_mut().zip(naive_power(&x[s..s + m], &w)) {
                *a += p;
            }
            count += 1;
            s += step;
        }
        sum.iter().map(|a| a / count as f64).collect()
    }

    /// Band energies by the spec's words: bins with e_i <= f_k < e_{i+1}
    /// (the last band also f_k == e_N), edges by the formula.
    fn naive_bands(power: &[f64], width: f64, b: Bands) -> Vec<f64> {
        let n = b.count;
        let edge = |i: usize| match b.scale {
            BandScale::Log => b.from * (b.to / b.from).powf(i as f64 / n as f64),
            BandScale::Linear => b.from + (b.to - b.from) * i as f64 / n as f64,
        };
        (0..n)
            .map(|i| {
                let (lo, hi) = (edge(i), if i + 1 == n { b.to } else { edge(i + 1) });
                power
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| {
                        let f = k as f64 * width;
                        f >= lo && (f < hi || (i + 1 == n && f == hi))
                    })
                    .map(|(_, p)| p)
                    .sum()
            })
            .collect()
    }

    fn naive_dct(l: &[f64], m: usize) -> Vec<f64> {
        let n = l.len() as f64;
        (0..m)
            .map(|j| {
                let s = if j == 0 {
                    (1.0 / n).sqrt()
                } else {
                    (2.0 / n).sqrt()
                };
                s * l
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v * (PI * j as f64 * (i as f64 + 0.5) / n).cos())
                    .sum::<f64>()
            })
            .collect()
    }

    fn close(got: &[f64], want: &[f64], what: &str) {
        assert_eq!(got.len(), want.len(), "{what}");
        for (k, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g - w).abs() <= 1e-9 * w.abs().max(1.0),
                "{what}[{k}]: got {g}, want {w}"
            );
        }
    }

    #[test]
    fn log_welch_is_the_log_of_a_naive_welch() {
        let n = 1000;
        let mut s = timed(n, SpectrumKind::LogWelch);
        s.taper = Taper::Hann;
        s.welch_segment = Some(256);
        s.bins = [0, 128];
        let (t, v) = texture(n);
        let want: Vec<f64> = naive_welch(&v[..n], 256, 128, Taper::Hann)
            .iter()
            .map(|p| p.max(LOG_FLOOR).log10())
            .collect();
        let mut fx = FeatureExtractor::new(&s);
        close(fx.features(&t, &v).unwrap(), &want, "log-welch");
        // Silence gives the floor's log, not -inf.
        let zeros = vec![0.0; v.len()];
        assert!(
            fx.features(&t, &zeros)
                .unwrap()
                .iter()
                .all(|&x| x == -300.0)
        );
    }

    #[test]
    fn band_energies_match_naive_sums_of_the_power() {
        let n = 800;
        let (t, v) = texture(n);
        for (kind, scale) in [
            (SpectrumKind::Power, BandScale::Log),
            (SpectrumKind::Power, BandScale::Linear),
            (SpectrumKind::LogPower, BandScale::Log),
            (SpectrumKind::Welch, BandScale::Linear),
            (SpectrumKind::LogWelch, BandScale::Log),
        ] {
            let mut s = timed(n, kind);
            let bands = Bands {
                count: 12,
                from: 60.0,
                to: 3900.0,
                scale,
            };
            s.bands = Some(bands);
            if kind.is_welch() {
                s.welch_segment = Some(200);
            }
            crate::profile::check_options(&s).unwrap();
            let power = if kind.is_welch() {
                naive_welch(&v[..n], 200, 100, Taper::None)
            } else {
                naive_power(&v[..n], &vec![1.0; n])
            };
            let mut want = naive_bands(&power, s.bin_width(), bands);
            if kind.is_log() {
                want.iter_mut().for_each(|e| *e = e.max(LOG_FLOOR).log10());
            }
            assert!(
                want.iter().all(|&e| e != 0.0 && e.is_finite()),
                "{kind:?} {want:?}"
            );
            let mut fx = FeatureExtractor::new(&s);
            close(
                fx.features(&t, &v).unwrap(),
                &want,
                &format!("{kind:?} {scale:?}"),
            );
        }
    }

    #[test]
    fn the_last_band_takes_the_bin_on_its_top_edge() {
        // 100 points at 8 kHz: bins 80 Hz apart; a band edge on a bin goes up.
        let mut s = timed(100, SpectrumKind::Power);
        s.bands = Some(Bands {
            count: 2,
            from: 800.0,
            to: 1600.0,
            scale: BandScale::Linear,
        });
        assert_eq!(s.band_bins(), vec![[10, 15], [15, 21]]);
        assert_eq!(s.kept_bins(), [10, 20]);
        assert_eq!(s.feature_count(), 2);
    }

    #[test]
    fn cepstra_are_the_orthonormal_dct_of_the_log_band_energies() {
        let n = 1200;
        let (t, v) = texture(n);
        for kind in [
            SpectrumKind::Welch,
            SpectrumKind::LogWelch,
            SpectrumKind::Power,
        ] {
            let mut s = timed(n, kind);
            let bands = Bands {
                count: 16,
                from: 50.0,
                to: 4000.0,
                scale: BandScale::Log,
            };
            s.bands = Some(bands);
            s.cepstra = Some(9);
            if kind.is_welch() {
                s.welch_segment = Some(400);
            }
            crate::profile::check_options(&s).unwrap();
            let power = if kind.is_welch() {
                naive_welch(&v[..n], 400, 200, Taper::None)
            } else {
                naive_power(&v[..n], &vec![1.0; n])
            };
            let logs: Vec<f64> = naive_bands(&power, s.bin_width(), bands)
                .iter()
                .map(|e| e.max(LOG_FLOOR).log10())
                .collect();
            let want = naive_dct(&logs, 9);
            let mut fx = FeatureExtractor::new(&s);
            close(
                fx.features(&t, &v).unwrap(),
                &want,
                &format!("cepstra {kind:?}"),
            );
            // drop_level leaves out c_0 and keeps c_1..c_8.
            s.drop_level = true;
            let mut fx = FeatureExtractor::new(&s);
            close(
                fx.features(&t, &v).unwrap(),
                &want[1..],
                &format!("cepstra without c_0 {kind:?}"),
            );
            s.drop_level = false;
            // All 16 coefficients keep all the information: the DCT inverts.
            s.cepstra = Some(16);
            let mut fx = FeatureExtractor::new(&s);
            let c = fx.features(&t, &v).unwrap().to_vec();
            let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
            assert!(
                (norm(&c) - norm(&logs)).abs() < 1e-9 * norm(&logs),
                "orthonormal"
            );
        }
    }

    #[test]
    fn without_c0_the_cepstra_do_not_see_a_gain() {
        let n = 1200;
        let (t, v) = texture(n);
        let mut s = timed(n, SpectrumKind::LogWelch);
        s.welch_segment = Some(400);
        s.bands = Some(Bands {
            count: 16,
            from: 50.0,
            to: 4000.0,
            scale: BandScale::Log,
        });
        s.cepstra = Some(9);
        s.drop_level = true;
        crate::profile::check_options(&s).unwrap();
        let mut fx = FeatureExtractor::new(&s);
        let quiet = fx.features(&t, &v).unwrap().to_vec();
        let louder: Vec<f64> = v.iter().map(|x| 3.0 * x).collect();
        let loud = fx.features(&t, &louder).unwrap().to_vec();
        assert_eq!(quiet.len(), 8);
        close(&loud, &quiet, "a gain of 3");
        // With c_0 kept, the gain shows: c_0 moves by sqrt(N) log10(9).
        s.drop_level = false;
        let mut fx = FeatureExtractor::new(&s);
        let mut c0 = |x: &[f64]| fx.features(&t, x).unwrap()[0];
        let shift = c0(&louder) - c0(&v);
        assert!((shift - 4.0 * 9f64.log10()).abs() < 1e-9, "{shift}");
    }

    #[test]
    fn several_channels_concatenate_their_cepstra() {
        let n = 600;
        let (t, v) = texture(n);
        let w: Vec<f64> = v.iter().map(|x| x * 0.5 + 0.01).collect();
        let mut s = timed(n, SpectrumKind::LogPower);
        s.bands = Some(Bands {
            count: 8,
            from: 100.0,
            to: 3000.0,
            scale: BandScale::Log,
        });
        s.cepstra = Some(4);
        let mut fx = FeatureExtractor::new(&s);
        let a = fx.features(&t, &v).unwrap().to_vec();
        let b = fx.features(&t, &w).unwrap().to_vec();
        s.channels = vec!["w".into()];
        let mut fx = FeatureExtractor::new(&s);
        let both = fx.features_of_channels(&t, &[&v, &w]).unwrap();
        assert_eq!(both, [a, b].concat().as_slice());
    }
}
