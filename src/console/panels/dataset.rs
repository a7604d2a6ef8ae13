//! The Dataset panel: the session's dataset folder, recordings per label,
//! whether a model is trained, and the last evaluation's confusion matrix
//! with SR/ER per class (the thesis's Table 4.1).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget};

use super::{elide_middle, fit_lines, frame};
use crate::classify::plural;
use crate::console::app::App;
use crate::console::keymap::Key;
use crate::profile::Method;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let d = &app.dataset;
    let room = usize::from(area.width.saturating_sub(2 + 7));
    let mut v = vec![Line::raw(format!(
        "folder {}",
        elide_middle(&d.dir.display().to_string(), room)
    ))];
    if d.counts.is_empty() {
        v.push(Line::raw(format!(
            "no recordings stored yet ({} stores a scan)",
            app.keys.name(Key::Store)
        )));
    } else {
        let per: Vec<String> = d.counts.iter().map(|(l, n)| format!("{l}: {n}")).collect();
        v.push(Line::raw(format!(
            "{} — {}",
            plural(d.total(), "recording", "recordings"),
            per.join("  ")
        )));
    }
    if d.unsaved > 0 {
        v.push(Line::raw(format!(
            "{} scan(s) not stored, in .unsaved/",
            d.unsaved
        )));
    }
    v.push(Line::raw(match (&d.model, &d.busy) {
        (_, Some(b)) => b.clone(),
        (Some(m), None) => match d.stale_model() {
            // What to do first: a narrow panel cuts the end of the line.
            Some(stale) => format!(
                "model stale: {} trains again (k = {}, {stale})",
                app.keys.name(Key::Train),
                m.k
            ),
            None => format!(
                "model: {} on {} of {}",
                match m.method {
                    Method::Knn => format!("{} k = {}", Method::Knn.name(), m.k),
                    other => other.name().to_string(),
                },
                plural(m.examples, "recording", "recordings"),
                m.labels.join(", ")
            ),
        },
        (None, None) => format!(
            "model: none ({} trains, {} evaluates)",
            app.keys.name(Key::Train),
            app.keys.name(Key::Evaluate)
        ),
    }));
    // Why k is not the profile's, or why the saved model is not used.
    if let Some(note) = d
        .model
        .as_ref()
        .and_then(|m| m.k_notice.as_ref())
        .or(d.model_note.as_ref())
    {
        v.push(Line::styled(
            note.clone(),
            Style::new().add_modifier(Modifier::DIM),
        ));
    }
    match &d.report {
        None => v.push(Line::raw("no evaluation yet")),
        Some(r) => {
            v.push(Line::styled(
                // The accuracy first: a narrow panel cuts the end of the line.
                format!(
                    "evaluation: {}/{} right ({:.1} %){}{}; rows true, columns classified as",
                    r.correct(),
                    r.tested(),
                    r.accuracy * 100.0,
                    d.report_method
                        .as_ref()
                        .map_or(String::new(), |m| format!(" by {m}")),
                    d.report_file
                        .as_ref()
                        .and_then(|f| f.file_name())
                        .map_or(String::new(), |f| format!(", in {}", f.to_string_lossy())),
                ),
                Style::new().add_modifier(Modifier::DIM),
            ));
            let mut head = format!("{:>7}", "");
            for l in &r.labels {
                head.push_str(&format!("{l:>7}"));
            }
            v.push(Line::styled(
                head,
                Style::new().add_modifier(Modifier::BOLD),
            ));
            for (i, l) in r.labels.iter().enumerate() {
                let mut row = format!("{l:>7}");
                for n in &r.confusion[i] {
                    row.push_str(&format!("{n:>7}"));
                }
                v.push(Line::raw(row));
            }
            let rate = |f: &dyn Fn(&crate::evaluate::ClassRate) -> f64, name: &str| {
                let mut row = format!("{name:>7}");
                for l in &r.labels {
                    let c = r.per_class.iter().find(|c| &c.label == l);
                    match c.map(f) {
                        Some(x) if x.is_finite() => row.push_str(&format!("{:>7.1}", x * 100.0)),
                        _ => row.push_str(&format!("{:>7}", "—")),
                    }
                }
                row
            };
            v.push(Line::raw(rate(&|c| c.success_rate, "SR(%)")));
            v.push(Line::raw(rate(&|c| c.error_rate, "ER(%)")));
        }
    }
    // A line too long for the panel is cut at a word, not mid-word.
    let inner = usize::from(area.width.saturating_sub(2));
    Paragraph::new(fit_lines(v, inner))
        .block(frame("Dataset"))
        .render(area, buf);
}
