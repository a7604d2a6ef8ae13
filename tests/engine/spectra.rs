//! Every spectrum kind on synthetic signals of known spectra; bands in Hz
//! and cycles/mm; several channels concatenated.

use std::f64::consts::PI;

use hapticlab::analysis::FeatureExtractor;
use hapticlab::profile::{Analysis, Detrend, SpectrumKind, Taper};

/// A time-axis analysis of `n` points at 1 kHz, all bins kept.
fn timed(n: usize, kind: SpectrumKind) -> Analysis {
    Analysis {
        channel: "v".into(),
        axis: "t_s".into(),
        window: [0.0, (n - 1) as f64 / 1000.0],
        spacing: 0.001,
        detrend: Detrend::None,
        spectrum: kind,
        bins: [0, n / 2],
        ..Analysis::default()
    }
}

/// Samples exactly on the grid (so resampling changes nothing), and 2 past
/// the window's end.
fn signal(n: usize, mut f: impl FnMut(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..n + 2).map(|j| j as f64 / 1000.0).collect();
    let v = t.iter().map(|&t| f(t)).collect();
    (t, v)
}

fn argmax(x: &[f64]) -> usize {
    (0..x.len()).max_by(|&a, &b| x[a].total_cmp(&x[b])).unwrap()
}

#[test]
fn magnitude_of_a_sine_on_a_bin_is_amplitude_times_half_n() {
    let n = 128;
    let mut fx = FeatureExtractor::new(&timed(n, SpectrumKind::Magnitude));
    // Bin 10 lies at 10 / (128 ms) = 78.125 Hz.
    let (t, v) = signal(n, |t| 0.3 * (2.0 * PI * 78.125 * t).sin());
    let f = fx.features(&t, &v).unwrap().to_vec();
    assert_eq!(argmax(&f), 10);
    assert!((f[10] - 0.3 * 64.0).abs() < 1e-9, "{}", f[10]);
    assert!(f[3] < 1e-9 && f[30] < 1e-9);
    assert!((fx.frequency(10) - 78.125).abs() < 1e-12);
}

#[test]
fn power_obeys_parseval_and_log_power_is_its_log() {
    let n = 100;
    let x = |t: f64| 0.5 * (2.0 * PI * 50.0 * t).sin() + 0.2 * (2.0 * PI * 130.0 * t).cos() + 0.1;
    let (t, v) = signal(n, x);
    let mut fx = FeatureExtractor::new(&timed(n, SpectrumKind::Power));
    let p = fx.features(&t, &v).unwrap().to_vec();
    let energy: f64 = v[..n].iter().map(|v| v * v).sum();
    let total: f64 = p.iter().sum();
    assert!(
        (total - energy).abs() < 1e-9 * energy,
        "{total} vs {energy}"
    );
    // 50 Hz is bin 5 of a 100 ms window: power A² n / 2.
    assert!((p[5] - 0.25 * 50.0).abs() < 1e-9, "{}", p[5]);
    assert!((p[13] - 0.04 * 50.0).abs() < 1e-9, "{}", p[13]);
    let mut lx = FeatureExtractor::new(&timed(n, SpectrumKind::LogPower));
    let l = lx.features(&t, &v).unwrap().to_vec();
    for (a, b) in l.iter().zip(&p) {
        assert!((a - b.max(1e-300).log10()).abs() < 1e-9);
    }
}

#[test]
fn welch_of_white_noise_is_flat_at_twice_the_variance_and_finds_a_tone() {
    let n = 4096;
    let mut s = timed(n, SpectrumKind::Welch);
    s.welch_segment = Some(128);
    s.welch_overlap = Some(0.5);
    s.taper = Taper::Hann;
    s.bins = [0, 64];
    let mut fx = FeatureExtractor::new(&s);
    // A fixed pseudo-random sequence, uniform on [−1, 1): variance 1/3.
    let mut state = 12345u64;
    let (t, v) = signal(n, |_| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    });
    let p = fx.features(&t, &v).unwrap().to_vec();
    let inner = &p[2..63];
    let mean = inner.iter().sum::<f64>() / inner.len() as f64;
    assert!((mean - 2.0 / 3.0).abs() < 0.05, "mean {mean}");
    // 62 segments averaged: each bin within 40 % of the mean.
    assert!(
        inner.iter().all(|v| (v / mean - 1.0).abs() < 0.4),
        "{inner:?}"
    );

    // A 250 Hz tone: bin 250 · 128 / 1000 = 32 of the 128-point segments.
    let (t, v) = signal(n, |t| (2.0 * PI * 250.0 * t).sin());
    let p = fx.features(&t, &v).unwrap().to_vec();
    assert_eq!(argmax(&p), 32);
    assert!((fx.frequency(32) - 250.0).abs() < 1e-9);
}

