//! The Traces panel: the probe's height y (mm) and the vertical force fy
//! (N) over the last seconds, from the telemetry feed (live or replayed).

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph, Widget};

use super::{bounds, frame};
use crate::console::app::App;
use crate::console::feed::TRACE_SPAN_S;

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
    chart(&y, "y mm", last.y_m * 1000.0, halves[0], buf);
    chart(&fy, "fy N", last.fy_n, halves[1], buf);
}

fn chart(data: &[(f64, f64)], name: &str, now: f64, area: Rect, buf: &mut Buffer) {
    let [lo, hi] = bounds(data.iter().map(|p| p.1));
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
        .render(area, buf);
    // The name and the latest value, top left inside the chart.
    let label = Line::raw(format!("{name} {now:+.3}"));
    let r = Rect::new(
        area.x + 1,
        area.y,
        area.width.saturating_sub(1),
        1.min(area.height),
    );
    if area.width > 12 {
        label.render(
            Rect::new(
                r.x + 7.min(r.width),
                r.y,
                r.width.saturating_sub(7),
                r.height,
            ),
            buf,
        );
    }
}
