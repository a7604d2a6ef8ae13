//! The search space of `tune`: [`space`], the options searched and their
//! values (simplest first) as the one list of options declares them
//! (`crate::profile::options`, each option's `search`), and how a choice
//! of values becomes an analysis and a classifier over the profile's own
//! ([`Setting`]).
//!
//! A value is set as a profile would write it, so a newly searched option
//! needs only its declaration. The values that depend on the data are
//! relative (a Welch segment `points/N`, a sub-window `window/N`) and
//! resolved here against the profile, so one list serves any rate and
//! window; cepstra get the log bands that fit the spectrum.

use std::sync::LazyLock;

use serde::Serialize;

use crate::analysis::check_settings;
use crate::profile::fitted::{fitting_bands, float, floor3};
use crate::profile::options::{
    ANALYSIS_OPTIONS, AnalysisOption, CLASSIFIER_OPTIONS, ClassifierOption, Group, Kind,
    classifier_option, option as option_named, plain_word,
};
use crate::profile::{Analysis, Classifier, FeatureFamily, Method, Windows};

/// One option searched: its name (the profile key) and its values as they
/// are written in a profile or described, simplest first.
#[derive(Debug, Clone, Copy)]
pub struct Searched {
    pub option: &'static str,
    pub values: &'static [&'static str],
    pub kind: Kind,
    /// Whether it changes the feature vectors (else it is a classifier
    /// option, and one feature matrix serves all its values).
    pub features: bool,
}

/// Every option `tune` searches, with its values, simplest first: the
/// analysis options in list order, then the classifier's. The order of
/// the rows is the order ties are broken in: between settings of equal
/// inner score, the one with the smaller sum of value positions wins, then
/// the one whose values come first row by row.
pub fn space() -> &'static [Searched] {
    static SPACE: LazyLock<Vec<Searched>> = LazyLock::new(|| {
        let analysis = ANALYSIS_OPTIONS.iter().map(|o| Searched {
            option: o.field(),
            values: o.search,
            kind: o.kind,
            features: o.changes_features,
        });
        let classifier = CLASSIFIER_OPTIONS.iter().map(|o| Searched {
            option: o.field(),
            values: o.search,
            kind: o.kind,
            features: false,
        });
        analysis
            .chain(classifier)
            .filter(|s| !s.values.is_empty())
            .collect()
    });
    &SPACE
}

/// The options `tune` decides: every `[analysis]` option of a group it
/// searches (the spectrum and its features, the sub-windows), in list
/// order, and every `[classifier]` option. The rest (the signal, the
/// resampling) stays the profile's.
pub fn decided_options() -> (
    impl Iterator<Item = &'static AnalysisOption>,
    impl Iterator<Item = &'static ClassifierOption>,
) {
    let searched = |g: Group| {
        ANALYSIS_OPTIONS
            .iter()
            .any(|o| o.group == g && !o.search.is_empty())
    };
    (
        ANALYSIS_OPTIONS.iter().filter(move |o| searched(o.group)),
        CLASSIFIER_OPTIONS.iter(),
    )
}

/// One point of the grid: the position of its value in each row of
/// [`space`], and the analysis and classifier it gives.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    pub values: Vec<usize>,
    pub analysis: Analysis,
    pub classifier: Classifier,
}

/// A setting's values by option, for reports: `[("spectrum", "log-welch"), …]`
/// with the resolved numbers (`welch_segment = 512`, not `points/4`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Described(pub Vec<(String, String)>);

impl Setting {
    /// The rank that breaks ties: the sum of value positions, then the
    /// positions row by row (smaller is simpler).
    pub fn simplicity(&self) -> (usize, &[usize]) {
        (self.values.iter().sum(), &self.values)
    }

    /// Whether the setting leaves the option unused: a spectrum option
    /// under another family, a neighbours' option under a linear
    /// classifier.
    pub fn unused(&self, option: &str) -> bool {
        (self.analysis.features != FeatureFamily::Spectrum
            && option_named(option).is_some_and(|o| o.spectrum_only()))
            || (self.classifier.method != Method::Knn
                && classifier_option(option).is_some_and(|o| o.neighbours_only()))
    }

