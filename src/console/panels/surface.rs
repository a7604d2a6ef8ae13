//! The Surface trace panel: the signal (the probe's height y) against the
//! distance along the stroke for the last scan, or the one being replayed,
//! with the analysis window marked by two dotted columns (the thesis's
//! Figs 4.5a–4.8a).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph, Widget, Wrap};

use super::{bounds, frame};
use crate::console::app::App;
use crate::console::scan::unit_of;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let Some(s) = app.scan() else {
        Paragraph::new(
            "no scan yet: press s (in any mode) to run the waypoint path and record the stroke",
        )
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
    let title = format!(
        "Surface trace: {} vs {} — {name}, window {:.1}–{:.1} {au} between ••",
        s.channel.trim_end_matches("_m"),
        s.axis.trim_end_matches("_m"),
        s.window[0],
        s.window[1]
    );
    if s.trace.is_empty() {
        Paragraph::new("the scan has no samples")
            .block(frame(&title))
            .render(area, buf);
        return;
    }
    let [xlo, xhi] = bounds(s.trace.iter().map(|p| p.0).chain(s.window));
    let [ylo, yhi] = bounds(s.trace.iter().map(|p| p.1));
    let edge = |x: f64| -> Vec<(f64, f64)> {
        (0..=40)
            .map(|i| (x, ylo + (yhi - ylo) * f64::from(i) / 40.0))
            .collect()
    };
    let (e0, e1) = (edge(s.window[0]), edge(s.window[1]));
    let datasets = vec![
        Dataset::default()
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .data(&s.trace),
        Dataset::default()
            .marker(Marker::Dot)
            .graph_type(GraphType::Scatter)
            .data(&e0),
        Dataset::default()
            .marker(Marker::Dot)
            .graph_type(GraphType::Scatter)
            .data(&e1),
    ];
    Chart::new(datasets)
        .block(frame(&title))
        .x_axis(Axis::default().bounds([xlo, xhi]).labels([
            format!("{xlo:.0}"),
            format!("{:.0} {au}", (xlo + xhi) / 2.0),
            format!("{xhi:.0}"),
        ]))
        .y_axis(Axis::default().bounds([ylo, yhi]).labels([
            format!("{ylo:.2}"),
            su.to_string(),
            format!("{yhi:.2}"),
        ]))
        .legend_position(None)
        .render(area, buf);
}
