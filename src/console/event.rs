//! The console's inputs besides telemetry: terminal events (keys, resizes)
//! and the signals that end the session cleanly (SIGINT, SIGTERM, SIGHUP
//! raise a flag; the loop sees it, shuts down the servo and restores the
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

    /// The next terminal event, waiting at most `timeout`.
    pub fn next(&self, timeout: Duration) -> io::Result<Option<Event>> {
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
}

/// Whether the terminal on standard input has gone (its other end closed:
/// an SSH connection dropped, a terminal window closed).
pub fn terminal_hung_up() -> bool {
    // SAFETY: isatty and poll on fd 0 with a zero timeout only inspect it.
    unsafe {
        if libc::isatty(0) != 1 {
            return false;
        }
        let mut fd = libc::pollfd {
            fd: 0,
            events: libc::POLLIN,
            revents: 0,
        };
        libc::poll(&mut fd, 1, 0) > 0
            && fd.revents & (libc::POLLHUP | libc::POLLERR | libc::POLLNVAL) != 0
    }
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
