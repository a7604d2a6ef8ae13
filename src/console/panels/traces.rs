//! The Traces panel: the probe's height y (mm) and the vertical force fy
//! (N) over the last seconds, from the telemetry feed (live or replayed).
//! Each trace spans at least [`MIN_SPAN_MM`] or [`MIN_SPAN_N`], so a probe
//! holding still draws a flat line rather than its encoder steps; the name
//! and latest value sit on their own row above the curve, never over it.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph, Widget};

use super::{bounds_spanning, frame};
use crate::console::app::App;
use crate::console::feed::TRACE_SPAN_S;

/// The smallest span of the y trace, mm.
pub const MIN_SPAN_MM: f64 = 0.5;
/// The smallest span of the fy trace, N.
pub const MIN_SPAN_N: f64 = 0.1;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let block = frame(&format!("Traces (last {TRACE_SPAN_S:.0} s)"));
    let inner = block.inner(area);
    block.render(area, buf);
    let h = &app.feed().history;
    let Some(last) = h.back() else {
        Paragraph::new("no telemetry yet").render(inner, buf);
        return;
    };
    let y: Vec<(f64, f64)> = h
        .iter()
        .map(|p| (p.t_s - last.t_s, p.y_m * 1000.0))
        .collect();
    let fy: Vec<(f64, f64)> = h.iter().map(|p| (p.t_s - last.t_s, p.fy_n)).collect();
    let halves: [Rect; 2] = if inner.width >= 2 * inner.height + 20 {
        Layout::horizontal([Constraint::Fill(1); 2])
            .spacing(2)
            .areas(inner)
    } else {
        Layout::vertical([Constraint::Fill(1); 2]).areas(inner)
    };
    let y_now = format!("y {:+.3} mm", last.y_m * 1000.0);
    let fy_now = format!("fy {:+.3} N", last.fy_n);
    chart(&y, &y_now, MIN_SPAN_MM, halves[0], buf);
    chart(&fy, &fy_now, MIN_SPAN_N, halves[1], buf);
}

/// One trace: its name and latest value on the top row, the curve below.
fn chart(data: &[(f64, f64)], label: &str, min_span: f64, area: Rect, buf: &mut Buffer) {
    if area.height == 0 {
        return;
    }
    let [top, plot] = Layout::vertical([Constraint::Length(1), Constraint::Fill(1)]).areas(area);
    Line::raw(label.to_string()).render(top, buf);
    let [lo, hi] = bounds_spanning(data.iter().map(|p| p.1), min_span);
    let ds = Dataset::default()
        .marker(Marker::Braille)
        .graph_type(GraphType::Line)
        .data(data);
    Chart::new(vec![ds])
        .x_axis(
            Axis::default()
                .bounds([-TRACE_SPAN_S, 0.0])
                .labels([format!("-{TRACE_SPAN_S:.0} s"), "now".into()]),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([format!("{lo:.2}"), format!("{hi:.2}")]),
        )
        .legend_position(None)
        .render(plot, buf);
}
