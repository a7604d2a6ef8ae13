//! The console's inputs besides telemetry: terminal events (keys, resizes)
//! polled without blocking longer than the rest of the frame, and the
//! signals that end the session cleanly (SIGINT, SIGTERM, SIGHUP raise a
//! flag; the loop sees it and shuts down the servo and restores the terminal).

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use ratatui::crossterm::event::{self, Event as TermEvent, KeyEvent, KeyEventKind};

#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    Key(KeyEvent),
    Resize(u16, u16),
}

/// The next terminal event, waiting at most `timeout`.
pub fn next(timeout: Duration) -> io::Result<Option<Event>> {
    if !event::poll(timeout)? {
        return Ok(None);
    }
    Ok(match event::read()? {
        TermEvent::Key(k) if k.kind != KeyEventKind::Release => Some(Event::Key(k)),
        TermEvent::Resize(w, h) => Some(Event::Resize(w, h)),
        _ => None,
    })
}

/// A flag raised by SIGINT, SIGTERM or SIGHUP.
#[derive(Clone)]
pub struct Signals(Arc<AtomicBool>);

impl Signals {
    pub fn register() -> io::Result<Signals> {
        let flag = Arc::new(AtomicBool::new(false));
        for sig in [
            signal_hook::consts::SIGINT,
            signal_hook::consts::SIGTERM,
            signal_hook::consts::SIGHUP,
        ] {
            signal_hook::flag::register(sig, flag.clone())?;
        }
        Ok(Signals(flag))
    }

    pub fn raised(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}
