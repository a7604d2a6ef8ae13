//! Analysis: from one scan's samples to the feature vector the classifier uses.
//!
//! This module owns the thesis's preprocessing and feature extraction
//! (sections 3.1.5 and 3.3.3): take the signal channel (the probe's height
//! `y_m`) along the resampling axis (`x_m`, the stroke), cut it to the
//! window, resample it every `spacing`, remove its trend, take the DFT and
//! keep the magnitudes of the chosen bins.
//!
//! It works on plain slices (`axis`, `signal`), never on a recording type or
//! a file: whoever reads recordings picks the two columns and hands them in.
//! After the first call it never allocates: the FFT is planned once in
//! [`FeatureExtractor::new`] and every buffer is reused.
//!
//! # Resampling
//! The axis is measured from the scan's first sample, along the direction of
//! travel: `d_j = s · (axis[j] − axis[0])` with `s` the sign of
//! `axis[last] − axis[0]` (so a scan in −x works like one in +x). The grid is
//! `g_i = window[0] + i · spacing` for `i = 0..n`, `n = settings.points()`.
//!
//! 1. Each sample goes to its nearest grid point,
//!    `i = round((d_j − window[0]) / spacing)`; samples outside `0 ≤ i < n`
//!    are dropped. Where that leaves bins empty, the window is binned again
//!    with every sample within [`resample::TIE`] spacings of a bin's edge
//!    going to the bin above, kept if it fills more bins: evenly spaced
//!    samples half a period off the grid sit on edges, and floating point
//!    rounds some down and some up.
//! 2. Each non-empty bin is replaced by its centroid (mean `d`, mean signal).
//!    This averaging is the thesis's "filtering" (Fig. 3.12). Because samples
//!    are binned by position, not ordered by time, a probe that moves back
//!    and forth (stick-slip) is handled: every pass over a spot counts once
//!    per sample.
//! 3. The value at `g_i` is the linear interpolation over the sequence of
//!    bin centroids (which is increasing in `d`), extrapolated linearly from
//!    the two nearest centroids beyond the first or last one. A signal that
//!    is a straight line in `d` is therefore resampled exactly.
//!
//! The scan must reach the window, give or take [`resample::END_SLACK`]
//! spacings at either end ([`AnalysisError::WindowNotCovered`]): a probe held
//! by friction on a flank stops a fraction of a millimetre short of the last
//! waypoint, and the thesis's window runs to the very end of the stroke, so
//! the grid points it did not reach are extrapolated from the last two bins.
//! At most a quarter of the bins may be empty ([`AnalysisError::TooSparse`]);
//! an end bin the scan passed over without a sample in it is an error
//! ([`AnalysisError::EdgeGap`]); and at least two bins must hold samples. A
//! time axis (`t_s`) works the same way, in seconds.
//!
//! # Spectrum
//! After the detrend (none, mean, or least-squares line) and the taper (none,
//! or Hann) the window's DFT is taken unnormalised, as Matlab's `fft` gives
//! it (the thesis's Eq. 3.4): `X_k = Σ_j x_j e^{−2πi jk/n}`. The thesis's
//! features are `|X_k|` for `k = bins[0]..=bins[1]`; the other spectrum
//! kinds (power, log-power, Welch) are described at [`spectrum::Spectrum`].
//! Bin `k` lies at `k / (m · spacing)` cycles per axis unit (`m` the DFT
//! length): Hz on a time axis, cycles/mm on a position axis once divided by
//! 1000; `band = [lo, hi]` keeps the bins in that range instead of `bins`.
//!
//! # Sub-windows
//! With `windows = { length, hop }` the window is cut into sub-windows
//! ([`Analysis::sub_windows`]) and each is analysed exactly as if it were
//! the window: [`FeatureExtractor::window_features`] moves the resampling
//! grid to the sub-window's start and reuses the one FFT plan and buffers,
//! so a sub-window costs no allocation beyond its output.
//!
//! # Other feature families
//! With `features = "quantiles"` each channel's detrended window becomes
//! interval quantiles ([`quantiles`], QUANT); with `features = "kernels"`
//! its detrended points are the features handed on, and the model fits
//! and applies the random kernels ([`kernels`], MiniRocket), because their
//! biases are fitted on training windows only; with `features = "hydra"`
//! its detrended window and first difference become the wins and losses
//! of competing random kernels ([`hydra`], Hydra). The spectrum is still
//! computed, for display.
//!
//! # Several channels
//! `channel` and then each of `channels` is resampled along the same axis
//! and analysed alike; the feature vector is their features concatenated.

