//! The windows the random-kernel timings use, shared by
//! `benches/kernels.rs` and `examples/kernel_window_cpu.rs` so both time
//! the same signal (contrib/aeon-peer.py --per-window makes the same kind
//! for aeon's MiniRocket).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `count` noisy sines of `points`, four periods, one per class in turn.
pub fn windows(count: usize, points: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|i| {
            let period = [5.0, 9.0, 14.0, 23.0][i % 4];
            let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            (0..points)
                .map(|t| {
                    (t as f64 / period * std::f64::consts::TAU + phase).sin()
                        + 0.3 * rng.random_range(-1.0..1.0)
                })
                .collect()
        })
        .collect()
}
