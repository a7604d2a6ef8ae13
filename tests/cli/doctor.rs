//! `hapticlab doctor`, the real binary on this machine (as tests/cli/cli.rs runs
//! it): the text and JSON reports, exit codes (0 nothing failed, 1 a check
//! failed, 2 a bad profile), a dataset path that cannot be a folder, the
//! firmware file through a falcon profile, and the terminal size read in a
//! pseudo-terminal.

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use portable_pty::{CommandBuilder, PtySize, native_pty_system};
use serde_json::Value;
use tempfile::TempDir;

const WORDS: [&str; 4] = ["ok", "warn", "FAIL", "note"];

use crate::common::run::Run;
use crate::common::{BIN, REPO, p};

/// `hapticlab doctor ARGS` from the repository, with a known terminal type.
fn doctor(args: &[&str]) -> Run {
    Command::new(BIN)
        .current_dir(REPO)
        .arg("doctor")
        .args(args)
        .env("TERM", "xterm-256color")
        .env_remove("NO_COLOR")
        .env_remove("COLORTERM")
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("run hapticlab")
        .into()
}

fn json(r: &Run) -> Value {
    serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {r:?}"))
}

fn check<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .find(|c| c["name"] == name)
        .unwrap_or_else(|| panic!("no check {name}: {report:#}"))
}

/// The thesis profile without its real-time request, so the checks do not
/// depend on whether this machine grants SCHED_FIFO.
fn thesis_at_normal_priority(dir: &Path) -> PathBuf {
    let text = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("realtime =") && !l.starts_with("spin_us ="))
        .collect();
    assert_eq!(
        kept.len() + 2,
        text.lines().count(),
        "the thesis profile changed"
    );
    let path = dir.join("thesis.toml");
    fs::write(&path, kept.join("\n")).unwrap();
    path
}