mod bands;
pub mod hydra;
pub mod kernels;
pub mod quantiles;
mod resample;
mod spectrum;

use std::fmt;

use thiserror::Error;

use crate::profile::{Analysis, FeatureFamily};
use crate::profile::{check_options, check_windows};
use bands::BandFeatures;
use hydra::Hydra;
use quantiles::Quantiles;
use resample::Resampler;
use spectrum::Spectrum;

pub use spectrum::{detrend, taper_weights};

/// Why a scan gives no features.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AnalysisError {
    #[error("the analysis settings cannot be used: {0}")]
    Settings(String),
    #[error("the scan has no samples")]
    Empty,
    #[error("the axis has {axis} samples but the signal has {signal}")]
    LengthMismatch { axis: usize, signal: usize },
    #[error("the {what} is not a finite number at sample {index} (value {value})")]
    NonFinite {
        what: &'static str,
        index: usize,
        value: f64,
    },
    #[error("{}", not_covered_message(.axis, .covered, .window))]
    WindowNotCovered {
        /// The axis name (`x_m`, `t_s`, …), for the message's unit.
        axis: String,
        /// The scan's extent, as distance along the direction of travel from its first sample.
        covered: (f64, f64),
        window: [f64; 2],
    },
    #[error(
        "the scan is too sparse along {axis}: {empty} of the {points} grid points \
         ({spacing} apart) in the window have no sample nearby, and at most a quarter may",
        spacing = show(.axis, *.spacing)
    )]
    TooSparse {
        axis: String,
        empty: usize,
        points: usize,
        spacing: f64,
    },
    #[error(
        "no sample of the scan lies within half a spacing ({half}) of the window's {edge} at {at} along {axis}",
        half = show_fine(.axis, .spacing / 2.0),
        at = show(.axis, *.at)
    )]
    EdgeGap {
        axis: String,
        edge: &'static str,
        at: f64,
        spacing: f64,
    },
    #[error("only {filled} grid point(s) along {axis} have samples; at least 2 are needed")]
    TooFewPoints { axis: String, filled: usize },
    /// Samples too large for their spectrum (a power past f64's range):
    /// every command that makes features refuses them alike.
    #[error(
        "feature {number} is not a finite number ({value}): the samples are too large for \
         their spectrum; check the recording's values",
        number = .index + 1
    )]
    FeatureNotFinite { index: usize, value: f64 },
}

/// The features, or the first one that is not a finite number.
fn check_finite(features: &[f64]) -> Result<&[f64], AnalysisError> {
    match features.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        Some((index, &value)) => Err(AnalysisError::FeatureNotFinite { index, value }),
        None => Ok(features),
    }
}

/// How an axis value is shown to people: metres as mm, seconds as s.
fn show(axis: &str, value: f64) -> String {
    if axis.ends_with("_m") {
        format!("{:.1} mm", value * 1000.0)
    } else if axis.ends_with("_s") {
        format!("{value:.3} s")
    } else {
        format!("{value}")
    }
}

/// A small axis value to the hundredth of a millimetre where that matters
/// (half of a 0.3 mm spacing is 0.15 mm, not "0.1 mm").
fn show_fine(axis: &str, value: f64) -> String {
    if axis.ends_with("_m") {
        let mm = format!("{:.2}", value * 1000.0);
        format!("{} mm", mm.strip_suffix('0').unwrap_or(&mm))
    } else {
        show(axis, value)
    }
}

