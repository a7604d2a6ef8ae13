//! Experiment profiles: the TOML schema, its loading and its validation.
//!
//! Everything an experiment depends on lives in a profile, one section per
//! module: [`device`], [`controller`], [`path`], [`analysis`],
//! [`classifier`], [`evaluation`], [`textures`], [`simulator`], [`console`]
//! and [`hardware`] (`[falcon]`, `[[triggers]]`, `[simulator.faults]`), each
//! owning its schema and its part of [`Profile::validate`]; [`locate`] finds
//! the line and column of a key in the text. Unknown keys are rejected by
//! serde; `validate()` then checks every value and names the file, line,
//! column and key of what is wrong.
//!
//! The profile is the ground layer: it depends on nothing in the crate but
//! the recording format's label rule (`crate::recording::check_label`), so
//! the engine (device, servo, analysis, classifier) can depend on it. Checks
//! that need arithmetic on the settings (DFT bins, the Falcon's reach) live
//! here with the settings, and the engine uses them from here. This module
//! never touches a device or a file other than the profile.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

pub mod analysis;
pub mod classifier;
pub mod console;
pub mod controller;
pub mod device;
pub mod evaluation;
pub mod falcon_reach;
pub mod families;
pub mod fitted;
pub mod hardware;
pub mod locate;
pub mod options;
pub mod path;
pub mod simulator;
pub mod textures;
pub mod tuned;

/// The one label rule, owned by the recording format.
pub use crate::recording::check_label;
pub use analysis::{
    Analysis, BandScale, Bands, Detrend, LOG_FLOOR, SpectrumKind, Taper, Windows, check_options,
    check_points, check_windows,
};
pub use classifier::{Classifier, K_AUTO, Method, Metric, Weights};
pub use console::{CONSOLE_ACTIONS, ConsoleSettings, KeySpec, NAMED_KEYS, parse_key};
pub use controller::Controller;
pub use device::{
    DEVICE_MAX_FORCE_N, Device, DeviceKind, Realtime, WORKSPACE_MAX_M, WORKSPACE_MIN_M,
};
pub use evaluation::{Evaluation, SplitMethod};
pub use families::FeatureFamily;
pub use locate::{line_col, locate_key};
pub use path::PathSpec;
pub use simulator::Simulator;
pub use textures::{Surface, Texture};

/// The thesis profile, compiled in so that `hapticlab` works from any folder.
pub const THESIS_PROFILE: &str = include_str!("../../profiles/thesis.toml");

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// The rig that makes scans: `[device]`, `[controller]` and `[path]`.
    /// A profile that only analyses recordings has none of them (see
    /// [`Profile::rig`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<Device>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<Controller>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathSpec>,
    pub analysis: Analysis,
    pub classifier: Classifier,
    pub evaluation: Evaluation,
    #[serde(default)]
    pub textures: Vec<Texture>,
    #[serde(default)]
    pub simulator: Simulator,
    /// The lab console's settings (optional).
    #[serde(default)]
    pub console: ConsoleSettings,
    /// The Novint Falcon and its emulator (`device.kind = "falcon"`, `"falcon-emulator"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub falcon: Option<hardware::FalconSection>,
    /// Hands-free triggers: HID foot switches and button boxes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub triggers: Vec<hardware::TriggerSpec>,
}

/// A profile as loaded: the values, where they came from, and the digest of
/// the exact text (recorded in every recording as `profile_sha256`).
#[derive(Debug, Clone)]
pub struct LoadedProfile {
    pub profile: Profile,
    pub origin: String,
    /// The folder relative paths in the profile resolve against.
    pub base_dir: PathBuf,
    pub sha256: String,
    /// Tune's mark, in a profile `tune` wrote.
    pub tuned_on: Option<tuned::TunedOn>,
}

/// A profile that cannot be used: where, which key, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileError {
    pub origin: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub key: Option<String>,
    pub reason: String,
}

