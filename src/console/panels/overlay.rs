//! Overlays drawn over the panels: the help screen (every key, from the key
//! map), the quit confirmation, and forms.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph, Widget, Wrap};

use super::{fit_lines, frame, frame_fit};
use crate::console::app::App;
use crate::console::app::Level;
use crate::console::form::{Form, Overlay};
use crate::console::keymap::Key;
use crate::console::session::Session;
use ratatui::style::Color;

fn centred(area: Rect, w: u16, h: u16) -> Rect {
    let w = w.min(area.width);
    let h = h.min(area.height);
    Rect::new(
        area.x + (area.width - w) / 2,
        area.y + (area.height - h) / 2,
        w,
        h,
    )
}

pub fn render(app: &App, o: &Overlay, area: Rect, buf: &mut Buffer) {
    match o {
        Overlay::Help => help(app, area, buf),
        Overlay::ConfirmQuit => confirm_quit(app, area, buf),
        Overlay::ConfirmAbort => {
            let r = centred(area, 60, 7);
            Clear.render(r, buf);
            let what = if app.queue_left > 0 {
                format!(
                    "Abort the running scan and the {} queued after it?",
                    app.queue_left
                )
            } else {
                "Abort the running scan?".to_string()
            };
            Paragraph::new(vec![
                Line::raw(what),
                Line::raw("Forces go off; its samples so far are kept as incomplete."),
                Line::raw(""),
                Line::raw("y: abort   any other key: keep scanning"),
            ])
            .wrap(Wrap { trim: true })
            .block(frame("Abort?"))
            .render(r, buf);
        }
        Overlay::Form(f) => form(f, area, buf),
        Overlay::Messages { scroll } => messages(app, *scroll, area, buf),
        Overlay::Sessions(list) => sessions(app, list, area, buf),
    }
}

/// The message log: newest first, each in full, wrapped; the header, the
/// footer (the log's keys) and the status line stay in sight.
fn messages(app: &App, scroll: usize, area: Rect, buf: &mut Buffer) {
    let r = centred(
        area,
        area.width.saturating_sub(4).max(20),
        area.height.saturating_sub(4),
    );
    Clear.render(r, buf);
    let mut lines = Vec::new();
    for s in app.log.iter().rev().skip(scroll) {
        let (mark, style) = match s.level {
            Level::Info => ("", Style::new()),
            Level::Warn => ("! ", Style::new().fg(Color::Yellow)),
            Level::Error => (
                "ERROR: ",
                Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
            ),
        };
        lines.push(Line::styled(format!("• {mark}{}", s.text), style));
    }
    let title = format!(
        "Messages: {} of {}, newest first",
        app.log.len().saturating_sub(scroll),
        app.log.len()
    );
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(frame_fit(&title, r.width))
        .render(r, buf);
}

/// The recent sessions to open, and today's new one.
fn sessions(app: &App, list: &[Session], area: Rect, buf: &mut Buffer) {
    let r = centred(area, 76, list.len() as u16 + 6);
    Clear.render(r, buf);
    let now = std::time::SystemTime::now();
    let mut lines: Vec<Line> = list
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let here = if s.dir == app.dataset.dir {
                "  (open)"
            } else {
                ""
            };
            Line::raw(format!(
                "{} {}  {}, {} stored{here}",
                i + 1,
                s.dir.display(),
                s.age(now),
                s.recordings
            ))
        })
        .collect();
    if list.is_empty() {
        lines.push(Line::raw(format!(
            "no session folders in {}",
            app.sessions_root().display()
        )));
    }
    lines.push(Line::raw(""));
    // `n` opens today's folder: new, already there, or the one open.
    let today = crate::console::session::today(&app.sessions_root(), now);
    let what = if today == app.dataset.dir {
        "today's session (open)"
    } else if today.is_dir() {
        "today's session"
    } else {
        "a new session"
    };
    lines.push(Line::raw(format!("n  {what}: {}", today.display())));
    Paragraph::new(fit_lines(lines, usize::from(r.width.saturating_sub(2))))
        .block(frame("Sessions"))
        .render(r, buf);
}

fn confirm_quit(app: &App, area: Rect, buf: &mut Buffer) {
    let r = centred(area, 60, 8);
    Clear.render(r, buf);
    let mut lines = Vec::new();
    if app.scan_busy() {
        let queued = if app.queue_left > 0 {
            format!(" ({} more queued)", app.queue_left)
        } else {
            String::new()
        };
        lines.push(Line::raw(format!(
            "A scan is running{queued}: quitting aborts it and keeps its samples as incomplete."
        )));
    } else if app.scan_saving {
        lines.push(Line::raw(
            "The scan that just ended is still being saved and analysed.",
        ));
    }
    if app.unsaved_scan() {
        let name = app
            .last_scan
            .as_ref()
            .map_or(String::new(), |s| s.path.display().to_string());
        // During a scan the unstored one is the scan before it.
        lines.push(Line::raw(if app.scan_busy() {
            format!("The scan before it is not stored in the dataset (it stays in {name}).")
        } else {
            format!("The last scan is not stored in the dataset (it stays in {name}).")
        }));
    }
    lines.push(Line::raw(""));
    lines.push(Line::raw(if app.unsaved_scan() {
        "y: quit anyway   w: store it, then quit   any other key: stay"
    } else {
        "y: quit anyway   any other key: stay"
    }));
    Paragraph::new(lines)
        .wrap(Wrap { trim: true })
        .block(frame("Quit?"))
        .render(r, buf);
}

