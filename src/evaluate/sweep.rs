//! `evaluate` with honest validation (k-fold, leave-one-out, grouped folds)
//! and parameter sweeps (`--sweep KEY=VALUES`): the thesis's section 4.3
//! parameter selection as one command.
//!
//! The recordings are read once ([`crate::dataset::load`], on every core)
//! into a [`Dataset`] holding each one's feature vector and metadata, or,
//! for a sweep over an `[analysis]` key, the columns the analysis reads, so
//! features are extracted again per value without re-reading files. A
//! sweep sets a key of the profile's `[analysis]`, `[classifier]` or
//! `[evaluation]` table through
//! TOML, so every key those tables accept can be swept and is validated as
//! in a profile file. Keys that change the recordings themselves (the
//! path's speed, the controller's stiffness, any `[controller]`, `[path]`,
//! `[simulator]` or `[device]` key) need a new dataset per value: with
//! `--simulate`, each value simulates one in virtual time (in a temporary
//! folder, same seed for every value) and evaluates it; over recordings on
//! disk they are refused.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use crate::analysis::FeatureExtractor;
use crate::classify::TrainingExample;
use crate::cli::ProfileArg;
use crate::commands::{Failure, load_profile};
use crate::dataset::{self, Entry, Keep, Options, Skipped, Unusable};
use crate::evaluate::cv::{self, CvReport};
use crate::evaluate::{self as ev};
use crate::profile::{Analysis, Profile, SplitMethod};

/// The options `evaluate` gains for cross-validation and sweeps.
#[derive(Debug, Args, Clone, Default)]
pub struct ValidationArgs {
    /// k-fold cross-validation with N folds, stratified by class (or grouped with --group-by).
    #[arg(long, value_name = "N", conflicts_with = "loo")]
    pub folds: Option<usize>,
    /// Leave-one-out (leave-one-group-out with --group-by).
    #[arg(long)]
    pub loo: bool,
    /// Keep recordings with the same value of this metadata key (session, trial, …) on one side of every split.
    #[arg(long, value_name = "KEY")]
    pub group_by: Option<String>,
    /// Seed of the folds' shuffle (default: the profile's evaluation.shuffle_seed, else 0).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Evaluate once per value of a profile key: `k=1..15`, `k=1..15:2`, `metric=euclidean,cosine`, `spacing=0.0002,0.0003`, `spectrum=magnitude,welch`; with --simulate also `controller.stiffness_n_per_m[1]=90..540:90`, `path.speed_m_per_s=0.005..0.03:0.005`.
    #[arg(long, value_name = "KEY=VALUES")]
    pub sweep: Option<String>,
    /// Worker threads for the folds and the reading (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Evaluate a dataset simulated from the profile in virtual time (no PATH; a temporary folder, removed after); with --sweep of a [controller], [path], [simulator] or [device] key, one dataset per value.
    #[arg(long)]
    pub simulate: bool,
    /// With --simulate: scans per texture (default: the profile's train_per_class + test_per_class).
    #[arg(long, value_name = "N")]
    pub per_class: Option<usize>,
}

impl ValidationArgs {
    /// Whether anything beyond the thesis's holdout was asked for.
    pub fn is_active(&self) -> bool {
        self.folds.is_some()
            || self.loo
            || self.group_by.is_some()
            || self.sweep.is_some()
            || self.simulate
            || self.per_class.is_some()
    }
}

fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

/// The recordings of one evaluation, loaded once ([`dataset::load`]): their
/// feature vectors under the profile's analysis ([`Keep::Features`]), or,
/// for a sweep over an `[analysis]` key, the columns the analysis reads
/// ([`Keep::Samples`]) so features are extracted again per value.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub scans: Vec<Entry>,
    /// Recordings left out (incomplete), in file-name order.
    pub skipped: Vec<Skipped>,
    /// The analysis the features were made under ([`Keep::Features`]).
    analysis: Analysis,
    keep: Keep,
}

pub use crate::dataset::meta_text;

impl Dataset {
    /// Read every recording under `paths` on `threads` threads, keeping
    /// what `keep` says. Incomplete recordings are listed, not kept; a
    /// malformed one is an error.
    pub fn load(
        paths: &[PathBuf],
        analysis: &Analysis,
        keep: Keep,
        threads: usize,
    ) -> Result<Dataset, Failure> {
        let options = Options {
            keep,
            unusable: Unusable::Fail,
            threads,
        };
        Dataset::load_files(
            &crate::commands::find_recordings(paths)?,
            analysis,
            options,
            &|| {},
        )
    }

