//! The servo loop end to end in virtual time: scans recorded whole, and every
//! way a scan can stop early leaves its samples on disk and the device safe.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use hapticlab::clock::{Clock, VirtualClock};
use hapticlab::device::sim::SimDevice;
use hapticlab::device::{DeviceError, HapticDevice, Reading};
use hapticlab::profile::{LoadedProfile, Profile};
use hapticlab::recording;
use hapticlab::servo::{Command, Links, Mode, ServoEvent, ServoLoop};

fn thesis() -> Profile {
    LoadedProfile::thesis().profile
}

/// A device that wraps the simulator and can fail, stall or panic on cue,
/// and remembers whether it was made safe.
struct Faulty {
    inner: SimDevice,
    reads: usize,
    fail_after: Option<usize>,
    panic_after: Option<usize>,
    safe: Arc<AtomicBool>,
    commands: Arc<AtomicUsize>,
}

impl HapticDevice for Faulty {
    fn kind(&self) -> &'static str {
        "faulty"
    }
    fn read(&mut self, t: f64) -> Result<Reading, DeviceError> {
        self.reads += 1;
        if self.fail_after.is_some_and(|n| self.reads > n) {
            return Err(DeviceError::Disconnected("unplugged".into()));
        }
        if self.panic_after.is_some_and(|n| self.reads > n) {
            panic!("injected panic in the device");
        }
        self.inner.read(t)
    }
    fn command(&mut self, f: [f64; 3]) -> Result<(), DeviceError> {
        assert!(f.iter().all(|v| v.is_finite()));
        self.safe.store(f == [0.0; 3], Ordering::SeqCst);
        self.commands.fetch_add(1, Ordering::SeqCst);
        self.inner.command(f)
    }
    fn make_safe(&mut self) {
        self.safe.store(true, Ordering::SeqCst);
        self.inner.make_safe();
    }
}

fn faulty(
    p: &Profile,
    fail_after: Option<usize>,
    panic_after: Option<usize>,
) -> (Faulty, Arc<AtomicBool>) {
    let safe = Arc::new(AtomicBool::new(true));
    (
        Faulty {
            inner: SimDevice::new(p, Path::new("."), Some("S2"), 5).unwrap(),
            reads: 0,
            fail_after,
            panic_after,
            safe: safe.clone(),
            commands: Arc::new(AtomicUsize::new(0)),
        },
        safe,
    )
}

fn virtual_clock(p: &Profile) -> VirtualClock {
    VirtualClock::new(p.rig().unwrap().device.rate_hz, 0.00002, 0.1, 3)
}

/// Run until the scan is no longer pending or the loop halts; the loop is dropped after.
fn run_scan<D: HapticDevice, C: Clock>(
    mut servo: ServoLoop<D, C>,
    max_ticks: u64,
) -> Option<String> {
    let mut halt = None;
    for _ in 0..max_ticks {
        if let Err(h) = servo.tick() {
            halt = Some(h.to_string());
            break;
        }
        if !servo.scan_pending() {
            break;
        }
    }
    halt
}

#[test]
fn a_virtual_scan_records_the_whole_scan_leg() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("S2").join("S2_001.csv");
    let (recorder, sink) = hapticlab::recorder::start();
    let (ev_tx, ev_rx) = crossbeam_channel::bounded(16);
    let links = Links {
        events: Some(ev_tx),
        ..Links::default()
    };
    let dev = SimDevice::new(&p, Path::new("."), Some("S2"), 11).unwrap();
    let mut servo = ServoLoop::new(dev, virtual_clock(&p), p.rig().unwrap(), sink, links);
    servo.apply(Command::StartScan {
        path: file.clone(),
        meta: vec![("label".into(), toml::Value::String("S2".into()))],
    });
    assert_eq!(servo.mode(), Mode::Test);
    assert_eq!(run_scan(servo, 20_000), None);
    let saved = recorder.join();
    assert_eq!(saved.len(), 1);
    assert!(saved[0].complete, "{saved:?}");
    let rec = recording::read(&file).unwrap();
    assert!(rec.is_complete());
    // 8.97 cm at 1 cm/s plus 0.3 s of dwell, at 1 kHz.
    assert!(
        (rec.len() as i64 - 9270).abs() <= 3,
        "{} samples",
        rec.len()
    );
    let t = rec.column("t_s").unwrap();
    assert_eq!(t[0], 0.0);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "time must increase");
    let x = rec.column("x_m").unwrap();
    assert!(
        (x[0] + 0.045).abs() < 0.0005,
        "starts at waypoint 4: {}",
        x[0]
    );
    assert!(
        *x.last().unwrap() > 0.0440,
        "reaches waypoint 5: {}",
        x.last().unwrap()
    );
    // The probe rides on the texture: y stays within the crest and groove heights.
    let y = rec.column("y_m").unwrap();
    let (lo, hi) = y[2000..]
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi < -0.0036 && lo > -0.0056, "y from {lo} to {hi}");
    assert!(
        hi - lo > 0.0004,
        "the corrugation shows in the trace: {}",
        hi - lo
    );
    let events: Vec<_> = ev_rx.try_iter().collect();
    assert!(matches!(events[0], ServoEvent::ScanStarted { .. }));
    match &events[1] {
        ServoEvent::ScanEnded {
            samples,
            aborted,
            stats,
            ..
        } => {
            assert_eq!(*samples as usize, rec.len());
            assert_eq!(*aborted, None);
            assert!((stats.rate_hz - 1000.0).abs() < 1.0, "{}", stats.rate_hz);
            assert_eq!(stats.dropped_telemetry, 0);
        }
        e => panic!("unexpected {e:?}"),
    }
}

