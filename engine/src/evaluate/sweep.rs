//! Parameter sweeps (`evaluate --sweep KEY=VALUES`, repeated for a grid):
//! the thesis's section 4.3 parameter selection, one validation
//! ([`super::plan::validate`]) per value of a profile key, or per
//! combination of the values of several keys (every one of them, the first
//! key's values changing slowest).
//!
//! The recordings are read once ([`crate::dataset::load`], on every core)
//! into a [`Recordings`] holding each one's feature vector and metadata, or,
//! for a sweep over an `[analysis]` key, the columns the analysis reads, so
//! features are extracted again per point without re-reading files. A
//! sweep sets keys of the profile's `[analysis]`, `[classifier]` or
//! `[evaluation]` table through TOML ([`keys`]), so every key those tables
//! accept can be swept and is validated as in a profile file, all of a
//! point's keys together. Keys that change the recordings themselves (the
//! path's speed, the controller's stiffness, any `[controller]`, `[path]`,
//! `[simulator]` or `[device]` key) need a new dataset per value: with
//! `--simulate`, each value simulates one in virtual time (in a temporary
//! folder, same seed for every value) and evaluates it; over recordings on
//! disk they are refused.
//!
//! A point the profile refuses (a value that makes another key invalid,
//! `spectrum = "welch"` beside `bins` only the magnitude spectrum has), or
//! whose recordings its analysis cannot use, is "not evaluated" with the
//! reason, and the sweep goes on. The best point is the one with the
//! highest pooled accuracy (each of them when several tie); when every
//! point ties there is no best. The text tables are in [`table`].
//!
//! Like the rest of `evaluate`, this never prints and knows no front end.

mod keys;
mod table;
pub use table::grid_axis;

pub use keys::{
    ANALYSIS_TABLES, SIMULATION_TABLES, SweepKey, parse_sweep, profile_with, resolve_key, with_key,
    with_resolved,
};

use serde::Serialize;

use super::EvaluateError;
use super::cv::CvReport;
use super::plan::{Plan, Recordings, Related, validate};
use crate::classify::TrainingExample;
use crate::dataset::{self, Keep, Options, Skipped, Unusable, meta_text};
use crate::profile::{Analysis, LoadedProfile, Profile};

fn bad(m: impl std::fmt::Display) -> EvaluateError {
    EvaluateError::Input(m.to_string())
}

/// The most points one sweep evaluates (all keys' values multiplied).
pub const MAX_POINTS: usize = 10_000;

/// One swept key and its values, as typed (`--sweep k=1..15`).
#[derive(Debug, Clone, PartialEq)]
pub struct Swept {
    pub key: String,
    pub values: Vec<toml::Value>,
}

impl Swept {
    /// `KEY=VALUES`, as [`parse_sweep`] reads it.
    pub fn parse(spec: &str) -> Result<Swept, EvaluateError> {
        let (key, values) = parse_sweep(spec)?;
        Ok(Swept { key, values })
    }
}

/// Every combination of the swept keys' values, as an index into each
/// key's values; the first key's changes slowest, so a two-key grid comes
/// row by row (rows the first key's values, columns the second's).
pub fn combinations(swept: &[Swept]) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new()];
    for s in swept {
        out = out
            .into_iter()
            .flat_map(|c: Vec<usize>| {
                (0..s.values.len()).map(move |i| {
                    let mut c = c.clone();
                    c.push(i);
                    c
                })
            })
            .collect();
    }
    out
}

