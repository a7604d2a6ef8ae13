//! `[analysis] features` and `[classifier] method` from the command line:
//! train, classify and evaluate take random kernels, the ridge and the LDA
//! through the same commands, and a setting they cannot use is one line and
//! exit 2.

use std::path::Path;

use crate::common::{p, run};

const SMALL: &str = "tests/data/small";
const TINY: &str = "tests/data/small/tiny.toml";

/// `tiny.toml` with `[analysis]` and `[classifier]` lines added, written
/// to `dir/name`.
fn tiny_with(dir: &Path, name: &str, analysis: &str, classifier: &str) -> String {
    let text = std::fs::read_to_string(Path::new(crate::common::REPO).join(TINY)).unwrap();
    let text = text
        .replace("bins = [1, 8]\n", &format!("bins = [1, 8]\n{analysis}\n"))
        .replace("k = 1\n", &format!("k = 1\n{classifier}\n"));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    p(&path).to_string()
}

/// `hapticlab ARGS` exits 2 with one line holding each of `says`.
fn refused(args: &[&str], says: &[&str]) {
    let r = run(args);
    assert_eq!(r.code, Some(2), "{args:?}: {r:?}");
    assert_eq!(r.stderr.trim_end().lines().count(), 1, "one line: {r:?}");
    for s in says {
        assert!(r.stderr.contains(s), "{args:?}: {s:?} missing: {r:?}");
    }
}

