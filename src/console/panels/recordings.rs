//! The Recordings panel (in a replay, in the Dataset panel's place): the
//! recordings of the folder, each with its label, its prediction, and
//! whether that was right, the one playing marked with `>`.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget};

use super::{cut_at_word, frame_fit};
use crate::console::app::App;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let Some(r) = &app.replay else {
        return;
    };
    let (right, known) = r.score();
    let shown = r.visible();
    let count = match &r.filter {
        Some(f) => format!("{} of {} ({f})", shown.len(), r.entries.len()),
        None => r.entries.len().to_string(),
    };
    let title = if known > 0 {
        format!("Recordings: {count}, {right}/{known} predicted right")
    } else if r.listing {
        format!("Recordings: {count}, predicting…")
    } else {
        format!("Recordings: {count}")
    };
    let block = frame_fit(&format!("{title} (label → predicted)"), area.width);
    let inner = block.inner(area);
    block.render(area, buf);
    let rows = usize::from(inner.height);
    if rows == 0 {
        return;
    }
    // Keep the selected one in view.
    let at = shown.iter().position(|&i| i >= r.selected).unwrap_or(0);
    let first = at.saturating_sub(rows.saturating_sub(1) / 2);
    let first = first.min(shown.len().saturating_sub(rows));
    let dataset = &app.dataset.dir;
    let lines: Vec<Line> = shown
        .iter()
        .map(|&i| (i, &r.entries[i]))
        .skip(first)
        .take(rows)
        .map(|(i, e)| {
            let name = e
                .path
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into_owned());
            let verdict = match e.right() {
                Some(true) => "right",
                Some(false) => "WRONG",
                None => "",
            };
            // Where curating put it, and a scan cut short, say so.
            let mut tags = Vec::new();
            if e.unsaved(dataset) {
                tags.push("unsaved");
            }
            if crate::console::curate::is_excluded(&e.path, dataset) {
                tags.push("excluded");
            }
            if e.complete == Some(false) {
                tags.push("incomplete");
            }
            let verdict = if tags.is_empty() {
                verdict.to_string()
            } else {
                format!("{verdict} ({})", tags.join(", "))
            };
            let text = format!(
                "{} {name:<16} {:>5} → {:<5} {verdict}",
                if i == r.selected { ">" } else { " " },
                e.label.as_deref().unwrap_or("?"),
                e.predicted.as_deref().unwrap_or("…"),
            );
            // Cut with a sign, not by the panel's border.
            let text = cut_at_word(&text, usize::from(inner.width));
            if i == r.selected {
                Line::styled(text, Style::new().add_modifier(Modifier::REVERSED))
            } else {
                Line::raw(text)
            }
        })
        .collect();
    Paragraph::new(lines).render(inner, buf);
}
