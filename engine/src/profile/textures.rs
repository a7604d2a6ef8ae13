//! `[[textures]]`: each texture's label (the one label rule of
//! `crate::recording`), description, published dimensions and surface
//! model. Schema and checks only; the simulator builds the surfaces.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::{Invalid, bad, finite_nonneg, finite_pos};
use crate::recording::check_label;

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Texture {
    pub label: String,
    #[serde(default)]
    pub description: String,
    /// Dimensions as published (e.g. Table 3.2's A, B, C), for display.
    #[serde(default)]
    pub dimensions_mm: BTreeMap<String, f64>,
    pub surface: Surface,
}

/// A texture's height profile along x, before the probe's dilation.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Surface {
    /// Flat with random micro-roughness (a seeded sum of sinusoids).
    Flat {
        roughness_rms_m: f64,
        correlation_length_m: f64,
    },
    /// Periodic trapezoidal corrugation: crest, falling flank, trough, rising flank.
    Trapezoid {
        crest_m: f64,
        depth_m: f64,
        trough_m: f64,
        flank_m: f64,
        #[serde(default)]
        roughness_rms_m: f64,
    },
    Sine {
        amplitude_m: f64,
        period_m: f64,
    },
    /// Heights against x from a CSV file with columns `x_m,height_m`
    /// (path relative to the profile's folder).
    Csv {
        path: PathBuf,
    },
}

impl Surface {
    /// The spatial period, where the surface has one.
    pub fn period_m(&self) -> Option<f64> {
        match self {
            Surface::Trapezoid {
                crest_m,
                trough_m,
                flank_m,
                ..
            } => Some(crest_m + trough_m + 2.0 * flank_m),
            Surface::Sine { period_m, .. } => Some(*period_m),
            _ => None,
        }
    }
}

/// Check `[[textures]]`: safe, distinct labels and sound surfaces.
pub(super) fn validate(textures: &[Texture]) -> Result<(), Invalid> {
    let mut seen = std::collections::BTreeSet::new();
    for (i, t) in textures.iter().enumerate() {
        let key = format!("textures[{i}]");
        if let Err(reason) = check_label(&t.label) {
            return bad(format!("{key}.label"), reason);
        }
        if !seen.insert(t.label.clone()) {
            return bad(
                format!("{key}.label"),
                format!("label {:?} appears twice", t.label),
            );
        }
        let sk = format!("{key}.surface");
        match &t.surface {
            Surface::Flat {
                roughness_rms_m,
                correlation_length_m,
            } => {
                finite_nonneg(&format!("{sk}.roughness_rms_m"), *roughness_rms_m)?;
                finite_pos(&format!("{sk}.correlation_length_m"), *correlation_length_m)?;
            }
            Surface::Trapezoid {
                crest_m,
                depth_m,
                trough_m,
                flank_m,
                roughness_rms_m,
            } => {
                finite_nonneg(&format!("{sk}.crest_m"), *crest_m)?;
                finite_pos(&format!("{sk}.depth_m"), *depth_m)?;
                finite_nonneg(&format!("{sk}.trough_m"), *trough_m)?;
                finite_nonneg(&format!("{sk}.flank_m"), *flank_m)?;
                finite_nonneg(&format!("{sk}.roughness_rms_m"), *roughness_rms_m)?;
                if crest_m + trough_m + 2.0 * flank_m < 1e-4 {
                    return bad(
                        sk,
                        "the period (crest + trough + 2 flanks) must be at least 0.1 mm",
                    );
                }
            }
            Surface::Sine {
                amplitude_m,
                period_m,
            } => {
                finite_nonneg(&format!("{sk}.amplitude_m"), *amplitude_m)?;
                if !(period_m.is_finite() && *period_m >= 1e-4) {
                    return bad(format!("{sk}.period_m"), "must be at least 0.1 mm");
                }
            }
            Surface::Csv { path } => {
                if path.as_os_str().is_empty() {
                    return bad(format!("{sk}.path"), "must name a CSV file");
                }
            }
        }
    }
    Ok(())
}
