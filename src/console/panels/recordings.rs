//! The Recordings panel (in a replay, in the Dataset panel's place): the
//! recordings of the folder, each with its label, its prediction, and
//! whether that was right, the one playing marked with `>`.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget};

use super::frame;
use crate::console::app::App;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let Some(r) = &app.replay else {
        return;
    };
    let (right, known) = r.score();
    let title = if known > 0 {
        format!(
            "Recordings: {}, {right}/{known} predicted right",
            r.entries.len()
        )
    } else if r.listing {
        format!("Recordings: {}, predicting…", r.entries.len())
    } else {
        format!("Recordings: {}", r.entries.len())
    };
    let block = frame(&format!("{title} (label → predicted)"));
    let inner = block.inner(area);
    block.render(area, buf);
    let rows = usize::from(inner.height);
    if rows == 0 {
        return;
    }
    // Keep the selected one in view.
    let first = r.selected.saturating_sub(rows.saturating_sub(1) / 2);
    let first = first.min(r.entries.len().saturating_sub(rows));
    let lines: Vec<Line> = r
        .entries
        .iter()
        .enumerate()
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
            let text = format!(
                "{} {name:<16} {:>5} → {:<5} {verdict}",
                if i == r.selected { ">" } else { " " },
                e.label.as_deref().unwrap_or("?"),
                e.predicted.as_deref().unwrap_or("…"),
            );
            if i == r.selected {
                Line::styled(text, Style::new().add_modifier(Modifier::REVERSED))
            } else {
                Line::raw(text)
            }
        })
        .collect();
    Paragraph::new(lines).render(inner, buf);
}
