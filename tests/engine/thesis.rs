//! The thesis's result (section 4.4 and Table 4.1) at a reduced size,
//! through the library: simulate 12 scans of each texture, extract the 49
//! DFT bins, check each corrugated texture's dominant bin, and classify an
//! 8/4 split with k-NN.

use hapticlab::acquire::{SimulateOptions, simulate_dataset};
use hapticlab::classify::Model;
use hapticlab::evaluate::{evaluate, split};
use hapticlab::profile::{Evaluation, LoadedProfile};
use hapticlab::support::load_examples;

const PER_CLASS: usize = 12;

/// The 1-based bin with the most energy (`features[0]` is bin 1).
fn dominant_bin(features: &[f64]) -> usize {
    let (i, _) = features
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .expect("features");
    i + 1
}

#[test]
fn dominant_bins_and_accuracy_match_the_thesis() {
    let lp = LoadedProfile::thesis();
    let p = &lp.profile;
    let dir = tempfile::tempdir().unwrap();
    let opts = SimulateOptions {
        out: dir.path().to_path_buf(),
        per_class: PER_CLASS,
        seed: p.simulator.seed,
        threads: 2,
        gzip: false,
        overwrite: false,
    };
    let saved = simulate_dataset(&lp, &opts, &|_, _| {}).unwrap();
    assert_eq!(saved.len(), 4 * PER_CLASS);
    assert!(saved.iter().all(|s| s.complete && s.error.is_none()));

    let examples = load_examples(&[dir.path().to_path_buf()], &p.analysis).unwrap();
    assert_eq!(examples.len(), 4 * PER_CLASS);
    assert_eq!(p.analysis.bins, [1, 49]);

    // Section 4.4: S2's spectrum peaks at bin 7, S3's and S4's at bin 4.
    for (label, bin) in [("S2", 7), ("S3", 4), ("S4", 4)] {
        let bins: Vec<usize> = examples
            .iter()
            .filter(|e| e.label == label)
            .map(|e| dominant_bin(&e.features))
            .collect();
        assert_eq!(bins.len(), PER_CLASS);
        let hits = bins.iter().filter(|&&b| b == bin).count();
        assert!(
            hits >= 10,
            "{label}: dominant bin {bin} in only {hits} of {PER_CLASS} scans: {bins:?}"
        );
    }

    // Table 4.1, reduced: 8 scans per texture to train, 4 to test.
    let eval = Evaluation {
        train_per_class: 8,
        test_per_class: 4,
        shuffle_seed: None,
        ..Evaluation::default()
    };
    let split = split(examples, &eval).unwrap();
    assert_eq!((split.train.len(), split.test.len()), (32, 16));
    let model = Model::train(&p.name, &p.analysis, &p.classifier, split.train).unwrap();
    let report = evaluate(&model, &split.test).unwrap();
    assert_eq!(report.tested(), 16);
    assert!(
        report.correct() >= 15,
        "{} of 16 right:\n{}",
        report.correct(),
        report.table()
    );
}
