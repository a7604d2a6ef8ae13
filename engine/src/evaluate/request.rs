//! The one evaluation: [`run`] takes a profile, where the recordings come
//! from and what the caller asks ([`Request`]: holdout, k-fold,
//! leave-one-out, grouped folds, sweeps and grids, simulated keys, and the
//! small-data fallback as a policy) and returns one [`Evaluation`]. The
//! command line's `evaluate` and the console's `e` both call it, so the same
//! folder gives the same method, k and numbers in both; front ends only
//! parse arguments and format the result.
//!
//! Never prints: long work is reported through [`Progress`], which the
//! front end implements (a progress bar, or nothing).

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;

use super::EvaluateError;
use super::plan::{
    Holdout, Overrides, Plan, Recordings, Related, Validated, holdout, validate_with_votes,
};
use super::sweep::{
    MakeScratch, Scratch, SimPlan, Sweep, Swept, combinations, resolve_all, simulated_dataset,
    sweep_grid, sweep_grid_simulated,
};
use crate::dataset::{Keep, Options, Skipped, Unusable, meta_text};
use crate::profile::{LoadedProfile, SplitMethod};

fn bad(m: impl std::fmt::Display) -> EvaluateError {
    EvaluateError::Input(m.to_string())
}

/// How long work is reported: one phase at a time ("reading",
/// "simulating"), its position, and a message naming what it is on.
/// Every method has a default that does nothing.
pub trait Progress: Sync {
    fn begin(&self, _what: &str, _total: usize) {}
    fn set(&self, _done: usize) {}
    fn message(&self, _text: &str) {}
    fn end(&self) {}
    /// The folder a simulated dataset is written to while it is read: by
    /// default a plain temporary folder; the command line's also handles
    /// Ctrl-C (cancellation is the front end's).
    fn scratch(&self) -> Result<Box<dyn Scratch + '_>, String> {
        super::sweep::temp_scratch()
    }
}

/// No progress shown.
pub struct Quiet;
impl Progress for Quiet {}

/// Where an evaluation's recordings come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Recordings or folders of recordings on disk.
    Recordings(Vec<PathBuf>),
    /// Datasets simulated from the profile in virtual time; `per_class`
    /// scans per texture (default: the holdout's train + test, else 30, or
    /// the folds when more).
    Simulated { per_class: Option<usize> },
}

/// What a caller asks of an evaluation over the profile's `[evaluation]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    pub source: Source,
    pub overrides: Overrides,
    /// Shuffle each class with this seed before a holdout split (and seed
    /// the folds with it when `overrides.seed` is unset).
    pub shuffle_seed: Option<u64>,
    /// `KEY=VALUES` specs: one is a sweep, more a grid.
    pub sweep: Vec<String>,
    /// When the profile's split cannot be met by the recordings, fall back
    /// to 5-fold cross-validation or leave-one-out ([`Plan::fall_back`])
    /// instead of refusing. Not with a sweep.
    pub fallback: bool,
}

impl Request {
    /// The profile's own evaluation of the recordings under `paths`.
    pub fn of_recordings(paths: Vec<PathBuf>) -> Request {
        Request {
            source: Source::Recordings(paths),
            overrides: Overrides::default(),
            shuffle_seed: None,
            sweep: Vec::new(),
            fallback: false,
        }
    }

    /// Whether anything beyond the thesis's holdout was asked for.
    fn asks_more(&self) -> bool {
        let o = &self.overrides;
        o.folds.is_some()
            || o.loo
            || o.group_by.is_some()
            || !self.sweep.is_empty()
            || matches!(self.source, Source::Simulated { .. })
    }
}

/// What was evaluated.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Outcome {
    /// The thesis's holdout split (Table 4.1); JSON: the [`super::Report`].
    Holdout(Holdout),
    /// Cross-validation (or a holdout reported as one fold of it).
    Validated(Validated),
    Sweep(Sweep),
}

/// How an evaluation's data was simulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Simulated {
    pub per_class: usize,
    /// The simulator's seed.
    pub seed: u64,
    /// One dataset per point of the sweep (a swept key changes the
    /// recordings), not one for all.
    pub per_point: bool,
}

