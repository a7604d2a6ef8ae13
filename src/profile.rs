//! Experiment profiles: the TOML schema, its loading and its validation.
//!
//! Everything an experiment depends on lives in a profile: the device, the
//! controller gains, the waypoint path, the analysis, the classifier, the
//! evaluation split, the textures and the simulator. Unknown keys are
//! rejected by serde; `validate()` then checks every value and names the
//! file, line, column and key of what is wrong. This module never touches a
//! device or a file other than the profile (and a texture's CSV, which the
//! simulator reads).

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

pub mod hardware;

/// The thesis profile, compiled in so that `hapticlab` works from any folder.
pub const THESIS_PROFILE: &str = include_str!("../profiles/thesis.toml");

/// What the device kinds can reach, in the profile frame (the thesis's frame:
/// x along the stroke, y vertical and up, z towards the user), in metres.
/// The Novint SDK frame the thesis used spans about 10 cm on each axis
/// (section 3.1.1); its z range is offset because Table 3.1 works at z = −2…−6 cm.
pub const WORKSPACE_MIN_M: [f64; 3] = [-0.05, -0.05, -0.07];
pub const WORKSPACE_MAX_M: [f64; 3] = [0.05, 0.05, 0.03];
/// The Falcon's largest continuous force (CHAI3D's figure), per axis, in newtons.
pub const DEVICE_MAX_FORCE_N: f64 = 8.0;

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub device: Device,
    pub controller: Controller,
    pub path: PathSpec,
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

/// The lab console's settings: `[console]` in a profile.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ConsoleSettings {
    /// Key bindings that replace the defaults, action name → key, e.g.
    /// `keys = { start = "F5", store = "Ctrl-s" }`. Actions are listed in
    /// [`CONSOLE_ACTIONS`]; keys are written as [`parse_key`] reads them.
    #[serde(default)]
    pub keys: BTreeMap<String, String>,
}

/// The console's actions and their default keys.
pub const CONSOLE_ACTIONS: &[(&str, &str)] = &[
    ("help", "?"),
    ("quit", "q"),
    ("mode", "m"),
    ("target", "t"),
    ("start", "s"),
    ("abort", "Esc"),
    ("store", "w"),
    ("label", "l"),
    ("queue", "n"),
    ("predict", "p"),
    ("train", "T"),
    ("evaluate", "e"),
    ("replay", "r"),
    ("faster", "+"),
    ("slower", "-"),
    ("left", "Left"),
    ("right", "Right"),
    ("up", "Up"),
    ("down", "Down"),
    ("away", "PageUp"),
    ("toward", "PageDown"),
    ("next_page", "Tab"),
    ("prev_page", "BackTab"),
    ("page_1", "1"),
    ("page_2", "2"),
    ("page_3", "3"),
    ("page_4", "4"),
    ("pause", "Space"),
    ("step", "."),
];

/// The named (non-character) keys a binding may use.
pub const NAMED_KEYS: &[&str] = &[
    "Esc",
    "Enter",
    "Tab",
    "BackTab",
    "Space",
    "Backspace",
    "Delete",
    "Insert",
    "Home",
    "End",
    "Up",
    "Down",
    "Left",
    "Right",
    "PageUp",
    "PageDown",
    "F1",
    "F2",
    "F3",
    "F4",
    "F5",
    "F6",
    "F7",
    "F8",
    "F9",
    "F10",
    "F11",
    "F12",
];

/// One key as a profile writes it: a character (`s`, `T`, `+`), a named
/// key (`Esc`, `PageUp`, `F5`), or `Ctrl-` and a letter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KeySpec {
    Char(char),
    Named(&'static str),
    Ctrl(char),
}

impl fmt::Display for KeySpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeySpec::Char(c) => write!(f, "{c}"),
            KeySpec::Named(n) => write!(f, "{n}"),
            KeySpec::Ctrl(c) => write!(f, "Ctrl-{c}"),
        }
    }
}

/// Read a key as written in `[console] keys`. Ctrl-C is reserved (it always quits).
pub fn parse_key(text: &str) -> Result<KeySpec, String> {
    let mut chars = text.chars();
    if let (Some(c), None) = (chars.next(), chars.next()) {
        if c.is_control() || c == ' ' {
            return Err(format!(
                "{text:?} is a control character; write \"Space\" or a named key"
            ));
        }
        return Ok(KeySpec::Char(c));
    }
    if let Some(rest) = text
        .strip_prefix("Ctrl-")
        .or_else(|| text.strip_prefix("ctrl-"))
    {
        let mut cs = rest.chars();
        return match (cs.next(), cs.next()) {
            (Some(c), None) if c.is_ascii_alphabetic() => {
                let c = c.to_ascii_lowercase();
                if c == 'c' {
                    Err("Ctrl-C is reserved: it always quits".into())
                } else {
                    Ok(KeySpec::Ctrl(c))
                }
            }
            _ => Err(format!(
                "{text:?}: Ctrl- takes one letter, as in \"Ctrl-s\""
            )),
        };
    }
    NAMED_KEYS
        .iter()
        .find(|n| n.eq_ignore_ascii_case(text))
        .map(|n| KeySpec::Named(n))
        .ok_or_else(|| {
            format!(
                "{text:?} is not a key: write one character, Ctrl-<letter>, or one of {}",
                NAMED_KEYS.join(", ")
            )
        })
}

