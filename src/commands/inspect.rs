//! `hapticlab inspect`: a dataset's health (the thesis's section 4.2) —
//! recordings per class, incomplete or unreadable files, scans the analysis
//! cannot use, per-class feature spread, and outliers.
//!
//! An outlier is a scan whose feature vector lies far from its class's
//! centroid: features are first standardised over the whole dataset (so no
//! feature dominates by its unit), then each scan's Euclidean distance to
//! its class's centroid is compared with that class's distances: beyond
//! `median + t · 1.4826 · MAD` (t = 3 by default; 1.4826 · MAD estimates a
//! standard deviation robustly, so one wild scan cannot hide itself by
//! inflating the spread), on the scale `d^(2/3)` where the skewed distances
//! are close to symmetric ([`robust_threshold`]). With `[analysis]
//! windows` the spread and thresholds are over sub-windows and a recording
//! is an outlier when most of its sub-windows are. [`outliers`] is pure;
//! the command reads files.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Serialize;

use crate::classify::{Scaling, TrainingExample};
use crate::dataset::{self, Skipped, Unusable, named_once};
use crate::support::{Failure, ProfileArg, folder_of, load_profile};

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outlier {
    pub file: String,
    pub label: String,
    /// Distance to the class centroid (standardised features).
    pub distance: f64,
    /// The class's threshold it exceeds.
    pub threshold: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassHealth {
    pub label: String,
    pub recordings: usize,
    /// Mean over the features of the within-class variance (raw features).
    pub mean_feature_variance: f64,
    /// Per feature: the within-class variance (raw features).
    pub feature_variance: Vec<f64>,
    /// Median distance to the centroid (standardised features).
    pub median_distance: f64,
    pub threshold: f64,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if !v.len().is_multiple_of(2) {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    }
}

/// The distance beyond which a scan is an outlier: the median + t robust
/// standard deviations (1.4826 · MAD) of the distances, taken on the scale
/// `d^(2/3)` and mapped back. Distances to a centroid are positive and
/// skewed (for a Gaussian class, d² is chi-square), most of all when a class
/// varies along few directions; a symmetric rule on `d` itself then flags
/// the long right tail of perfectly ordinary classes (n = 30, t = 3: 2.4 %
/// of the scans of a 1-D Gaussian class, 0.6 % in 49-D, against 0.13 % for
/// a normal variable). `(d²)^(1/3)` is close to normal for a chi-square of
/// any degrees (Wilson and Hilferty, 1931), which brings that to about
/// 0.5 % whatever the dimension. The robust deviation is floored at 1e-9 of
/// the median so float noise in a class of near-identical scans is not an
/// outlier.
pub fn robust_threshold(dist: &[f64], t: f64) -> f64 {
    let x: Vec<f64> = dist.iter().map(|d| d.powf(2.0 / 3.0)).collect();
    let med = median(&mut x.clone());
    let mut dev: Vec<f64> = x.iter().map(|v| (v - med).abs()).collect();
    let sd = (1.4826 * median(&mut dev)).max(1e-9 * med);
    (med + t * sd).max(0.0).powf(1.5)
}

/// Per-class health and the outliers, class by class in label order, each
/// class's outliers farthest first.
pub fn outliers(examples: &[TrainingExample], t: f64) -> (Vec<ClassHealth>, Vec<Outlier>) {
    let rows: Vec<&[f64]> = examples.iter().map(|e| e.features.as_slice()).collect();
    let scaling = Scaling::fit(&rows);
    let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, e) in examples.iter().enumerate() {
        by.entry(&e.label).or_default().push(i);
    }
    let d = rows.first().map_or(0, |r| r.len());
    let (mut health, mut out) = (Vec::new(), Vec::new());
    for (label, idx) in by {
        let n = idx.len() as f64;
        let mut raw_mean = vec![0.0; d];
        let mut centroid = vec![0.0; d];
        let mut z = vec![0.0; d];
        let scaled: Vec<Vec<f64>> = idx
            .iter()
            .map(|&i| {
                scaling.apply(rows[i], &mut z);
                z.clone()
            })
            .collect();
        for (&i, s) in idx.iter().zip(&scaled) {
            for f in 0..d {
                raw_mean[f] += rows[i][f] / n;
                centroid[f] += s[f] / n;
            }
        }
        let feature_variance: Vec<f64> = (0..d)
            .map(|f| {
                idx.iter()
                    .map(|&i| (rows[i][f] - raw_mean[f]).powi(2))
                    .sum::<f64>()
                    / (n - 1.0).max(1.0)
            })
            .collect();
        let dist: Vec<f64> = scaled
            .iter()
            .map(|s| {
                s.iter()
                    .zip(&centroid)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let med = median(&mut dist.clone());
        let threshold = robust_threshold(&dist, t);
        let mut found: Vec<Outlier> = idx
            .iter()
            .zip(&dist)
            .filter(|(_, x)| idx.len() >= 3 && **x > threshold && **x > 1e-12)
            .map(|(&i, &x)| Outlier {
                file: examples[i].file.clone(),
                label: label.to_string(),
                distance: x,
                threshold,
            })
            .collect();
        found.sort_by(|a, b| b.distance.total_cmp(&a.distance));
        out.extend(found);
        health.push(ClassHealth {
            label: label.to_string(),
            recordings: idx.len(),
            mean_feature_variance: feature_variance.iter().sum::<f64>() / d.max(1) as f64,
            feature_variance,
            median_distance: med,
            threshold,
        });
    }
    (health, out)
}

#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    pub files: usize,
    pub classes: Vec<ClassHealth>,
    pub incomplete: Vec<String>,
    /// Files that could not be read, with the reason.
    pub unreadable: Vec<(String, String)>,
    /// Complete recordings the analysis cannot use, with the reason.
    pub unusable: Vec<(String, String)>,
    pub outliers: Vec<Outlier>,
    pub threshold_factor: f64,
}

impl Inspection {
    pub fn text(&self) -> String {
        let mut s = format!(
            "{} files: {} usable, {} incomplete, {} unreadable, {} unusable by the analysis\n\n",
            self.files,
            self.classes.iter().map(|c| c.recordings).sum::<usize>(),
            self.incomplete.len(),
            self.unreadable.len(),
            self.unusable.len()
        );
        s.push_str("class  recordings  mean feature variance  median distance  outlier beyond\n");
        for c in &self.classes {
            s.push_str(&format!(
                "{:<5}  {:>10}  {:>21.4e}  {:>15.3}  {:>14.3}\n",
                c.label, c.recordings, c.mean_feature_variance, c.median_distance, c.threshold
            ));
        }
        let counts: Vec<usize> = self.classes.iter().map(|c| c.recordings).collect();
        if let (Some(lo), Some(hi)) = (counts.iter().min(), counts.iter().max())
            && lo != hi
        {
            s.push_str(&format!(
                "note: the classes are unbalanced ({lo} to {hi} recordings)\n"
            ));
        }
        for f in &self.incomplete {
            s.push_str(&format!("incomplete: {f} (no `# end samples` trailer)\n"));
        }
        for (f, e) in &self.unreadable {
            s.push_str(&format!("unreadable: {}\n", named_once(f, e)));
        }
        for (reason, files) in alike(&self.unusable) {
            match files[..] {
                [f] => s.push_str(&format!("unusable: {}\n", named_once(f, reason))),
                _ => s.push_str(&format!(
                    "unusable: {} recordings: {reason} ({})\n",
                    files.len(),
                    some_of(&files)
                )),
            }
        }
        s.push_str(&small_classes_note(&self.classes));
        if self.outliers.is_empty() {
            s.push_str(&format!(
                "no outliers (distance d to the class centroid beyond median + {} x 1.4826 x MAD of d^(2/3))\n",
                self.threshold_factor
            ));
        } else {
            s.push_str(&format!(
                "outliers (distance d to the class centroid beyond median + {} x 1.4826 x MAD of d^(2/3), standardised features):\n",
                self.threshold_factor
            ));
            for o in &self.outliers {
                s.push_str(&format!(
                    "  {}  {}  distance {:.3} > {:.3}\n",
                    o.file, o.label, o.distance, o.threshold
                ));
            }
        }
        s
    }
}

/// Below this many recordings a class's median and MAD are rough: on
/// Gaussian classes (1, 2 and 49 dimensions, t = 3) the rule flags about
/// 2–5 % of ordinary scans at 3 to 8 recordings and 1.4–1.7 % at 10,
/// against 0.5 % at 30 (`small_classes_flag_ordinary_scans_more_often`
/// measures it).
const FEW_FOR_OUTLIERS: usize = 10;

/// A line naming the classes too small to look for outliers in (under 3:
/// none are called) or to trust a flag in (under [`FEW_FOR_OUTLIERS`]).
fn small_classes_note(classes: &[ClassHealth]) -> String {
    let names = |keep: &dyn Fn(usize) -> bool| -> Vec<&str> {
        classes
            .iter()
            .filter(|c| keep(c.recordings))
            .map(|c| c.label.as_str())
            .collect()
    };
    let none = names(&|n| n < 3);
    let rough = names(&|n| (3..FEW_FOR_OUTLIERS).contains(&n));
    let mut s = String::new();
    if !none.is_empty() {
        s.push_str(&format!(
            "note: {}: fewer than 3 recordings, no outliers are looked for\n",
            none.join(", ")
        ));
    }
    if !rough.is_empty() {
        s.push_str(&format!(
            "note: {}: fewer than {FEW_FOR_OUTLIERS} recordings, so the median and spread are rough and \
             an ordinary scan is flagged about 2–5 % of the time (0.5 % at 30): look at a flagged scan \
             (hapticlab plot trace FILE) before setting it aside\n",
            rough.join(", ")
        ));
    }
    s
}

/// The unusable recordings grouped by their reason, in the order first
/// met: recordings under the wrong profile all give the same reason, and
/// one line says it for all.
fn alike(unusable: &[(String, String)]) -> Vec<(&str, Vec<&str>)> {
    let mut out: Vec<(&str, Vec<&str>)> = Vec::new();
    for (f, e) in unusable {
        let reason = e
            .strip_prefix(f.as_str())
            .and_then(|r| r.strip_prefix(": "))
            .unwrap_or(e);
        match out.iter_mut().find(|(r, _)| *r == reason) {
            Some((_, files)) => files.push(f),
            None => out.push((reason, vec![f])),
        }
    }
    out
}

/// The first three files, and how many more.
fn some_of(files: &[&str]) -> String {
    let shown = files[..files.len().min(3)].join(", ");
    match files.len() {
        n if n > 3 => format!("{shown} and {} more", n - 3),
        _ => shown,
    }
}

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    /// Outlier threshold t: distance d to the class centroid beyond median + t x 1.4826 x MAD, on the scale d^(2/3).
    #[arg(long, default_value_t = 3.0, value_name = "T")]
    pub threshold: f64,
    /// Print JSON for scripts.
    #[arg(long)]
    pub json: bool,
}

