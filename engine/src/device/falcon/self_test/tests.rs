//! The self-test against the emulated Falcon in virtual time, its user
//! scripted: a clean device passes every step; a motor wired backwards
//! fails a pulse; encoders that read a few degrees off fail the calibration,
//! which suggests the offset that fixes them; declined forces apply none; a
//! panic mid-pulse leaves the forces zero; an unhomed grip fails homing and
//! skips the rest.

use std::path::Path;
use std::time::Duration;

use super::*;
use crate::clock::VirtualClock;
use crate::device::falcon::emulator::{EmulatedFalcon, EmulatorConfig};
use crate::device::falcon::{TransportError, open_emulated};
use crate::profile::LoadedProfile;

fn thesis_emulator() -> LoadedProfile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../profiles/thesis-emulator.toml");
    LoadedProfile::load(&path).unwrap()
}

/// A user who does what is asked (the emulator's hand does it) and answers
/// every question with `yes`.
struct Script {
    yes: bool,
    requests: Vec<Request>,
    questions: Vec<String>,
    notes: Vec<String>,
}

impl Script {
    fn answering(yes: bool) -> Script {
        Script {
            yes,
            requests: Vec::new(),
            questions: Vec::new(),
            notes: Vec::new(),
        }
    }
}

impl<T: HandOf> Operator<T> for Script {
    fn request(&mut self, request: &Request, transport: &mut T) {
        self.requests.push(*request);
        if let Some(task) = request.hand_task() {
            transport.emulator().ask_hand(task);
        }
    }
    fn confirm(&mut self, question: &str) -> bool {
        self.questions.push(question.into());
        self.yes
    }
    fn note(&mut self, line: &str) {
        self.notes.push(line.into());
    }
}

/// Transports with an emulated Falcon inside.
trait HandOf {
    fn emulator(&mut self) -> &mut EmulatedFalcon;
}

impl HandOf for EmulatedFalcon {
    fn emulator(&mut self) -> &mut EmulatedFalcon {
        self
    }
}

fn clock() -> VirtualClock {
    VirtualClock::new(1000.0, 0.0, 0.0, 1)
}

fn options() -> Options {
    Options {
        homing_timeout_s: 30.0,
        move_timeout_s: 30.0,
        ..Options::default()
    }
}

fn run_on(lp: &LoadedProfile, user: &mut Script) -> (Report, FalconDevice<EmulatedFalcon>) {
    let (report, device) = run(
        &lp.profile.name,
        |log| open_emulated(lp, None, 7, log),
        Pace {
            clock: &mut clock(),
            stop: &AtomicBool::new(false),
        },
        user,
        &options(),
    );
    (report, device.expect("the emulated Falcon opens"))
}

fn verdict(report: &Report, name: &str) -> Verdict {
    report
        .steps
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no step {name}: {:#?}", report.steps))
        .verdict
}

#[test]
fn a_clean_emulated_falcon_passes_every_step() {
    let lp = thesis_emulator();
    let mut user = Script::answering(true);
    let (report, device) = run_on(&lp, &mut user);
    let text = report.lines().join("\n");
    println!("{text}");
    assert!(report.passed, "{text}");
    let names: Vec<&str> = report.steps.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "open",
            "leds",
            "link",
            "homing",
            "encoders",
            "pulse x",
            "pulse y",
            "pulse z",
            "calibration"
        ]
    );
    // The user was asked to home, move, hold, and finally let go; asked once before any force.
    assert_eq!(user.requests[0], Request::WatchLeds);
    assert!(
        matches!(user.requests[1], Request::Home { .. }),
        "{:?}",
        user.requests
    );
    assert_eq!(user.requests.last(), Some(&Request::LetGo));
    assert_eq!(user.questions.len(), 1, "{:?}", user.questions);
    assert!(user.questions[0].contains("1.0 N for 100 ms"));
    // Positions were told while the grip moved.
    assert!(
        user.notes.iter().any(|n| n.contains("grip at")),
        "{:?}",
        user.notes
    );
    // Each pulse moved the grip clearly along its own axis.
    assert_eq!(report.pulses.len(), 3);
    for p in &report.pulses {
        assert!(p.along_m > 0.002 && p.cosine > 0.9, "{p:?}\n{text}");
        assert_eq!(p.force_n, 1.0);
        assert!(
            (p.along_mm_per_n - p.along_m * 1000.0).abs() < 1e-9,
            "{p:?}"
        );
    }
    assert!(text.contains("mm/N"), "{text}");
    // The calibration found the arms at the model's stops, give and noise
    // cancelling to well under the tolerance, and suggests the offset in use.
    let c = report.calibration.as_ref().expect("calibrated");
    assert!(c.passed, "{c:#?}");
    assert_eq!(c.stops.len(), 2);
    for stop in &c.stops {
        assert!(stop.reached, "{stop:?}");
        for d in stop.difference_deg {
            assert!(d.abs() < 0.3, "{stop:?}");
        }
    }
    assert!(c.offset_error_deg.abs() < 0.1, "{c:#?}");
    assert!((c.suggested_offset_deg - 35.0).abs() < 0.1, "{c:#?}");
    assert!(c.grip_force_n > 1.0 && c.grip_force_n < 5.0, "{c:#?}");
    for t in c.travel_deg {
        assert!((t - c.model_travel_deg).abs() < 0.3, "{c:#?}");
    }
    assert!(text.contains("result: PASS") && text.contains("firmware already running"));
    // Forces zero at the end, in the driver and at the device.
    assert_eq!(device.motor_commands(), [0; 3]);
    assert_eq!(device.transport().motor(), [0; 3]);
    // The pulses stayed within 1 N: no motor command near its limit.
    assert!(device.transport().counters.max_motor < 1000);
}