    /// The family's and the classifier's positions among the values
    /// searched: smaller is simpler (the spectrum and k nearest neighbours
    /// first).
    pub fn family_rank(&self) -> (usize, usize) {
        let at = |option: &str| {
            space()
                .iter()
                .position(|s| s.option == option)
                .map_or(0, |row| self.values[row])
        };
        (at("features"), at("method"))
    }

    /// The family and the classifier, as a report names them:
    /// `kernels + ridge`.
    pub fn family(&self) -> String {
        format!(
            "{} + {}",
            plain_word(&self.analysis.features),
            plain_word(&self.classifier.method)
        )
    }

    /// The feature-changing part of the values.
    pub fn feature_key(&self) -> Vec<usize> {
        space()
            .iter()
            .zip(&self.values)
            .filter(|(s, _)| s.features)
            .map(|(_, &v)| v)
            .collect()
    }

    /// The feature options only, with their values.
    pub fn describe_features(&self) -> Described {
        let all = self.describe();
        Described(
            space()
                .iter()
                .zip(all.0)
                .filter(|(s, _)| s.features)
                .map(|(_, d)| d)
                .collect(),
        )
    }

    /// Each option with the value this setting gives it, as a report
    /// writes it.
    pub fn describe(&self) -> Described {
        let a = &self.analysis;
        let text = |option: &str| -> String {
            if self.unused(option) {
                return "-".into();
            }
            match option {
                // What a reader needs beyond the value: the bands under
                // the cepstra, the hop of the sub-windows.
                "cepstra" => match (a.cepstra, a.bands) {
                    (Some(n), Some(b)) => format!("{n} of {} bands", b.count),
                    _ => "none".into(),
                },
                "windows" => match a.windows {
                    Some(w) => format!("{} every {}", float(w.length), float(w.hop)),
                    None => "none".into(),
                },
                "welch_segment" if a.welch_segment.is_none() => "-".into(),
                _ => match (option_named(option), classifier_option(option)) {
                    (Some(o), _) => o.text(a),
                    (None, Some(o)) => o.text(&self.classifier),
                    (None, None) => "?".into(),
                },
            }
        };
        Described(
            space()
                .iter()
                .map(|s| (s.option.to_string(), text(s.option)))
                .collect(),
        )
    }
}

/// The largest power of two at most `n` (1 for 0).
fn floor_pow2(n: usize) -> usize {
    if n <= 1 {
        1
    } else {
        1usize << (usize::BITS - 1 - n.leading_zeros())
    }
}

/// The longest Welch segment searched as the whole (sub-)window
/// (`points/1`): short windows only, such as 2 s of a 100 Hz IMU or its
/// half-second sub-windows, where a quarter of the points leaves too few
/// for a spectrum (a quarter of 50 points is 12) and one or two segments
/// of it are the resolution there is. A long window is served by its
/// quarter and sixteenth; its whole length would give thousands of noisy
/// bins.
pub const WHOLE_SEGMENT_MOST: usize = 256;

/// A value relative to the data (`points/4`, `window/4`): its divisor.
fn share(value: &str, of: &str) -> Option<usize> {
    value.strip_prefix(of)?.strip_prefix('/')?.parse().ok()
}