#[test]
fn a_device_that_vanishes_mid_scan_leaves_an_incomplete_recording_and_zero_forces() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.csv");
    let (recorder, sink) = hapticlab::recorder::start();
    // The scan leg starts after about 3.4 s of transit; unplug at 6 s.
    let (dev, safe) = faulty(&p, Some(6000), None);
    let mut servo = ServoLoop::new(
        dev,
        virtual_clock(&p),
        p.rig().unwrap(),
        sink,
        Links::default(),
    );
    servo.apply(Command::StartScan {
        path: file.clone(),
        meta: vec![],
    });
    let halt = run_scan(servo, 20_000).expect("the loop halts");
    assert!(halt.contains("unplugged"), "{halt}");
    assert!(safe.load(Ordering::SeqCst), "forces zeroed");
    let saved = recorder.join();
    assert!(!saved[0].complete);
    assert!(saved[0].aborted.as_deref().unwrap().contains("unplugged"));
    let rec = recording::read(&file).unwrap();
    assert!(!rec.is_complete());
    assert!(
        rec.len() > 2000 && rec.len() < 3000,
        "{} samples kept",
        rec.len()
    );
}

/// A clock that falls behind by two periods on every tick after `from`.
struct Stalling {
    inner: VirtualClock,
    ticks: u64,
    from: u64,
    extra: f64,
}

impl Clock for Stalling {
    fn wait_until(&mut self, d: f64) -> f64 {
        self.ticks += 1;
        let t = self.inner.wait_until(d);
        if self.ticks > self.from {
            self.extra += 0.0008;
        }
        t + self.extra
    }
    fn now(&self) -> f64 {
        self.inner.now() + self.extra
    }
    fn is_virtual(&self) -> bool {
        true
    }
    fn stall(&mut self, secs: f64) {
        self.inner.stall(secs);
    }
}