/// A range of axis values, unit once at the end: "60.0–89.7 mm".
fn show_range(axis: &str, lo: f64, hi: f64) -> String {
    let lo = show(axis, lo);
    let hi = show(axis, hi);
    match lo.split_once(' ') {
        Some((num, unit)) if hi.ends_with(unit) => format!("{num}–{hi}"),
        _ => format!("{lo}–{hi}"),
    }
}

fn not_covered_message(axis: &str, covered: &(f64, f64), window: &[f64; 2]) -> String {
    format!(
        "the scan covers {} along {axis} but the window needs {}",
        show_range(axis, covered.0, covered.1),
        show_range(axis, window[0], window[1]),
    )
}

/// Checks the analysis settings the extractor depends on (the same bounds
/// the profile's `validate()` applies), so that a model file's settings can
/// be checked too. The reason names the key.
pub fn check_settings(settings: &Analysis) -> Result<(), String> {
    if settings.axis.is_empty() {
        return Err("analysis.axis must name a column".into());
    }
    if !(settings.spacing.is_finite() && settings.spacing > 0.0) {
        return Err(format!(
            "analysis.spacing must be a positive number, got {}",
            settings.spacing
        ));
    }
    let [w0, w1] = settings.window;
    if !(w0.is_finite() && w1.is_finite() && w0 >= 0.0 && w1 > w0) {
        return Err(format!(
            "analysis.window must be [start, end] with 0 <= start < end, got {:?}",
            settings.window
        ));
    }
    if let Some(w) = settings.windows {
        check_windows(settings, w).map_err(|reason| format!("analysis.windows {reason}"))?;
    }
    crate::profile::check_points(settings).map_err(|(key, reason)| format!("{key}: {reason}"))?;
    let [a, b] = settings.bins;
    let m = settings.dft_points();
    if settings.uses_spectrum()
        && settings.band.is_none()
        && settings.bands.is_none()
        && (a > b || b > m / 2)
    {
        return Err(format!(
            "analysis.bins must be [first, last] with first <= last <= {}, got {:?}",
            m / 2,
            settings.bins
        ));
    }
    check_options(settings).map_err(|(key, reason)| format!("{key} {reason}"))
}

/// Turns one scan's (axis, signal) samples into features, reusing its FFT
/// plan and buffers from call to call.
#[derive(Clone)]
pub struct FeatureExtractor {
    settings: Analysis,
    resampler: Resampler,
    resampled: Vec<f64>,
    detrended: Vec<f64>,
    spectrum: Spectrum,
    /// The one-sided spectrum of the last channel transformed.
    values: Vec<f64>,
    /// The concatenated features of every channel.
    features: Vec<f64>,
    kept: [usize; 2],
    /// `bands` (and `cepstra`), when set: reduce the linear power to them.
    bands: Option<BandFeatures>,
    /// `features = "quantiles"`: the interval quantile transform.
    quantiles: Option<Quantiles>,
    /// `features = "hydra"`: the competing kernels.
    hydra: Option<Hydra>,
    /// One channel's band features.
    band_values: Vec<f64>,
    has_spectrum: bool,
    /// Every sub-window's `[start, end]` (the window alone without `windows`).
    sub_windows: Vec<[f64; 2]>,
    /// Set while [`FeatureExtractor::all_window_features`] runs over samples
    /// checked finite with the axis in order.
    in_order: bool,
}

/// Whether every value is finite and the axis never decreases: then each
/// sub-window can find its own samples by binary search.
fn sub_windows_may_search(axis: &[f64], signals: &[&[f64]]) -> bool {
    axis.first().is_some_and(|a| a.is_finite())
        && axis.windows(2).all(|w| w[0] <= w[1] && w[1].is_finite())
        && signals
            .iter()
            .all(|s| s.len() == axis.len() && s.iter().all(|v| v.is_finite()))
}

impl fmt::Debug for FeatureExtractor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FeatureExtractor")
            .field("settings", &self.settings)
            .field("points", &self.resampled.len())
            .finish_non_exhaustive()
    }
}

