//! `evaluate` with honest validation (k-fold, leave-one-out, grouped folds)
//! and parameter sweeps (`--sweep KEY=VALUES`): the thesis's section 4.3
//! parameter selection as one command.
//!
//! The recordings are read once into a [`Dataset`] holding only the columns
//! the analysis needs (and the metadata), so a sweep over analysis keys
//! re-extracts features without re-reading files. A sweep sets a key of the
//! profile's `[analysis]`, `[classifier]` or `[evaluation]` table through
//! TOML, so every key those tables accept can be swept and is validated as
//! in a profile file. Keys that change the recordings themselves (the
//! simulator's speed, stiffness, …) need a new dataset and are refused.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use crate::analysis::FeatureExtractor;
use crate::classify::TrainingExample;
use crate::cli::ProfileArg;
use crate::commands::{Failure, label_of, load_profile};
use crate::evaluate::cv::{self, CvReport};
use crate::evaluate::{self as ev};
use crate::profile::{Analysis, Profile, SplitMethod};
use crate::recording;

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
    /// Evaluate once per value of a profile key: `k=1..15`, `k=1..15:2`, `metric=euclidean,cosine`, `spacing=0.0002,0.0003`, `spectrum=magnitude,welch`.
    #[arg(long, value_name = "KEY=VALUES")]
    pub sweep: Option<String>,
    /// Worker threads for the folds and the reading (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

impl ValidationArgs {
    /// Whether anything beyond the thesis's holdout was asked for.
    pub fn is_active(&self) -> bool {
        self.folds.is_some() || self.loo || self.group_by.is_some() || self.sweep.is_some()
    }
}

fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

/// One recording as the analysis needs it.
#[derive(Debug, Clone)]
pub struct Scan {
    pub file: String,
    pub label: String,
    pub meta: Vec<(String, toml::Value)>,
    pub axis: Vec<f64>,
    /// `channel`, then `channels`, as the analysis names them.
    pub signals: Vec<Vec<f64>>,
}

#[derive(Debug, Clone, Default)]
pub struct Dataset {
    pub scans: Vec<Scan>,
    /// Files skipped as incomplete.
    pub incomplete: Vec<String>,
}

/// A metadata value as a group key: strings as they are, others in TOML.
pub fn meta_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

