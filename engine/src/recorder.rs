//! Getting every scan sample from the servo thread onto disk.
//!
//! The servo thread fills fixed-size blocks of samples and hands each full
//! block to a writer thread, which appends it to the recording and flushes,
//! then returns the empty block to a pool. The servo thread never waits on
//! the disk and never allocates while the pool has blocks; if the writer
//! lags so far that the pool runs dry it allocates a new block (counted)
//! rather than drop a sample. A scan that ends early — abort, device error,
//! a panic unwinding the servo thread — still sends what it has and is
//! written without its trailer, so it reads back as incomplete.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, TrySendError, bounded, unbounded};

use crate::recording::RecordingWriter;

/// One servo tick of a scan.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    pub t_s: f64,
    pub pos_m: [f64; 3],
    pub force_n: [f64; 3],
}

/// The recording columns of a scan, in order.
pub const COLUMNS: [&str; 7] = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"];

/// Samples per block: a quarter second at 1 kHz.
const BLOCK: usize = 250;
const POOL: usize = 16;
const QUEUE: usize = 1024;

enum ToWriter {
    Begin {
        path: PathBuf,
        meta: Vec<(String, toml::Value)>,
        id: u64,
    },
    Block(Vec<Sample>),
    End {
        aborted: Option<String>,
    },
}

/// What became of a scan on disk.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedScan {
    pub path: PathBuf,
    pub rows: usize,
    /// Written with its trailer: the scan completed.
    pub complete: bool,
    /// Why the scan stopped early, if it did.
    pub aborted: Option<String>,
    /// The recording could not be written (or not wholly): why.
    pub error: Option<String>,
}

/// The servo thread's end: push samples, begin and end scans.
pub struct ScanSink {
    tx: Sender<ToWriter>,
    free: Receiver<Vec<Sample>>,
    block: Vec<Sample>,
    active: bool,
    rows: u64,
    /// Blocks allocated because the pool ran dry.
    pub grown: u64,
    /// This scan's number (from 1), and the number of the last scan whose
    /// recording the writer could not write (0: none).
    scan_id: u64,
    failed: Arc<AtomicU64>,
}

/// The writer thread's handle: results of saved scans.
pub struct Recorder {
    pub saved: Receiver<SavedScan>,
    thread: Option<JoinHandle<()>>,
}

/// Start a writer thread; returns its handle and the sink for the servo thread.
/// Each recording is fsynced when it is finished or aborted.
pub fn start() -> (Recorder, ScanSink) {
    start_with(true)
}

/// A writer for a batch of recordings that the caller syncs as a whole
/// afterwards ([`crate::recording::sync_folder`]), as `simulate` does.
pub fn start_batch() -> (Recorder, ScanSink) {
    start_with(false)
}

fn start_with(sync_each: bool) -> (Recorder, ScanSink) {
    let (tx, rx) = bounded::<ToWriter>(QUEUE);
    let (free_tx, free_rx) = bounded::<Vec<Sample>>(QUEUE);
    for _ in 0..POOL {
        free_tx
            .try_send(Vec::with_capacity(BLOCK))
            .expect("the pool channel holds POOL blocks");
    }
    let (saved_tx, saved_rx) = unbounded();
    let failed = Arc::new(AtomicU64::new(0));
    let thread = std::thread::Builder::new()
        .name("recorder".into())
        .spawn({
            let failed = failed.clone();
            move || writer_loop(rx, free_tx, saved_tx, sync_each, &failed)
        })
        .expect("spawn the recorder thread");
    (
        Recorder {
            saved: saved_rx,
            thread: Some(thread),
        },
        ScanSink {
            tx,
            free: free_rx,
            block: Vec::with_capacity(BLOCK),
            active: false,
            rows: 0,
            grown: 0,
            scan_id: 0,
            failed,
        },
    )
}

impl Recorder {
    /// Wait for the writer to finish everything sent to it (after the sink is dropped).
    pub fn join(mut self) -> Vec<SavedScan> {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.saved.try_iter().collect()
    }
}

impl ScanSink {
    pub fn is_active(&self) -> bool {
        self.active
    }

    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The running scan's recording could not be written (a full disk): the
    /// writer has closed it; the scan should stop. One atomic load.
    pub fn write_failed(&self) -> bool {
        self.active && self.failed.load(Ordering::Relaxed) == self.scan_id
    }