impl FeatureExtractor {
    /// An extractor for validated settings (a loaded profile's or a loaded
    /// model's).
    ///
    /// # Panics
    /// When the settings fail [`check_settings`]; use [`Self::try_new`] for
    /// settings that have not been validated.
    pub fn new(settings: &Analysis) -> Self {
        match Self::try_new(settings) {
            Ok(x) => x,
            Err(e) => panic!("{e}"),
        }
    }

    pub fn try_new(settings: &Analysis) -> Result<Self, AnalysisError> {
        check_settings(settings).map_err(AnalysisError::Settings)?;
        let n = settings.points();
        let bands = BandFeatures::new(settings);
        // Bands sum linear power; they take the log themselves.
        let kind = if bands.is_some() {
            settings.spectrum.linear()
        } else {
            settings.spectrum
        };
        let spectrum = Spectrum::new(
            kind,
            settings.taper,
            settings.detrend,
            settings.dft_points(),
            settings.overlap(),
        );
        Ok(FeatureExtractor {
            settings: settings.clone(),
            resampler: Resampler::new(n, settings.window[0], settings.spacing),
            resampled: vec![0.0; n],
            detrended: vec![0.0; n],
            values: vec![0.0; spectrum.len()],
            spectrum,
            features: vec![0.0; settings.feature_count()],
            kept: settings.kept_bins(),
            band_values: vec![0.0; bands.as_ref().map_or(0, BandFeatures::len)],
            bands,
            quantiles: (settings.features == FeatureFamily::Quantiles).then(|| Quantiles::new(n)),
            hydra: (settings.features == FeatureFamily::Hydra).then(|| Hydra::new(n)),
            has_spectrum: false,
            sub_windows: settings.sub_windows(),
            in_order: false,
        })
    }

    pub fn settings(&self) -> &Analysis {
        &self.settings
    }

    /// Number of resampled points in the window.
    pub fn points(&self) -> usize {
        self.resampled.len()
    }

    /// Resample `signal` along `axis` onto the window's grid (see the module
    /// documentation). `axis[j]` and `signal[j]` are one sample; the order of
    /// samples does not matter except that the first sample is the scan's
    /// origin and the last gives its direction.
    pub fn resample(&mut self, axis: &[f64], signal: &[f64]) -> Result<&[f64], AnalysisError> {
        self.resampler
            .run(&self.settings.axis, axis, signal, &mut self.resampled)?;
        Ok(&self.resampled)
    }

    /// Resample, detrend, taper, transform, and return the kept bins of one
    /// signal (`settings.features_per_channel()` values).
    pub fn features(&mut self, axis: &[f64], signal: &[f64]) -> Result<&[f64], AnalysisError> {
        self.transform(axis, signal)?;
        let per = self.settings.features_per_channel();
        self.keep_channel(0, per);
        check_finite(&self.features[..per])
    }

    fn transform(&mut self, axis: &[f64], signal: &[f64]) -> Result<(), AnalysisError> {
        self.resample_own(axis, signal)?;
        self.transform_resampled();
        Ok(())
    }

    /// Resample one signal into `self.resampled` (in order when the
    /// sub-windows may each visit only their own samples).
    fn resample_own(&mut self, axis: &[f64], signal: &[f64]) -> Result<(), AnalysisError> {
        if self.in_order {
            self.resampler
                .run_in_order(&self.settings.axis, axis, signal, &mut self.resampled)
        } else {
            self.resampler
                .run(&self.settings.axis, axis, signal, &mut self.resampled)
        }
    }

    /// Detrend, taper and transform `self.resampled`.
    fn transform_resampled(&mut self) {
        self.detrended.copy_from_slice(&self.resampled);
        detrend(self.settings.detrend, &mut self.detrended);
        self.spectrum.compute(&self.detrended, &mut self.values);
        self.has_spectrum = true;
    }

