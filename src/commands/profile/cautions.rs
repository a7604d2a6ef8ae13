//! What `profile new` warns about: recordings whose differences would
//! quietly spoil every analysis of the folder — rates that differ (and may
//! go with the labels). Each caution is one line, said on standard error by
//! the command and in the profile's comments by the draft, so the two never
//! differ.

use std::collections::BTreeMap;

use super::survey::Survey;

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
                crate::classify::plural(r.count, "recording", "recordings"),
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
