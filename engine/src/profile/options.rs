//! The one list of analysis options: each `[analysis]` key declared once
//! ([`ANALYSIS_OPTIONS`]) with its type, allowed values, unit, whether a
//! sweep may vary it, whether it changes the features (and so which models
//! fit a profile), its group and one line of advice for `profile new`, the
//! values `tune` searches, and how the features it decides are labelled;
//! the `[classifier]` keys likewise ([`CLASSIFIER_OPTIONS`]). Derived from
//! it: the model compatibility check ([`first_difference`]), the sweep
//! keys, `tune`'s space and the lines it writes, `profile new`'s groups
//! and advice, `check`'s message for a word or flag an option does not
//! take ([`check_written`]) and the Spectrum panel's labels
//! ([`FeatureNames::of`]). Adding an option
//! means its analysis code, its line here, and its tests (the compiler and
//! a test refuse an `Analysis` field missing here).

use super::Invalid;
use super::analysis::{Analysis, SpectrumKind};
use super::classifier::Classifier;
use super::families::FeatureFamily;

/// A value's kind, as a profile writes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Text,
    Number,
    Integer,
    Flag,
    /// One of the listed words.
    Choice,
    /// `[a, b]`.
    Pair,
    /// A list of column names.
    List,
    /// A table (`{ … }`).
    Table,
}

/// Where `profile new` puts an option, in this order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// Which signal, along which axis, over which stretch.
    Signal,
    /// How the signal is resampled and prepared.
    Resampling,
    /// Which spectrum and which of its parts become features.
    Spectrum,
    /// Sub-windows and their vote.
    Windows,
}

impl Group {
    /// Every group, in the order `profile new` writes them.
    pub const ALL: [Group; 4] = [
        Group::Signal,
        Group::Resampling,
        Group::Spectrum,
        Group::Windows,
    ];
    /// What the group decides, as `profile new` heads it.
    pub fn title(self) -> &'static str {
        match self {
            Group::Signal => "The signal: which column, along which axis, over which stretch",
            Group::Resampling => "Resampling: the step, and what is removed before the spectrum",
            Group::Spectrum => "The spectrum, and which of its parts become features",
            Group::Windows => "Sub-windows, each a vote",
        }
    }
}

/// What a scan's features are, channel by channel (the Spectrum panel's
/// labels), as the option that decides them declares.
#[derive(Debug, Clone, PartialEq)]
pub enum FeatureNames {
    /// DFT bins from the first kept on; `value` says what a bin holds.
    Bins { value: &'static str },
    /// Band energies: band `i` from `edges[i]` to `edges[i + 1]`, in `unit`.
    Bands {
        edges: Vec<f64>,
        unit: &'static str,
        value: &'static str,
    },
    /// Cepstral coefficients `c<first>, …` of the log band energies
    /// (`first` is 1 when the level term c0 is dropped).
    Cepstra { first: usize },
    /// The window's resampled points, which the model turns into random
    /// kernel features.
    Points,
    /// Interval quantiles (QUANT), numbered from 0.
    Quantiles,
    /// Competing kernels' wins and losses (Hydra), numbered from 0.
    Hydra,
}

impl FeatureNames {
    /// The names of an analysis's features: those of the one option that
    /// decides them (`bins`, `band`, `bands` or `cepstra`).
    pub fn of(a: &Analysis) -> FeatureNames {
        ANALYSIS_OPTIONS
            .iter()
            .filter_map(|o| o.labels)
            .find_map(|labels| labels(a))
            .unwrap_or(FeatureNames::Bins { value: "value" })
    }
}

/// What one DFT bin of `a`'s spectrum holds.
fn bin_value(a: &Analysis) -> &'static str {
    match a.spectrum {
        SpectrumKind::Magnitude => "|X|",
        SpectrumKind::Power | SpectrumKind::Welch => "power",
        SpectrumKind::LogPower | SpectrumKind::LogWelch => "log10 power",
    }
}

