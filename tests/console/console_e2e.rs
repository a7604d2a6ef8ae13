//! The real binary in a pseudo-terminal (portable-pty, screen parsed by
//! vt100): start the console on a fast test profile, run a scan, predict it,
//! read the label off the screen, quit, and check the terminal was restored.
//! A second run is ended by SIGTERM mid-scan: the scan must be kept on disk
//! as aborted and the terminal restored. A third runs the same profile on
//! the emulated Falcon, through the real driver: homed, then a scan.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use portable_pty::{Child, CommandBuilder, PtySize, native_pty_system};

const COLS: u16 = 160;
/// Every wait: generous, so that a machine busy with other work (both cores
/// taken) slows the test down but never fails it.
const PATIENCE: Duration = Duration::from_secs(60);
const ROWS: u16 = 48;

fn fast_profile() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/console-fast.toml")
}

struct Session {
    child: Box<dyn Child + Send + Sync>,
    writer: Box<dyn Write + Send>,
    output: Receiver<Vec<u8>>,
    parser: vt100::Parser,
    raw: Vec<u8>,
}

impl Session {
    /// `hapticlab console --profile PROFILE --dataset DS`, run in `cwd`.
    fn console(profile: &Path, ds: &Path, cwd: &Path) -> Session {
        Session::start(
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

    fn start(args: &[&str], cwd: &Path) -> Session {
        let pty = native_pty_system()
            .openpty(PtySize {
                rows: ROWS,
                cols: COLS,
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
        let (tx, output) = channel();
        std::thread::spawn(move || {
            let _keep_master_open = pty.master;
            let mut buf = [0u8; 8192];
            while let Ok(n) = reader.read(&mut buf) {
                if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                    break;
                }
            }
        });
        Session {
            child,
            writer,
            output,
            parser: vt100::Parser::new(
                std::num::NonZeroU16::new(ROWS).unwrap(),
                std::num::NonZeroU16::new(COLS).unwrap(),
                0,
            ),
            raw: Vec::new(),
        }
    }

    fn pump(&mut self, wait: Duration) {
        if let Ok(bytes) = self.output.recv_timeout(wait) {
            self.parser.process(&bytes);
            self.raw.extend_from_slice(&bytes);
        }
        while let Ok(bytes) = self.output.try_recv() {
            self.parser.process(&bytes);
            self.raw.extend_from_slice(&bytes);
        }
    }

    fn screen(&self) -> String {
        self.parser.screen().contents()
    }

    /// Wait until the screen shows `text`.
    fn wait_for(&mut self, text: &str, limit: Duration) -> String {
        let start = Instant::now();
        loop {
            self.pump(Duration::from_millis(50));
            let s = self.screen();
            if s.contains(text) {
                return s;
            }
            assert!(
                start.elapsed() < limit,
                "waited {limit:?} for {text:?}; the screen:\n{s}"
            );
        }
    }

    fn send(&mut self, keys: &str) {
        self.writer.write_all(keys.as_bytes()).unwrap();
        self.writer.flush().unwrap();
    }

    /// Wait for the process to end; its exit status.
    fn wait_exit(&mut self, limit: Duration) -> portable_pty::ExitStatus {
        let start = Instant::now();
        loop {
            self.pump(Duration::from_millis(50));
            if let Some(status) = self.child.try_wait().unwrap() {
                self.pump(Duration::from_millis(200));
                return status;
            }
            assert!(
                start.elapsed() < limit,
                "the console did not exit:\n{}",
                self.screen()
            );
        }
    }

    fn restored(&self) -> bool {
        !self.parser.screen().alternate_screen() && self.raw.windows(8).any(|w| w == b"\x1b[?1049l")
    }
}

fn simulate(dir: &Path) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["simulate", "--profile"])
        .arg(fast_profile())
        .arg("--out")
        .arg(dir)
        .args(["--per-class", "6", "--threads", "2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn scan_predict_and_quit_in_a_pseudo_terminal() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    simulate(&ds);
    let profile = fast_profile();
    let mut s = Session::console(&profile, &ds, tmp.path());
    s.wait_for("Device", PATIENCE);
    s.wait_for("Homed    yes", PATIENCE);
    // Label S2: the simulator mounts texture S2.
    s.send("l\x7f\x7fS2\r");
    s.wait_for("mounting texture S2", PATIENCE);
    s.send("s");
    // "stores it" comes once the recorder has written the scan and the
    // console has read it back; "scan complete" alone comes earlier, with the
    // motion's end, and a key sent then finds no scan yet (on a busy machine
    // the file takes a while: `q` then quit without asking).
    s.wait_for("stores it", PATIENCE);
    s.send("p");
    let screen = s.wait_for("Predicted ", PATIENCE);
    let label = screen
        .split("Predicted ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap()
        .to_string();
    assert_eq!(label, "S2", "the screen:\n{screen}");
    assert!(screen.contains("recorded as S2: right"), "{screen}");
    // Quitting with the scan unstored asks first.
    s.send("q");
    s.wait_for("Quit?", PATIENCE);
    s.send("y");
    let status = s.wait_exit(PATIENCE);
    assert!(status.success(), "{status:?}");
    assert!(s.restored(), "the alternate screen was not left");
    assert!(
        ds.join("model.json").exists(),
        "p trained and saved a model"
    );
    assert_eq!(std::fs::read_dir(ds.join(".unsaved")).unwrap().count(), 1);
}

#[test]
fn sigterm_mid_scan_keeps_the_scan_and_restores_the_terminal() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let profile = fast_profile();
    let mut s = Session::console(&profile, &ds, tmp.path());
    s.wait_for("Homed    yes", PATIENCE);
    s.send("s");
    s.wait_for("% recorded", PATIENCE);
    let pid = s.child.process_id().unwrap();
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(pid as i32, libc::SIGTERM) }, 0);
    let status = s.wait_exit(PATIENCE);
    assert!(status.success(), "{status:?}");
    assert!(s.restored(), "the alternate screen was not left");
    let scans: Vec<_> = std::fs::read_dir(ds.join(".unsaved"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(scans.len(), 1);
    let rec = hapticlab::recording::read(&scans[0]).unwrap();
    assert!(!rec.is_complete(), "interrupted: no trailer");
    assert!(rec.len() > 10, "{} samples", rec.len());
    assert!(rec.aborted().is_some());
}

/// SIGHUP says the terminal has gone: the console stops the servo first,
/// restores the terminal (here it is still there) and exits 1.
#[test]
fn sighup_quits_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let profile = fast_profile();
    let ds = tmp.path().join("ds");
    let mut s = Session::console(&profile, &ds, tmp.path());
    s.wait_for("Homed    yes", PATIENCE);
    let pid = s.child.process_id().unwrap();
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(pid as i32, libc::SIGHUP) }, 0);
    let status = s.wait_exit(PATIENCE);
    assert_eq!(status.exit_code(), 1, "{status:?}");
    assert!(status.signal().is_none(), "{status:?}");
    assert!(s.restored(), "the alternate screen was not left");
}

