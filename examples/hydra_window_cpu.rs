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

/// This thread's CPU time, in seconds.
fn thread_cpu() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: usize| -> usize {
        match args.get(i) {
            None => default,
            Some(a) => a.parse().unwrap_or_else(|_| {
                eprintln!("hydra_window_cpu: {a:?} is not a whole number (POINTS [R])");
                std::process::exit(2)
            }),
        }
    };
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