/// An evaluation's result: the outcome, the plan as it ran (after any
/// fallback), why it fell back, and what it ran on.
#[derive(Debug, Clone)]
pub struct Evaluation {
    pub outcome: Outcome,
    pub plan: Plan,
    /// Why the plan is not the profile's (the fallback's reason).
    pub fell_back: Option<String>,
    /// Recordings evaluated (each once, however many sub-windows).
    pub recordings: usize,
    /// Sub-windows held as feature vectors, with `[analysis] windows`.
    pub windows: Option<usize>,
    /// With simulated data: how it was simulated.
    pub simulated: Option<Simulated>,
    /// Recordings left out (incomplete).
    pub skipped: Vec<Skipped>,
    /// Whether these are the recordings the profile was tuned on (its
    /// `tune` mark's fingerprint: [`crate::profile::tuned`]).
    pub tuned_on_these: bool,
}

/// Whether the recordings are those the profile's `tune` mark names.
fn tuned_on_these(lp: &LoadedProfile, data: &Recordings) -> bool {
    lp.tuned_on.as_ref().is_some_and(|t| {
        t.recordings == data.counts().0
            && t.fingerprint
                == crate::profile::tuned::fingerprint(
                    data.scans
                        .iter()
                        .map(|e| (e.label.as_str(), e.file.as_str())),
                )
    })
}

impl Outcome {
    /// The k the models used, each once, smallest first (one per fold at
    /// most; empty for a sweep, whose points name their own).
    pub fn k_used(&self) -> Vec<usize> {
        let mut k: Vec<usize> = match self {
            Outcome::Holdout(h) => vec![h.k],
            Outcome::Validated(v) => v.report.folds.iter().map(|f| f.k).collect(),
            Outcome::Sweep(_) => Vec::new(),
        };
        k.sort_unstable();
        k.dedup();
        k
    }

    /// Why k was not the profile's, when it was not.
    pub fn k_notice(&self) -> Option<String> {
        match self {
            Outcome::Holdout(h) => h.k_notice.clone(),
            Outcome::Validated(v) => v.report.k_notice(),
            Outcome::Sweep(_) => None,
        }
    }

    /// The pooled report (`None` for a sweep).
    pub fn report(&self) -> Option<&super::Report> {
        match self {
            Outcome::Holdout(h) => Some(&h.report),
            Outcome::Validated(v) => Some(&v.report.report),
            Outcome::Sweep(_) => None,
        }
    }

    /// The test recordings' sub-window votes, with `[analysis] windows`.
    pub fn voted(&self) -> bool {
        match self {
            Outcome::Holdout(h) => h.windows.is_some(),
            Outcome::Validated(v) => v.windows.is_some(),
            Outcome::Sweep(_) => false,
        }
    }
}