fn form(f: &Form, area: Rect, buf: &mut Buffer) {
    let h = f.fields.len() as u16 + 6;
    let r = centred(area, 64, h);
    Clear.render(r, buf);
    let mut lines = Vec::new();
    for (i, field) in f.fields.iter().enumerate() {
        let focused = i == f.focus;
        lines.push(Line::from(vec![
            Span::raw(format!(
                "{} {:<8} ",
                if focused { ">" } else { " " },
                field.name
            )),
            Span::styled(
                format!("{}{}", field.text, if focused { "_" } else { "" }),
                if focused {
                    Style::new().add_modifier(Modifier::REVERSED)
                } else {
                    Style::new()
                },
            ),
        ]));
    }
    lines.push(Line::raw(""));
    match &f.error {
        Some(e) => lines.push(Line::styled(
            format!("ERROR: {e}"),
            Style::new().add_modifier(Modifier::BOLD),
        )),
        None => lines.push(Line::raw(f.hint.clone())),
    }
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(frame(f.title()))
        .render(r, buf);
}

fn help(app: &App, area: Rect, buf: &mut Buffer) {
    let k = |key| app.keys.name(key);
    let rows: Vec<(String, &str)> = vec![
        (
            k(Key::Mode),
            "cycle the mode: Manual (no forces) → Target → Test",
        ),
        (
            k(Key::Start),
            "start a measurement: run the waypoint path, record the stroke",
        ),
        (
            k(Key::Abort),
            "abort a scan or queue (asks first); stop motion; leave a replay",
        ),
        (
            k(Key::Store),
            "store the last scan as <dataset>/<label>/<label>_NNN.csv",
        ),
        (
            format!("{} {}", k(Key::Label), k(Key::Queue)),
            "label of the next scans (mounts its texture); queue N scans",
        ),
        (
            k(Key::Predict),
            "predict the scan on screen (trains first if no model)",
        ),
        (
            format!("{} {}", k(Key::Train), k(Key::Evaluate)),
            "train k-NN (saved as model.json); evaluate: confusion matrix",
        ),
        (
            format!(
                "{} {}{}{}{} {}/{}",
                k(Key::Target),
                k(Key::Left),
                k(Key::Right),
                k(Key::Up),
                k(Key::Down),
                k(Key::Away),
                k(Key::Toward)
            ),
            "type a target (cm), or nudge it 1 mm in x, y, z",
        ),
        (
            format!("{}/{}", k(Key::Faster), k(Key::Slower)),
            "path speed (replay: 1×, 4×, 16×)",
        ),
        (k(Key::Replay), "replay browser on the dataset folder"),
        (
            format!("{} {} {}", k(Key::Pause), k(Key::Step), k(Key::Left)),
            "replay: pause, single step, restart",
        ),
        (
            format!("↑↓ PgUp/PgDn {}/{}", k(Key::First), k(Key::Last)),
            "replay: a recording, a page, the first/last",
        ),
        (
            format!("{} {} {}", k(Key::Jump), k(Key::NextWrong), k(Key::Filter)),
            "replay: jump to a label, next WRONG, show one label",
        ),
        (
            format!(
                "{} {} {} {} {}",
                k(Key::Delete),
                k(Key::Exclude),
                k(Key::Relabel),
                k(Key::Store),
                k(Key::Undo)
            ),
            "replay: delete (.trash/), exclude, relabel, store, undo",
        ),
        (
            format!("{} {}", k(Key::Messages), k(Key::Sessions)),
            "the message log; recent sessions (open one, start today's)",
        ),
        (
            match app.page_count() {
                1 => k(Key::NextPage),
                n => format!("{} 1-{n}", k(Key::NextPage)),
            },
            "next page / page N (small terminals)",
        ),
        (
            k(Key::Quit),
            "quit (asks during a scan or queue, or if unsaved); Ctrl-C: now",
        ),
    ];
    let h = rows.len() as u16 + 5;
    let r = centred(area, 78, h);
    Clear.render(r, buf);
    let mut lines: Vec<Line> = rows
        .into_iter()
        .map(|(key, what)| {
            Line::from(vec![
                Span::styled(
                    format!("{key:>12} "),
                    Style::new().add_modifier(Modifier::BOLD),
                ),
                Span::raw(what.to_string()),
            ])
        })
        .collect();
    lines.push(Line::raw(
        "  any key closes; keys are set in the profile's [console] keys table",
    ));
    Paragraph::new(lines).block(frame("Keys")).render(r, buf);
}
