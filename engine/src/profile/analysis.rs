//! `[analysis]`: how a recording becomes a feature vector — the channel(s),
//! the axis, the window (or `"scan-leg"`), the spacing, the detrending, the
//! spectrum, the taper, and the bins or band kept — and the pure arithmetic
//! on those settings (points, DFT bins, bin width) that the analysis engine
//! and the checks share. Schema and checks only: the signal processing lives
//! in `crate::analysis`, which depends on this module, never the reverse.

use serde::{Deserialize, Serialize};

use super::families::{FeatureFamily, quantile_feature_count};
use super::options::{option, words};
use super::path::PathSpec;
use super::{Invalid, bad, compact, dist, finite_pos, is_default};

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
    /// `log10` of the power, floored at [`LOG_FLOOR`].
    LogPower,
    /// Welch's averaged periodogram: segments of `welch_segment` points
    /// overlapping by `welch_overlap`, each tapered by `taper`.
    Welch,
    /// `log10` of the Welch spectrum, floored at [`LOG_FLOOR`].
    LogWelch,
}

/// The floor under every logarithm of a power (`log-power`, `log-welch`,
/// log band energies, cepstra): `log10(max(P, LOG_FLOOR))`, so a silent
/// window gives finite features (−300) rather than −inf.
pub const LOG_FLOOR: f64 = 1e-300;

impl SpectrumKind {
    /// Welch's segments (`welch`, `log-welch`).
    pub fn is_welch(self) -> bool {
        matches!(self, SpectrumKind::Welch | SpectrumKind::LogWelch)
    }
    /// A logarithm of a power (`log-power`, `log-welch`).
    pub fn is_log(self) -> bool {
        matches!(self, SpectrumKind::LogPower | SpectrumKind::LogWelch)
    }
    /// The linear power this kind takes the log of (itself when not a log).
    pub fn linear(self) -> SpectrumKind {
        match self {
            SpectrumKind::LogPower => SpectrumKind::Power,
            SpectrumKind::LogWelch => SpectrumKind::Welch,
            k => k,
        }
    }
}

/// How `bands` spaces its edges.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum BandScale {
    /// Geometric: each band a fixed ratio wider than the one before.
    #[default]
    Log,
    /// Arithmetic: every band equally wide.
    Linear,
}

/// `bands = { count = N, from = F0, to = F1, scale = "log" }`: the power
/// summed over `count` bands with edges spaced from `from` to `to` (in the
/// unit of `band`: Hz on a time axis, cycles/mm on a position axis).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Bands {
    pub count: usize,
    pub from: f64,
    pub to: f64,
    #[serde(default)]
    pub scale: BandScale,
}

impl Bands {
    /// The `count + 1` edges e_0 = from .. e_N = to.
    pub fn edges(&self) -> Vec<f64> {
        let n = self.count.max(1);
        (0..=n)
            .map(|i| {
                let t = i as f64 / n as f64;
                if i == n {
                    self.to
                } else {
                    match self.scale {
                        BandScale::Log => self.from * (self.to / self.from).powf(t),
                        BandScale::Linear => self.from + (self.to - self.from) * t,
                    }
                }
            })
            .collect()
    }
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
    #[serde(default, deserialize_with = "bins_pair")]
    pub bins: [usize; 2],
    /// More signal columns, analysed like `channel` and their features
    /// concatenated after its own, in this order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<String>,
    #[serde(default, skip_serializing_if = "is_default")]
    pub taper: Taper,
    /// The frequencies kept, [low, high] inclusive, instead of `bins`: in Hz
    /// for a time axis (`t_s`), in cycles/mm for a position axis (`*_m`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "band_pair"
    )]
    pub band: Option<[f64; 2]>,
    /// Welch only: points per segment (default: a quarter of the window).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub welch_segment: Option<usize>,
    /// Welch only: overlap of consecutive segments, 0 <= overlap < 1 (default 0.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub welch_overlap: Option<f64>,
    /// Band energies instead of `bins`/`band`: one feature per band, the
    /// power summed over its bins (its log10 for a log spectrum).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bands: Option<Bands>,
    /// The first `cepstra` coefficients of the orthonormal DCT-II of the log
    /// band energies instead of the energies themselves (as MFCCs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cepstra: Option<usize>,
    /// Drop c_0, the cepstrum's level term (the mean log band energy), and
    /// keep c_1..c_{cepstra-1}: a gain that drifts between trials moves
    /// only c_0, so without it the features do not see the drift.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub drop_level: bool,

    /// What the features are: the spectrum's (the default, the thesis's),
    /// random convolutional kernels, or interval quantiles; see
    /// [`FeatureFamily`].
    #[serde(default, skip_serializing_if = "is_default")]
    pub features: FeatureFamily,
    /// Random kernels only: the features asked for per channel (default
    /// 10000; a multiple of 84 is made, 9996 for the default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernel_features: Option<usize>,

    // --- Sub-windows (issue 13 part 3) ---
    /// Cut the window into sub-windows `length` long every `hop` (axis
    /// unit), each analysed as if it were the window; a recording is
    /// classified by its sub-windows' vote. See [`Windows`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub windows: Option<Windows>,
}