/// `hapticlab inspect`.
pub fn run(a: InspectArgs) -> Result<(), Failure> {
    let InspectArgs {
        profile,
        paths,
        threshold,
        json,
    } = a;
    let paths = &paths[..];
    let lp = load_profile(&profile)?;
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(Failure::BadInput(format!(
            "--threshold must be a positive number, got {threshold}"
        )));
    }
    let files = dataset::find(paths)?;
    let loaded = dataset::load(
        &files,
        &lp.profile.analysis,
        dataset::Options {
            unusable: Unusable::Skip,
            ..dataset::Options::default()
        },
        &|| {},
    )?;
    let (mut incomplete, mut unreadable, mut unusable) = (Vec::new(), Vec::new(), Vec::new());
    for s in &loaded.skipped {
        match s {
            Skipped::Incomplete { file, .. } => incomplete.push(file.clone()),
            Skipped::Unusable {
                file,
                reason,
                unreadable: true,
            } => unreadable.push((file.clone(), reason.clone())),
            Skipped::Unusable { file, reason, .. } => unusable.push((file.clone(), reason.clone())),
        }
    }
    let examples = loaded.into_examples();
    let (mut classes, mut outliers) = outliers(&examples, threshold);
    if lp.profile.analysis.windows.is_some() {
        (classes, outliers) = by_recording(&examples, classes, outliers);
    }
    let report = Inspection {
        files: files.len(),
        classes,
        incomplete,
        unreadable,
        unusable,
        outliers,
        threshold_factor: threshold,
    };
    if json {
        crate::outln!(
            "{}",
            serde_json::to_string(&report).map_err(|e| Failure::Runtime(e.to_string()))?
        );
    } else {
        crate::outp!("{}", report.text());
    }
    if report.classes.is_empty() && !report.unusable.is_empty() && lp.is_built_in() {
        let a = &lp.profile.analysis;
        crate::errln!(
            "warning: none of the {} recordings could be analysed by the built-in thesis profile (used when no -p is given; it analyses {} along {} of the thesis's Falcon scans): give their profile with -p P.toml, or make one: hapticlab profile new --from {} --out P.toml",
            report.files,
            a.channel,
            a.axis,
            folder_of(paths)
        );
    }
    Ok(())
}