#[test]
fn the_sim_profile_on_a_writable_folder_passes_with_a_line_per_check() {
    let tmp = TempDir::new().unwrap();
    let ds = tmp.path().join("session");
    let profile = thesis_at_normal_priority(tmp.path());
    let r = doctor(&["--profile", p(&profile), "--dataset", p(&ds)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let lines: Vec<&str> = r.stdout.lines().collect();
    assert!(
        lines[0].starts_with("hapticlab doctor: profile thesis (device sim)"),
        "{r:?}"
    );
    let checks: Vec<&str> = lines[1..lines.len() - 1]
        .iter()
        .copied()
        .filter(|l| !l.trim_start().starts_with("fix:"))
        .collect();
    assert_eq!(checks.len(), 9, "{r:?}");
    for l in &checks {
        let word = l.split_whitespace().next().unwrap();
        assert!(WORDS.contains(&word), "no status word: {l}\n{r:?}");
        assert_ne!(word, "FAIL", "{r:?}");
    }
    let summary = lines.last().unwrap();
    assert!(
        summary.starts_with("9 checks:") && summary.ends_with("— ready"),
        "{r:?}"
    );
    assert!(
        r.stdout.contains("usb") && r.stdout.contains("free-space"),
        "{r:?}"
    );
    // Piped: the terminal check says so as a note.
    assert!(
        r.stdout
            .contains("note  terminal    standard output is not a terminal"),
        "{r:?}"
    );
    assert!(!ds.exists(), "doctor created the dataset folder");
    assert!(r.stderr.is_empty(), "{r:?}");
}

#[test]
fn json_has_every_check_with_a_status_and_ok() {
    let tmp = TempDir::new().unwrap();
    let profile = thesis_at_normal_priority(tmp.path());
    let r = doctor(&[
        "--json",
        "--profile",
        p(&profile),
        "--dataset",
        p(tmp.path()),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v = json(&r);
    assert_eq!(v["ok"], true, "{v:#}");
    let checks = v["checks"].as_array().unwrap();
    let names: Vec<&str> = checks.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "usb",
            "udev",
            "firmware",
            "realtime",
            "terminal",
            "term",
            "colour",
            "dataset",
            "free-space"
        ]
    );
    for c in checks {
        let status = c["status"].as_str().unwrap();
        assert!(["ok", "warn", "fail", "note"].contains(&status), "{c}");
        assert!(!c["finding"].as_str().unwrap().is_empty(), "{c}");
        // A fix exactly when something is wrong.
        assert_eq!(
            c["fix"].is_string(),
            matches!(status, "warn" | "fail"),
            "{c}"
        );
    }
    assert_eq!(check(&v, "dataset")["status"], "ok");
    assert_eq!(check(&v, "term")["finding"], "TERM=xterm-256color");
    // The thesis scan: 9270 rows at 1 kHz, about half a MiB each.
    let space = check(&v, "free-space")["finding"].as_str().unwrap();
    assert!(
        space.contains("1000 Hz × 9.27 s") && space.contains("KiB"),
        "{space}"
    );
}

#[test]
fn a_dataset_under_a_regular_file_fails_with_exit_1() {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join("notes.txt");
    fs::write(&file, "not a folder").unwrap();
    let ds = file.join("session");
    let r = doctor(&["--dataset", p(&ds)]);
    assert_eq!(r.code, Some(1), "{r:?}");
    let line = r
        .stdout
        .lines()
        .find(|l| l.starts_with("FAIL  dataset"))
        .unwrap_or_else(|| panic!("no FAIL line: {r:?}"));
    assert!(line.contains("notes.txt is a file"), "{line}");
    assert!(
        r.stdout.contains("fix: give `--dataset` a folder path"),
        "{r:?}"
    );
    assert!(
        r.stdout.lines().last().unwrap().ends_with("not ready"),
        "{r:?}"
    );
    assert!(
        r.stderr.contains("dataset failed") && !r.stderr.contains("panicked"),
        "{r:?}"
    );
    let r = doctor(&["--json", "--dataset", p(&ds)]);
    assert_eq!(r.code, Some(1), "{r:?}");
    let v = json(&r);
    assert_eq!(v["ok"], false);
    assert_eq!(check(&v, "dataset")["status"], "fail");
}

#[test]
fn a_bad_profile_is_bad_input() {
    let r = doctor(&["--profile", "profiles/invalid/bad-device-kind.toml"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stdout.is_empty(), "{r:?}");
    assert!(
        r.stderr.contains("profiles/invalid/bad-device-kind.toml"),
        "{r:?}"
    );
    let r = doctor(&["--profile", "profiles/no-such.toml", "--json"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("no-such.toml"), "{r:?}");
    let r = doctor(&["--frobnicate"]);
    assert_eq!(r.code, Some(2), "{r:?}");
}

/// The falcon profile copied beside a firmware file of `len` bytes.
fn falcon_profile(dir: &Path, firmware_len: Option<usize>) -> String {
    let text = fs::read_to_string(Path::new(REPO).join("profiles/thesis-falcon.toml")).unwrap();
    let profile = dir.join("falcon.toml");
    fs::write(&profile, text).unwrap();
    if let Some(len) = firmware_len {
        fs::create_dir_all(dir.join("firmware")).unwrap();
        fs::write(dir.join("firmware/nvent_firmware.bin"), vec![0x5a; len]).unwrap();
    }
    p(&profile).to_string()
}

#[test]
fn the_falcon_profile_checks_its_firmware_file() {
    let tmp = TempDir::new().unwrap();
    let ds = tmp.path().join("ds");
    let firmware = |len| {
        let dir = tmp.path().join(format!("fw{len:?}"));
        fs::create_dir_all(&dir).unwrap();
        let r = doctor(&[
            "--json",
            "-p",
            &falcon_profile(&dir, len),
            "--dataset",
            p(&ds),
        ]);
        let v = json(&r);
        (r, check(&v, "firmware").clone(), check(&v, "usb").clone())
    };
    let (r, fw, usb) = firmware(None);
    assert_eq!(r.code, Some(1), "{r:?}");
    assert_eq!(fw["status"], "fail", "{fw}");
    assert!(
        fw["finding"]
            .as_str()
            .unwrap()
            .contains("cannot read the firmware"),
        "{fw}"
    );
    assert!(fw["fix"].as_str().unwrap().contains("libnifalcon"), "{fw}");
    // Without a usable Falcon on this machine's USB: a failure, with the fix.
    match usb["status"].as_str().unwrap() {
        "fail" => assert!(usb["fix"].is_string(), "{usb}"),
        "ok" => assert!(usb["fix"].is_null(), "{usb}"),
        other => panic!("a falcon profile's usb check is {other}: {usb}"),
    }
    let (_, fw, _) = firmware(Some(100));
    assert_eq!(fw["status"], "fail", "{fw}");
    assert!(
        fw["finding"]
            .as_str()
            .unwrap()
            .contains("100 B is not a Falcon firmware image"),
        "{fw}"
    );
    let (_, fw, _) = firmware(Some(8492));
    assert_eq!(fw["status"], "ok", "{fw}");
    assert!(fw["finding"].as_str().unwrap().contains("8492 B"), "{fw}");
}

#[test]
fn a_realtime_request_is_checked_against_the_limits_and_cores() {
    let tmp = TempDir::new().unwrap();
    let text = fs::read_to_string(Path::new(REPO).join("tests/data/profiles/quick-scan.toml"))
        .unwrap()
        .replace(
            "[device]\n",
            "[device]\nrealtime = { priority = 10, lock_memory = true, cpu = 1000 }\n",
        );
    let profile = tmp.path().join("rt.toml");
    fs::write(&profile, text).unwrap();
    let r = doctor(&["--json", "-p", p(&profile), "--dataset", p(tmp.path())]);
    // Real-time shortfalls warn (the servo runs on without them): exit 0.
    assert_eq!(r.code, Some(0), "{r:?}");
    let v = json(&r);
    for name in ["rt-priority", "memory-lock"] {
        let c = check(&v, name);
        assert!(
            ["ok", "warn"].contains(&c["status"].as_str().unwrap()),
            "{c}"
        );
    }
    let cpu = check(&v, "cpu-pinning");
    assert_eq!(cpu["status"], "warn", "{cpu}");
    assert!(
        cpu["finding"].as_str().unwrap().contains("core 1000 asked"),
        "{cpu}"
    );
}

#[test]
fn on_a_small_terminal_the_size_is_read_and_warned_about() {
    let tmp = TempDir::new().unwrap();
    let pty = native_pty_system()
        .openpty(PtySize {
            rows: 20,
            cols: 60,
            pixel_width: 0,
            pixel_height: 0,
        })
        .unwrap();
    let mut cmd = CommandBuilder::new(BIN);
    let profile = thesis_at_normal_priority(tmp.path());
    cmd.args([
        "doctor",
        "--profile",
        p(&profile),
        "--dataset",
        p(tmp.path()),
    ]);
    cmd.cwd(REPO);
    cmd.env("TERM", "xterm-256color");
    cmd.env_remove("NO_COLOR");
    let mut child = pty.slave.spawn_command(cmd).unwrap();
    drop(pty.slave);
    let mut reader = pty.master.try_clone_reader().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        while let Ok(n) = reader.read(&mut buf) {
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
        }
        let _ = tx.send(out);
    });
    let status = child.wait().unwrap();
    drop(pty.master);
    let out = rx.recv_timeout(Duration::from_secs(10)).unwrap_or_default();
    let text = String::from_utf8_lossy(&out).replace('\r', "");
    assert!(status.success(), "{status:?}\n{text}");
    assert!(
        text.contains("warn  terminal    60×20 is smaller than the console's 80×24"),
        "{text}"
    );
    assert!(
        text.contains("fix: make the window at least 80 columns by 24 rows"),
        "{text}"
    );
    assert!(text.contains("ok    colour      256 colours"), "{text}");
}

#[test]
fn help_has_an_example() {
    let r: Run = Command::new(BIN)
        .args(["doctor", "--help"])
        .output()
        .unwrap()
        .into();
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout
            .contains("hapticlab doctor --profile profiles/thesis-falcon.toml"),
        "{r:?}"
    );
    assert!(
        r.stdout.contains("--json") && r.stdout.contains("--dataset"),
        "{r:?}"
    );
}

/// `doctor --udev-rule` prints the rule a binary-only install needs, the
/// very text of contrib/70-novint-falcon.rules: numbered 70 so that
/// `uaccess` runs before systemd's 73-seat-late.rules, group `users` (which
/// Debian, Fedora and Arch all have), the Falcon's ids; and checks nothing.
#[test]
fn udev_rule_prints_the_shipped_rule_and_checks_nothing() {
    let r = doctor(&["--udev-rule"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let shipped =
        fs::read_to_string(Path::new(REPO).join("contrib/70-novint-falcon.rules")).unwrap();
    assert_eq!(r.stdout.trim_end(), shipped.trim_end(), "{r:?}");
    let rule = r
        .stdout
        .lines()
        .find(|l| !l.starts_with('#') && !l.trim().is_empty())
        .expect("a rule line");
    for part in [
        r#"ATTRS{idVendor}=="0403""#,
        r#"ATTRS{idProduct}=="cb48""#,
        r#"TAG+="uaccess""#,
        r#"GROUP="users""#,
    ] {
        assert!(rule.contains(part), "{part} missing: {rule}");
    }
    assert!(
        !r.stdout.contains("ok ") && !r.stdout.contains("FAIL"),
        "{r:?}"
    );
    // It prints, it does not report: --json makes no sense with it.
    let r = doctor(&["--udev-rule", "--json"]);
    assert_eq!(r.code, Some(2), "{r:?}");
}