#[test]
fn a_motor_wired_backwards_fails_a_pulse() {
    for motor in 0..3u8 {
        let mut lp = thesis_emulator();
        lp.profile.falcon.as_mut().unwrap().emulator.reversed_motor = Some(motor);
        let mut user = Script::answering(true);
        let (report, device) = run_on(&lp, &mut user);
        let text = report.lines().join("\n");
        println!("reversed motor {motor}:\n{text}");
        assert!(!report.passed, "motor {motor}:\n{text}");
        assert_eq!(verdict(&report, "encoders"), Verdict::Pass, "{text}");
        let failed: Vec<&Step> = report
            .steps
            .iter()
            .filter(|s| s.verdict == Verdict::Fail)
            .collect();
        assert!(
            !failed.is_empty() && failed.iter().all(|s| s.name.starts_with("pulse ")),
            "motor {motor}:\n{text}"
        );
        assert!(text.contains("result: FAIL"), "{text}");
        assert_eq!(device.transport().motor(), [0; 3]);
    }
}

#[test]
fn declined_pulses_are_skipped_and_no_force_is_applied() {
    let lp = thesis_emulator();
    let mut user = Script::answering(false);
    let (report, device) = run_on(&lp, &mut user);
    assert!(!report.passed);
    for axis in ["pulse x", "pulse y", "pulse z", "calibration"] {
        assert_eq!(verdict(&report, axis), Verdict::Skipped);
    }
    // Asked once, for the pulses and the push to the stops together.
    assert_eq!(user.questions.len(), 1, "{:?}", user.questions);
    assert!(user.questions[0].contains("stops"), "{:?}", user.questions);
    assert!(report.calibration.is_none());
    assert_eq!(verdict(&report, "encoders"), Verdict::Pass);
    assert_eq!(device.transport().counters.max_motor, 0);
}

