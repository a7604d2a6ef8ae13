//! The Prediction panel: the predicted texture, the votes per class, the
//! nearest neighbours' distances, and the texture's description and
//! dimensions from the profile (the thesis GUI's "Predicted texture").

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::frame;
use crate::console::app::App;
use crate::console::keymap::Key;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let block = frame("Prediction");
    let p = app.scan().and_then(|s| s.prediction.as_ref());
    let lines: Vec<Line> = match p {
        None => {
            let how = if app.model.is_some() {
                format!(
                    "{} predicts the scan on screen",
                    app.keys.name(Key::Predict)
                )
            } else {
                format!(
                    "no model yet: {} trains on the dataset and predicts",
                    app.keys.name(Key::Predict)
                )
            };
            let what = if app.scan().is_some() {
                "not predicted yet"
            } else {
                "no scan yet"
            };
            vec![Line::raw(what), Line::raw(how)]
        }
        Some(Err(e)) => vec![Line::raw(format!("no prediction: {e}"))],
        Some(Ok(pv)) => {
            let pr = &pv.prediction;
            let tex = app.profile.profile.texture(&pr.label);
            let mut v = vec![Line::from(vec![
                Span::raw("Predicted "),
                Span::styled(
                    pr.label.clone(),
                    Style::new().add_modifier(Modifier::BOLD | Modifier::REVERSED),
                ),
                Span::raw(match tex {
                    Some(t) if !t.description.is_empty() => format!(" — {}", t.description),
                    _ => String::new(),
                }),
            ])];
            let dims = tex.map_or(String::new(), |t| {
                t.dimensions_mm
                    .iter()
                    .map(|(k, v)| format!("{k} {v} mm"))
                    .collect::<Vec<_>>()
                    .join(", ")
            });
            let truth = match app.scan().and_then(|s| s.label.as_deref()) {
                Some(l) if l == pr.label => format!("recorded as {l}: right"),
                Some(l) => format!("recorded as {l}: WRONG"),
                None => String::new(),
            };
            let loo = if pv.left_out {
                " (left out of the model)"
            } else {
                ""
            };
            let second: Vec<String> = [dims, truth]
                .into_iter()
                .filter(|s| !s.is_empty())
                .collect();
            v.push(Line::raw(format!("{}{loo}", second.join("; "))));
            let k: usize = pr.votes.iter().map(|(_, n)| n).sum::<usize>().max(1);
            // A bar per class when there is room, else one line of votes.
            let rows = usize::from(area.height.saturating_sub(2));
            if rows > 4 + pr.votes.len() {
                for (label, n) in &pr.votes {
                    let bar = "█".repeat(n * 12 / k);
                    let votes = if *n == 1 { "vote " } else { "votes" };
                    v.push(Line::raw(format!("{label:>6} {n:>3} {votes} {bar}")));
                }
            } else {
                let votes: Vec<String> = pr.votes.iter().map(|(l, n)| format!("{l} {n}")).collect();
                v.push(Line::raw(format!("votes: {}", votes.join(", "))));
            }
            let near: Vec<String> = pr
                .neighbours
                .iter()
                .map(|n| format!("{} {:.2e}", n.label, n.distance))
                .collect();
            // As many neighbours as fit one row: a pair is never split.
            let room = usize::from(area.width.saturating_sub(2));
            let mut line = "nearest:".to_string();
            for (i, n) in near.iter().enumerate() {
                let more = if i + 1 < near.len() { ", …" } else { "" };
                if line.chars().count() + 1 + n.chars().count() + more.chars().count() > room
                    && i > 0
                {
                    line.push_str(" …");
                    break;
                }
                line.push_str(if i == 0 { " " } else { ", " });
                line.push_str(n);
            }
            v.push(Line::raw(line));
            v
        }
    };
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(block)
        .render(area, buf);
}
