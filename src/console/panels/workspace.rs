//! The Workspace panel: the end effector in the device's workspace, seen
//! from the top (x right, z toward you down) and from the side (x right, y
//! up), with the waypoint path numbered as in Table 3.1. The probe is `@`,
//! a Target-mode goal `+`.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::widgets::canvas::{Canvas, Context, Line as CLine, Rectangle};
use ratatui::widgets::{Block, Widget};

use super::frame;
use crate::console::app::App;
use crate::profile::{WORKSPACE_MAX_M, WORKSPACE_MIN_M};
use crate::servo::Mode;

/// A view: which axis is across, which is up (and whether it is flipped).
struct View {
    title: &'static str,
    across: usize,
    up: usize,
    flip: bool,
}

const TOP: View = View {
    title: "top: x→ z↓",
    across: 0,
    up: 2,
    flip: true,
};
const SIDE: View = View {
    title: "side: x→ y↑",
    across: 0,
    up: 1,
    flip: false,
};

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let block = frame("Workspace (cm)");
    let inner = block.inner(area);
    block.render(area, buf);
    let halves: [Rect; 2] = Layout::horizontal([Constraint::Fill(1); 2]).areas(inner);
    draw(app, &TOP, halves[0], buf);
    draw(app, &SIDE, halves[1], buf);
}

fn draw(app: &App, v: &View, area: Rect, buf: &mut Buffer) {
    let s = |p: [f64; 3], a: usize| {
        let x = p[a] * 100.0;
        if a == v.up && v.flip { -x } else { x }
    };
    let lo = |a: usize| {
        let (l, h) = (WORKSPACE_MIN_M[a] * 100.0, WORKSPACE_MAX_M[a] * 100.0);
        if a == v.up && v.flip { -h } else { l }
    };
    let span = |a: usize| (WORKSPACE_MAX_M[a] - WORKSPACE_MIN_M[a]) * 100.0;
    let (x0, y0) = (lo(v.across), lo(v.up));
    let (w, h) = (span(v.across), span(v.up));
    // An analysis-only profile (replay) has no path to draw.
    let wps: &[[f64; 3]] = app
        .profile
        .profile
        .path
        .as_ref()
        .map_or(&[], |p| &p.waypoints_m);
    let probe = app.feed().latest.map(|t| t.pos_m);
    let target = (app.replay.is_none() && app.mode() == Mode::Target)
        .then_some(app.target_m)
        .flatten();
    let paint = |ctx: &mut Context| {
        ctx.draw(&Rectangle {
            x: x0,
            y: y0,
            width: w,
            height: h,
            color: Color::DarkGray,
        });
        for pair in wps.windows(2) {
            ctx.draw(&CLine::new(
                s(pair[0], v.across),
                s(pair[0], v.up),
                s(pair[1], v.across),
                s(pair[1], v.up),
                Color::Cyan,
            ));
        }
        ctx.layer();
        for (i, p) in wps.iter().enumerate() {
            ctx.print(s(*p, v.across), s(*p, v.up), format!("{}", i + 1));
        }
        if let Some(t) = target {
            ctx.print(s(t, v.across), s(t, v.up), "+");
        }
        if let Some(p) = probe {
            ctx.print(s(p, v.across), s(p, v.up), "@");
        }
    };
    Canvas::default()
        .block(Block::new().title(v.title))
        .marker(Marker::Braille)
        .x_bounds([x0, x0 + w])
        .y_bounds([y0, y0 + h])
        .paint(paint)
        .render(area, buf);
}