/// The fast profile on the emulated Falcon (the real driver's packets,
/// kinematics and homing over a byte-level emulator).
fn fast_emulator_profile(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(fast_profile()).unwrap();
    assert!(text.contains("kind = \"sim\""));
    let text = text.replace("kind = \"sim\"", "kind = \"falcon-emulator\"")
        + "\n[falcon]\norigin_m = [0.0, 0.0, 0.15]\n\n[falcon.emulator]\nfirmware_loaded = true\nauto_home = true\n";
    let path = dir.join("console-fast-emulator.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_console_drives_the_emulated_falcon_once_homed() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let profile = fast_emulator_profile(tmp.path());
    let mut s = Session::console(&profile, &ds, tmp.path());
    s.wait_for("falcon-emulator", PATIENCE);
    // The simulated hand pulls the grip out and pushes it in.
    s.wait_for("Homed    yes", PATIENCE);
    s.send("s");
    // "stores it" comes once the recorder has written the scan and the
    // console has read it back; "scan complete" alone comes earlier, with the
    // motion's end, and a key sent then finds no scan yet (on a busy machine
    // the file takes a while: `q` then quit without asking).
    s.wait_for("stores it", PATIENCE);
    s.send("q");
    s.wait_for("Quit?", PATIENCE);
    s.send("y");
    let status = s.wait_exit(PATIENCE);
    assert!(status.success(), "{status:?}");
    assert!(s.restored(), "the alternate screen was not left");
    let scans: Vec<_> = std::fs::read_dir(ds.join(".unsaved"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(scans.len(), 1);
    let rec = hapticlab::recording::read(&scans[0]).unwrap();
    assert!(rec.is_complete(), "the scan ran to its end");
    assert_eq!(
        rec.meta_str("device"),
        Some("falcon-emulator"),
        "recorded through the Falcon driver"
    );
    // The stroke was traced: x covers the scan leg.
    let x = rec.column("x_m").unwrap();
    let span =
        x.iter().cloned().fold(f64::MIN, f64::max) - x.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 0.025, "x spans only {span} m");
}

/// An unwritable dataset folder is refused when the console starts, before
/// anything moves (as `scan --out` is): one message naming the folder and
/// `--dataset`, exit 1, and no terminal set up.
#[test]
fn an_unwritable_dataset_folder_is_refused_before_anything_moves() {
    let tmp = tempfile::tempdir().unwrap();
    // A path under a regular file: nobody, not even root, can create it.
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"not a folder").unwrap();
    let ds = file.join("ds");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["console", "--profile"])
        .arg(fast_profile())
        .arg("--dataset")
        .arg(&ds)
        .current_dir(tmp.path())
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one message: {stderr}");
    assert!(
        lines[0].contains(&format!(
            "cannot record into {}",
            ds.join(".unsaved").display()
        )) && lines[0].contains("Not a directory")
            && lines[0].contains("--dataset"),
        "{stderr}"
    );
    // Nothing was drawn: the terminal was never opened.
    assert!(
        out.stdout.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&out.stdout)
    );
}
