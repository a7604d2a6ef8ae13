//! What a feature setting would cost in one search, known before any
//! work, and the settings a search leaves out for it ([`affordable`]):
//!
//! - those `evaluate` or `train` would refuse on these recordings (their
//!   feature vectors over [`crate::dataset::check_size`]'s limit, or their
//!   validation over [`MAX_COMPARISONS`] value operations, counted for
//!   their classifier): a tuned profile must run on the
//!   recordings it was tuned on;
//! - random kernels whose transforms would take longer than
//!   [`Options::max_minutes`](super::Options) of CPU over the whole search.
//!   The kernels are fitted again in every inner and outer fold, and every
//!   window the fold trains or tests on is transformed with them: on
//!   5-second clips at 44.1 kHz under leave-one-out that is hours for one
//!   setting, where the spectra take seconds;
//! - competing kernels whose features, made once per recording, would take
//!   longer than that: on 56 of those clips, 4 to 6 minutes a setting.
//!
//! The estimate counts the work (points × features per window
//! transformed, points × kernels and dilations per fit) at the rates
//! measured on the project's 2-core development machine (`BENCHMARKS.md`,
//! "What tune leaves out"); it depends on the recordings and the plan
//! only, never on the machine it runs on, so a search is the same
//! anywhere. It leans high: every outer fold tested is counted for every
//! kernel setting, though only the setting its search chose is fitted
//! there.

use serde::Serialize;

use super::Part;
use super::parts::{recordings_of, trained_on_by_all};
use super::space::Setting;
use crate::analysis::kernels::{KERNEL_COUNT, KernelLayout};
use crate::classify::MAX_COMPARISONS;
use crate::dataset::check_size;
use crate::evaluate::plan::{Fits, check_validation, validation_work};
use crate::profile::{Analysis, FeatureFamily};

/// Seconds per point and feature of one window transformed (the counting
/// of positive values, most of the transform).
pub const TRANSFORM_SECONDS: f64 = 0.18e-9;
/// Seconds per point and kernel-dilation pair of one fit (a convolution
/// and the selection of its biases).
pub const FIT_SECONDS: f64 = 14e-9;
/// Seconds per point and dilation of one window's competing kernels (64
/// groups of 8 over the signal and its difference).
pub const HYDRA_SECONDS: f64 = 1.3e-6;

/// The work a search does per feature setting that is fitted fold by fold:
/// recordings transformed (each fold's training and test recordings,
/// over every inner fold of every part and every outer fold tested) and
/// fits (one per fold). A part whose inner folds all train on some
/// recordings (forward folds under a time split) fits the kernels once on
/// those and transforms each of its recordings once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Work {
    pub transformed: usize,
    pub fits: usize,
}

impl Work {
    /// The work of a search over `parts` (the outer parts) with `inner`
    /// (each part's inner folds).
    pub fn of(parts: &[Part], inner: &[Vec<Part>]) -> Work {
        let size = |p: &Part| p.train.len() + p.test.len();
        let tested: Vec<&Part> = parts.iter().filter(|p| !p.test.is_empty()).collect();
        let (mut transformed, mut fits) = (0, 0);
        for folds in inner {
            if trained_on_by_all(folds).is_empty() {
                transformed += folds.iter().map(size).sum::<usize>();
                fits += folds.len();
            } else {
                transformed += recordings_of(folds).len();
                fits += 1;
            }
        }
        Work {
            transformed: transformed + tested.iter().map(|p| size(p)).sum::<usize>(),
            fits: fits + tested.len(),
        }
    }
}

/// Feature settings of one family left out of a search for one reason.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeftOut {
    /// The feature family: `kernels`, `quantiles`, `spectrum`.
    pub family: String,
    /// Feature settings left out, and the settings (with every classifier)
    /// they make.
    pub feature_settings: usize,
    pub settings: usize,
    /// Why, in one sentence: the figure and what would search them.
    pub reason: String,
}

