//! The front ends' hold on the terminal, made so that losing it can never
//! cost a safe stop: raw mode and the alternate screen entered and left
//! fallibly, a panic hook that cannot panic, lines printed fallibly, and a
//! test for a terminal (or pipe) whose other end has gone.
//!
//! Why not ratatui's `init`/`restore`: their panic hook and `restore` report
//! a failure with `eprintln!`, which itself panics when the terminal is gone
//! (a dropped SSH connection): a panic inside the panic hook aborts the
//! process, and the servo's guard that zeroes the forces never runs. Nothing
//! here panics on a failed write; what cannot be written is dropped.
//!
//! It must never block the caller on a terminal that has gone, and never
//! print with `println!`/`eprintln!`.

use std::fmt;
use std::io::{self, Stdout, Write};
use std::mem::ManuallyDrop;
use std::sync::Once;
use std::sync::atomic::{AtomicBool, Ordering};

use ratatui::Terminal;
use ratatui::backend::CrosstermBackend;
use ratatui::crossterm::{cursor, execute, terminal};

/// Raw mode and the alternate screen are on (and need leaving).
static ENTERED: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// This thread entered the terminal (and draws on it).
    static DRAWS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The console's terminal. Dropping it leaves the alternate screen and raw
/// mode fallibly; ratatui's own `Terminal` is never dropped, because its
/// `Drop` reports a failure to show the cursor with `eprintln!`, which
/// panics on a terminal that has gone (and a panic in `Drop` while unwinding
/// aborts). Its few buffers are left to the process's exit.
pub struct Screen(ManuallyDrop<Terminal<CrosstermBackend<Stdout>>>);

impl std::ops::Deref for Screen {
    type Target = Terminal<CrosstermBackend<Stdout>>;
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl std::ops::DerefMut for Screen {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

impl Drop for Screen {
    fn drop(&mut self) {
        leave();
    }
}

/// Raw mode and the alternate screen, for a full-screen front end. The
/// panic hook ([`install_panic_hook`]) leaves them too.
pub fn enter() -> io::Result<Screen> {
    install_panic_hook();
    terminal::enable_raw_mode()?;
    ENTERED.store(true, Ordering::SeqCst);
    DRAWS.with(|d| d.set(true));
    let opened = execute!(io::stdout(), terminal::EnterAlternateScreen)
        .and_then(|()| Terminal::new(CrosstermBackend::new(io::stdout())));
    match opened {
        Ok(t) => Ok(Screen(ManuallyDrop::new(t))),
        Err(e) => {
            leave();
            Err(e)
        }
    }
}

/// Leave the alternate screen and raw mode, show the cursor; failures (a
/// terminal that has gone) are ignored. Does nothing unless [`enter`] ran.
pub fn leave() {
    if ENTERED.swap(false, Ordering::SeqCst) {
        // Raw mode first: it has more side effects than the screen.
        let _ = terminal::disable_raw_mode();
        let _ = execute!(io::stdout(), terminal::LeaveAlternateScreen, cursor::Show);
    }
}

/// A panic hook that cannot panic: when the thread that draws on the
/// terminal panics, it leaves the terminal fallibly (a worker thread's panic
/// is reported by whoever joins it, and the screen stays), then hands over
/// to the default hook, which writes the message to standard error ignoring
/// failures. Installed once.
pub fn install_panic_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if DRAWS.try_with(|d| d.get()).unwrap_or(false) {
                leave();
            }
            default(info);
        }));
    });
}

/// The first failure to write standard output that was not a closed pipe
/// (a full disk, an I/O error): the output is lost, and the command must
/// not end as if it had succeeded ([`stdout_failure`]).
static OUT_FAILED: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// Notes `e` unless it is a closed pipe (the reader has gone: quiet, as
/// `head` expects).
fn note_out_failure(e: &io::Error) {
    if e.kind() != io::ErrorKind::BrokenPipe
        && let Ok(mut f) = OUT_FAILED.lock()
    {
        f.get_or_insert_with(|| e.to_string());
    }
}

/// Why standard output could not be written, if it could not (a closed
/// pipe is no failure): `main` ends such a run with exit code 1.
pub fn stdout_failure() -> Option<String> {
    OUT_FAILED.lock().ok().and_then(|f| f.clone())
}

/// Write a line to standard output; `false` when it could not be written
/// (the terminal or the pipe has gone, the disk is full). Never panics.
pub fn out(args: fmt::Arguments<'_>) -> bool {
    let mut o = io::stdout().lock();
    writeln!(o, "{args}")
        .and_then(|()| o.flush())
        .inspect_err(note_out_failure)
        .is_ok()
}

/// Write text to standard output as it is (no line end added); `false` when
/// it could not be written. Never panics.
pub fn out_text(args: fmt::Arguments<'_>) -> bool {
    let mut o = io::stdout().lock();
    write!(o, "{args}")
        .and_then(|()| o.flush())
        .inspect_err(note_out_failure)
        .is_ok()
}

/// `println!` that never panics: a line to standard output, dropped when the
/// terminal or pipe has gone.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {{
        let _ = $crate::terminal::out(format_args!($($t)*));
    }};
}

/// `print!` that never panics.
#[macro_export]
macro_rules! outp {
    ($($t:tt)*) => {{
        let _ = $crate::terminal::out_text(format_args!($($t)*));
    }};
}

/// `eprintln!` that never panics: a line to standard error, dropped when it
/// cannot be written.
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => {{
        let _ = $crate::terminal::err(format_args!($($t)*));
    }};
}

/// Write a line to standard error; `false` when it could not be written.
/// Never panics.
pub fn err(args: fmt::Arguments<'_>) -> bool {
    writeln!(io::stderr().lock(), "{args}").is_ok()
}

/// Whether the terminal has gone: standard input, when it is a terminal,
/// hung up (its other end closed: an SSH connection dropped, a terminal
/// window or tmux session closed), or standard output or error hung up or
/// lost their reader (a pipe whose reading end closed). A closed descriptor
/// or a plain file never counts.
pub fn lost() -> bool {
    #[cfg(unix)]
    {
        // SAFETY: isatty and poll on the standard descriptors with a zero
        // timeout only inspect them.
        unsafe {
            let stdin_tty = libc::isatty(0) == 1;
            let mut fds = [
                libc::pollfd {
                    fd: if stdin_tty { 0 } else { -1 },
                    events: libc::POLLIN,
                    revents: 0,
                },
                libc::pollfd {
                    fd: 1,
                    events: libc::POLLOUT,
                    revents: 0,
                },
                libc::pollfd {
                    fd: 2,
                    events: libc::POLLOUT,
                    revents: 0,
                },
            ];
            if libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, 0) <= 0 {
                return false;
            }
            fds.iter()
                .any(|f| f.fd >= 0 && f.revents & (libc::POLLHUP | libc::POLLERR) != 0)
        }
    }
    #[cfg(not(unix))]
    {
        false
    }
}