/// `windows = { length = L, hop = H }`: sub-window `j` starts at
/// `s_j = w0 + j·H` for `j = 0, 1, …` while `s_j + L <= w1 + 1e-9·L`, with
/// `[w0, w1]` the resolved `window`; each is analysed exactly as if
/// `window = [s_j, s_j + L]`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Windows {
    /// Sub-window length, in the axis unit.
    pub length: f64,
    /// Distance between consecutive sub-window starts, in the axis unit.
    pub hop: f64,
}

/// What `window = "scan-leg"` reads as until [`super::Profile::resolve_window`]
/// works out the leg's extent: [0, +inf], which no validation accepts.
pub(super) const SCAN_LEG: [f64; 2] = [0.0, f64::INFINITY];

/// `[a, b]` and nothing more: serde's arrays stop reading after their
/// length, so `bins = [1, 49, 3]` would pass as `[1, 49]`. Stops at the third
/// element, so a huge array costs no more than TOML's own parsing.
struct Pair<T> {
    key: &'static str,
    what: &'static str,
    marker: std::marker::PhantomData<T>,
}

impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Pair<T> {
    type Value = [T; 2];
    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = {}", self.key, self.what)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<[T; 2], A::Error> {
        let wrong = |n: &str| {
            serde::de::Error::custom(format!(
                "{} must be {}, two numbers; got {n}",
                self.key, self.what
            ))
        };
        let Some(a) = seq.next_element()? else {
            return Err(wrong("none"));
        };
        let Some(b) = seq.next_element()? else {
            return Err(wrong("one"));
        };
        if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
            return Err(wrong("more"));
        }
        Ok([a, b])
    }
}

fn bins_pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[usize; 2], D::Error> {
    d.deserialize_seq(Pair {
        key: "bins",
        what: "[first, last]",
        marker: std::marker::PhantomData,
    })
}

fn band_pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    d.deserialize_seq(Pair {
        key: "band",
        what: "[low, high]",
        marker: std::marker::PhantomData,
    })
    .map(Some)
}

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
            bands: None,
            cepstra: None,
            drop_level: false,
            features: FeatureFamily::Spectrum,
            kernel_features: None,
            windows: None,
        }
    }
}

