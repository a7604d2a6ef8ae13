//! The competing-kernel transform's CPU time per window on one core: the
//! features `Hydra::compute` makes of one channel's window of noisy sines
//! (`benches/shared/noisy_sines.rs`), after a warm-up call. Prints the
//! thread's CPU time per window (median of R calls) and per point and
//! dilation: the rate `tune` estimates a competing-kernel setting's cost
//! with (`hapticlab::tune::cost::HYDRA_SECONDS`), measured.
//!
//!     cargo run --release --example hydra_window_cpu -- POINTS [R]

use hapticlab::analysis::hydra::Hydra;
use hapticlab::profile::families::hydra_dilations;

#[path = "../benches/shared/noisy_sines.rs"]
mod noisy_sines;
use noisy_sines::windows;
#[path = "../benches/shared/thread_cpu.rs"]
mod thread_cpu;
use thread_cpu::{number_arg, thread_cpu};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number =
        |i: usize, default: usize| number_arg(&args, i, default, "hydra_window_cpu", "POINTS [R]");
    let (points, repeats) = (number(0, 1000), number(1, 20).max(1));
    let dilations = hydra_dilations(points).len();
    if dilations == 0 {
        eprintln!("hydra_window_cpu: {points} points: competing kernels need at least 10");
        std::process::exit(2);
    }
    let mut h = Hydra::new(points);
    let mut out = vec![0.0; h.len()];
    let one = windows(1, points, 2).remove(0);
    h.compute(&one, &mut out);
    let mut cpu: Vec<f64> = (0..repeats)
        .map(|_| {
            let c0 = thread_cpu();
            h.compute(std::hint::black_box(&one), &mut out);
            thread_cpu() - c0
        })
        .collect();
    cpu.sort_by(f64::total_cmp);
    let median = cpu[cpu.len() / 2];
    println!(
        "competing kernels, {points} points, {dilations} dilations, {} features: {:.3} ms a window (median of {repeats}), {:.2e} s per point and dilation",
        h.len(),
        median * 1e3,
        median / (points * dilations) as f64
    );
}