    /// Open a recording at `path` with `meta` (rare: allocation is fine here).
    pub fn begin(&mut self, path: &Path, meta: Vec<(String, toml::Value)>) {
        if self.active {
            self.end(Some("a new scan started before this one ended".into()));
        }
        self.scan_id += 1;
        self.send(ToWriter::Begin {
            path: path.to_path_buf(),
            meta,
            id: self.scan_id,
        });
        self.active = true;
        self.rows = 0;
    }

    /// Append one sample; never blocks while the writer keeps up.
    #[inline]
    pub fn push(&mut self, s: Sample) {
        if !self.active {
            return;
        }
        self.block.push(s);
        self.rows += 1;
        if self.block.len() >= BLOCK {
            let next = match self.free.try_recv() {
                Ok(b) => b,
                Err(_) => {
                    self.grown += 1;
                    Vec::with_capacity(BLOCK)
                }
            };
            let full = std::mem::replace(&mut self.block, next);
            self.send(ToWriter::Block(full));
        }
    }

    /// Close the scan: complete (`None`) or aborted with the reason.
    pub fn end(&mut self, aborted: Option<String>) {
        if !self.active {
            return;
        }
        if !self.block.is_empty() {
            let next = self.free.try_recv().unwrap_or_default();
            let last = std::mem::replace(&mut self.block, next);
            self.send(ToWriter::Block(last));
        }
        self.send(ToWriter::End { aborted });
        self.active = false;
    }

    fn send(&mut self, msg: ToWriter) {
        match self.tx.try_send(msg) {
            Ok(()) => {}
            // The writer is a thousand blocks behind: wait rather than lose data.
            Err(TrySendError::Full(msg)) => {
                let _ = self.tx.send(msg);
            }
            // The writer is gone (it panicked): nothing more can be saved.
            Err(TrySendError::Disconnected(_)) => {}
        }
    }
}

impl Drop for ScanSink {
    fn drop(&mut self) {
        if self.active {
            self.end(Some("the servo loop stopped during the scan".into()));
        }
    }
}

struct Open {
    writer: Option<RecordingWriter>,
    path: PathBuf,
    error: Option<String>,
    /// Rows kept on disk when a write failed.
    kept: usize,
    id: u64,
}

impl Open {
    /// Append a block and flush. The first failure closes the recording, cut
    /// back to its last whole rows and marked aborted, and is kept.
    fn write(&mut self, block: &[Sample], row: &mut [f64; 7], failed: &AtomicU64) {
        let Some(w) = self.writer.as_mut() else {
            return;
        };
        let result = block
            .iter()
            .try_for_each(|s| {
                row[0] = s.t_s;
                row[1..4].copy_from_slice(&s.pos_m);
                row[4..7].copy_from_slice(&s.force_n);
                w.write_row(row)
            })
            .and_then(|()| w.flush());
        if let Err(e) = result {
            failed.store(self.id, Ordering::Relaxed);
            let w = self.writer.take().expect("checked above");
            let (kept, cut) =
                w.abort_after_error(&format!("the recording could not be written: {e}"));
            self.kept = kept;
            self.error = Some(match cut {
                None => format!("{e}{}", storage_hint(&e)),
                Some(c) => format!(
                    "{e}{}; cutting the file back to whole rows failed too: {c}",
                    storage_hint(&e)
                ),
            });
        }
    }
}

/// Advice for an error that says the disk (or the file size limit) is full.
fn storage_hint(e: &crate::recording::RecordingError) -> &'static str {
    match e {
        crate::recording::RecordingError::Io { source, .. }
            if matches!(
                source.kind(),
                std::io::ErrorKind::StorageFull | std::io::ErrorKind::FileTooLarge
            ) =>
        {
            " (the disk is full or the file size limit is reached: free some space, or record to another disk with --out)"
        }
        _ => "",
    }
}