/// Evaluate as `req` asks under `lp`'s profile (see the module
/// documentation).
pub fn run(
    lp: &LoadedProfile,
    req: &Request,
    progress: &dyn Progress,
) -> Result<Evaluation, EvaluateError> {
    let mut overrides = req.overrides.clone();
    if overrides.seed.is_none() {
        overrides.seed = req.shuffle_seed;
    }
    let mut plan = Plan::new(&lp.profile, &overrides);
    if !req.asks_more() && plan.method == SplitMethod::Holdout {
        // The thesis's holdout: its shuffle only from the shuffle seed.
        plan.holdout_shuffle = req.shuffle_seed.or(lp.profile.evaluation.shuffle_seed);
        return thesis_holdout(lp, req, plan, progress);
    }
    let swept = req
        .sweep
        .iter()
        .map(|spec| Swept::parse(spec))
        .collect::<Result<Vec<_>, _>>()?;
    let keys = if swept.is_empty() {
        Vec::new()
    } else {
        resolve_all(&lp.profile, &swept)?
    };
    let per_class = match &req.source {
        Source::Simulated { per_class } => Some(*per_class),
        Source::Recordings(_) => None,
    };
    if let Some((spec, k)) = req
        .sweep
        .iter()
        .zip(&keys)
        .find(|(_, k)| k.needs_simulation())
        && per_class.is_none()
    {
        return Err(bad(format!(
            "--sweep {}: this key changes the recordings themselves, so it cannot be swept over \
             recordings on disk; simulate a dataset per value instead: \
             hapticlab evaluate --profile {} --simulate --folds 5 --sweep {spec}",
            k.name(),
            lp.origin
        )));
    }
    if req.fallback && !swept.is_empty() {
        return Err(bad(
            "--fallback chooses the validation for one evaluation; a sweep names its own (--folds N or --loo)",
        ));
    }
    let make_scratch = || progress.scratch();
    let sim = match per_class {
        Some(per_class) => Some(sim_plan(lp, per_class, &plan, &make_scratch)?),
        None => None,
    };
    if let Some(sim) = sim
        && keys.iter().any(|k| k.needs_simulation())
    {
        let s = simulated_sweep(lp, &swept, &keys, &plan, sim, progress)?;
        return Ok(Evaluation {
            outcome: Outcome::Sweep(s),
            plan,
            fell_back: None,
            recordings: sim.per_class * lp.profile.textures.len(),
            windows: None,
            simulated: Some(Simulated {
                per_class: sim.per_class,
                seed: lp.profile.simulator.seed,
                per_point: true,
            }),
            skipped: Vec::new(),
            tuned_on_these: false,
        });
    }
    // Samples are kept only when a sweep extracts features again per value;
    // otherwise memory holds one feature vector per recording.
    let keep = if keys.iter().any(|k| k.table == "analysis") {
        Keep::Samples
    } else {
        Keep::Features
    };
    let options = Options {
        keep,
        unusable: Unusable::Fail,
        threads: plan.threads,
    };
    let data = load(lp, &req.source, sim, options, progress)?;
    let (recordings, held) = data.counts();
    let windows = (lp.profile.analysis.windows.is_some() && keep == Keep::Features).then_some(held);
    let simulated = sim.map(|s| Simulated {
        per_class: s.per_class,
        seed: lp.profile.simulator.seed,
        per_point: false,
    });
    if !swept.is_empty() {
        let s = sweep_grid(&lp.profile, &data, &swept, &plan, &|_| {})?;
        return Ok(Evaluation {
            outcome: Outcome::Sweep(s),
            plan,
            fell_back: None,
            recordings,
            windows,
            simulated,
            tuned_on_these: tuned_on_these(lp, &data),
            skipped: data.skipped,
        });
    }
    let examples = data.examples(&lp.profile.analysis)?;
    let fell_back = if req.fallback {
        plan.fall_back(&lp.profile, &examples)
    } else {
        None
    };
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let segments = data.segments();
    let related = Related::new(groups.as_deref(), &segments);
    let validated = validate_with_votes(&lp.profile, examples, related, &plan)
        .map_err(|e| not_enough(e, req))?;
    Ok(Evaluation {
        outcome: Outcome::Validated(validated),
        plan,
        fell_back,
        recordings,
        windows,
        simulated,
        tuned_on_these: tuned_on_these(lp, &data),
        skipped: data.skipped,
    })
}

/// A split the recordings cannot meet, with what to do about it.
fn not_enough(e: EvaluateError, req: &Request) -> EvaluateError {
    match e {
        EvaluateError::NotEnough { .. } if !req.fallback => bad(format!(
            "{e}; cross-validate instead (--folds 5 or --loo), or let evaluate choose (--fallback)"
        )),
        e => e,
    }
}

/// The thesis's holdout (Table 4.1), unless the recordings cannot meet it
/// and the caller asked for the fallback.
fn thesis_holdout(
    lp: &LoadedProfile,
    req: &Request,
    mut plan: Plan,
    progress: &dyn Progress,
) -> Result<Evaluation, EvaluateError> {
    let options = Options {
        keep: Keep::Features,
        unusable: Unusable::Fail,
        threads: plan.threads,
    };
    let data = load(lp, &req.source, None, options, progress)?;
    let (recordings, held) = data.counts();
    let examples = data.examples(&lp.profile.analysis)?;
    if examples.is_empty() {
        return Err(bad(format!(
            "none of the {} recording(s) found can be used (each is named above)",
            data.skipped.len()
        )));
    }
    // One texture cannot be told from another: 100 % would mean nothing.
    super::check_two_labels(&examples)?;
    let windows = lp.profile.analysis.windows.is_some().then_some(held);
    let fell_back = if req.fallback {
        plan.fall_back(&lp.profile, &examples)
    } else {
        None
    };
    let segments = data.segments();
    let related = Related::new(None, &segments);
    let outcome = if fell_back.is_some() {
        Outcome::Validated(validate_with_votes(&lp.profile, examples, related, &plan)?)
    } else {
        Outcome::Holdout(
            holdout(&lp.profile, examples, related, &plan).map_err(|e| not_enough(e, req))?,
        )
    };
    Ok(Evaluation {
        outcome,
        plan,
        fell_back,
        recordings,
        windows,
        simulated: None,
        tuned_on_these: tuned_on_these(lp, &data),
        skipped: data.skipped,
    })
}