/// `base` with each `(field, value, kind)` set as a profile writes it (a
/// word, a number, `true`); `none` leaves an option that is not a choice
/// out, at its default.
fn written<T: Serialize + serde::de::DeserializeOwned>(
    base: &T,
    set: &[(&str, &str, Kind)],
) -> Option<T> {
    let mut t = toml::Table::try_from(base).ok()?;
    for &(field, v, kind) in set {
        if v == "none" && kind != Kind::Choice {
            t.remove(field);
            continue;
        }
        // A bare word (`log-welch`) is a string, as a sweep reads it.
        let value = toml::from_str::<toml::Table>(&format!("v = {v}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(v.to_string()));
        t.insert(field.to_string(), value);
    }
    toml::Value::Table(t).try_into().ok()
}

/// `base` with the `fields` left out (at their defaults).
fn left_out<'a, T: Serialize + serde::de::DeserializeOwned>(
    base: &T,
    fields: impl Iterator<Item = &'a str>,
) -> Option<T> {
    let mut t = toml::Table::try_from(base).ok()?;
    for field in fields {
        t.remove(field);
    }
    toml::Value::Table(t).try_into().ok()
}

/// The analysis and classifier of one point of the grid over the profile's
/// own, or `None` when the values do not fit together or the data (a
/// segment below 16 points, no bands that fit, a setting the analysis
/// refuses).
pub fn resolve(base: (&Analysis, &Classifier), values: &[usize]) -> Option<Setting> {
    let rows = space();
    let mut chosen = Vec::with_capacity(rows.len());
    for (row, &v) in rows.iter().zip(values) {
        chosen.push((row, *row.values.get(v)?));
    }
    if chosen.len() != rows.len() {
        return None;
    }
    // A family and a classifier are options like the others, but the
    // spectrum's options mean nothing to another family and k nearest
    // neighbours' nothing to a linear classifier: those settings are
    // searched once, with the options they do not use at their first value
    // (written as left out). The random kernels and the competing kernels
    // go to linear classifiers only, as their papers pair them: thousands
    // of proportions of positive values, or of wins and losses, are made
    // for a linear decision, not for distances.
    let word = |option: &str| chosen.iter().find(|(r, _)| r.option == option).map(|x| x.1);
    let spectrum = word("features").is_none_or(|f| f == "spectrum");
    let neighbours = word("method").is_none_or(|m| m == "knn");
    if matches!(word("features"), Some("kernels" | "hydra")) && neighbours {
        return None;
    }
    let unused = |option: &str| {
        (!spectrum && option_named(option).is_some_and(|o| o.spectrum_only()))
            || (!neighbours && classifier_option(option).is_some_and(|o| o.neighbours_only()))
    };
    if rows
        .iter()
        .zip(values)
        .any(|(row, &v)| v != 0 && unused(row.option))
    {
        return None;
    }
    let chosen: Vec<_> = chosen
        .into_iter()
        .filter(|(row, _)| !unused(row.option))
        .collect();
    // Every value as a profile writes it, at once; those relative to the
    // data after.
    let as_written = |features: bool| -> Vec<(&str, &str, Kind)> {
        chosen
            .iter()
            .filter(|(row, v)| row.features == features && !v.contains('/'))
            .map(|(row, v)| (row.option, *v, row.kind))
            .collect()
    };
    // What the search decides starts afresh: an option it decides but
    // does not search, or one whose value is relative to the data, is
    // left out (at its default) until set; the rest (channels, axis,
    // window, spacing, detrend) is the profile's.
    let (analysis, classifier) = decided_options();
    let afresh = |field: &str, search: &[&str]| {
        search.is_empty()
            || unused(field)
            || chosen
                .iter()
                .any(|(row, v)| row.option == field && v.contains('/'))
    };
    let mut a: Analysis = left_out(
        base.0,
        analysis
            .filter(|o| afresh(o.field(), o.search))
            .map(|o| o.field()),
    )?;
    // An option every profile sets stays the profile's when unused.
    let mut c: Classifier = left_out(
        base.1,
        classifier
            .filter(|o| afresh(o.field(), o.search) && !(o.required() && unused(o.field())))
            .map(|o| o.field()),
    )?;
    a = written(&a, &as_written(true))?;
    a.window_is_scan_leg = base.0.window_is_scan_leg;
    c = written(&c, &as_written(false))?;
    let value = |option: &str| chosen.iter().find(|(r, _)| r.option == option).map(|x| x.1);
    if let Some(n) = value("windows").and_then(|v| share(v, "window")) {
        let length = floor3((a.window[1] - a.window[0]) / n as f64).0;
        a.windows = Some(Windows {
            length,
            hop: floor3(length / 2.0).0,
        });
    }
    // A power of two, at most this share of the (sub-)window's points,
    // and every bin of it but DC.
    if let Some(n) = value("welch_segment").and_then(|v| share(v, "points")) {
        let segment = floor_pow2(a.points() / n.max(1));
        if segment < 16 || (n == 1 && segment > WHOLE_SEGMENT_MOST) {
            return None;
        }
        a.welch_segment = Some(segment);
        a.bins = [1, segment / 2];
    }
    match a.cepstra {
        // Cepstra are of log band energies: the log spectrum's, in bands
        // that fit it.
        Some(n) => {
            if !a.spectrum.is_log() {
                return None;
            }
            let bands = fitting_bands(&a)?;
            a.bands = Some(bands);
            a.cepstra = Some(n.min(bands.count));
        }
        // Nothing to drop: the same setting as drop_level = false.
        None if a.drop_level => return None,
        None => {}
    }
    check_settings(&a).ok()?;
    Some(Setting {
        values: values.to_vec(),
        analysis: a,
        classifier: c,
    })
}

/// Every point of the grid that resolves, in grid order (the last row
/// varying fastest).
pub fn grid(base: (&Analysis, &Classifier)) -> Vec<Setting> {
    let sizes: Vec<usize> = space().iter().map(|s| s.values.len()).collect();
    let total: usize = sizes.iter().product();
    let mut out = Vec::new();
    for mut i in 0..total {
        let mut values = vec![0; sizes.len()];
        for (v, &n) in values.iter_mut().zip(&sizes).rev() {
            *v = i % n;
            i /= n;
        }
        if let Some(s) = resolve(base, &values) {
            out.push(s);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fingertip() -> (Analysis, Classifier) {
        let a = Analysis {
            channel: "vib".into(),
            axis: "t_s".into(),
            window: [0.0, 5.99],
            spacing: 1.0 / 2200.0,
            ..Analysis::default()
        };
        (a, Classifier::default())
    }

    #[test]
    fn every_setting_resolves_to_valid_distinct_settings() {
        let (a, c) = fingertip();
        let g = grid((&a, &c));
        // k nearest neighbours' settings: every classifier row but the method.
        let neighbours: usize = space()
            .iter()
            .filter(|s| !s.features && s.option != "method")
            .map(|s| s.values.len())
            .product();
        let count = |family: &str| g.iter().filter(|s| s.family() == family).count();
        // taper × segment × windows (none, a quarter, a half) × (welch's
        // bins; log-welch's bins, cepstra with and without c0): cepstra
        // only on the log spectrum.
        let spectra = 2 * 2 * 3 * (1 + 3);
        assert_eq!(count("spectrum + knn"), spectra * neighbours);
        assert_eq!(count("spectrum + ridge"), spectra);
        assert_eq!(count("spectrum + lda"), spectra);
        // The other families: only the sub-windows (none, a quarter, a
        // half); both kinds of kernels with the linear classifiers only.
        assert_eq!(count("quantiles + knn"), 3 * neighbours);
        assert_eq!(count("quantiles + ridge"), 3);
        assert_eq!(count("quantiles + lda"), 3);
        assert_eq!(count("kernels + knn"), 0);
        assert_eq!(count("kernels + ridge"), 3);
        assert_eq!(count("kernels + lda"), 3);
        assert_eq!(count("hydra + knn"), 0);
        assert_eq!(count("hydra + ridge"), 3);
        assert_eq!(count("hydra + lda"), 3);
        assert_eq!(g.len(), (spectra + 3) * (neighbours + 2) + 6 + 6);
        // A family's unused options are at their defaults and said as `-`.
        for s in g.iter().filter(|s| s.family() == "kernels + ridge") {
            assert_eq!(s.analysis.welch_segment, None);
            assert_eq!(s.classifier.k, c.k, "the profile's k is kept");
            let d = s.describe();
            let said = |o: &str| d.0.iter().find(|(k, _)| k == o).unwrap().1.clone();
            assert_eq!(said("welch_segment"), "-");
            assert_eq!(said("k"), "-");
            assert_eq!(said("method"), "ridge");
        }
        for s in &g {
            assert!(check_settings(&s.analysis).is_ok());
        }
        for (i, s) in g.iter().enumerate() {
            for t in &g[i + 1..] {
                assert!(s.analysis != t.analysis || s.classifier != t.classifier);
            }
        }
        // The first point is the simplest: every row's first value.
        assert_eq!(g[0].simplicity().0, 0);
        assert_eq!(g[0].analysis.welch_segment, Some(2048));
        assert_eq!(g[0].analysis.bins, [1, 1024]);
    }

    /// 200-point trials (2 s at 100 Hz, the long set cut into trials):
    /// coarse spectra still get bands (8 of them) for cepstra, and half
    /// windows start every half window, though that is half a sample period
    /// off the samples (the analysis bins samples on edges: issue 21).
    /// 2 s at 100 Hz (the long set cut into trials): 199 points.
    fn short_trials() -> Analysis {
        Analysis {
            channel: "acc".into(),
            axis: "t_s".into(),
            window: [0.0, 1.98],
            spacing: 0.01,
            ..Analysis::default()
        }
    }

    #[test]
    fn short_trials_get_coarse_bands_and_half_windows_every_half() {
        let a = short_trials();
        let c = Classifier::default();
        let g = grid((&a, &c));
        assert!(
            g.iter()
                .any(|s| s.analysis.bands.is_some_and(|b| b.count == 8)),
            "no cepstra on 200-point trials"
        );
        let hops: Vec<f64> = g
            .iter()
            .filter_map(|s| s.analysis.windows)
            .map(|w| w.hop)
            .collect();
        assert!(hops.contains(&0.495), "{hops:?}");
    }

    /// A short (sub-)window is also one segment as long as it allows: a
    /// quarter of the trial's 50-point sub-windows (12 points) is too few,
    /// so without it sub-windows of short trials were never searched. A
    /// long window is not (its whole length: thousands of bins).
    #[test]
    fn a_short_window_is_searched_whole_and_a_long_one_is_not() {
        let c = Classifier::default();
        let segments = |a: &Analysis, length: Option<f64>| -> Vec<usize> {
            let mut s: Vec<usize> = grid((a, &c))
                .iter()
                .filter(|s| s.analysis.windows.map(|w| w.length) == length)
                .filter_map(|s| s.analysis.welch_segment)
                .collect();
            s.sort_unstable();
            s.dedup();
            s
        };
        let short = short_trials();
        assert_eq!(segments(&short, None), [32, 128]);
        assert_eq!(segments(&short, Some(0.495)), [32]);
        assert_eq!(segments(&short, Some(0.99)), [16, 64]);
        let (long, _) = fingertip();
        assert_eq!(segments(&long, None), [512, 2048]);
        assert!(
            grid((&long, &c))
                .iter()
                .filter(|s| s.analysis.features == FeatureFamily::Spectrum)
                .all(|s| s.analysis.welch_segment.is_some_and(|n| n <= 2048))
        );
    }

    #[test]
    fn cepstra_get_bands_that_fit_and_windows_a_quarter() {
        let (a, c) = fingertip();
        let row = |o: &str| space().iter().position(|s| s.option == o).unwrap();
        let mut v = vec![0; space().len()];
        v[row("cepstra")] = 1;
        v[row("drop_level")] = 1;
        v[row("windows")] = 1;
        let s = resolve((&a, &c), &v).unwrap();
        assert_eq!(s.analysis.cepstra, Some(13));
        assert!(s.analysis.drop_level);
        let w = s.analysis.windows.unwrap();
        assert_eq!((w.length, w.hop), (1.49, 0.745));
        assert_eq!(s.analysis.welch_segment, Some(512));
        let d = s.describe();
        assert_eq!(d.0[0], ("features".to_string(), "spectrum".to_string()));
        assert_eq!(d.0[1], ("spectrum".to_string(), "log-welch".to_string()));
    }

    /// Each value the option list declares reaches its option: a setting
    /// with it says it (a word or number as written; relative values
    /// resolved), so a newly searched option needs only its declaration.
    #[test]
    fn every_declared_value_sets_its_option() {
        // A long window and a short one (a whole segment only fits there).
        let (a, c) = fingertip();
        let mut g = grid((&a, &c));
        g.extend(grid((&short_trials(), &c)));
        for (row, r) in space().iter().enumerate() {
            for (i, v) in r.values.iter().enumerate() {
                let s = g
                    .iter()
                    .find(|s| s.values[row] == i)
                    .unwrap_or_else(|| panic!("{} = {v}: in no setting", r.option));
                let said = &s.describe().0[row];
                assert_eq!(said.0, r.option);
                let relative = v.contains('/');
                if relative {
                    assert!(
                        said.1.chars().next().is_some_and(|c| c.is_ascii_digit()),
                        "{said:?}"
                    );
                } else {
                    assert!(said.1.starts_with(v), "{} = {v} gave {said:?}", r.option);
                }
            }
        }
        // The rows are the options that declare values, in list order.
        let declared: Vec<&str> = ANALYSIS_OPTIONS
            .iter()
            .filter(|o| !o.search.is_empty())
            .map(|o| o.field())
            .chain(
                CLASSIFIER_OPTIONS
                    .iter()
                    .filter(|o| !o.search.is_empty())
                    .map(|o| o.field()),
            )
            .collect();
        let rows: Vec<&str> = space().iter().map(|r| r.option).collect();
        assert_eq!(rows, declared);
    }
}
