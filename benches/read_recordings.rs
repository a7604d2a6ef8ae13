//! Throughput of the recording reader on a typical scan: 9000 rows of 7
//! columns written by `RecordingWriter`, parsed from memory (plain and gzip)
//! on one core; then a dataset of 240 such scans read from the page cache
//! into feature vectors by `dataset::load` (the thesis profile's analysis),
//! on one thread and on one per core.

use std::hint::black_box;
use std::io::Write as _;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use hapticlab::dataset::{self, Keep, Options, Unusable};
use hapticlab::profile::LoadedProfile;
use hapticlab::recording::{self, RecordingWriter};

const ROWS: usize = 9000;

/// A scan like the simulator's: x ramps along the stroke, y follows the
/// texture's wave with a little noise, the forces vary with it.
fn typical_recording() -> Vec<u8> {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("S2/001.csv");
    let meta = [
        ("label".to_string(), toml::Value::String("S2".into())),
        ("profile".to_string(), toml::Value::String("thesis".into())),
        (
            "profile_sha256".to_string(),
            toml::Value::String("9f".repeat(32)),
        ),
        ("device".to_string(), toml::Value::String("sim".into())),
        ("rate_hz".to_string(), toml::Value::Float(1000.0)),
        (
            "started_at".to_string(),
            toml::Value::String("2026-11-21T22:00:00Z".into()),
        ),
    ];
    let columns = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"];
    let mut writer = RecordingWriter::create(&path, &meta, &columns).expect("create");
    // A small linear congruential generator: deterministic noise without a dependency.
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut noise = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for i in 0..ROWS {
        let t = i as f64 / 1000.0;
        let x = -0.045 + 0.01 * t;
        let wave = (2.0 * std::f64::consts::PI * x / 0.003).sin();
        let y = -0.0048 + 0.0004 * wave + 2e-6 * noise();
        let row = [
            t,
            x,
            y,
            -0.02 + 1e-6 * noise(),
            0.2 * wave + 0.01 * noise(),
            -0.31 - 0.05 * wave,
            0.02 * noise(),
        ];
        writer.write_row(&row).expect("row");
    }
    writer.finish().expect("finish");
    std::fs::read(&path).expect("read back")
}

fn read_recordings(c: &mut Criterion) {
    let text = typical_recording();
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(&text).expect("gzip");
    let gz = encoder.finish().expect("gzip");

    let mut group = c.benchmark_group("read_recordings");
    // Both measured in bytes of CSV text, so the numbers compare.
    group.throughput(Throughput::Bytes(text.len() as u64));
    group.bench_function("parse_9000x7", |b| {
        b.iter(|| recording::parse(black_box(&text), "bench.csv").expect("parse"))
    });
    group.bench_function("parse_9000x7_gz", |b| {
        b.iter(|| recording::parse(black_box(&gz), "bench.csv.gz").expect("parse"))
    });
    group.finish();
}

/// Scans in the dataset case: 60 per texture folder, about 125 MB of CSV.
const SCANS: usize = 240;

fn load_dataset(c: &mut Criterion) {
    let text = typical_recording();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut files = Vec::with_capacity(SCANS);
    for i in 0..SCANS {
        let folder = dir.path().join(format!("S{}", i % 4 + 1));
        std::fs::create_dir_all(&folder).expect("folder");
        let file = folder.join(format!("{i:03}.csv"));
        std::fs::write(&file, &text).expect("write");
        files.push(file);
    }
    files.sort();
    let analysis = LoadedProfile::thesis().profile.analysis;
    let mut group = c.benchmark_group("read_recordings");
    group.sample_size(10);
    group.throughput(Throughput::Bytes((text.len() * SCANS) as u64));
    for (name, threads) in [
        ("dataset_load_240_one_thread", 1),
        ("dataset_load_240_every_core", dataset::cores()),
    ] {
        let options = Options {
            keep: Keep::Features,
            unusable: Unusable::Fail,
            threads,
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                let loaded =
                    dataset::load(black_box(&files), &analysis, options, &|| {}).expect("load");
                assert_eq!(loaded.entries.len(), SCANS);
                loaded
            })
        });
    }
    group.finish();
}

// No plots: the crate's plotters has only the ab_glyph font backend
// (no system fonts), and criterion's plots would find no font.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = read_recordings, load_dataset
}
criterion_main!(benches);