/// The swept keys resolved against the profile. No key, the same key (or
/// vector component) twice, or more than [`MAX_POINTS`] combinations is
/// bad input.
pub fn resolve_all(profile: &Profile, swept: &[Swept]) -> Result<Vec<SweepKey>, EvaluateError> {
    if swept.is_empty() {
        return Err(bad("--sweep: no key to sweep"));
    }
    let keys = swept
        .iter()
        .map(|s| resolve_key(profile, &s.key))
        .collect::<Result<Vec<_>, _>>()?;
    for (i, k) in keys.iter().enumerate() {
        let same = |o: &SweepKey| {
            o.table == k.table
                && o.field == k.field
                && (o.component == k.component || o.component.is_none() || k.component.is_none())
        };
        if keys[..i].iter().any(same) {
            return Err(bad(format!(
                "--sweep {}: this key is swept twice; give each key once (one --sweep per key of the grid)",
                k.name()
            )));
        }
    }
    let n = swept
        .iter()
        .try_fold(1usize, |n, s| n.checked_mul(s.values.len()))
        .filter(|&n| n <= MAX_POINTS);
    if n.is_none() {
        let sizes: Vec<String> = swept.iter().map(|s| s.values.len().to_string()).collect();
        return Err(bad(format!(
            "--sweep: {} combinations is too many (at most {MAX_POINTS}); sweep fewer values",
            sizes.join(" × ")
        )));
    }
    Ok(keys)
}

#[derive(Debug, Clone, Serialize)]
pub struct SweepPoint {
    /// The swept value; in a grid, each key's value joined by ", ".
    pub value: String,
    /// Each swept key's value, in the order of [`Sweep::keys`].
    pub values: Vec<String>,
    /// Whether this point was evaluated. When not, `reason` says why and
    /// its numbers are NaN (`null` in JSON).
    pub evaluated: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub accuracy: f64,
    pub accuracy_mean: f64,
    pub accuracy_std: f64,
    pub macro_f1: f64,
    /// The k used per fold (differs from the value with k = "auto", and
    /// where a texture had fewer training scans than k: see `k_notice`).
    pub k: Vec<usize>,
    /// Why the value's k gave way to one chosen by CV in some folds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_notice: Option<String>,
    /// Recordings evaluated (simulated sweeps: scans that finished).
    pub recordings: usize,
    /// Simulated sweeps: scans that did not finish (left out).
    #[serde(skip_serializing_if = "is_zero")]
    pub incomplete: usize,
    /// The same text as `reason`, under the name simulated sweeps first
    /// gave it (kept for the scripts that read it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// The best point: the highest pooled accuracy (each of them when
    /// several tie). No point is best when every point ties.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub best: bool,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    /// The swept key (as typed; simulated sweeps: `table.field`); in a
    /// grid, the keys joined by " × ".
    pub key: String,
    /// Each swept key, in the order given: a two-key grid's rows are the
    /// first key's values, its columns the second's.
    pub keys: Vec<String>,
    pub method: String,
    /// One per combination, the first key's value changing slowest.
    pub points: Vec<SweepPoint>,
    /// Set when every value was evaluated on its own simulated dataset.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated: Option<SimulatedInfo>,
}

impl Sweep {
    fn new(
        keys: Vec<String>,
        method: String,
        mut points: Vec<SweepPoint>,
        simulated: Option<SimulatedInfo>,
    ) -> Sweep {
        mark_best(&mut points);
        Sweep {
            key: keys.join(" × "),
            keys,
            method,
            points,
            simulated,
        }
    }

    /// How many points were evaluated.
    pub fn evaluated(&self) -> usize {
        self.points.iter().filter(|p| p.evaluated).count()
    }

    /// The best points (none when every point ties).
    pub fn best(&self) -> impl Iterator<Item = &SweepPoint> {
        self.points.iter().filter(|p| p.best)
    }
}

/// Mark the points with the highest accuracy as best, unless every point
/// ties: all evaluated with one accuracy, or none evaluated. A point not
/// evaluated ranks below every evaluated one.
fn mark_best(points: &mut [SweepPoint]) {
    let top = points
        .iter()
        .filter(|p| p.evaluated)
        .map(|p| p.accuracy)
        .reduce(f64::max);
    let Some(top) = top else { return };
    if points.iter().all(|p| p.evaluated && p.accuracy == top) {
        return;
    }
    for p in points {
        p.best = p.evaluated && p.accuracy == top;
    }
}

