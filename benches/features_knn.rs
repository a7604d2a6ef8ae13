//! One scan's features plus one k-NN query, the work `classify` does per
//! recording: 9000 samples (a 89.7 mm stroke in x, a trapezoid-like y wave
//! with noise) through the thesis analysis, then k = 10 among 80 training
//! vectors of 49 features.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::analysis::FeatureExtractor;
use hapticlab::classify::{Model, TrainingExample};
use hapticlab::profile::LoadedProfile;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A scan over a corrugation of `period` metres: (x, y), 9000 samples.
fn scan(period: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let shift = rng.random_range(0.0..period);
    let x: Vec<f64> = (0..9000)
        .map(|j| -0.045 + 0.0897 * j as f64 / 8999.0)
        .collect();
    let y = x
        .iter()
        .map(|&x| {
            let phase = ((x + shift) / period).rem_euclid(1.0);
            let shape = (4.0 * (phase - 0.5).abs() - 1.0).clamp(-0.6, 0.6) / 0.6;
            -0.0048 + 0.0009 * shape + 0.00002 * rng.random_range(-1.0..1.0)
        })
        .collect();
    (x, y)
}

fn bench(c: &mut Criterion) {
    let profile = LoadedProfile::thesis().profile;
    let mut fx = FeatureExtractor::new(&profile.analysis);
    let periods = [
        ("S1", 0.0005),
        ("S2", 0.00424),
        ("S3", 0.0075),
        ("S4", 0.0079),
    ];
    let mut examples = Vec::new();
    for (c, (label, period)) in periods.iter().enumerate() {
        for i in 0..20 {
            let (x, y) = scan(*period, (c * 100 + i) as u64);
            examples.push(TrainingExample {
                file: format!("{label}/{i:02}.csv"),
                label: label.to_string(),
                features: fx.features(&x, &y).unwrap().to_vec(),
            });
        }
    }
    let model = Model::train("thesis", &profile.analysis, &profile.classifier, examples).unwrap();
    let (x, y) = scan(0.00424, 999);

    c.bench_function("features (9000 samples)", |b| {
        b.iter(|| fx.features(black_box(&x), black_box(&y)).unwrap()[0])
    });
    let query = fx.features(&x, &y).unwrap().to_vec();
    c.bench_function("k-NN query (80 x 49, k = 10)", |b| {
        b.iter(|| model.classify(black_box(&query)).unwrap())
    });
    // A parsed 5 s, 44.1 kHz clip (a tone plus broadband texture), one
    // 0.5 s window, log-Welch of 2048-point segments (issue 13).
    let audio = hapticlab::profile::Analysis {
        channel: "pac".into(),
        axis: "t_s".into(),
        window: [1.0, 1.5],
        spacing: 1.0 / 44100.0,
        detrend: hapticlab::profile::Detrend::Mean,
        spectrum: hapticlab::profile::SpectrumKind::LogWelch,
        taper: hapticlab::profile::Taper::Hann,
        welch_segment: Some(2048),
        ..Default::default()
    };
    let mut ax = FeatureExtractor::new(&hapticlab::profile::Analysis {
        bins: [1, 1024],
        ..audio.clone()
    });
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let t: Vec<f64> = (0..5 * 44100).map(|j| j as f64 / 44100.0).collect();
    let pac: Vec<f64> = t
        .iter()
        .map(|&t| (2.0 * std::f64::consts::PI * 310.0 * t).sin() + rng.random_range(-0.5..0.5))
        .collect();
    c.bench_function(
        "features (5 s at 44.1 kHz, 0.5 s window, log-Welch 2048)",
        |b| b.iter(|| ax.features(black_box(&t), black_box(&pac)).unwrap()[0]),
    );
    // The whole clip cut into 0.5 s sub-windows with half-window hops (19
    // of them), each a log-Welch of 2048-point segments: what `classify`
    // and `evaluate` compute per recording with `windows` (issue 13: < 5 ms).
    let mut wx = FeatureExtractor::new(&hapticlab::profile::Analysis {
        window: [0.0, 4.99],
        windows: Some(hapticlab::profile::Windows {
            length: 0.5,
            hop: 0.25,
        }),
        bins: [1, 1024],
        ..audio
    });
    assert_eq!(wx.sub_windows().len(), 18);
    c.bench_function(
        "features (5 s at 44.1 kHz, all 0.5 s sub-windows, hop 0.25 s, log-Welch 2048)",
        |b| {
            b.iter(|| {
                wx.all_window_features(black_box(&t), &[black_box(&pac)])
                    .unwrap()
                    .len()
            })
        },
    );
    c.bench_function("features + k-NN query", |b| {
        b.iter(|| {
            let f = fx.features(black_box(&x), black_box(&y)).unwrap();
            model.classify(f).unwrap()
        })
    });
}

// No plots: the crate's plotters has only the ab_glyph font backend
// (no system fonts), and criterion's plots would find no font.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