    /// The recordings in `files`, loaded as `options` say; `progress`
    /// hears each file.
    pub fn load_files(
        files: &[PathBuf],
        analysis: &Analysis,
        options: Options,
        progress: &(dyn Fn() + Sync),
    ) -> Result<Dataset, Failure> {
        let loaded = dataset::load(files, analysis, options, progress)?;
        Ok(Dataset {
            scans: loaded.entries,
            skipped: loaded.skipped,
            analysis: analysis.clone(),
            keep: options.keep,
        })
    }

    /// The feature vectors under `analysis`: the kept ones when it is the
    /// analysis they were made under, else extracted again from the kept
    /// columns (whose channels must be `analysis`'s).
    pub fn examples(&self, analysis: &Analysis) -> Result<Vec<TrainingExample>, Failure> {
        if self.keep == Keep::Features {
            if *analysis != self.analysis {
                return Err(Failure::Runtime(
                    "the recordings were loaded for other analysis settings (features only)".into(),
                ));
            }
            return Ok(self.scans.iter().map(Entry::example).collect());
        }
        let mut fx = FeatureExtractor::try_new(analysis).map_err(bad)?;
        self.scans
            .iter()
            .map(|s| {
                Ok(TrainingExample {
                    file: s.file.clone(),
                    label: s.label.clone(),
                    features: s.features_with(&mut fx)?,
                })
            })
            .collect()
    }

    /// Each scan's value of a metadata key; a scan without it is an error.
    pub fn groups(&self, key: &str) -> Result<Vec<String>, Failure> {
        self.scans
            .iter()
            .map(|s| {
                s.meta_text(key).ok_or_else(|| {
                    bad(format!(
                        "{}: no metadata key `{key}` to group by (--group-by)",
                        s.file
                    ))
                })
            })
            .collect()
    }
}

/// The validation the arguments and the profile ask for.
#[derive(Debug, Clone)]
pub struct Plan {
    pub method: SplitMethod,
    pub folds: usize,
    pub group_by: Option<String>,
    pub seed: u64,
    /// For a holdout: shuffle each class with this seed, else take the
    /// recordings in file-name order (as plain `evaluate` does).
    pub holdout_shuffle: Option<u64>,
    pub threads: usize,
}

impl Plan {
    pub fn new(p: &Profile, args: &ValidationArgs) -> Plan {
        let e = &p.evaluation;
        let method = if args.loo {
            SplitMethod::LeaveOneOut
        } else if args.folds.is_some()
            || (args.group_by.is_some() && e.method == SplitMethod::Holdout)
        {
            SplitMethod::KFold
        } else {
            e.method
        };
        Plan {
            method,
            folds: args.folds.or(e.folds).unwrap_or(10),
            group_by: args.group_by.clone().or_else(|| e.group_by.clone()),
            seed: args.seed.or(e.shuffle_seed).unwrap_or(0),
            holdout_shuffle: args.seed.or(e.shuffle_seed),
            threads: args
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        }
    }

    pub fn describe(&self) -> String {
        let g = self
            .group_by
            .as_ref()
            .map_or(String::new(), |g| format!(", grouped by {g}"));
        match self.method {
            SplitMethod::Holdout => match self.holdout_shuffle {
                Some(s) => format!("holdout split (shuffled, seed {s})"),
                None => "holdout split (file-name order)".into(),
            },
            SplitMethod::KFold => format!(
                "{}-fold cross-validation{g}, seed {}",
                self.folds, self.seed
            ),
            SplitMethod::LeaveOneOut if self.group_by.is_some() => {
                format!("leave-one-group-out{g}")
            }
            SplitMethod::LeaveOneOut => "leave-one-out".into(),
        }
    }
}