#[test]
fn a_streak_of_missed_deadlines_stops_the_motion_and_keeps_the_samples() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.csv");
    let (recorder, sink) = hapticlab::recorder::start();
    let (dev, safe) = faulty(&p, None, None);
    let clock = Stalling {
        inner: virtual_clock(&p),
        ticks: 0,
        from: 5000,
        extra: 0.0,
    };
    let (ev_tx, ev_rx) = crossbeam_channel::bounded(16);
    let links = Links {
        events: Some(ev_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(dev, clock, p.rig().unwrap(), sink, links);
    servo.apply(Command::StartScan {
        path: file.clone(),
        meta: vec![],
    });
    assert_eq!(run_scan(servo, 20_000), None);
    assert!(safe.load(Ordering::SeqCst));
    let events: Vec<_> = ev_rx.try_iter().collect();
    let stopped = events
        .iter()
        .find_map(|e| match e {
            ServoEvent::MotionStopped { reason } => Some(reason.clone()),
            _ => None,
        })
        .expect("a MotionStopped event");
    // Ticks this late with the force at its limit: the tick-interval guard
    // (servo/guards.rs) may see the oscillation starting before the streak.
    assert!(
        stopped.contains("consecutive missed deadlines")
            || stopped.contains("too far apart for the controller's gains"),
        "{stopped}"
    );
    let saved = recorder.join();
    assert!(!saved[0].complete);
    let rec = recording::read(&file).unwrap();
    assert!(!rec.is_complete() && rec.len() > 1000);
}

/// Idle in Manual mode on a machine too busy for the loop: nothing moves,
/// so nothing is stopped (the late ticks are counted for the Device panel).
#[test]
fn a_streak_of_missed_deadlines_while_nothing_moves_stops_nothing() {
    let p = thesis();
    let (_recorder, sink) = hapticlab::recorder::start();
    let (dev, _safe) = faulty(&p, None, None);
    let clock = Stalling {
        inner: virtual_clock(&p),
        ticks: 0,
        from: 100,
        extra: 0.0,
    };
    let (ev_tx, ev_rx) = crossbeam_channel::bounded(16);
    let links = Links {
        events: Some(ev_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(dev, clock, p.rig().unwrap(), sink, links);
    for _ in 0..2000 {
        servo.tick().unwrap();
    }
    let events: Vec<_> = ev_rx.try_iter().collect();
    assert!(
        !events
            .iter()
            .any(|e| matches!(e, ServoEvent::MotionStopped { .. })),
        "{events:?}"
    );
    assert!(servo.stats().missed_deadlines > 1000);
}

#[test]
fn a_panic_in_the_servo_thread_zeroes_forces_and_keeps_the_samples() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.csv");
    let (dev, safe) = faulty(&p, None, Some(5000));
    let (recorder, sink) = hapticlab::recorder::start();
    let pp = p.clone();
    let f2 = file.clone();
    let handle = std::thread::spawn(move || {
        let mut servo = ServoLoop::new(
            dev,
            virtual_clock(&pp),
            pp.rig().unwrap(),
            sink,
            Links::default(),
        );
        servo.apply(Command::StartScan {
            path: f2,
            meta: vec![],
        });
        for _ in 0..20_000 {
            let _ = servo.tick();
        }
    });
    assert!(handle.join().is_err(), "the thread panicked");
    assert!(safe.load(Ordering::SeqCst), "forces zeroed while unwinding");
    let saved = recorder.join();
    assert_eq!(saved.len(), 1);
    assert!(
        saved[0]
            .aborted
            .as_deref()
            .unwrap()
            .contains("servo loop stopped")
    );
    let rec = recording::read(&file).unwrap();
    assert!(!rec.is_complete());
    assert!(rec.len() > 1000, "{} samples kept", rec.len());
}

#[test]
fn manual_mode_applies_no_force_and_target_mode_holds_the_target() {
    let p = thesis();
    let (recorder, sink) = hapticlab::recorder::start();
    let (dev, _) = faulty(&p, None, None);
    let (tel_tx, tel_rx) = crossbeam_channel::bounded(100_000);
    let links = Links {
        telemetry: Some(tel_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(dev, virtual_clock(&p), p.rig().unwrap(), sink, links);
    for _ in 0..100 {
        servo.tick().unwrap();
    }
    let t: Vec<_> = tel_rx.try_iter().collect();
    assert!(
        t.iter()
            .all(|t| t.force_n == [0.0; 3] && t.mode == Mode::Manual)
    );
    let target = [0.01, 0.02, -0.03];
    servo.apply(Command::SetTarget(target));
    for _ in 0..4000 {
        servo.tick().unwrap();
    }
    let last = tel_rx.try_iter().last().unwrap();
    assert_eq!(last.mode, Mode::Target);
    assert_eq!(last.setpoint_m, target);
    for a in [0, 2] {
        assert!(
            (last.pos_m[a] - target[a]).abs() < 0.0002,
            "{:?}",
            last.pos_m
        );
    }
    // y sags 0.8 mm under the probe's weight.
    assert!(
        (target[1] - last.pos_m[1] - 0.0008).abs() < 0.0002,
        "{:?}",
        last.pos_m
    );
    servo.apply(Command::Abort);
    servo.tick().unwrap();
    assert_eq!(tel_rx.try_iter().last().unwrap().force_n, [0.0; 3]);
    drop(servo);
    assert!(recorder.join().is_empty());
}

#[test]
fn a_stalled_telemetry_consumer_is_counted_not_waited_for() {
    let p = thesis();
    let (_recorder, sink) = hapticlab::recorder::start();
    let dev = SimDevice::new(&p, Path::new("."), None, 1).unwrap();
    let (tel_tx, _tel_rx) = crossbeam_channel::bounded(10);
    let links = Links {
        telemetry: Some(tel_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(dev, virtual_clock(&p), p.rig().unwrap(), sink, links);
    for _ in 0..1000 {
        servo.tick().unwrap();
    }
    assert_eq!(servo.stats().dropped_telemetry, 990);
    assert_eq!(servo.stats().ticks, 1000);
}

/// A starved CPU while the probe is driven (issue 23): from tick `from`,
/// every second tick comes 8 ms late (the machine ran something else), the
/// others at the loop's half-period catch-up: never a streak of missed
/// deadlines, but intervals over the 3.8 ms the thesis's gains stand.
/// (One tick in four 5 ms late, or one in three 7 ms late, leaves the
/// thesis scan stable: no force at the limit, nothing stopped.)
struct Starved {
    inner: VirtualClock,
    ticks: u64,
    from: u64,
}

impl Clock for Starved {
    fn wait_until(&mut self, d: f64) -> f64 {
        self.ticks += 1;
        if self.ticks > self.from && self.ticks.is_multiple_of(2) {
            self.inner.stall(0.008);
        }
        self.inner.wait_until(d)
    }
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn is_virtual(&self) -> bool {
        true
    }
    fn stall(&mut self, secs: f64) {
        self.inner.stall(secs);
    }
}

/// Counts the forces commanded at the limit on some axis, and after the
/// motion stopped.
struct AtLimit {
    inner: SimDevice,
    limit: f64,
    at_limit: u64,
    after_stop: Option<u64>,
}

impl HapticDevice for AtLimit {
    fn kind(&self) -> &'static str {
        "sim"
    }
    fn read(&mut self, t: f64) -> Result<Reading, DeviceError> {
        self.inner.read(t)
    }
    fn command(&mut self, f: [f64; 3]) -> Result<(), DeviceError> {
        if f.iter().any(|v| v.abs() >= self.limit - 1e-9) {
            self.at_limit += 1;
            if let Some(n) = self.after_stop.as_mut() {
                *n += 1;
            }
        }
        self.inner.command(f)
    }
    fn make_safe(&mut self) {
        self.inner.make_safe();
    }
}

/// Ticks 8 ms apart, never two late in a row: the tick-interval
/// guard stops the motion, saying why, before the controller sits in a
/// limit cycle at the force limit (at most the guard's 10 saturated ticks
/// in its window of 100, none after the stop).
#[test]
fn scattered_late_ticks_stop_the_motion_instead_of_a_limit_cycle() {
    let p = thesis();
    let dir = tempfile::tempdir().unwrap();
    let (recorder, sink) = hapticlab::recorder::start();
    let limit = p.rig().unwrap().controller.force_limit_n;
    let dev = AtLimit {
        inner: SimDevice::new(&p, Path::new("."), Some("S2"), 5).unwrap(),
        limit,
        at_limit: 0,
        after_stop: None,
    };
    let clock = Starved {
        inner: virtual_clock(&p),
        ticks: 0,
        from: 5000,
    };
    let (ev_tx, ev_rx) = crossbeam_channel::bounded(64);
    let links = Links {
        events: Some(ev_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(dev, clock, p.rig().unwrap(), sink, links);
    servo.apply(Command::StartScan {
        path: dir.path().join("scan.csv"),
        meta: vec![],
    });
    let mut stopped = None;
    for _ in 0..20_000 {
        servo.tick().expect("no device fault");
        if stopped.is_none() {
            stopped = ev_rx.try_iter().find_map(|e| match e {
                ServoEvent::MotionStopped { reason } => Some(reason),
                _ => None,
            });
            if stopped.is_some() {
                servo.device_mut().after_stop = Some(0);
            }
        }
        if stopped.is_some() && !servo.scan_pending() {
            break;
        }
    }
    let stopped = stopped.expect("the motion stops");
    assert!(
        stopped.contains("too far apart for the controller's gains"),
        "{stopped}"
    );
    let d = servo.device();
    println!(
        "{} ticks at the force limit before the stop: {stopped}",
        d.at_limit
    );
    assert!(d.at_limit <= 20, "{} ticks at the force limit", d.at_limit);
    assert_eq!(d.after_stop, Some(0));
    drop(servo);
    assert!(!recorder.join()[0].complete);
}
