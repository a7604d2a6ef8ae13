//! `[evaluation]`: how `evaluate` splits the recordings (holdout, k-fold,
//! leave-one-out, grouped by a metadata key). Schema and checks only; the
//! splitting is `crate::evaluate`.

use serde::{Deserialize, Serialize};

use super::classifier::{Classifier, Method};
use super::{Invalid, bad, is_default};

/// How `evaluate` splits the recordings.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SplitMethod {
    /// One split: `train_per_class` then `test_per_class` of each class (the thesis).
    #[default]
    Holdout,
    /// `folds`-fold cross-validation, stratified by class (or by group with `group_by`).
    KFold,
    /// Each recording (or each group, with `group_by`) tested once against all the others.
    LeaveOneOut,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Evaluation {
    /// Holdout only (required there): recordings of each class trained on.
    /// K-fold and leave-one-out need neither count (0 when not given).
    #[serde(default)]
    pub train_per_class: usize,
    #[serde(default)]
    pub test_per_class: usize,
    /// Holdout only: recordings of each class left out between the
    /// training and the test ones (as scikit-learn's `TimeSeriesSplit`'s
    /// `gap`), so overlapping segments of one long recording (`import
    /// --split-hop` below `--split`) share no signal across the split.
    #[serde(default, skip_serializing_if = "is_default")]
    pub gap_per_class: usize,
    /// When set, each class's recordings are shuffled with this seed before
    /// the split; otherwise they are taken in file-name order.
    #[serde(default)]
    pub shuffle_seed: Option<u64>,
    #[serde(default, skip_serializing_if = "is_default")]
    pub method: SplitMethod,
    /// Folds of `k-fold` (default 10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// A metadata key (`session`, `trial`, …): recordings sharing its value
    /// are always on the same side of a split.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group_by: Option<String>,
}

impl Evaluation {
    /// Recordings of each class a holdout takes: trained on, left out
    /// between, tested.
    pub fn holdout_needs(&self) -> usize {
        self.train_per_class + self.gap_per_class + self.test_per_class
    }

    /// How a holdout takes them, for a message: "5 to train, 2 left out,
    /// 5 to test" (the middle part only with `gap_per_class`).
    pub fn holdout_parts(&self) -> String {
        let gap = if self.gap_per_class > 0 {
            format!("{} left out, ", self.gap_per_class)
        } else {
            String::new()
        };
        format!(
            "{} to train, {gap}{} to test",
            self.train_per_class, self.test_per_class
        )
    }
}

impl Default for Evaluation {
    fn default() -> Self {
        Evaluation {
            train_per_class: 20,
            test_per_class: 10,
            gap_per_class: 0,
            shuffle_seed: None,
            method: SplitMethod::Holdout,
            folds: None,
            group_by: None,
        }
    }
}

/// Check `[evaluation]`, and the classifier's `k` against the training set
/// it gives (`textures` classes of `train_per_class` each). A profile
/// without `[[textures]]` (an analysis-only one) does not know its labels
/// until the recordings are read: its `k` is checked against the training
/// examples then (20 labels of 5 trials train 100, so k = 9 is fine).
pub(super) fn validate(
    e: &Evaluation,
    classifier: &Classifier,
    textures: usize,
) -> Result<(), Invalid> {
    match (e.method, e.folds) {
        (SplitMethod::KFold, Some(f)) if f < 2 => {
            return bad("evaluation.folds", "must be at least 2");
        }
        (SplitMethod::Holdout | SplitMethod::LeaveOneOut, Some(_)) => {
            return bad("evaluation.folds", "is only used with method = \"k-fold\"");
        }
        _ => {}
    }
    if e.gap_per_class > 0 && e.method != SplitMethod::Holdout {
        return bad(
            "evaluation.gap_per_class",
            "is only used with method = \"holdout\" (the recordings left out between its training and test ones)",
        );
    }
    if e.group_by.as_deref() == Some("") {
        return bad("evaluation.group_by", "must name a metadata key");
    }
    if e.method == SplitMethod::Holdout && e.train_per_class == 0 {
        return bad(
            "evaluation.train_per_class",
            "must be at least 1 (method = \"holdout\" splits by it)",
        );
    }
    // A ridge or an LDA has no k to check.
    if e.train_per_class > 0
        && textures > 0
        && classifier.method == Method::Knn
        && !classifier.k_is_auto()
        && classifier.k > e.train_per_class * textures
    {
        return bad(
            "classifier.k",
            format!(
                "k = {} exceeds the training set ({} per class)",
                classifier.k, e.train_per_class
            ),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(toml_text: &str) -> Result<(), Invalid> {
        let e: Evaluation = toml::from_str(toml_text).unwrap();
        validate(&e, &Classifier::default(), 4)
    }

    #[test]
    fn only_the_holdout_demands_train_per_class() {
        assert!(check("method = \"leave-one-out\"").is_ok());
        assert!(check("method = \"k-fold\"").is_ok());
        assert!(check("method = \"k-fold\"\nfolds = 5").is_ok());
        assert!(check("train_per_class = 20\ntest_per_class = 10").is_ok());
        let err = format!("{:?}", check("test_per_class = 10").unwrap_err());
        assert!(err.contains("train_per_class"), "{err}");
        assert!(check("method = \"leave-one-out\"\nfolds = 3").is_err());
    }

    #[test]
    fn a_gap_is_only_for_the_holdout() {
        assert!(check("train_per_class = 5\ntest_per_class = 4\ngap_per_class = 1").is_ok());
        let err = format!(
            "{:?}",
            check("method = \"k-fold\"\ngap_per_class = 1").unwrap_err()
        );
        assert!(err.contains("evaluation.gap_per_class"), "{err}");
    }

    #[test]
    fn k_is_checked_against_the_training_set_where_the_labels_are_known() {
        let e: Evaluation = toml::from_str("train_per_class = 5\ntest_per_class = 5").unwrap();
        let k = |k| Classifier {
            k,
            ..Classifier::default()
        };
        assert!(validate(&e, &k(20), 4).is_ok());
        let err = format!("{:?}", validate(&e, &k(21), 4).unwrap_err());
        assert!(err.contains("exceeds the training set"), "{err}");
        // No [[textures]]: the labels come with the recordings.
        assert!(validate(&e, &k(9), 0).is_ok());
        // A ridge or an LDA does not use k.
        for method in [Method::Ridge, Method::Lda] {
            let c = Classifier { method, ..k(21) };
            assert!(validate(&e, &c, 4).is_ok(), "{method:?}");
        }
    }
}
