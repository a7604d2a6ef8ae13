//! The Position panel: the probe's x, y, z in cm beside the set-point the
//! servo is steering to and, in Target mode, the target typed or nudged.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget};

use super::{cm, frame};
use crate::console::app::App;
use crate::servo::Mode;

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let t = app.feed().latest;
    let target = match (app.replay.is_some(), app.mode()) {
        (false, Mode::Target) => app.target_m,
        _ => None,
    };
    let mut lines = vec![Line::styled(
        "cm      actual  set-pt  target",
        Style::new().add_modifier(Modifier::DIM),
    )];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let actual = t.map_or("      —".into(), |t| cm(t.pos_m[a]));
        let set = match t {
            Some(t) if t.mode != Mode::Manual => cm(t.setpoint_m[a]),
            _ => "      —".into(),
        };
        let tgt = target.map_or("      —".into(), |m| cm(m[a]));
        lines.push(Line::raw(format!("{name}    {actual} {set} {tgt}")));
    }
    Paragraph::new(lines)
        .block(frame("Position"))
        .render(area, buf);
}