/// The estimated CPU seconds of one feature setting over a search of
/// `work` on `recordings`: random kernels fitted fold by fold, competing
/// kernels made once per recording; `None` for the cheap families.
pub fn setting_seconds(analysis: &Analysis, work: Work, recordings: usize) -> Option<f64> {
    let channels = (1 + analysis.channels.len()) as f64;
    let per_recording = analysis.sub_windows().len() as f64;
    let points = analysis.points();
    match analysis.features {
        FeatureFamily::Kernels => {
            let layout = KernelLayout::new(points, analysis.kernel_features_asked()).ok()?;
            let points = points as f64;
            let window = channels * points * layout.feature_count() as f64 * TRANSFORM_SECONDS;
            let fit =
                channels * points * (KERNEL_COUNT * layout.dilations.len()) as f64 * FIT_SECONDS;
            Some(work.transformed as f64 * per_recording * window + work.fits as f64 * fit)
        }
        FeatureFamily::Hydra => {
            let dilations = crate::profile::families::hydra_dilations(points).len();
            let window = channels * (points * dilations) as f64 * HYDRA_SECONDS;
            Some(recordings as f64 * per_recording * window)
        }
        FeatureFamily::Spectrum | FeatureFamily::Quantiles => None,
    }
}

/// CPU time in the lab's words: minutes below two hours, else hours; a
/// range in one unit.
fn cpu_time(least: f64, most: f64) -> String {
    let (unit, per) = if most < 7200.0 {
        ("CPU-minutes", 60.0)
    } else {
        ("CPU-hours", 3600.0)
    };
    let digits = usize::from(unit == "CPU-hours");
    let (a, b) = (
        format!("{:.*}", digits, least / per),
        format!("{:.*}", digits, most / per),
    );
    if a == b {
        format!("{b} {unit}")
    } else {
        format!("{a} to {b} {unit}")
    }
}

