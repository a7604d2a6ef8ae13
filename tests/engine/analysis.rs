//! Feature extraction against first principles: sines peak at their bin,
//! Parseval holds, straight lines resample exactly, and the features equal a
//! naive O(n²) DFT of the resampled, detrended window.

use std::f64::consts::PI;

use hapticlab::analysis::{AnalysisError, FeatureExtractor};
use hapticlab::profile::{Analysis, Detrend, SpectrumKind};
use proptest::prelude::*;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn thesis(detrend: Detrend) -> Analysis {
    Analysis {
        channel: "y_m".into(),
        axis: "x_m".into(),
        window: [0.060, 0.0897],
        spacing: 0.0003,
        detrend,
        spectrum: SpectrumKind::Magnitude,
        bins: [1, 49],
        ..Analysis::default()
    }
}

/// `samples` positions from `start` to `start + len`, evenly spaced.
fn ramp(start: f64, len: f64, samples: usize) -> Vec<f64> {
    (0..samples)
        .map(|j| start + len * j as f64 / (samples - 1) as f64)
        .collect()
}

/// The thesis's 8.97 cm stroke from x = −45 mm, 9000 samples.
fn stroke() -> Vec<f64> {
    ramp(-0.045, 0.0897, 9000)
}

fn naive_dft(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, &v) in x.iter().enumerate() {
                let a = -2.0 * PI * ((j * k) % n) as f64 / n as f64;
                re += v * a.cos();
                im += v * a.sin();
            }
            re.hypot(im)
        })
        .collect()
}

/// Σ|X_k|² over the full DFT, from the one-sided half (real input: X_{n−k} = conj X_k).
fn full_energy(one_sided: &[f64], n: usize) -> f64 {
    one_sided
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let twice = k != 0 && !(n.is_multiple_of(2) && k == n / 2);
            m * m * if twice { 2.0 } else { 1.0 }
        })
        .sum()
}

fn argmax(x: &[f64]) -> usize {
    x.iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)
        .unwrap()
}