fn writer_loop(
    rx: Receiver<ToWriter>,
    free: Sender<Vec<Sample>>,
    saved: Sender<SavedScan>,
    sync_each: bool,
    failed: &AtomicU64,
) {
    let mut open: Option<Open> = None;
    let mut row = [0.0f64; 7];
    for msg in rx.iter() {
        match msg {
            ToWriter::Begin { path, meta, id } => {
                if let Some(o) = open.take() {
                    close(
                        o,
                        Some("a new scan started before this one ended".into()),
                        &saved,
                    );
                }
                let refs: Vec<&str> = COLUMNS.to_vec();
                open = Some(match RecordingWriter::create(&path, &meta, &refs) {
                    Ok(mut w) => Open {
                        writer: Some({
                            if !sync_each {
                                w.defer_sync();
                            }
                            w
                        }),
                        path,
                        error: None,
                        kept: 0,
                        id,
                    },
                    Err(e) => {
                        failed.store(id, Ordering::Relaxed);
                        Open {
                            writer: None,
                            path,
                            error: Some(format!("{e}{}", storage_hint(&e))),
                            kept: 0,
                            id,
                        }
                    }
                });
            }
            ToWriter::Block(mut block) => {
                if let Some(o) = open.as_mut() {
                    o.write(&block, &mut row, failed);
                }
                block.clear();
                let _ = free.try_send(block);
            }
            ToWriter::End { aborted } => {
                if let Some(o) = open.take() {
                    close(o, aborted, &saved);
                }
            }
        }
    }
    if let Some(o) = open.take() {
        close(
            o,
            Some("the servo loop vanished during the scan".into()),
            &saved,
        );
    }
}

fn close(o: Open, aborted: Option<String>, saved: &Sender<SavedScan>) {
    let mut error = o.error;
    let mut rows = o.kept;
    let mut complete = false;
    if let Some(w) = o.writer {
        rows = w.rows();
        let done = match &aborted {
            None => w.finish(),
            Some(reason) => w.abort(reason),
        };
        match done {
            Ok(n) => {
                rows = n;
                complete = aborted.is_none();
            }
            Err(e) => error = Some(e.to_string()),
        }
    }
    let _ = saved.send(SavedScan {
        path: o.path,
        rows,
        complete,
        aborted,
        error,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: usize) -> Sample {
        Sample {
            t_s: i as f64 * 0.001,
            pos_m: [i as f64 * 1e-6, 0.0, 0.0],
            force_n: [0.0; 3],
        }
    }

    #[test]
    fn a_writer_that_lags_loses_no_sample() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("burst.csv");
        let (recorder, mut sink) = start();
        sink.begin(&path, vec![]);
        // Far faster than the writer can format: the pool runs dry and grows.
        let n = 200_000;
        for i in 0..n {
            sink.push(sample(i));
        }
        sink.end(None);
        let grown = sink.grown;
        drop(sink);
        let saved = recorder.join();
        assert_eq!(saved.len(), 1);
        assert!(saved[0].complete, "{saved:?}");
        assert_eq!(saved[0].rows, n);
        let rec = crate::recording::read(&path).unwrap();
        assert_eq!(rec.len(), n);
        let x = rec.column("x_m").unwrap();
        assert!((x[n - 1] - (n - 1) as f64 * 1e-6).abs() < 1e-9);
        // The pool held 16 blocks; this many samples needed more (counted, not lost).
        assert!(grown > 0, "the test did not make the writer lag");
    }

    #[test]
    fn a_recording_that_cannot_be_written_tells_the_scan_to_stop() {
        let dir = tempfile::tempdir().unwrap();
        // A regular file where the scan's folder should be.
        std::fs::write(dir.path().join("blocked"), b"").unwrap();
        let (recorder, mut sink) = start();
        sink.begin(&dir.path().join("blocked/scan.csv"), vec![]);
        let give_up = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while !sink.write_failed() {
            assert!(std::time::Instant::now() < give_up, "never told");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        sink.end(Some("the recording could not be written".into()));
        // The next scan starts with a clean slate.
        let ok = dir.path().join("ok.csv");
        sink.begin(&ok, vec![]);
        for i in 0..600 {
            sink.push(sample(i));
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert!(!sink.write_failed());
        sink.end(None);
        drop(sink);
        let saved = recorder.join();
        assert!(
            saved[0].error.as_deref().unwrap().contains("blocked"),
            "{saved:?}"
        );
        assert!(saved[1].complete && saved[1].error.is_none(), "{saved:?}");
    }

    #[test]
    fn dropping_the_sink_mid_scan_keeps_the_samples_as_aborted() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.csv");
        let (recorder, mut sink) = start();
        sink.begin(&path, vec![]);
        for i in 0..1234 {
            sink.push(sample(i));
        }
        drop(sink);
        let saved = recorder.join();
        assert_eq!(saved[0].rows, 1234);
        assert!(!saved[0].complete);
        assert!(
            saved[0]
                .aborted
                .as_deref()
                .unwrap()
                .contains("servo loop stopped")
        );
        let rec = crate::recording::read(&path).unwrap();
        assert!(!rec.is_complete());
        assert_eq!(rec.len(), 1234);
    }
}
