//! The emulated Falcon under the real driver: firmware, homing, reach, faults, timing.

use super::*;
use crate::device::Reading;
use crate::device::falcon::{FalconConfig, FalconDevice, FalconStats, firmware};
use crate::profile::LoadedProfile;
use crate::profile::hardware::EmulatorTiming;
use std::path::Path;

fn emulator(cfg: EmulatorConfig) -> EmulatedFalcon {
    let lp = LoadedProfile::thesis();
    let sim = SimDevice::new(&lp.profile, Path::new("."), None, 3).unwrap();
    EmulatedFalcon::new(sim, cfg)
}

fn opts(attempts: u32) -> firmware::LoadOptions {
    firmware::LoadOptions {
        attempts,
        ..firmware::LoadOptions::default()
    }
}

fn not_loaded(device: EmulatorSection) -> EmulatorConfig {
    EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            ..device
        },
        ..EmulatorConfig::default()
    }
}

fn image() -> firmware::FirmwareImage {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    firmware::FirmwareImage {
        path: "test-image.bin".into(),
        bytes: (0..8492).map(|_| rng.random()).collect(),
    }
}

#[test]
fn a_running_firmware_is_probed_and_not_reloaded() {
    let mut e = emulator(EmulatorConfig::default());
    let r = firmware::ensure_loaded(&mut e, None, &opts(3), &mut |_| {}).unwrap();
    assert!(r.already_loaded);
    assert_eq!(e.counters.uploads_started, 0);
}

#[test]
fn the_upload_runs_the_handshake_and_echoes_every_chunk() {
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            ..EmulatorSection::default()
        },
        leading_zero: true,
        ..EmulatorConfig::default()
    });
    let mut log = Vec::new();
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(5), &mut |m| {
        log.push(m.to_string())
    })
    .unwrap();
    assert!(!r.already_loaded);
    assert_eq!(r.attempts, 1);
    assert!(e.firmware_running());
    assert_eq!(e.counters.uploads_completed, 1);
    assert!(
        log.iter().any(|m| m.contains("firmware running")),
        "{log:?}"
    );
}

#[test]
fn an_upload_that_fails_twice_succeeds_on_the_third_attempt() {
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            upload_failures: 2,
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(20), &mut |_| {}).unwrap();
    assert_eq!(r.attempts, 3);
    assert_eq!(r.failures.len(), 2);
    assert!(
        r.failures[0].contains("chunk 41 of 137"),
        "{:?}",
        r.failures
    );
    assert!(r.failures[0].contains("echo differs"), "{:?}", r.failures);
    assert_eq!(e.counters.uploads_started, 3);
}

#[test]
fn too_many_failures_name_the_failing_step() {
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            upload_failures: 5,
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    let err = firmware::ensure_loaded(&mut e, Some(&image()), &opts(3), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("failed 3 times"), "{err}");
    assert!(err.contains("chunk 41"), "{err}");
    // No image at all: says where to get one.
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    let err = firmware::ensure_loaded(&mut e, None, &opts(3), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("libnifalcon"), "{err}");
}

#[test]
fn a_silent_boot_loader_fails_at_the_handshake() {
    // The cable is pulled before anything is said: the link error is named.
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    e.unplug();
    let err = firmware::ensure_loaded(&mut e, Some(&image()), &opts(3), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("unplugged"), "{err}");
}

#[test]
fn the_grip_homes_after_a_pull_out_and_push_in_and_leds_follow() {
    let e = emulator(EmulatorConfig::default());
    let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
    let mut t = 0.0;
    let mut homed_at = None;
    let mut last_axes = 0;
    for k in 1..5000 {
        t = k as f64 * 0.001;
        let r = dev.read(t).unwrap();
        // Before homing a force is asked for: none may be applied. After,
        // a spring holds the grip at the workspace's centre.
        let hold = [0.0, 0.0, -0.04];
        let f = if r.homed {
            [0, 1, 2].map(|a| 200.0 * (hold[a] - r.pos_m[a]))
        } else {
            [0.0, 3.0, 0.0]
        };
        dev.command(f).unwrap();
        // The per-arm flags only ever rise.
        let axes = dev.transport().homed_axes;
        assert_eq!(axes & last_axes, last_axes, "a homed flag dropped");
        last_axes = axes;
        if !r.homed {
            assert_eq!(dev.transport().motor, [0; 3]);
            assert_eq!(dev.transport().flags & packet::LED_RED, packet::LED_RED);
        } else if homed_at.is_none() {
            homed_at = Some(t);
        }
    }
    let homed_at = homed_at.expect("homed");
    assert!(homed_at < 3.0, "homed only at {homed_at} s");
    assert_eq!(dev.transport().flags & packet::LED_BLUE, packet::LED_BLUE);
    // After homing the reading is the true position, within an encoder step or two.
    let r = dev.read(t + 0.001).unwrap();
    let truth = dev.transport().sim().true_position();
    for a in 0..3 {
        assert!(
            (r.pos_m[a] - truth[a]).abs() < 2e-4,
            "{:?} vs {truth:?}",
            r.pos_m
        );
    }
    assert!(dev.transport().counters.max_motor > 0);
}

