//! `simulate` of the 120-scan thesis dataset (30 scans of each of the four
//! textures), in virtual time on every core, writing plain CSV.
//!
//! cargo bench --bench simulate

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::acquire::{SimulateOptions, simulate_dataset};
use hapticlab::profile::LoadedProfile;

fn bench(c: &mut Criterion) {
    let lp = LoadedProfile::thesis();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut g = c.benchmark_group("simulate");
    g.sample_size(10);
    g.bench_function("thesis_120_scans", |b| {
        b.iter_with_setup(
            || tempfile::tempdir().expect("a temp dir"),
            |dir| {
                let opts = SimulateOptions {
                    out: dir.path().to_path_buf(),
                    per_class: 30,
                    seed: 1,
                    threads,
                    gzip: false,
                    overwrite: false,
                };
                let saved = simulate_dataset(&lp, &opts, &|_, _| {}).expect("simulate");
                assert_eq!(saved.len(), 120);
                dir
            },
        )
    });
    g.finish();
}

// No plots: the crate's plotters has only the ab_glyph font backend
// (no system fonts), and criterion's plots would find no font.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
