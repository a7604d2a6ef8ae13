//! The servo loop's last line of defence: a front end that has gone (its
//! command channel disconnected) or is stuck (its heartbeat stopped) makes
//! the loop zero the forces and end the scan on its own, kept as aborted.
//! Under the virtual clock, so loop time is exact and the machine's load
//! does not matter.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use hapticlab::clock::VirtualClock;
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::{LoadedProfile, Profile};
use hapticlab::recorder::SavedScan;
use hapticlab::servo::{Command, Links, Mode, ServoLoop, WATCHDOG_S};

/// The thesis profile: its scan leg runs from about 3.4 s to 12.7 s of loop time.
fn thesis() -> Profile {
    LoadedProfile::thesis().profile
}

type Servo = ServoLoop<SimDevice, VirtualClock>;

/// A loop on the thesis profile, commanded through a channel, 5 s into a
/// scan to `file`: recording, forces on.
fn mid_scan(
    p: &Profile,
    file: &Path,
    heartbeat: Option<Arc<AtomicU64>>,
) -> (
    Servo,
    crossbeam_channel::Sender<Command>,
    hapticlab::recorder::Recorder,
) {
    let (recorder, sink) = hapticlab::recorder::start();
    let (tx, rx) = crossbeam_channel::bounded(16);
    let links = Links {
        commands: Some(rx),
        ..Links::default()
    };
    let dev = SimDevice::new(p, Path::new("."), Some("S2"), 5).unwrap();
    let clock = VirtualClock::new(p.rig().unwrap().device.rate_hz, 0.0, 0.0, 5);
    let mut servo = ServoLoop::new(dev, clock, p.rig().unwrap(), sink, links);
    if let Some(h) = heartbeat {
        servo.watch_heartbeat(h);
    }
    tx.send(Command::StartScan {
        path: file.to_path_buf(),
        meta: vec![("label".into(), toml::Value::String("S2".into()))],
    })
    .unwrap();
    for _ in 0..5000 {
        servo.tick().unwrap();
    }
    assert_eq!(servo.mode(), Mode::Test);
    assert!(servo.scan_pending());
    assert!(
        servo.device().applied_force().iter().any(|f| *f != 0.0),
        "forces are on mid-scan"
    );
    (servo, tx, recorder)
}

fn saved_one(recorder: hapticlab::recorder::Recorder) -> SavedScan {
    let mut saved = recorder.join();
    assert_eq!(saved.len(), 1, "{saved:?}");
    saved.remove(0)
}

fn assert_forces_off(servo: &Servo) {
    assert_eq!(servo.mode(), Mode::Manual);
    assert_eq!(servo.device().applied_force(), [0.0; 3]);
}

#[test]
fn a_disconnected_command_channel_halts_the_loop_safely() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("S2_001.csv");
    let (mut servo, tx, recorder) = mid_scan(&p, &file, None);
    drop(tx);
    let halt = servo.tick().unwrap_err();
    assert_eq!(halt, hapticlab::servo::Halt::Interrupted);
    assert_forces_off(&servo);
    drop(servo);
    let saved = saved_one(recorder);
    assert!(!saved.complete);
    assert!(
        saved
            .aborted
            .as_deref()
            .unwrap()
            .contains("command channel closed"),
        "{saved:?}"
    );
    let rec = hapticlab::recording::read(&file).unwrap();
    assert!(!rec.is_complete() && rec.len() > 100, "{} rows", rec.len());
    assert!(rec.aborted().unwrap().contains("front end is gone"));
}

#[test]
fn a_heartbeat_that_stops_stops_the_motion() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("S2_001.csv");
    let beat = Arc::new(AtomicU64::new(0));
    let (mut servo, tx, recorder) = mid_scan(&p, &file, Some(beat.clone()));
    // Not armed before the first beat: 5 s passed without one and the
    // scan runs. Beating every 30 ms (a console's frames) keeps it running.
    for i in 0..200 {
        if i % 30 == 0 {
            beat.fetch_add(1, Ordering::Relaxed);
        }
        servo.tick().unwrap();
    }
    assert_eq!(
        servo.mode(),
        Mode::Test,
        "a beating front end is not stopped"
    );
    // The beat stops: the motion stops WATCHDOG_S later, not before.
    let ticks = (WATCHDOG_S * p.rig().unwrap().device.rate_hz) as usize;
    for _ in 0..ticks - 50 {
        servo.tick().unwrap();
    }
    assert_eq!(
        servo.mode(),
        Mode::Test,
        "stopped before the watchdog's time"
    );
    for _ in 0..100 {
        servo.tick().unwrap();
    }
    assert_forces_off(&servo);
    // It stays stopped.
    for _ in 0..10 {
        servo.tick().unwrap();
    }
    assert_forces_off(&servo);
    drop(tx);
    drop(servo);
    let saved = saved_one(recorder);
    assert!(!saved.complete);
    assert!(
        saved.aborted.as_deref().unwrap().contains("no heartbeat"),
        "{saved:?}"
    );
    let rec = hapticlab::recording::read(&file).unwrap();
    assert!(rec.aborted().unwrap().contains("stopped responding"));
}

#[test]
fn a_loop_never_heartbeaten_is_not_watched() {
    // Headless `scan` never beats: its scans run to the end.
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("S2_001.csv");
    let beat = Arc::new(AtomicU64::new(0));
    let (mut servo, _tx, recorder) = mid_scan(&p, &file, Some(beat));
    for _ in 0..10_000 {
        servo.tick().unwrap();
    }
    drop(servo);
    let saved = saved_one(recorder);
    assert!(saved.complete, "{saved:?}");
}
