//! Drawing the console: `impl Widget for &App`, a pure function of the
//! app's state (it borrows the app and never changes it).
//!
//! One panel per file under `panels/`, each `pub fn render(&App, Rect, &mut
//! Buffer)`. The screen is a header line, the panels of the current page,
//! and a two-line footer (keys, then the status line). How many pages there
//! are depends on the terminal's size:
//!
//! ```text
//! large (≥ 150×44): one page with everything
//! ┌Device──────┐┌Position──┐┌Workspace (top │ side)──────────────┐
//! │backend,LED │└──────────┘│  x→ z↓          │  x→ y↑            │
//! │mode, rate  │┌Force─────┐│                 │                   │
//! └────────────┘└──────────┘└───────────────────────────────────┘
//! ┌Traces (y, fy)──────────────┐┌Surface trace (y against x)──────┐
//! └────────────────────────────┘└─────────────────────────────────┘
//! ┌Spectrum────────┐┌Prediction─────────┐┌Dataset────────────────┐
//! └────────────────┘└───────────────────┘└───────────────────────┘
//!
//! medium (≥ 100×30), page 1 Live: the whole dashboard but the Dataset
//! ┌Device──────┐┌Position──┐┌Workspace────────────────────────────┐
//! │            │└──────────┘│                                     │
//! │            │┌Force─────┐│                                     │
//! └────────────┘└──────────┘└─────────────────────────────────────┘
//! ┌Traces (y, fy)─────────────────┐┌Surface trace (the window)───────┐
//! └───────────────────────────────┘└─────────────────────────────────┘
//! ┌Spectrum───────────────────────┐┌Prediction───────────────────────┐
//! └───────────────────────────────┘└─────────────────────────────────┘
//! page 2 Analysis = Surface trace, Spectrum │ Prediction, Dataset
//!
//! small (80×24): 1 Live = Device │ Position/Force over Traces;
//! 2 Scan = Surface trace over Spectrum │ Prediction; 3 Workspace =
//! Workspace │ Position/Force; 4 Dataset = Dataset
//! ```
//! In a replay the Dataset panel's place shows the list of recordings.

pub mod dataset;
pub mod device;
pub mod footer;
pub mod force;
pub mod overlay;
pub mod position;
pub mod prediction;
pub mod recordings;
pub mod spectrum;
pub mod surface;
pub mod traces;
pub mod workspace;

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Widget};

use super::app::App;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Panel {
    Device,
    Position,
    Force,
    Traces,
    Surface,
    Spectrum,
    Prediction,
    Workspace,
    Dataset,
}

/// A page: its name in the tab bar and how it places its panels.
pub struct Page {
    pub name: &'static str,
    pub place: fn(Rect) -> Vec<(Panel, Rect)>,
}

const LARGE: [Page; 1] = [Page {
    name: "All",
    place: large,
}];
const MEDIUM: [Page; 2] = [
    Page {
        name: "Live",
        place: medium_live,
    },
    Page {
        name: "Analysis",
        place: medium_analysis,
    },
];
const SMALL: [Page; 4] = [
    Page {
        name: "Live",
        place: small_live,
    },
    Page {
        name: "Scan",
        place: small_scan,
    },
    Page {
        name: "Workspace",
        place: small_workspace,
    },
    Page {
        name: "Dataset",
        place: |r| vec![(Panel::Dataset, r)],
    },
];

/// The pages at a terminal size.
pub fn pages(width: u16, height: u16) -> &'static [Page] {
    if width >= 150 && height >= 44 {
        &LARGE
    } else if width >= 100 && height >= 30 {
        &MEDIUM
    } else {
        &SMALL
    }
}

fn position_force(r: Rect) -> Vec<(Panel, Rect)> {
    let [p, f] = Layout::vertical([Constraint::Length(6), Constraint::Min(5)]).areas(r);
    vec![(Panel::Position, p), (Panel::Force, f)]
}

fn top_row(r: Rect) -> Vec<(Panel, Rect)> {
    let [d, pf, w] = Layout::horizontal([
        Constraint::Length(40),
        Constraint::Length(34),
        Constraint::Min(30),
    ])
    .areas(r);
    let mut v = vec![(Panel::Device, d)];
    v.extend(position_force(pf));
    v.push((Panel::Workspace, w));
    v
}