impl Dataset {
    /// Read every recording under `paths` (in parallel), keeping the columns
    /// `analysis` needs. Incomplete recordings are listed, not kept.
    pub fn load(
        paths: &[PathBuf],
        analysis: &Analysis,
        threads: usize,
    ) -> Result<Dataset, Failure> {
        let files = crate::commands::recording_files(paths)?;
        let names: Vec<String> = std::iter::once(analysis.axis.clone())
            .chain(analysis.all_channels().map(str::to_string))
            .collect();
        let read_one = |f: &PathBuf| -> Result<Result<Scan, String>, Failure> {
            let rec = recording::read(f).map_err(bad)?;
            if !rec.is_complete() {
                return Ok(Err(f.display().to_string()));
            }
            let mut cols = Vec::with_capacity(names.len());
            for n in &names {
                let c = rec.column(n).ok_or_else(|| {
                    bad(format!(
                        "{}: no column `{n}` (the recording has {})",
                        f.display(),
                        rec.columns.join(", ")
                    ))
                })?;
                cols.push(c.to_vec());
            }
            let label = label_of(&rec, f)?;
            let axis = cols.remove(0);
            Ok(Ok(Scan {
                file: f.display().to_string(),
                label,
                meta: rec.meta,
                axis,
                signals: cols,
            }))
        };
        let threads = threads.clamp(1, files.len());
        let per = files.len().div_ceil(threads);
        let results: Vec<Result<Vec<Result<Scan, String>>, Failure>> = std::thread::scope(|s| {
            let handles: Vec<_> = files
                .chunks(per)
                .map(|chunk| {
                    let read_one = &read_one;
                    s.spawn(move || chunk.iter().map(read_one).collect::<Result<Vec<_>, _>>())
                })
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|_| Err(bad("a reader thread panicked")))
                })
                .collect()
        });
        let mut out = Dataset::default();
        for r in results {
            for s in r? {
                match s {
                    Ok(scan) => out.scans.push(scan),
                    Err(file) => out.incomplete.push(file),
                }
            }
        }
        Ok(out)
    }

    /// The feature vectors under `analysis` (whose channels must be the
    /// ones the dataset was loaded with).
    pub fn examples(&self, analysis: &Analysis) -> Result<Vec<TrainingExample>, Failure> {
        let mut fx = FeatureExtractor::try_new(analysis).map_err(bad)?;
        self.scans
            .iter()
            .map(|s| {
                let signals: Vec<&[f64]> = s.signals.iter().map(Vec::as_slice).collect();
                let features = fx
                    .features_of_channels(&s.axis, &signals)
                    .map_err(|e| bad(format!("{}: {e}", s.file)))?
                    .to_vec();
                Ok(TrainingExample {
                    file: s.file.clone(),
                    label: s.label.clone(),
                    features,
                })
            })
            .collect()
    }

    /// Each scan's value of a metadata key; a scan without it is an error.
    pub fn groups(&self, key: &str) -> Result<Vec<String>, Failure> {
        self.scans
            .iter()
            .map(|s| {
                s.meta
                    .iter()
                    .find(|(k, _)| k == key)
                    .map(|(_, v)| meta_text(v))
                    .ok_or_else(|| {
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
            SplitMethod::Holdout => format!("holdout split (seed {})", self.seed),
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
        eval.shuffle_seed = Some(plan.seed);
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

/// Keys that change the recordings, not their analysis: sweeping them
/// needs a new dataset per value.
const NEEDS_RESIMULATING: [&str; 6] = [
    "speed",
    "speed_m_per_s",
    "stiffness",
    "stiffness_y",
    "stiffness_n_per_m",
    "damping_n_s_per_m",
];

/// `KEY=VALUES` into the key and its values as TOML literals.
pub fn parse_sweep(spec: &str) -> Result<(String, Vec<toml::Value>), Failure> {
    let (key, values) = spec.split_once('=').ok_or_else(|| {
        bad(format!(
            "--sweep {spec:?}: expected KEY=VALUES, e.g. k=1..15"
        ))
    })?;
    let key = key.trim().to_string();
    let short = key.rsplit('.').next().unwrap_or(&key);
    if NEEDS_RESIMULATING.contains(&short)
        || key.starts_with("simulator")
        || key.starts_with("path")
        || key.starts_with("controller")
    {
        return Err(bad(format!(
            "--sweep {key}: this key changes the recordings themselves, which evaluate cannot redo; \
             simulate one dataset per value (hapticlab simulate --profile P --out DIR) and evaluate each. \
             Sweepable: any key of [analysis], [classifier] or [evaluation], e.g. k, metric, weights, \
             spacing, spectrum, taper, window, band, welch_segment"
        )));
    }
    let values = values.trim();
    let mut out = Vec::new();
    if let Some((a, b)) = values.split_once("..") {
        let (b, step) = match b.split_once(':') {
            Some((b, s)) => (b, s),
            None => (b, "1"),
        };
        let parse = |s: &str| {
            s.trim().parse::<i64>().map_err(|_| {
                bad(format!(
                    "--sweep {key}: {values:?} is not a range like 1..15 or 1..15:2"
                ))
            })
        };
        let (a, b, step) = (parse(a)?, parse(b)?, parse(step)?);
        if step <= 0 || b < a || (b - a) / step > 10_000 {
            return Err(bad(format!(
                "--sweep {key}: {values:?} is an empty or too long range"
            )));
        }
        let mut v = a;
        while v <= b {
            out.push(toml::Value::Integer(v));
            v += step;
        }
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

/// The profile with `key` set to `value`: the key is looked up in
/// `[analysis]`, `[classifier]`, then `[evaluation]` (or named with its
/// table, `analysis.spacing`), then the profile is validated.
pub fn with_key(profile: &Profile, key: &str, value: &toml::Value) -> Result<Profile, Failure> {
    let mut doc = toml::Table::try_from(profile).map_err(bad)?;
    let (tables, field): (Vec<&str>, &str) = match key.split_once('.') {
        Some((t, f)) => (vec![t], f),
        None => (vec!["analysis", "classifier", "evaluation"], key),
    };
    let table = tables
        .iter()
        .find(|t| {
            doc.get(**t)
                .and_then(|v| v.as_table())
                .is_some_and(|tab| tab.contains_key(field) || known_field(t, field))
        })
        .ok_or_else(|| {
            bad(format!(
                "--sweep {key}: not a key of [analysis], [classifier] or [evaluation]"
            ))
        })?;
    if let Some(tab) = doc.get_mut(*table).and_then(|v| v.as_table_mut()) {
        tab.insert(field.to_string(), value.clone());
    }
    let p: Profile = toml::Value::Table(doc)
        .try_into()
        .map_err(|e: toml::de::Error| {
            bad(format!("--sweep {key} = {value}: {}", e.message().trim()))
        })?;
    p.validate()
        .map_err(|v| bad(format!("--sweep {key} = {value}: {}: {}", v.key, v.reason)))?;
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
    /// The k used per fold (differs from the value only with k = "auto").
    pub k: Vec<usize>,
}

#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    pub key: String,
    pub method: String,
    pub points: Vec<SweepPoint>,
}

/// Evaluate once per value; features are re-extracted only when the
/// analysis changes.
pub fn sweep(
    profile: &Profile,
    data: &Dataset,
    key: &str,
    values: &[toml::Value],
    plan: &Plan,
    progress: &dyn Fn(usize),
) -> Result<Sweep, Failure> {
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let mut points = Vec::new();
    let mut cached: Option<(Analysis, Vec<TrainingExample>)> = None;
    for (i, v) in values.iter().enumerate() {
        let p = with_key(profile, key, v)?;
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
        let r = validate(&p, examples, groups.as_deref(), plan)?;
        points.push(SweepPoint {
            value: crate::study::meta_text(v),
            accuracy: r.accuracy,
            accuracy_mean: r.accuracy_mean,
            accuracy_std: r.accuracy_std,
            macro_f1: r.macro_f1,
            k: r.folds.iter().map(|f| f.k).collect(),
        });
        progress(i + 1);
    }
    Ok(Sweep {
        key: key.to_string(),
        method: plan.describe(),
        points,
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
            out.push_str(&format!(
                "{:<w$}  {:>7.1}%  {:>8.1} ± {:<5.1} %  {:>8.3}\n",
                p.value,
                100.0 * p.accuracy,
                100.0 * p.accuracy_mean,
                100.0 * p.accuracy_std,
                p.macro_f1
            ));
        }
        if let Some(best) = self.points.iter().max_by(|a, b| {
            a.accuracy
                .total_cmp(&b.accuracy)
                .then(std::cmp::Ordering::Greater)
        }) {
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

/// `hapticlab evaluate` with cross-validation or a sweep.
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
    let data = Dataset::load(paths, &lp.profile.analysis, plan.threads)?;
    for f in &data.incomplete {
        eprintln!("warning: {f}: incomplete scan (no `# end samples` trailer), skipped");
    }
    if let Some(spec) = &args.sweep {
        let (key, values) = parse_sweep(spec)?;
        let s = sweep(&lp.profile, &data, &key, &values, &plan, &|_| {})?;
        if json {
            println!("{}", serde_json::to_string(&s).map_err(bad)?);
        } else {
            println!(
                "profile {}: sweeping {key} over {} values, {}, {} recordings",
                lp.profile.name,
                values.len(),
                plan.describe(),
                data.scans.len()
            );
            print!("{}", s.table());
        }
        return Ok(());
    }
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let examples = data.examples(&lp.profile.analysis)?;
    let report = validate(&lp.profile, examples, groups.as_deref(), &plan)?;
    if json {
        println!("{}", serde_json::to_string(&report).map_err(bad)?);
    } else {
        println!(
            "profile {}: k-NN k = {} ({:?}, {:?} votes{}), {}, {} recordings",
            lp.profile.name,
            lp.profile.classifier.k_text(),
            lp.profile.classifier.metric,
            lp.profile.classifier.weights,
            if lp.profile.classifier.standardize {
                ", standardised"
            } else {
                ""
            },
            plan.describe(),
            data.scans.len()
        );
        print!("{}", report.table());
    }
    Ok(())
}
