//! What the linear classifiers (ridge, LDA) share: one row of weights and
//! an intercept per class, and a score per class that is their dot product
//! with the (standardised or centred) features plus the intercept.

/// Each class's score for the prepared features `z`.
pub(crate) fn scores(weights: &[Vec<f64>], intercepts: &[f64], z: &[f64]) -> Vec<f64> {
    weights
        .iter()
        .zip(intercepts)
        .map(|(w, b)| super::dot(w, z) + b)
        .collect()
}

/// Whether a fit read from a file has `classes` rows of `features` finite
/// weights and `classes` finite intercepts.
pub(crate) fn weights_fit(
    weights: &[Vec<f64>],
    intercepts: &[f64],
    features: usize,
    classes: usize,
) -> bool {
    weights.len() == classes
        && intercepts.len() == classes
        && weights.iter().all(|w| w.len() == features && finite(w))
        && finite(intercepts)
}

pub(crate) fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Test examples of `classes` labels in turn, `p` features uniform in
/// (-1, 1) with 0.7 added where `j % classes` is the label, and
/// `offset(j)` added to feature `j`.
#[cfg(test)]
pub(crate) fn separable(
    n: usize,
    p: usize,
    classes: usize,
    seed: u64,
    offset: impl Fn(usize) -> f64,
) -> (Vec<Vec<f64>>, Vec<usize>) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let labels: Vec<usize> = (0..n).map(|i| i % classes).collect();
    let rows = labels
        .iter()
        .map(|&c| {
            (0..p)
                .map(|j| {
                    rng.random_range(-1.0..1.0)
                        + if j % classes == c { 0.7 } else { 0.0 }
                        + offset(j)
                })
                .collect()
        })
        .collect();
    (rows, labels)
}