/// One `[analysis]` option.
#[derive(Debug, Clone, Copy)]
pub struct AnalysisOption {
    /// The key, with its table: `analysis.spacing`.
    pub name: &'static str,
    pub kind: Kind,
    /// The words a [`Kind::Choice`] or [`Kind::Flag`] takes, or a short
    /// description of the values allowed.
    pub allowed: &'static [&'static str],
    /// The unit ("" for none; "axis" for the analysis axis's unit).
    pub unit: &'static str,
    /// Whether `evaluate --sweep` may vary it.
    pub sweepable: bool,
    /// Whether it changes the feature vector: a model trained under
    /// another value does not fit.
    pub changes_features: bool,
    pub group: Group,
    /// One line for `profile new` and `check`.
    pub advice: &'static str,
    /// The values `tune` searches, simplest first (none: not searched):
    /// each as a profile writes it (a word, a number, `true`), `none` for
    /// the option left out, or relative to the data as `tune` resolves it
    /// (`points/4`: a power of two, at most a quarter of the points;
    /// `points/1`: the largest power of two within the points, searched only
    /// where that is short (`WHOLE_SEGMENT_MOST` in tune's space);
    /// `window/4`: a quarter of the window).
    pub search: &'static [&'static str],
    /// The value as the model file writes it, and whether two analyses
    /// agree on it (some options only matter when another is set).
    value: fn(&Analysis) -> String,
    same: fn(&Analysis, &Analysis) -> bool,
    /// The value as a profile line writes it (`None`: the line is left out).
    line: fn(&Analysis) -> Option<String>,
    /// How the features are labelled when this option decides them
    /// (`None` from the function when another one does).
    labels: Option<fn(&Analysis) -> Option<FeatureNames>>,
}

/// How an option is written in a model file, compared, and written in a
/// profile.
type Compare = (
    fn(&Analysis) -> String,
    fn(&Analysis, &Analysis) -> bool,
    fn(&Analysis) -> Option<String>,
);

fn json<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_else(|e| format!("<{e}>"))
}

/// A value as a profile line writes it (`"mean"`, `[1, 49]`, `{ length =
/// 1.49, hop = 0.745 }`, fields in declared order); `None` for an option
/// left out.
fn toml_value<T: serde::Serialize>(value: &T) -> Option<String> {
    let mut text = String::new();
    value
        .serialize(toml::ser::ValueSerializer::new(&mut text))
        .ok()?;
    Some(text)
}

macro_rules! field {
    ($f:ident) => {
        (
            |a: &Analysis| json(&a.$f),
            |a: &Analysis, b: &Analysis| a.$f == b.$f,
            |a: &Analysis| toml_value(&a.$f),
        )
    };
}

/// An option whose value is compared as is.
#[allow(clippy::too_many_arguments)]
const fn opt(
    name: &'static str,
    kind: Kind,
    allowed: &'static [&'static str],
    unit: &'static str,
    sweepable: bool,
    group: Group,
    advice: &'static str,
    (value, same, line): Compare,
) -> AnalysisOption {
    AnalysisOption {
        name,
        kind,
        allowed,
        unit,
        sweepable,
        changes_features: true,
        group,
        advice,
        search: &[],
        value,
        same,
        line,
        labels: None,
    }
}

impl AnalysisOption {
    /// The option with the values `tune` searches.
    const fn searched(mut self, values: &'static [&'static str]) -> Self {
        self.search = values;
        self
    }
    /// The option with how it labels the features it decides.
    const fn labelled(mut self, labels: fn(&Analysis) -> Option<FeatureNames>) -> Self {
        self.labels = Some(labels);
        self
    }
}

