//! The real Falcon driver over the byte-level emulator: whole scans in
//! virtual time (clean and with faults), the firmware upload failing and
//! recovering, bad firmware files, and — through the binary — a live scan
//! whose cable is pulled mid-stroke, `devices`, and the exit codes.

use std::path::Path;

use hapticlab::acquire::{SimulateOptions, simulate_dataset, simulate_one};
use hapticlab::classify::Model;
use hapticlab::device::falcon::{self, OpenError};
use hapticlab::evaluate::{evaluate, split};
use hapticlab::profile::Evaluation;
use hapticlab::profile::LoadedProfile;
use hapticlab::recording;
use hapticlab::support::load_examples;

fn quick() -> LoadedProfile {
    LoadedProfile::load(Path::new("tests/data/profiles/quick-emulator.toml")).unwrap()
}

/// A stand-in firmware image: random bytes of nvent_firmware.bin's size
/// (the emulator echoes whatever it is sent; no real image is ever used).
fn fake_firmware(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("nvent_firmware.bin");
    let bytes: Vec<u8> = (0..8492u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn a_whole_scan_runs_through_the_emulated_falcon() {
    let lp = quick();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("S2/S2_001.csv");
    let (saved, stats) = simulate_one(&lp, "S2", 7, &path).unwrap();
    assert!(saved.complete && saved.rows > 700, "{saved:?}");
    let link = stats.link.expect("the Falcon reports its link");
    assert_eq!(link.bad_packets, 0);
    assert_eq!(link.missed_replies, 0);
    assert!(link.replies >= saved.rows as u64, "{link:?}");
    let rec = recording::read(&path).unwrap();
    assert_eq!(rec.meta_str("device"), Some("falcon-emulator"));
    // The probe rode the texture: its height stays near the scan height.
    let y = rec.column("y_m").unwrap();
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    assert!((mean - -0.0043).abs() < 0.001, "mean height {mean}");
}

/// A link whose replies all come 1.5 ms late (`slow_link_ms`, a hub or a
/// loaded host): the scan runs on, holding positions on missed ticks, and
/// its link statistics say so (most replies missed), where a clean link
/// misses none; the line `scan` prints carries the count.
#[test]
fn a_slow_link_is_reported_in_the_scan_statistics_not_hidden() {
    let dir = tempfile::tempdir().unwrap();
    let mut lp = quick();
    lp.profile.falcon.as_mut().unwrap().emulator.slow_link_ms = 1.5;
    let path = dir.path().join("S2/S2_001.csv");
    let (saved, stats) = simulate_one(&lp, "S2", 7, &path).unwrap();
    let link = stats.link.expect("the Falcon reports its link");
    let per_1000 = 1000.0 * link.missed_replies as f64 / stats.ticks as f64;
    assert!(per_1000 > 300.0, "{per_1000:.1} missed per 1000: {link:?}");
    let summary = stats.summary();
    assert!(
        summary.contains(&format!("{} missed replies", link.missed_replies)),
        "{summary}"
    );
    assert!(saved.rows > 0, "{saved:?}");
}

/// The thesis scan through the timed link (`[falcon.emulator.timing]` in
/// profiles/thesis-emulator.toml): the loop keeps 1 kHz; replies that come
/// too late are counted as missed, never fatal. Prints the figure: missed
/// replies per 1000 ticks.
#[test]
fn the_thesis_scan_keeps_1_khz_through_the_timed_link() {
    let lp = LoadedProfile::load(Path::new("profiles/thesis-emulator.toml")).unwrap();
    assert!(
        lp.profile
            .falcon
            .as_ref()
            .unwrap()
            .emulator
            .timing
            .is_some()
    );
    let dir = tempfile::tempdir().unwrap();
    let (saved, stats) = simulate_one(&lp, "S3", 5, &dir.path().join("S3/S3_001.csv")).unwrap();
    assert!(saved.complete && saved.rows > 8900, "{saved:?}");
    assert!((stats.rate_hz - 1000.0).abs() < 2.0, "{stats:?}");
    let link = stats.link.unwrap();
    assert!(link.missed_replies > 0, "no reply was ever late: {link:?}");
    assert!(
        link.replies + link.missed_replies >= stats.ticks,
        "{link:?}"
    );
    println!(
        "missed replies per 1000 ticks through the timed link: {:.2} ({} of {} ticks)",
        1000.0 * link.missed_replies as f64 / stats.ticks as f64,
        link.missed_replies,
        stats.ticks
    );
}

/// The figures issue 14 asks for, on the thesis scan leg (one scan of each
/// texture through `profiles/thesis-emulator.toml`'s timed link, virtual
/// time): saturated ticks and missed replies per 1000 ticks, printed with
/// `--nocapture`. The bounds are sanity, not timing: replies are missed now
/// and then but rarely, and the path's forces (8 N limit) rarely or never
/// drive a motor to ±4095.
#[test]
fn saturated_ticks_and_missed_replies() {
    let lp = LoadedProfile::load(Path::new("profiles/thesis-emulator.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (mut ticks, mut missed, mut saturated) = (0u64, 0u64, 0u64);
    for (i, label) in ["S1", "S2", "S3", "S4"].into_iter().enumerate() {
        let path = dir.path().join(format!("{label}/{label}_001.csv"));
        let (saved, stats) = simulate_one(&lp, label, 11 + i as u64, &path).unwrap();
        assert!(saved.complete, "{saved:?}");
        let link = stats.link.expect("the Falcon reports its link");
        assert!(link.saturated_ticks <= stats.ticks && link.missed_replies <= stats.ticks);
        println!(
            "{label}: {} scan ticks, {:.2} saturated and {:.2} missed replies per 1000 ticks",
            stats.ticks,
            1000.0 * link.saturated_ticks as f64 / stats.ticks as f64,
            1000.0 * link.missed_replies as f64 / stats.ticks as f64,
        );
        ticks += stats.ticks;
        missed += link.missed_replies;
        saturated += link.saturated_ticks;
    }
    let per_1000 = |n: u64| 1000.0 * n as f64 / ticks as f64;
    println!(
        "thesis scan leg, 4 scans, {ticks} ticks: saturated ticks {:.2} per 1000 ({saturated}), missed replies {:.2} per 1000 ({missed})",
        per_1000(saturated),
        per_1000(missed)
    );
    assert!(ticks > 4 * 8900, "{ticks}");
    // The timed link loses a few replies, never a large share.
    assert!(missed > 0 && per_1000(missed) < 20.0, "{missed} of {ticks}");
    // Saturation is an exception on the thesis path, not the rule.
    assert!(per_1000(saturated) < 10.0, "{saturated} of {ticks}");
}

/// The thesis's result through the whole driver stack (reduced: 12 scans
/// per texture, 8 to train and 4 to test; `hapticlab simulate --per-class 30`
/// on profiles/thesis-emulator.toml and `evaluate` give 40/40).
#[test]
fn the_thesis_result_holds_through_the_emulated_falcon() {
    let lp = LoadedProfile::load(Path::new("profiles/thesis-emulator.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let opts = SimulateOptions {
        out: dir.path().to_path_buf(),
        per_class: 12,
        seed: 1,
        threads: 2,
        gzip: false,
        overwrite: false,
    };
    let saved = simulate_dataset(&lp, &opts, &|_, _| {}).unwrap();
    assert!(saved.iter().all(|s| s.complete), "{saved:?}");
    let p = &lp.profile;
    let examples = load_examples(&[dir.path().to_path_buf()], &p.analysis).unwrap();
    let eval = Evaluation {
        train_per_class: 8,
        test_per_class: 4,
        shuffle_seed: None,
        ..Evaluation::default()
    };
    let split = split(examples, &eval).unwrap();
    let model = Model::train(&p.name, &p.analysis, &p.classifier, split.train).unwrap();
    let report = evaluate(&model, &split.test).unwrap();
    assert!(report.correct() >= 15, "{}", report.table());
}

#[test]
fn lost_garbled_and_split_replies_are_counted_and_the_scan_completes() {
    let mut lp = quick();
    let e = &mut lp.profile.falcon.as_mut().unwrap().emulator;
    e.drop_rate = 0.02;
    e.garble_rate = 0.02;
    e.split_rate = 0.2;
    let dir = tempfile::tempdir().unwrap();
    let (saved, stats) = simulate_one(&lp, "S3", 11, &dir.path().join("S3/S3_001.csv")).unwrap();
    assert!(saved.complete, "{saved:?}");
    let link = stats.link.unwrap();
    assert!(link.missed_replies > 5, "{link:?}");
    assert!(link.bad_packets > 5, "{link:?}");
    assert!(link.replies > link.packets * 9 / 10, "{link:?}");
}

#[test]
fn an_upload_that_fails_twice_is_retried_then_scans() {
    let dir = tempfile::tempdir().unwrap();
    let fw = fake_firmware(dir.path());
    let mut lp = quick();
    let f = lp.profile.falcon.as_mut().unwrap();
    f.firmware = Some(fw.clone());
    f.emulator.firmware_loaded = false;
    f.emulator.upload_failures = 2;
    let mut log = Vec::new();
    let dev = falcon::open_emulated(&lp, Some("S1"), 3, &mut |m| log.push(m.to_string())).unwrap();
    let report = dev.stats().firmware;
    assert_eq!(report.attempts, 3, "{log:?}");
    assert!(
        report.failures.iter().all(|f| f.contains("echo differs")),
        "{report:?}"
    );
    assert!(log.iter().any(|m| m.contains("attempt 3 of 20")), "{log:?}");
    assert_eq!(log.last().map(String::as_str), Some("firmware running"));
    drop(dev);
    // A whole scan through the same setup.
    let (saved, _) = simulate_one(&lp, "S1", 3, &dir.path().join("S1/S1_001.csv")).unwrap();
    assert!(saved.complete);
}

#[test]
fn a_missing_or_wrong_firmware_file_is_bad_input_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let mut lp = quick();
    let f = lp.profile.falcon.as_mut().unwrap();
    f.emulator.firmware_loaded = false;
    f.firmware = Some(dir.path().join("nowhere/nvent_firmware.bin"));
    let Err(OpenError::BadInput(m)) = falcon::open_emulated(&lp, None, 1, &mut |_| {}) else {
        panic!("a missing firmware file must be bad input");
    };
    assert!(
        m.contains("nowhere/nvent_firmware.bin") && m.contains("libnifalcon"),
        "{m}"
    );
    let short = dir.path().join("short.bin");
    std::fs::write(&short, [0u8; 512]).unwrap();
    lp.profile.falcon.as_mut().unwrap().firmware = Some(short);
    let Err(OpenError::BadInput(m)) = falcon::open_emulated(&lp, None, 1, &mut |_| {}) else {
        panic!("a wrong-size firmware file must be bad input");
    };
    assert!(m.contains("512 bytes") && m.contains("8492"), "{m}");
}

fn hapticlab(args: &[&str]) -> (Option<i32>, String, String) {
    let o = crate::common::hapticlab().args(args).output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn unplugging_mid_scan_stops_it_keeps_the_samples_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, stdout, stderr) = hapticlab(&[
        "scan",
        "-p",
        "tests/data/profiles/quick-emulator-unplug.toml",
        "--label",
        "S2",
        "--out",
        out,
    ]);
    assert_eq!(code, Some(1), "{stdout}\n{stderr}");
    assert!(stderr.contains("pull the grip all the way out"), "{stderr}");
    assert!(
        stdout.contains("unplugged") && stdout.contains("samples kept"),
        "{stdout}"
    );
    let rec = recording::read(&dir.path().join("S2/S2_001.csv")).unwrap();
    assert!(!rec.is_complete());
    assert!(rec.len() > 50, "{} rows", rec.len());
}

#[test]
fn a_live_scan_through_the_emulator_completes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, stdout, stderr) = hapticlab(&[
        "scan",
        "-p",
        "tests/data/profiles/quick-emulator.toml",
        "--label",
        "S4",
        "--out",
        out,
    ]);
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    assert!(stderr.contains("homed: the LEDs are blue"), "{stderr}");
    assert!(
        stdout.contains("complete") && stdout.contains("link:"),
        "{stdout}"
    );
}

#[test]
fn devices_and_the_falcon_exit_codes() {
    let (code, stdout, _) = hapticlab(&["devices"]);
    assert_eq!(code, Some(0));
    assert!(
        stdout.contains("Novint Falcons") && stdout.contains("HID triggers"),
        "{stdout}"
    );
    // simulate refuses a real Falcon: bad input.
    let dir = tempfile::tempdir().unwrap();
    let (code, _, stderr) = hapticlab(&[
        "simulate",
        "-p",
        "profiles/thesis-falcon.toml",
        "--per-class",
        "1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("scan"), "{stderr}");
    // scan on a real Falcon without its firmware file: bad input, before any USB.
    let (code, _, stderr) = hapticlab(&[
        "scan",
        "-p",
        "profiles/thesis-falcon.toml",
        "--label",
        "S1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("profiles/firmware/nvent_firmware.bin") && stderr.contains("libnifalcon"),
        "{stderr}"
    );
}

/// Trigger presses drive `scan`: start begins each scan, abort stops one.
#[test]
fn trigger_presses_start_and_abort_live_scans() {
    use hapticlab::acquire::{LiveHooks, LiveScans, scan_live_with};
    use hapticlab::triggers::{TriggerAction, TriggerEvent};
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;

    let lp = quick();
    let dir = tempfile::tempdir().unwrap();
    let press = |action| TriggerEvent::Action {
        action,
        source: "pedal".into(),
    };
    let run = |events: Vec<TriggerEvent>, count: usize| {
        let (tx, rx) = crossbeam_channel::unbounded();
        for e in events {
            tx.send(e).unwrap();
        }
        let req = LiveScans {
            label: "S2".into(),
            texture: None,
            count,
            out: dir.path().to_path_buf(),
            seed: 1,
        };
        let mut notes = Vec::new();
        let mut scans = Vec::new();
        let r = scan_live_with(
            &lp,
            &req,
            Arc::new(AtomicBool::new(false)),
            LiveHooks {
                on_scan: &mut |s| scans.push(s.saved.clone()),
                on_note: &mut |m| notes.push(m.to_string()),
                triggers: Some(rx),
            },
        );
        drop(tx);
        (r.map(|v| v.len()).map_err(|e| e.to_string()), scans, notes)
    };
    // One press, one complete scan.
    let (n, scans, notes) = run(vec![press(TriggerAction::Start)], 1);
    assert_eq!(n, Ok(1));
    assert!(scans[0].complete, "{scans:?}");
    assert!(notes.iter().any(|m| m.contains("press start")), "{notes:?}");
    // Start, then abort while it runs: the scan stops, and no second one starts.
    let (n, scans, _) = run(
        vec![press(TriggerAction::Start), press(TriggerAction::Abort)],
        2,
    );
    assert_eq!(n, Ok(1));
    assert!(!scans[0].complete);
    assert_eq!(scans[0].aborted.as_deref(), Some("aborted by the user"));
    // Abort while waiting: nothing runs.
    let (n, _, notes) = run(vec![press(TriggerAction::Abort)], 1);
    assert_eq!(n, Ok(0));
    assert!(
        notes.iter().any(|m| m.contains("no more scans")),
        "{notes:?}"
    );
}
