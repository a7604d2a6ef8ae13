//! The model file: a [`Model`] saved as pretty-printed JSON with a
//! `format` tag ([`MODEL_FORMAT`]), loaded back with every part checked
//! (each error naming the file, and the line and column where JSON has
//! them), and the check that a profile's analysis settings are the ones
//! the model's features were made under. Never prints.

use std::path::Path;

use super::{ClassifyError, MODEL_FORMAT, Model, check_parts, sorted_labels};
use crate::profile::Analysis;

impl Model {
    /// Write the model as pretty-printed JSON.
    pub fn save(&self, path: &Path) -> Result<(), ClassifyError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| ClassifyError::Invalid {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        text.push('\n');
        std::fs::write(path, text).map_err(|source| ClassifyError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Read and check a model file.
    pub fn load(path: &Path) -> Result<Model, ClassifyError> {
        let text = std::fs::read_to_string(path).map_err(|source| ClassifyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// Parse a model from its JSON text; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Model, ClassifyError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| ClassifyError::Malformed {
                path: path.to_path_buf(),
                line: e.line(),
                column: e.column(),
                message: strip_position(&e),
            })?;
        match value.get("format") {
            Some(serde_json::Value::String(f)) if f == MODEL_FORMAT => {}
            Some(serde_json::Value::String(f)) => {
                return Err(ClassifyError::WrongFormat {
                    path: path.to_path_buf(),
                    found: f.clone(),
                });
            }
            _ => {
                return Err(ClassifyError::NotAModel {
                    path: path.to_path_buf(),
                });
            }
        }
        // Parse the text again (not the value) so schema errors carry a line and column.
        let mut model: Model = serde_json::from_str(text).map_err(|e| ClassifyError::Schema {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: strip_position(&e),
        })?;
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
        if let Some(sc) = &model.scaling {
            let n = model.feature_count();
            if sc.mean.len() != n
                || sc.scale.len() != n
                || sc.scale.iter().any(|v| !(v.is_finite() && *v > 0.0))
                || sc.mean.iter().any(|v| !v.is_finite())
            {
                return Err(invalid(format!(
                    "its scaling must have {n} finite means and {n} positive scales"
                )));
            }
        }
        model.prepare();
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

/// serde_json's message without its trailing " at line L column C" (we
/// print the position in front, compiler style).
fn strip_position(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}