/// How a simulated sweep's datasets were made.
#[derive(Debug, Clone, Serialize)]
pub struct SimulatedInfo {
    /// Scans per texture and value.
    pub per_class: usize,
    /// The dataset seed (the profile's `simulator.seed`): the same for every
    /// value, so the values differ only in the swept key.
    pub seed: u64,
}

/// A temporary folder for one simulated dataset's scans, made by the front
/// end, which decides what an interruption (Ctrl-C) does while workers fill
/// it: the engine only reports progress through [`Scratch::watch`] and calls
/// [`Scratch::checkpoint`] between steps. The folder is removed on drop.
pub trait Scratch: Sync {
    fn path(&self) -> &std::path::Path;
    /// Wraps the progress callback of `workers` threads filling the folder,
    /// called after each of their scans.
    fn watch<'a>(
        &'a self,
        workers: usize,
        progress: &'a (dyn Fn(usize, usize) + Sync),
    ) -> Box<dyn Fn(usize, usize) + Sync + 'a>;
    /// A point between steps where the front end may end the run.
    fn checkpoint(&self);
}

/// A plain temporary folder, for a caller with no interruption to handle.
struct TempScratch(tempfile::TempDir);

impl Scratch for TempScratch {
    fn path(&self) -> &std::path::Path {
        self.0.path()
    }
    fn watch<'a>(
        &'a self,
        _workers: usize,
        progress: &'a (dyn Fn(usize, usize) + Sync),
    ) -> Box<dyn Fn(usize, usize) + Sync + 'a> {
        Box::new(progress)
    }
    fn checkpoint(&self) {}
}

/// A [`Scratch`] that is only a temporary folder named `hapticlab-simulate-…`.
pub fn temp_scratch<'a>() -> Result<Box<dyn Scratch + 'a>, String> {
    let dir = tempfile::Builder::new()
        .prefix("hapticlab-simulate-")
        .tempdir()
        .map_err(|e| e.to_string())?;
    Ok(Box::new(TempScratch(dir)))
}

/// Makes a [`Scratch`] folder for each simulated dataset.
pub type MakeScratch<'a> = dyn Fn() -> Result<Box<dyn Scratch + 'a>, String> + Sync + 'a;

/// How `evaluate --simulate` makes its datasets.
#[derive(Clone, Copy)]
pub struct SimPlan<'a> {
    pub per_class: usize,
    pub threads: usize,
    /// Where each dataset's scans are written while it is read.
    pub scratch: &'a MakeScratch<'a>,
}

impl std::fmt::Debug for SimPlan<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimPlan")
            .field("per_class", &self.per_class)
            .field("threads", &self.threads)
            .finish_non_exhaustive()
    }
}