/// Drive `dev` for `seconds` with `force` of each reading.
fn drive(
    dev: &mut FalconDevice<EmulatedFalcon>,
    from_s: f64,
    seconds: f64,
    force: impl Fn(&Reading) -> [f64; 3],
) -> f64 {
    let mut t = from_s;
    for _ in 0..(seconds * 1000.0) as usize {
        t += 0.001;
        let r = dev.read(t).unwrap();
        dev.command(force(&r)).unwrap();
    }
    t
}

/// The reading at rest is the true grip position, within encoder steps.
fn assert_reading_follows(dev: &mut FalconDevice<EmulatedFalcon>, t: f64) {
    let r = dev.read(t + 0.001).unwrap();
    assert!(r.homed);
    let truth = dev.transport().sim().true_position();
    for a in 0..3 {
        assert!(
            (r.pos_m[a] - truth[a]).abs() < 3e-4,
            "the reading {:?} is not the grip at {truth:?}",
            r.pos_m
        );
    }
}

#[test]
fn once_homed_the_hand_lets_go_in_the_middle_and_the_reading_follows() {
    let e = emulator(EmulatorConfig::default());
    let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
    // Manual mode: no forces asked for, ever.
    let t = drive(&mut dev, 0.0, 10.0, |_| [0.0; 3]);
    let emu = dev.transport();
    assert!(emu.is_homed());
    assert!(emu.released, "the hand never let go");
    // Let go in the middle; with no texture under it, the probe's weight
    // takes it down to the floor (y), but it stays put across (x, z).
    let p = emu.sim().true_position();
    for a in [0, 2] {
        assert!(
            (p[a] - WORKSPACE_CENTRE_M[a]).abs() < 0.01,
            "left at {p:?}, not in the middle"
        );
    }
    assert_eq!(emu.counters.unreachable, 0);
    assert_reading_follows(&mut dev, t);
}

#[test]
fn at_the_arms_stops_the_grip_is_held_back_and_still_read() {
    let e = emulator(EmulatorConfig::default());
    let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
    let t = drive(&mut dev, 0.0, 3.0, |_| [0.0; 3]);
    assert!(dev.transport().is_homed());
    // Push hard out, right and up: leg 2's arm reaches its stop (73.5°)
    // well inside the workspace box, where the driver keeps the force on
    // (and before the legs' reach ends).
    let push = 6.0 / 3f64.sqrt();
    let t = drive(&mut dev, t, 2.0, |_| [push, push, push]);
    let emu = dev.transport();
    let p = emu.cfg.frame.to_falcon(emu.sim().true_position());
    let a = kinematics::inverse(p).expect("within reach");
    let top = a.theta1.iter().fold(f64::MIN, |m, t| m.max(t.to_degrees()));
    let (_, stop) = kinematics::joint_limits_deg();
    assert!(
        top > stop - 1.0 && top < stop + 0.5,
        "the highest arm is at {top:.2}°, its stop at {stop:.2}° (grip at {p:?})"
    );
    assert!(
        (0..3).all(|i| p[i] < kinematics::FALCON_MAX_M[i]),
        "{p:?}: held by the box, not the stop"
    );
    assert_eq!(emu.counters.unreachable, 0);
    assert_reading_follows(&mut dev, t);
}