/// How many scans per texture to simulate, checked against the plan.
fn sim_plan<'a>(
    lp: &LoadedProfile,
    per_class: Option<usize>,
    plan: &Plan,
    scratch: &'a MakeScratch<'a>,
) -> Result<SimPlan<'a>, EvaluateError> {
    lp.rig()
        .map_err(|e| bad(format!("evaluate --simulate: {e}")))?;
    let e = &lp.profile.evaluation;
    // The holdout's own counts; cross-validation names none, so as many
    // scans as `simulate` makes by default (more when the folds need it).
    let held_out = e.holdout_needs();
    let sim = SimPlan {
        per_class: per_class.unwrap_or(if held_out > 0 {
            held_out
        } else {
            crate::acquire::DEFAULT_PER_CLASS.max(plan.folds)
        }),
        threads: plan.threads,
        scratch,
    };
    if sim.per_class == 0 {
        return Err(bad("--per-class must be at least 1"));
    }
    if plan.method == SplitMethod::Holdout && sim.per_class < held_out {
        return Err(bad(format!(
            "--per-class {}: the profile's holdout split needs {held_out} scans per texture ({}); \
             simulate at least that many, or cross-validate (--folds N)",
            sim.per_class,
            e.holdout_parts()
        )));
    }
    Ok(sim)
}

/// The recordings, read from disk or simulated, as `options` say.
fn load(
    lp: &LoadedProfile,
    source: &Source,
    sim: Option<SimPlan<'_>>,
    options: Options,
    progress: &dyn Progress,
) -> Result<Recordings, EvaluateError> {
    let an = &lp.profile.analysis;
    let data = match (source, sim) {
        (Source::Simulated { .. }, Some(sim)) => {
            progress.begin("simulating", sim.per_class * lp.profile.textures.len());
            simulated_dataset(lp, sim, an, options, &|done, _| progress.set(done))
        }
        (Source::Recordings(paths), _) => {
            if paths.is_empty() {
                return Err(bad(
                    "no recordings: give a PATH, or --simulate to evaluate a simulated dataset",
                ));
            }
            // Finding no recordings is the user's to fix, as in every command.
            let files = crate::dataset::find(paths).map_err(bad)?;
            progress.begin("reading", files.len());
            let done = AtomicUsize::new(0);
            Recordings::load_files(&files, an, options, &|| {
                progress.set(done.fetch_add(1, Ordering::Relaxed) + 1);
            })
        }
        (Source::Simulated { .. }, None) => unreachable!("a simulated source has a plan"),
    };
    progress.end();
    data
}

/// A sweep of keys that change the recordings: one simulated dataset per
/// combination of their values.
fn simulated_sweep(
    lp: &LoadedProfile,
    swept: &[Swept],
    keys: &[super::sweep::SweepKey],
    plan: &Plan,
    sim: SimPlan<'_>,
    progress: &dyn Progress,
) -> Result<Sweep, EvaluateError> {
    let combos = combinations(swept);
    let points = combos.len();
    // `path.speed_m_per_s = 0.4, k = 1 (3/4)`.
    let naming = |i: usize| {
        let set: Vec<String> = keys
            .iter()
            .zip(swept)
            .zip(&combos[i])
            .map(|((k, w), &j)| format!("{} = {}", k.name(), meta_text(&w.values[j])))
            .collect();
        format!("{} ({}/{points})", set.join(", "), i + 1)
    };
    let per_value = sim.per_class * lp.profile.textures.len();
    // One dataset per combination of the recording keys' values.
    let datasets: usize = keys
        .iter()
        .zip(swept)
        .filter(|(k, _)| k.needs_simulation())
        .map(|(_, w)| w.values.len())
        .product();
    progress.begin("simulating", per_value * datasets);
    // The point whose dataset is being simulated (+1), and how many
    // datasets were started.
    let (current, started) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let s = sweep_grid_simulated(lp, swept, plan, sim, &|i, done, _| {
        if current.swap(i + 1, Ordering::Relaxed) != i + 1 {
            started.fetch_add(1, Ordering::Relaxed);
            progress.message(&naming(i));
        }
        let before = started.load(Ordering::Relaxed).saturating_sub(1);
        progress.set(before * per_value + done);
    });
    progress.end();
    s
}

#[cfg(test)]
mod tests;