    /// The features of every channel (`channel`, then `channels`, one
    /// signal each in that order), concatenated. The channels are
    /// transformed last to first, so afterwards [`Self::resampled`],
    /// [`Self::detrended`] and [`Self::spectrum`] show `channel`'s.
    pub fn features_of_channels(
        &mut self,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<&[f64], AnalysisError> {
        let per = self.settings.features_per_channel();
        self.check_channels(signals.len())?;
        for (c, signal) in signals.iter().enumerate().rev() {
            self.transform(axis, signal)?;
            self.keep_channel(c, per);
        }
        check_finite(&self.features)
    }

    /// Refuses `given` signals unless there is one per channel analysed
    /// (`channel`, then `channels`).
    fn check_channels(&self, given: usize) -> Result<(), AnalysisError> {
        let want = 1 + self.settings.channels.len();
        if given == want {
            Ok(())
        } else {
            Err(AnalysisError::Settings(format!(
                "{want} channel(s) to analyse but {given} given"
            )))
        }
    }

    /// Channel `c`'s features (`per` of them) of the spectrum last
    /// transformed, into their place in `self.features`.
    fn keep_channel(&mut self, c: usize, per: usize) {
        let slot = &mut self.features[c * per..(c + 1) * per];
        match (self.settings.features, &mut self.quantiles, &mut self.hydra) {
            // The model's kernels transform the detrended points.
            (FeatureFamily::Kernels, ..) => slot.copy_from_slice(&self.detrended),
            (FeatureFamily::Quantiles, Some(q), _) => q.compute(&self.detrended, slot),
            (FeatureFamily::Hydra, _, Some(h)) => h.compute(&self.detrended, slot),
            _ => {
                if let Some(b) = &mut self.bands {
                    b.compute(&self.values, &mut self.band_values);
                }
                let own = match self.bands {
                    Some(_) => &self.band_values[..],
                    None => &self.values[self.kept[0]..=self.kept[1]],
                };
                slot.copy_from_slice(own);
            }
        }
    }

    /// The `[start, end]` of each sub-window along the axis, in order (the
    /// window alone when `windows` is not set).
    pub fn sub_windows(&self) -> &[[f64; 2]] {
        &self.sub_windows
    }

    /// The features of every channel of sub-window `j` (see
    /// [`Analysis::sub_windows`]): exactly what an extractor whose window
    /// is that sub-window gives, with this one's FFT plan and buffers.
    /// Without `windows`, sub-window 0 is the window.
    ///
    /// # Panics
    /// When `j` is not below `sub_windows().len()`.
    pub fn window_features(
        &mut self,
        j: usize,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<&[f64], AnalysisError> {
        self.resampler.set_start(self.sub_windows[j][0]);
        let done = self.features_of_channels(axis, signals).map(|_| ());
        self.resampler.set_start(self.sub_windows[0][0]);
        done?;
        Ok(&self.features)
    }

    /// The features of every sub-window in order, each as
    /// [`Self::window_features`] gives it: one vector per sub-window.
    pub fn all_window_features(
        &mut self,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<Vec<Vec<f64>>, AnalysisError> {
        self.each_sub_window(axis, signals, |fx| {
            fx.features_of_channels(axis, signals).map(<[f64]>::to_vec)
        })
    }

    /// Every sub-window's channels (`channel`, then `channels`) resampled,
    /// in order: the grid [`Self::all_window_features`] transforms. An
    /// extractor whose settings differ only after the resampling (spectrum,
    /// taper, segment, bins, bands, cepstra) gives from them, by
    /// [`Self::features_of_resampled`], exactly the features
    /// `all_window_features` would: `tune` resamples once for them all.
    pub fn resample_windows(
        &mut self,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<Vec<Vec<Vec<f64>>>, AnalysisError> {
        self.check_channels(signals.len())?;
        self.each_sub_window(axis, signals, |fx| {
            signals
                .iter()
                .map(|signal| {
                    fx.resample_own(axis, signal)?;
                    Ok(fx.resampled.clone())
                })
                .collect()
        })
    }

    /// `each` for every sub-window in order, the resampler started at it;
    /// afterwards the resampler starts at the first again.
    fn each_sub_window<T>(
        &mut self,
        axis: &[f64],
        signals: &[&[f64]],
        mut each: impl FnMut(&mut Self) -> Result<T, AnalysisError>,
    ) -> Result<Vec<T>, AnalysisError> {
        // One pass decides whether the sub-windows may each visit only
        // their own samples (see `Resampler::run_in_order`); otherwise each
        // goes over the whole recording, as a single window does.
        self.in_order = sub_windows_may_search(axis, signals) && self.sub_windows.len() > 1;
        let all = (0..self.sub_windows.len())
            .map(|j| {
                self.resampler.set_start(self.sub_windows[j][0]);
                each(self)
            })
            .collect();
        self.resampler.set_start(self.sub_windows[0][0]);
        self.in_order = false;
        all
    }

    /// The features of one sub-window from its resampled channels (one of
    /// [`Self::resample_windows`]' entries, made under the same grid).
    pub fn features_of_resampled(
        &mut self,
        channels: &[Vec<f64>],
    ) -> Result<&[f64], AnalysisError> {
        let per = self.settings.features_per_channel();
        self.check_channels(channels.len())?;
        if let Some(c) = channels.iter().find(|c| c.len() != self.resampled.len()) {
            return Err(AnalysisError::Settings(format!(
                "{} resampled points to transform but {} given",
                self.resampled.len(),
                c.len()
            )));
        }
        for (c, points) in channels.iter().enumerate().rev() {
            self.resampled.copy_from_slice(points);
            self.transform_resampled();
            self.keep_channel(c, per);
        }
        check_finite(&self.features)
    }

    /// The last window resampled (by [`Self::resample`] or
    /// [`Self::features`]), before the detrend; empty before the first.
    pub fn resampled(&self) -> &[f64] {
        if self.has_spectrum || self.resampler.has_run() {
            &self.resampled
        } else {
            &[]
        }
    }

    /// The window [`Self::features`] last transformed, after the detrend;
    /// empty before the first.
    pub fn detrended(&self) -> &[f64] {
        if self.has_spectrum {
            &self.detrended
        } else {
            &[]
        }
    }

    /// The full one-sided spectrum (of the settings' kind), bins `0..=m/2`,
    /// of the window [`Self::features`] last transformed, for display; empty
    /// before the first. The features are `spectrum()[a..=b]` with
    /// `[a, b] = settings.kept_bins()`; with `bands` it is the linear power
    /// (Welch's for `log-welch`) the bands sum.
    pub fn spectrum(&self) -> &[f64] {
        if self.has_spectrum { &self.values } else { &[] }
    }

    /// Frequency of spectrum bin `k`, in `settings.frequency_unit()`.
    pub fn frequency(&self, k: usize) -> f64 {
        k as f64 * self.settings.bin_width()
    }

    /// Position of grid point `i` along the axis, from the scan's start.
    pub fn grid_position(&self, i: usize) -> f64 {
        self.settings.window[0] + i as f64 * self.settings.spacing
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis's analysis (the default), as the profile states it.
    fn thesis() -> Analysis {
        let a = Analysis::default();
        assert_eq!(a, crate::profile::LoadedProfile::thesis().profile.analysis);
        a
    }

    /// A scan from 0 to `len` along x in `samples` even steps.
    fn ramp(len: f64, samples: usize) -> Vec<f64> {
        (0..samples)
            .map(|j| len * j as f64 / (samples - 1) as f64)
            .collect()
    }

    #[test]
    fn thesis_window_has_100_points_and_49_features() {
        let mut fx = FeatureExtractor::new(&thesis());
        assert_eq!(fx.points(), 100);
        assert!(fx.spectrum().is_empty());
        let x = ramp(0.0897, 9000);
        let y: Vec<f64> = x.iter().map(|x| (x * 2000.0).sin() * 1e-3).collect();
        assert_eq!(fx.features(&x, &y).unwrap().len(), 49);
        assert_eq!(fx.spectrum().len(), 51);
        assert_eq!(fx.detrended().len(), 100);
    }

    #[test]
    fn each_sub_window_is_analysed_as_if_it_were_the_window() {
        let mut a = thesis();
        a.bins = [1, 24];
        a.windows = Some(crate::profile::Windows {
            length: 0.0147,
            hop: 0.0075,
        });
        let subs = a.sub_windows();
        assert_eq!(subs.len(), 3, "{subs:?}");
        let mut fx = FeatureExtractor::new(&a);
        assert_eq!(fx.points(), 50);
        let x = ramp(0.0897, 9000);
        let y: Vec<f64> = x
            .iter()
            .map(|x| (x * 2000.0).sin() * 1e-3 + (x * 777.0).cos() * x)
            .collect();
        let all = fx.all_window_features(&x, &[&y]).unwrap();
        assert_eq!(all.len(), 3);
        for (j, [s, e]) in subs.iter().copied().enumerate() {
            let mut one = a.clone();
            one.windows = None;
            one.window = [s, e];
            let mut single = FeatureExtractor::new(&one);
            assert_eq!(single.points(), 50);
            let want = single.features_of_channels(&x, &[&y]).unwrap().to_vec();
            assert_eq!(all[j], want, "sub-window {j}");
        }
        assert_ne!(all[0], all[1]);
        // The extractor's own window is back at the first sub-window.
        let first = fx.features_of_channels(&x, &[&y]).unwrap().to_vec();
        assert_eq!(first, all[0]);
    }

    /// Sub-windows that find their samples by binary search give, to the
    /// bit, what a single window over the whole recording gives: on a
    /// jittered time axis with samples exactly on bin edges, and on an axis
    /// that runs backwards (no search then).
    #[test]
    fn sub_windows_searched_or_not_match_a_single_window_exactly() {
        let mut a = Analysis {
            axis: "t_s".into(),
            channel: "f".into(),
            window: [0.0, 0.999],
            spacing: 0.001,
            spectrum: crate::profile::SpectrumKind::LogWelch,
            welch_segment: Some(64),
            bins: [1, 32],
            ..thesis()
        };
        a.windows = Some(crate::profile::Windows {
            length: 0.25,
            hop: 0.125,
        });
        let mut rng = 12345u64;
        let mut jitter = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.0004
        };
        // Every third sample sits exactly half-way between grid points.
        let t: Vec<f64> = (0..1500)
            .map(|j| {
                let base = j as f64 * 0.0007;
                if j % 3 == 0 {
                    base + 0.0005
                } else {
                    base + jitter().abs() * 0.1
                }
            })
            .scan(f64::NEG_INFINITY, |last, v: f64| {
                *last = v.max(*last);
                Some(*last)
            })
            .collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| (t * 900.0).sin() + (t * 71.0).cos())
            .collect();
        for backwards in [false, true] {
            let (t, y): (Vec<f64>, Vec<f64>) = if backwards {
                (t.iter().map(|v| -v).collect(), y.clone())
            } else {
                (t.clone(), y.clone())
            };
            let mut fx = FeatureExtractor::new(&a);
            let all = fx.all_window_features(&t, &[&y]).unwrap();
            assert_eq!(all.len(), a.sub_windows().len());
            for (j, [s, e]) in a.sub_windows().into_iter().enumerate() {
                let mut one = a.clone();
                one.windows = None;
                one.window = [s, e];
                let want = FeatureExtractor::new(&one)
                    .features_of_channels(&t, &[&y])
                    .unwrap()
                    .to_vec();
                assert_eq!(all[j], want, "sub-window {j}, backwards {backwards}");
            }
        }
    }

    #[test]
    fn sub_windows_follow_the_spec_and_none_fit_when_too_long() {
        let mut a = Analysis {
            axis: "t_s".into(),
            channel: "f".into(),
            window: [0.0, 1.0],
            spacing: 0.001,
            ..thesis()
        };
        a.windows = Some(crate::profile::Windows {
            length: 0.5,
            hop: 0.25,
        });
        assert_eq!(a.sub_windows(), vec![[0.0, 0.5], [0.25, 0.75], [0.5, 1.0]]);
        a.windows = Some(crate::profile::Windows {
            length: 0.3,
            hop: 0.3,
        });
        let s = a.sub_windows();
        assert_eq!(s.len(), 3, "{s:?}");
        a.windows = Some(crate::profile::Windows {
            length: 1.5,
            hop: 0.3,
        });
        assert!(a.sub_windows().is_empty());
        assert!(
            check_settings(&a)
                .unwrap_err()
                .contains("analysis.windows length 1.5 s")
        );
        a.windows = None;
        assert_eq!(a.sub_windows(), vec![[0.0, 1.0]]);
    }

    #[test]
    fn window_not_covered_names_the_extent_in_mm() {
        let mut fx = FeatureExtractor::new(&thesis());
        let x = ramp(0.0852, 8000);
        let y = vec![0.0; x.len()];
        let err = fx.features(&x, &y).unwrap_err();
        assert!(
            matches!(err, AnalysisError::WindowNotCovered { .. }),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "the scan covers 0.0–85.2 mm along x_m but the window needs 60.0–89.7 mm"
        );
    }

    #[test]
    fn time_axis_messages_use_seconds() {
        let mut s = thesis();
        s.axis = "t_s".into();
        s.window = [6.0, 8.97];
        s.spacing = 0.03;
        let mut fx = FeatureExtractor::new(&s);
        let t = ramp(5.0, 5000);
        let err = fx.resample(&t, &vec![0.0; t.len()]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the scan covers 0.000–5.000 s along t_s but the window needs 6.000–8.970 s"
        );
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let mut fx = FeatureExtractor::new(&thesis());
        assert_eq!(fx.features(&[], &[]).unwrap_err(), AnalysisError::Empty);
        assert_eq!(
            fx.features(&[0.0, 1.0], &[0.0]).unwrap_err(),
            AnalysisError::LengthMismatch { axis: 2, signal: 1 }
        );
        let x = ramp(0.0897, 9000);
        let mut y = vec![0.0; x.len()];
        y[17] = f64::NAN;
        let err = fx.features(&x, &y).unwrap_err();
        assert!(
            matches!(
                err,
                AnalysisError::NonFinite {
                    what: "signal",
                    index: 17,
                    ..
                }
            ),
            "{err:?}"
        );
        // A stationary probe covers nothing.
        let still = vec![0.01; 100];
        assert!(fx.features(&still, &still).is_err());
    }

    #[test]
    fn sparse_scans_are_rejected() {
        let mut fx = FeatureExtractor::new(&thesis());
        // One sample every 0.6 mm: every other grid point is empty.
        let x = ramp(0.0897, 150);
        let err = fx.features(&x, &vec![0.0; x.len()]).unwrap_err();
        assert!(matches!(err, AnalysisError::TooSparse { .. }), "{err:?}");
        assert!(err.to_string().contains("0.3 mm apart"), "{err}");
        // Dense, but with a hole at the window's start.
        let x: Vec<f64> = ramp(0.0897, 9000)
            .into_iter()
            .filter(|x| (x - 0.060).abs() > 0.0002)
            .collect();
        let err = fx.features(&x, &vec![0.0; x.len()]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "no sample of the scan lies within half a spacing (0.15 mm) of the window's start at 60.0 mm along x_m"
        );
    }

    #[test]
    fn invalid_settings_are_refused() {
        let mut s = thesis();
        s.bins = [1, 51];
        assert!(matches!(
            FeatureExtractor::try_new(&s),
            Err(AnalysisError::Settings(_))
        ));
        s.bins = [1, 49];
        s.spacing = 0.0;
        assert!(FeatureExtractor::try_new(&s).is_err());
        s.spacing = 1e-12;
        assert!(FeatureExtractor::try_new(&s).is_err());
    }
}
