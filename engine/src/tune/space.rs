//! The search space of `tune`: [`SPACE`], one table of the options searched
//! and their values (simplest first), and how a choice of values becomes an
//! analysis and a classifier over the profile's own ([`Setting`]).
//!
//! The values of the options that depend on the data are relative (a
//! Welch segment is a fraction of the analysed window's points, a
//! sub-window a fraction of the window) and resolved against the profile,
//! so one table serves any rate and window.

use serde::Serialize;

use crate::analysis::check_settings;
use crate::profile::{
    Analysis, BandScale, Bands, Classifier, Metric, SpectrumKind, Taper, Weights, Windows,
};

/// One option searched: its name (the profile key) and its values as they
/// are written in a profile or described, simplest first.
#[derive(Debug, Clone, Copy)]
pub struct Searched {
    pub option: &'static str,
    pub values: &'static [&'static str],
    /// Whether it changes the feature vectors (else it is a classifier
    /// option, and one feature matrix serves all its values).
    pub features: bool,
}

/// Every option `tune` searches, with its values, simplest first. The
/// order of the rows is the order ties are broken in: between settings of
/// equal inner score, the one with the smaller sum of value positions wins,
/// then the one whose values come first row by row.
pub const SPACE: &[Searched] = &[
    Searched {
        option: "spectrum",
        values: &["log-welch", "welch"],
        features: true,
    },
    Searched {
        option: "taper",
        values: &["none", "hann"],
        features: true,
    },
    // A power of two: the largest at most this share of the (sub-)window.
    Searched {
        option: "welch_segment",
        values: &["points/4", "points/16"],
        features: true,
    },
    // 13 cepstra of log bands fitted to the spectrum (with `drop_level`),
    // or every bin of the spectrum but DC.
    Searched {
        option: "cepstra",
        values: &["none", "13"],
        features: true,
    },
    Searched {
        option: "drop_level",
        values: &["false", "true"],
        features: true,
    },
    // Sub-windows a quarter of the window, every eighth.
    Searched {
        option: "windows",
        values: &["none", "window/4"],
        features: true,
    },
    Searched {
        option: "k",
        values: &["1", "3", "5", "9"],
        features: false,
    },
    Searched {
        option: "metric",
        values: &["euclidean", "manhattan", "cosine"],
        features: false,
    },
    Searched {
        option: "weights",
        values: &["uniform", "distance"],
        features: false,
    },
    Searched {
        option: "standardize",
        values: &["false", "true"],
        features: false,
    },
];

/// The cepstra kept when `cepstra` is searched on, and the bands under them.
const CEPSTRA: usize = 13;

/// One point of the grid: the position of its value in each row of
/// [`SPACE`], and the analysis and classifier it gives.
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

    /// The feature-changing part of the values.
    pub fn feature_key(&self) -> Vec<usize> {
        SPACE
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
            SPACE
                .iter()
                .zip(all.0)
                .filter(|(s, _)| s.features)
                .map(|(_, d)| d)
                .collect(),
        )
    }

    /// Each option with the value this setting gives it.
    pub fn describe(&self) -> Described {
        let a = &self.analysis;
        let c = &self.classifier;
        let windows = match a.windows {
            Some(w) => format!("{} every {}", trim(w.length), trim(w.hop)),
            None => "none".into(),
        };
        let text = |option: &str| -> String {
            match option {
                "spectrum" => kebab(&a.spectrum),
                "taper" => kebab(&a.taper),
                "welch_segment" => a.welch_segment.map_or("-".into(), |s| s.to_string()),
                "cepstra" => match (a.cepstra, a.bands) {
                    (Some(n), Some(b)) => format!("{n} of {} bands", b.count),
                    _ => "none".into(),
                },
                "drop_level" => a.drop_level.to_string(),
                "windows" => windows.clone(),
                "k" => c.k.to_string(),
                "metric" => kebab(&c.metric),
                "weights" => kebab(&c.weights),
                "standardize" => c.standardize.to_string(),
                _ => "?".into(),
            }
        };
        Described(
            SPACE
                .iter()
                .map(|s| (s.option.to_string(), text(s.option)))
                .collect(),
        )
    }
}