/// With `[analysis] windows` the statistics are over sub-windows (the
/// examples, a recording's consecutive); this counts each class's
/// recordings and keeps as outliers the recordings most of whose
/// sub-windows are (the vote), each with its farthest flagged sub-window.
fn by_recording(
    examples: &[TrainingExample],
    mut classes: Vec<ClassHealth>,
    window_outliers: Vec<Outlier>,
) -> (Vec<ClassHealth>, Vec<Outlier>) {
    let mut windows: BTreeMap<&str, usize> = BTreeMap::new();
    for e in examples {
        *windows.entry(&e.file).or_default() += 1;
    }
    for c in &mut classes {
        c.recordings = examples
            .iter()
            .enumerate()
            .filter(|(i, e)| e.label == c.label && (*i == 0 || examples[i - 1].file != e.file))
            .count();
    }
    let mut flagged: BTreeMap<String, Vec<Outlier>> = BTreeMap::new();
    for o in window_outliers {
        flagged.entry(o.file.clone()).or_default().push(o);
    }
    let mut out: Vec<Outlier> = flagged
        .into_iter()
        .filter(|(file, w)| 2 * w.len() > windows.get(file.as_str()).copied().unwrap_or(0))
        .filter_map(|(_, w)| {
            w.into_iter()
                .max_by(|a, b| a.distance.total_cmp(&b.distance))
        })
        .collect();
    out.sort_by(|a, b| {
        a.label
            .cmp(&b.label)
            .then(b.distance.total_cmp(&a.distance))
    });
    (classes, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ex(file: &str, label: &str, f: Vec<f64>) -> TrainingExample {
        TrainingExample {
            file: file.into(),
            label: label.into(),
            features: f,
        }
    }

    #[test]
    fn a_wild_scan_is_flagged_and_the_rest_are_not() {
        let mut v = Vec::new();
        for i in 0..20 {
            let j = (i * 7 % 5) as f64 * 0.01;
            v.push(ex(&format!("a{i}"), "A", vec![1.0 + j, 2.0 - j]));
            v.push(ex(&format!("b{i}"), "B", vec![5.0 - j, 1.0 + j]));
        }
        v.push(ex("wild", "A", vec![3.0, 0.0]));
        let (health, out) = outliers(&v, 3.0);
        assert_eq!(out.len(), 1, "{out:?}");
        assert_eq!(out[0].file, "wild");
        assert_eq!(health[0].recordings, 21);
        assert!(health[1].mean_feature_variance < health[0].mean_feature_variance);
        // A class of identical scans has no outlier.
        let same: Vec<_> = (0..5)
            .map(|i| ex(&format!("s{i}"), "S", vec![1.0]))
            .collect();
        assert!(outliers(&same, 3.0).1.is_empty());
    }

    /// Small classes are named: under 3 nothing is looked for, under 10 a
    /// flag is rough; 10 or more say nothing.
    #[test]
    fn small_classes_say_their_flags_are_rough() {
        let v: Vec<_> = (0..12)
            .flat_map(|i| {
                let f = vec![(i * 7 % 5) as f64];
                let mut e = vec![ex(&format!("a{i}"), "A", f.clone())];
                if i < 5 {
                    e.push(ex(&format!("b{i}"), "B", f.clone()));
                }
                if i < 2 {
                    e.push(ex(&format!("c{i}"), "C", f));
                }
                e
            })
            .collect();
        let (classes, outliers) = outliers(&v, 3.0);
        let t = Inspection {
            files: v.len(),
            classes,
            incomplete: vec![],
            unreadable: vec![],
            unusable: vec![],
            outliers,
            threshold_factor: 3.0,
        }
        .text();
        assert!(t.contains("note: C: fewer than 3 recordings"), "{t}");
        assert!(t.contains("note: B: fewer than 10 recordings"), "{t}");
        assert!(!t.contains("A: fewer"), "{t}");
    }

    /// A reason that already names its file names it once.
    #[test]
    fn each_bad_file_is_named_once() {
        let i = Inspection {
            files: 2,
            classes: vec![],
            incomplete: vec![],
            unreadable: vec![(
                "d/x.csv".into(),
                "d/x.csv:1: not a hapticlab recording".into(),
            )],
            unusable: vec![("d/y.csv".into(), "the scan covers too little".into())],
            outliers: vec![],
            threshold_factor: 3.0,
        };
        let t = i.text();
        assert!(
            t.contains("unreadable: d/x.csv:1: not a hapticlab recording\n"),
            "{t}"
        );
        assert!(
            t.contains("unusable: d/y.csv: the scan covers too little\n"),
            "{t}"
        );
    }

    /// Ordinary Gaussian classes varying along one direction (the most
    /// skewed distances): few flags. The rule on `d` itself flagged 2.4 %.
    #[test]
    fn ordinary_classes_are_rarely_flagged_whatever_their_dimension() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for dims in [1usize, 2, 49] {
            let mut v = Vec::new();
            for c in 0..300 {
                for i in 0..30 {
                    let f: Vec<f64> = (0..dims)
                        .map(|j| {
                            let z: f64 = StandardNormal.sample(&mut rng);
                            10.0 * (c * dims + j) as f64 + z
                        })
                        .collect();
                    v.push(ex(&format!("{c}/{i}"), &format!("c{c}"), f));
                }
            }
            let flagged = outliers(&v, 3.0).1.len() as f64 / v.len() as f64;
            assert!(
                flagged < 0.009,
                "{dims} dims: {:.2} % flagged",
                100.0 * flagged
            );
        }
    }

    /// What [`FEW_FOR_OUTLIERS`] says: five recordings of a Gaussian class
    /// have several times the false flags of thirty.
    #[test]
    fn small_classes_flag_ordinary_scans_more_often() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut rate = |n: usize| {
            let v: Vec<_> = (0..(12_000 / n))
                .flat_map(|c| (0..n).map(move |i| (c, i)))
                .map(|(c, i)| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    ex(
                        &format!("{c}/{i}"),
                        &format!("c{c}"),
                        vec![10.0 * c as f64 + z],
                    )
                })
                .collect();
            outliers(&v, 3.0).1.len() as f64 / v.len() as f64
        };
        let (five, thirty) = (rate(5), rate(30));
        assert!(five > 0.02 && thirty < 0.009, "{five} at 5, {thirty} at 30");
    }

    /// A recording is an outlier when most of its sub-windows are; classes
    /// count recordings, not sub-windows.
    #[test]
    fn with_windows_a_recording_is_an_outlier_by_the_vote_of_its_windows() {
        let mut v = Vec::new();
        for i in 0..20 {
            let j = (i * 7 % 5) as f64 * 0.01;
            for w in 0..3 {
                let (a, b) = if i == 0 && w < 2 || i == 1 && w == 0 {
                    (3.0, 0.0)
                } else {
                    (1.0 + j, 2.0 - j)
                };
                v.push(ex(&format!("a{i}"), "A", vec![a, b]));
                v.push(ex(&format!("b{i}"), "B", vec![5.0 - j, 1.0 + j]));
            }
        }
        // Each recording's windows consecutive, as the loader gives them.
        v.sort_by(|x, y| x.file.cmp(&y.file));
        let (health, out) = outliers(&v, 3.0);
        assert_eq!(out.len(), 3, "{out:?}");
        let (health, out) = by_recording(&v, health, out);
        assert_eq!(out.len(), 1, "{out:?}");
        assert_eq!(out[0].file, "a0");
        assert_eq!(health[0].recordings, 20);
        assert_eq!(health[1].recordings, 20);
    }

    #[test]
    fn the_threshold_maps_back_to_distances() {
        // Symmetric on the d^(2/3) scale: 1, 8, 27 (2/3-powers 1, 4, 9).
        let t = robust_threshold(&[1.0, 8.0, 27.0], 0.0);
        assert!((t - 8.0).abs() < 1e-9, "{t}");
        // MAD of the 2/3-powers is 3 (|1-4|, 0, |9-4|=5 -> median 3).
        let t = robust_threshold(&[1.0, 8.0, 27.0], 1.0);
        assert!((t - (4.0 + 1.4826 * 3.0f64).powf(1.5)).abs() < 1e-9, "{t}");
    }
}
