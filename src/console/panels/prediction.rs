//! The Prediction panel: the predicted texture, the votes per class, the
//! nearest neighbours' distances, and the texture's description and
//! dimensions from the profile (the thesis GUI's "Predicted texture").
//! With `[analysis] windows` the votes are the sub-windows' ("S2 3 of 4
//! windows, 75 %"), and while a scan runs the panel follows it: the live
//! estimate, sub-window by sub-window, until the stored recording's
//! prediction replaces it.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::frame;
use crate::classify::{RecordingPrediction, plural};
use crate::console::app::App;
use crate::console::estimate::Estimate;
use crate::console::keymap::Key;
use crate::console::scan::unit_of;

/// Width of the longest bar, in cells.
const BAR: usize = 12;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    if let Some(e) = app.live_estimate() {
        Paragraph::new(estimate_lines(app, e, area))
            .wrap(Wrap { trim: false })
            .block(frame("Prediction (live)"))
            .render(area, buf);
        return;
    }
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
            let mut v = vec![headline(app, "Predicted ", &pr.label)];
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
            if let Some(w) = &pv.windows {
                v.extend(vote_lines(w, None, area));
                return Paragraph::new(v)
                    .wrap(Wrap { trim: false })
                    .block(block)
                    .render(area, buf);
            }
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

/// The predicted texture in bold, with its description.
fn headline(app: &App, lead: &str, label: &str) -> Line<'static> {
    let tex = app.profile.profile.texture(label);
    Line::from(vec![
        Span::raw(lead.to_string()),
        Span::styled(
            label.to_string(),
            Style::new().add_modifier(Modifier::BOLD | Modifier::REVERSED),
        ),
        Span::raw(match tex {
            Some(t) if !t.description.is_empty() => format!(" — {}", t.description),
            _ => String::new(),
        }),
    ])
}

/// A vote over sub-windows: how sure it is ("S2 3 of 4 windows, 75 %",
/// and how many of `all` are done while a scan runs), a bar of sub-windows
/// per class when there is room, and each sub-window's label in order
/// (`·` for those to come).
fn vote_lines(p: &RecordingPrediction, all: Option<usize>, area: Rect) -> Vec<Line<'static>> {
    let done = p.windows.len();
    let top = p.tally.first().map_or(0, |t| t.windows);
    let so_far = match all {
        Some(n) => format!("; {done} of {} analysed", plural(n, "window", "windows")),
        None => String::new(),
    };
    let mut v = vec![Line::raw(format!(
        "{} {top} of {}, {:.0} %{so_far}",
        p.label,
        plural(done, "window", "windows"),
        p.agreement() * 100.0
    ))];
    // Classes some sub-window chose; the rest only had neighbour votes.
    let chosen: Vec<_> = p.tally.iter().filter(|t| t.windows > 0).collect();
    let rows = usize::from(area.height.saturating_sub(2));
    if rows > 5 + chosen.len() {
        for t in &chosen {
            let bar = "█".repeat(t.windows * BAR / done.max(1));
            let noun = if t.windows == 1 { "window " } else { "windows" };
            v.push(Line::raw(format!(
                "{:>6} {:>3} {noun} {bar}",
                t.label, t.windows
            )));
        }
    }
    let mut each: Vec<String> = p.windows.iter().map(|w| w.label.clone()).collect();
    each.extend(std::iter::repeat_n(
        "·".to_string(),
        all.unwrap_or(done).saturating_sub(done),
    ));
    v.push(Line::raw(format!("windows: {}", each.join(" "))));
    v
}

/// The live estimate of the scan running (or just ended).
fn estimate_lines(app: &App, e: &Estimate, area: Rect) -> Vec<Line<'static>> {
    if let Some(err) = &e.error {
        return vec![Line::raw(format!("no live estimate: {err}"))];
    }
    let status = if e.running {
        "the scan runs: the vote so far"
    } else {
        "the scan ended: the stored recording's vote follows"
    };
    let Some(p) = &e.current else {
        let (scale, unit) = unit_of(&e.axis);
        let first = e.sub_windows.first().map_or(String::new(), |w| {
            format!("; the first ends at {:.1} {unit}", w[1] * scale)
        });
        return vec![
            Line::raw(format!(
                "Live estimate: 0 of {} analysed{first}",
                plural(e.windows(), "window", "windows")
            )),
            Line::raw(status),
        ];
    };
    let mut v = vec![headline(app, "Estimate ", &p.label), Line::raw(status)];
    v.extend(vote_lines(p, Some(e.windows()), area));
    v
}
