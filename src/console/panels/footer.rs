//! The header line (profile, mode, page tabs) and the footer: the keys that
//! matter now, then the status line, marked `!` for a warning and `ERROR:`
//! for an error so that nothing rests on colour alone.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Widget;

use super::{Page, cut_at_word};
use crate::console::app::{App, Level};
use crate::console::form::Overlay;
use crate::console::keymap::Key;
use crate::servo::Mode;

pub fn render_header(app: &App, pages: &[Page], area: Rect, buf: &mut Buffer) {
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let mut spans = vec![Span::styled(
        " hapticlab ",
        bold.add_modifier(Modifier::REVERSED),
    )];
    match &app.replay {
        Some(r) => {
            let name = r
                .selected_path()
                .and_then(|p| p.file_name())
                .map_or(String::new(), |n| n.to_string_lossy().into_owned());
            spans.push(Span::raw(format!(" replay {name} ")));
        }
        None => spans.push(Span::raw(format!(
            " {} · {} mode ",
            app.profile.profile.name,
            app.mode().name()
        ))),
    }
    if pages.len() > 1 {
        let current = app.page % pages.len();
        spans.push(Span::raw("│"));
        for (i, p) in pages.iter().enumerate() {
            if i == current {
                spans.push(Span::styled(
                    format!(" [{} {}] ", i + 1, p.name),
                    bold.add_modifier(Modifier::REVERSED),
                ));
            } else {
                spans.push(Span::raw(format!(" {} {} ", i + 1, p.name)));
            }
        }
    }
    Line::from(spans).render(area, buf);
}

/// The key hints for what is on screen now, most important first: an
/// open overlay's keys, a running scan's, the replay's, or the idle console's.
pub fn hints(app: &App) -> Vec<(String, &'static str)> {
    let k = |key| app.keys.name(key);
    let s = |t: &str| t.to_string();
    match &app.overlay {
        Some(Overlay::Help) => return vec![(s("any key"), "closes the help")],
        Some(Overlay::ConfirmQuit) => {
            let mut v = vec![(s("y"), "quit")];
            if app.unsaved_scan() {
                v.push((s("w"), "store it, then quit"));
            }
            v.push((
                s("any other key"),
                if app.scan_busy() {
                    "stay, the scan goes on"
                } else {
                    "stay"
                },
            ));
            return v;
        }
        Some(Overlay::ConfirmAbort) => {
            return vec![
                (s("y"), "abort the scan"),
                (s("any other key"), "keep scanning"),
            ];
        }
        Some(Overlay::Messages { .. }) => {
            return vec![
                (s("↑↓ PgUp/PgDn"), "scroll"),
                (s("any other key"), "closes the log"),
            ];
        }
        Some(Overlay::Sessions(_)) => {
            return vec![
                (s("1-9"), "open that session"),
                (s("n"), "start today's"),
                (s("any other key"), "stay"),
            ];
        }
        Some(Overlay::Form(f)) => {
            let mut v = vec![(s("Enter"), "ok"), (s("Esc"), "close the form")];
            if f.fields.len() > 1 {
                v.push((s("Tab"), "next field"));
            }
            return v;
        }
        None => {}
    }
    if app.replay.is_some() {
        // Leaving first, then the list and the curating keys; the player's
        // last (a narrow footer ends with "? more", and help has them all).
        let mut v = vec![(k(Key::Help), "help")];
        if app.source != crate::console::app::Source::ReplayOnly {
            v.push((k(Key::Abort), "back"));
        }
        v.extend([
            (k(Key::Quit), "quit"),
            (format!("{}{}", k(Key::Up), k(Key::Down)), "recording"),
            (k(Key::Predict), "predict"),
            (k(Key::Jump), "to label"),
            (k(Key::NextWrong), "next wrong"),
            (k(Key::Filter), "filter"),
            (k(Key::Delete), "delete"),
            (k(Key::Exclude), "exclude"),
            (k(Key::Relabel), "relabel"),
            (k(Key::Undo), "undo"),
            (format!("{}/{}", k(Key::Away), k(Key::Toward)), "page"),
            (format!("{}/{}", k(Key::First), k(Key::Last)), "ends"),
            (k(Key::Pause), "pause"),
            (format!("{}/{}", k(Key::Faster), k(Key::Slower)), "speed"),
            (k(Key::Step), "step"),
            (k(Key::Left), "restart"),
        ]);
        return v;
    }
    if app.scan_busy() {
        let abort = if app.queue_left > 0 {
            "abort scan + queue (asks)"
        } else {
            "abort the scan (asks)"
        };
        return vec![
            (k(Key::Help), "help"),
            (k(Key::Abort), abort),
            (k(Key::Quit), "quit (asks)"),
            (format!("{}/{}", k(Key::Faster), k(Key::Slower)), "speed"),
            (k(Key::Predict), "predict last"),
        ];
    }
    // Help and quit first: keys that do not fit are dropped from the end,
    // and these two must always show.
    let mut v = vec![
        (k(Key::Help), "help"),
        (k(Key::Quit), "quit"),
        (k(Key::Start), "start"),
    ];
    if app.mode() != Mode::Manual {
        v.push((k(Key::Abort), "stop"));
    }
    v.extend([
        (k(Key::Store), "store"),
        (k(Key::Predict), "predict"),
        (k(Key::Mode), "mode"),
        (k(Key::Target), "target"),
        (k(Key::Label), "label"),
        (k(Key::Queue), "queue"),
        (k(Key::Train), "train"),
        (k(Key::Evaluate), "evaluate"),
        (k(Key::Replay), "replay"),
    ]);
    v
}

