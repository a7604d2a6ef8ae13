//! The one list of analysis options: each `[analysis]` key declared once
//! ([`ANALYSIS_OPTIONS`]) with its type, allowed values, unit, whether a
//! sweep may vary it, whether it changes the features (and so which models
//! fit a profile), its group and one line of advice for `profile new`, and
//! a small default search range for a tuner. The model compatibility
//! check ([`first_difference`]) and the sweep keys read it; adding an
//! option means its analysis code, its line here, and its tests (the
//! compiler and a test below refuse an `Analysis` field missing here).

use super::analysis::Analysis;

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

/// Where `profile new` puts an option.
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

/// One `[analysis]` option.
#[derive(Debug, Clone, Copy)]
pub struct AnalysisOption {
    /// The key, with its table: `analysis.spacing`.
    pub name: &'static str,
    pub kind: Kind,
    /// The words a [`Kind::Choice`] takes, or a short description of the
    /// values allowed.
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
    /// A small default search range for a tuner (`evaluate --sweep`
    /// syntax), where one makes sense.
    pub search: Option<&'static str>,
    /// The value as the model file writes it, and whether two analyses
    /// agree on it (some options only matter when another is set).
    value: fn(&Analysis) -> String,
    same: fn(&Analysis, &Analysis) -> bool,
}

/// How an option is written and compared.
type Compare = (fn(&Analysis) -> String, fn(&Analysis, &Analysis) -> bool);

fn json<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_else(|e| format!("<{e}>"))
}

