//! The model file: a [`Model`] saved as pretty-printed JSON with a
//! `format` tag ([`MODEL_FORMAT`]), loaded back with every part checked
//! (each error naming the file, and the line and column where JSON has
//! them), and the check that a profile's analysis settings are the ones
//! the model's features were made under. Never prints.

use std::io::{BufReader, Read, Write};

use serde::Deserialize;
use std::path::{Path, PathBuf};

use crate::io::OutputError;

use super::{ClassifyError, MODEL_FORMAT, MODEL_FORMAT_V2, Model, check_parts, sorted_labels};
use crate::profile::{Analysis, FeatureFamily, Method};

impl Model {
    /// Write the model as pretty-printed JSON, streamed to a temporary file
    /// then put in place ([`crate::io::write_output`]): refused when `path`
    /// is one of `inputs`, a recording or not a regular file, and when it
    /// exists unless `existing` says to replace it.
    pub fn save(
        &self,
        path: &Path,
        inputs: &[PathBuf],
        existing: crate::io::Existing,
    ) -> Result<(), OutputError> {
        crate::io::write_output(path, inputs, existing, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })
    }

    /// Read and check a model file, streamed into the model (no copy of
    /// its text or of a JSON tree is held; a huge model costs its
    /// examples and their prepared matrix). Only a regular file is read.
    pub fn load(path: &Path) -> Result<Model, ClassifyError> {
        let open = || {
            crate::io::open_input(path)
                .map(|f| BufReader::with_capacity(1 << 16, f))
                .map_err(|source| ClassifyError::Io {
                    path: path.to_path_buf(),
                    source,
                })
        };
        Self::parse(open()?, open, path)
    }

    /// Parse a model from its JSON text; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Model, ClassifyError> {
        Self::parse(text.as_bytes(), || Ok(text.as_bytes()), path)
    }

    /// Parses `first` into a model; when it is not one, `again` reads the
    /// same JSON once more for its `format` tag, so a file of another kind
    /// or version is named as such rather than by its first odd field.
    fn parse<R: Read>(
        first: R,
        again: impl FnOnce() -> Result<R, ClassifyError>,
        path: &Path,
    ) -> Result<Model, ClassifyError> {
        let mut de = serde_json::Deserializer::from_reader(first);
        let parsed = Model::deserialize(&mut de).and_then(|m| de.end().map(|()| m));
        let mut model = match parsed {
            Ok(m) if m.format == MODEL_FORMAT || m.format == MODEL_FORMAT_V2 => m,
            Ok(m) => {
                return Err(ClassifyError::WrongFormat {
                    path: path.to_path_buf(),
                    found: m.format,
                });
            }
            Err(e) if e.is_data() => {
                format_tag(again()?, path)?;
                return Err(ClassifyError::Schema {
                    path: path.to_path_buf(),
                    line: e.line(),
                    column: e.column(),
                    message: strip_position(&e),
                });
            }
            Err(e) => {
                return Err(ClassifyError::Malformed {
                    path: path.to_path_buf(),
                    line: e.line(),
                    column: e.column(),
                    message: strip_position(&e),
                });
            }
        };
        let invalid = |reason: String| ClassifyError::Invalid {
            path: path.to_path_buf(),
            reason,
        };
        check_parts(&model.analysis, &model.classifier, &model.examples)
            .map_err(|e| invalid(e.to_string()))?;
        if model.labels != sorted_labels(&model.examples) {
            return Err(invalid(
                "its labels are not the sorted distinct labels of its examples".to_string(),
            ));
        }
        check_fitted(&model).map_err(invalid)?;
        let knn = model.classifier.method == Method::Knn;
        match (&model.scaling, model.classifier.standardize && knn) {
            (Some(sc), true) => {
                let n = model.fitted_feature_count();
                if sc.mean.len() != n
                    || sc.scale.len() != n
                    || sc.scale.iter().any(|v| !(v.is_finite() && *v > 0.0))
                    || sc.mean.iter().any(|v| !v.is_finite())
                {
                    return Err(invalid(format!(
                        "its scaling must have {n} finite means and {n} positive finite scales"
                    )));
                }
            }
            (None, false) => {}
            // Classifying unscaled under `standardize = true` (or scaled
            // without it) is not the model that was trained.
            (None, true) => {
                return Err(invalid(
                    "classifier.standardize = true but it has no scaling; train it again".into(),
                ));
            }
            (Some(_), false) => {
                return Err(invalid(
                    "it has a scaling but classifier.standardize = false (or a ridge or an \
                     LDA, which need none of the model's); train it again"
                        .into(),
                ));
            }
        }
        model.prepare();
        // Scaled features so large that their distances overflow would
        // make every recording equally near: refused here, not met as NaN.
        if let Some(file) = model.unmeasurable_example() {
            return Err(invalid(format!(
                "example {file}'s features, scaled by its scaling, are too large to measure \
                 distances with (the means and scales are out of range); train it again"
            )));
        }
        Ok(model)
    }

    /// Using the model on features made with other analysis settings is an
    /// error naming the first field that differs.
    pub fn check_settings(&self, analysis: &Analysis) -> Result<(), ClassifyError> {
        // Every option that changes the features, from the one list.
        match crate::profile::options::first_difference(&self.analysis, analysis) {
            None => Ok(()),
            Some((field, model, profile)) => Err(ClassifyError::SettingsDiffer {
                field,
                model,
                profile,
            }),
        }
    }
}

