//! The Surface trace panel: the signal (the probe's height y) against the
//! distance along the stroke for the last scan, or the one being replayed,
//! zoomed to the analysis window so the window fills the panel's width (the
//! thesis's Figs 4.5a–4.8a). The signal axis spans at least half a
//! millimetre (0.1 N for a force), so a flat texture draws a flat line with
//! its noise. A scan that stops before the window shows its whole stroke.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph, Widget, Wrap};

use super::{bounds, bounds_spanning, fit_title, frame};
use crate::console::app::App;
use crate::console::scan::unit_of;

/// The smallest span of the signal axis, by unit.
fn min_span(unit: &str) -> f64 {
    match unit {
        "mm" => 0.5,
        "N" => 0.1,
        _ => 0.0,
    }
}

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let Some(s) = app.scan() else {
        // The first scan's trace is drawn once the scan ends and is analysed.
        let text = if app.scan_running || app.scan_saving {
            "the first scan is running: its trace shows when it ends".to_string()
        } else {
            format!(
                "no scan yet: press {} (in any mode) to run the waypoint path and record the stroke",
                app.keys.name(crate::console::keymap::Key::Start)
            )
        };
        Paragraph::new(text)
            .wrap(Wrap { trim: true })
            .block(frame("Surface trace"))
            .render(area, buf);
        return;
    };
    let (_, au) = unit_of(&s.axis);
    let (_, su) = unit_of(&s.channel);
    let name = s
        .path
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let (signal, axis) = (
        s.channel.trim_end_matches("_m"),
        s.axis.trim_end_matches("_m"),
    );
    let [w0, w1] = s.window;
    // The window's points, with one on each side so the curve meets the edges.
    let first = s.trace.iter().position(|p| p.0 >= w0);
    let last = s.trace.iter().rposition(|p| p.0 <= w1);
    let zoomed = match (first, last) {
        (Some(a), Some(b)) if b > a => {
            Some(&s.trace[a.saturating_sub(1)..(b + 2).min(s.trace.len())])
        }
        _ => None,
    };
    let window = format!("{w0:.1}–{w1:.1} {au}");
    let titles: Vec<String> = if zoomed.is_some() {
        vec![
            format!("Surface trace: {signal} vs {axis} in the window {window} — {name}"),
            format!("Surface trace: {signal} vs {axis}, window {window}"),
            format!("Surface trace, window {window}"),
            "Surface trace".into(),
        ]
    } else {
        vec![
            format!("Surface trace: {signal} vs {axis} — {name} ends before the window {window}"),
            format!("Surface trace: ends before the window {window}"),
            "Surface trace: short of the window".into(),
            "Surface trace".into(),
        ]
    };
    let title = fit_title(&titles, area.width);
    if s.trace.is_empty() {
        Paragraph::new("the scan has no samples")
            .block(frame(&title))
            .render(area, buf);
        return;
    }
    let (points, [xlo, xhi]) = match zoomed {
        Some(p) => (p, [w0, w1]),
        None => (&s.trace[..], bounds(s.trace.iter().map(|p| p.0))),
    };
    let [ylo, yhi] = bounds_spanning(
        points
            .iter()
            .filter(|p| (xlo..=xhi).contains(&p.0))
            .map(|p| p.1),
        min_span(su),
    );
    let datasets = vec![
        Dataset::default()
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .data(points),
    ];
    Chart::new(datasets)
        .block(frame(&title))
        .x_axis(Axis::default().bounds([xlo, xhi]).labels([
            format!("{xlo:.1}"),
            format!("{axis} {au}"),
            format!("{xhi:.1}"),
        ]))
        .y_axis(Axis::default().bounds([ylo, yhi]).labels([
            format!("{ylo:.2}"),
            su.to_string(),
            format!("{yhi:.2}"),
        ]))
        .legend_position(None)
        .render(area, buf);
}
