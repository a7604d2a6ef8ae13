//! The tuned profile's text: the input profile's own text with the lines
//! of the options searched replaced (or added to their section, or
//! commented out when the chosen setting does not use them), each marked
//! `# tune`, and a comment block at the end with the outer estimate and
//! the table of the best settings by inner score.

use std::fmt::Write as _;

use super::TuneReport;
use super::space::{Setting, decided_options};
use crate::profile::{Analysis, Classifier};

/// A key and the value written for it (`None`: the key must not be set).
type Line = (&'static str, Option<String>);

/// The keys `tune` decides, per section, and what the chosen setting
/// writes for each (as the option list writes it), in list order.
pub(super) fn decided(setting: &Setting) -> Vec<(&'static str, Vec<Line>)> {
    let (analysis, classifier) = decided_options();
    vec![
        (
            "analysis",
            analysis
                .map(|o| {
                    let used = !setting.unused(o.field());
                    (o.field(), o.written(&setting.analysis).filter(|_| used))
                })
                .collect(),
        ),
        (
            "classifier",
            classifier
                // An option every profile sets keeps the profile's line
                // when the setting does not use it.
                .filter(|o| !(o.required() && setting.unused(o.field())))
                .map(|o| {
                    let used = !setting.unused(o.field());
                    (o.field(), o.written(&setting.classifier).filter(|_| used))
                })
                .collect(),
        ),
    ]
}

/// Whether a profile read back from [`tuned_profile`]'s text holds the
/// setting: its analysis and classifier, but for `bins`, which bands
/// replace (a profile may not set both, so the text leaves `bins` out and
/// it reads back as its default).
pub fn reads_back_as(setting: &Setting, analysis: &Analysis, classifier: &Classifier) -> bool {
    let mut want = setting.analysis.clone();
    if want.bands.is_some() {
        want.bins = analysis.bins;
    }
    want == *analysis && setting.classifier == *classifier
}

/// The key a `key = value` line sets, when it is one.
fn key_of(line: &str) -> Option<&str> {
    let t = line.trim_start();
    if t.starts_with('#') || t.starts_with('[') {
        return None;
    }
    let (k, _) = t.split_once('=')?;
    Some(k.trim())
}

/// The section a `[name]` line opens.
fn section_of(line: &str) -> Option<&str> {
    let t = line.trim();
    let inner = t.strip_prefix('[')?.split(']').next()?;
    Some(inner.trim_matches('[').trim())
}

/// `original` with the chosen setting's lines and the search's comment
/// block; `about` is the block's first line (the folder and seed).
pub fn tuned_profile(
    original: &str,
    setting: &Setting,
    report: &TuneReport,
    about: &str,
) -> String {
    let mut lines: Vec<String> = original.lines().map(str::to_string).collect();
    for (section, keys) in decided(setting) {
        let mut written = vec![false; keys.len()];
        let mut inside = false;
        let mut last_key: Option<usize> = None;
        let mut header: Option<usize> = None;
        for (i, line) in lines.iter_mut().enumerate() {
            if let Some(s) = section_of(line) {
                inside = s == section;
                if inside {
                    header = Some(i);
                }
                continue;
            }
            if !inside {
                continue;
            }
            let Some(key) = key_of(line) else { continue };
            last_key = Some(i);
            if let Some(j) = keys.iter().position(|(k, _)| *k == key) {
                *line = match &keys[j].1 {
                    Some(v) => format!("{key} = {v}  # tune"),
                    None => format!("# {}  # tune: not used by the setting chosen", line.trim()),
                };
                written[j] = true;
            }
        }
        let missing: Vec<String> = keys
            .iter()
            .zip(&written)
            .filter(|(_, w)| !**w)
            .filter_map(|((k, v), _)| v.as_ref().map(|v| format!("{k} = {v}  # tune")))
            .collect();
        match last_key.or(header) {
            Some(at) => {
                for (n, l) in missing.into_iter().enumerate() {
                    lines.insert(at + 1 + n, l);
                }
            }
            None => {
                lines.push(String::new());
                lines.push(format!("[{section}]"));
                lines.extend(missing);
            }
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out.push_str(&comment_block(report, about));
    out
}

/// The comment block at the end of a tuned profile.
fn comment_block(r: &TuneReport, about: &str) -> String {
    let mut w = String::new();
    let pct = |x: f64| format!("{:.1} %", 100.0 * x);
    let _ = writeln!(w, "\n# --- hapticlab tune: {about} ---");
    // Which code chose it, as a recording's `software` key says.
    let _ = writeln!(w, "# software = {:?}", crate::version::SOFTWARE);
    let _ = writeln!(
        w,
        "# The lines marked `# tune` were chosen by nested validation: {} of the {} settings of the",
        r.configurations, r.grid
    );
    let _ = writeln!(
        w,
        "# search scored by {} inner folds ({}) inside the training part only, the best then",
        r.inner_folds,
        r.inner_split.describe()
    );
    let _ = writeln!(
        w,
        "# tested once on what [evaluation] ({}) holds out.",
        r.method
    );
    let _ = writeln!(
        w,
        "# Outer estimate: {} ({}/{} test recordings): the figure to quote. The inner scores below are not an estimate.",
        pct(r.outer_accuracy),
        r.outer.correct(),
        r.outer.tested()
    );
    if r.tuned_on.holdout {
        let _ = writeln!(
            w,
            "# `hapticlab evaluate` of this profile on these recordings tests the same held-out part: the same figure."
        );
    } else {
        let _ = writeln!(
            w,
            "# These lines were chosen on every one of these recordings, so `hapticlab evaluate` of this profile on"
        );
        let _ = writeln!(
            w,
            "# them flatters (it says so): quote the outer estimate, or evaluate on recordings the search never saw."
        );
    }
    let families: Vec<String> = r
        .families
        .iter()
        .map(|f| format!("{} {}", f.family, pct(f.inner_accuracy)))
        .collect();
    let _ = writeln!(
        w,
        "# Family chosen: {} (the best inner score of each: {}).",
        r.chosen.family,
        families.join(", ")
    );
    for l in &r.left_out {
        let _ = writeln!(
            w,
            "# Left out: {} {} feature setting(s): {}.",
            l.feature_settings, l.family, l.reason
        );
    }
    let _ = writeln!(w, "{}", r.tuned_on.line());
    let _ = writeln!(
        w,
        "# Best settings by inner score (mean accuracy over the inner folds):"
    );
    let Some(first) = r.table.first() else {
        return w;
    };
    let mut widths: Vec<usize> = first.options.0.iter().map(|(k, _)| k.len()).collect();
    for row in &r.table {
        for (wd, (_, v)) in widths.iter_mut().zip(&row.options.0) {
            *wd = (*wd).max(v.len());
        }
    }
    let mut head = "#   inner".to_string();
    for ((k, _), wd) in first.options.0.iter().zip(&widths) {
        let _ = write!(head, "  {k:<wd$}");
    }
    let _ = writeln!(w, "{}", head.trim_end());
    for row in &r.table {
        let mut line = format!("# {:>7}", pct(row.inner_accuracy));
        for ((_, v), wd) in row.options.0.iter().zip(&widths) {
            let _ = write!(line, "  {v:<wd$}");
        }
        let _ = writeln!(w, "{}", line.trim_end());
    }
    w
}