/// A number as TOML writes it, shortest (`0.25`, `3.0`).
pub fn trim(v: f64) -> String {
    let s = format!("{v}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// An enum's profile spelling (its serde name).
pub fn kebab<T: Serialize>(v: &T) -> String {
    serde_json::to_value(v)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

/// The largest power of two at most `n` (1 for 0).
fn floor_pow2(n: usize) -> usize {
    if n <= 1 {
        1
    } else {
        1usize << (usize::BITS - 1 - n.leading_zeros())
    }
}

/// A value rounded down to three significant digits, so a written band
/// edge or sub-window reads cleanly and stays inside what it bounds.
fn floor3(v: f64) -> f64 {
    if v <= 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(2 - v.log10().floor() as i32);
    (v * scale).floor() / scale
}

/// Log bands from a few bins up to Nyquist that each hold a bin: 32, or
/// fewer when the spectrum is too coarse.
fn fitting_bands(a: &Analysis) -> Option<Bands> {
    let bw = a.bin_width();
    let nyquist = bw * (a.dft_points() / 2) as f64;
    for count in [32, 24, 16] {
        for lowest in [2.0, 4.0, 8.0] {
            let b = Bands {
                count,
                from: floor3(bw * lowest),
                to: floor3(nyquist),
                scale: BandScale::Log,
            };
            let candidate = Analysis {
                bands: Some(b),
                cepstra: Some(CEPSTRA.min(count)),
                ..a.clone()
            };
            if b.to > b.from && check_settings(&candidate).is_ok() {
                return Some(b);
            }
        }
    }
    None
}

/// The analysis and classifier of one point of the grid over the profile's
/// own, or `None` when the values do not fit together or the data (a
/// segment below 16 points, no bands that fit, a setting the analysis
/// refuses).
pub fn resolve(base: (&Analysis, &Classifier), values: &[usize]) -> Option<Setting> {
    let mut a = base.0.clone();
    let mut c = base.1.clone();
    // What the search decides is set afresh; the rest (channels, axis,
    // window, spacing, detrend) is the profile's.
    a.band = None;
    a.bands = None;
    a.cepstra = None;
    a.drop_level = false;
    a.welch_overlap = None;
    c.k_candidates = None;
    let value = |option: &str| {
        let row = SPACE.iter().position(|s| s.option == option)?;
        Some(SPACE[row].values[*values.get(row)?])
    };
    a.spectrum = match value("spectrum")? {
        "welch" => SpectrumKind::Welch,
        _ => SpectrumKind::LogWelch,
    };
    a.taper = match value("taper")? {
        "hann" => Taper::Hann,
        _ => Taper::None,
    };
    a.windows = match value("windows")? {
        "window/4" => {
            let span = a.window[1] - a.window[0];
            let length = floor3(span / 4.0);
            Some(Windows {
                length,
                hop: floor3(length / 2.0),
            })
        }
        _ => None,
    };
    let share = match value("welch_segment")? {
        "points/16" => 16,
        _ => 4,
    };
    a.welch_segment = None;
    let segment = floor_pow2(a.points() / share);
    if segment < 16 {
        return None;
    }
    a.welch_segment = Some(segment);
    a.bins = [1, segment / 2];
    let cepstra = value("cepstra")? != "none";
    let drop_level = value("drop_level")? == "true";
    if cepstra {
        // Cepstra are of log band energies: the log spectrum's.
        if !a.spectrum.is_log() {
            return None;
        }
        let bands = fitting_bands(&a)?;
        a.bands = Some(bands);
        a.cepstra = Some(CEPSTRA.min(bands.count));
        a.drop_level = drop_level;
    } else if drop_level {
        // Nothing to drop: the same setting as drop_level = false.
        return None;
    }
    c.k = value("k")?.parse().ok()?;
    c.metric = match value("metric")? {
        "manhattan" => Metric::Manhattan,
        "cosine" => Metric::Cosine,
        _ => Metric::Euclidean,
    };
    c.weights = match value("weights")? {
        "distance" => Weights::Distance,
        _ => Weights::Uniform,
    };
    c.standardize = value("standardize")? == "true";
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
    let sizes: Vec<usize> = SPACE.iter().map(|s| s.values.len()).collect();
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
        let classifier_points: usize = SPACE
            .iter()
            .filter(|s| !s.features)
            .map(|s| s.values.len())
            .product();
        assert_eq!(g.len() % classifier_points, 0);
        // welch × taper × segment × (bins, cepstra with and without c0) ×
        // windows, but cepstra only on the log spectrum.
        assert_eq!(g.len() / classifier_points, 2 * 2 * 2 * (3 + 1));
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

    #[test]
    fn cepstra_get_bands_that_fit_and_windows_a_quarter() {
        let (a, c) = fingertip();
        let row = |o: &str| SPACE.iter().position(|s| s.option == o).unwrap();
        let mut v = vec![0; SPACE.len()];
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
        assert_eq!(d.0[0], ("spectrum".to_string(), "log-welch".to_string()));
    }
}