/// Encoders that read a few degrees off (the emulated Falcon's count 0 is
/// not at the profile's `encoder_offset_deg`): the calibration measures the
/// arms that far from the model's stops, fails, and suggests an offset
/// within a few tenths of a degree of the true one.
#[test]
fn encoders_off_by_a_few_degrees_fail_the_calibration_with_the_offset_to_set() {
    for error_deg in [3.0, -4.0] {
        let mut lp = thesis_emulator();
        let falcon = lp.profile.falcon.as_mut().unwrap();
        falcon.emulator.encoder_offset_error_deg = error_deg;
        let (report, device) = run_on(&lp, &mut Script::answering(true));
        let text = report.lines().join("\n");
        println!("encoders {error_deg:+}° off:\n{text}");
        assert!(!report.passed, "{text}");
        assert_eq!(verdict(&report, "calibration"), Verdict::Fail, "{text}");
        // Only the calibration sees it: directions and distances still hold.
        let failed: Vec<&str> = report
            .not_passed()
            .iter()
            .map(|s| s.name.as_str())
            .collect();
        assert_eq!(failed, ["calibration"], "{text}");
        let c = report.calibration.as_ref().unwrap();
        for stop in &c.stops {
            assert!(stop.reached, "{stop:?}");
            for d in stop.difference_deg {
                assert!((d + error_deg).abs() < 0.3, "{stop:?}");
            }
        }
        let truth = 35.0 + error_deg;
        assert!(
            (c.suggested_offset_deg - truth).abs() < 0.2,
            "suggested {} for {truth}",
            c.suggested_offset_deg
        );
        assert!(
            text.contains(&format!("set `encoder_offset_deg = {truth:.1}`")),
            "{text}"
        );
        assert_eq!(device.transport().motor(), [0; 3]);
        // With the suggested offset the same Falcon passes.
        let mut lp = thesis_emulator();
        let falcon = lp.profile.falcon.as_mut().unwrap();
        falcon.emulator.encoder_offset_error_deg = error_deg;
        falcon.encoder_offset_deg = c.suggested_offset_deg;
        // (The emulator's count 0 follows the profile's offset plus the
        // error; the fixed profile's emulator keeps the old one.)
        falcon.emulator.encoder_offset_error_deg = truth - c.suggested_offset_deg;
        let (report, _) = run_on(&lp, &mut Script::answering(true));
        let text = report.lines().join("\n");
        assert!(report.passed, "{text}");
    }
}

/// Motors without power cannot push the arms to their stops: the
/// calibration says they did not get there, never a wrong offset.
#[test]
fn arms_that_do_not_reach_their_stops_fail_without_an_offset() {
    /// A user who does what is asked; the wall power goes as the push to
    /// the stops begins.
    struct PowerGoesAtStops(Script);
    impl Operator<EmulatedFalcon> for PowerGoesAtStops {
        fn request(&mut self, request: &Request, transport: &mut EmulatedFalcon) {
            if matches!(request, Request::HandsOffForStops { .. }) {
                transport.lose_motor_power();
            }
            self.0.request(request, transport);
        }
        fn confirm(&mut self, q: &str) -> bool {
            Operator::<EmulatedFalcon>::confirm(&mut self.0, q)
        }
        fn note(&mut self, line: &str) {
            Operator::<EmulatedFalcon>::note(&mut self.0, line)
        }
    }
    let lp = thesis_emulator();
    let (report, _) = run(
        &lp.profile.name,
        |log| open_emulated(&lp, None, 7, log),
        Pace {
            clock: &mut clock(),
            stop: &AtomicBool::new(false),
        },
        &mut PowerGoesAtStops(Script::answering(true)),
        &options(),
    );
    let text = report.lines().join("\n");
    println!("{text}");
    assert_eq!(verdict(&report, "pulse z"), Verdict::Pass, "{text}");
    assert_eq!(verdict(&report, "calibration"), Verdict::Fail, "{text}");
    assert!(
        text.contains("the grip did not get to both stops")
            && text.contains("check the Falcon's power supply"),
        "{text}"
    );
    assert!(!text.contains("set `encoder_offset_deg"), "{text}");
    let c = report.calibration.as_ref().unwrap();
    assert!(!c.passed, "{c:#?}");
    assert!(c.travel_deg.iter().all(|t| t.abs() < 10.0), "{c:#?}");
}

/// The emulator behind a transport that panics once, 20 packets into the
/// first force (as a bug mid-pulse would).
struct PanicsMidPulse {
    inner: EmulatedFalcon,
    forced: u32,
    panicked: bool,
}

impl HandOf for PanicsMidPulse {
    fn emulator(&mut self) -> &mut EmulatedFalcon {
        &mut self.inner
    }
}

impl FalconTransport for PanicsMidPulse {
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.inner.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.write(bytes)?;
        if self.inner.motor() != [0; 3] {
            self.forced += 1;
        }
        if self.forced == 20 && !self.panicked {
            self.panicked = true;
            panic!("a bug mid-pulse");
        }
        Ok(())
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.inner.read(buf, timeout)
    }
    fn now(&self) -> std::time::Instant {
        self.inner.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.inner.advance_to(t_s)
    }
    fn take_stall(&mut self) -> Option<Duration> {
        self.inner.take_stall()
    }
}