/// What a model fitted beyond its examples, checked against its settings:
/// kernels exactly under `features = "kernels"`, a ridge exactly under
/// `method = "ridge"`, an LDA exactly under `method = "lda"`, each of the
/// sizes they give, and none in a v1 file (which predates them).
fn check_fitted(model: &Model) -> Result<(), String> {
    let a = &model.analysis;
    let wants_kernels = a.features == FeatureFamily::Kernels;
    let wants_ridge = model.classifier.method == Method::Ridge;
    let wants_lda = model.classifier.method == Method::Lda;
    if model.format == MODEL_FORMAT
        && (model.kernels.is_some() || model.ridge.is_some() || model.lda.is_some())
    {
        return Err(format!(
            "a {MODEL_FORMAT:?} file holds no kernels, ridge or LDA; its format should be {MODEL_FORMAT_V2:?}"
        ));
    }
    match (&model.kernels, wants_kernels) {
        (Some(k), true) => k.check(a.points(), 1 + a.channels.len(), a.kernel_features_asked())?,
        (None, false) => {}
        (None, true) => {
            return Err(
                "analysis.features = \"kernels\" but it has no kernels; train it again".into(),
            );
        }
        (Some(_), false) => {
            return Err(
                "it has kernels but analysis.features is not \"kernels\"; train it again".into(),
            );
        }
    }
    match (&model.ridge, wants_ridge) {
        (Some(r), true) => r.check(model.fitted_feature_count(), model.labels.len())?,
        (None, false) => {}
        (None, true) => {
            return Err("classifier.method = \"ridge\" but it has no ridge; train it again".into());
        }
        (Some(_), false) => {
            return Err(
                "it has a ridge but classifier.method is not \"ridge\"; train it again".into(),
            );
        }
    }
    match (&model.lda, wants_lda) {
        (Some(l), true) => l.check(model.fitted_feature_count(), model.labels.len()),
        (None, false) => Ok(()),
        (None, true) => Err("classifier.method = \"lda\" but it has no LDA; train it again".into()),
        (Some(_), false) => {
            Err("it has an LDA but classifier.method is not \"lda\"; train it again".into())
        }
    }
}

/// The `format` tag of JSON that is not a valid model: an error unless it
/// is this version's (then the model's own fields are at fault). The rest
/// of the document is skipped, not kept.
fn format_tag<R: Read>(r: R, path: &Path) -> Result<(), ClassifyError> {
    #[derive(serde::Deserialize)]
    struct Tag {
        format: Option<serde_json::Value>,
    }
    match serde_json::from_reader::<_, Tag>(r) {
        Ok(Tag {
            format: Some(serde_json::Value::String(f)),
        }) if f == MODEL_FORMAT || f == MODEL_FORMAT_V2 => Ok(()),
        Ok(Tag {
            format: Some(serde_json::Value::String(found)),
        }) => Err(ClassifyError::WrongFormat {
            path: path.to_path_buf(),
            found,
        }),
        _ => Err(ClassifyError::NotAModel {
            path: path.to_path_buf(),
        }),
    }
}

/// serde_json's message without its trailing " at line L column C" (we
/// print the position in front, compiler style).
fn strip_position(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}