/// Every `[analysis]` option, in the order a profile lists them (and
/// `profile new` writes them, group by group; `tune` searches them).
pub const ANALYSIS_OPTIONS: &[AnalysisOption] = &[
    opt(
        "analysis.channel",
        Kind::Text,
        &["a column of the recordings"],
        "",
        false,
        Group::Signal,
        "the signal column the features come from (thesis: y_m, the probe's height)",
        field!(channel),
    ),
    opt(
        "analysis.axis",
        Kind::Choice,
        &["x_m", "y_m", "z_m", "t_s"],
        "",
        false,
        Group::Signal,
        "resample along position (a surface's texture) or time (vibration, sound)",
        field!(axis),
    ),
    opt(
        "analysis.window",
        Kind::Pair,
        &["[start, end] from the scan's start", "\"scan-leg\""],
        "axis",
        false,
        Group::Signal,
        "the stretch of each scan analysed; the same for every scan",
        field!(window),
    ),
    opt(
        "analysis.spacing",
        Kind::Number,
        &["a positive number"],
        "axis",
        true,
        Group::Resampling,
        "resampling step: smaller keeps finer texture, up to the sensor's resolution",
        field!(spacing),
    ),
    opt(
        "analysis.detrend",
        Kind::Choice,
        &["none", "mean", "linear"],
        "",
        true,
        Group::Resampling,
        "remove the mean (or a line) so a tilt or offset is not taken for texture",
        field!(detrend),
    ),
    // Before the spectrum's options: it decides whether they are used,
    // and which labels the features get.
    opt(
        "analysis.features",
        Kind::Choice,
        &["spectrum", "kernels", "quantiles", "hydra"],
        "",
        true,
        Group::Spectrum,
        "spectrum as the thesis; kernels (MiniRocket), quantiles (QUANT) or hydra (competing kernels) for vibration or motion a spectrum misses, best with classifier.method = \"ridge\" or \"lda\"",
        field!(features),
    )
    // Simplest first: the thesis's spectrum, then the cheaper family.
    .searched(&["spectrum", "quantiles", "kernels", "hydra"])
    .labelled(|a| match a.features {
        FeatureFamily::Spectrum => None,
        FeatureFamily::Kernels => Some(FeatureNames::Points),
        FeatureFamily::Quantiles => Some(FeatureNames::Quantiles),
        FeatureFamily::Hydra => Some(FeatureNames::Hydra),
    }),
    opt(
        "analysis.kernel_features",
        Kind::Integer,
        &["84 to 100000"],
        "",
        true,
        Group::Spectrum,
        "kernels only: features per channel (default 10000; more can help long windows)",
        (
            |a| json(&a.kernel_features),
            |a, b| {
                a.kernel_features_asked() == b.kernel_features_asked()
                    || a.features != FeatureFamily::Kernels
            },
            |a| toml_value(&a.kernel_features),
        ),
    ),
    opt(
        "analysis.spectrum",
        Kind::Choice,
        &["magnitude", "power", "log-power", "welch", "log-welch"],
        "",
        true,
        Group::Spectrum,
        "magnitude as the thesis; Welch or log spectra for noisy or wide-range signals",
        field!(spectrum),
    )
    .searched(&["log-welch", "welch"]),
    opt(
        "analysis.taper",
        Kind::Choice,
        &["none", "hann"],
        "",
        true,
        Group::Spectrum,
        "a Hann taper reduces leakage between neighbouring bins",
        field!(taper),
    )
    .searched(&["none", "hann"]),
    opt(
        "analysis.bins",
        Kind::Pair,
        &["[first, last] DFT bins, inclusive"],
        "",
        true,
        Group::Spectrum,
        "which DFT bins become features (thesis: 1..49, DC dropped); ignored with band or bands",
        (
            |a| json(&a.bins),
            |a, b| a.bins == b.bins || a.band.is_some() || a.bands.is_some(),
            // Left out where band or bands replace it.
            |a| {
                (a.band.is_none() && a.bands.is_none())
                    .then(|| toml_value(&a.bins))
                    .flatten()
            },
        ),
    )
    .labelled(|a| {
        (a.band.is_none() && a.bands.is_none()).then(|| FeatureNames::Bins {
            value: bin_value(a),
        })
    }),
    opt(
        "analysis.channels",
        Kind::List,
        &["more columns of the recordings"],
        "",
        false,
        Group::Signal,
        "more signal columns, their features after channel's",
        field!(channels),
    ),
    opt(
        "analysis.band",
        Kind::Pair,
        &["[low, high] frequencies, inclusive"],
        "Hz or cycles/mm",
        true,
        Group::Spectrum,
        "keep the frequencies of a band instead of bins (Hz on a time axis, cycles/mm on a position axis)",
        field!(band),
    )
    .labelled(|a| {
        (a.band.is_some() && a.bands.is_none()).then(|| FeatureNames::Bins {
            value: bin_value(a),
        })
    }),
    // Searched as a share of the points (a power of two): one table serves
    // any rate and window. A short (sub-)window's whole length too: a
    // quarter of 50 points is below any segment worth a spectrum.
    opt(
        "analysis.welch_segment",
        Kind::Integer,
        &["4 to the window's points"],
        "points",
        true,
        Group::Spectrum,
        "Welch only: points per segment (default: a quarter of the window)",
        (
            |a| json(&a.welch_segment),
            |a, b| a.dft_points() == b.dft_points(),
            |a| toml_value(&a.welch_segment),
        ),
    )
    .searched(&["points/4", "points/16", "points/1"]),
    opt(
        "analysis.welch_overlap",
        Kind::Number,
        &["0 <= overlap < 1"],
        "",
        true,
        Group::Spectrum,
        "Welch only: overlap of consecutive segments (default 0.5)",
        (
            |a| json(&a.welch_overlap),
            |a, b| a.overlap() == b.overlap() || !a.spectrum.is_welch(),
            |a| toml_value(&a.welch_overlap),
        ),
    ),
    opt(
        "analysis.bands",
        Kind::Table,
        &["{ count, from, to, scale }"],
        "Hz or cycles/mm",
        true,
        Group::Spectrum,
        "band energies instead of bins: few robust features for sound and vibration",
        field!(bands),
    )
    .labelled(|a| {
        let b = a.bands.filter(|_| a.cepstra.is_none())?;
        Some(FeatureNames::Bands {
            edges: b.edges(),
            unit: a.frequency_unit(),
            value: if a.spectrum.is_log() {
                "log10 energy"
            } else {
                "energy"
            },
        })
    }),
    // Searched on: 13 of log bands `tune` fits to the spectrum.
    opt(
        "analysis.cepstra",
        Kind::Integer,
        &["1 to bands.count"],
        "",
        true,
        Group::Spectrum,
        "cepstral coefficients of the log band energies (as MFCCs)",
        field!(cepstra),
    )
    .searched(&["none", "13"])
    .labelled(|a| {
        let m = a.cepstra.filter(|_| a.bands.is_some())?;
        // Those kept are the last of the `cepstra` coefficients.
        Some(FeatureNames::Cepstra {
            first: m.saturating_sub(a.features_per_channel()),
        })
    }),
    opt(
        "analysis.drop_level",
        Kind::Flag,
        &["true", "false"],
        "",
        true,
        Group::Spectrum,
        "drop c0, the level term, so a drifting gain does not move the features",
        (
            |a| json(&a.drop_level),
            |a, b| a.drop_level == b.drop_level,
            // Written when set, as `profile new` offers it.
            |a| a.drop_level.then(|| "true".into()),
        ),
    )
    .searched(&["false", "true"]),
    // Searched as sub-windows a quarter of the window, every eighth.
    opt(
        "analysis.windows",
        Kind::Table,
        &["{ length, hop }"],
        "axis",
        true,
        Group::Windows,
        "cut the window into sub-windows and classify a scan by their vote",
        field!(windows),
    )
    .searched(&["none", "window/4", "window/2"]),
];

