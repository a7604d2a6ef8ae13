//! The Force panel: the force the servo commands, fx, fy, fz in newtons,
//! and its magnitude.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget};

use super::frame;
use crate::console::app::App;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let t = app.feed().latest;
    let f = t.map(|t| t.force_n);
    let fmt = |a: usize| f.map_or("     —".into(), |f| format!("{:+6.3}", f[a]));
    let mag = f.map_or("—".into(), |f| {
        format!("{:.3}", (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt())
    });
    let lines = vec![
        Line::raw(format!("fx {} N", fmt(0))),
        Line::raw(format!("fy {} N    |F| {mag} N", fmt(1))),
        Line::raw(format!("fz {} N", fmt(2))),
    ];
    Paragraph::new(lines)
        .block(frame("Force"))
        .render(area, buf);
}
