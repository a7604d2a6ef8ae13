//! What `profile new` warns about: recordings whose differences would
//! quietly spoil every analysis of the folder — rates that differ (and may
//! go with the labels), a few recordings much shorter than the rest. Each caution is one line, said on standard error by
//! the command and in the profile's comments by the draft, so the two never
//! differ.

use std::collections::BTreeMap;

use super::draft::shown;
use super::survey::Survey;
use crate::classify::plural;
use crate::profile::fitted::{float, floor3};

/// `a: 2, b: 2`: recordings per label.
pub fn per_label(labels: &BTreeMap<String, usize>) -> String {
    labels
        .iter()
        .map(|(l, n)| format!("{l}: {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A rate for people: `100 Hz`, `1 kHz`, `44.1 kHz`.
pub fn rate_text(rate_hz: f64) -> String {
    let rate_hz = crate::profile::fitted::significant(rate_hz, 6);
    if rate_hz >= 1000.0 {
        format!("{} kHz", rate_hz / 1000.0)
    } else {
        format!("{rate_hz} Hz")
    }
}

/// Rates that differ: which labels have each, what the analysis does
/// with them along a time axis (`spacing`, one period of the slowest),
/// and, when a rate goes with one label only, that the labels would be
/// told apart by their rate.
pub fn of_rates(s: &Survey, time: Option<&str>) -> Option<String> {
    if s.rates.len() < 2 {
        return None;
    }
    let each: Vec<String> = s
        .rates
        .iter()
        .map(|r| {
            format!(
                "{}: {} ({})",
                rate_text(r.hz),
                plural(r.count, "recording", "recordings"),
                per_label(&r.labels)
            )
        })
        .collect();
    let mut text = format!("the recordings' rates differ: {}", each.join("; "));
    if let Some(spacing) = time {
        let slowest = s.slowest_rate();
        text.push_str(&format!(
            ". Every recording is analysed at {}, the slowest (spacing = {spacing}), so the faster ones lose all above {}",
            rate_text(slowest),
            rate_text(slowest / 2.0)
        ));
    }
    let alone: Vec<String> = s
        .rates
        .iter()
        .filter(|r| r.labels.len() == 1)
        .filter_map(|r| {
            let label = r.labels.keys().next()?;
            Some(format!("{} goes with label {label} alone", rate_text(r.hz)))
        })
        .collect();
    if !alone.is_empty() {
        text.push_str(&format!(
            ". {}: the classifier would tell the labels apart by their rate, not their texture",
            alone.join(", ")
        ));
    }
    text.push_str(
        ". Check the --rate each label was imported with and import again those that were wrong, or keep recordings of one rate",
    );
    Some(text)
}

/// File names numbered without leading zeros, so that file-name order —
/// the order a time split and a holdout take — is not their number order.
pub fn of_names(s: &Survey) -> Option<String> {
    let (before, after) = s.out_of_number_order.as_ref()?;
    Some(format!(
        "file names are numbered without leading zeros: file-name order, which a holdout and the \
         time split take, puts {before} before {after}; if the numbers are the trials' order in \
         time, rename them with leading zeros (as import --split names its trials: -seg001, \
         -seg002, …) and run profile new again"
    ))
}

/// A length along `axis` for people: seconds along time, millimetres along
/// a position.
fn length_text(axis: &str, v: f64) -> String {
    if axis.ends_with("_m") {
        format!("{} mm", shown(v * 1000.0))
    } else {
        format!("{} s", shown(v))
    }
}

/// Recordings much shorter than the median along `axis` (under half):
/// the few that the window, fitted to the others (`end`), leaves
/// uncovered — `evaluate` refuses them, so they are named with what to do —
/// or, when they are many, that the window fits the shortest and so
/// analyses only that much of every recording.
pub fn of_lengths(s: &Survey, axis: &str, end: &str, spacing: f64) -> Option<String> {
    let r = s.reach.get(axis)?;
    r.short.first()?;
    let named: Vec<String> = r
        .short
        .iter()
        .take(5)
        .map(|(f, t)| format!("{f} ({})", length_text(axis, *t)))
        .collect();
    let more = match r.short.len() {
        n if n > 5 => format!(", and {} more", n - 5),
        _ => String::new(),
    };
    let median = length_text(axis, r.median);
    let (_, uncovered) = s.window_reach(axis);
    if uncovered.is_empty() {
        return Some(format!(
            "{} of {} recordings are under half the median length along {axis} ({median}), e.g. {}: \
             the window fits the shortest (window = [0.0, {end}]), so every recording is analysed over only \
             that much; remove the short ones and run profile new again to use more of each",
            r.short.len(),
            s.complete,
            named[0]
        ));
    }
    // The longest of the short ones still analysable: a window by hand.
    let shortest = uncovered.iter().map(|u| u.1).fold(f64::INFINITY, f64::min);
    let (by_hand, _) = floor3(shortest);
    let keep = if by_hand >= 8.0 * spacing {
        format!(
            "; or, to keep {}, set window = [0.0, {}] by hand, which analyses only that much of every recording",
            if uncovered.len() == 1 { "it" } else { "them" },
            float(by_hand)
        )
    } else {
        String::new()
    };
    Some(format!(
        "{} under half the median length along {axis} ({median}): {}{more}. The window was fitted to the others \
         (window = [0.0, {end}]), so {} not cover it and evaluate refuses {} until {} removed from the folder{keep}",
        plural(uncovered.len(), "recording is", "recordings are"),
        named.join(", "),
        if uncovered.len() == 1 {
            "it does"
        } else {
            "they do"
        },
        if uncovered.len() == 1 { "it" } else { "them" },
        if uncovered.len() == 1 {
            "it is"
        } else {
            "they are"
        },
    ))
}
