//! The console's inputs besides telemetry: terminal events (keys, resizes)
//! and the signals that end the session cleanly (SIGINT, SIGTERM, SIGHUP
//! raise a flag; the loop sees it, stops the servo, then restores the
//! terminal).
//!
//! Terminal events are read on their own thread and handed over through a
//! channel, which the loop waits on for no longer than the rest of the
//! frame. The thread is there because crossterm's reader spins without
//! returning once the terminal is closed under it (a read of 0 bytes is
//! retried forever): the loop must stay free to see the hang-up — the
//! SIGHUP flag, or [`terminal_hung_up`] — and leave.

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use crossbeam_channel::{Receiver, RecvTimeoutError, bounded};
use ratatui::crossterm::event::{self, Event as TermEvent, KeyEvent, KeyEventKind};

#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    Key(KeyEvent),
    Resize(u16, u16),
}

/// Where the console's loop gets its terminal events: the real terminal
/// ([`Input`]), or a script in tests.
pub trait EventSource {
    /// The next terminal event, waiting at most `timeout`; an error means
    /// the terminal is lost.
    fn next(&mut self, timeout: Duration) -> io::Result<Option<Event>>;

    /// Whether the terminal has gone (hung up), checked once a frame.
    fn hung_up(&self) -> bool {
        false
    }
}

/// Terminal events from the reader thread.
pub struct Input {
    rx: Receiver<io::Result<Event>>,
}

impl Input {
    pub fn start() -> io::Result<Input> {
        let (tx, rx) = bounded(256);
        std::thread::Builder::new()
            .name("console-input".into())
            .spawn(move || {
                loop {
                    let ev = match event::read() {
                        Ok(TermEvent::Key(k)) if k.kind != KeyEventKind::Release => Event::Key(k),
                        Ok(TermEvent::Resize(w, h)) => Event::Resize(w, h),
                        Ok(_) => continue,
                        Err(e) => {
                            let _ = tx.send(Err(e));
                            return;
                        }
                    };
                    if tx.send(Ok(ev)).is_err() {
                        return;
                    }
                }
            })?;
        Ok(Input { rx })
    }
}

impl EventSource for Input {
    fn next(&mut self, timeout: Duration) -> io::Result<Option<Event>> {
        match self.rx.recv_timeout(timeout) {
            Ok(Ok(e)) => Ok(Some(e)),
            Ok(Err(e)) => Err(e),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => Err(io::Error::new(
                io::ErrorKind::BrokenPipe,
                "the terminal input closed",
            )),
        }
    }

    fn hung_up(&self) -> bool {
        terminal_hung_up()
    }
}

/// Whether the terminal has gone (its other end closed: an SSH connection
/// dropped, a terminal window closed); see [`crate::terminal::lost`].
pub fn terminal_hung_up() -> bool {
    crate::terminal::lost()
}

/// Flags raised by signals: SIGINT or SIGTERM ask the session to end;
/// SIGHUP says its terminal has gone.
#[derive(Clone)]
pub struct Signals {
    stop: Arc<AtomicBool>,
    hangup: Arc<AtomicBool>,
}

impl Signals {
    pub fn register() -> io::Result<Signals> {
        let stop = Arc::new(AtomicBool::new(false));
        let hangup = Arc::new(AtomicBool::new(false));
        for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            signal_hook::flag::register(sig, stop.clone())?;
        }
        signal_hook::flag::register(signal_hook::consts::SIGHUP, hangup.clone())?;
        Ok(Signals { stop, hangup })
    }

    /// Flags no signal raises: for a session run in a test.
    pub fn unraised() -> Signals {
        Signals {
            stop: Arc::new(AtomicBool::new(false)),
            hangup: Arc::new(AtomicBool::new(false)),
        }
    }

    /// SIGINT, SIGTERM or SIGHUP arrived.
    pub fn raised(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || self.hung_up()
    }

    /// SIGHUP arrived: the terminal has gone.
    pub fn hung_up(&self) -> bool {
        self.hangup.load(Ordering::Relaxed)
    }
}
