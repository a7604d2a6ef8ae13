//! The servo loop in real time on the simulator: achieved rate, period error
//! percentiles, missed deadlines, while the probe runs the thesis path, its
//! scans are recorded, and a console-like consumer drains the telemetry and
//! renders a full 200×60 console frame thirty times a second. Not a statistical micro-benchmark: one long run,
//! reported. `HAPTICLAB_SOAK_S` sets the duration (default 60 s). It runs
//! the thesis profile's real-time setup (SCHED_FIFO 80, memory locked, spin
//! 200 µs while driving); `HAPTICLAB_RT=0` runs at normal priority and
//! `HAPTICLAB_SPIN_US=N` changes the spin. To find where late ticks come
//! from, `HAPTICLAB_NO_SCAN=1` holds the probe instead of scanning and
//! `HAPTICLAB_NO_DRAW=1` drains telemetry without drawing.
//!
//! As a soak (`HAPTICLAB_SOAK_S=600`) it also shows that nothing is lost and
//! memory stays flat: every recording is read back and its rows counted
//! against the samples the loop reported, and the process's resident memory
//! is sampled every second (first reading after 10 s, to skip start-up).
//!
//! cargo bench --bench servo_realtime

use std::time::{Duration, Instant};

use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;
use hapticlab::servo::{Command, ServoEvent, spawn};

fn main() {
    // `cargo bench` passes `--bench`; a filter that names nothing here skips the run.
    if std::env::args()
        .skip(1)
        .any(|a| !a.starts_with("--") && !"servo_realtime".contains(&a))
    {
        return;
    }
    let secs: f64 = std::env::var("HAPTICLAB_SOAK_S")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60.0);
    let mut lp = LoadedProfile::thesis();
    let flag = |name: &str| std::env::var(name).is_ok_and(|v| v == "1");
    // The thesis profile's own real-time setup unless overridden:
    // `HAPTICLAB_RT=0` runs at normal priority, `HAPTICLAB_SPIN_US=N` sets
    // device.spin_us.
    let device = lp
        .profile
        .device
        .as_mut()
        .expect("the thesis profile's [device]");
    if std::env::var("HAPTICLAB_RT").is_ok_and(|v| v == "0") {
        device.realtime = None;
    }
    if let Some(spin) = std::env::var("HAPTICLAB_SPIN_US")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        device.spin_us = spin;
    }
    let rt = device.realtime.is_some();
    let spin_us = device.spin_us;
    let (no_scan, no_draw) = (flag("HAPTICLAB_NO_SCAN"), flag("HAPTICLAB_NO_DRAW"));
    let profile = lp.profile.clone();
    let base = lp.base_dir.clone();
    let rig = lp.rig().expect("the thesis profile's rig");
    let handle = spawn(rig, move || {
        SimDevice::new(&profile, &base, Some("S2"), 1).expect("the thesis texture S2")
    })
    .expect("spawn the servo thread");
    let dir = tempfile::tempdir().expect("a temp dir");
    let started = Instant::now();
    let mut scans = 0;
    let mut samples = 0;
    // Samples per scan, as the loop reported them when each scan ended.
    let mut reported = std::collections::HashMap::new();
    let mut next_scan = true;
    let console = hapticlab::console::fixtures::app(200, 60);
    let mut rss: Vec<(f64, u64)> = Vec::new();
    let mut next_rss = 10.0_f64.min(secs / 2.0);
    let mut terminal = ratatui::Terminal::new(ratatui::backend::TestBackend::new(200, 60))
        .expect("a test terminal");
    while started.elapsed() < Duration::from_secs_f64(secs) {
        if next_scan && !no_scan {
            scans += 1;
            handle.send(Command::StartScan {
                path: dir.path().join(format!("scan_{scans:03}.csv")),
                meta: vec![("label".into(), toml::Value::String("S2".into()))],
            });
            next_scan = false;
        }
        // A console-like consumer: drain telemetry and draw thirty times a second.
        std::thread::sleep(Duration::from_millis(33));
        let _ = handle.telemetry.try_iter().count();
        if !no_draw {
            terminal
                .draw(|f| f.render_widget(&console, f.area()))
                .expect("draw");
        }
        let t = started.elapsed().as_secs_f64();
        if t >= next_rss {
            if let Some(kib) = resident_kib() {
                rss.push((t, kib));
            }
            next_rss += 1.0;
        }
        for e in handle.events.try_iter() {
            match e {
                ServoEvent::ScanEnded {
                    samples: n, path, ..
                } => {
                    samples += n;
                    reported.insert(path, n as usize);
                    next_scan = true;
                }
                ServoEvent::Notice { message } => println!("  note: {message}"),
                _ => {}
            }
        }
    }
    let (result, saved) = handle.shutdown();
    let (_, stats) = result.expect("the servo thread ran");
    let complete = saved.iter().filter(|s| s.complete).count();
    println!(
        "servo_realtime: {secs:.0} s on the simulator, {}, {}, {}, spin {spin_us} µs",
        if no_scan {
            "probe held (no scans)"
        } else {
            "thesis path, scans recorded"
        },
        if no_draw {
            "no drawing"
        } else {
            "console frame drawn at 30 fps"
        },
        if rt {
            "SCHED_FIFO requested"
        } else {
            "normal priority"
        }
    );
    println!("  {}", stats.summary());
    println!(
        "  mean rate error {:.3} %; {} scans started, {} complete, {} samples written",
        (stats.rate_hz / 1000.0 - 1.0).abs() * 100.0,
        scans,
        complete,
        samples
    );
    println!(
        "  recorder blocks allocated because the writer lagged: {}",
        stats.recorder_blocks_grown
    );
    // Nothing lost: every recording read back; each scan that ended while
    // the run went on holds exactly the samples the loop reported for it.
    let (mut rows, mut checked, mut lost) = (0, 0, 0);
    for s in &saved {
        match hapticlab::recording::read(&s.path) {
            Ok(r) => {
                rows += r.len();
                if let Some(&n) = reported.get(&s.path) {
                    checked += 1;
                    lost += n.abs_diff(r.len());
                }
            }
            Err(e) => println!("  UNREADABLE {}: {e}", s.path.display()),
        }
    }
    println!(
        "  read back: {} recordings, {rows} rows; {checked} ended scans checked against the loop's counts: {}",
        saved.len(),
        if lost == 0 {
            "no sample lost".to_string()
        } else {
            format!("{lost} samples MISSING")
        }
    );
    if let (Some(first), Some(last)) = (rss.first(), rss.last()) {
        let max = rss.iter().map(|r| r.1).max().unwrap_or(0);
        let slope = if last.0 > first.0 {
            (last.1 as f64 - first.1 as f64) / (last.0 - first.0) * 60.0
        } else {
            0.0
        };
        println!(
            "  resident memory: {:.1} MiB at {:.0} s, {:.1} MiB at {:.0} s, max {:.1} MiB ({:+.1} KiB per minute)",
            first.1 as f64 / 1024.0,
            first.0,
            last.1 as f64 / 1024.0,
            last.0,
            max as f64 / 1024.0,
            slope
        );
    }
}

/// This process's resident set (VmRSS), KiB; Linux only.
fn resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
}