/// One `[classifier]` option: what `check` says of it and what `tune`
/// searches (the classifier's values need no new features).
#[derive(Debug, Clone, Copy)]
pub struct ClassifierOption {
    /// The key, with its table: `classifier.k`.
    pub name: &'static str,
    pub kind: Kind,
    /// As [`AnalysisOption::allowed`].
    pub allowed: &'static [&'static str],
    pub advice: &'static str,
    /// As [`AnalysisOption::search`].
    pub search: &'static [&'static str],
    /// The value as a report writes it.
    value: fn(&Classifier) -> String,
    /// As [`AnalysisOption`]'s `line`.
    line: fn(&Classifier) -> Option<String>,
}

/// Every `[classifier]` option, in the order a profile lists them.
pub const CLASSIFIER_OPTIONS: &[ClassifierOption] = &[
    ClassifierOption {
        name: "classifier.k",
        kind: Kind::Integer,
        allowed: &["a whole number >= 1", "\"auto\""],
        advice: "the neighbours that vote: 1 for few recordings per label, more to outvote a stray one",
        search: &["1", "3", "5", "9"],
        value: |c| c.k_text(),
        line: |c| {
            if c.k_is_auto() {
                Some("\"auto\"".into())
            } else {
                toml_value(&c.k)
            }
        },
    },
    ClassifierOption {
        name: "classifier.metric",
        kind: Kind::Choice,
        allowed: &["euclidean", "manhattan", "cosine"],
        advice: "the distance between feature vectors; cosine for recordings whose level differs",
        search: &["euclidean", "manhattan", "cosine"],
        value: |c| json(&c.metric),
        line: |c| toml_value(&c.metric),
    },
    ClassifierOption {
        name: "classifier.weights",
        kind: Kind::Choice,
        allowed: &["uniform", "distance"],
        advice: "one vote per neighbour (the thesis), or each by 1 / distance",
        search: &["uniform", "distance"],
        value: |c| json(&c.weights),
        line: |c| toml_value(&c.weights),
    },
    ClassifierOption {
        name: "classifier.standardize",
        kind: Kind::Flag,
        allowed: &["true", "false"],
        advice: "z-score every feature over the training set: features of very different sizes",
        search: &["false", "true"],
        value: |c| json(&c.standardize),
        line: |c| toml_value(&c.standardize),
    },
    ClassifierOption {
        name: "classifier.method",
        kind: Kind::Choice,
        allowed: &["knn", "ridge", "lda"],
        advice: "k nearest neighbours (the thesis), or for many features (kernels, quantiles) a ridge classifier or a linear discriminant with a shrunk covariance (lda)",
        search: &["knn", "ridge", "lda"],
        value: |c| json(&c.method),
        line: |c| toml_value(&c.method),
    },
    ClassifierOption {
        name: "classifier.k_candidates",
        kind: Kind::List,
        allowed: &["whole numbers >= 1"],
        advice: "the values k = \"auto\" tries (default 1, 3, 5, …, 15)",
        search: &[],
        value: |c| json(&c.k_candidates),
        line: |c| toml_value(&c.k_candidates),
    },
];