impl ConsoleSettings {
    /// Every action with its key: the defaults, overridden by `keys`.
    pub fn bindings(&self) -> Result<Vec<(&'static str, KeySpec)>, Invalid> {
        for name in self.keys.keys() {
            if !CONSOLE_ACTIONS.iter().any(|(a, _)| a == name) {
                return bad(
                    format!("console.keys.{name}"),
                    format!(
                        "no such console action; the actions are {}",
                        CONSOLE_ACTIONS
                            .iter()
                            .map(|(a, _)| *a)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
                .map(|()| Vec::new());
            }
        }
        let mut out: Vec<(&'static str, KeySpec)> = Vec::with_capacity(CONSOLE_ACTIONS.len());
        for (action, default) in CONSOLE_ACTIONS {
            let (text, key) = match self.keys.get(*action) {
                Some(t) => (t.as_str(), format!("console.keys.{action}")),
                None => (*default, "console.keys".to_string()),
            };
            let spec = parse_key(text).map_err(|reason| Invalid {
                key: key.clone(),
                reason,
            })?;
            if let Some((other, _)) = out.iter().find(|(_, s)| *s == spec) {
                return Err(Invalid {
                    key,
                    reason: format!(
                        "key {spec} is bound to both {other:?} and {action:?}; give one of them another key"
                    ),
                });
            }
            out.push((action, spec));
        }
        Ok(out)
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DeviceKind {
    /// The physical simulation of the Falcon and the texture (the default).
    Sim,
    /// A real Novint Falcon on USB.
    Falcon,
    /// The real driver stack over a byte-level emulated Falcon.
    FalconEmulator,
}

impl DeviceKind {
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Sim => "sim",
            DeviceKind::Falcon => "falcon",
            DeviceKind::FalconEmulator => "falcon-emulator",
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Device {
    pub kind: DeviceKind,
    /// Servo rate in Hz (the thesis: 1 kHz).
    pub rate_hz: f64,
    /// Consecutive missed deadlines that abort a motion.
    #[serde(default = "default_missed_streak")]
    pub missed_deadline_streak: u32,
    /// A tick counts as missed when it starts this late, as a fraction of the period.
    #[serde(default = "default_missed_fraction")]
    pub missed_deadline_fraction: f64,
    /// Ask the OS for real-time scheduling of the servo thread (opt-in).
    #[serde(default)]
    pub realtime: Option<Realtime>,
    /// While the loop drives the probe (Target and Test modes) or a scan
    /// records, wake this many microseconds before each deadline and spin to
    /// it: trades CPU (spin / period of a core, never in Manual mode) for
    /// punctual ticks where the OS wakes threads late. 0 sleeps all the way.
    #[serde(default)]
    pub spin_us: u32,
}

/// Real-time setup of the servo thread: SCHED_FIFO at `priority`, memory
/// locked, optionally pinned to one core. When the system refuses (no
/// privilege, no RT limits), the loop says so once and runs on without it.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Realtime {
    /// SCHED_FIFO priority, 1–99.
    pub priority: u8,
    /// Lock the process's memory (mlockall) so page faults cannot stall a tick.
    #[serde(default)]
    pub lock_memory: bool,
    /// Pin the servo thread to this core.
    #[serde(default)]
    pub cpu: Option<usize>,
}

fn default_missed_streak() -> u32 {
    50
}
fn default_missed_fraction() -> f64 {
    0.5
}

/// Eq. 3.1's spring–damper law, per axis, in SI units.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Controller {
    pub stiffness_n_per_m: [f64; 3],
    pub damping_n_s_per_m: [f64; 3],
    /// Per-axis clamp on the commanded force.
    pub force_limit_n: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// Waypoints (x, y, z) in metres; the probe starts held at the first.
    pub waypoints_m: Vec<[f64; 3]>,
    /// Set-point speed along the path, m/s.
    pub speed_m_per_s: f64,
    /// Set-point speed on the other legs (default: `speed_m_per_s`).
    #[serde(default)]
    pub transit_speed_m_per_s: Option<f64>,
    /// The scan leg, 1-based: leg N runs from waypoint N to waypoint N+1.
    pub scan_leg: usize,
    /// Time held at the end of the scan leg, still recorded, so the probe settles.
    #[serde(default)]
    pub dwell_s: f64,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Detrend {
    None,
    #[default]
    Mean,
    Linear,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SpectrumKind {
    /// |DFT| as Matlab's fft gives it (unnormalised): the thesis's feature.
    #[default]
    Magnitude,
    /// The one-sided periodogram `|X_k|² / n` (the bins in between doubled,
    /// so the bins sum to `Σ x² `, Parseval).
    Power,
    /// `log10` of the power, with a floor of 1e-300.
    LogPower,
    /// Welch's averaged periodogram: segments of `welch_segment` points
    /// overlapping by `welch_overlap`, each tapered by `taper`.
    Welch,
}

/// The taper applied to the window (or to each Welch segment) before the DFT.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Taper {
    /// Rectangular: no taper (the thesis).
    #[default]
    None,
    /// Periodic Hann, `0.5 − 0.5 cos(2π j / n)`.
    Hann,
}

/// How a recording becomes a feature vector.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    /// The signal column (thesis: `y_m`, the probe's height).
    pub channel: String,
    /// The resampling axis: a position column (distance from the scan's
    /// first sample) or `t_s` (time since the scan's first sample).
    pub axis: String,
    /// [start, end] of the window along the axis, from the scan's start, in
    /// the axis's unit; `"scan-leg"` in a profile: the whole scan leg,
    /// `[0, the leg's extent along the axis]` (for `t_s`, its duration with
    /// the dwell), worked out from `[path]` when the profile is loaded.
    #[serde(deserialize_with = "window_or_scan_leg")]
    pub window: [f64; 2],
    /// Set when the profile said `window = "scan-leg"`: the window follows
    /// the path (a sweep of the path's speed moves its end).
    #[serde(skip)]
    pub window_is_scan_leg: bool,
    /// Resampling spacing, in the axis's unit (thesis: 0.3 mm).
    pub spacing: f64,
    #[serde(default)]
    pub detrend: Detrend,
    #[serde(default)]
    pub spectrum: SpectrumKind,
    /// First and last DFT bin kept, inclusive (thesis: 1..49, DC dropped).
    /// Ignored when `band` is set.
    #[serde(default)]
    pub bins: [usize; 2],
    /// More signal columns, analysed like `channel` and their features
    /// concatenated after its own, in this order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<String>,
    #[serde(default, skip_serializing_if = "is_default")]
    pub taper: Taper,
    /// The frequencies kept, [low, high] inclusive, instead of `bins`: in Hz
    /// for a time axis (`t_s`), in cycles/mm for a position axis (`*_m`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<[f64; 2]>,
    /// Welch only: points per segment (default: a quarter of the window).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub welch_segment: Option<usize>,
    /// Welch only: overlap of consecutive segments, 0 <= overlap < 1 (default 0.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub welch_overlap: Option<f64>,
}

/// What `window = "scan-leg"` reads as until [`Profile::resolve_window`]
/// works out the leg's extent: [0, +inf], which no validation accepts.
const SCAN_LEG: [f64; 2] = [0.0, f64::INFINITY];

fn window_or_scan_leg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum W {
        Range([f64; 2]),
        Word(String),
    }
    match W::deserialize(d) {
        Ok(W::Range(r)) => Ok(r),
        Ok(W::Word(w)) if w == "scan-leg" => Ok(SCAN_LEG),
        Ok(W::Word(w)) => Err(serde::de::Error::custom(format!(
            "window must be [start, end] or \"scan-leg\", got {w:?}"
        ))),
        Err(_) => Err(serde::de::Error::custom(
            "window must be [start, end] (two numbers) or \"scan-leg\"",
        )),
    }
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

impl Default for Analysis {
    /// The thesis's analysis.
    fn default() -> Self {
        Analysis {
            channel: "y_m".into(),
            axis: "x_m".into(),
            window: [0.060, 0.0897],
            window_is_scan_leg: false,
            spacing: 0.0003,
            detrend: Detrend::Mean,
            spectrum: SpectrumKind::Magnitude,
            bins: [1, 49],
            channels: Vec::new(),
            taper: Taper::None,
            band: None,
            welch_segment: None,
            welch_overlap: None,
        }
    }
}

impl Analysis {
    /// Number of resampled points in the window: both ends included.
    pub fn points(&self) -> usize {
        ((self.window[1] - self.window[0]) / self.spacing + 1e-6).floor() as usize + 1
    }
    /// Every signal column analysed: `channel`, then `channels`.
    pub fn all_channels(&self) -> impl Iterator<Item = &str> {
        std::iter::once(self.channel.as_str()).chain(self.channels.iter().map(String::as_str))
    }
    /// Points of one DFT: the window's, or a Welch segment's.
    pub fn dft_points(&self) -> usize {
        let n = self.points();
        match self.spectrum {
            SpectrumKind::Welch => self.welch_segment.unwrap_or((n / 4).max(4)),
            _ => n,
        }
    }
    /// Welch overlap as a fraction (default one half).
    pub fn overlap(&self) -> f64 {
        self.welch_overlap.unwrap_or(0.5)
    }
    /// How a DFT bin's index turns into the unit `band` is written in: bin
    /// `k` lies at `k · bin_width()` (Hz, or cycles/mm for a position axis).
    pub fn bin_width(&self) -> f64 {
        let per_axis_unit = 1.0 / (self.dft_points() as f64 * self.spacing);
        if self.axis.ends_with("_m") {
            per_axis_unit / 1000.0
        } else {
            per_axis_unit
        }
    }
    /// The unit of `band` and of [`Self::bin_width`].
    pub fn frequency_unit(&self) -> &'static str {
        if self.axis.ends_with("_m") {
            "cycles/mm"
        } else if self.axis.ends_with("_s") {
            "Hz"
        } else {
            "cycles per axis unit"
        }
    }
    /// The first and last bin kept (inclusive), from `band` or `bins`; the
    /// first is past the last when the band holds no bin.
    pub fn kept_bins(&self) -> [usize; 2] {
        match self.band {
            None => self.bins,
            Some([lo, hi]) => {
                let w = self.bin_width();
                let half = self.dft_points() / 2;
                let first = ((lo / w) - 1e-9).ceil().max(0.0) as usize;
                let last = (((hi / w) + 1e-9).floor().max(0.0) as usize).min(half);
                [first, last]
            }
        }
    }
    /// Features per channel.
    pub fn features_per_channel(&self) -> usize {
        let [a, b] = self.kept_bins();
        (b + 1).saturating_sub(a)
    }
    pub fn feature_count(&self) -> usize {
        self.features_per_channel() * (1 + self.channels.len())
    }
}

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

fn k_or_auto<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum K {
        N(usize),
        S(String),
    }
    match K::deserialize(d)? {
        K::N(n) if n == K_AUTO => Err(serde::de::Error::custom("k is too large")),
        K::N(n) => Ok(n),
        K::S(s) if s == "auto" => Ok(K_AUTO),
        K::S(s) => Err(serde::de::Error::custom(format!(
            "k must be a whole number or \"auto\", got {s:?}"
        ))),
    }
}

fn write_k<S: serde::Serializer>(k: &usize, s: S) -> Result<S::Ok, S::Error> {
    if *k == K_AUTO {
        s.serialize_str("auto")
    } else {
        s.serialize_u64(*k as u64)
    }
}

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
    pub train_per_class: usize,
    pub test_per_class: usize,
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

impl Default for Evaluation {
    fn default() -> Self {
        Evaluation {
            train_per_class: 20,
            test_per_class: 10,
            shuffle_seed: None,
            method: SplitMethod::Holdout,
            folds: None,
            group_by: None,
        }
    }
}

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

/// The physical model behind `device.kind = "sim"`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Simulator {
    pub seed: u64,
    /// Effective moving mass of the end effector, per axis.
    pub mass_kg: f64,
    /// Weight the mechanism does not balance (the probe mount), pulling −y.
    pub unbalanced_weight_n: f64,
    /// Viscous friction of the mechanism.
    pub mechanism_damping_n_s_per_m: f64,
    pub probe_diameter_m: f64,
    /// Height of the sphere centre when it rests on the texture's crests.
    pub surface_top_y_m: f64,
    /// Where along x the texture's first period starts (before placement jitter).
    pub surface_origin_x_m: f64,
    /// Each scan's texture is shifted by a uniform random amount up to this (re-mounting).
    pub placement_jitter_m: f64,
    pub contact_stiffness_n_per_m: f64,
    pub contact_damping_n_s_per_m: f64,
    pub friction_coefficient: f64,
    /// Encoder resolution (the Falcon's 400 dpi ≈ 0.0635 mm).
    pub encoder_resolution_m: f64,
    pub position_noise_m: f64,
    /// Per-tick chance that the USB exchange slips by up to a quarter period
    /// (the thesis's loop ran at 800–1000 Hz); virtual time only.
    pub period_jitter_fraction: f64,
    /// Standard deviation of the ordinary tick-time jitter; virtual time only.
    pub period_jitter_s: f64,
    /// Physics sub-steps per servo tick.
    pub substeps: u32,
    /// Injected faults (`[simulator.faults]`, device.kind = "sim" only).
    #[serde(skip_serializing_if = "is_default_faults")]
    pub faults: hardware::SimFaults,
}

fn is_default_faults(f: &hardware::SimFaults) -> bool {
    *f == hardware::SimFaults::default()
}

impl Default for Simulator {
    fn default() -> Self {
        Simulator {
            seed: 1,
            mass_kg: 0.06,
            unbalanced_weight_n: 0.216,
            mechanism_damping_n_s_per_m: 0.5,
            probe_diameter_m: 0.002,
            surface_top_y_m: -0.0038,
            surface_origin_x_m: -0.045,
            placement_jitter_m: 0.01,
            contact_stiffness_n_per_m: 3000.0,
            contact_damping_n_s_per_m: 3.0,
            friction_coefficient: 0.3,
            encoder_resolution_m: 0.0000635,
            position_noise_m: 0.00001,
            period_jitter_fraction: 0.1,
            period_jitter_s: 0.000_02,
            substeps: 4,
            faults: hardware::SimFaults::default(),
        }
    }
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

impl LoadedProfile {
    /// The built-in thesis profile.
    pub fn thesis() -> LoadedProfile {
        Self::from_str(THESIS_PROFILE, "<built-in thesis profile>", Path::new("."))
            .expect("the built-in thesis profile is valid")
    }

