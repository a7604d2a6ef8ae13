//! `tune`'s speed target (issue 21): at least 96 settings scored with 5
//! inner folds over 200 recordings × 13,200 samples at 2.2 kHz (the size
//! of the generated fingertip set), parsing included. The peer,
//! scikit-learn's GridSearchCV over the same settings, is
//! `contrib/tune_reference.py`, which runs both side by side; this bench
//! tracks hapticlab's side alone.
//!
//! The recordings are generated in a temporary folder in the setup (not
//! timed): 20 classes of tones in noise whose level drifts with the trial.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::dataset::{Keep, Options, Unusable};
use hapticlab::evaluate::plan::Recordings;
use hapticlab::profile::LoadedProfile;
use hapticlab::recording::RecordingWriter;

const CLASSES: usize = 20;
const TRIALS: usize = 10;
const SAMPLES: usize = 13_200;
const RATE: f64 = 2200.0;

const PROFILE: &str = "name = \"bench\"\n[analysis]\nchannel = \"vib\"\naxis = \"t_s\"\n\
window = [0.0, 5.99]\nspacing = 0.00045454545454545455\n[classifier]\nk = 1\n\
[evaluation]\nmethod = \"holdout\"\ntrain_per_class = 5\ntest_per_class = 5\n";

fn write_dataset(dir: &Path) {
    let mut state = 3u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for c in 0..CLASSES {
        let label = format!("F{:02}", c + 1);
        for t in 0..TRIALS {
            let path = dir
                .join(&label)
                .join(format!("{label}-trial{:02}.csv", t + 1));
            let meta = vec![("label".to_string(), toml::Value::String(label.clone()))];
            let mut w = RecordingWriter::create(&path, &meta, &["t_s", "vib"]).unwrap();
            w.defer_sync();
            let gain = 1.0 + 0.1 * t as f64;
            let f0 = 40.0 + 23.0 * c as f64;
            for j in 0..SAMPLES {
                let time = j as f64 / RATE;
                let v =
                    gain * (300.0 * (std::f64::consts::TAU * f0 * time).sin() + 400.0 * noise());
                w.write_row(&[time, v.round()]).unwrap();
            }
            w.finish().unwrap();
        }
    }
}

fn tune_96(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path());
    let profile = LoadedProfile::from_str(PROFILE, "bench.toml", Path::new("."))
        .unwrap()
        .profile;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let files = hapticlab::dataset::find(&[dir.path().to_path_buf()]).unwrap();
    let options = Options {
        keep: Keep::Samples,
        unusable: Unusable::Fail,
        threads,
    };
    let search = hapticlab::tune::Options {
        budget: 96,
        seed: 0,
        threads,
        max_minutes: hapticlab::tune::MAX_MINUTES,
    };
    let mut g = c.benchmark_group("tune");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function(
        "96 settings, 5 inner folds, 200 recordings x 13200 samples, parsing included",
        |b| {
            b.iter(|| {
                let data =
                    Recordings::load_files(&files, &profile.analysis, options, &|| {}).unwrap();
                let r = hapticlab::tune::tune("bench", &profile, &data.scans, &search, &|_, _| {})
                    .unwrap();
                assert_eq!(r.configurations, 96);
                black_box(r.outer_accuracy)
            })
        },
    );
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = tune_96
}
criterion_main!(benches);
