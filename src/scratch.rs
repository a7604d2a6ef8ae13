//! A scratch folder: a temporary folder that is removed when it is dropped
//! and when the user presses Ctrl-C while it exists (`evaluate --simulate`
//! writes its simulated scans into one).
//!
//! Ctrl-C's default action kills the process at once, so no `Drop` runs and
//! the folder would stay in the system's temporary folder. While a scratch
//! folder exists, SIGINT only raises a flag; the workers filling the folder
//! look at it between scans ([`ScratchFolder::watch`]): the first to see it
//! waits until every other worker has finished its scan (so none can create
//! a file after the removal), removes the folder and ends the process with
//! status 130, as the shell reports a Ctrl-C. With no scratch folder alive,
//! SIGINT ends the process with status 130 straight away. This module
//! prints one line (the interruption) and never touches anything but its
//! folder. It is a front end's: the engine's simulated sweeps see it only
//! as an [`evaluate::sweep::Scratch`].

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::Duration;

use crate::evaluate;

/// The process's SIGINT flags, registered once: `interrupted` is raised by
/// every SIGINT; `exit_now` (true unless a scratch folder is alive) makes
/// SIGINT end the process with status 130 as before.
struct Sigint {
    interrupted: Arc<AtomicBool>,
    exit_now: Arc<AtomicBool>,
    /// Scratch folders alive.
    alive: Mutex<usize>,
}

static SIGINT: OnceLock<Result<Sigint, String>> = OnceLock::new();

fn sigint() -> Result<&'static Sigint, String> {
    SIGINT
        .get_or_init(|| {
            let s = Sigint {
                interrupted: Arc::new(AtomicBool::new(false)),
                exit_now: Arc::new(AtomicBool::new(true)),
                alive: Mutex::new(0),
            };
            let sig = signal_hook::consts::SIGINT;
            signal_hook::flag::register_conditional_shutdown(sig, 130, s.exit_now.clone())
                .and_then(|_| signal_hook::flag::register(sig, s.interrupted.clone()))
                .map_err(|e| format!("cannot watch for Ctrl-C: {e}"))?;
            Ok(s)
        })
        .as_ref()
        .map_err(Clone::clone)
}

/// A temporary folder removed on drop and on Ctrl-C.
pub struct ScratchFolder {
    dir: tempfile::TempDir,
    sigint: &'static Sigint,
    /// Workers that saw the interruption and stopped for good.
    parked: Mutex<usize>,
    parked_changed: Condvar,
    /// The most scans any worker reported done.
    done: AtomicUsize,
    cleaning: AtomicBool,
}

impl ScratchFolder {
    /// A new empty folder in the system's temporary folder, named `prefix…`.
    pub fn new(prefix: &str) -> Result<ScratchFolder, String> {
        let sigint = sigint()?;
        let dir = tempfile::Builder::new()
            .prefix(prefix)
            .tempdir()
            .map_err(|e| e.to_string())?;
        let mut alive = sigint.alive.lock().unwrap_or_else(|p| p.into_inner());
        if *alive == 0 {
            sigint.interrupted.store(false, Ordering::SeqCst);
        }
        *alive += 1;
        sigint.exit_now.store(false, Ordering::SeqCst);
        drop(alive);
        Ok(ScratchFolder {
            dir,
            sigint,
            parked: Mutex::new(0),
            parked_changed: Condvar::new(),
            done: AtomicUsize::new(0),
            cleaning: AtomicBool::new(false),
        })
    }

    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Whether Ctrl-C was pressed since this folder was made.
    pub fn interrupted(&self) -> bool {
        self.sigint.interrupted.load(Ordering::SeqCst)
    }

    /// After Ctrl-C, when no worker is filling the folder any more: remove
    /// it, say so, and end the process (status 130).
    pub fn exit_if_interrupted(&self) {
        if self.interrupted() {
            self.remove_and_exit();
        }
    }

    /// Wraps the progress callback of `workers` threads that fill the folder
    /// and call it after each of `total` scans: after Ctrl-C, the first
    /// caller removes the folder once the others have stopped, and the
    /// process ends; the others stop for good.
    pub fn watch<'a>(
        &'a self,
        workers: usize,
        progress: &'a (dyn Fn(usize, usize) + Sync),
    ) -> impl Fn(usize, usize) + Sync + 'a {
        move |done, total| {
            self.done.fetch_max(done, Ordering::SeqCst);
            if !self.interrupted() {
                progress(done, total);
                return;
            }
            if self.cleaning.swap(true, Ordering::SeqCst) {
                // Another worker removes the folder: start no new scan.
                *self.parked.lock().unwrap_or_else(|p| p.into_inner()) += 1;
                self.parked_changed.notify_all();
                loop {
                    std::thread::park();
                }
            }
            // Every other worker is stopped, or has no scan left.
            let parked = self.parked.lock().unwrap_or_else(|p| p.into_inner());
            let _ = self.parked_changed.wait_timeout_while(
                parked,
                Duration::from_secs(120),
                |parked| *parked + 1 < workers.max(1) && self.done.load(Ordering::SeqCst) < total,
            );
            self.remove_and_exit();
        }
    }

    fn remove_and_exit(&self) -> ! {
        let path = self.dir.path();
        match std::fs::remove_dir_all(path) {
            Ok(()) => crate::errln!(
                "interrupted: removed the temporary folder {}",
                path.display()
            ),
            Err(e) => crate::errln!(
                "interrupted: could not remove the temporary folder {}: {e}",
                path.display()
            ),
        }
        std::process::exit(130)
    }
}

impl Drop for ScratchFolder {
    fn drop(&mut self) {
        let mut alive = self.sigint.alive.lock().unwrap_or_else(|p| p.into_inner());
        *alive = alive.saturating_sub(1);
        if *alive == 0 {
            self.sigint.exit_now.store(true, Ordering::SeqCst);
        }
        drop(alive);
        // A Ctrl-C that came after the last look at the flag still ends the run.
        if self.interrupted() {
            self.remove_and_exit();
        }
        // Otherwise the TempDir removes the folder after this.
    }
}

impl evaluate::sweep::Scratch for ScratchFolder {
    fn path(&self) -> &Path {
        ScratchFolder::path(self)
    }

    fn watch<'a>(
        &'a self,
        workers: usize,
        progress: &'a (dyn Fn(usize, usize) + Sync),
    ) -> Box<dyn Fn(usize, usize) + Sync + 'a> {
        Box::new(ScratchFolder::watch(self, workers, progress))
    }

    fn checkpoint(&self) {
        self.exit_if_interrupted();
    }
}

/// A scratch folder for `evaluate --simulate`'s datasets
/// ([`evaluate::sweep::SimPlan::scratch`]).
pub fn make() -> Result<Box<dyn evaluate::sweep::Scratch>, String> {
    Ok(Box::new(ScratchFolder::new("hapticlab-simulate-")?))
}
