//! The random-kernel transform's CPU time per window on one core, for a
//! side-by-side run with aeon's MiniRocket (`contrib/aeon-peer.py
//! --per-window POINTS` times aeon on the same kind of windows): the 9996
//! features of `KernelTransform::transform`, biases fitted on 80 windows
//! of noisy sines (`benches/shared/noisy_sines.rs`, as `cargo bench
//! --bench kernels` times them), after a warm-up call. Prints the thread's
//! CPU time per call of one window (median of R calls) and per window of a
//! batch of 100 different windows, as aeon-peer.py does.
//!
//!     cargo run --release --example kernel_window_cpu -- POINTS [R]
//!
//! A second line gives the fit's CPU time (biases on the 80 windows) and
//! both as rates per point: the ones `tune` estimates a kernel setting's
//! cost with (`hapticlab::tune::cost`), measured.
//!
//! e.g., alternated with aeon in one run:
//!
//!     for i in 1 2 3; do
//!       cargo run -q --release --example kernel_window_cpu -- 1000
//!       /tmp/aeonenv/bin/python contrib/aeon-peer.py --per-window 1000
//!     done

use hapticlab::analysis::kernels::{DEFAULT_FEATURES, KernelTransform};

#[path = "../benches/shared/noisy_sines.rs"]
mod noisy_sines;
use noisy_sines::windows;
#[path = "../benches/shared/thread_cpu.rs"]
mod thread_cpu;
use thread_cpu::{number_arg, thread_cpu};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number =
        |i: usize, default: usize| number_arg(&args, i, default, "kernel_window_cpu", "POINTS [R]");
    let (points, repeats) = (number(0, 1000), number(1, 50).max(1));
    let train = windows(80, points, 1);
    let refs: Vec<&[f64]> = train.iter().map(Vec::as_slice).collect();
    let c0 = thread_cpu();
    let fitted = KernelTransform::fit(&refs, points, 1, DEFAULT_FEATURES);
    let fit_cpu = thread_cpu() - c0;
    let t = match fitted {
        Ok(t) => t,
        Err(e) => {
            eprintln!("kernel_window_cpu: {points} points: {e}");
            std::process::exit(2)
        }
    };
    let mut conv = t.convolution();
    let mut out = vec![0.0; t.feature_count()];
    let one = windows(1, points, 2).remove(0);
    let batch = windows(100, points, 3);
    // The warm-up call.
    t.transform(&one, &mut conv, &mut out);
    let mut single: Vec<f64> = (0..repeats)
        .map(|_| {
            let c0 = thread_cpu();
            t.transform(std::hint::black_box(&one), &mut conv, &mut out);
            thread_cpu() - c0
        })
        .collect();
    single.sort_by(f64::total_cmp);
    let c0 = thread_cpu();
    for w in &batch {
        t.transform(std::hint::black_box(w), &mut conv, &mut out);
    }
    let batched = (thread_cpu() - c0) / batch.len() as f64;
    println!(
        "{} random-kernel transform, one core, {} features, windows of {points} points: \
         CPU {:.3} ms per call of one window (median of {repeats}, min {:.3}), \
         CPU {:.3} ms per window in a batch of 100",
        hapticlab::version::SOFTWARE,
        t.feature_count(),
        1e3 * single[single.len() / 2],
        1e3 * single[0],
        1e3 * batched
    );
    // The rates tune's estimate of a kernel setting's cost uses
    // (hapticlab::tune::cost): per point and feature of a window
    // transformed, per point and kernel-dilation pair of a fit.
    let pairs = hapticlab::analysis::kernels::KERNEL_COUNT * t.layout.dilations.len();
    println!(
        "  fit on 80 windows: CPU {:.3} s, {:.2} ns per point and kernel-dilation pair \
         (tune::cost::FIT_SECONDS {:.2} ns); transform {:.3} ns per point and feature \
         (tune::cost::TRANSFORM_SECONDS {:.3} ns)",
        fit_cpu,
        1e9 * fit_cpu / (points * pairs) as f64,
        1e9 * hapticlab::tune::cost::FIT_SECONDS,
        1e9 * batched / (points * t.feature_count()) as f64,
        1e9 * hapticlab::tune::cost::TRANSFORM_SECONDS
    );
}
