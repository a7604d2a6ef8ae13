//! A lost terminal stops the motion first: the real binary in a
//! pseudo-terminal whose master side is closed mid-scan (what sshd does to a
//! dropped connection, what `tmux kill-session` does), or whose process
//! group gets SIGHUP; and headless `scan` whose standard output stops being
//! read. Each time the process must exit by itself (0 or 1, never killed by
//! a signal or aborted) within 2 s, and the scan must be on disk, kept with
//! an `# aborted` line. `replay` and `simulate` losing their terminal exit 1
//! too, never by a panic.

use std::io::{Read, Write};
use std::os::fd::RawFd;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

use portable_pty::{Child, CommandBuilder, ExitStatus, PtySize, native_pty_system};

/// The process must be gone this soon after its terminal is.
const EXIT_LIMIT: Duration = Duration::from_secs(2);
/// Conditions that depend on the machine's load get this long.
const PATIENCE: Duration = Duration::from_secs(60);

fn fast_profile() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/console-fast.toml")
}

/// The console's session in a pseudo-terminal whose master side the test
/// can close: the reader thread owns the master and lets go of it on request.
struct Pty {
    child: Box<dyn Child + Send + Sync>,
    writer: Option<Box<dyn Write + Send>>,
    output: Receiver<Vec<u8>>,
    close: Sender<()>,
    closed: Receiver<()>,
    parser: vt100::Parser,
}

fn readable(fd: RawFd, ms: i32) -> bool {
    let mut p = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: poll on a descriptor this thread owns, with a timeout.
    unsafe { libc::poll(&mut p, 1, ms) > 0 }
}

impl Pty {
    fn console(ds: &Path, cwd: &Path) -> Pty {
        let profile = fast_profile();
        Pty::start(
            &[
                "console",
                "--profile",
                profile.to_str().unwrap(),
                "--dataset",
                ds.to_str().unwrap(),
            ],
            cwd,
        )
    }

    fn start(args: &[&str], cwd: &Path) -> Pty {
        let pty = native_pty_system()
            .openpty(PtySize {
                rows: 48,
                cols: 160,
                pixel_width: 0,
                pixel_height: 0,
            })
            .unwrap();
        let mut cmd = CommandBuilder::new(env!("CARGO_BIN_EXE_hapticlab"));
        cmd.args(args);
        cmd.cwd(cwd);
        cmd.env("TERM", "xterm-256color");
        let child = pty.slave.spawn_command(cmd).unwrap();
        drop(pty.slave);
        let mut reader = pty.master.try_clone_reader().unwrap();
        let writer = pty.master.take_writer().unwrap();
        let fd = pty.master.as_raw_fd().unwrap();
        let (tx, output) = channel();
        let (close, close_rx) = channel::<()>();
        let (closed_tx, closed) = channel();
        std::thread::spawn(move || {
            let master = pty.master;
            let mut buf = [0u8; 8192];
            loop {
                if close_rx.try_recv().is_ok() {
                    break;
                }
                // Wait for output a little at a time, so a close request is
                // seen; the reader shares the master's file description.
                if !readable(fd, 20) {
                    continue;
                }
                match reader.read(&mut buf) {
                    Ok(n) if n > 0 => {
                        let _ = tx.send(buf[..n].to_vec());
                    }
                    _ => break,
                }
            }
            drop(reader);
            drop(master);
            let _ = closed_tx.send(());
        });
        Pty {
            child,
            writer: Some(writer),
            output,
            close,
            closed,
            parser: vt100::Parser::new(
                std::num::NonZeroU16::new(48).unwrap(),
                std::num::NonZeroU16::new(160).unwrap(),
                0,
            ),
        }
    }

    fn pump(&mut self, wait: Duration) {
        if let Ok(bytes) = self.output.recv_timeout(wait) {
            self.parser.process(&bytes);
        }
        while let Ok(bytes) = self.output.try_recv() {
            self.parser.process(&bytes);
        }
    }

    fn wait_for(&mut self, text: &str) {
        let start = Instant::now();
        loop {
            self.pump(Duration::from_millis(50));
            let s = self.parser.screen().contents();
            if s.contains(text) {
                return;
            }
            assert!(
                start.elapsed() < PATIENCE,
                "waited {PATIENCE:?} for {text:?}; the screen:\n{s}"
            );
        }
    }

    fn send(&mut self, keys: &str) {
        let w = self.writer.as_mut().unwrap();
        w.write_all(keys.as_bytes()).unwrap();
        w.flush().unwrap();
    }

    /// Close the master side: every descriptor on it. Returns when it is closed.
    fn close_master(&mut self) {
        self.close.send(()).unwrap();
        self.closed.recv_timeout(PATIENCE).unwrap();
        // The writer is a duplicate of the master: the last one closes it.
        drop(self.writer.take());
    }

