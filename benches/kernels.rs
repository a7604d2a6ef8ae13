//! The new feature families per window, as `evaluate` and `classify` pay
//! them: the random-kernel transform (MiniRocket's 9996 features, biases
//! fitted on 80 training windows) and the interval quantiles of one
//! window of 100 points (the thesis's), of 1000 points and of 13,200 points
//! (6 s at 2.2 kHz); and the ridge's fit (alpha by leave-one-out) on 80
//! windows of kernel features.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::analysis::kernels::{DEFAULT_FEATURES, KernelTransform};
use hapticlab::analysis::quantiles::Quantiles;
use hapticlab::classify::ridge::RidgeFit;

#[path = "shared/noisy_sines.rs"]
mod noisy_sines;
use noisy_sines::windows;

fn bench(c: &mut Criterion) {
    for points in [100, 1000, 13_200] {
        let train = windows(80, points, 1);
        let refs: Vec<&[f64]> = train.iter().map(Vec::as_slice).collect();
        let t = KernelTransform::fit(&refs, points, 1, DEFAULT_FEATURES).unwrap();
        let mut conv = t.convolution();
        let mut out = vec![0.0; t.feature_count()];
        let query = windows(1, points, 2).remove(0);
        c.bench_function(
            &format!("random kernels: one window of {points} points (9996 features)"),
            |b| {
                b.iter(|| {
                    t.transform(black_box(&query), &mut conv, &mut out);
                    out[0]
                })
            },
        );
        let mut q = Quantiles::new(points);
        let mut qout = vec![0.0; q.len()];
        c.bench_function(
            &format!("interval quantiles: one window of {points} points"),
            |b| {
                b.iter(|| {
                    q.compute(black_box(&query), &mut qout);
                    qout[0]
                })
            },
        );
        if points == 100 {
            let rows: Vec<Vec<f64>> = train
                .iter()
                .map(|w| {
                    let mut o = vec![0.0; t.feature_count()];
                    t.transform(w, &mut conv, &mut o);
                    o
                })
                .collect();
            let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            let classes: Vec<usize> = (0..80).map(|i| i % 4).collect();
            c.bench_function(
                "ridge fit: 80 windows x 9996 kernel features, 10 alphas by LOO",
                |b| b.iter(|| RidgeFit::fit(black_box(&rows), &classes, 4).unwrap().alpha),
            );
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