#[test]
fn a_panic_mid_pulse_leaves_the_forces_zero() {
    let lp = thesis_emulator();
    let config = crate::device::falcon::config_from_profile(&lp).unwrap();
    let sim = crate::device::sim::SimDevice::new(&lp.profile, &lp.base_dir, None, 7)
        .unwrap()
        .without_faults();
    let inner = EmulatedFalcon::new(
        sim,
        EmulatorConfig {
            device: lp.profile.falcon.clone().unwrap().emulator,
            frame: config.frame,
            position_noise_m: lp.profile.simulator.position_noise_m,
            ..EmulatorConfig::default()
        },
    );
    let wrapped = PanicsMidPulse {
        inner,
        forced: 0,
        panicked: false,
    };
    let mut device = FalconDevice::open(wrapped, config, &mut |_| {}).unwrap();
    let mut report = Report::new("thesis-emulator");
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_steps(
            &mut device,
            Pace {
                clock: &mut clock(),
                stop: &AtomicBool::new(false),
            },
            &mut Script::answering(true),
            &options(),
            &mut report,
        )
    }));
    assert!(outcome.is_err(), "the transport should have panicked");
    assert!(device.transport().panicked);
    assert_eq!(device.transport().inner.motor(), [0; 3]);
    assert_eq!(device.motor_commands(), [0; 3]);
}

/// Ctrl-C while the user holds the grip for the pulses: the pulse step
/// fails as interrupted, no pulse runs, and the forces are zero.
#[test]
fn a_stop_flag_ends_the_test_with_the_forces_zero() {
    let lp = thesis_emulator();
    let stop = AtomicBool::new(false);
    struct StopsAtHold<'a> {
        stop: &'a AtomicBool,
        script: Script,
    }
    impl Operator<EmulatedFalcon> for StopsAtHold<'_> {
        fn request(&mut self, request: &Request, transport: &mut EmulatedFalcon) {
            if *request == Request::HoldLightly {
                self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
            }
            self.script.request(request, transport);
        }
        fn confirm(&mut self, q: &str) -> bool {
            Operator::<EmulatedFalcon>::confirm(&mut self.script, q)
        }
        fn note(&mut self, line: &str) {
            Operator::<EmulatedFalcon>::note(&mut self.script, line)
        }
    }
    let mut user = StopsAtHold {
        stop: &stop,
        script: Script::answering(true),
    };
    let (report, device) = run(
        &lp.profile.name,
        |log| open_emulated(&lp, None, 7, log),
        Pace {
            clock: &mut clock(),
            stop: &stop,
        },
        &mut user,
        &options(),
    );
    let device = device.unwrap();
    let text = report.lines().join("\n");
    assert_eq!(verdict(&report, "encoders"), Verdict::Pass, "{text}");
    assert_eq!(verdict(&report, "pulses"), Verdict::Fail, "{text}");
    assert!(
        text.contains("interrupted (Ctrl-C)") && !report.passed,
        "{text}"
    );
    assert!(report.pulses.is_empty());
    assert_eq!(device.transport().counters.max_motor, 0);
    assert_eq!(device.transport().motor(), [0; 3]);
}

/// A Falcon without firmware: the self-test uploads it, each step told, a
/// failed first attempt retried, and the report says how it went.
#[test]
fn firmware_is_loaded_when_needed_and_each_step_told() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("nvent_firmware.bin");
    let bytes: Vec<u8> = (0..8492u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&image, bytes).unwrap();
    let mut lp = thesis_emulator();
    let falcon = lp.profile.falcon.as_mut().unwrap();
    falcon.firmware = Some(image);
    falcon.emulator.firmware_loaded = false;
    falcon.emulator.upload_failures = 1;
    let mut user = Script::answering(true);
    let (report, device) = run_on(&lp, &mut user);
    let text = report.lines().join("\n");
    assert!(report.passed, "{text}");
    assert_eq!(device.transport().counters.uploads_completed, 1);
    assert!(
        text.contains("firmware uploaded on attempt 2 (1 failed before)"),
        "{text}"
    );
    let told = user.notes.join("\n");
    assert!(
        told.contains("uploading firmware") && told.contains("attempt 1 failed"),
        "{told}"
    );
    assert!(
        report.open_log.iter().any(|l| l == "firmware running"),
        "{text}"
    );
}