    /// Wait for the process to exit on its own; its status and how long it took.
    fn wait_exit(&mut self, limit: Duration) -> (ExitStatus, Duration) {
        let start = Instant::now();
        loop {
            while self.output.try_recv().is_ok() {}
            if let Some(status) = self.child.try_wait().unwrap() {
                return (status, start.elapsed());
            }
            if start.elapsed() > limit {
                let _ = self.child.kill();
                panic!("the process did not exit within {limit:?}");
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// The one scan under `.unsaved/`, read back: it must end with `# aborted`.
fn assert_scan_aborted(ds: &Path, reason: &str) {
    let scans: Vec<_> = std::fs::read_dir(ds.join(".unsaved"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(scans.len(), 1, "{scans:?}");
    let text = std::fs::read_to_string(&scans[0]).unwrap();
    let last = text.lines().last().unwrap();
    assert!(
        last.starts_with("# aborted = ") && last.contains(reason),
        "the scan's last line: {last}"
    );
    let rec = hapticlab::recording::read(&scans[0]).unwrap();
    assert!(!rec.is_complete());
    assert!(rec.len() > 10, "{} samples", rec.len());
}

/// Exited by itself with 0 or 1: not killed by a signal, not aborted (134), not a panic (101).
fn assert_exited_cleanly(status: &ExitStatus, took: Duration) {
    assert!(status.signal().is_none(), "killed by a signal: {status:?}");
    assert!(
        status.exit_code() <= 1,
        "exit code {} (101 is a panic, 134 an abort): {status:?}",
        status.exit_code()
    );
    assert!(
        took <= EXIT_LIMIT,
        "took {took:?} to exit after the terminal went"
    );
}

/// Start the console, start a scan, wait until it records.
fn console_mid_scan(tmp: &Path) -> (Pty, PathBuf) {
    let ds = tmp.join("ds");
    let mut s = Pty::console(&ds, tmp);
    s.wait_for("Homed    yes");
    s.send("s");
    s.wait_for("% recorded");
    (s, ds)
}

#[test]
fn closing_the_terminal_mid_scan_stops_the_scan_and_exits() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut s, ds) = console_mid_scan(tmp.path());
    s.close_master();
    let (status, took) = s.wait_exit(PATIENCE);
    assert_exited_cleanly(&status, took);
    assert_eq!(
        status.exit_code(),
        1,
        "a lost terminal is a runtime failure"
    );
    assert_scan_aborted(&ds, "terminal lost");
}

#[test]
fn sighup_to_the_process_group_mid_scan_stops_the_scan_and_exits() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut s, ds) = console_mid_scan(tmp.path());
    // portable-pty makes the child a session (and process group) leader.
    let pid = s.child.process_id().unwrap() as i32;
    // SAFETY: kill(2) on our own child's process group.
    assert_eq!(unsafe { libc::kill(-pid, libc::SIGHUP) }, 0);
    let (status, took) = s.wait_exit(PATIENCE);
    assert_exited_cleanly(&status, took);
    assert_scan_aborted(&ds, "terminal lost");
}

#[test]
fn headless_scan_whose_output_is_closed_stops_the_scan_and_exits() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["scan", "--profile"])
        .arg(fast_profile())
        .args(["--label", "S2", "--count", "3", "--out"])
        .arg(&out)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the first scan records (its file has samples), then close
    // the reading ends of both pipes, as a terminal that has gone would.
    let file = out.join("S2").join("S2_001.csv");
    let start = Instant::now();
    while std::fs::read_to_string(&file).map_or(0, |t| t.lines().count()) < 200 {
        assert!(start.elapsed() < PATIENCE, "the scan never recorded");
        assert!(child.try_wait().unwrap().is_none(), "scan ended early");
        std::thread::sleep(Duration::from_millis(20));
    }
    drop(child.stdout.take());
    drop(child.stderr.take());
    let closed = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if closed.elapsed() > PATIENCE {
            let _ = child.kill();
            panic!("scan did not exit");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = closed.elapsed();
    use std::os::unix::process::ExitStatusExt;
    assert!(status.signal().is_none(), "killed by a signal: {status:?}");
    assert_eq!(status.code(), Some(1), "{status:?}");
    assert!(took <= EXIT_LIMIT, "took {took:?} to exit");
    let text = std::fs::read_to_string(&file).unwrap();
    let last = text.lines().last().unwrap();
    assert!(
        last.starts_with("# aborted = ") && last.contains("terminal lost"),
        "the scan's last line: {last}"
    );
    // No later scan was started.
    assert!(!out.join("S2").join("S2_002.csv").exists());
}

#[test]
fn closing_the_terminal_ends_a_replay_with_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["simulate", "--profile"])
        .arg(fast_profile())
        .arg("--out")
        .arg(&ds)
        .args(["--per-class", "1", "--threads", "1"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let profile = fast_profile();
    let mut s = Pty::start(
        &[
            "replay",
            "--profile",
            profile.to_str().unwrap(),
            ds.to_str().unwrap(),
        ],
        tmp.path(),
    );
    s.wait_for("S2_001");
    s.close_master();
    let (status, took) = s.wait_exit(PATIENCE);
    assert_exited_cleanly(&status, took);
    assert_eq!(
        status.exit_code(),
        1,
        "a lost terminal is a runtime failure"
    );
}

#[test]
fn simulate_whose_output_is_closed_stops_and_exits_1() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sim");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["simulate", "--profile"])
        .arg(fast_profile())
        .arg("--out")
        .arg(&out)
        .args(["--per-class", "500", "--threads", "1"])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Nobody reads its output any more.
    drop(child.stdout.take());
    let mut stderr = child.stderr.take().unwrap();
    let closed = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if closed.elapsed() > PATIENCE {
            let _ = child.kill();
            panic!("simulate did not stop");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut msg = String::new();
    stderr.read_to_string(&mut msg).unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert!(status.signal().is_none(), "killed by a signal: {status:?}");
    assert_eq!(status.code(), Some(1), "{status:?} {msg}");
    assert!(
        msg.contains("the terminal was lost: simulate stopped after"),
        "{msg}"
    );
    // Stopped early: far fewer than the 2000 asked for, each one complete.
    let files: Vec<_> = std::fs::read_dir(&out)
        .map(|d| {
            d.flat_map(|e| std::fs::read_dir(e.unwrap().path()).unwrap())
                .collect()
        })
        .unwrap_or_default();
    assert!(files.len() < 2000, "{} files", files.len());
    for f in files {
        let rec = hapticlab::recording::read(&f.unwrap().path()).unwrap();
        assert!(rec.is_complete());
    }
}