impl fmt::Display for ProfileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.origin)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        write!(f, ": ")?;
        if let Some(key) = &self.key {
            write!(f, "{key}: ")?;
        }
        write!(f, "{}", self.reason)
    }
}

impl std::error::Error for ProfileError {}

pub fn sha256_hex(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// Where the built-in thesis profile says it came from.
const BUILT_IN: &str = "<built-in thesis profile>";

impl LoadedProfile {
    /// The built-in thesis profile.
    pub fn thesis() -> LoadedProfile {
        Self::from_str(THESIS_PROFILE, BUILT_IN, Path::new("."))
            .expect("the built-in thesis profile is valid")
    }

    /// Whether this is the built-in thesis profile (what a command uses
    /// without `-p`), rather than a file.
    pub fn is_built_in(&self) -> bool {
        self.origin == BUILT_IN
    }

    /// Load a profile file, or the built-in one for the name `thesis` when no such file exists.
    pub fn load(path: &Path) -> Result<LoadedProfile, ProfileError> {
        if path.as_os_str() == "thesis" && !path.exists() {
            return Ok(Self::thesis());
        }
        let origin = path.display().to_string();
        let text = crate::io::read_input_to_string(path).map_err(|e| ProfileError {
            origin: origin.clone(),
            line: None,
            column: None,
            key: None,
            reason: format!("cannot read the profile: {}", crate::io::said(&e)),
        })?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        Self::from_str(&text, &origin, &base)
    }

    pub fn from_str(
        text: &str,
        origin: &str,
        base_dir: &Path,
    ) -> Result<LoadedProfile, ProfileError> {
        // A check that failed, placed at its key's line in the file.
        let at_key = |v: Invalid| {
            let (line, column) = locate_key(text, &v.key);
            ProfileError {
                origin: origin.to_string(),
                line,
                column,
                key: Some(v.key),
                reason: v.reason,
            }
        };
        // A word an option does not take, said from the option's
        // declaration (before serde's message, which names no key).
        let doc: Option<toml::Table> = toml::from_str(text).ok();
        if let Some(v) = doc.as_ref().and_then(options::check_written) {
            return Err(at_key(v));
        }
        let profile: Profile = toml::from_str(text).map_err(|e| {
            let (line, column) = match e.span() {
                Some(span) => line_col(text, span.start),
                None => (None, None),
            };
            let reason = e.message().trim().to_string();
            // TOML's "duplicate key" names no key: read it from the line.
            let duplicate = e
                .span()
                .filter(|_| reason.starts_with("duplicate key"))
                .and_then(|span| locate::duplicate_key(text, span.start));
            let (key, reason) = match duplicate {
                Some((key, reason)) => (Some(key), reason),
                None => (None, reason),
            };
            ProfileError {
                origin: origin.to_string(),
                line,
                column,
                key,
                reason,
            }
        })?;
        if let Some(v) = doc.as_ref().and_then(one_feature_choice) {
            return Err(at_key(v));
        }
        let mut profile = profile;
        profile.resolve_window();
        profile.validate().map_err(at_key)?;
        Ok(LoadedProfile {
            profile,
            origin: origin.to_string(),
            base_dir: base_dir.to_path_buf(),
            sha256: sha256_hex(text.as_bytes()),
            tuned_on: tuned::TunedOn::find(text),
        })
    }

    /// The rig, or an error naming the missing sections and this file.
    pub fn rig(&self) -> Result<Rig<'_>, MissingRig> {
        self.profile.rig().map_err(|e| MissingRig {
            origin: Some(self.origin.clone()),
            ..e
        })
    }

    /// A file path named in the profile, resolved against the profile's folder.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        }
    }
}