macro_rules! field {
    ($f:ident) => {
        (
            |a: &Analysis| json(&a.$f),
            |a: &Analysis, b: &Analysis| a.$f == b.$f,
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
    search: Option<&'static str>,
    (value, same): Compare,
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
        search,
        value,
        same,
    }
}

/// Every `[analysis]` option, in the order a profile lists them.
pub const ANALYSIS_OPTIONS: &[AnalysisOption] = &[
    opt(
        "analysis.channel",
        Kind::Text,
        &["a column of the recordings"],
        "",
        false,
        Group::Signal,
        "the signal column the features come from (thesis: y_m, the probe's height)",
        None,
        field!(channel),
    ),
    opt(
        "analysis.axis",
        Kind::Text,
        &["a position column (*_m) or t_s"],
        "",
        false,
        Group::Signal,
        "resample along position (a surface's texture) or time (vibration, sound)",
        None,
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
        None,
        field!(window),
    ),
    opt(
        "analysis.spacing",
        Kind::Number,
        &["> 0"],
        "axis",
        true,
        Group::Resampling,
        "resampling step: smaller keeps finer texture, up to the sensor's resolution",
        Some("0.0002,0.0003,0.0005"),
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
        Some("mean,linear"),
        field!(detrend),
    ),
    opt(
        "analysis.taper",
        Kind::Choice,
        &["none", "hann"],
        "",
        true,
        Group::Resampling,
        "a Hann taper reduces leakage between neighbouring bins",
        Some("none,hann"),
        field!(taper),
    ),
    opt(
        "analysis.spectrum",
        Kind::Choice,
        &["magnitude", "power", "log-power", "welch", "log-welch"],
        "",
        true,
        Group::Spectrum,
        "magnitude as the thesis; Welch or log spectra for noisy or wide-range signals",
        Some("magnitude,power,log-power"),
        field!(spectrum),
    ),
    opt(
        "analysis.bins",
        Kind::Pair,
        &["[first, last] DFT bins, inclusive"],
        "",
        true,
        Group::Spectrum,
        "which DFT bins become features (thesis: 1..49, DC dropped); ignored with band or bands",
        Some("[1,24],[1,49]"),
        (
            |a| json(&a.bins),
            |a, b| a.bins == b.bins || a.band.is_some() || a.bands.is_some(),
        ),
    ),
    opt(
        "analysis.channels",
        Kind::List,
        &["more columns of the recordings"],
        "",
        false,
        Group::Signal,
        "more signal columns, their features after channel's",
        None,
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
        None,
        field!(band),
    ),
    opt(
        "analysis.welch_segment",
        Kind::Integer,
        &[">= 2 points"],
        "points",
        true,
        Group::Spectrum,
        "Welch only: points per segment (default: a quarter of the window)",
        None,
        (
            |a| json(&a.welch_segment),
            |a, b| a.dft_points() == b.dft_points(),
        ),
    ),
    opt(
        "analysis.welch_overlap",
        Kind::Number,
        &["0 <= overlap < 1"],
        "",
        true,
        Group::Spectrum,
        "Welch only: overlap of consecutive segments (default 0.5)",
        Some("0.25,0.5,0.75"),
        (
            |a| json(&a.welch_overlap),
            |a, b| a.overlap() == b.overlap() || !a.spectrum.is_welch(),
        ),
    ),
    opt(
        "analysis.bands",
        Kind::Table,
        &["{ count, low, high, scale }"],
        "Hz or cycles/mm",
        true,
        Group::Spectrum,
        "band energies instead of bins: few robust features for sound and vibration",
        None,
        field!(bands),
    ),
    opt(
        "analysis.cepstra",
        Kind::Integer,
        &[">= 1, <= the bands' count"],
        "",
        true,
        Group::Spectrum,
        "cepstral coefficients of the log band energies (as MFCCs)",
        Some("8,13,20"),
        field!(cepstra),
    ),
    opt(
        "analysis.drop_level",
        Kind::Flag,
        &["true", "false"],
        "",
        true,
        Group::Spectrum,
        "drop c0, the level term, so a drifting gain does not move the features",
        Some("false,true"),
        field!(drop_level),
    ),
    opt(
        "analysis.windows",
        Kind::Table,
        &["{ length, hop }"],
        "axis",
        true,
        Group::Windows,
        "cut the window into sub-windows and classify a scan by their vote",
        None,
        field!(windows),
    ),
];

impl AnalysisOption {
    /// The key within `[analysis]`: `spacing`.
    pub fn field(&self) -> &'static str {
        self.name.strip_prefix("analysis.").unwrap_or(self.name)
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
/// here (and then the test below wants it in [`ANALYSIS_OPTIONS`]).
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
        "windows",
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_analysis_field_is_declared_once() {
        let names = field_names(&Analysis::default());
        for n in &names {
            assert_eq!(
                ANALYSIS_OPTIONS.iter().filter(|o| o.field() == *n).count(),
                1,
                "analysis.{n} must be declared once in ANALYSIS_OPTIONS"
            );
        }
        assert_eq!(
            names.len(),
            ANALYSIS_OPTIONS.len(),
            "an option that is no field"
        );
        // What serde writes of an analysis is among the options, too.
        let v = serde_json::to_value(Analysis::default()).unwrap();
        for key in v.as_object().unwrap().keys() {
            assert!(
                option(key).is_some(),
                "analysis.{key} is not in ANALYSIS_OPTIONS"
            );
        }
    }

    #[test]
    fn a_difference_in_sub_windows_is_a_difference() {
        let a = Analysis::default();
        let mut b = a.clone();
        assert!(first_difference(&a, &b).is_none());
        b.windows = Some(crate::profile::Windows {
            length: 0.01,
            hop: 0.005,
        });
        // Sub-windows change the DFT length too, so welch_segment's
        // comparison may name it first; windows itself differs either way.
        assert!(first_difference(&a, &b).is_some());
        let w = option("windows").unwrap();
        assert!(!(w.same)(&a, &b));
        assert!((w.value)(&b).contains("0.005"));
    }

    #[test]
    fn bins_do_not_matter_under_a_band() {
        let a = Analysis {
            band: Some([1.0, 2.0]),
            ..Analysis::default()
        };
        let mut b = a.clone();
        b.bins = [1, 3];
        assert!(first_difference(&a, &b).is_none());
    }

    #[test]
    fn every_search_range_parses_as_a_sweep() {
        for o in ANALYSIS_OPTIONS {
            if let Some(s) = o.search {
                assert!(o.sweepable, "{}", o.name);
                crate::evaluate::sweep::Swept::parse(&format!("{}={s}", o.field()))
                    .unwrap_or_else(|e| panic!("{}: {e}", o.name));
            }
        }
    }
}
