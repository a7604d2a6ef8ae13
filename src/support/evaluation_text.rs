//! An evaluation's plain text, for every front end that shows one
//! (`hapticlab evaluate`, and the report the console's `e` keeps): the
//! header naming the method and the k actually used, and the table.

use crate::evaluate::request::{Evaluation, Outcome};
use crate::profile::{FeatureFamily, LoadedProfile, Method};

/// The report's plain text: Table 4.1, and for cross-validation the
/// spread and the macro-F1.
pub fn table(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Holdout(h) => h.table(),
        Outcome::Validated(v) => v.report.table(),
        Outcome::Sweep(s) => s.table(),
    }
}

/// The k actually used: "10", "3 (k = auto)", "1 or 10 (per fold)", with
/// why when it is not the profile's.
pub fn k_text(lp: &LoadedProfile, ev: &Evaluation) -> String {
    let used: Vec<String> = ev
        .outcome
        .k_used()
        .iter()
        .map(ToString::to_string)
        .collect();
    let mut text = used.join(" or ");
    if used.len() > 1 {
        text.push_str(" (per fold)");
    }
    if lp.profile.classifier.k_is_auto() {
        text.push_str(" (k = auto, chosen by CV inside the training part)");
    } else if ev.outcome.k_notice().is_some() {
        text.push_str(&format!(
            ", not the profile's {}: chosen by CV where a texture had too few training scans (see the note)",
            lp.profile.classifier.k_text()
        ));
    }
    text
}

/// The line above the table: the profile, the k and the method actually
/// used, what was evaluated, and why the method is not the profile's when
/// it fell back.
pub fn header(lp: &LoadedProfile, ev: &Evaluation) -> String {
    match tuned_note(lp, ev) {
        Some(note) => format!("{}\n{note}", method_line(lp, ev)),
        None => method_line(lp, ev),
    }
}

/// Which figure to quote when the profile was tuned on these recordings:
/// the same held-out part gives tune's outer estimate; any other split
/// tests recordings the search chose the lines on, and flatters.
fn tuned_note(lp: &LoadedProfile, ev: &Evaluation) -> Option<String> {
    let t = lp.tuned_on.as_ref().filter(|_| ev.tuned_on_these)?;
    let estimate = format!("{:.1} %", 100.0 * t.outer_estimate);
    Some(
        if t.holdout && ev.fell_back.is_none() && t.validation == ev.plan.describe() {
            format!(
                "tuned on these recordings; this holdout's test part was never seen by the search, so this is tune's outer estimate ({estimate})"
            )
        } else {
            format!(
                "note: this profile was tuned on these recordings ({}): its lines were chosen on them, so the figure below flatters; quote tune's outer estimate, {estimate}",
                t.validation
            )
        },
    )
}

/// The method line: the profile, the k and the method actually used, what
/// was evaluated, and why the method is not the profile's when it fell back.
fn method_line(lp: &LoadedProfile, ev: &Evaluation) -> String {
    let p = &lp.profile;
    let fell_back = ev
        .fell_back
        .as_ref()
        .map_or(String::new(), |why| format!(" — fallback: {why}"));
    if let Outcome::Holdout(h) = &ev.outcome {
        let e = &p.evaluation;
        let voted = if h.windows.is_some() {
            format!(
                "; {}, classified by the vote of their windows",
                recordings_and_windows(
                    ev.recordings.min(h.report.train.len() + h.report.tested()),
                    held_windows(ev, h)
                )
            )
        } else {
            String::new()
        };
        return format!(
            "profile {}: {}, {} training and {} test recordings per class{}{}{voted}",
            p.name,
            classifier_text(lp, ev),
            e.train_per_class,
            e.test_per_class,
            if e.gap_per_class > 0 {
                format!(", {} left out between them", e.gap_per_class)
            } else {
                String::new()
            },
            ev.plan
                .holdout_shuffle
                .map_or(" (file-name order)".into(), |s| format!(
                    " (shuffled, seed {s})"
                )),
        );
    }
    let classifier = match p.classifier.method {
        Method::Knn => format!(
            "{} ({:?}, {:?} votes{})",
            classifier_text(lp, ev),
            p.classifier.metric,
            p.classifier.weights,
            if p.classifier.standardize {
                ", standardised"
            } else {
                ""
            },
        ),
        Method::Ridge | Method::Lda => classifier_text(lp, ev),
    };
    format!(
        "profile {}: {classifier}, {}, {}{}{fell_back}",
        p.name,
        ev.plan.describe(),
        source_text(ev),
        if ev.outcome.voted() {
            ", each recording classified by the vote of its windows"
        } else {
            ""
        },
    )
}

/// The classifier as the header names it, after the features when they
/// are not the spectrum's: `k-NN k = 10`, `random kernels, ridge`,
/// `LDA (Ledoit–Wolf shrinkage)`.
fn classifier_text(lp: &LoadedProfile, ev: &Evaluation) -> String {
    let p = &lp.profile;
    let features = match p.analysis.features {
        FeatureFamily::Spectrum => "",
        FeatureFamily::Kernels => "random kernels, ",
        FeatureFamily::Quantiles => "interval quantiles, ",
        FeatureFamily::Hydra => "competing kernels, ",
    };
    match p.classifier.method {
        Method::Knn => format!("{features}k-NN k = {}", k_text(lp, ev)),
        Method::Ridge => format!("{features}ridge (alpha by leave-one-out)"),
        Method::Lda => format!("{features}LDA (Ledoit–Wolf shrinkage)"),
    }
}

/// The windows of the recordings a holdout used.
fn held_windows(ev: &Evaluation, h: &crate::evaluate::plan::Holdout) -> usize {
    let per = ev.windows.unwrap_or(0) / ev.recordings.max(1);
    per * (h.report.train.len() + h.report.tested())
}

/// "40 recordings, 120 windows".
fn recordings_and_windows(recordings: usize, windows: usize) -> String {
    format!(
        "{}, {}",
        crate::classify::plural(recordings, "recording", "recordings"),
        crate::classify::plural(windows, "window", "windows")
    )
}

/// What was evaluated: "120 recordings", "120 recordings, 360 windows",
/// "120 simulated recordings (seed 7)", "each on 30 simulated scans per
/// texture (seed 7)".
pub fn source_text(ev: &Evaluation) -> String {
    let windows = ev.windows.map_or(String::new(), |w| {
        format!(", {}", crate::classify::plural(w, "window", "windows"))
    });
    match ev.simulated {
        Some(s) if s.per_point => format!(
            "each on {} simulated scans per texture (seed {})",
            s.per_class, s.seed
        ),
        Some(s) => format!(
            "{} simulated recordings{windows} (seed {})",
            ev.recordings, s.seed
        ),
        None => format!(
            "{}{windows}",
            crate::classify::plural(ev.recordings, "recording", "recordings")
        ),
    }
}