/// Validate `profile`'s classifier on `examples` as `plan` says.
pub fn validate(
    profile: &Profile,
    examples: Vec<TrainingExample>,
    groups: Option<&[String]>,
    plan: &Plan,
) -> Result<CvReport, Failure> {
    if plan.method == SplitMethod::Holdout {
        let mut eval = profile.evaluation.clone();
        eval.shuffle_seed = plan.holdout_shuffle;
        let split = ev::split(examples, &eval).map_err(bad)?;
        let mut all = split.train.clone();
        all.extend(split.test.iter().cloned());
        let n_train = split.train.len();
        let folds = vec![(n_train..all.len()).collect()];
        return cv::cross_validate(
            &all,
            &folds,
            &profile.name,
            &profile.analysis,
            &profile.classifier,
            "holdout",
            plan.seed,
            1,
        )
        .map_err(bad);
    }
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    let folds = cv::make_folds(&labels, groups, plan.method, plan.folds, plan.seed).map_err(bad)?;
    cv::cross_validate(
        &examples,
        &folds,
        &profile.name,
        &profile.analysis,
        &profile.classifier,
        &plan.describe(),
        plan.seed,
        plan.threads,
    )
    .map_err(bad)
}

/// `KEY=VALUES` into the key and its values as TOML literals: `1..15`,
/// `1..15:2`, `0.005..0.02:0.005` (a range, ends included), or a comma
/// list (`euclidean,cosine`, `[0,1],[1,2]`).
pub fn parse_sweep(spec: &str) -> Result<(String, Vec<toml::Value>), Failure> {
    let (key, values) = spec.split_once('=').ok_or_else(|| {
        bad(format!(
            "--sweep {spec:?}: expected KEY=VALUES, e.g. k=1..15"
        ))
    })?;
    let key = key.trim().to_string();
    if key.is_empty() {
        return Err(bad(format!("--sweep {spec:?}: no key before `=`")));
    }
    let values = values.trim();
    let mut out = Vec::new();
    if let Some((a, b)) = values.split_once("..") {
        out = parse_range(&key, values, a, b)?;
    } else {
        for item in split_top_level(values)
            .iter()
            .map(|s| s.trim())
            .filter(|s| !s.is_empty())
        {
            let v = toml::from_str::<toml::Table>(&format!("v = {item}"))
                .ok()
                .and_then(|mut t| t.remove("v"))
                .unwrap_or_else(|| toml::Value::String(item.to_string()));
            out.push(v);
        }
    }
    if out.is_empty() {
        return Err(bad(format!("--sweep {key}: no values")));
    }
    Ok((key, out))
}

/// `a..b` or `a..b:step`: whole numbers when all three are, else decimals
/// rounded to the most decimals written (so 0.1 steps stay 0.1, 0.2, …).
fn parse_range(key: &str, values: &str, a: &str, b: &str) -> Result<Vec<toml::Value>, Failure> {
    let (b, step) = match b.split_once(':') {
        Some((b, s)) => (b, s),
        None => (b, "1"),
    };
    let (a, b, step) = (a.trim(), b.trim(), step.trim());
    let not_range = || {
        bad(format!(
            "--sweep {key}: {values:?} is not a range like 1..15, 1..15:2 or 0.005..0.02:0.005"
        ))
    };
    let too_long = || {
        bad(format!(
            "--sweep {key}: {values:?} is an empty or too long range (at most 10,000 values)"
        ))
    };
    if let (Ok(a), Ok(b), Ok(step)) = (a.parse::<i64>(), b.parse::<i64>(), step.parse::<i64>()) {
        if step <= 0 || b < a || (b - a) / step > 10_000 {
            return Err(too_long());
        }
        return Ok((0..=(b - a) / step)
            .map(|i| toml::Value::Integer(a + i * step))
            .collect());
    }
    let decimals = [a, b, step]
        .iter()
        .map(|s| s.split_once('.').map_or(0, |(_, d)| d.len()))
        .max()
        .unwrap_or(0)
        .min(15) as i32;
    let num = |s: &str| {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(not_range)
    };
    let (a, b, step) = (num(a)?, num(b)?, num(step)?);
    if step <= 0.0 || b < a || (b - a) / step > 10_000.0 {
        return Err(too_long());
    }
    let scale = 10f64.powi(decimals);
    let n = ((b - a) / step + 1e-9).floor() as usize;
    Ok((0..=n)
        .map(|i| toml::Value::Float(((a + i as f64 * step) * scale).round() / scale))
        .collect())
}

/// Split at the commas outside brackets: `[0,1],[1,2]` is two values.
fn split_top_level(s: &str) -> Vec<&str> {
    let (mut depth, mut start, mut out) = (0i32, 0, Vec::new());
    for (i, c) in s.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&s[start..]);
    out
}

/// The tables a sweep sets without new recordings: their keys change how
/// the recordings are analysed, classified or split.
pub const ANALYSIS_TABLES: [&str; 3] = ["analysis", "classifier", "evaluation"];
/// The tables whose keys change the recordings themselves: sweeping them
/// needs a new simulated dataset per value (`evaluate --simulate`).
pub const SIMULATION_TABLES: [&str; 4] = ["controller", "path", "simulator", "device"];