pub fn render_footer(app: &App, pages: &[Page], area: Rect, buf: &mut Buffer) {
    if area.height == 0 {
        return;
    }
    let width = usize::from(area.width);
    let mut used = 0;
    let mut spans = Vec::new();
    let pager = if pages.len() > 1 {
        format!(
            " {}: page {}/{}",
            app.keys.name(Key::NextPage),
            app.page % pages.len() + 1,
            pages.len()
        )
    } else {
        String::new()
    };
    let hints = hints(app);
    let len = |(key, what): &(String, &str)| key.chars().count() + what.chars().count() + 2;
    let mut room = width.saturating_sub(pager.chars().count());
    // Keys that do not fit: a sign that help lists them all.
    let more = format!("{} more", app.keys.name(Key::Help));
    let cut = hints.iter().map(len).sum::<usize>() > room;
    if cut {
        room = room.saturating_sub(more.chars().count() + 1);
    }
    for h in hints {
        if used + len(&h) > room {
            break;
        }
        used += len(&h);
        let (key, what) = h;
        spans.push(Span::styled(
            key,
            Style::new().add_modifier(Modifier::BOLD | Modifier::REVERSED),
        ));
        spans.push(Span::raw(format!(" {what} ")));
    }
    if cut {
        spans.push(Span::raw(format!("{more} ")));
        used += more.chars().count() + 1;
    }
    spans.push(Span::raw(format!(
        "{:>w$}",
        pager,
        w = width.saturating_sub(used)
    )));
    Line::from(spans).render(Rect { height: 1, ..area }, buf);
    if area.height < 2 {
        return;
    }
    let (prefix, style) = match app.status.level {
        Level::Info => ("", Style::new()),
        Level::Warn => ("! ", Style::new().fg(Color::Yellow)),
        Level::Error => (
            "ERROR: ",
            Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
        ),
    };
    // A message too long for the line is cut with a sign that the log has it whole.
    let full = format!("{prefix}{}", app.status.text);
    let status = if full.chars().count() <= width {
        full
    } else {
        let more = format!(" {} log", app.keys.name(Key::Messages));
        let cut = cut_at_word(&full, width.saturating_sub(more.chars().count()));
        format!("{cut}{more}")
    };
    Line::styled(status, style).render(
        Rect {
            y: area.y + 1,
            height: 1,
            ..area
        },
        buf,
    );
}