/// A whole number in groups of three: 21,436,128.
fn counted(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Why a feature setting is left out.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reason {
    /// `evaluate` and `train` would refuse its vectors (the figure: their
    /// values).
    Values,
    /// `evaluate` would refuse to validate them (the figure: the value
    /// comparisons or multiply-adds, [`validation_work`]).
    Comparisons,
    /// It would take over `--max-minutes` (the figure: CPU seconds).
    Seconds,
}

/// Why a setting over `recordings` in a search of `work` is left out, and
/// the figure that says so: the checks `evaluate` makes before any work,
/// then the kernels' estimated time.
fn left_out_because(
    setting: &Setting,
    fits: Fits,
    work: Work,
    max_minutes: f64,
) -> Option<(Reason, f64)> {
    let analysis = &setting.analysis;
    if let Err(crate::dataset::DatasetError::TooLarge { values, .. }) =
        check_size(fits.recordings, analysis)
    {
        return Some((Reason::Values, values as f64));
    }
    let vectors = fits.recordings.saturating_mul(analysis.sub_windows().len());
    let features = analysis.fitted_feature_count();
    let method = setting.classifier.method;
    if check_validation(method, vectors, features, fits).is_err() {
        return Some((
            Reason::Comparisons,
            validation_work(method, vectors, features, fits),
        ));
    }
    setting_seconds(analysis, work, fits.recordings)
        .filter(|&seconds| seconds > max_minutes * 60.0)
        .map(|seconds| (Reason::Seconds, seconds))
}

/// The feature settings of one family left out for one reason: their
/// keys, the settings they make, and the least and most figure.
struct Tally {
    family: FeatureFamily,
    reason: Reason,
    keys: Vec<Vec<usize>>,
    settings: usize,
    least: f64,
    most: f64,
}

/// The settings of `all` a search of `work` over the recordings `evaluate`
/// would validate as `fits` says can afford, in their order, and those it
/// leaves out, by family and reason.
pub fn affordable(
    all: Vec<Setting>,
    fits: Fits,
    work: Work,
    max_minutes: f64,
) -> (Vec<Setting>, Vec<LeftOut>) {
    let mut tallies: Vec<Tally> = Vec::new();
    let mut kept = Vec::new();
    for s in all {
        let Some((reason, figure)) = left_out_because(&s, fits, work, max_minutes) else {
            kept.push(s);
            continue;
        };
        let family = s.analysis.features;
        let key = s.feature_key();
        match tallies
            .iter_mut()
            .find(|t| t.family == family && t.reason == reason)
        {
            Some(t) => {
                if !t.keys.contains(&key) {
                    t.keys.push(key);
                }
                t.settings += 1;
                t.least = t.least.min(figure);
                t.most = t.most.max(figure);
            }
            None => tallies.push(Tally {
                family,
                reason,
                keys: vec![key],
                settings: 1,
                least: figure,
                most: figure,
            }),
        }
    }
    let left = tallies
        .into_iter()
        .map(|t| LeftOut {
            reason: match t.reason {
                Reason::Values => format!(
                    "evaluate and train would refuse them on these recordings: their feature vectors would hold {} values or more, over the limit of {}",
                    counted(t.least as usize),
                    counted(crate::dataset::MAX_VALUES)
                ),
                Reason::Comparisons => format!(
                    "evaluate would refuse to validate them on these recordings: {:.1e} value comparisons (k-NN) or multiply-adds a fit (ridge and LDA) or more, over the limit of {MAX_COMPARISONS:.0e}",
                    t.least
                ),
                Reason::Seconds => format!(
                    "about {} each in this search ({}), over --max-minutes {max_minutes}; --max-minutes {} searches them",
                    cpu_time(t.least, t.most),
                    if t.family == FeatureFamily::Hydra {
                        format!("the features of {} recordings, made once", counted(fits.recordings))
                    } else {
                        format!(
                            "{} fits, {} recordings transformed",
                            counted(work.fits),
                            counted(work.transformed)
                        )
                    },
                    (t.most / 60.0).ceil()
                ),
            },
            family: crate::profile::options::plain_word(&t.family),
            feature_settings: t.keys.len(),
            settings: t.settings,
        })
        .collect();
    (kept, left)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(train: usize, test: usize) -> Part {
        Part {
            train: (0..train).collect(),
            test: (train..train + test).collect(),
        }
    }

    /// `n` recordings (from `from`) dealt into 5 folds that each test
    /// every fifth one and train on the rest.
    fn dealt(from: usize, n: usize) -> Vec<Part> {
        (0..5)
            .map(|j| {
                let (test, train): (Vec<usize>, Vec<usize>) =
                    (from..from + n).partition(|r| r % 5 == j);
                Part { train, test }
            })
            .collect()
    }

    #[test]
    fn the_work_counts_every_fold_that_fits_and_what_it_transforms() {
        // Two outer folds of 10 + 10, each with 5 inner folds of 8 + 2, and
        // the search over all 20 that chooses (no test part).
        let parts = vec![part(10, 10), part(10, 10), part(20, 0)];
        let inner = vec![dealt(0, 10), dealt(0, 10), dealt(0, 20)];
        let w = Work::of(&parts, &inner);
        assert_eq!(w.fits, 15 + 2);
        assert_eq!(w.transformed, 5 * 10 + 5 * 10 + 5 * 20 + 20 + 20);
        // Forward folds (fold j trains on blocks 0..=j, tests block j + 1)
        // all train on the first block: one fit, each recording once.
        let forward: Vec<Part> = (1..5)
            .map(|j| Part {
                train: (0..2 * j).collect(),
                test: (2 * j..2 * j + 2).collect(),
            })
            .collect();
        let w = Work::of(&[part(10, 10)], &[forward]);
        assert_eq!(w.fits, 1 + 1);
        assert_eq!(w.transformed, 10 + 20);
    }

    #[test]
    fn figures_read_as_a_person_writes_them() {
        assert_eq!(cpu_time(600.0, 600.0), "10 CPU-minutes");
        assert_eq!(cpu_time(600.0, 1800.0), "10 to 30 CPU-minutes");
        assert_eq!(cpu_time(2.8 * 3600.0, 3.5 * 3600.0), "2.8 to 3.5 CPU-hours");
        assert_eq!(counted(21_436_128), "21,436,128");
        assert_eq!(counted(341), "341");
        assert_eq!(counted(1000), "1,000");
    }
}