#[test]
fn hann_taper_cuts_leakage_far_from_an_off_bin_tone() {
    let n = 256;
    // 10.5 bins: the worst case for a rectangular window.
    let f0 = 10.5 * 1000.0 / n as f64;
    let (t, v) = signal(n, |t| (2.0 * PI * f0 * t).sin());
    let mut rect = FeatureExtractor::new(&timed(n, SpectrumKind::Power));
    let r = rect.features(&t, &v).unwrap().to_vec();
    let mut s = timed(n, SpectrumKind::Power);
    s.taper = Taper::Hann;
    let mut hann = FeatureExtractor::new(&s);
    let h = hann.features(&t, &v).unwrap().to_vec();
    assert!(argmax(&h) == 10 || argmax(&h) == 11);
    let far = |x: &[f64]| x[60] / x[argmax(x)];
    assert!(
        far(&h) < far(&r) * 1e-3,
        "hann {} rect {}",
        far(&h),
        far(&r)
    );
}

#[test]
fn a_band_in_hz_keeps_the_bins_inside_it() {
    let n = 1000;
    let mut s = timed(n, SpectrumKind::Magnitude);
    s.band = Some([10.0, 20.0]);
    // 1 Hz apart: bins 10..=20.
    assert_eq!(s.kept_bins(), [10, 20]);
    assert_eq!(s.feature_count(), 11);
    let mut fx = FeatureExtractor::new(&s);
    let (t, v) = signal(n, |t| (2.0 * PI * 13.0 * t).sin());
    let f = fx.features(&t, &v).unwrap().to_vec();
    assert_eq!(f.len(), 11);
    assert_eq!(argmax(&f), 3);
}

#[test]
fn a_band_in_cycles_per_mm_matches_the_thesis_bins() {
    // The thesis window: 100 points 0.3 mm apart, bins 1/30 cycle/mm apart.
    let mut s = Analysis::default();
    assert_eq!(s.frequency_unit(), "cycles/mm");
    assert!((s.bin_width() - 1.0 / 30.0).abs() < 1e-12);
    s.band = Some([1.0 / 30.0, 49.0 / 30.0]);
    assert_eq!(s.kept_bins(), [1, 49]);
    // A 4.24 mm period (the S2 texture) puts 0.236 cycles/mm at bin 7.
    s.band = Some([0.2, 0.25]);
    assert_eq!(s.kept_bins(), [6, 7]);
    // A band between two bins holds none: refused with the bin spacing.
    s.band = Some([0.201, 0.202]);
    let err = hapticlab::analysis::check_settings(&s).unwrap_err();
    assert!(err.contains("holds no DFT bin"), "{err}");
}

#[test]
fn several_channels_are_concatenated_in_order() {
    let n = 64;
    let mut s = timed(n, SpectrumKind::Magnitude);
    s.bins = [1, 8];
    s.channels = vec!["w".into()];
    assert_eq!(s.feature_count(), 16);
    let mut fx = FeatureExtractor::new(&s);
    let (t, a) = signal(n, |t| (2.0 * PI * 1000.0 / 64.0 * 2.0 * t).sin());
    let (_, b) = signal(n, |t| (2.0 * PI * 1000.0 / 64.0 * 5.0 * t).sin());
    let f = fx.features_of_channels(&t, &[&a, &b]).unwrap().to_vec();
    assert_eq!(argmax(&f[..8]) + 1, 2);
    assert_eq!(argmax(&f[8..]) + 1, 5);
    // The display buffers show the first channel.
    assert_eq!(argmax(fx.spectrum()), 2);
    assert!(fx.features_of_channels(&t, &[&a]).is_err());
}

#[test]
fn welch_settings_are_checked() {
    let mut s = timed(256, SpectrumKind::Welch);
    s.bins = [0, 10];
    s.welch_segment = Some(512);
    assert!(FeatureExtractor::try_new(&s).is_err());
    s.welch_segment = Some(64);
    s.welch_overlap = Some(1.0);
    assert!(FeatureExtractor::try_new(&s).is_err());
    s.welch_overlap = Some(0.75);
    assert!(FeatureExtractor::try_new(&s).is_ok());
    let mut m = timed(256, SpectrumKind::Magnitude);
    m.welch_segment = Some(64);
    assert!(FeatureExtractor::try_new(&m).is_err());
}