/// `progress` hears (done, total) scans.
pub fn simulated_dataset(
    lp: &crate::profile::LoadedProfile,
    sim: SimPlan<'_>,
    analysis: &Analysis,
    options: Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Recordings, EvaluateError> {
    // Removed on drop; the front end decides what Ctrl-C does meanwhile.
    let dir = (sim.scratch)().map_err(EvaluateError::Scratch)?;
    let opts = crate::acquire::SimulateOptions {
        out: dir.path().to_path_buf(),
        per_class: sim.per_class,
        seed: lp.profile.simulator.seed,
        threads: sim.threads.max(1),
        gzip: false,
        overwrite: false,
    };
    crate::acquire::simulate_dataset(lp, &opts, &*dir.watch(opts.threads, progress))?;
    dir.checkpoint();
    let files = dataset::find(&[dir.path().to_path_buf()])?;
    let options = Options {
        threads: sim.threads,
        ..options
    };
    let mut data = Recordings::load_files(&files, analysis, options, &|| {})?;
    dir.checkpoint();
    let relative = |f: &str| {
        std::path::Path::new(f)
            .strip_prefix(dir.path())
            .map_or_else(|_| f.to_string(), |r| r.display().to_string())
    };
    let prefix = format!("{}/", dir.path().display());
    for s in &mut data.scans {
        s.file = relative(&s.file);
    }
    for s in &mut data.skipped {
        match s {
            Skipped::Incomplete { file, .. } => *file = relative(file),
            Skipped::Unusable { file, reason, .. } => {
                *file = relative(file);
                *reason = reason.replace(&prefix, "");
            }
        }
    }
    data.scans.sort_by(|a, b| a.file.cmp(&b.file));
    data.skipped.sort_by(|a, b| a.file().cmp(b.file()));
    Ok(data)
}

/// The keys of one point and its values, as [`profile_with`] takes them.
fn point_set<'a>(
    keys: &'a [SweepKey],
    swept: &'a [Swept],
    combo: &[usize],
) -> Vec<(&'a SweepKey, &'a toml::Value)> {
    keys.iter()
        .zip(swept)
        .zip(combo)
        .map(|((k, s), &i)| (k, &s.values[i]))
        .collect()
}

fn texts(set: &[(&SweepKey, &toml::Value)]) -> Vec<String> {
    set.iter().map(|(_, v)| meta_text(v)).collect()
}

fn evaluated(values: Vec<String>, r: &CvReport, data: &Recordings) -> SweepPoint {
    SweepPoint {
        value: values.join(", "),
        values,
        evaluated: true,
        reason: None,
        accuracy: r.report.accuracy,
        accuracy_mean: r.accuracy_mean,
        accuracy_std: r.accuracy_std,
        macro_f1: r.macro_f1,
        k: r.folds.iter().map(|f| f.k).collect(),
        k_notice: r.k_notice(),
        // Recordings, not sub-windows.
        recordings: data.counts().0,
        incomplete: data.skipped.len(),
        error: None,
        best: false,
    }
}

fn not_evaluated(
    values: Vec<String>,
    reason: String,
    recordings: usize,
    incomplete: usize,
) -> SweepPoint {
    SweepPoint {
        value: values.join(", "),
        values,
        evaluated: false,
        reason: Some(reason.clone()),
        accuracy: f64::NAN,
        accuracy_mean: f64::NAN,
        accuracy_std: f64::NAN,
        macro_f1: f64::NAN,
        k: Vec::new(),
        k_notice: None,
        recordings,
        incomplete,
        error: Some(reason),
        best: false,
    }
}

/// Features under `analysis`, extracted once per distinct analysis of the
/// sweep (a grid meets the same one on every row).
fn examples_for(
    analysis: &Analysis,
    data: &Recordings,
    cache: &mut Vec<(Analysis, Vec<TrainingExample>)>,
) -> Result<Vec<TrainingExample>, EvaluateError> {
    if let Some((_, e)) = cache.iter().find(|(a, _)| a == analysis) {
        return Ok(e.clone());
    }
    let e = data.examples(analysis)?;
    cache.push((analysis.clone(), e.clone()));
    Ok(e)
}

/// Validate one point's profile on `data`. With an `[evaluation]` key
/// swept (`replan`), the plan is made again from the point's profile, so a
/// swept `folds` or `method` takes effect (the command line's still win).
fn validate_point(
    p: &Profile,
    data: &Recordings,
    cache: &mut Vec<(Analysis, Vec<TrainingExample>)>,
    plan: &Plan,
    replan: bool,
) -> Result<CvReport, EvaluateError> {
    let plan = if replan {
        plan.for_profile(p)
    } else {
        plan.clone()
    };
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let examples = examples_for(&p.analysis, data, cache)?;
    let segments = data.segments();
    validate(
        p,
        examples,
        Related::new(groups.as_deref(), &segments),
        &plan,
    )
}

