//! The model file: a [`Model`] saved as pretty-printed JSON with a
//! `format` tag ([`MODEL_FORMAT`]), loaded back with every part checked
//! (each error naming the file, and the line and column where JSON has
//! them), and the check that a profile's analysis settings are the ones
//! the model's features were made under. Never prints.

use std::path::Path;

use super::{ClassifyError, MODEL_FORMAT, Model, check_parts, json, sorted_labels};
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
        match (&model.scaling, model.classifier.standardize) {
            (Some(sc), true) => {
                let n = model.feature_count();
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
                    "it has a scaling but classifier.standardize = false; train it again".into(),
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
        let (m, p) = (&self.analysis, analysis);
        let differ = |field: &'static str, model: String, profile: String| {
            Err(ClassifyError::SettingsDiffer {
                field,
                model,
                profile,
            })
        };
        if m.channel != p.channel {
            return differ("analysis.channel", json(&m.channel), json(&p.channel));
        }
        if m.axis != p.axis {
            return differ("analysis.axis", json(&m.axis), json(&p.axis));
        }
        if m.window != p.window {
            return differ("analysis.window", json(&m.window), json(&p.window));
        }
        if m.spacing != p.spacing {
            return differ("analysis.spacing", json(&m.spacing), json(&p.spacing));
        }
        if m.detrend != p.detrend {
            return differ("analysis.detrend", json(&m.detrend), json(&p.detrend));
        }
        if m.spectrum != p.spectrum {
            return differ("analysis.spectrum", json(&m.spectrum), json(&p.spectrum));
        }
        if m.bands != p.bands {
            return differ("analysis.bands", json(&m.bands), json(&p.bands));
        }
        if m.cepstra != p.cepstra {
            return differ("analysis.cepstra", json(&m.cepstra), json(&p.cepstra));
        }
        if m.drop_level != p.drop_level {
            return differ(
                "analysis.drop_level",
                json(&m.drop_level),
                json(&p.drop_level),
            );
        }
        if m.bins != p.bins && m.band.is_none() && m.bands.is_none() {
            return differ("analysis.bins", json(&m.bins), json(&p.bins));
        }
        if m.channels != p.channels {
            return differ("analysis.channels", json(&m.channels), json(&p.channels));
        }
        if m.taper != p.taper {
            return differ("analysis.taper", json(&m.taper), json(&p.taper));
        }
        if m.band != p.band {
            return differ("analysis.band", json(&m.band), json(&p.band));
        }
        if m.dft_points() != p.dft_points() {
            return differ(
                "analysis.welch_segment",
                json(&m.welch_segment),
                json(&p.welch_segment),
            );
        }
        if m.overlap() != p.overlap() && m.spectrum.is_welch() {
            return differ(
                "analysis.welch_overlap",
                json(&m.welch_overlap),
                json(&p.welch_overlap),
            );
        }
        Ok(())
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
