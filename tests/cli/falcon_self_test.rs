//! `hapticlab devices --self-test` end to end on the emulated Falcon (real
//! time, the emulator's simulated hand doing what the user is asked): a
//! clean device passes every step and exits 0; a motor wired backwards
//! fails the force pulses and exits 1; declined pulses skip and exit 1;
//! bad input exits 2. Each run waits for the binary to exit, never for time.

use crate::common::run::Run;

fn self_test(args: &[&str]) -> Run {
    let mut all = vec!["devices", "--self-test"];
    all.extend_from_slice(args);
    crate::common::hapticlab()
        .args(&all)
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap()
        .into()
}

/// The report's line for a step: its verdict word.
fn verdict<'a>(stdout: &'a str, step: &str) -> Option<&'a str> {
    stdout.lines().find_map(|l| {
        let rest = l.strip_prefix(step)?;
        rest.split_whitespace().next()
    })
}

#[test]
fn the_thesis_emulator_passes_every_step() {
    let r = self_test(&["-p", "profiles/thesis-emulator.toml", "--yes"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    for step in [
        "open", "leds", "link", "homing", "encoders", "pulse x", "pulse y", "pulse z",
    ] {
        assert_eq!(verdict(&r.stdout, step), Some("PASS"), "{step}: {r:?}");
    }
    assert!(
        r.stdout.contains("result: PASS")
            && r.stdout.contains("hapticlab Falcon self-test")
            && r.stdout.contains("firmware already running")
            && r.stdout.contains("link:")
            && r.stdout.contains("forces zeroed"),
        "{r:?}"
    );
    // The user was told what to do, step by step; positions came as the grip moved.
    assert!(
        r.stderr.contains("pull the grip all the way out")
            && r.stderr.contains("move the grip around")
            && r.stderr.contains("hold the grip lightly")
            && r.stderr.contains("grip at"),
        "{r:?}"
    );
}

#[test]
fn a_motor_wired_backwards_fails_the_pulses_and_exits_1() {
    let r = self_test(&[
        "-p",
        "tests/data/profiles/thesis-emulator-reversed-motor.toml",
        "--yes",
        "--json",
    ]);
    assert_eq!(r.code, Some(1), "{r:?}");
    let report: serde_json::Value = serde_json::from_str(&r.stdout).expect("a JSON report");
    assert_eq!(report["passed"], false, "{r:?}");
    let steps = report["steps"].as_array().unwrap();
    let verdict_of = |name: &str| {
        steps
            .iter()
            .find(|s| s["name"] == name)
            .map(|s| s["verdict"].as_str().unwrap().to_string())
    };
    assert_eq!(verdict_of("encoders").as_deref(), Some("pass"), "{r:?}");
    let failed: Vec<&str> = steps
        .iter()
        .filter(|s| s["verdict"] == "fail")
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert!(
        !failed.is_empty() && failed.iter().all(|n| n.starts_with("pulse ")),
        "{r:?}"
    );
    assert_eq!(report["pulses"].as_array().unwrap().len(), 3);
    assert!(report["link"]["packets"].as_u64().unwrap() > 1000, "{r:?}");
    assert!(
        r.stderr.contains("self-test did not pass") && r.stderr.contains("pulse"),
        "{r:?}"
    );
}

#[test]
fn declined_pulses_are_skipped_and_the_test_does_not_pass() {
    // Standard input is empty: the question before the pulses reads no "y".
    let r = self_test(&["-p", "profiles/thesis-emulator.toml"]);
    assert_eq!(r.code, Some(1), "{r:?}");
    assert!(r.stderr.contains("[y/N]"), "{r:?}");
    for step in ["pulse x", "pulse y", "pulse z"] {
        assert_eq!(verdict(&r.stdout, step), Some("SKIPPED"), "{r:?}");
    }
    assert_eq!(verdict(&r.stdout, "encoders"), Some("PASS"), "{r:?}");
}

#[test]
fn bad_input_exits_2_naming_what() {
    // The simulator is no Falcon.
    let r = self_test(&[]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("--self-test needs a Falcon profile") && r.stderr.contains("\"sim\""),
        "{r:?}"
    );
    // A real Falcon's profile without its firmware file: refused before any USB.
    let r = self_test(&["-p", "profiles/thesis-falcon.toml"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("nvent_firmware.bin"), "{r:?}");
    // --yes and --json belong to --self-test.
    let r: Run = crate::common::hapticlab()
        .args(["devices", "--yes"])
        .output()
        .unwrap()
        .into();
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("--self-test"), "{r:?}");
}

/// A copy of the thesis emulator profile in `dir` with `extra` lines added
/// to its `[falcon.emulator]` table.
fn emulator_profile(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string("profiles/thesis-emulator.toml").unwrap();
    let text = text.replacen(
        "[falcon.emulator]\n",
        &format!("[falcon.emulator]\n{extra}\n"),
        1,
    );
    let path = dir.join("emulator.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The self-test interrupted by `signals` (sent `apart` from each other)
/// once the force pulses begin, on firmware that keeps the last force.
fn interrupted_by(signals: &[i32]) -> Run {
    use std::io::BufRead;
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let profile = emulator_profile(dir.path(), "keeps_last_force = true");
    let mut child = crate::common::hapticlab()
        .args(["devices", "--self-test", "--yes", "--json", "-p"])
        .arg(&profile)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in std::io::BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
        {
            if line.contains("pulse along x") {
                let _ = tx.send(());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    // Waits for the pulses to begin, not for a time.
    rx.recv_timeout(Duration::from_secs(120))
        .expect("the pulses never began");
    for &sig in signals {
        assert_eq!(unsafe { libc::kill(child.id() as i32, sig) }, 0);
    }
    let give_up = Instant::now() + Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > give_up {
            let _ = child.kill();
            panic!("the self-test did not end after {signals:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: reader.join().unwrap(),
    }
}

#[test]
fn each_signal_ends_the_self_test_with_the_emulated_motors_at_zero() {
    for signals in [
        &[libc::SIGINT][..],
        &[libc::SIGTERM],
        &[libc::SIGHUP],
        // A second Ctrl-C still zeroes the forces before the process ends.
        &[libc::SIGINT, libc::SIGINT],
    ] {
        let r = interrupted_by(signals);
        assert_eq!(r.code, Some(1), "{signals:?}: {r:?}");
        let report: serde_json::Value = serde_json::from_str(&r.stdout).expect("a JSON report");
        let text = report.to_string();
        assert!(text.contains("interrupted"), "{signals:?}: {r:?}");
        assert_eq!(
            report["motors_after"],
            serde_json::json!([0, 0, 0]),
            "{signals:?}: {r:?}"
        );
        assert_eq!(report["zero_force_confirmed"], true, "{signals:?}: {r:?}");
        // Measured before the pulses began: the link's quality.
        assert!(
            report["link"]["round_trip_p99_ms"].as_f64().is_some()
                && report["link"]["missed_per_1000"].as_f64().is_some(),
            "{r:?}"
        );
        assert!(!r.stderr.contains("panicked"), "{r:?}");
    }
}