#[test]
fn kernels_and_ridge_train_classify_and_evaluate() {
    let dir = tempfile::tempdir().unwrap();
    let data = format!("{SMALL}/two-labels");
    let profile = tiny_with(
        dir.path(),
        "k.toml",
        "features = \"kernels\"\nkernel_features = 840",
        "method = \"ridge\"",
    );
    let model = dir.path().join("m.json");
    let r = run(&["train", "-p", &profile, "--out", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(saved["format"], "hapticlab model v2");
    assert_eq!(saved["kernels"]["biases"][0].as_array().unwrap().len(), 840);
    assert_eq!(saved["ridge"]["weights"].as_array().unwrap().len(), 2);
    let r = run(&["classify", "-p", &profile, "--model", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    // Each training scan is predicted with itself left out (the model
    // trained again, kernels and all, without it); no neighbours to name.
    assert_eq!(
        r.stdout.matches("left out of the model").count(),
        6,
        "{r:?}"
    );
    assert!(!r.stdout.contains("nearest"), "{r:?}");
    // Under a profile's k-NN the model's own settings classify, and the
    // warning names the key, as for any classifier setting.
    let knn = tiny_with(
        dir.path(),
        "knn.toml",
        "features = \"kernels\"\nkernel_features = 840",
        "",
    );
    let r = run(&["classify", "-p", &knn, "--model", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stderr.contains("classifier.method = \"ridge\""), "{r:?}");
    // Under other features it is refused.
    let quantiles = tiny_with(dir.path(), "q.toml", "features = \"quantiles\"", "");
    refused(
        &["classify", "-p", &quantiles, "--model", p(&model), &data],
        &["analysis.features", "\"kernels\"", "\"quantiles\""],
    );
    let r = run(&["evaluate", "-p", &profile, &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("random kernels, ridge"), "{r:?}");
}

#[test]
fn lda_trains_classifies_and_evaluates_on_spectrum_and_kernels() {
    let dir = tempfile::tempdir().unwrap();
    let data = format!("{SMALL}/two-labels");
    let kernels = "features = \"kernels\"\nkernel_features = 840";
    for (name, analysis, header) in [
        ("spectrum", "", "profile tiny: LDA (Ledoit–Wolf shrinkage),"),
        (
            "kernels",
            kernels,
            "profile tiny: random kernels, LDA (Ledoit–Wolf shrinkage),",
        ),
    ] {
        let profile = tiny_with(
            dir.path(),
            &format!("{name}.toml"),
            analysis,
            "method = \"lda\"",
        );
        let model = dir.path().join(format!("{name}.json"));
        let r = run(&["train", "-p", &profile, "--out", p(&model), &data]);
        assert_eq!(r.code, Some(0), "{name}: {r:?}");
        assert!(
            r.stdout.contains("trained LDA on 6 recordings"),
            "{name}: {r:?}"
        );
        let saved: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
        assert_eq!(saved["format"], "hapticlab model v2", "{name}");
        assert_eq!(saved["classifier"]["method"], "lda", "{name}");
        assert_eq!(saved["lda"]["weights"].as_array().unwrap().len(), 2);
        assert_eq!(saved["lda"]["priors"], serde_json::json!([0.5, 0.5]));
        assert!(saved.get("ridge").is_none() && saved.get("scaling").is_none());
        assert_eq!(saved.get("kernels").is_some(), name == "kernels");
        let r = run(&["classify", "-p", &profile, "--model", p(&model), &data]);
        assert_eq!(r.code, Some(0), "{name}: {r:?}");
        // Each training scan predicted with itself left out (the LDA, and
        // the kernels, fitted again on the other five); no neighbours.
        assert_eq!(
            r.stdout.matches("left out of the model").count(),
            6,
            "{name}: {r:?}"
        );
        assert!(!r.stdout.contains("nearest"), "{name}: {r:?}");
        let r = run(&["evaluate", "-p", &profile, "--loo", &data]);
        assert_eq!(r.code, Some(0), "{name}: {r:?}");
        assert!(r.stdout.contains(header), "{name}: {r:?}");
        // tiny.toml's holdout trains on one recording a texture: there is
        // no covariance to shrink, and that is said, not scored.
        refused(
            &["evaluate", "-p", &profile, &data],
            &["no covariance to estimate", "two different examples"],
        );
    }
    // Under a profile's ridge the LDA model is not used silently.
    let ridge = tiny_with(dir.path(), "ridge.toml", "", "method = \"ridge\"");
    let model = dir.path().join("spectrum.json");
    let r = run(&["classify", "-p", &ridge, "--model", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stderr.contains("classifier.method = \"lda\""), "{r:?}");
}

#[test]
fn settings_the_families_cannot_use_are_refused_by_key() {
    let dir = tempfile::tempdir().unwrap();
    let data = format!("{SMALL}/two-labels");
    let few = tiny_with(
        dir.path(),
        "few.toml",
        "features = \"kernels\"\nkernel_features = 10",
        "",
    );
    refused(
        &["evaluate", "-p", &few, &data],
        &["analysis.kernel_features", "84 to 100000", "10"],
    );
    let unused = tiny_with(dir.path(), "unused.toml", "kernel_features = 840", "");
    refused(
        &["check", &unused],
        &[
            "analysis.kernel_features",
            "only used with features = \"kernels\"",
        ],
    );
    let word = tiny_with(dir.path(), "word.toml", "features = \"wavelets\"", "");
    refused(
        &["check", &word],
        &[
            "analysis.features",
            "\"spectrum\", \"kernels\", \"quantiles\" or \"hydra\"",
        ],
    );
    let method = tiny_with(dir.path(), "method.toml", "", "method = \"lasso\"");
    refused(
        &["check", &method],
        &["classifier.method", "\"knn\", \"ridge\" or \"lda\""],
    );
    let welch = tiny_with(
        dir.path(),
        "welch.toml",
        "features = \"quantiles\"\nwelch_segment = 8",
        "",
    );
    refused(
        &["check", &welch],
        &[
            "analysis.welch_segment",
            "only used with features = \"spectrum\"",
        ],
    );
}

/// `check` says what the classifier sees and which classifier: the kernels'
/// features made (not the points they are made of), no k for a ridge or
/// an LDA.
#[test]
fn check_names_the_family_and_the_classifier() {
    let dir = tempfile::tempdir().unwrap();
    for (i, (analysis, method, says)) in [
        (
            "features = \"kernels\"\nkernel_features = 200",
            "ridge",
            "168 random-kernel features (200 asked",
        ),
        (
            "features = \"quantiles\"",
            "lda",
            "interval-quantile features, LDA",
        ),
        // 16 points: one dilation, 64 groups of 8 kernels, wins and losses.
        (
            "features = \"hydra\"",
            "ridge",
            "1024 competing-kernel features, ridge",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let profile = tiny_with(
            dir.path(),
            &format!("{i}.toml"),
            analysis,
            &format!("method = \"{method}\""),
        );
        let r = run(&["check", &profile]);
        assert_eq!(r.code, Some(0), "{r:?}");
        assert!(r.stdout.contains(says), "{says}: {r:?}");
        assert!(
            r.stdout.contains(&format!(
                ", {}",
                if method == "lda" { "LDA" } else { method }
            )),
            "{r:?}"
        );
        assert!(!r.stdout.contains("k = "), "{r:?}");
    }
}

/// Competing kernels (Hydra) go through the same commands: nothing fitted
/// but the classifier, so the model file holds no kernels; a window
/// shorter than a kernel's span of the first difference is refused by key.
#[test]
fn competing_kernels_train_classify_and_evaluate() {
    let dir = tempfile::tempdir().unwrap();
    let data = format!("{SMALL}/two-labels");
    let profile = tiny_with(
        dir.path(),
        "h.toml",
        "features = \"hydra\"",
        "method = \"ridge\"",
    );
    let model = dir.path().join("m.json");
    let r = run(&["train", "-p", &profile, "--out", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(saved["analysis"]["features"], "hydra");
    assert!(
        saved.get("kernels").is_none(),
        "nothing of the features is fitted"
    );
    assert_eq!(saved["ridge"]["weights"].as_array().unwrap().len(), 2);
    let r = run(&["classify", "-p", &profile, "--model", p(&model), &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert_eq!(
        r.stdout.matches("left out of the model").count(),
        6,
        "{r:?}"
    );
    let r = run(&["evaluate", "-p", &profile, &data]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("competing kernels, ridge"), "{r:?}");
    // Under the spectrum the model is refused, as any family's.
    refused(
        &["classify", "-p", TINY, "--model", p(&model), &data],
        &["analysis.features", "\"hydra\"", "\"spectrum\""],
    );
    let text = std::fs::read_to_string(&profile).unwrap();
    let short = dir.path().join("short.toml");
    std::fs::write(
        &short,
        text.replace("window = [0.0, 0.015]", "window = [0.0, 0.008]"),
    )
    .unwrap();
    refused(
        &["check", p(&short)],
        &[
            "analysis.window",
            "9 points",
            "competing kernels need at least 10",
        ],
    );
}