/// Evaluate one key over its values (a one-key [`sweep_grid`]).
pub fn sweep(
    profile: &Profile,
    data: &Recordings,
    key: &str,
    values: &[toml::Value],
    plan: &Plan,
    progress: &dyn Fn(usize),
) -> Result<Sweep, EvaluateError> {
    let swept = [Swept {
        key: key.to_string(),
        values: values.to_vec(),
    }];
    sweep_grid(profile, data, &swept, plan, progress)
}

/// Evaluate every combination of the swept keys' values on `data`;
/// features are extracted again only for an analysis not met before. A
/// point that cannot be evaluated (the profile refuses the combination, the
/// analysis cannot use the recordings, the split cannot be made) is
/// reported with its reason and the sweep goes on; an unknown key, a key
/// swept twice, or a runtime failure stops it. `progress` hears the
/// points done.
pub fn sweep_grid(
    profile: &Profile,
    data: &Recordings,
    swept: &[Swept],
    plan: &Plan,
    progress: &dyn Fn(usize),
) -> Result<Sweep, EvaluateError> {
    let keys = resolve_all(profile, swept)?;
    if let Some(s) = swept
        .iter()
        .zip(&keys)
        .find_map(|(s, k)| k.needs_simulation().then_some(s))
    {
        return Err(bad(format!(
            "--sweep {}: this key changes the recordings themselves; sweep it on simulated datasets (--simulate)",
            s.key
        )));
    }
    // A missing group key is the whole sweep's error, not each point's.
    if let Some(g) = &plan.group_by {
        data.groups(g)?;
    }
    let (recordings, _) = data.counts();
    let replan = keys.iter().any(|k| k.table == "evaluation");
    let mut cache = Vec::new();
    let mut points = Vec::new();
    for (i, combo) in combinations(swept).iter().enumerate() {
        let set = point_set(&keys, swept, combo);
        let values = texts(&set);
        let point = match profile_with(profile, &set) {
            Err(reason) => not_evaluated(values, reason, recordings, data.skipped.len()),
            Ok(p) => {
                if p.analysis
                    .all_channels()
                    .ne(profile.analysis.all_channels())
                    || p.analysis.axis != profile.analysis.axis
                {
                    return Err(bad(
                        "--sweep: sweeping the axis or the channels is not supported; evaluate once per channel",
                    ));
                }
                match validate_point(&p, data, &mut cache, plan, replan) {
                    Ok(r) => evaluated(values, &r, data),
                    Err(e) if e.is_bad_input() => {
                        not_evaluated(values, e.to_string(), recordings, data.skipped.len())
                    }
                    Err(e) => return Err(e),
                }
            }
        };
        points.push(point);
        progress(i + 1);
    }
    // As typed (`k`), like the sweeps before simulated ones.
    let names = swept.iter().map(|s| s.key.clone()).collect();
    Ok(Sweep::new(names, plan.describe(), points, None))
}

/// Evaluate one key that changes the recordings over its values (a one-key
/// [`sweep_grid_simulated`]).
pub fn sweep_simulated(
    lp: &LoadedProfile,
    key: &str,
    values: &[toml::Value],
    plan: &Plan,
    sim: SimPlan<'_>,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Sweep, EvaluateError> {
    let swept = [Swept {
        key: key.to_string(),
        values: values.to_vec(),
    }];
    sweep_grid_simulated(lp, &swept, plan, sim, progress)
}