/// The emulator behind a transport that raises the stop flag (as a signal
/// would) 20 packets into the first force, on firmware that keeps the last
/// force it was sent.
struct StopsMidPulse {
    inner: EmulatedFalcon,
    stop: std::sync::Arc<AtomicBool>,
    forced: u32,
    held_when_stopped: [i16; 3],
}

impl HandOf for StopsMidPulse {
    fn emulator(&mut self) -> &mut EmulatedFalcon {
        &mut self.inner
    }
}

impl FalconTransport for StopsMidPulse {
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.inner.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.write(bytes)?;
        if self.inner.motor() != [0; 3] {
            self.forced += 1;
            if self.forced == 20 {
                self.held_when_stopped = self.inner.motor();
                self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        }
        Ok(())
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.inner.read(buf, timeout)
    }
    fn now(&self) -> std::time::Instant {
        self.inner.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.inner.advance_to(t_s)
    }
    fn applied_motor(&self) -> Option<[i16; 3]> {
        self.inner.applied_motor()
    }
}

#[test]
fn a_signal_while_a_pulse_holds_a_force_leaves_the_motors_at_zero() {
    let mut lp = thesis_emulator();
    lp.profile
        .falcon
        .as_mut()
        .unwrap()
        .emulator
        .keeps_last_force = true;
    let config = crate::device::falcon::config_from_profile(&lp).unwrap();
    let sim = crate::device::sim::SimDevice::new(&lp.profile, &lp.base_dir, None, 7)
        .unwrap()
        .without_faults();
    let inner = EmulatedFalcon::new(
        sim,
        EmulatorConfig {
            device: lp.profile.falcon.clone().unwrap().emulator,
            frame: config.frame,
            position_noise_m: lp.profile.simulator.position_noise_m,
            ..EmulatorConfig::default()
        },
    );
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let wrapped = StopsMidPulse {
        inner,
        stop: stop.clone(),
        forced: 0,
        held_when_stopped: [0; 3],
    };
    let (report, device) = run(
        &lp.profile.name,
        |log| {
            FalconDevice::open(wrapped, config, log)
                .map_err(|e| crate::device::falcon::OpenError::Device(e.to_string()))
        },
        Pace {
            clock: &mut clock(),
            stop: &stop,
        },
        &mut Script::answering(true),
        &options(),
    );
    let device = device.unwrap();
    let text = report.lines().join("\n");
    assert_ne!(device.transport().held_when_stopped, [0; 3]);
    assert!(text.contains("interrupted (Ctrl-C)"), "{text}");
    // The firmware would have kept the force: only the zero packet stopped it.
    assert_eq!(device.transport().inner.motor(), [0; 3]);
    assert_eq!(report.motors_after, Some([0; 3]));
    assert!(report.zero_force_confirmed, "{text}");
    assert!(
        text.contains("the zero-force packet left the host"),
        "{text}"
    );
}

#[test]
fn a_slow_link_fails_the_link_step_and_a_timed_one_passes() {
    // The thesis emulator's timed link: each reply read at the next tick,
    // about one period after its packet, under the two-period limit.
    let lp = thesis_emulator();
    let (report, _) = run_on(&lp, &mut Script::answering(true));
    let q = report
        .link
        .as_ref()
        .and_then(|l| l.quality)
        .expect("measured");
    let text = report.lines().join("\n");
    assert_eq!(verdict(&report, "link"), Verdict::Pass, "{text}");
    assert!(q.round_trip_p99_ms.unwrap() < q.limit_p99_ms, "{q:?}");
    // Every reply 1.5 ms late: over a tick, reported, not hidden.
    let mut lp = thesis_emulator();
    lp.profile.falcon.as_mut().unwrap().emulator.slow_link_ms = 1.5;
    let (report, _) = run_on(&lp, &mut Script::answering(true));
    let text = report.lines().join("\n");
    let q = report
        .link
        .as_ref()
        .and_then(|l| l.quality)
        .expect("measured");
    assert_eq!(verdict(&report, "link"), Verdict::Fail, "{text}");
    assert!(
        q.missed_per_1000 > 100.0 || q.round_trip_p99_ms.is_none_or(|p| p >= 1.0),
        "{q:?}"
    );
    assert!(text.contains("the link is too slow"), "{text}");
}