/// A swept key, resolved against the profile: its table, its field, and
/// for a 3-vector (`stiffness_n_per_m`, …) optionally one component.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepKey {
    pub table: String,
    pub field: String,
    /// 0, 1, 2 for x, y, z: written `stiffness_n_per_m[1]` or `stiffness_n_per_m.y`.
    pub component: Option<usize>,
}

impl SweepKey {
    /// Whether each value needs its own recordings (a simulated dataset).
    pub fn needs_simulation(&self) -> bool {
        SIMULATION_TABLES.contains(&self.table.as_str())
    }
    /// `table.field` or `table.field[i]`, as reports name it.
    pub fn name(&self) -> String {
        match self.component {
            Some(i) => format!("{}.{}[{i}]", self.table, self.field),
            None => format!("{}.{}", self.table, self.field),
        }
    }
}

/// Find `key` in the profile: `table.field` (`analysis.spacing`,
/// `path.speed_m_per_s`), or a bare field looked up in `[analysis]`,
/// `[classifier]`, `[evaluation]`, then `[controller]`, `[path]`,
/// `[simulator]`, `[device]`; a 3-vector's component as `field[1]` or
/// `field.y`.
pub fn resolve_key(profile: &Profile, key: &str) -> Result<SweepKey, Failure> {
    let doc = toml::Table::try_from(profile).map_err(bad)?;
    let unknown = || {
        bad(format!(
            "--sweep {key}: not a key of [analysis], [classifier] or [evaluation] (evaluated on the \
             recordings) nor of [controller], [path], [simulator] or [device] (with --simulate); \
             e.g. k, spacing, taper, controller.stiffness_n_per_m[1], path.speed_m_per_s"
        ))
    };
    let mut rest = key.trim();
    let mut component = None;
    if let Some(open) = rest.strip_suffix(']').and_then(|r| r.rfind('[')) {
        let idx = &rest[open + 1..rest.len() - 1];
        component = Some(idx.trim().parse::<usize>().map_err(|_| {
            bad(format!(
                "--sweep {key}: `[{idx}]` is not a component index (0, 1 or 2)"
            ))
        })?);
        rest = &rest[..open];
    }
    let (table, field) = match rest.split_once('.') {
        Some((t, f)) if ANALYSIS_TABLES.contains(&t) || SIMULATION_TABLES.contains(&t) => {
            (Some(t), f)
        }
        _ => (None, rest),
    };
    let field = match field.rsplit_once('.') {
        Some((f, axis @ ("x" | "y" | "z"))) if component.is_none() => {
            component = Some(["x", "y", "z"].iter().position(|a| *a == axis).unwrap_or(0));
            f
        }
        Some(_) => return Err(unknown()),
        None => field,
    };
    let has = |t: &str| {
        doc.get(t)
            .and_then(|v| v.as_table())
            .is_some_and(|tab| tab.contains_key(field) || known_field(t, field))
    };
    let table = match table {
        Some(t) if has(t) => t,
        Some(_) => return Err(unknown()),
        None => ANALYSIS_TABLES
            .iter()
            .chain(SIMULATION_TABLES.iter())
            .find(|t| has(t))
            .copied()
            .ok_or_else(unknown)?,
    };
    if let Some(i) = component {
        let len = doc
            .get(table)
            .and_then(|t| t.get(field))
            .and_then(|v| v.as_array())
            .map(Vec::len);
        if len != Some(3) || i > 2 {
            return Err(bad(format!(
                "--sweep {key}: only a 3-vector such as controller.stiffness_n_per_m has components, [0] to [2] (x, y, z)"
            )));
        }
    }
    Ok(SweepKey {
        table: table.to_string(),
        field: field.to_string(),
        component,
    })
}

/// The profile with `key` set to `value` (see [`resolve_key`]), validated
/// as a profile file would be. A whole number where the profile holds a
/// decimal is taken as that decimal.
pub fn with_key(profile: &Profile, key: &str, value: &toml::Value) -> Result<Profile, Failure> {
    let k = resolve_key(profile, key)?;
    with_resolved(profile, &k, value)
}