/// A choice as a profile writes it, without quotes: `kernels`.
pub fn plain_word<T: serde::Serialize>(value: &T) -> String {
    plain(json(value))
}

/// A JSON value as a report reads it: a word without its quotes, `none`
/// for an option left out.
fn plain(json: String) -> String {
    match serde_json::from_str::<serde_json::Value>(&json) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(serde_json::Value::Null) => "none".into(),
        _ => json,
    }
}

impl ClassifierOption {
    /// The key within `[classifier]`: `k`.
    pub fn field(&self) -> &'static str {
        self.name.strip_prefix("classifier.").unwrap_or(self.name)
    }
    /// Whether only k nearest neighbours use it (every option but the
    /// method: a linear classifier standardises on its own).
    pub fn neighbours_only(&self) -> bool {
        self.field() != "method"
    }
    /// Whether every profile sets it (`k`, the thesis's `k = 10`), used or
    /// not: a setting that does not use it keeps the profile's line.
    pub fn required(&self) -> bool {
        self.field() == "k"
    }
    /// The value `c` gives it, as a report writes it (`euclidean`, `3`).
    pub fn text(&self, c: &Classifier) -> String {
        plain((self.value)(c))
    }
    /// As [`AnalysisOption::written`].
    pub fn written(&self, c: &Classifier) -> Option<String> {
        (self.line)(c)
    }
}

/// The `[classifier]` option named `name` (`k` or `classifier.k`).
pub fn classifier_option(name: &str) -> Option<&'static ClassifierOption> {
    CLASSIFIER_OPTIONS
        .iter()
        .find(|o| o.name == name || o.field() == name)
}