/// A trapezoid-like corrugation of `period` (metres) along x, plus noise.
fn corrugation(x: &[f64], period: f64, noise: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    x.iter()
        .map(|&x| {
            let phase = (x / period).rem_euclid(1.0);
            let shape = (4.0 * (phase - 0.5).abs() - 1.0).clamp(-0.6, 0.6) / 0.6;
            -0.0048 + 0.0009 * shape + noise * rng.random_range(-1.0..1.0)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn a_sine_of_k_cycles_peaks_at_bin_k(
        k in 1usize..=49,
        phase in 0.0..(2.0 * PI),
        amplitude in 1e-6f64..10.0,
        offset in -1.0f64..1.0,
    ) {
        let settings = thesis(Detrend::Mean);
        let n = settings.points();
        let length = n as f64 * settings.spacing; // the DFT's period
        let x = stroke();
        let y: Vec<f64> = x
            .iter()
            .map(|&xv| {
                // Distance from the stroke's start, less the window's start.
                let d = xv + 0.045 - settings.window[0];
                offset + amplitude * (2.0 * PI * k as f64 * d / length + phase).sin()
            })
            .collect();
        let mut fx = FeatureExtractor::new(&settings);
        let features = fx.features(&x, &y).unwrap().to_vec();
        prop_assert_eq!(argmax(&features) + settings.bins[0], k);
        prop_assert_eq!(argmax(&fx.spectrum()[1..]) + 1, k);
    }

    #[test]
    fn parseval_holds_for_the_resampled_window(
        seed in any::<u64>(),
        spacing in prop::sample::select(vec![0.0003, 0.00029, 0.00031, 0.0005]),
        detrend in prop::sample::select(vec![Detrend::None, Detrend::Mean, Detrend::Linear]),
    ) {
        let mut settings = thesis(detrend);
        settings.spacing = spacing;
        settings.bins = [1, 20];
        let x = stroke();
        let y = corrugation(&x, 0.0042, 0.0002, seed);
        let mut fx = FeatureExtractor::new(&settings);
        fx.features(&x, &y).unwrap();
        let n = fx.points();
        let time: f64 = fx.detrended().iter().map(|v| v * v).sum();
        let freq = full_energy(fx.spectrum(), n) / n as f64;
        prop_assert!((time - freq).abs() <= 1e-9 * time.max(1e-30), "n {} time {} freq {}", n, time, freq);
    }

    #[test]
    fn a_straight_line_resamples_exactly(
        slope in -100.0f64..100.0,
        intercept in -100.0f64..100.0,
        start in -0.05f64..0.05,
        backwards in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let direction = if backwards { -1.0 } else { 1.0 };
        // Uneven steps averaging 0.02 mm, to just past the window's end.
        let mut x = vec![start];
        let mut d = 0.0;
        while d < 0.0899 {
            d += 0.00002 * rng.random_range(0.1..1.9);
            x.push(start + direction * d);
        }
        // Time order does not matter: shuffle all but the first and last samples.
        let last = x.len() - 1;
        x[1..last].shuffle(&mut rng);
        let y: Vec<f64> = x.iter().map(|x| intercept + slope * x).collect();
        let settings = thesis(Detrend::None);
        let mut fx = FeatureExtractor::new(&settings);
        let r = fx.resample(&x, &y).unwrap().to_vec();
        for (i, v) in r.iter().enumerate() {
            let xi = start + direction * fx.grid_position(i);
            let want = intercept + slope * xi;
            prop_assert!((v - want).abs() < 1e-9, "i {} got {} want {}", i, v, want);
        }
    }
}

#[test]
fn features_equal_a_naive_dft_of_the_window() {
    for detrend in [Detrend::None, Detrend::Mean, Detrend::Linear] {
        let settings = thesis(detrend);
        let x = stroke();
        let y = corrugation(&x, 0.0075, 0.00005, 7);
        let mut fx = FeatureExtractor::new(&settings);
        let features = fx.features(&x, &y).unwrap().to_vec();
        // Detrend independently of the library.
        let mut w = fx.resampled().to_vec();
        let n = w.len() as f64;
        match detrend {
            Detrend::None => {}
            Detrend::Mean => {
                let m = w.iter().sum::<f64>() / n;
                w.iter_mut().for_each(|v| *v -= m);
            }
            Detrend::Linear => {
                let t: Vec<f64> = (0..w.len()).map(|j| j as f64).collect();
                let (mt, mw) = (t.iter().sum::<f64>() / n, w.iter().sum::<f64>() / n);
                let sxy: f64 = t.iter().zip(&w).map(|(t, w)| (t - mt) * (w - mw)).sum();
                let sxx: f64 = t.iter().map(|t| (t - mt).powi(2)).sum();
                let b = sxy / sxx;
                for (v, t) in w.iter_mut().zip(&t) {
                    *v -= mw + b * (t - mt);
                }
            }
        }
        let dft = naive_dft(&w);
        assert_eq!(features.len(), 49);
        for (k, f) in (1..=49).zip(&features) {
            assert!(
                (f - dft[k]).abs() < 1e-12,
                "{detrend:?} bin {k}: {f} vs {}",
                dft[k]
            );
        }
        for (k, s) in fx.spectrum().iter().enumerate() {
            assert!((s - dft[k]).abs() < 1e-12);
        }
    }
}

#[test]
fn the_dominant_bin_follows_the_period() {
    // Section 4.4's bins: 4.24 mm → bin 7, 7.5 mm → bin 4 in a 30 mm window.
    let x = stroke();
    let mut fx = FeatureExtractor::new(&thesis(Detrend::Mean));
    for (period, bin) in [(0.00424, 7), (0.0075, 4)] {
        let y = corrugation(&x, period, 0.00001, 1);
        let f = fx.features(&x, &y).unwrap();
        assert_eq!(argmax(f) + 1, bin, "period {period}");
    }
}

#[test]
fn back_and_forth_motion_resamples_by_position() {
    let settings = thesis(Detrend::Mean);
    let surface = |x: f64| 0.001 * (2.0 * PI * x / 0.0042).sin() + 0.01 * x;
    // Forward to 70 mm, back to 66 mm, forward to the end, in 0.01 mm steps.
    let mut x = Vec::new();
    let step = 0.00001;
    let mut p = 0.0;
    while p < 0.070 {
        x.push(p);
        p += step;
    }
    while p > 0.066 {
        x.push(p);
        p -= step;
    }
    while p < 0.0899 {
        x.push(p);
        p += step;
    }
    let y: Vec<f64> = x.iter().map(|&x| surface(x)).collect();
    let mut fx = FeatureExtractor::new(&settings);
    let r = fx.resample(&x, &y).unwrap().to_vec();
    for (i, v) in r.iter().enumerate() {
        let want = surface(fx.grid_position(i));
        // Bin averaging of a sine over ±0.15 mm shrinks it by under 4 %.
        assert!((v - want).abs() < 5e-5, "i {i}: {v} vs {want}");
    }
    // The same features as a scan that went straight through.
    let straight: Vec<f64> = (0..9000).map(|j| j as f64 * step).collect();
    let ys: Vec<f64> = straight.iter().map(|&x| surface(x)).collect();
    let f_back = fx.features(&x, &y).unwrap().to_vec();
    let f_straight = fx.features(&straight, &ys).unwrap().to_vec();
    let scale = f_straight.iter().cloned().fold(0.0, f64::max);
    for (a, b) in f_back.iter().zip(&f_straight) {
        assert!((a - b).abs() < 1e-3 * scale, "{a} vs {b}");
    }
}

#[test]
fn a_scan_in_minus_x_is_measured_along_its_travel() {
    let settings = thesis(Detrend::Mean);
    let forward = ramp(-0.045, 0.0897, 9000);
    let backward: Vec<f64> = forward.iter().map(|x| -x).collect();
    let y = corrugation(&forward, 0.0042, 0.0, 3);
    let mut fx = FeatureExtractor::new(&settings);
    let a = fx.features(&forward, &y).unwrap().to_vec();
    let b = fx.features(&backward, &y).unwrap().to_vec();
    for (a, b) in a.iter().zip(&b) {
        assert!((a - b).abs() < 1e-12);
    }
}

#[test]
fn a_short_scan_does_not_cover_the_window() {
    let mut fx = FeatureExtractor::new(&thesis(Detrend::Mean));
    // Out to 80 mm and back: the window's last 10 mm are never reached.
    let mut x = ramp(0.0, 0.08, 8000);
    x.extend(ramp(0.08, -0.08, 8000));
    let y = vec![0.0; x.len()];
    match fx.features(&x, &y) {
        Err(AnalysisError::WindowNotCovered {
            covered, window, ..
        }) => {
            assert_eq!(covered, (0.0, 0.08));
            assert!((window[0] - 0.06).abs() < 1e-12);
            assert!((window[1] - 0.0897).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // A jump over the window's start leaves no sample to anchor it.
    let mut x = vec![0.0];
    x.extend(ramp(0.065, 0.025, 3000));
    let y = vec![0.0; x.len()];
    assert!(matches!(
        fx.features(&x, &y),
        Err(AnalysisError::EdgeGap { edge: "start", .. })
    ));
}