/// `bins`, `band` and `bands` each choose the features kept, and `bins` has
/// a default, so only the text tells whether it was written beside one of
/// the others (which would silently win): the first pair written, refused.
fn one_feature_choice(doc: &toml::Table) -> Option<Invalid> {
    let analysis = doc.get("analysis")?.as_table()?;
    let written: Vec<&str> = ["bins", "band", "bands"]
        .into_iter()
        .filter(|k| analysis.contains_key(*k))
        .collect();
    match written[..] {
        [first, second, ..] => Some(Invalid {
            key: format!("analysis.{second}"),
            reason: format!(
                "`{first}` and `{second}` both choose the features kept: keep one of them"
            ),
        }),
        _ => None,
    }
}

/// A value that fails validation: its dotted key and the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    pub key: String,
    pub reason: String,
}

fn bad(key: impl Into<String>, reason: impl Into<String>) -> Result<(), Invalid> {
    Err(Invalid {
        key: key.into(),
        reason: reason.into(),
    })
}

/// A number as people read it when a value is echoed back: as written in
/// the usual range, in exponent form beyond it (`1e-300`, not 300 zeros).
pub fn compact(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn finite_pos(key: &str, v: f64) -> Result<(), Invalid> {
    if !(v.is_finite() && v > 0.0) {
        return bad(
            key,
            format!("must be a positive number, got {}", compact(v)),
        );
    }
    Ok(())
}

fn finite_nonneg(key: &str, v: f64) -> Result<(), Invalid> {
    if !(v.is_finite() && v >= 0.0) {
        return bad(key, format!("must be zero or more, got {}", compact(v)));
    }
    Ok(())
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

impl Profile {
    /// Check every value, section by section in the file's order; the first
    /// problem found is returned with its key.
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.name.trim().is_empty() {
            return bad("name", "must not be empty");
        }
        if let Some(d) = &self.device {
            device::validate(d)?;
        }
        if let Some(c) = &self.controller {
            controller::validate(c)?;
        }
        if let Some(p) = &self.path {
            path::validate(p)?;
        }
        analysis::validate(&self.analysis, self.path.as_ref())?;
        classifier::validate(&self.classifier)?;
        evaluation::validate(&self.evaluation, &self.classifier, self.textures.len())?;
        textures::validate(&self.textures)?;
        simulator::validate(&self.simulator, self.device.as_ref().map(|d| d.rate_hz))?;
        hardware::validate_sim_faults(self)?;
        self.console.bindings()?;
        hardware::validate(self)
    }

    pub fn texture(&self, label: &str) -> Option<&Texture> {
        self.textures.iter().find(|t| t.label == label)
    }

    /// The scan leg's extent along `axis`: its travel along a position
    /// axis (`x_m`, `y_m`, `z_m`), metres, or its duration with the dwell
    /// (`t_s`), seconds. `None` for another axis or an invalid path.
    pub fn scan_leg_extent(&self, axis: &str) -> Option<f64> {
        let p = self.path.as_ref()?;
        if p.scan_leg == 0 || p.scan_leg >= p.waypoints_m.len() {
            return None;
        }
        let (a0, a1) = (p.waypoints_m[p.scan_leg - 1], p.waypoints_m[p.scan_leg]);
        match axis {
            "x_m" => Some((a1[0] - a0[0]).abs()),
            "y_m" => Some((a1[1] - a0[1]).abs()),
            "z_m" => Some((a1[2] - a0[2]).abs()),
            "t_s" => Some(dist(a0, a1) / p.speed_m_per_s + p.dwell_s),
            _ => None,
        }
    }

    /// Work out `window = "scan-leg"`: [0, the leg's extent along the
    /// axis]. Call after deserialising, before [`Self::validate`] (which
    /// refuses the unresolved [0, +inf]); again after changing the path.
    pub fn resolve_window(&mut self) {
        if self.analysis.window == analysis::SCAN_LEG {
            self.analysis.window_is_scan_leg = true;
        }
        if self.analysis.window_is_scan_leg
            && let Some(e) = self.scan_leg_extent(&self.analysis.axis)
            && e.is_finite()
            && e > 0.0
        {
            self.analysis.window = [0.0, e];
        }
    }

    /// The rig that makes scans, when the profile has all of it; otherwise
    /// which of `[device]`, `[controller]` and `[path]` are missing (the
    /// profile is then analysis only).
    pub fn rig(&self) -> Result<Rig<'_>, MissingRig> {
        match (&self.device, &self.controller, &self.path) {
            (Some(device), Some(controller), Some(path)) => Ok(Rig {
                device,
                controller,
                path,
            }),
            (d, c, p) => Err(MissingRig {
                origin: None,
                profile: self.name.clone(),
                missing: [
                    (d.is_none(), "[device]"),
                    (c.is_none(), "[controller]"),
                    (p.is_none(), "[path]"),
                ]
                .into_iter()
                .filter_map(|(gone, name)| gone.then_some(name))
                .collect(),
            }),
        }
    }

    /// No `[device]`, `[controller]` nor `[path]`: the profile analyses
    /// recordings and makes none.
    pub fn is_analysis_only(&self) -> bool {
        self.device.is_none() && self.controller.is_none() && self.path.is_none()
    }
}