/// The words of a choice as a message lists them: `"none", "mean" or
/// "linear"`.
pub fn words(allowed: &[&str]) -> String {
    let quoted: Vec<String> = allowed.iter().map(|w| format!("{w:?}")).collect();
    match quoted.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// Why `v` is not a value of a [`Kind::Choice`] or [`Kind::Flag`] option
/// (`None` for another kind, or a value it takes): the words it takes and
/// its advice, from its declaration.
fn refused(kind: Kind, allowed: &[&str], advice: &str, v: &toml::Value) -> Option<String> {
    let fits = match (kind, v) {
        (Kind::Choice, toml::Value::String(s)) => allowed.contains(&s.as_str()),
        (Kind::Flag, toml::Value::Boolean(_)) => true,
        (Kind::Choice | Kind::Flag, _) => false,
        _ => true,
    };
    let expected = match kind {
        Kind::Flag => "true or false".to_string(),
        _ => words(allowed),
    };
    (!fits).then(|| format!("must be {expected}, got {v}: {advice}"))
}

/// The first word or flag written in `[analysis]` or `[classifier]` that
/// its option does not take, as `check` reports it: read from the text
/// before the values are, so the message and the list cannot disagree.
pub fn check_written(doc: &toml::Table) -> Option<Invalid> {
    let table = |name: &str| doc.get(name).and_then(|t| t.as_table());
    let analysis = table("analysis").into_iter().flat_map(|t| {
        ANALYSIS_OPTIONS.iter().filter_map(move |o| {
            let v = t.get(o.field())?;
            Some((o.name, refused(o.kind, o.allowed, o.advice, v)?))
        })
    });
    let classifier = table("classifier").into_iter().flat_map(|t| {
        CLASSIFIER_OPTIONS.iter().filter_map(move |o| {
            let v = t.get(o.field())?;
            Some((o.name, refused(o.kind, o.allowed, o.advice, v)?))
        })
    });
    analysis
        .chain(classifier)
        .next()
        .map(|(key, reason)| Invalid {
            key: key.to_string(),
            reason,
        })
}

impl AnalysisOption {
    /// The key within `[analysis]`: `spacing`.
    pub fn field(&self) -> &'static str {
        self.name.strip_prefix("analysis.").unwrap_or(self.name)
    }
    /// Whether only the spectrum family uses it: every option of the
    /// spectrum's group but the family itself and the kernels' count.
    pub fn spectrum_only(&self) -> bool {
        self.group == Group::Spectrum && !matches!(self.field(), "features" | "kernel_features")
    }
    /// The value `a` gives it, as a report writes it (`log-welch`, `512`,
    /// `none` when left out).
    pub fn text(&self, a: &Analysis) -> String {
        plain((self.value)(a))
    }
    /// The value `a` gives it as a profile line writes it (`"mean"`,
    /// `0.0003`, `[1, 49]`, `{ length = 1.49, hop = 0.745 }`); `None` when
    /// the line is left out (an option unset, or unused beside another).
    pub fn written(&self, a: &Analysis) -> Option<String> {
        (self.line)(a)
    }
}

/// The option named `name` (`spacing` or `analysis.spacing`).
pub fn option(name: &str) -> Option<&'static AnalysisOption> {
    ANALYSIS_OPTIONS
        .iter()
        .find(|o| o.name == name || o.field() == name)
}

/// The options `profile new` puts in `group`, in profile order.
pub fn in_group(group: Group) -> impl Iterator<Item = &'static AnalysisOption> {
    ANALYSIS_OPTIONS.iter().filter(move |o| o.group == group)
}

/// Whether two analyses resample every recording onto the same grids:
/// every option outside [`Group::Spectrum`] agrees (the spectrum's
/// options act only on the resampled points), and so does whether the
/// window is the scan leg.
pub fn same_grid(a: &Analysis, b: &Analysis) -> bool {
    a.window_is_scan_leg == b.window_is_scan_leg
        && ANALYSIS_OPTIONS
            .iter()
            .filter(|o| o.group != Group::Spectrum)
            .all(|o| (o.same)(a, b))
}

/// A difference that makes features incomparable: the first option (in
/// list order) on which `model` and `profile` disagree, with both values
/// as the model file writes them.
pub fn first_difference(
    model: &Analysis,
    profile: &Analysis,
) -> Option<(&'static str, String, String)> {
    ANALYSIS_OPTIONS
        .iter()
        .filter(|o| o.changes_features)
        .find(|o| !(o.same)(model, profile))
        .map(|o| (o.name, (o.value)(model), (o.value)(profile)))
}

/// Every field of [`Analysis`] that a profile sets, by name: written as an
/// exhaustive pattern so a new field does not compile until it is named
/// here (and then a test in options/tests.rs wants it in [`ANALYSIS_OPTIONS`]).
#[cfg(test)]
fn field_names(a: &Analysis) -> Vec<&'static str> {
    let Analysis {
        channel: _,
        axis: _,
        window: _,
        window_is_scan_leg: _, // how `window` was written, not an option
        spacing: _,
        detrend: _,
        spectrum: _,
        bins: _,
        channels: _,
        taper: _,
        band: _,
        welch_segment: _,
        welch_overlap: _,
        bands: _,
        cepstra: _,
        drop_level: _,
        features: _,
        kernel_features: _,
        windows: _,
    } = a;
    vec![
        "channel",
        "axis",
        "window",
        "spacing",
        "detrend",
        "spectrum",
        "bins",
        "channels",
        "taper",
        "band",
        "welch_segment",
        "welch_overlap",
        "bands",
        "cepstra",
        "drop_level",
        "features",
        "kernel_features",
        "windows",
    ]
}

mod reference;
pub use reference::{REGENERATE, profile_keys_markdown};

#[cfg(test)]
mod tests;
