//! How k is chosen where the profile's cannot be used or says `auto`: an
//! inner stratified cross-validation of the candidates on the training
//! rows only (split from classify.rs, whose k-NN it calls).

#[allow(clippy::wildcard_imports)]
use super::*;

/// Inner stratified 5-fold cross-validation of every candidate k on the
/// (prepared) training rows; folds deal each class's recordings round-robin
/// in their order, so the choice is deterministic. `recording_of` numbers
/// each row's recording: a recording's sub-windows (consecutive rows of one
/// file) stay in one fold, so no window is scored against its own
/// recording's others.
pub(super) fn select_k(
    classifier: &Classifier,
    matrix: &[f64],
    norms: &[f64],
    classes_of: &[usize],
    recording_of: &[usize],
    classes: usize,
) -> Vec<KScore> {
    let n = classes_of.len();
    let d = matrix.len() / n.max(1);
    let mut fold_of = vec![0usize; n];
    let mut seen = vec![0usize; classes];
    let recordings = recording_of.last().map_or(0, |r| r + 1);
    let folds = inner_folds(recordings);
    for (i, &c) in classes_of.iter().enumerate() {
        if i > 0 && recording_of[i] == recording_of[i - 1] {
            fold_of[i] = fold_of[i - 1];
            continue;
        }
        fold_of[i] = seen[c] % folds;
        seen[c] += 1;
    }
    let candidates = classifier
        .k_candidates
        .clone()
        .unwrap_or_else(|| AUTO_K_CANDIDATES.to_vec());
    let kmax = candidates.iter().copied().max().unwrap_or(1);
    let mut correct = vec![0usize; candidates.len()];
    let mut tested = 0usize;
    let mut nearest = Vec::new();
    for f in 0..folds {
        let train: Vec<usize> = (0..n).filter(|&i| fold_of[i] != f).collect();
        if train.is_empty() {
            continue;
        }
        for q in (0..n).filter(|&i| fold_of[i] == f) {
            tested += 1;
            let row = &matrix[q * d..(q + 1) * d];
            nearest_rows(
                classifier.metric,
                row,
                matrix,
                norms,
                train.iter().copied(),
                kmax.min(train.len()),
                &mut nearest,
            );
            for (ci, &k) in candidates.iter().enumerate() {
                let k = k.min(nearest.len());
                let (order, _) = rank_classes(
                    classifier.metric,
                    classifier.weights,
                    &nearest[..k],
                    classes_of,
                    classes,
                );
                if order[0] == classes_of[q] {
                    correct[ci] += 1;
                }
            }
        }
    }
    candidates
        .iter()
        .zip(correct)
        .map(|(&k, c)| KScore {
            k,
            accuracy: c as f64 / tested.max(1) as f64,
        })
        .collect()
}

/// Each example's recording, numbered from 0: consecutive examples of one
/// file (a recording's sub-windows) share a number.
pub(super) fn recording_numbers(examples: &[TrainingExample]) -> Vec<usize> {
    let mut numbers = Vec::with_capacity(examples.len());
    for (i, e) in examples.iter().enumerate() {
        let same = i > 0 && examples[i - 1].file == e.file;
        numbers.push(match numbers.last() {
            Some(&last) if same => last,
            Some(&last) => last + 1,
            None => 0,
        });
    }
    numbers
}

/// The folds of the inner cross-validation that chooses k among `n`
/// recordings.
pub(super) fn inner_folds(n: usize) -> usize {
    5.min(n).max(2)
}

/// The texture with the fewest examples (the first in label order on a
/// tie) and its count.
pub(super) fn smallest_class(examples: &[TrainingExample]) -> Option<(String, usize)> {
    let mut counts: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    for e in examples {
        *counts.entry(e.label.as_str()).or_default() += 1;
    }
    counts
        .into_iter()
        .fold(None, |best: Option<(&str, usize)>, (l, n)| match best {
            Some((_, b)) if b <= n => best,
            _ => Some((l, n)),
        })
        .map(|(l, n)| (l.to_string(), n))
}