/// The sections a profile needs to make scans, borrowed from it: what the
/// servo loop, the devices, `scan`, `simulate` and the live console run on.
#[derive(Debug, Clone, Copy)]
pub struct Rig<'a> {
    pub device: &'a Device,
    pub controller: &'a Controller,
    pub path: &'a PathSpec,
}

impl Rig<'_> {
    /// Length of the scan leg, metres.
    pub fn scan_leg_length_m(&self) -> f64 {
        dist(
            self.path.waypoints_m[self.path.scan_leg - 1],
            self.path.waypoints_m[self.path.scan_leg],
        )
    }
}

/// A profile without a rig asked to make scans: which sections it lacks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingRig {
    /// The profile file, when known ([`LoadedProfile::rig`]).
    pub origin: Option<String>,
    /// The profile's name.
    pub profile: String,
    /// The sections missing, as `[device]`, `[controller]`, `[path]`.
    pub missing: Vec<&'static str>,
}

impl MissingRig {
    /// The missing sections in words: `[path]`, `[device] or [path]`,
    /// `[device], [controller] or [path]`.
    pub fn sections(&self) -> String {
        match self.missing.split_last() {
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }
}

impl fmt::Display for MissingRig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = format!("no {} section", self.sections());
        match &self.origin {
            Some(o) => write!(f, "{o}: ")?,
            None => write!(f, "profile {:?}: ", self.profile)?,
        }
        write!(
            f,
            "{what}: it analyses recordings only (features, train, classify, evaluate, inspect, plot, replay); \
             making scans needs a rig: [device], [controller] and [path] (see profiles/thesis.toml)"
        )
    }
}

impl std::error::Error for MissingRig {}

pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_profile_loads_and_validates() {
        let p = LoadedProfile::thesis();
        assert_eq!(p.profile.name, "thesis");
        assert_eq!(p.profile.analysis.points(), 100);
        assert_eq!(p.profile.analysis.feature_count(), 49);
        assert_eq!(p.profile.classifier.k, 10);
        assert_eq!(p.profile.textures.len(), 4);
        assert_eq!(p.sha256.len(), 64);
    }

    #[test]
    fn a_table_written_twice_is_named_with_its_first_header() {
        let text = THESIS_PROFILE.replace("[evaluation]\n", "[evaluation]\n[evaluation]\n");
        let e = LoadedProfile::from_str(&text, "p.toml", Path::new(".")).unwrap_err();
        let first = text.lines().position(|l| l == "[evaluation]").unwrap() + 1;
        assert_eq!(e.key.as_deref(), Some("evaluation"), "{e}");
        assert!(
            e.to_string().contains(&format!(
                "the table `[evaluation]` is written twice (first at line {first})"
            )),
            "{e}"
        );
    }
}
