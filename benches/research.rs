//! The performance targets:
//! - `evaluate` with 10-fold cross-validation over 2,000 recordings of
//!   10,000 samples, parsing included (target < 10 s);
//! - one k-NN query against 100,000 training vectors of 64 features
//!   (target < 5 ms).
//!
//! The dataset is generated in a temporary folder in the setup (not timed).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::classify::{Model, TrainingExample};
use hapticlab::evaluate::cv::{Dealt, cross_validate, make_folds};
use hapticlab::evaluate::plan::Recordings;
use hapticlab::profile::{Analysis, Classifier, SplitMethod};
use hapticlab::recording::RecordingWriter;

const RECORDINGS: usize = 2000;
const SAMPLES: usize = 10_000;

/// Thesis-like scans: 10,000 samples at 1 kHz along 89.7 mm, a corrugation
/// whose period depends on the class, the thesis's seven columns.
fn write_dataset(dir: &std::path::Path) {
    let columns = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"];
    for r in 0..RECORDINGS {
        let class = r % 4;
        let label = format!("S{}", class + 1);
        let path = dir.join(&label).join(format!("{label}_{r:04}.csv"));
        let meta = vec![("label".to_string(), toml::Value::String(label.clone()))];
        let mut w = RecordingWriter::create(&path, &meta, &columns).unwrap();
        w.defer_sync();
        let period = [0.0, 0.00424, 0.0075, 0.0079][class];
        let phase = (r * 7919 % 1000) as f64 / 1000.0;
        let mut row = [0.0; 7];
        for j in 0..SAMPLES {
            let x = 0.0897 * j as f64 / (SAMPLES - 1) as f64;
            let noise = (((j * 7 + r * 13) % 17) as f64 - 8.0) * 2e-6;
            let y = if period > 0.0 {
                -0.004 - 0.0005 * (2.0 * std::f64::consts::PI * (x / period + phase)).sin()
            } else {
                -0.004
            } + noise;
            row = [j as f64 / 1000.0, x - 0.045, y, -0.02, 0.1, -0.3, 0.0];
            w.write_row(&row).unwrap();
        }
        let _ = row;
        w.finish().unwrap();
    }
}

fn evaluate_10_fold(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path());
    let analysis = Analysis::default();
    let classifier = Classifier::default();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let paths = vec![dir.path().to_path_buf()];
    let mut g = c.benchmark_group("evaluate");
    g.sample_size(10).measurement_time(Duration::from_secs(60));
    g.bench_function(
        "10-fold CV, 2000 recordings x 10000 samples, parsing included",
        |b| {
            b.iter(|| {
                let data = Recordings::load(
                    &paths,
                    &analysis,
                    hapticlab::dataset::Keep::Features,
                    threads,
                )
                .unwrap();
                let examples = data.examples(&analysis).unwrap();
                let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
                let folds =
                    Dealt::plain(make_folds(&labels, None, SplitMethod::KFold, 10, 1).unwrap());
                let r = cross_validate(
                    &examples,
                    &folds,
                    "bench",
                    &analysis,
                    &classifier,
                    "k-fold",
                    1,
                    threads,
                )
                .unwrap();
                assert_eq!(r.test.len(), RECORDINGS);
                black_box(r.accuracy)
            })
        },
    );
    g.finish();
}

fn knn_query(c: &mut Criterion) {
    let analysis = Analysis {
        window: [0.0, 0.0897],
        bins: [1, 64],
        ..Analysis::default()
    };
    let mut state = 1u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let examples: Vec<TrainingExample> = (0..100_000)
        .map(|i| TrainingExample {
            file: format!("{i}.csv"),
            label: format!("S{}", i % 10),
            features: (0..64).map(|_| next()).collect(),
        })
        .collect();
    let query: Vec<f64> = (0..64).map(|_| next()).collect();
    let mut g = c.benchmark_group("knn");
    for (name, classifier) in [
        ("euclidean k=10", Classifier::default()),
        (
            "cosine k=10 standardised",
            Classifier {
                metric: hapticlab::profile::Metric::Cosine,
                standardize: true,
                ..Classifier::default()
            },
        ),
    ] {
        let model = Model::train("bench", &analysis, &classifier, examples.clone()).unwrap();
        g.bench_function(format!("one query, 100000 x 64, {name}"), |b| {
            b.iter(|| model.classify(black_box(&query)).unwrap())
        });
    }
    g.finish();
}

// No plots: the crate's plotters has only the ab_glyph font backend
// (no system fonts), and criterion's plots would find no font.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = knn_query, evaluate_10_fold
}
criterion_main!(benches);
