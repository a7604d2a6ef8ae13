//! The keys and values of a sweep: `KEY=VALUES` parsed ([`parse_sweep`]),
//! a key found in the profile ([`resolve_key`]), and the profile with one
//! or several keys set ([`with_key`], [`profile_with`]), validated as a
//! profile file would be. Never prints and knows no front end.

use super::super::EvaluateError;
use crate::profile::Profile;

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
    // Examples only of keys that apply: an analysis-only profile has no
    // rig to simulate, so no rig key to offer.
    let rig = !profile.is_analysis_only();
    let unknown = || {
        let (rig_keys, examples) = if rig {
            (
                " nor of [controller], [path], [simulator] or [device] (with --simulate)",
                ", controller.stiffness_n_per_m[1], path.speed_m_per_s",
            )
        } else {
            (
                "; this profile has no [controller], [path], [simulator] or [device] to \
                 simulate with",
                "",
            )
        };
        bad(format!(
            "--sweep {key}: not a key of [analysis], [classifier] or [evaluation] (evaluated on \
             the recordings){rig_keys}; e.g. k, spacing, taper{examples}"
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
    profile_with(profile, &[(k, value)])
        .map_err(|reason| bad(format!("--sweep {} = {value}: {reason}", k.name())))
}

/// The profile with every key of `set` set to its value (one point of a
/// grid), validated once all are set, so a combination that is valid
/// together (`spectrum = "welch"` with the `bins` Welch allows) passes. The
/// error is the reason alone (`analysis.bins: …`), for the sweep to report
/// beside the point.
pub fn profile_with(
    profile: &Profile,
    set: &[(&SweepKey, &toml::Value)],
) -> Result<Profile, String> {
    let mut doc = toml::Table::try_from(profile).map_err(|e| e.to_string())?;
    let as_like = |old: Option<&toml::Value>, v: &toml::Value| match (old, v) {
        (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => toml::Value::Float(*i as f64),
        _ => v.clone(),
    };
    for (k, value) in set {
        let Some(tab) = doc.get_mut(&k.table).and_then(|v| v.as_table_mut()) else {
            continue;
        };
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
        .map_err(|e: toml::de::Error| e.message().trim().to_string())?;
    // A window over the whole scan leg follows the swept path (unless the
    // window itself is swept).
    if !set
        .iter()
        .any(|(k, _)| k.table == "analysis" && k.field == "window")
    {
        p.analysis.window_is_scan_leg = profile.analysis.window_is_scan_leg;
    }
    p.resolve_window();
    p.validate()
        .map_err(|v| format!("{}: {}", v.key, v.reason))?;
    Ok(p)
}

/// Optional keys a table may lack (because they are at their default).
fn known_field(table: &str, field: &str) -> bool {
    match table {
        // The one list of options.
        "analysis" => crate::profile::options::option(field).is_some(),
        "classifier" => crate::profile::options::classifier_option(field).is_some(),
        "evaluation" => [
            "shuffle_seed",
            "method",
            "folds",
            "group_by",
            "gap_per_class",
        ]
        .contains(&field),
        "path" => ["transit_speed_m_per_s"].contains(&field),
        _ => false,
    }
}
