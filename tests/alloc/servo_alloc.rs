//! The servo loop allocates nothing per tick while it records a scan: a
//! counting allocator (`tests/common/counting_alloc.rs`) counts the allocations made on
//! the thread that ticks the loop, and only while that thread has opted in,
//! so the recorder's writer thread and the test harness are not counted.

use std::path::Path;

use crate::counting_alloc::allocations_during;

use hapticlab::clock::VirtualClock;
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;
use hapticlab::servo::{Command, Links, ServoEvent, ServoLoop, Telemetry};

#[test]
fn the_counter_counts_only_when_asked() {
    let (n, v) = allocations_during(|| std::hint::black_box(vec![1u8; 32]));
    assert_eq!(n, 1);
    drop(v);
    let spawn = |allocs: usize| {
        std::thread::spawn(move || {
            for _ in 0..allocs {
                drop(std::hint::black_box(vec![1u8; 32]));
            }
        })
        .join()
        .unwrap()
    };
    // Warm up whatever spawning caches once, then compare two spawns.
    spawn(0);
    let (quiet, ()) = allocations_during(|| spawn(0));
    let (busy, ()) = allocations_during(|| spawn(100));
    assert_eq!(quiet, busy, "another thread's allocations were counted");
}

#[test]
fn ticks_on_the_scan_leg_do_not_allocate() {
    let lp = LoadedProfile::thesis();
    let p = &lp.profile;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("S2").join("S2_001.csv");

    let device = SimDevice::new(p, Path::new("."), Some("S2"), 7).unwrap();
    let clock = VirtualClock::new(
        p.rig().unwrap().device.rate_hz,
        p.simulator.period_jitter_s,
        p.simulator.period_jitter_fraction,
        7,
    );
    let (recorder, sink) = hapticlab::recorder::start();
    let (cmd_tx, cmd_rx) = crossbeam_channel::bounded::<Command>(16);
    let (tel_tx, tel_rx) = crossbeam_channel::bounded::<Telemetry>(256);
    let (ev_tx, ev_rx) = crossbeam_channel::bounded::<ServoEvent>(64);
    let links = Links {
        commands: Some(cmd_rx),
        telemetry: Some(tel_tx),
        events: Some(ev_tx),
        stop: None,
    };
    let mut servo = ServoLoop::new(device, clock, p.rig().unwrap(), sink, links);
    cmd_tx
        .send(Command::StartScan {
            path: file.clone(),
            meta: vec![("label".into(), toml::Value::String("S2".into()))],
        })
        .unwrap();

    // The transit to the scan leg takes about 3.4 s (3400 ticks); the scan
    // leg then lasts 9.27 s. Drain telemetry now and then, as a console would.
    // In real time a block of 250 samples fills every quarter second; virtual
    // time runs hundreds of times faster, so give the writer thread a moment
    // per block, or it could fall 16 blocks behind and the sink would grow
    // its pool (a counted fallback, not a per-tick allocation).
    let tick = |servo: &mut ServoLoop<_, _>, n: usize| {
        for i in 1..=n {
            servo.tick().unwrap();
            if i % 16 == 0 {
                while tel_rx.try_recv().is_ok() {}
            }
            if i % 250 == 0 {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        }
    };
    tick(&mut servo, 5000);
    let started: Vec<ServoEvent> = ev_rx.try_iter().collect();
    assert!(
        started
            .iter()
            .any(|e| matches!(e, ServoEvent::ScanStarted { path } if *path == file)),
        "the scan leg has not started after 5000 ticks: {started:?}"
    );
    assert!(servo.scan_pending());

    let (n, ()) = allocations_during(|| tick(&mut servo, 3000));

    // Still mid-scan, nothing stopped it: the 3000 ticks were all recorded ticks.
    assert!(servo.scan_pending(), "the scan ended during the window");
    let events: Vec<ServoEvent> = ev_rx.try_iter().collect();
    assert!(events.is_empty(), "{events:?}");
    assert_eq!(
        n, 0,
        "ServoLoop::tick allocated {n} times in 3000 scan ticks"
    );
    assert_eq!(servo.stats().recorder_blocks_grown, 0);

    // The scan was really being recorded: end it and read it back.
    drop(servo);
    let saved = recorder.join();
    assert_eq!(saved.len(), 1, "{saved:?}");
    assert!(saved[0].error.is_none(), "{saved:?}");
    let rec = hapticlab::recording::read(&file).unwrap();
    assert!(!rec.is_complete());
    assert!(rec.len() >= 3000, "only {} rows recorded", rec.len());
}
