//! `[classifier]`: the method (k-NN, ridge or LDA), the k-NN's k (or
//! `"auto"` and its candidates), metric, vote weights and standardisation. Schema and checks only; the classifier
//! itself is `crate::classify`.

use serde::{Deserialize, Serialize};

use super::{Invalid, bad, is_default};

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    #[default]
    Euclidean,
    /// Sum of absolute differences (L1).
    Manhattan,
    /// 1 − cos(angle between the vectors); a zero vector is at distance 1.
    Cosine,
}

/// How the k nearest neighbours vote.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Weights {
    /// One vote each (the thesis).
    #[default]
    Uniform,
    /// Each votes 1 / distance (an exact match outvotes everything else).
    Distance,
}

/// Which classifier the model is.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// k nearest neighbours (the thesis).
    #[default]
    Knn,
    /// A ridge classifier, its penalty chosen by leave-one-out on the
    /// training examples (`k`, `metric` and `weights` are not used).
    Ridge,
    /// Linear discriminant analysis, its covariance shrunk by Ledoit and
    /// Wolf's intensity (`k`, `metric` and `weights` are not used).
    Lda,
}

impl Method {
    /// The classifier as a report names it: `k-NN`, `ridge`, `LDA`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Knn => "k-NN",
            Method::Ridge => "ridge",
            Method::Lda => "LDA",
        }
    }
}

/// `classifier.k = "auto"` is stored as this value of `k`.
pub const K_AUTO: usize = usize::MAX;

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Classifier {
    /// A number, or `"auto"` ([`K_AUTO`]): chosen by inner cross-validation
    /// on the training part among `k_candidates`.
    #[serde(deserialize_with = "k_or_auto", serialize_with = "write_k")]
    pub k: usize,
    #[serde(default)]
    pub metric: Metric,
    #[serde(default, skip_serializing_if = "is_default")]
    pub weights: Weights,
    /// Standardise every feature (mean 0, standard deviation 1) with the
    /// mean and deviation of the training examples, stored in the model.
    #[serde(default, skip_serializing_if = "is_default")]
    pub standardize: bool,
    /// The values `k = "auto"` tries (default 1, 3, 5, …, 15).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_candidates: Option<Vec<usize>>,
    /// k-NN (the default), ridge or LDA.
    #[serde(default, skip_serializing_if = "is_default")]
    pub method: Method,
}

impl Default for Classifier {
    /// The thesis's classifier.
    fn default() -> Self {
        Classifier {
            k: 10,
            metric: Metric::Euclidean,
            weights: Weights::Uniform,
            standardize: false,
            k_candidates: None,
            method: Method::Knn,
        }
    }
}

impl Classifier {
    pub fn k_is_auto(&self) -> bool {
        self.k == K_AUTO
    }
    /// `k` for people: a number or `auto`.
    pub fn k_text(&self) -> String {
        if self.k_is_auto() {
            "auto".into()
        } else {
            self.k.to_string()
        }
    }
}

/// What `k` may be, said the same way wherever a `k` is read (a profile, a
/// model, a sweep's value).
const K_EXPECTED: &str = "k must be a whole number ≥ 1 or \"auto\"";

fn k_or_auto<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    struct KVisitor;
    impl serde::de::Visitor<'_> for KVisitor {
        type Value = usize;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a whole number ≥ 1 or \"auto\"")
        }
        fn visit_u64<E: serde::de::Error>(self, n: u64) -> Result<usize, E> {
            match usize::try_from(n) {
                Ok(n) if n != K_AUTO => Ok(n),
                _ => Err(E::custom(format!(
                    "{K_EXPECTED}, got {n}, which is too large"
                ))),
            }
        }
        fn visit_i64<E: serde::de::Error>(self, n: i64) -> Result<usize, E> {
            match u64::try_from(n) {
                Ok(n) => self.visit_u64(n),
                Err(_) => Err(E::custom(format!("{K_EXPECTED}, got {n}"))),
            }
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<usize, E> {
            Err(E::custom(format!(
                "{K_EXPECTED}, got {}",
                crate::profile::compact(v)
            )))
        }
        fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<usize, E> {
            if s == "auto" {
                Ok(K_AUTO)
            } else {
                Err(E::custom(format!("{K_EXPECTED}, got {s:?}")))
            }
        }
    }
    d.deserialize_any(KVisitor)
}

fn write_k<S: serde::Serializer>(k: &usize, s: S) -> Result<S::Ok, S::Error> {
    if *k == K_AUTO {
        s.serialize_str("auto")
    } else {
        s.serialize_u64(*k as u64)
    }
}

/// Check `[classifier]` on its own (its `k` against the training set is
/// checked with `[evaluation]`).
pub(super) fn validate(c: &Classifier) -> Result<(), Invalid> {
    if c.k == 0 {
        return bad("classifier.k", "must be at least 1");
    }
    if let Some(c) = &c.k_candidates
        && (c.is_empty() || c.contains(&0) || c.contains(&K_AUTO))
    {
        return bad(
            "classifier.k_candidates",
            "must list whole numbers of at least 1",
        );
    }
    Ok(())
}