/// Evaluate every combination of keys among which some change the
/// recordings (the path's speed, the controller's stiffness, a simulator
/// setting): each combination's values of those keys simulate their own
/// dataset ([`simulated_dataset`], same seed for every one; the points
/// that share them share it), then the point validates as `plan` says. A
/// point the profile refuses, or whose recordings the analysis cannot use
/// (a path so fast the window has gaps), is reported with its reason and
/// the sweep goes on. `progress` hears (point index, scans done
/// in its dataset, scans per dataset).
pub fn sweep_grid_simulated(
    lp: &LoadedProfile,
    swept: &[Swept],
    plan: &Plan,
    sim: SimPlan<'_>,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Sweep, EvaluateError> {
    let keys = resolve_all(&lp.profile, swept)?;
    // Samples are kept only when an [analysis] key is swept: points with
    // the same recordings then extract their own features.
    let keep = if keys.iter().any(|k| k.table == "analysis") {
        Keep::Samples
    } else {
        Keep::Features
    };
    let replan = keys.iter().any(|k| k.table == "evaluation");
    let mut made: Option<(Vec<String>, Recordings)> = None;
    let combos = combinations(swept);
    // Evaluated grouped by the recording keys' values, so each of their
    // combinations is simulated once whatever the keys' order; reported
    // in the grid's order.
    let mut order: Vec<usize> = (0..combos.len()).collect();
    order.sort_by_key(|&i| {
        keys.iter()
            .zip(&combos[i])
            .filter(|(k, _)| k.needs_simulation())
            .map(|(_, &j)| j)
            .collect::<Vec<_>>()
    });
    let mut points: Vec<Option<SweepPoint>> = vec![None; combos.len()];
    let mut cache = Vec::new();
    for i in order {
        let set = point_set(&keys, swept, &combos[i]);
        let values = texts(&set);
        let p = match profile_with(&lp.profile, &set) {
            Ok(p) => p,
            Err(reason) => {
                points[i] = Some(not_evaluated(values, reason, 0, 0));
                continue;
            }
        };
        let recordings_of: Vec<String> = set
            .iter()
            .filter(|(k, _)| k.needs_simulation())
            .map(|(_, v)| meta_text(v))
            .collect();
        let lp_v = LoadedProfile {
            profile: p,
            ..lp.clone()
        };
        let data = match made {
            Some((ref of, ref data)) if *of == recordings_of => data,
            _ => {
                // Recordings the analysis cannot use are this point's
                // result; they are listed, not fatal.
                let options = Options {
                    keep,
                    unusable: Unusable::Skip,
                    ..Options::default()
                };
                made = None;
                cache.clear();
                let data = simulated_dataset(
                    &lp_v,
                    sim,
                    &lp_v.profile.analysis,
                    options,
                    &|done, total| progress(i, done, total),
                )?;
                &made.insert((recordings_of, data)).1
            }
        };
        let incomplete = data
            .skipped
            .iter()
            .filter(|s| matches!(s, Skipped::Incomplete { .. }))
            .count();
        let mut unusable = data.skipped.iter().filter_map(|s| match s {
            Skipped::Unusable {
                reason, unreadable, ..
            } => Some((reason, *unreadable)),
            Skipped::Incomplete { .. } => None,
        });
        let result = match unusable.next() {
            // An unreadable file is not the value's doing: stop.
            Some((reason, true)) => return Err(bad(reason)),
            Some((reason, false)) => Err(bad(reason)),
            None if data.scans.is_empty() => Err(bad("no simulated scan finished")),
            None => validate_point(&lp_v.profile, data, &mut cache, plan, replan),
        };
        points[i] = Some(match result {
            Ok(r) => evaluated(values, &r, data),
            Err(e) if e.is_bad_input() => {
                not_evaluated(values, e.to_string(), data.counts().0, incomplete)
            }
            Err(e) => return Err(e),
        });
    }
    Ok(Sweep::new(
        keys.iter().map(SweepKey::name).collect(),
        plan.describe(),
        points.into_iter().flatten().collect(),
        Some(SimulatedInfo {
            per_class: sim.per_class,
            seed: lp.profile.simulator.seed,
        }),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn swept(key: &str, n: i64) -> Swept {
        Swept {
            key: key.into(),
            values: (1..=n).map(toml::Value::Integer).collect(),
        }
    }

    fn at(accuracy: Option<f64>) -> SweepPoint {
        let values = vec!["v".to_string()];
        match accuracy {
            Some(a) => SweepPoint {
                accuracy: a,
                ..not_evaluated(values, String::new(), 1, 0)
            }
            .tap_evaluated(),
            None => not_evaluated(values, "refused".into(), 1, 0),
        }
    }

    impl SweepPoint {
        fn tap_evaluated(mut self) -> SweepPoint {
            self.evaluated = true;
            self.reason = None;
            self.error = None;
            self
        }
    }

    fn best_of(accuracies: &[Option<f64>]) -> Vec<bool> {
        let mut points: Vec<SweepPoint> = accuracies.iter().map(|a| at(*a)).collect();
        mark_best(&mut points);
        points.iter().map(|p| p.best).collect()
    }

    #[test]
    fn combinations_come_row_by_row() {
        let c = combinations(&[swept("a", 2), swept("b", 3)]);
        assert_eq!(
            c,
            [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]].map(Vec::from)
        );
        assert_eq!(
            combinations(&[swept("a", 2), swept("b", 2), swept("c", 2)]).len(),
            8
        );
    }

    #[test]
    fn the_best_is_the_top_accuracy_unless_every_point_ties() {
        assert_eq!(
            best_of(&[Some(0.5), Some(0.9), Some(0.7)]),
            [false, true, false]
        );
        assert_eq!(
            best_of(&[Some(0.9), Some(0.5), Some(0.9)]),
            [true, false, true]
        );
        assert_eq!(best_of(&[Some(0.9), Some(0.9)]), [false, false]);
        assert_eq!(best_of(&[Some(0.9)]), [false]);
        assert_eq!(best_of(&[None, None]), [false, false]);
        // A point not evaluated ranks below every evaluated one.
        assert_eq!(best_of(&[Some(0.9), None]), [true, false]);
    }

    #[test]
    fn the_verdict_names_the_best_or_says_none() {
        let sweep = |acc: &[Option<f64>]| {
            let points = acc.iter().map(|a| at(*a)).collect();
            Sweep::new(vec!["k".into()], "3-fold".into(), points, None).table()
        };
        assert!(sweep(&[Some(0.5), Some(0.9)]).contains("best: k = v (90.0 %), 3-fold"));
        assert!(sweep(&[Some(0.9), Some(0.9)]).contains("no best: every value gives 90.0 %"));
        let none = sweep(&[None, None]);
        assert!(none.contains("no value could be evaluated"), "{none}");
        assert!(none.contains("not evaluated: refused"), "{none}");
    }

    #[test]
    fn a_key_swept_twice_or_too_many_points_is_refused() {
        let p = LoadedProfile::thesis().profile;
        assert!(resolve_all(&p, &[swept("k", 2), swept("classifier.k", 2)]).is_err());
        assert!(resolve_all(&p, &[swept("k", 200), swept("spacing", 200)]).is_err());
        assert!(resolve_all(&p, &[]).is_err());
        let k = resolve_all(&p, &[swept("k", 2), swept("taper", 2)]).unwrap();
        assert_eq!(k[1].name(), "analysis.taper");
    }

    #[test]
    fn a_grid_point_is_validated_with_all_its_keys_set() {
        let p = LoadedProfile::thesis().profile;
        let spectrum = resolve_key(&p, "spectrum").unwrap();
        let bins = resolve_key(&p, "bins").unwrap();
        let welch = toml::Value::String("welch".into());
        let few: toml::Value = toml::from_str::<toml::Table>("v = [1, 12]").unwrap()["v"].clone();
        // Alone, Welch is refused beside the thesis's 49 bins…
        let e = profile_with(&p, &[(&spectrum, &welch)]).unwrap_err();
        assert!(e.starts_with("analysis.bins"), "{e}");
        // …together with bins it allows, the point is valid.
        let q = profile_with(&p, &[(&spectrum, &welch), (&bins, &few)]).unwrap();
        assert_eq!(q.analysis.bins, [1, 12]);
    }
}