fn large(r: Rect) -> Vec<(Panel, Rect)> {
    let [a, b, c] = Layout::vertical([
        Constraint::Length(TOP_ROW),
        Constraint::Fill(1),
        Constraint::Fill(1),
    ])
    .areas(r);
    let mut v = top_row(a);
    let [t, s] = Layout::horizontal([Constraint::Fill(1); 2]).areas(b);
    v.push((Panel::Traces, t));
    v.push((Panel::Surface, s));
    let [sp, pr, ds] = Layout::horizontal([
        Constraint::Percentage(34),
        Constraint::Percentage(33),
        Constraint::Percentage(33),
    ])
    .areas(c);
    v.extend([
        (Panel::Spectrum, sp),
        (Panel::Prediction, pr),
        (Panel::Dataset, ds),
    ]);
    v
}

/// The top row's height: the Device panel's nine rows and its frame.
const TOP_ROW: u16 = 11;

fn medium_live(r: Rect) -> Vec<(Panel, Rect)> {
    let [a, b, c] = Layout::vertical([
        Constraint::Length(TOP_ROW),
        Constraint::Fill(3),
        Constraint::Fill(2),
    ])
    .areas(r);
    let mut v = top_row(a);
    let [t, s] = Layout::horizontal([Constraint::Fill(1); 2]).areas(b);
    v.push((Panel::Traces, t));
    v.push((Panel::Surface, s));
    let [sp, pr] = Layout::horizontal([Constraint::Fill(1); 2]).areas(c);
    v.push((Panel::Spectrum, sp));
    v.push((Panel::Prediction, pr));
    v
}

fn medium_analysis(r: Rect) -> Vec<(Panel, Rect)> {
    let [l, rt] = Layout::horizontal([Constraint::Percentage(55), Constraint::Fill(1)]).areas(r);
    let [s, sp] = Layout::vertical([Constraint::Fill(1); 2]).areas(l);
    let [p, d] = Layout::vertical([Constraint::Fill(1); 2]).areas(rt);
    vec![
        (Panel::Surface, s),
        (Panel::Spectrum, sp),
        (Panel::Prediction, p),
        (Panel::Dataset, d),
    ]
}

fn small_live(r: Rect) -> Vec<(Panel, Rect)> {
    let [a, b] = Layout::vertical([Constraint::Length(11), Constraint::Fill(1)]).areas(r);
    let [d, pf] = Layout::horizontal([Constraint::Fill(1); 2]).areas(a);
    let mut v = vec![(Panel::Device, d)];
    v.extend(position_force(pf));
    v.push((Panel::Traces, b));
    v
}

fn small_scan(r: Rect) -> Vec<(Panel, Rect)> {
    let [s, b] = Layout::vertical([Constraint::Fill(1); 2]).areas(r);
    let [sp, p] = Layout::horizontal([Constraint::Fill(1); 2]).areas(b);
    vec![
        (Panel::Surface, s),
        (Panel::Spectrum, sp),
        (Panel::Prediction, p),
    ]
}

fn small_workspace(r: Rect) -> Vec<(Panel, Rect)> {
    let [w, pf] = Layout::horizontal([Constraint::Fill(1), Constraint::Length(34)]).areas(r);
    let mut v = vec![(Panel::Workspace, w)];
    v.extend(position_force(pf));
    v
}

/// A panel's frame: a bordered block with its title in bold.
pub fn frame(title: &str) -> Block<'static> {
    Block::bordered().title(Line::styled(
        format!(" {title} "),
        Style::new().add_modifier(Modifier::BOLD),
    ))
}

/// A panel's frame whose title fits `width` (the panel's): cut at a word
/// with `…` rather than cut off by the border without a sign.
pub fn frame_fit(title: &str, width: u16) -> Block<'static> {
    frame(&cut_at_word(title, usize::from(width).saturating_sub(4)))
}

/// Chart bounds around `values`, padded, never empty.
pub fn bounds(values: impl Iterator<Item = f64>) -> [f64; 2] {
    bounds_spanning(values, 0.0)
}

