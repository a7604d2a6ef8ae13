//! The terminal checks: size, TERM, colour.

use super::{Check, MIN_TERMINAL, Status, TerminalFacts, check, with_fix};

/// The terminal the console would draw on.
pub fn terminal_checks(t: &TerminalFacts) -> Vec<Check> {
    let (w, h) = MIN_TERMINAL;
    let size = if !t.stdout_is_terminal {
        check(
            "terminal",
            Status::Note,
            format!(
                "standard output is not a terminal (piped or redirected): size not checked; the console needs at least {w}×{h}"
            ),
        )
    } else {
        match t.size {
            None => with_fix(
                check(
                    "terminal",
                    Status::Warn,
                    "a terminal, but its size cannot be read",
                ),
                format!("run the console in a terminal emulator of at least {w}×{h}"),
            ),
            Some((cols, rows)) if cols < w || rows < h => with_fix(
                check(
                    "terminal",
                    Status::Warn,
                    format!(
                        "{cols}×{rows} is smaller than the console's {w}×{h}: panels will be cut"
                    ),
                ),
                format!("make the window at least {w} columns by {h} rows (or use a smaller font)"),
            ),
            Some((cols, rows)) => check(
                "terminal",
                Status::Ok,
                format!("{cols}×{rows} (the console needs at least {w}×{h})"),
            ),
        }
    };
    let term = t.term.as_deref().filter(|s| !s.is_empty());
    let unusable = match term {
        None => Some("TERM is not set".to_string()),
        Some("dumb") => Some("TERM=dumb: no cursor movement".to_string()),
        Some(_) => None,
    };
    let term_check = match (&unusable, t.stdout_is_terminal) {
        (None, _) => check(
            "term",
            Status::Ok,
            format!("TERM={}", term.unwrap_or_default()),
        ),
        (Some(why), false) => check(
            "term",
            Status::Note,
            format!("{why} (fine for the commands; the console needs a real terminal type)"),
        ),
        (Some(why), true) => with_fix(
            check(
                "term",
                Status::Warn,
                format!("{why}: the console cannot draw"),
            ),
            "run the console in a terminal emulator, or `export TERM=xterm-256color`",
        ),
    };
    let colour = if t.no_color {
        check(
            "colour",
            Status::Note,
            "NO_COLOR is set: the console draws without colour (status words and marks carry the meaning)",
        )
    } else if unusable.is_some() || term.is_some_and(|s| s.contains("mono")) {
        check(
            "colour",
            Status::Note,
            format!("no colour with TERM={}", term.unwrap_or("(unset)")),
        )
    } else {
        let depth = match t.colorterm.as_deref() {
            Some("truecolor" | "24bit") => "24-bit colour",
            _ if term.is_some_and(|s| s.contains("256")) => "256 colours",
            _ => "basic colours",
        };
        check(
            "colour",
            Status::Ok,
            format!(
                "{depth} (TERM={}{}); the console uses the 16 basic colours",
                term.unwrap_or_default(),
                t.colorterm
                    .as_deref()
                    .map_or(String::new(), |c| format!(", COLORTERM={c}"))
            ),
        )
    };
    vec![size, term_check, colour]
}
