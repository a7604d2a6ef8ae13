//! The Device panel: the backend, the homed state (the thesis's LED, as
//! words), the mode, the servo's rate and 99th-percentile period error,
//! dropped telemetry, and the scan in progress. In a replay: the recording,
//! its clock and the replay speed.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::{elide_middle, frame};
use crate::console::app::{App, Source};

fn row<'a>(name: &'a str, value: impl Into<Span<'a>>) -> Line<'a> {
    Line::from(vec![
        Span::styled(
            format!("{name:<8} "),
            Style::new().add_modifier(Modifier::DIM),
        ),
        value.into(),
    ])
}

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    // Room for a value after its 9-column name.
    let room = usize::from(area.width.saturating_sub(2 + 9));
    let lines = match &app.replay {
        Some(r) => replay_lines(app, r, room),
        None => live_lines(app, room),
    };
    // Wrapped at words: a long value (the homing advice) pushes the rows
    // below it down rather than being cut mid-word.
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(frame("Device"))
        .render(area, buf);
}

fn live_lines(app: &App, room: usize) -> Vec<Line<'_>> {
    let backend = match &app.source {
        Source::Live { backend } if backend == "sim" => "sim (simulated Falcon)".to_string(),
        Source::Live { backend } => backend.clone(),
        Source::ReplayOnly => "none (replay only)".into(),
    };
    let t = app.live.latest;
    let mut lines = vec![row("Backend", backend)];
    lines.push(row(
        "Texture",
        match &app.mounted {
            Some(m) => format!("{m} mounted, label {}", app.label),
            None => format!("label {}", app.label),
        },
    ));
    lines.push(match t {
        None => row("Homed", "waiting for the device…"),
        Some(t) if t.homed => row(
            "Homed",
            Span::styled("yes (LED blue)", Style::new().fg(Color::Blue)),
        ),
        Some(_) => row(
            "Homed",
            Span::styled(
                "NO (LED red): pull the grip all the way out, then push it back in",
                Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
            ),
        ),
    });
    lines.push(row(
        "Mode",
        format!("{}   speed ×{:.2}", app.mode().name(), app.speed_scale),
    ));
    match t {
        Some(t) if t.stats.ticks > 0 => {
            lines.push(row(
                "Servo",
                format!(
                    "{:.0} Hz, p99 error {:.0} µs",
                    t.stats.rate_hz, t.stats.period_error_p99_us
                ),
            ));
            lines.push(row(
                "Dropped",
                format!(
                    "{} telemetry; {} late ticks",
                    t.stats.dropped_telemetry, t.stats.missed_deadlines
                ),
            ));
            // Late ticks in a row that would stop a motion, while nothing
            // moves: a busy machine, worth a warning, not an alarm.
            let limit = app
                .profile
                .profile
                .device
                .as_ref()
                .map_or(u32::MAX, |d| d.missed_deadline_streak);
            if t.stats.longest_missed_streak >= limit {
                lines.push(row(
                    "Late",
                    Span::styled(
                        format!(
                            "! {} ticks late in a row: the machine is busy (nothing was moving)",
                            t.stats.longest_missed_streak
                        ),
                        Style::new().fg(Color::Yellow),
                    ),
                ));
            }
            if let Some(l) = t.stats.link {
                lines.push(row(
                    "Link",
                    format!(
                        "{} missed replies; {} saturated ticks",
                        l.missed_replies, l.saturated_ticks
                    ),
                ));
            }
        }
        _ => {
            lines.push(row("Servo", "starting…"));
            lines.push(row("Dropped", "0 telemetry"));
        }
    }
    let scan = if let Some(t) = t.filter(|t| t.scanning) {
        format!("stroke {:.0} % recorded", t.scan_progress * 100.0)
    } else if app.scan_running {
        "path to the texture…".to_string()
    } else if let Some(s) = &app.last_scan {
        match (&s.stored, s.complete) {
            (Some(_), _) => "idle; last stored".into(),
            (None, true) => "idle; last NOT stored".into(),
            (None, false) => "idle; last incomplete".into(),
        }
    } else {
        "idle".into()
    };
    lines.push(row("Scan", scan));
    if app.queue_total > 0 {
        lines.push(row(
            "Queue",
            format!(
                "{} of {} stored, {} to start",
                app.queue_stored, app.queue_total, app.queue_left
            ),
        ));
    }
    lines.push(row(
        "Dataset",
        elide_middle(&app.dataset.dir.display().to_string(), room),
    ));
    lines
}

fn replay_lines<'a>(
    app: &'a App,
    r: &'a crate::console::replay::Replay,
    room: usize,
) -> Vec<Line<'a>> {
    let mut lines = vec![row("Backend", "replay of a recording")];
    let name = r
        .selected_path()
        .and_then(|p| p.file_name())
        .map_or("(none)".into(), |n| n.to_string_lossy().into_owned());
    lines.push(row("File", elide_middle(&name, room)));
    if let Some(s) = &r.scan {
        lines.push(row(
            "Label",
            format!(
                "{}{}",
                s.label.as_deref().unwrap_or("(none)"),
                if s.complete { "" } else { ", incomplete" }
            ),
        ));
    }
    match &r.player {
        Some(p) => {
            let state = if p.finished() {
                "ended (space replays)"
            } else if p.paused {
                "paused"
            } else {
                "playing"
            };
            lines.push(row(
                "Clock",
                format!("{:.2} / {:.2} s", p.position_s(), p.duration_s()),
            ));
            lines.push(row("Speed", format!("{}×, {state}", p.speed)));
        }
        None => lines.push(row(
            "Clock",
            r.error
                .clone()
                .unwrap_or_else(|| "no recording open".into()),
        )),
    }
    lines.push(row("Mode", "Test (recorded)"));
    lines.push(row(
        "Model",
        match &app.dataset.model {
            Some(m) => format!("k-NN, {} examples", m.examples),
            None if r.listing => "training…".into(),
            None => "none".into(),
        },
    ));
    lines
}