    /// Load a profile file, or the built-in one for the name `thesis` when no such file exists.
    pub fn load(path: &Path) -> Result<LoadedProfile, ProfileError> {
        if path.as_os_str() == "thesis" && !path.exists() {
            return Ok(Self::thesis());
        }
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ProfileError {
            origin: origin.clone(),
            line: None,
            column: None,
            key: None,
            reason: format!("cannot read the profile: {e}"),
        })?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        Self::from_str(&text, &origin, &base)
    }

    pub fn from_str(
        text: &str,
        origin: &str,
        base_dir: &Path,
    ) -> Result<LoadedProfile, ProfileError> {
        let profile: Profile = toml::from_str(text).map_err(|e| {
            let (line, column) = match e.span() {
                Some(span) => line_col(text, span.start),
                None => (None, None),
            };
            ProfileError {
                origin: origin.to_string(),
                line,
                column,
                key: None,
                reason: e.message().trim().to_string(),
            }
        })?;
        let mut profile = profile;
        profile.resolve_window();
        if let Err(v) = profile.validate() {
            let (line, column) = locate_key(text, &v.key);
            return Err(ProfileError {
                origin: origin.to_string(),
                line,
                column,
                key: Some(v.key),
                reason: v.reason,
            });
        }
        Ok(LoadedProfile {
            profile,
            origin: origin.to_string(),
            base_dir: base_dir.to_path_buf(),
            sha256: sha256_hex(text.as_bytes()),
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

fn finite_pos(key: &str, v: f64) -> Result<(), Invalid> {
    if !(v.is_finite() && v > 0.0) {
        return bad(key, format!("must be a positive number, got {v}"));
    }
    Ok(())
}

fn finite_nonneg(key: &str, v: f64) -> Result<(), Invalid> {
    if !(v.is_finite() && v >= 0.0) {
        return bad(key, format!("must be zero or more, got {v}"));
    }
    Ok(())
}

/// A label is used as a folder name: keep it to letters, digits, `-`, `_` and `.`.
pub fn check_label(label: &str) -> Result<(), String> {
    if label.is_empty() || label.len() > 64 {
        return Err(format!("label {label:?} must have 1 to 64 characters"));
    }
    if label.starts_with('.') {
        return Err(format!("label {label:?} must not start with '.'"));
    }
    if !label
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.')
    {
        return Err(format!(
            "label {label:?} may hold only letters, digits, '-', '_' and '.' (it names a folder)"
        ));
    }
    Ok(())
}

impl Profile {
    /// Check every value; the first problem found is returned with its key.
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.name.trim().is_empty() {
            return bad("name", "must not be empty");
        }
        // device
        let d = &self.device;
        if !(d.rate_hz.is_finite() && (10.0..=10_000.0).contains(&d.rate_hz)) {
            return bad(
                "device.rate_hz",
                format!("must be between 10 and 10000 Hz, got {}", d.rate_hz),
            );
        }
        if d.missed_deadline_streak == 0 {
            return bad("device.missed_deadline_streak", "must be at least 1");
        }
        if let Some(rt) = &d.realtime
            && !(1..=99).contains(&rt.priority)
        {
            return bad(
                "device.realtime.priority",
                format!("must be from 1 to 99, got {}", rt.priority),
            );
        }
        if f64::from(d.spin_us) * 1e-6 * d.rate_hz >= 0.9 {
            return bad(
                "device.spin_us",
                format!(
                    "{} µs is most of the {:.0} µs period; keep it under 90 %",
                    d.spin_us,
                    1e6 / d.rate_hz
                ),
            );
        }
        if !(d.missed_deadline_fraction > 0.0 && d.missed_deadline_fraction <= 10.0) {
            return bad("device.missed_deadline_fraction", "must be in (0, 10]");
        }
        // controller
        let c = &self.controller;
        for i in 0..3 {
            finite_nonneg(
                &format!("controller.stiffness_n_per_m[{i}]"),
                c.stiffness_n_per_m[i],
            )?;
            finite_nonneg(
                &format!("controller.damping_n_s_per_m[{i}]"),
                c.damping_n_s_per_m[i],
            )?;
        }
        finite_pos("controller.force_limit_n", c.force_limit_n)?;
        if c.force_limit_n > DEVICE_MAX_FORCE_N {
            return bad(
                "controller.force_limit_n",
                format!(
                    "{} N exceeds the device's {} N",
                    c.force_limit_n, DEVICE_MAX_FORCE_N
                ),
            );
        }
        // path
        let p = &self.path;
        if p.waypoints_m.len() < 2 {
            return bad("path.waypoints_m", "needs at least two waypoints");
        }
        for (i, w) in p.waypoints_m.iter().enumerate() {
            for a in 0..3 {
                if !w[a].is_finite() || w[a] < WORKSPACE_MIN_M[a] || w[a] > WORKSPACE_MAX_M[a] {
                    return bad(
                        format!("path.waypoints_m[{i}]"),
                        format!(
                            "waypoint {} ({:.4}, {:.4}, {:.4}) m is outside the device's workspace: {} must lie in [{}, {}] m",
                            i + 1,
                            w[0],
                            w[1],
                            w[2],
                            ["x", "y", "z"][a],
                            WORKSPACE_MIN_M[a],
                            WORKSPACE_MAX_M[a]
                        ),
                    );
                }
            }
        }
        if !(p.speed_m_per_s.is_finite() && p.speed_m_per_s > 0.0 && p.speed_m_per_s <= 0.5) {
            return bad(
                "path.speed_m_per_s",
                format!("must be in (0, 0.5] m/s, got {}", p.speed_m_per_s),
            );
        }
        if let Some(v) = p.transit_speed_m_per_s
            && !(v.is_finite() && v > 0.0 && v <= 0.5)
        {
            return bad(
                "path.transit_speed_m_per_s",
                format!("must be in (0, 0.5] m/s, got {v}"),
            );
        }
        if p.scan_leg == 0 || p.scan_leg >= p.waypoints_m.len() {
            return bad(
                "path.scan_leg",
                format!(
                    "must name a leg from 1 to {} (leg N runs from waypoint N to N+1), got {}",
                    p.waypoints_m.len() - 1,
                    p.scan_leg
                ),
            );
        }
        finite_nonneg("path.dwell_s", p.dwell_s)?;
        let a0 = p.waypoints_m[p.scan_leg - 1];
        let a1 = p.waypoints_m[p.scan_leg];
        let leg_len = dist(a0, a1);
        if leg_len <= 0.0 {
            return bad("path.scan_leg", "the scan leg has zero length");
        }
        // analysis
        let an = &self.analysis;
        let axis_index = match an.axis.as_str() {
            "x_m" => Some(0),
            "y_m" => Some(1),
            "z_m" => Some(2),
            "t_s" => None,
            other => {
                return bad(
                    "analysis.axis",
                    format!("must be one of x_m, y_m, z_m, t_s, got {other:?}"),
                );
            }
        };
        if an.channel.is_empty() || an.channel == an.axis {
            return bad(
                "analysis.channel",
                "must name a signal column other than the axis",
            );
        }
        finite_pos("analysis.spacing", an.spacing)?;
        if an.window == SCAN_LEG {
            return bad(
                "analysis.window",
                "\"scan-leg\" needs a scan leg that moves along the axis",
            );
        }
        if !(an.window[0].is_finite()
            && an.window[1].is_finite()
            && an.window[0] >= 0.0
            && an.window[1] > an.window[0])
        {
            return bad(
                "analysis.window",
                format!(
                    "must be [start, end] with 0 <= start < end, got {:?}",
                    an.window
                ),
            );
        }
        let leg_extent = match axis_index {
            Some(ax) => (a1[ax] - a0[ax]).abs(),
            None => leg_len / p.speed_m_per_s + p.dwell_s,
        };
        if axis_index.is_some() && leg_extent <= 0.0 {
            return bad(
                "analysis.axis",
                "the scan leg does not move along this axis",
            );
        }
        if an.window[1] > leg_extent + 1e-9 {
            return bad(
                "analysis.window",
                format!(
                    "ends at {} but the scan leg spans only {:.6} along {} (window = \"scan-leg\" takes all of it)",
                    an.window[1], leg_extent, an.axis
                ),
            );
        }
        let n = an.points();
        if n < 4 {
            return bad(
                "analysis.spacing",
                format!("leaves only {n} points in the window (need 4)"),
            );
        }
        if n > 1 << 20 {
            return bad(
                "analysis.spacing",
                format!("leaves {n} points in the window (at most 1048576)"),
            );
        }
        let m = an.dft_points();
        if an.band.is_none() && (an.bins[0] > an.bins[1] || an.bins[1] > m / 2) {
            return bad(
                "analysis.bins",
                format!(
                    "must be [first, last] with first <= last <= {} (half the {} {} points), got {:?}",
                    m / 2,
                    m,
                    if m == n { "window" } else { "Welch segment" },
                    an.bins
                ),
            );
        }
        for (i, c) in an.channels.iter().enumerate() {
            if c.is_empty() || *c == an.axis || an.all_channels().filter(|x| x == c).count() > 1 {
                return bad(
                    format!("analysis.channels[{i}]"),
                    "must name a signal column other than the axis, once",
                );
            }
        }
        if let Err((key, reason)) = crate::analysis::check_options(an) {
            return bad(key, reason);
        }
        // classifier and evaluation
        if self.classifier.k == 0 {
            return bad("classifier.k", "must be at least 1");
        }
        if let Some(c) = &self.classifier.k_candidates
            && (c.is_empty() || c.contains(&0) || c.contains(&K_AUTO))
        {
            return bad(
                "classifier.k_candidates",
                "must list whole numbers of at least 1",
            );
        }
        match (self.evaluation.method, self.evaluation.folds) {
            (SplitMethod::KFold, Some(f)) if f < 2 => {
                return bad("evaluation.folds", "must be at least 2");
            }
            (SplitMethod::Holdout | SplitMethod::LeaveOneOut, Some(_)) => {
                return bad("evaluation.folds", "is only used with method = \"k-fold\"");
            }
            _ => {}
        }
        if self.evaluation.group_by.as_deref() == Some("") {
            return bad("evaluation.group_by", "must name a metadata key");
        }
        if self.evaluation.train_per_class == 0 {
            return bad("evaluation.train_per_class", "must be at least 1");
        }
        if !self.classifier.k_is_auto()
            && self.classifier.k > self.evaluation.train_per_class * self.textures.len().max(1)
        {
            return bad(
                "classifier.k",
                format!(
                    "k = {} exceeds the training set ({} per class)",
                    self.classifier.k, self.evaluation.train_per_class
                ),
            );
        }
        // textures
        let mut seen = std::collections::BTreeSet::new();
        for (i, t) in self.textures.iter().enumerate() {
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
        // simulator
        let s = &self.simulator;
        finite_pos("simulator.mass_kg", s.mass_kg)?;
        finite_nonneg("simulator.unbalanced_weight_n", s.unbalanced_weight_n)?;
        finite_nonneg(
            "simulator.mechanism_damping_n_s_per_m",
            s.mechanism_damping_n_s_per_m,
        )?;
        finite_pos("simulator.probe_diameter_m", s.probe_diameter_m)?;
        if s.probe_diameter_m > 0.02 {
            return bad("simulator.probe_diameter_m", "must be at most 20 mm");
        }
        if !s.surface_top_y_m.is_finite() {
            return bad("simulator.surface_top_y_m", "must be a number");
        }
        if !s.surface_origin_x_m.is_finite() {
            return bad("simulator.surface_origin_x_m", "must be a number");
        }
        finite_nonneg("simulator.placement_jitter_m", s.placement_jitter_m)?;
        finite_pos(
            "simulator.contact_stiffness_n_per_m",
            s.contact_stiffness_n_per_m,
        )?;
        finite_nonneg(
            "simulator.contact_damping_n_s_per_m",
            s.contact_damping_n_s_per_m,
        )?;
        finite_nonneg("simulator.friction_coefficient", s.friction_coefficient)?;
        if s.friction_coefficient > 2.0 {
            return bad("simulator.friction_coefficient", "must be at most 2");
        }
        finite_nonneg("simulator.encoder_resolution_m", s.encoder_resolution_m)?;
        finite_nonneg("simulator.position_noise_m", s.position_noise_m)?;
        if !(0.0..=1.0).contains(&s.period_jitter_fraction) {
            return bad("simulator.period_jitter_fraction", "must be in [0, 1]");
        }
        finite_nonneg("simulator.period_jitter_s", s.period_jitter_s)?;
        if s.period_jitter_s * d.rate_hz > 0.2 {
            return bad(
                "simulator.period_jitter_s",
                "must be under a fifth of the servo period",
            );
        }
        if !(1..=64).contains(&s.substeps) {
            return bad("simulator.substeps", "must be from 1 to 64");
        }
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
        let p = &self.path;
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
        if self.analysis.window == SCAN_LEG {
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

    /// Length of the scan leg, metres.
    pub fn scan_leg_length_m(&self) -> f64 {
        dist(
            self.path.waypoints_m[self.path.scan_leg - 1],
            self.path.waypoints_m[self.path.scan_leg],
        )
    }
}

pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (Option<usize>, Option<usize>) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (Some(line), Some(col))
}

/// Find where a dotted key such as `path.waypoints_m[2]` or
/// `textures[1].surface.depth_m` is written, by scanning the table headers
/// and keys. Good for the layouts TOML is normally written in; `None` when
/// the key is not written (a default value) or written in another style.
pub fn locate_key(text: &str, key: &str) -> (Option<usize>, Option<usize>) {
    // Split "a.b[2].c" into segments with optional indices.
    let segments: Vec<(String, Option<usize>)> = key
        .split('.')
        .map(|s| match s.find('[') {
            Some(i) => (s[..i].to_string(), s[i + 1..s.len() - 1].parse().ok()),
            None => (s.to_string(), None),
        })
        .collect();
    // The table path is everything but the last segment (with array-of-table indices).
    let (last, table) = segments.split_last().expect("a key has a segment");
    let mut table_names: Vec<&str> = table.iter().map(|(n, _)| n.as_str()).collect();
    let mut counters: BTreeMap<String, usize> = BTreeMap::new();
    let mut current: Vec<String> = Vec::new();
    let mut current_idx: Vec<Option<usize>> = Vec::new();
    let want_idx: Vec<Option<usize>> = table.iter().map(|(_, i)| *i).collect();
    let mut fallback: (Option<usize>, Option<usize>) = (None, None);
    // Open brackets of a multi-line value being skipped.
    let mut depth: i64 = 0;
    for (ln, raw) in text.lines().enumerate() {
        let line = raw.trim_start();
        let indent = raw.len() - line.len();
        let code = line.split('#').next().unwrap_or("");
        if depth > 0 {
            depth += code.matches('[').count() as i64 - code.matches(']').count() as i64;
            continue;
        }
        if let Some(rest) = line.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let c = counters.entry(name.clone()).or_insert(0);
            let idx = *c;
            *c += 1;
            current = name.split('.').map(|s| s.trim().to_string()).collect();
            current_idx = vec![None; current.len()];
            if let Some(l) = current_idx.last_mut() {
                *l = Some(idx);
            }
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.split(']').next().unwrap_or("").trim().to_string();
            current = name.split('.').map(|s| s.trim().to_string()).collect();
            current_idx = vec![None; current.len()];
            // A sub-table of an array of tables refers to its latest element.
            for (i, seg) in current.iter().enumerate() {
                let prefix = current[..=i].join(".");
                if let Some(c) = counters.get(&prefix) {
                    let _ = seg;
                    current_idx[i] = Some(c.saturating_sub(1));
                }
            }
            continue;
        }
        // key = value, possibly a dotted key or an inline table.
        let Some(eq) = line.find('=') else { continue };
        let value = code.get(eq + 1..).unwrap_or("");
        depth = value.matches('[').count() as i64 - value.matches(']').count() as i64;
        let k = line[..eq].trim();
        let mut path: Vec<String> = current.clone();
        let mut pidx = current_idx.clone();
        for part in k.split('.') {
            path.push(part.trim().trim_matches('"').to_string());
            pidx.push(None);
        }
        let names_match = |upto: usize| -> bool {
            path.len() >= upto
                && path[..upto]
                    .iter()
                    .map(String::as_str)
                    .eq(table_names.iter().copied())
                && pidx[..upto]
                    .iter()
                    .zip(want_idx.iter())
                    .all(|(have, want)| want.is_none() || have == want)
        };
        let col = indent + 1;
        if names_match(table_names.len())
            && path.len() == table_names.len() + 1
            && path.last().map(String::as_str) == Some(last.0.as_str())
        {
            // An element of a multi-line array: the Nth line after the key that opens an element.
            if let Some(index) = last.1 {
                let rest = line[eq + 1..].trim();
                if rest == "[" {
                    let mut seen = 0;
                    for (j, next) in text.lines().enumerate().skip(ln + 1) {
                        let t = next.trim_start();
                        if t.starts_with(']') {
                            break;
                        }
                        if t.starts_with('[')
                            || t.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '"')
                        {
                            if seen == index {
                                return (Some(j + 1), Some(next.len() - t.len() + 1));
                            }
                            seen += 1;
                        }
                    }
                }
            }
            return (Some(ln + 1), Some(col));
        }
        // An inline table holding the key: `surface = { kind = ..., depth_m = ... }`.
        if table_names.len() == path.len() && names_match(path.len()) {
            if let Some(pos) = line
                .find(&format!("{} ", last.0))
                .or_else(|| line.find(&format!("{}=", last.0)))
            {
                return (Some(ln + 1), Some(indent + pos + 1));
            }
            fallback = (Some(ln + 1), Some(col));
        }
        // The table itself, when the key is absent: point at its header's first key.
        if fallback.0.is_none() && names_match(table_names.len()) && !table_names.is_empty() {
            fallback = (Some(ln + 1), Some(col));
        }
    }
    table_names.clear();
    fallback
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
    fn locates_keys() {
        let text = "name = \"x\"\n[path]\nspeed_m_per_s = 1\n[[textures]]\nlabel = \"a\"\n[[textures]]\nlabel = \"b\"\nsurface = { kind = \"sine\", period_m = 0 }\n";
        assert_eq!(locate_key(text, "path.speed_m_per_s"), (Some(3), Some(1)));
        assert_eq!(locate_key(text, "textures[1].label"), (Some(7), Some(1)));
        assert_eq!(locate_key(text, "textures[1].surface.period_m").0, Some(8));
    }

    #[test]
    fn labels_must_be_safe_file_names() {
        assert!(check_label("S2").is_ok());
        assert!(check_label("../etc").is_err());
        assert!(check_label("a/b").is_err());
        assert!(check_label("").is_err());
        assert!(check_label(".hidden").is_err());
    }
}