/// [`with_key`] for a key already resolved.
pub fn with_resolved(
    profile: &Profile,
    k: &SweepKey,
    value: &toml::Value,
) -> Result<Profile, Failure> {
    let name = k.name();
    let mut doc = toml::Table::try_from(profile).map_err(bad)?;
    let as_like = |old: Option<&toml::Value>, v: &toml::Value| match (old, v) {
        (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => toml::Value::Float(*i as f64),
        _ => v.clone(),
    };
    if let Some(tab) = doc.get_mut(&k.table).and_then(|v| v.as_table_mut()) {
        match k.component {
            Some(i) => {
                if let Some(arr) = tab.get_mut(&k.field).and_then(|v| v.as_array_mut()) {
                    let v = as_like(arr.get(i), value);
                    if let Some(slot) = arr.get_mut(i) {
                        *slot = v;
                    }
                }
            }
            None => {
                let v = as_like(tab.get(&k.field), value);
                tab.insert(k.field.clone(), v);
            }
        }
    }
    let mut p: Profile = toml::Value::Table(doc)
        .try_into()
        .map_err(|e: toml::de::Error| {
            bad(format!("--sweep {name} = {value}: {}", e.message().trim()))
        })?;
    // A window over the whole scan leg follows the swept path (unless the
    // window itself is swept).
    if !(k.table == "analysis" && k.field == "window") {
        p.analysis.window_is_scan_leg = profile.analysis.window_is_scan_leg;
    }
    p.resolve_window();
    p.validate()
        .map_err(|v| bad(format!("--sweep {name} = {value}: {}: {}", v.key, v.reason)))?;
    Ok(p)
}

/// Optional keys a table may lack (because they are at their default).
fn known_field(table: &str, field: &str) -> bool {
    match table {
        "analysis" => [
            "channels",
            "taper",
            "band",
            "welch_segment",
            "welch_overlap",
            "detrend",
            "spectrum",
            "bins",
        ]
        .contains(&field),
        "classifier" => ["metric", "weights", "standardize", "k_candidates"].contains(&field),
        "evaluation" => ["shuffle_seed", "method", "folds", "group_by"].contains(&field),
        "path" => ["transit_speed_m_per_s"].contains(&field),
        _ => false,
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct SweepPoint {
    pub value: String,
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
    /// Simulated sweeps: why this value's dataset could not be evaluated
    /// (e.g. a path so fast the window has gaps); its numbers are NaN
    /// (`null` in JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    pub key: String,
    pub method: String,
    pub points: Vec<SweepPoint>,
    /// Set when every value was evaluated on its own simulated dataset.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated: Option<SimulatedInfo>,
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

/// How `evaluate --simulate` makes its datasets.
#[derive(Debug, Clone, Copy)]
pub struct SimPlan {
    pub per_class: usize,
    pub threads: usize,
}

/// A dataset simulated from `lp` in virtual time (`per_class` scans of
/// every texture, seeded with the profile's `simulator.seed`), written to a
/// temporary folder that is removed before this returns, and loaded for
/// `analysis` as `options` say (its `threads` are `sim.threads`). File
/// names are relative (`S2/S2_001.csv`), in the reasons for skipping too.
/// `progress` hears (done, total) scans.
pub fn simulated_dataset(
    lp: &crate::profile::LoadedProfile,
    sim: SimPlan,
    analysis: &Analysis,
    options: Options,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Dataset, Failure> {
    // Removed on drop, and on Ctrl-C (which would otherwise skip the drop).
    let dir = crate::scratch::ScratchFolder::new("hapticlab-simulate-").map_err(|e| {
        Failure::Runtime(format!(
            "cannot make a temporary folder for the simulated scans: {e}"
        ))
    })?;
    let opts = crate::acquire::SimulateOptions {
        out: dir.path().to_path_buf(),
        per_class: sim.per_class,
        seed: lp.profile.simulator.seed,
        threads: sim.threads.max(1),
        gzip: false,
        overwrite: false,
    };
    crate::acquire::simulate_dataset(lp, &opts, &dir.watch(opts.threads, progress))?;
    dir.exit_if_interrupted();
    let files = dataset::find(&[dir.path().to_path_buf()])?;
    let options = Options {
        threads: sim.threads,
        ..options
    };
    let mut data = Dataset::load_files(&files, analysis, options, &|| {})?;
    dir.exit_if_interrupted();
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

fn point(value: &toml::Value, r: &CvReport, data: &Dataset) -> SweepPoint {
    SweepPoint {
        value: crate::study::meta_text(value),
        accuracy: r.accuracy,
        accuracy_mean: r.accuracy_mean,
        accuracy_std: r.accuracy_std,
        macro_f1: r.macro_f1,
        k: r.folds.iter().map(|f| f.k).collect(),
        k_notice: r.k_notice(),
        recordings: data.scans.len(),
        incomplete: data.skipped.len(),
        error: None,
    }
}

/// Evaluate once per value; features are re-extracted only when the
/// analysis changes. Every value is checked before the first is evaluated.
pub fn sweep(
    profile: &Profile,
    data: &Dataset,
    key: &str,
    values: &[toml::Value],
    plan: &Plan,
    progress: &dyn Fn(usize),
) -> Result<Sweep, Failure> {
    let k = resolve_key(profile, key)?;
    if k.needs_simulation() {
        return Err(bad(format!(
            "--sweep {key}: this key changes the recordings themselves; sweep it on simulated datasets (--simulate)"
        )));
    }
    let profiles = values
        .iter()
        .map(|v| with_resolved(profile, &k, v))
        .collect::<Result<Vec<_>, _>>()?;
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let mut points = Vec::new();
    let mut cached: Option<(Analysis, Vec<TrainingExample>)> = None;
    for (i, (v, p)) in values.iter().zip(&profiles).enumerate() {
        if p.analysis
            .all_channels()
            .ne(profile.analysis.all_channels())
            || p.analysis.axis != profile.analysis.axis
        {
            return Err(bad(format!(
                "--sweep {key}: sweeping the axis or the channels is not supported; evaluate once per channel"
            )));
        }
        let examples = match &cached {
            Some((a, e)) if *a == p.analysis => e.clone(),
            _ => {
                let e = data.examples(&p.analysis)?;
                cached = Some((p.analysis.clone(), e.clone()));
                e
            }
        };
        let r = validate(p, examples, groups.as_deref(), plan)?;
        points.push(point(v, &r, data));
        progress(i + 1);
    }
    Ok(Sweep {
        // As typed (`k`), like the sweeps before simulated ones.
        key: key.to_string(),
        method: plan.describe(),
        points,
        simulated: None,
    })
}

/// Evaluate once per value of a key that changes the recordings (the path's
/// speed, the controller's stiffness, a simulator setting): each value
/// simulates its own dataset ([`simulated_dataset`], same seed for every
/// value), then validates as `plan` says. Every value is checked before
/// the first is simulated. `progress` hears (value index, scans done in
/// this value, scans per value).
pub fn sweep_simulated(
    lp: &crate::profile::LoadedProfile,
    key: &str,
    values: &[toml::Value],
    plan: &Plan,
    sim: SimPlan,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Sweep, Failure> {
    let k = resolve_key(&lp.profile, key)?;
    let profiles = values
        .iter()
        .map(|v| with_resolved(&lp.profile, &k, v))
        .collect::<Result<Vec<_>, _>>()?;
    let mut points = Vec::new();
    for (i, (v, p)) in values.iter().zip(profiles).enumerate() {
        let lp_v = crate::profile::LoadedProfile {
            profile: p,
            ..lp.clone()
        };
        // Recordings the analysis cannot use (a path so fast the window
        // has gaps) are this value's result: say so and go on. Anything
        // else (an unreadable file, k larger than the training part, …)
        // stops the sweep.
        let options = Options {
            unusable: Unusable::Skip,
            ..Options::default()
        };
        let data = simulated_dataset(
            &lp_v,
            sim,
            &lp_v.profile.analysis,
            options,
            &|done, total| progress(i, done, total),
        )?;
        let mut unusable = data.skipped.iter().filter_map(|s| match s {
            Skipped::Unusable {
                reason, unreadable, ..
            } => Some((reason, *unreadable)),
            Skipped::Incomplete { .. } => None,
        });
        let examples = match unusable.next() {
            Some((reason, true)) => return Err(bad(reason)),
            Some((reason, false)) => Err(bad(reason)),
            None if data.scans.is_empty() => Err(bad("no simulated scan finished")),
            None => data.examples(&lp_v.profile.analysis),
        };
        let examples = match examples {
            Ok(e) => e,
            Err(f) => {
                points.push(SweepPoint {
                    value: meta_text(v),
                    accuracy: f64::NAN,
                    accuracy_mean: f64::NAN,
                    accuracy_std: f64::NAN,
                    macro_f1: f64::NAN,
                    k: Vec::new(),
                    k_notice: None,
                    recordings: data.scans.len(),
                    incomplete: data
                        .skipped
                        .iter()
                        .filter(|s| matches!(s, Skipped::Incomplete { .. }))
                        .count(),
                    error: Some(f.message().to_string()),
                });
                continue;
            }
        };
        let groups = match &plan.group_by {
            Some(g) => Some(data.groups(g)?),
            None => None,
        };
        let r = validate(&lp_v.profile, examples, groups.as_deref(), plan)
            .map_err(|f| bad(format!("--sweep {} = {v}: {}", k.name(), f.message())))?;
        points.push(point(v, &r, &data));
    }
    Ok(Sweep {
        key: k.name(),
        method: plan.describe(),
        points,
        simulated: Some(SimulatedInfo {
            per_class: sim.per_class,
            seed: lp.profile.simulator.seed,
        }),
    })
}

impl Sweep {
    pub fn table(&self) -> String {
        let w = self
            .points
            .iter()
            .map(|p| p.value.len())
            .chain([self.key.len()])
            .max()
            .unwrap_or(1);
        let mut out = format!("{:<w$}  accuracy  per-fold mean ± sd  macro-F1\n", self.key);
        for p in &self.points {
            if let Some(e) = &p.error {
                out.push_str(&format!("{:<w$}  not evaluated: {e}\n", p.value));
                continue;
            }
            out.push_str(&format!(
                "{:<w$}  {:>7.1}%  {:>8.1} ± {:<5.1} %  {:>8.3}",
                p.value,
                100.0 * p.accuracy,
                100.0 * p.accuracy_mean,
                100.0 * p.accuracy_std,
                p.macro_f1
            ));
            if p.incomplete > 0 {
                out.push_str(&format!(
                    "  ({} of {} scans did not finish)",
                    p.incomplete,
                    p.incomplete + p.recordings
                ));
            }
            out.push('\n');
            if let Some(n) = &p.k_notice {
                out.push_str(&format!("{:<w$}  ({n})\n", ""));
            }
        }
        if let Some(best) = self
            .points
            .iter()
            .filter(|p| p.error.is_none())
            .max_by(|a, b| {
                a.accuracy
                    .total_cmp(&b.accuracy)
                    .then(std::cmp::Ordering::Greater)
            })
        {
            out.push_str(&format!(
                "best: {} = {} ({:.1} %), {}\n",
                self.key,
                best.value,
                100.0 * best.accuracy,
                self.method
            ));
        }
        out
    }
}

/// `hapticlab evaluate` with cross-validation, a sweep, or simulated data.
pub fn run_evaluate(
    profile: &ProfileArg,
    paths: &[PathBuf],
    shuffle_seed: Option<u64>,
    json: bool,
    args: &ValidationArgs,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let mut args = args.clone();
    if args.seed.is_none() {
        args.seed = shuffle_seed;
    }
    let plan = Plan::new(&lp.profile, &args);
    let sweep_spec = match &args.sweep {
        Some(spec) => {
            let (key, values) = parse_sweep(spec)?;
            let k = resolve_key(&lp.profile, &key)?;
            Some((spec, key, k, values))
        }
        None => None,
    };
    match (args.simulate, paths.is_empty()) {
        (true, false) => {
            return Err(bad(
                "--simulate evaluates datasets simulated from the profile: give no PATH",
            ));
        }
        (false, true) => {
            return Err(bad(
                "no recordings: give a PATH, or --simulate to evaluate a simulated dataset",
            ));
        }
        _ => {}
    }
    if let Some((spec, _, k, _)) = &sweep_spec
        && k.needs_simulation()
        && !args.simulate
    {
        return Err(bad(format!(
            "--sweep {}: this key changes the recordings themselves, so it cannot be swept over \
             recordings on disk; simulate a dataset per value instead: \
             hapticlab evaluate --profile {} --simulate --folds 5 --sweep {spec}",
            k.name(),
            profile.profile.display()
        )));
    }
    let sim = SimPlan {
        per_class: args.per_class.unwrap_or(
            lp.profile.evaluation.train_per_class + lp.profile.evaluation.test_per_class,
        ),
        threads: plan.threads,
    };
    if args.per_class.is_some() && !args.simulate {
        return Err(bad(
            "--per-class sets how many scans --simulate makes per texture; add --simulate (and no PATH)",
        ));
    }
    if args.simulate && sim.per_class == 0 {
        return Err(bad("--per-class must be at least 1"));
    }
    let e = &lp.profile.evaluation;
    if args.simulate
        && plan.method == SplitMethod::Holdout
        && sim.per_class < e.train_per_class + e.test_per_class
    {
        return Err(bad(format!(
            "--per-class {}: the profile's holdout split needs {} scans per texture ({} to train, {} to test); \
             simulate at least that many, or cross-validate (--folds N)",
            sim.per_class,
            e.train_per_class + e.test_per_class,
            e.train_per_class,
            e.test_per_class
        )));
    }
    let n_textures = lp.profile.textures.len();
    if let Some((_, key, k, values)) = &sweep_spec
        && k.needs_simulation()
    {
        let per_value = sim.per_class * n_textures;
        let pb = crate::commands::progress_bar((per_value * values.len()) as u64, "simulating");
        let s = sweep_simulated(&lp, key, values, &plan, sim, &|i, done, _| {
            if done == 1 {
                pb.set_message(format!(
                    "{} = {} ({}/{})",
                    k.name(),
                    meta_text(&values[i]),
                    i + 1,
                    values.len()
                ));
            }
            pb.set_position((i * per_value + done) as u64);
        })?;
        pb.finish_and_clear();
        if json {
            crate::outln!("{}", serde_json::to_string(&s).map_err(bad)?);
        } else {
            crate::outln!(
                "profile {}: sweeping {} over {} values, each on {} simulated scans per texture (seed {}), {}",
                lp.profile.name,
                s.key,
                values.len(),
                sim.per_class,
                lp.profile.simulator.seed,
                plan.describe(),
            );
            crate::outp!("{}", s.table());
        }
        return Ok(());
    }
    // Samples are kept only when a sweep extracts features again per value;
    // otherwise memory holds one feature vector per recording.
    let keep = match &sweep_spec {
        Some((_, _, k, _)) if k.table == "analysis" => Keep::Samples,
        _ => Keep::Features,
    };
    let options = Options {
        keep,
        unusable: Unusable::Fail,
        threads: plan.threads,
    };
    let data = if args.simulate {
        let pb = crate::commands::progress_bar((sim.per_class * n_textures) as u64, "simulating");
        let d = simulated_dataset(&lp, sim, &lp.profile.analysis, options, &|done, _| {
            pb.set_position(done as u64)
        });
        pb.finish_and_clear();
        d?
    } else {
        let files = crate::commands::find_recordings(paths)?;
        let pb = crate::commands::progress_bar(files.len() as u64, "reading");
        let d = Dataset::load_files(&files, &lp.profile.analysis, options, &|| pb.inc(1));
        pb.finish_and_clear();
        d?
    };
    crate::commands::warn_skipped(&data.skipped);
    let source = if args.simulate {
        format!(
            "{} simulated recordings (seed {})",
            data.scans.len(),
            lp.profile.simulator.seed
        )
    } else {
        crate::classify::plural(data.scans.len(), "recording", "recordings")
    };
    if let Some((_, key, _, values)) = &sweep_spec {
        let s = sweep(&lp.profile, &data, key, values, &plan, &|_| {})?;
        if json {
            crate::outln!("{}", serde_json::to_string(&s).map_err(bad)?);
        } else {
            crate::outln!(
                "profile {}: sweeping {} over {} values, {}, {source}",
                lp.profile.name,
                s.key,
                values.len(),
                plan.describe(),
            );
            crate::outp!("{}", s.table());
        }
        return Ok(());
    }
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let examples = data.examples(&lp.profile.analysis)?;
    let report = validate(&lp.profile, examples, groups.as_deref(), &plan)?;
    let notice = report.k_notice();
    if let Some(n) = &notice {
        crate::errln!("note: {n}");
    }
    if json {
        crate::outln!("{}", serde_json::to_string(&report).map_err(bad)?);
    } else {
        crate::outln!(
            "profile {}: k-NN k = {}{} ({:?}, {:?} votes{}), {}, {source}",
            lp.profile.name,
            lp.profile.classifier.k_text(),
            if notice.is_some() {
                ", chosen by CV in folds with too few scans of a texture (see the note)"
            } else {
                ""
            },
            lp.profile.classifier.metric,
            lp.profile.classifier.weights,
            if lp.profile.classifier.standardize {
                ", standardised"
            } else {
                ""
            },
            plan.describe(),
        );
        crate::outp!("{}", report.table());
    }
    Ok(())
}