#[test]
fn faults_are_survived_and_counted_and_unplugging_stops_the_motors() {
    let e = emulator(EmulatorConfig {
        device: EmulatorSection {
            drop_rate: 0.05,
            garble_rate: 0.05,
            split_rate: 0.3,
            unplug_after_s: Some(4.0),
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
    let hold = [0.0, 0.0, -0.04];
    let mut failed_at = None;
    for k in 1..5000 {
        let t = k as f64 * 0.001;
        match dev.read(t) {
            Ok(r) => {
                let f = if r.homed {
                    [0, 1, 2].map(|a| 200.0 * (hold[a] - r.pos_m[a]))
                } else {
                    [0.0; 3]
                };
                dev.command(f).unwrap();
            }
            Err(e) => {
                assert!(
                    matches!(e, crate::device::DeviceError::Disconnected(_)),
                    "{e}"
                );
                assert!(e.to_string().contains("unplugged"), "{e}");
                failed_at = Some(t);
                break;
            }
        }
    }
    let t = failed_at.expect("the unplug is noticed");
    assert!((4.0..4.01).contains(&t), "noticed at {t}");
    let s = dev.stats();
    assert!(s.missed_replies > 50 && s.bad_packets > 50, "{s:?}");
    assert!(dev.is_homed());
    // The motors stopped with the cable; the driver stays failed and safe.
    assert_eq!(dev.transport().motor, [0; 3]);
    dev.make_safe();
    assert!(dev.read(t + 0.001).is_err());
    assert!(dev.command([1.0, 0.0, 0.0]).is_err());
}

#[test]
fn slow_fresh_firmware_is_waited_for_within_the_probe_window() {
    // Fresh firmware that takes 600 ms to start: the old 4 x 30 ms probe
    // gives up on every attempt; the default 1 s window finds it at once.
    let slow = || {
        emulator(not_loaded(EmulatorSection {
            firmware_start_ms: 600.0,
            ..EmulatorSection::default()
        }))
    };
    let mut e = slow();
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(3), &mut |_| {}).unwrap();
    assert_eq!(r.attempts, 1, "{r:?}");
    assert!(e.counters.ignored_while_starting > 0, "{:?}", e.counters);
    let mut e = slow();
    let short = firmware::LoadOptions {
        attempts: 2,
        probe_window: Duration::from_millis(120),
    };
    let err = firmware::ensure_loaded(&mut e, Some(&image()), &short, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("does not answer packets within 120 ms"),
        "{err}"
    );
}

#[test]
fn a_stale_byte_before_sync_is_purged() {
    let cfg = not_loaded(EmulatorSection {
        stale_byte_before_sync: true,
        ..EmulatorSection::default()
    });
    // The stray byte is there: right after the baud change a read finds it.
    let mut e = emulator(cfg.clone());
    firmware::set_loader_mode(&mut e).unwrap();
    e.write(&[0x0A, 0x43, 0x0D]).unwrap();
    let mut buf = [0u8; 16];
    let n = e.read(&mut buf, Duration::from_millis(50)).unwrap();
    assert_eq!(&buf[..n], &[0x0A, 0x44, 0x2C, 0x0D]);
    e.control(ftdi::MODEM, ftdi::DTR_LOW).unwrap();
    e.control(ftdi::BAUD, ftdi::BAUD_LOADER).unwrap();
    let n = e.read(&mut buf, Duration::from_millis(50)).unwrap();
    assert_eq!(&buf[..n], &[0x00], "the stray byte");
    // The driver purges it before the sync byte: the upload goes through.
    let mut e = emulator(cfg);
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(3), &mut |_| {}).unwrap();
    assert_eq!(r.attempts, 1, "{r:?}");
    assert!(e.firmware_running());
}

#[test]
fn an_upload_that_needs_a_reopen_succeeds_on_the_second_attempt() {
    let mut e = emulator(not_loaded(EmulatorSection {
        upload_needs_reopen: true,
        ..EmulatorSection::default()
    }));
    let mut log = Vec::new();
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(5), &mut |m| {
        log.push(m.to_string())
    })
    .unwrap();
    assert_eq!(r.attempts, 2, "{log:?}");
    assert!(r.failures[0].contains("handshake"), "{r:?}");
    assert_eq!(e.counters.reopens, 1);
    assert!(log.iter().any(|m| m.contains("reopening")), "{log:?}");
    // Without a reopen the same device never answers.
    let mut e = emulator(not_loaded(EmulatorSection {
        upload_needs_reopen: true,
        ..EmulatorSection::default()
    }));
    for _ in 0..2 {
        let step = firmware::upload_once(&mut e, &image().bytes, Duration::from_secs(1));
        assert!(
            matches!(step, Err(firmware::UploadStep::Handshake { .. })),
            "{step:?}"
        );
    }
}

