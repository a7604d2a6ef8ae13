//! Parameter sweeps (`evaluate --sweep KEY=VALUES`): the thesis's section
//! 4.3 parameter selection, one validation ([`super::plan::validate`]) per
//! value of a profile key.
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

//! Like the rest of `evaluate`, this never prints and knows no front end.

use serde::Serialize;

use super::EvaluateError;
use super::cv::CvReport;
use super::plan::{Dataset, Plan, validate};
use crate::classify::TrainingExample;
use crate::dataset::{self, Options, Skipped, Unusable, meta_text};
use crate::profile::{Analysis, Profile};

fn bad(m: impl std::fmt::Display) -> EvaluateError {
    EvaluateError::Input(m.to_string())
}

/// `KEY=VALUES` into the key and its values as TOML literals: `1..15`,
/// `1..15:2`, `0.005..0.02:0.005` (a range, ends included), or a comma
/// list (`euclidean,cosine`, `[0,1],[1,2]`).
pub fn parse_sweep(spec: &str) -> Result<(String, Vec<toml::Value>), EvaluateError> {
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
fn parse_range(
    key: &str,
    values: &str,
    a: &str,
    b: &str,
) -> Result<Vec<toml::Value>, EvaluateError> {
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
pub fn resolve_key(profile: &Profile, key: &str) -> Result<SweepKey, EvaluateError> {
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
pub fn with_key(
    profile: &Profile,
    key: &str,
    value: &toml::Value,
) -> Result<Profile, EvaluateError> {
    let k = resolve_key(profile, key)?;
    with_resolved(profile, &k, value)
}

/// [`with_key`] for a key already resolved.
pub fn with_resolved(
    profile: &Profile,
    k: &SweepKey,
    value: &toml::Value,
) -> Result<Profile, EvaluateError> {
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
) -> Result<Dataset, EvaluateError> {
    // Removed on drop, and on Ctrl-C (which would otherwise skip the drop).
    let dir = crate::scratch::ScratchFolder::new("hapticlab-simulate-")
        .map_err(EvaluateError::Scratch)?;
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
        value: meta_text(value),
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
) -> Result<Sweep, EvaluateError> {
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
) -> Result<Sweep, EvaluateError> {
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
                    error: Some(f.to_string()),
                });
                continue;
            }
        };
        let groups = match &plan.group_by {
            Some(g) => Some(data.groups(g)?),
            None => None,
        };
        let r = validate(&lp_v.profile, examples, groups.as_deref(), plan)
            .map_err(|f| bad(format!("--sweep {} = {v}: {f}", k.name())))?;
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