impl Analysis {
    /// Number of resampled points in the window (in one sub-window when
    /// `windows` is set): both ends included.
    pub fn points(&self) -> usize {
        let span = match self.windows {
            Some(w) => w.length,
            None => self.window[1] - self.window[0],
        };
        // Saturating: an absurd window must read as too many points, never
        // wrap around to none.
        ((span / self.spacing + 1e-6).floor() as usize).saturating_add(1)
    }
    /// The `[start, end]` of every sub-window in order (the whole window
    /// alone when `windows` is not set); empty when none fits.
    pub fn sub_windows(&self) -> Vec<[f64; 2]> {
        let [w0, w1] = self.window;
        let Some(Windows { length, hop }) = self.windows else {
            return vec![self.window];
        };
        if !(length > 0.0 && hop > 0.0 && length.is_finite() && hop.is_finite()) {
            return Vec::new();
        }
        let mut out = Vec::new();
        let mut j = 0usize;
        loop {
            let s = w0 + j as f64 * hop;
            if s + length > w1 + 1e-9 * length {
                break;
            }
            out.push([s, s + length]);
            j += 1;
        }
        out
    }
    /// Every signal column analysed: `channel`, then `channels`.
    pub fn all_channels(&self) -> impl Iterator<Item = &str> {
        std::iter::once(self.channel.as_str()).chain(self.channels.iter().map(String::as_str))
    }
    /// Points of one DFT: the window's, or a Welch segment's.
    pub fn dft_points(&self) -> usize {
        let n = self.points();
        if self.spectrum.is_welch() {
            self.welch_segment.unwrap_or((n / 4).max(4))
        } else {
            n
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
    /// Each band's bins, `[first, end)`, when `bands` is set: bin `k`
    /// (at `f_k = k · bin_width()`) is in band `i` when `e_i <= f_k < e_{i+1}`,
    /// and the last band also takes `f_k == e_N`. Only bins `0..=m/2` exist,
    /// so a band above the Nyquist frequency holds none (`first == end`).
    pub fn band_bins(&self) -> Vec<[usize; 2]> {
        let Some(b) = self.bands else {
            return Vec::new();
        };
        let w = self.bin_width();
        let top = self.dft_points() / 2 + 1;
        let edges = b.edges();
        // The first bin at or above `e` (strictly above when `strict`).
        let first_from = |e: f64, strict: bool| {
            let mut k = ((e / w).floor().max(0.0) as usize).min(top);
            while k > 0 && (k - 1) as f64 * w >= e {
                k -= 1;
            }
            while k < top && ((k as f64 * w) < e || (strict && k as f64 * w == e)) {
                k += 1;
            }
            k
        };
        (0..b.count)
            .map(|i| {
                let last = i + 1 == b.count;
                [first_from(edges[i], false), first_from(edges[i + 1], last)]
            })
            .collect()
    }
    /// The first and last bin kept (inclusive), from `bands`, `band` or
    /// `bins`; the first is past the last when the band holds no bin. With
    /// `bands`, the bins the bands span (for plots).
    pub fn kept_bins(&self) -> [usize; 2] {
        if self.bands.is_some() {
            let b = self.band_bins();
            let first = b.first().map_or(0, |r| r[0]);
            let end = b.last().map_or(0, |r| r[1]);
            return [first, end.saturating_sub(1)];
        }
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
    /// Features per channel: as the family makes them (for random kernels,
    /// the window's points, which the model transforms).
    pub fn features_per_channel(&self) -> usize {
        match self.features {
            FeatureFamily::Spectrum => {}
            FeatureFamily::Kernels => return self.points(),
            FeatureFamily::Quantiles => return quantile_feature_count(self.points()),
            FeatureFamily::Hydra => return super::families::hydra_feature_count(self.points()),
        }
        if let Some(m) = self.cepstra {
            return m - usize::from(self.drop_level);
        }
        if let Some(b) = self.bands {
            return b.count;
        }
        let [a, b] = self.kept_bins();
        (b + 1).saturating_sub(a)
    }
    pub fn feature_count(&self) -> usize {
        self.features_per_channel() * (1 + self.channels.len())
    }
    /// Features the classifier sees per window: for random kernels the
    /// ones the model makes of the points (a multiple of 84 per channel),
    /// else [`Self::feature_count`].
    pub fn fitted_feature_count(&self) -> usize {
        match self.features {
            FeatureFamily::Kernels => {
                let per = self.kernel_features_asked() / super::families::KERNEL_COUNT
                    * super::families::KERNEL_COUNT;
                per * (1 + self.channels.len())
            }
            _ => self.feature_count(),
        }
    }
    /// Random kernels: the features asked for per channel.
    pub fn kernel_features_asked(&self) -> usize {
        self.kernel_features
            .unwrap_or(super::families::DEFAULT_KERNEL_FEATURES)
    }
    /// Whether the spectrum's options (bins, band, bands, …) make the
    /// features.
    pub fn uses_spectrum(&self) -> bool {
        self.features == FeatureFamily::Spectrum
    }
}

/// What an option allows, as its declaration says it (`0 <= overlap < 1`):
/// a message cannot then disagree with the list.
fn declared(field: &str) -> &'static str {
    option(field)
        .and_then(|o| o.allowed.first())
        .copied()
        .unwrap_or("")
}

/// Checks the options beyond the thesis's (spectrum kind, Welch segments,
/// band): `Err((key, reason))`. Assumes the window and spacing are valid.
pub fn check_options(s: &Analysis) -> Result<(), (String, String)> {
    let bad = |key: &str, reason: String| Err((format!("analysis.{key}"), reason));
    let n = s.points();
    check_family(s)?;
    if s.spectrum.is_welch() {
        let m = s.dft_points();
        if m < 4 || m > n {
            return bad(
                "welch_segment",
                format!("must be {} ({n}), got {m}", declared("welch_segment")),
            );
        }
        let o = s.overlap();
        if !(o.is_finite() && (0.0..1.0).contains(&o)) {
            return bad(
                "welch_overlap",
                format!("must be {}, got {o}", declared("welch_overlap")),
            );
        }
    } else if s.welch_segment.is_some() {
        return bad(
            "welch_segment",
            "is only used with spectrum = \"welch\" or \"log-welch\"".into(),
        );
    } else if s.welch_overlap.is_some() {
        return bad(
            "welch_overlap",
            "is only used with spectrum = \"welch\" or \"log-welch\"".into(),
        );
    }
    check_bands(s)?;
    if let Some([lo, hi]) = s.band {
        let nyquist = s.bin_width() * (s.dft_points() / 2) as f64;
        let unit = s.frequency_unit();
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi >= lo) {
            return bad(
                "band",
                format!(
                    "must be [low, high] in {unit} with 0 <= low <= high, got {:?}",
                    [lo, hi]
                ),
            );
        }
        let [a, b] = s.kept_bins();
        if a > b {
            return bad(
                "band",
                format!(
                    "holds no DFT bin: bins are {:.4} {unit} apart up to {nyquist:.4} {unit}",
                    s.bin_width()
                ),
            );
        }
    }
    Ok(())
}

/// `features` and the options only one family uses: `Err((key, reason))`.
fn check_family(s: &Analysis) -> Result<(), (String, String)> {
    let bad = |key: &str, reason: String| Err((format!("analysis.{key}"), reason));
    let family = super::options::plain_word(&s.features);
    if s.kernel_features.is_some() && s.features != FeatureFamily::Kernels {
        return bad(
            "kernel_features",
            format!("is only used with features = \"kernels\", not \"{family}\""),
        );
    }
    if s.uses_spectrum() {
        return Ok(());
    }
    let spectrum_only = [
        ("band", s.band.is_some()),
        ("bands", s.bands.is_some()),
        ("cepstra", s.cepstra.is_some()),
        ("drop_level", s.drop_level),
        ("welch_segment", s.welch_segment.is_some()),
        ("welch_overlap", s.welch_overlap.is_some()),
    ];
    if let Some((key, _)) = spectrum_only.iter().find(|(_, set)| *set) {
        return bad(
            key,
            format!("is only used with features = \"spectrum\", not \"{family}\""),
        );
    }
    // The fewest points a family takes, said of the key that sets them.
    let n = s.points();
    let least = match s.features {
        FeatureFamily::Kernels => Some((
            super::families::KERNEL_MIN_POINTS,
            "random kernels",
            "a kernel spans 9",
        )),
        FeatureFamily::Hydra => Some((
            super::families::HYDRA_MIN_POINTS,
            "competing kernels",
            "a kernel spans 9 of the first difference",
        )),
        FeatureFamily::Spectrum | FeatureFamily::Quantiles => None,
    };
    if let Some((least, what, why)) = least.filter(|l| n < l.0) {
        let key = if s.windows.is_some() {
            "windows"
        } else {
            "window"
        };
        return bad(
            key,
            format!("holds {n} points; {what} need at least {least} ({why})"),
        );
    }
    if s.features == FeatureFamily::Kernels {
        let asked = s.kernel_features_asked();
        let [lo, hi] = super::families::KERNEL_FEATURES_RANGE;
        if !(lo..=hi).contains(&asked) {
            return bad(
                "kernel_features",
                format!("must be {lo} to {hi}, got {asked}"),
            );
        }
    }
    Ok(())
}

/// `bands` and `cepstra`: `Err((key, reason))`.
fn check_bands(s: &Analysis) -> Result<(), (String, String)> {
    let bad = |key: &str, reason: String| Err((format!("analysis.{key}"), reason));
    let Some(b) = s.bands else {
        if s.drop_level {
            return bad(
                "drop_level",
                "needs `bands` and `cepstra` (it drops the cepstra's c_0)".into(),
            );
        }
        if s.cepstra.is_some() {
            return bad(
                "cepstra",
                "needs `bands` (the cepstra are the DCT of the log band energies)".into(),
            );
        }
        return Ok(());
    };
    let unit = s.frequency_unit();
    if s.band.is_some() {
        return bad("bands", "replaces `band`: set one of them, not both".into());
    }
    if s.spectrum == SpectrumKind::Magnitude {
        return bad(
            "bands",
            "sums power, so it needs spectrum = \"power\", \"log-power\", \"welch\" or \"log-welch\", not \"magnitude\"".into(),
        );
    }
    if b.count == 0 || b.count > 4096 {
        return bad("bands.count", format!("must be 1 to 4096, got {}", b.count));
    }
    let low = if b.scale == BandScale::Log {
        "0 < from"
    } else {
        "0 <= from"
    };
    if !(b.from.is_finite()
        && b.to.is_finite()
        && b.from >= 0.0
        && b.to > b.from
        && (b.scale == BandScale::Linear || b.from > 0.0))
    {
        return bad(
            "bands",
            format!(
                "needs {low} < to in {unit}, got from = {}, to = {}",
                b.from, b.to
            ),
        );
    }
    let edges = b.edges();
    for (i, [first, end]) in s.band_bins().into_iter().enumerate() {
        if first >= end {
            return bad(
                "bands",
                format!(
                    "band {i} ({:.4}–{:.4} {unit}) holds no spectrum bin (bins are {:.4} {unit} apart up to {:.4} {unit}): \
                     raise `from`, use fewer bands, or longer segments",
                    edges[i],
                    edges[i + 1],
                    s.bin_width(),
                    s.bin_width() * (s.dft_points() / 2) as f64,
                ),
            );
        }
    }
    if let Some(m) = s.cepstra
        && !(1..=b.count).contains(&m)
    {
        return bad(
            "cepstra",
            format!("must be {} ({}), got {m}", declared("cepstra"), b.count),
        );
    }
    match s.cepstra {
        None if s.drop_level => {
            return bad(
                "drop_level",
                "needs `cepstra` (it drops the cepstra's c_0)".into(),
            );
        }
        Some(1) if s.drop_level => {
            return bad(
                "drop_level",
                "needs cepstra >= 2: with cepstra = 1 only c_0 is kept, and it would be dropped"
                    .into(),
            );
        }
        _ => {}
    }
    Ok(())
}

/// Sub-windows (checked once the window is): a positive length and hop, and at least one sub-window in
/// the window (at most 100000 of them).
pub fn check_windows(s: &Analysis, w: Windows) -> Result<(), String> {
    let unit = if s.axis.ends_with("_m") {
        " m"
    } else if s.axis.ends_with("_s") {
        " s"
    } else {
        ""
    };
    if !(w.length.is_finite() && w.length > 0.0) {
        return Err(format!(
            "length must be a positive number (in the axis unit), got {}",
            compact(w.length)
        ));
    }
    if !(w.hop.is_finite() && w.hop > 0.0) {
        return Err(format!(
            "hop must be a positive number (in the axis unit), got {}",
            compact(w.hop)
        ));
    }
    if w.hop < s.spacing * (1.0 - 1e-9) {
        // Sub-windows closer than one resampled point repeat the same
        // samples: only more work (issue 19: 30 s on 12 recordings).
        return Err(format!(
            "hop {}{unit} is below analysis.spacing ({}{unit}): sub-windows would start within one resampled point of each other; set hop to at least {} (a longer hop), or a finer spacing",
            compact(w.hop),
            compact(s.spacing),
            compact(s.spacing)
        ));
    }
    let [w0, w1] = s.window;
    if w0 + w.length > w1 + 1e-9 * w.length {
        return Err(format!(
            "length {}{unit} is longer than the window [{}, {}] ({}{unit}): no sub-window fits",
            compact(w.length),
            compact(w0),
            compact(w1),
            compact(w1 - w0)
        ));
    }
    if (w1 - w0 - w.length) / w.hop > 100_000.0 {
        return Err(format!(
            "hop {}{unit} cuts the window into more than 100000 sub-windows",
            compact(w.hop)
        ));
    }
    Ok(())
}

/// The window (or sub-window) must hold 4 to 2^20 resampled points: the
/// key to blame and why, naming the window and the spacing. A window
/// shorter than the spacing, or one beyond any recording, is the window's
/// fault, not the spacing's.
pub fn check_points(an: &Analysis) -> Result<(), (String, String)> {
    let (key, what, span) = match an.windows {
        Some(w) => ("analysis.windows", "sub-window length", w.length),
        None => ("analysis.window", "window", an.window[1] - an.window[0]),
    };
    let n = an.points();
    let spacing = compact(an.spacing);
    if n < 4 {
        let key = if span < an.spacing {
            key
        } else {
            "analysis.spacing"
        };
        return Err((
            key.into(),
            format!(
                "the {what} ({}) holds only {n} point(s) at spacing {spacing} (need 4): \
                 lengthen the {what} or shrink the spacing",
                compact(span)
            ),
        ));
    }
    if n > 1 << 20 {
        // No rig strokes a kilometre or records for 1000 s of one window:
        // past that the window is absurd; short of it, the spacing is fine.
        let key = if span > 1.0e3 {
            key
        } else {
            "analysis.spacing"
        };
        return Err((
            key.into(),
            format!(
                "the {what} ({}) holds {} points at spacing {spacing} (at most 1048576): \
                 shorten the {what} to the recordings' extent, or widen the spacing",
                compact(span),
                compact((span / an.spacing).floor() + 1.0)
            ),
        ));
    }
    Ok(())
}

/// Check `[analysis]`, and against the path (validated before it) when the
/// profile has one: an analysis-only profile has none to check against.
pub(super) fn validate(an: &Analysis, p: Option<&PathSpec>) -> Result<(), Invalid> {
    let axis_index = match an.axis.as_str() {
        "x_m" => Some(0),
        "y_m" => Some(1),
        "z_m" => Some(2),
        "t_s" => None,
        other => {
            return bad(
                "analysis.axis",
                format!(
                    "must be {}, got {other:?}",
                    option("axis").map_or(String::new(), |o| words(o.allowed))
                ),
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
            if p.is_none() {
                "\"scan-leg\" needs the scan leg of a [path], and this profile has no [path] section: give the window as [start, end] in the axis unit"
            } else {
                "\"scan-leg\" needs a scan leg that moves along the axis"
            },
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
                "must be [start, end] with 0 <= start < end, got [{}, {}]",
                compact(an.window[0]),
                compact(an.window[1])
            ),
        );
    }
    if let Some(w) = an.windows {
        check_windows(an, w).or_else(|reason| bad("analysis.windows", reason))?;
    }
    if let Some(p) = p {
        check_against_scan_leg(an, p, axis_index)?;
    }
    if let Err((key, reason)) = check_points(an) {
        return bad(key, reason);
    }
    let m = an.dft_points();
    if an.uses_spectrum()
        && an.band.is_none()
        && an.bands.is_none()
        && (an.bins[0] > an.bins[1] || an.bins[1] > m / 2)
    {
        return bad(
            "analysis.bins",
            format!(
                "must be [first, last] with first <= last <= {} (half the {} {} points), got {:?}",
                m / 2,
                m,
                if m == an.points() {
                    "window"
                } else {
                    "Welch segment"
                },
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
    if let Err((key, reason)) = check_options(an) {
        return bad(key, reason);
    }
    Ok(())
}

/// The window must lie on the path's scan leg, which must move along the
/// axis (a position axis), or last as long as the window (`t_s`).
fn check_against_scan_leg(
    an: &Analysis,
    p: &PathSpec,
    axis_index: Option<usize>,
) -> Result<(), Invalid> {
    let a0 = p.waypoints_m[p.scan_leg - 1];
    let a1 = p.waypoints_m[p.scan_leg];
    let leg_extent = match axis_index {
        Some(ax) => (a1[ax] - a0[ax]).abs(),
        None => dist(a0, a1) / p.speed_m_per_s + p.dwell_s,
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
    Ok(())
}