/// Chart bounds around `values` spanning at least `min_span`, centred on
/// the data: a probe holding still draws a flat line with its noise, not
/// encoder steps blown up to the panel's height.
pub fn bounds_spanning(values: impl Iterator<Item = f64>, min_span: f64) -> [f64; 2] {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return [-1.0, 1.0];
    }
    if hi - lo < min_span {
        let mid = (lo + hi) / 2.0;
        lo = mid - min_span / 2.0;
        hi = mid + min_span / 2.0;
    }
    let pad = ((hi - lo) * 0.08).max(1e-3);
    [lo - pad, hi + pad]
}

/// The first of `titles` (longest first) that fits a frame `width` wide;
/// the last one cut at a word, with `…`, when none does.
pub fn fit_title(titles: &[String], width: u16) -> String {
    // The frame's corners and the spaces around the title.
    let room = usize::from(width).saturating_sub(4);
    if let Some(t) = titles.iter().find(|t| t.chars().count() <= room) {
        return t.clone();
    }
    cut_at_word(titles.last().map_or("", String::as_str), room)
}

/// `text` cut at a word boundary to at most `width` characters, with `…`.
pub fn cut_at_word(text: &str, width: usize) -> String {
    if text.chars().count() <= width {
        return text.to_string();
    }
    if width == 0 {
        return String::new();
    }
    let head: String = text.chars().take(width - 1).collect();
    let cut = head.rfind(' ').map_or(head.as_str(), |i| &head[..i]);
    format!("{}…", cut.trim_end())
}

/// Lines cut at a word (with `…`) where they are wider than `width`; each
/// cut line keeps its first span's style.
pub fn fit_lines(lines: Vec<Line<'_>>, width: usize) -> Vec<Line<'static>> {
    lines
        .into_iter()
        .map(|l| {
            let style = l.spans.first().map_or(l.style, |s| l.style.patch(s.style));
            let text: String = l.spans.iter().map(|s| s.content.as_ref()).collect();
            Line::styled(cut_at_word(&text, width), style)
        })
        .collect()
}

/// A path shortened in the middle to `width` characters, keeping its start
/// and its file name: `recordings/…/S2_031.csv`.
pub fn elide_middle(text: &str, width: usize) -> String {
    let n = text.chars().count();
    if n <= width {
        return text.to_string();
    }
    if width < 3 {
        return text.chars().skip(n - width).collect();
    }
    let tail = (width - 1) * 2 / 3;
    let head = width - 1 - tail;
    let start: String = text.chars().take(head).collect();
    let end: String = text.chars().skip(n - tail).collect();
    format!("{start}…{end}")
}

/// Centimetres with two decimals, from metres.
pub fn cm(m: f64) -> String {
    format!("{:7.2}", m * 100.0)
}

/// Draw one panel.
pub fn render_panel(p: Panel, app: &App, area: Rect, buf: &mut Buffer) {
    match p {
        Panel::Device => device::render(app, area, buf),
        Panel::Position => position::render(app, area, buf),
        Panel::Force => force::render(app, area, buf),
        Panel::Traces => traces::render(app, area, buf),
        Panel::Surface => surface::render(app, area, buf),
        Panel::Spectrum => spectrum::render(app, area, buf),
        Panel::Prediction => prediction::render(app, area, buf),
        Panel::Workspace => workspace::render(app, area, buf),
        Panel::Dataset => {
            if app.replay.is_some() {
                recordings::render(app, area, buf)
            } else {
                dataset::render(app, area, buf)
            }
        }
    }
}

impl Widget for &App {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let [header, body, foot] = Layout::vertical([
            Constraint::Length(1),
            Constraint::Fill(1),
            Constraint::Length(2),
        ])
        .areas(area);
        let pages = pages(area.width, area.height);
        let page = &pages[self.page % pages.len()];
        footer::render_header(self, pages, header, buf);
        for (panel, rect) in (page.place)(body) {
            render_panel(panel, self, rect, buf);
        }
        footer::render_footer(self, pages, foot, buf);
        if let Some(o) = &self.overlay {
            overlay::render(self, o, area, buf);
        }
    }
}

#[cfg(test)]
mod svg;
#[cfg(test)]
mod tests;