#[test]
fn usb_read_errors_are_ridden_out_and_a_streak_ends_the_link() {
    let run = |errors: u32| {
        let e = emulator(EmulatorConfig {
            device: EmulatorSection {
                read_error_after_s: Some(3.0),
                read_errors: errors,
                ..EmulatorSection::default()
            },
            ..EmulatorConfig::default()
        });
        let config = FalconConfig {
            read_error_streak: 10,
            ..FalconConfig::default()
        };
        let mut dev = FalconDevice::open(e, config, &mut |_| {}).unwrap();
        for k in 1..4000 {
            if let Err(e) = dev.read(f64::from(k) * 0.001) {
                return (Err(e.to_string()), dev.stats());
            }
            dev.command([0.0; 3]).unwrap();
        }
        (Ok(()), dev.stats())
    };
    let (r, s) = run(9);
    assert_eq!(r, Ok(()));
    assert_eq!(s.usb_errors, 9);
    assert!(s.missed_replies >= 9, "{s:?}");
    let (r, s) = run(10);
    let err = r.unwrap_err();
    assert!(
        err.contains("10 USB transfers in a row failed") && err.contains("stalled"),
        "{err}"
    );
    assert_eq!(s.usb_errors, 10);
}

fn timed(timing: EmulatorTiming) -> EmulatorConfig {
    EmulatorConfig {
        device: EmulatorSection {
            timing: Some(timing),
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    }
}

/// Drive a homed device at 1 kHz (its ticks `late_s` after their
/// deadlines) for `ticks`; missed replies and the longest read wait.
fn run_timed(cfg: EmulatorConfig, ticks: u32, late_s: f64) -> (FalconStats, f64) {
    let mut dev = FalconDevice::open(emulator(cfg), FalconConfig::default(), &mut |_| {}).unwrap();
    let mut k = 0;
    loop {
        let homed = dev.read(f64::from(k) * 0.001).unwrap().homed;
        dev.command([0.0; 3]).unwrap();
        if homed {
            break;
        }
        k += 1;
        assert!(k < 10_000, "not homed");
    }
    let before = dev.stats();
    let mut longest = 0.0f64;
    let hold = [0.0, 0.0, -0.04];
    for j in 1..=ticks {
        let r = dev.read(f64::from(k + j) * 0.001 + late_s).unwrap();
        if let Some(w) = dev.take_stall() {
            longest = longest.max(w.as_secs_f64());
        }
        dev.command([0, 1, 2].map(|a| 200.0 * (hold[a] - r.pos_m[a])))
            .unwrap();
    }
    let mut s = dev.stats();
    s.missed_replies -= before.missed_replies;
    (s, longest)
}

#[test]
fn the_timed_link_answers_within_the_reply_window_but_late_replies_are_missed() {
    // No jitter, nothing late: the 1 ms latency timer batches every reply,
    // yet each comes before the next tick's window closes.
    let exact = EmulatorTiming {
        jitter_ms: 0.0,
        late_rate: 0.0,
        ..EmulatorTiming::default()
    };
    let (s, longest) = run_timed(timed(exact.clone()), 2000, 0.0);
    assert_eq!(s.missed_replies, 0, "{s:?}");
    assert!(longest <= 0.0009 + 1e-9, "a read waited {longest} s");
    // Every reply late by 2.5 ms: it misses its window every time, the
    // packet is re-sent after two misses, and the link goes on.
    let late = EmulatorTiming {
        late_rate: 0.4999,
        late_ms: 5.0,
        ..exact
    };
    let (s, longest) = run_timed(timed(late), 2000, 0.0);
    assert!(s.missed_replies > 100, "{s:?}");
    assert!(s.resends > 0, "{s:?}");
    assert!(
        longest <= 0.0009 + 1e-9,
        "a read waited {longest} s (past its timeout)"
    );
}

#[test]
fn the_timed_link_is_deterministic_under_its_seed() {
    let cfg = |seed| EmulatorConfig {
        seed,
        ..timed(EmulatorTiming {
            late_rate: 0.01,
            ..EmulatorTiming::default()
        })
    };
    let a = run_timed(cfg(7), 1000, 0.0002);
    assert_eq!(a, run_timed(cfg(7), 1000, 0.0002));
    assert!(a.0.missed_replies > 0, "{:?}", a.0);
}

#[test]
fn loading_firmware_through_the_timed_link_waits_for_the_16_ms_timer() {
    let mut e = emulator(EmulatorConfig {
        device: EmulatorSection {
            firmware_loaded: false,
            timing: Some(EmulatorTiming::default()),
            ..EmulatorSection::default()
        },
        ..EmulatorConfig::default()
    });
    let start = e.now();
    let r = firmware::ensure_loaded(&mut e, Some(&image()), &opts(3), &mut |_| {}).unwrap();
    assert_eq!(r.attempts, 1);
    // The probe before the upload asks for 1 s; 8492 bytes at ~140 kbaud
    // take 0.6 s, echoed as they arrive (each full 62-byte chunk goes back
    // at once); short answers wait for the 16 ms timer.
    let took = e.now() - start;
    assert!(
        (1.6..2.0).contains(&took.as_secs_f64()),
        "the load took {took:?} of link time"
    );
}
