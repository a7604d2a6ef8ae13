//! The Falcon self-test (`hapticlab devices --self-test`): what a lab runs
//! the first time it plugs a Falcon in, and pastes into an issue.
//!
//! Step by step: open the device (loading the firmware if it is not
//! running, each step told), cycle the LEDs, ask the user to home the grip
//! and wait for the homing bits, read the encoders while the user moves the
//! grip (positions told as they come), push the grip with a small force
//! pulse each way along each axis and check it moved the way it was pushed,
//! then zero the forces. Each step ends PASS, FAIL or SKIPPED with its
//! figures in a [`Report`].
//!
//! The user is an [`Operator`]: told what to do, asked before any force,
//! and told how things go. The terminal is one operator, a test script
//! another, and the emulator's simulated hand does what it is asked through
//! the transport it is handed. This module never prints and never decides
//! how long a human takes: it waits for conditions (homing bits, motion),
//! each with a timeout. Forces are on only inside [`ForcesOff`], whose
//! `Drop` zeroes them on every way out (an error, a panic, an early return).

use std::sync::atomic::{AtomicBool, Ordering};

use serde::Serialize;

use super::emulator::HandTask;
use super::{FalconDevice, FalconTransport, OpenError, packet};
use crate::clock::Clock;
use crate::device::{DeviceError, HapticDevice, LinkStats, Reading};

/// What the user is asked to do with the grip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Request {
    /// Watch the LEDs while they cycle.
    WatchLeds,
    /// Pull the grip all the way out, then push it all the way in.
    Home { timeout_s: f64 },
    /// Move the grip around: left and right, up and down, in and out.
    MoveGrip { span_m: f64, timeout_s: f64 },
    /// Hold the grip lightly in the middle of the workspace; the motors
    /// will push it.
    HoldLightly,
    /// Let go of the grip.
    LetGo,
}

impl Request {
    /// The request in words, for a person.
    pub fn instruction(&self) -> String {
        match self {
            Request::WatchLeds => {
                "watch the Falcon's LEDs: red, green, then blue, half a second each".into()
            }
            Request::Home { timeout_s } => format!(
                "home the Falcon: pull the grip all the way out towards you, then push it all the way back in (waiting up to {timeout_s:.0} s for the homing bits)"
            ),
            Request::MoveGrip { span_m, timeout_s } => format!(
                "move the grip around: left and right, up and down, in and out, at least {:.0} mm each way (waiting up to {timeout_s:.0} s)",
                span_m * 1000.0
            ),
            Request::HoldLightly => {
                "hold the grip lightly in the middle of the workspace, fingertips only: the motors will push it a little along each axis".into()
            }
            Request::LetGo => "done: you can let go of the grip".into(),
        }
    }

    /// What the emulator's simulated hand does for this request (a person
    /// is told [`Request::instruction`]).
    pub fn hand_task(&self) -> Option<HandTask> {
        match self {
            // Hands off: the grip is homed only when the user is asked to.
            Request::WatchLeds => Some(HandTask::LetGo),
            Request::Home { .. } => Some(HandTask::Home),
            Request::MoveGrip { .. } => Some(HandTask::MoveGrip),
            Request::HoldLightly => Some(HandTask::HoldLightly),
            Request::LetGo => Some(HandTask::LetGo),
        }
    }
}

/// The user's side of the self-test. `T` is the Falcon's transport, so the
/// emulator's hand can act on a request; a person ignores it.
pub trait Operator<T> {
    /// Ask the user to do something with the grip (the test then waits for
    /// it to happen).
    fn request(&mut self, request: &Request, transport: &mut T);
    /// A yes/no question (before any force is applied).
    fn confirm(&mut self, question: &str) -> bool;
    /// Progress: a step starting, the firmware loader's steps, positions.
    fn note(&mut self, line: &str);
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Pass,
    Fail,
    /// Not run: the user declined, or an earlier step failed.
    Skipped,
}

impl Verdict {
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
            Verdict::Skipped => "SKIPPED",
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    pub name: String,
    pub verdict: Verdict,
    /// What was measured, in words and numbers.
    pub detail: String,
}

/// One force pulse pair's measurement (for the report and tests).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PulseResponse {
    /// 0 = x, 1 = y, 2 = z (profile frame).
    pub axis: usize,
    /// Half the difference of the motions under the + and the − pulse
    /// (drift and gravity cancel), metres.
    pub motion_m: [f64; 3],
    /// Its component along the pushed axis, metres.
    pub along_m: f64,
    /// The cosine between the motion and the pushed axis.
    pub cosine: f64,
}

/// The link measured over a few seconds with the grip let go.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkQuality {
    /// Packet written to its reply read: the median and the 99th percentile.
    pub round_trip_p50_ms: Option<f64>,
    pub round_trip_p99_ms: Option<f64>,
    pub missed_per_1000: f64,
    /// The limits the step passes within.
    pub limit_p99_ms: f64,
    pub limit_missed_per_1000: f64,
}

/// The link's counters over the whole test, and its measured quality.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkReport {
    #[serde(flatten)]
    pub counts: LinkStats,
    #[serde(flatten)]
    pub quality: Option<LinkQuality>,
}

/// The whole run, for the user to paste into an issue.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    pub hapticlab: String,
    pub platform: String,
    pub profile: String,
    pub device: String,
    /// The firmware loader's and the USB layer's steps, as they were told.
    pub open_log: Vec<String>,
    pub steps: Vec<Step>,
    pub pulses: Vec<PulseResponse>,
    pub link: Option<LinkReport>,
    /// Seconds from the first exchange until the forces were zeroed.
    pub duration_s: f64,
    /// The zero-force packet that ended the test was seen to leave the host.
    pub zero_force_confirmed: bool,
    /// The motor commands the device applies after the test, where that
    /// can be known (the emulator); `None` for a real Falcon.
    pub motors_after: Option<[i16; 3]>,
    pub passed: bool,
}

impl Report {
    fn new(profile: &str) -> Report {
        Report {
            hapticlab: env!("CARGO_PKG_VERSION").into(),
            platform: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            profile: profile.into(),
            device: String::new(),
            open_log: Vec::new(),
            steps: Vec::new(),
            pulses: Vec::new(),
            link: None,
            duration_s: 0.0,
            zero_force_confirmed: false,
            motors_after: None,
            passed: false,
        }
    }

    fn push(&mut self, name: &str, verdict: Verdict, detail: impl Into<String>) {
        self.steps.push(Step {
            name: name.into(),
            verdict,
            detail: detail.into(),
        });
        self.passed = self.steps.iter().all(|s| s.verdict == Verdict::Pass);
    }

    /// The steps that did not pass.
    pub fn not_passed(&self) -> Vec<&Step> {
        self.steps
            .iter()
            .filter(|s| s.verdict != Verdict::Pass)
            .collect()
    }

    /// The report as text lines.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![
            "hapticlab Falcon self-test".to_string(),
            format!(
                "hapticlab {} ({}), profile {}, device {}",
                self.hapticlab, self.platform, self.profile, self.device
            ),
        ];
        // The opening's steps, unless the open step's line says it all
        // (one line: "firmware already running").
        let open_detail = self.steps.first().map(|s| s.detail.as_str());
        if !(self.open_log.len() == 1 && open_detail == Some(self.open_log[0].as_str())) {
            for l in &self.open_log {
                out.push(format!("  open: {l}"));
            }
        }
        for s in &self.steps {
            out.push(format!(
                "{:<10} {:<7} {}",
                s.name,
                s.verdict.word(),
                s.detail
            ));
        }
        if let Some(LinkReport { counts: l, .. }) = &self.link {
            out.push(format!(
                "link: {} packets, {} replies, {} missed ({:.2} per 1000 packets), {} bad packets, {} USB errors, {} saturated ticks",
                l.packets,
                l.replies,
                l.missed_replies,
                per_1000(l.missed_replies, l.packets),
                l.bad_packets,
                l.usb_errors,
                l.saturated_ticks
            ));
        }
        out.push(if self.zero_force_confirmed {
            format!(
                "forces zeroed after {:.1} s (the zero-force packet left the host)",
                self.duration_s
            )
        } else {
            format!(
                "forces zeroed after {:.1} s, but the zero-force packet was not seen to leave the host within {} ms: if the grip still pushes, unplug the Falcon's power",
                self.duration_s,
                super::SAFE_FLUSH.as_millis()
            )
        });
        let failed = self.not_passed().len();
        out.push(if self.passed {
            format!("result: PASS ({} steps)", self.steps.len())
        } else {
            format!(
                "result: FAIL ({failed} of {} steps did not pass)",
                self.steps.len()
            )
        });
        out
    }
}

fn per_1000(n: u64, of: u64) -> f64 {
    if of == 0 {
        0.0
    } else {
        1000.0 * n as f64 / of as f64
    }
}

/// How the self-test runs (`Options::default()` is what the command uses).
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    pub rate_hz: f64,
    /// Each LED colour is shown this long.
    pub led_s: f64,
    pub homing_timeout_s: f64,
    /// The grip must travel this far along every axis while moved.
    pub move_span_m: f64,
    pub move_timeout_s: f64,
    /// Positions are told this often while the grip moves.
    pub tell_every_s: f64,
    /// The pulse's force (at most 1 N) and length.
    pub pulse_n: f64,
    pub pulse_s: f64,
    /// The grip counts as at rest when it moved less than this in the last
    /// `rest_window_s`; a pulse waits for that, at most `rest_timeout_s`.
    pub rest_m: f64,
    pub rest_window_s: f64,
    pub rest_timeout_s: f64,
    /// A pulse passes when the grip moved at least this far along the
    /// pushed axis, and the motion's cosine with it is at least `min_cosine`.
    pub min_motion_m: f64,
    pub min_cosine: f64,
    /// Apply the pulses without asking (`--yes`).
    pub assume_yes: bool,
    /// The link is measured this long; it passes with at most this many
    /// missed replies per 1000 packets (the round trip's 99th percentile
    /// must stay under two servo periods: the exchange is lockstep, so a
    /// reply read at the next tick measures one period by construction, and
    /// one later than two holds the position for two ticks or more).
    pub link_s: f64,
    pub max_missed_per_1000: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rate_hz: 1000.0,
            led_s: 0.5,
            homing_timeout_s: 120.0,
            move_span_m: 0.01,
            move_timeout_s: 60.0,
            tell_every_s: 0.5,
            pulse_n: 1.0,
            pulse_s: 0.1,
            rest_m: 0.0005,
            rest_window_s: 0.1,
            rest_timeout_s: 5.0,
            min_motion_m: 0.0005,
            min_cosine: 0.7,
            assume_yes: false,
            link_s: 3.0,
            max_missed_per_1000: 100.0,
        }
    }
}

/// The largest pulse the self-test applies, newtons.
pub const MAX_PULSE_N: f64 = 1.0;

/// The Falcon's forces, on only while this lives: dropping it zeroes them
/// (an error, a panic, an early return: every way out).
pub struct ForcesOff<'a, T: FalconTransport>(pub &'a mut FalconDevice<T>);

impl<T: FalconTransport> Drop for ForcesOff<'_, T> {
    fn drop(&mut self) {
        self.0.make_safe();
    }
}

/// Why a step stopped before it could judge.
#[derive(Debug)]
enum Halt {
    Device(DeviceError),
    /// The stop flag was raised (Ctrl-C).
    Interrupted,
}

impl From<DeviceError> for Halt {
    fn from(e: DeviceError) -> Halt {
        Halt::Device(e)
    }
}

/// Ticks at the profile's rate on `clock`, against absolute deadlines.
struct Ticker<'c, C: Clock> {
    clock: &'c mut C,
    stop: &'c AtomicBool,
    period: f64,
    k: u64,
    t: f64,
}

impl<C: Clock> Ticker<'_, C> {
    /// One exchange: read, sit out the link's waits, command `force_n`.
    fn tick<T: FalconTransport>(
        &mut self,
        dev: &mut FalconDevice<T>,
        force_n: [f64; 3],
    ) -> Result<Reading, Halt> {
        if self.stop.load(Ordering::Relaxed) {
            return Err(Halt::Interrupted);
        }
        self.k += 1;
        let deadline = self.k as f64 * self.period;
        self.t = self.clock.wait_until(deadline);
        if self.t - deadline > 10.0 * self.period {
            // Far behind (a stall): skip the passed deadlines.
            self.k = (self.t / self.period).floor() as u64;
        }
        let r = dev.read(self.t)?;
        if let Some(d) = dev.take_stall() {
            self.clock.stall(d.as_secs_f64());
        }
        dev.command(force_n)?;
        Ok(r)
    }

    fn ticks(&self, secs: f64) -> u64 {
        (secs / self.period).ceil().max(1.0) as u64
    }
}

/// Where the self-test runs: the clock that paces its exchanges, and a flag
/// that stops it (Ctrl-C) with the forces zeroed.
pub struct Pace<'a, C: Clock> {
    pub clock: &'a mut C,
    pub stop: &'a AtomicBool,
}

/// Open the Falcon with `open` (which tells its steps to the operator) and
/// run every step; the report says what passed. The device is handed back
/// for inspection (its forces zero), or why it did not open.
pub fn run<T: FalconTransport, C: Clock>(
    profile: &str,
    open: impl FnOnce(&mut dyn FnMut(&str)) -> Result<FalconDevice<T>, OpenError>,
    pace: Pace<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
) -> (Report, Result<FalconDevice<T>, OpenError>) {
    let mut report = Report::new(profile);
    operator.note("opening the Falcon");
    let mut log = Vec::new();
    let opened = open(&mut |line: &str| {
        operator.note(line);
        log.push(line.to_string());
    });
    report.open_log = log;
    let mut device = match opened {
        Ok(d) => d,
        Err(e) => {
            report.push("open", Verdict::Fail, e.to_string());
            return (report, Err(e));
        }
    };
    report.device = device.kind().to_string();
    let fw = &device.stats().firmware;
    let how = if fw.already_loaded {
        "firmware already running".to_string()
    } else {
        format!(
            "firmware uploaded on attempt {} ({} failed before)",
            fw.attempts,
            fw.failures.len()
        )
    };
    report.push("open", Verdict::Pass, how);
    run_steps(&mut device, pace, operator, options, &mut report);
    let quality = report.link.take().and_then(|l| l.quality);
    report.link = device
        .link_stats()
        .map(|counts| LinkReport { counts, quality });
    let stats = device.stats();
    report.zero_force_confirmed = stats.safe_confirmed > 0 && stats.safe_unconfirmed == 0;
    report.motors_after = device.transport().applied_motor();
    (report, Ok(device))
}

/// Every step after opening, on an open device. Forces are zero when it returns.
pub fn run_steps<T: FalconTransport, C: Clock>(
    device: &mut FalconDevice<T>,
    pace: Pace<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) {
    let mut ticker = Ticker {
        clock: pace.clock,
        stop: pace.stop,
        period: 1.0 / options.rate_hz,
        k: 0,
        t: 0.0,
    };
    let mut guard = ForcesOff(device);
    let steps: [(&str, StepFn<T, C>); 5] = [
        ("leds", leds),
        ("link", link),
        ("homing", homing),
        ("encoders", encoders),
        ("pulses", pulses),
    ];
    let mut failed = false;
    let mut halted = false;
    for (name, step) in steps {
        if failed {
            report.push(name, Verdict::Skipped, "not run: an earlier step failed");
            continue;
        }
        operator.note(&format!("step: {name}"));
        match step(&mut guard, &mut ticker, operator, options, report) {
            Ok(()) => {}
            Err(Halt::Device(e)) => {
                halted = true;
                report.push(name, Verdict::Fail, format!("the device failed: {e}"));
            }
            Err(Halt::Interrupted) => {
                halted = true;
                report.push(name, Verdict::Fail, "interrupted (Ctrl-C)");
            }
        }
        // A slow link is reported, and the steps after it still run: they
        // measure directions and distances, not timing. Any other failure,
        // or a halt, ends the test.
        failed = halted
            || report
                .steps
                .iter()
                .any(|s| s.verdict == Verdict::Fail && s.name != "link");
    }
    guard.0.make_safe();
    report.duration_s = ticker.t;
    operator.request(&Request::LetGo, guard.0.transport_mut());
}

type StepFn<T, C> = fn(
    &mut ForcesOff<'_, T>,
    &mut Ticker<'_, C>,
    &mut dyn Operator<T>,
    &Options,
    &mut Report,
) -> Result<(), Halt>;

fn leds<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) -> Result<(), Halt> {
    operator.request(&Request::WatchLeds, dev.0.transport_mut());
    let mut answered = Vec::new();
    for (colour, bits) in [
        ("red", packet::LED_RED),
        ("green", packet::LED_GREEN),
        ("blue", packet::LED_BLUE),
    ] {
        dev.0.show_leds(Some(bits));
        let before = dev.0.stats();
        for _ in 0..ticker.ticks(options.led_s) {
            ticker.tick(dev.0, [0.0; 3])?;
        }
        let after = dev.0.stats();
        answered.push((
            colour,
            after.packets_sent - before.packets_sent,
            after.replies - before.replies,
        ));
    }
    dev.0.show_leds(None);
    let silent: Vec<&str> = answered
        .iter()
        .filter(|(_, _, replies)| *replies == 0)
        .map(|(c, _, _)| *c)
        .collect();
    let figures: Vec<String> = answered
        .iter()
        .map(|(c, p, r)| format!("{c} {r} of {p}"))
        .collect();
    let detail = format!(
        "replies while each colour showed: {} (the Falcon cannot see its LEDs: look)",
        figures.join(", ")
    );
    let verdict = if silent.is_empty() {
        Verdict::Pass
    } else {
        Verdict::Fail
    };
    report.push("leds", verdict, detail);
    Ok(())
}

/// The link with the grip let go: round trips and missed replies over
/// `link_s`, against two servo periods and `max_missed_per_1000`.
fn link<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    _operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) -> Result<(), Halt> {
    dev.0.reset_round_trips();
    let before = dev.0.stats();
    for _ in 0..ticker.ticks(options.link_s) {
        ticker.tick(dev.0, [0.0; 3])?;
    }
    let after = dev.0.stats();
    let packets = after.packets_sent - before.packets_sent;
    let missed = after.missed_replies - before.missed_replies;
    let rt = dev.0.round_trips();
    let ms = |q: f64| rt.quantile(q).map(|s| s * 1000.0);
    let q = LinkQuality {
        round_trip_p50_ms: ms(0.5),
        round_trip_p99_ms: ms(0.99),
        missed_per_1000: per_1000(missed, packets),
        limit_p99_ms: 2.0 * 1000.0 * ticker.period,
        limit_missed_per_1000: options.max_missed_per_1000,
    };
    let shown = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v:.2} ms"));
    let detail = format!(
        "round trip p50 {}, p99 {}; {:.1} missed replies per 1000 packets over {:.1} s (passes with p99 under {:.2} ms, two servo periods, and at most {:.0} missed per 1000)",
        shown(q.round_trip_p50_ms),
        shown(q.round_trip_p99_ms),
        q.missed_per_1000,
        options.link_s,
        q.limit_p99_ms,
        q.limit_missed_per_1000
    );
    let fast = q.round_trip_p99_ms.is_some_and(|p| p < q.limit_p99_ms);
    let (verdict, detail) = if fast && q.missed_per_1000 <= q.limit_missed_per_1000 {
        (Verdict::Pass, detail)
    } else {
        (
            Verdict::Fail,
            format!(
                "{detail}: the link is too slow for the lockstep exchange (positions are held on missed ticks): plug the Falcon in directly, not through a hub, and close programs that load the machine"
            ),
        )
    };
    report.push("link", verdict, detail);
    report.link = Some(LinkReport {
        counts: LinkStats::default(),
        quality: Some(q),
    });
    Ok(())
}

fn homing<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) -> Result<(), Halt> {
    if ticker.tick(dev.0, [0.0; 3])?.homed {
        report.push("homing", Verdict::Pass, "already homed (LEDs blue)");
        return Ok(());
    }
    let timeout_s = options.homing_timeout_s;
    operator.request(&Request::Home { timeout_s }, dev.0.transport_mut());
    let start = ticker.t;
    let limit = ticker.ticks(timeout_s);
    for _ in 0..limit {
        if ticker.tick(dev.0, [0.0; 3])?.homed {
            let p = dev.0.pos;
            report.push(
                "homing",
                Verdict::Pass,
                format!(
                    "homed {:.2} s after asking; grip at {}",
                    ticker.t - start,
                    mm(p)
                ),
            );
            return Ok(());
        }
    }
    let homed_bits = if dev.0.is_homed() {
        "homing bits up but no position"
    } else {
        "homing bits never all up"
    };
    report.push(
        "homing",
        Verdict::Fail,
        format!(
            "not homed within {timeout_s:.0} s ({homed_bits}); if the LEDs stay red, check the Falcon's wall power (homing needs the motors)"
        ),
    );
    Ok(())
}

fn encoders<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) -> Result<(), Halt> {
    let (span_m, timeout_s) = (options.move_span_m, options.move_timeout_s);
    operator.request(
        &Request::MoveGrip { span_m, timeout_s },
        dev.0.transport_mut(),
    );
    let fk_failures = dev.0.stats().fk_failures;
    let start = ticker.t;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let tell_every = ticker.ticks(options.tell_every_s);
    let limit = ticker.ticks(timeout_s);
    let mut covered = false;
    for k in 0..limit {
        let r = ticker.tick(dev.0, [0.0; 3])?;
        for a in 0..3 {
            lo[a] = lo[a].min(r.pos_m[a]);
            hi[a] = hi[a].max(r.pos_m[a]);
        }
        if k % tell_every == 0 {
            operator.note(&format!("  grip at {}", mm(r.pos_m)));
        }
        if (0..3).all(|a| hi[a] - lo[a] >= span_m) {
            covered = true;
            break;
        }
    }
    let span: [f64; 3] = std::array::from_fn(|a| (hi[a] - lo[a]).max(0.0));
    let new_failures = dev.0.stats().fk_failures - fk_failures;
    let detail = format!(
        "grip moved {:.1} / {:.1} / {:.1} mm along x / y / z in {:.1} s (x {:+.1}…{:+.1}, y {:+.1}…{:+.1}, z {:+.1}…{:+.1} mm); {new_failures} positions not solved",
        span[0] * 1000.0,
        span[1] * 1000.0,
        span[2] * 1000.0,
        ticker.t - start,
        lo[0] * 1000.0,
        hi[0] * 1000.0,
        lo[1] * 1000.0,
        hi[1] * 1000.0,
        lo[2] * 1000.0,
        hi[2] * 1000.0,
    );
    if covered && new_failures == 0 {
        report.push("encoders", Verdict::Pass, detail);
    } else {
        let still: Vec<&str> = ["x", "y", "z"]
            .into_iter()
            .zip(span)
            .filter(|(_, s)| *s < span_m)
            .map(|(n, _)| n)
            .collect();
        let why = if still.is_empty() {
            "positions the kinematics could not solve".to_string()
        } else {
            format!(
                "no {:.0} mm of motion along {} within {timeout_s:.0} s (an encoder or its cable?)",
                span_m * 1000.0,
                still.join(", ")
            )
        };
        report.push("encoders", Verdict::Fail, format!("{detail}: {why}"));
    }
    Ok(())
}

/// Wait (at most `rest_timeout_s`) until the grip is at rest; its position then.
fn come_to_rest<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    options: &Options,
) -> Result<[f64; 3], Halt> {
    let window = ticker.ticks(options.rest_window_s) as usize;
    let mut recent: std::collections::VecDeque<[f64; 3]> =
        std::collections::VecDeque::with_capacity(window + 1);
    for _ in 0..ticker.ticks(options.rest_timeout_s) {
        let p = ticker.tick(dev.0, [0.0; 3])?.pos_m;
        recent.push_back(p);
        if recent.len() > window {
            recent.pop_front();
            let first = recent[0];
            if recent.iter().all(|q| distance(*q, first) < options.rest_m) {
                break;
            }
        }
    }
    Ok(mean(recent.iter().rev().take(20)))
}

/// One pulse of `force` for `pulse_s`: the motion from rest to its end.
fn pulse<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    options: &Options,
    force: [f64; 3],
) -> Result<[f64; 3], Halt> {
    let rest = come_to_rest(dev, ticker, options)?;
    let n = ticker.ticks(options.pulse_s);
    let mut last = std::collections::VecDeque::with_capacity(6);
    for _ in 0..n {
        last.push_back(ticker.tick(dev.0, force)?.pos_m);
        if last.len() > 5 {
            last.pop_front();
        }
    }
    // Forces off at once; the next tick carries zero.
    dev.0.command([0.0; 3])?;
    let end = mean(last.iter());
    Ok(std::array::from_fn(|a| end[a] - rest[a]))
}

fn pulses<T: FalconTransport, C: Clock>(
    dev: &mut ForcesOff<'_, T>,
    ticker: &mut Ticker<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) -> Result<(), Halt> {
    let f = options.pulse_n.clamp(0.0, MAX_PULSE_N);
    let ms = options.pulse_s * 1000.0;
    operator.request(&Request::HoldLightly, dev.0.transport_mut());
    let question =
        format!("apply force pulses of {f:.1} N for {ms:.0} ms, each way along x, y and z?");
    if !options.assume_yes && !operator.confirm(&question) {
        for axis in ["x", "y", "z"] {
            report.push(
                &format!("pulse {axis}"),
                Verdict::Skipped,
                "declined: no force was applied",
            );
        }
        return Ok(());
    }
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        operator.note(&format!("  pulse along {name}: +{f:.1} N, then -{f:.1} N"));
        let mut push = [0.0; 3];
        push[axis] = f;
        let plus = pulse(dev, ticker, options, push)?;
        push[axis] = -f;
        let minus = pulse(dev, ticker, options, push)?;
        let motion_m: [f64; 3] = std::array::from_fn(|a| (plus[a] - minus[a]) / 2.0);
        let along_m = motion_m[axis];
        let size = distance(motion_m, [0.0; 3]);
        let cosine = if size > 0.0 { along_m / size } else { 0.0 };
        report.pulses.push(PulseResponse {
            axis,
            motion_m,
            along_m,
            cosine,
        });
        let detail = format!(
            "±{f:.1} N for {ms:.0} ms: moved {:+.2} mm along {name} (motion {}; cosine {cosine:.2}, at least {:.2} and {:.1} mm needed)",
            along_m * 1000.0,
            mm(motion_m),
            options.min_cosine,
            options.min_motion_m * 1000.0
        );
        let ok = along_m >= options.min_motion_m && cosine >= options.min_cosine;
        let (verdict, detail) = if ok {
            (Verdict::Pass, detail)
        } else if along_m <= -options.min_motion_m {
            (
                Verdict::Fail,
                format!(
                    "{detail}: the grip moved against the push (a motor wired backwards, or the wrong frame?)"
                ),
            )
        } else {
            (
                Verdict::Fail,
                format!(
                    "{detail}: the motion does not follow the push (a motor wired backwards or without power, or a wrong gain?)"
                ),
            )
        };
        report.push(&format!("pulse {name}"), verdict, detail);
    }
    Ok(())
}

fn mm(p: [f64; 3]) -> String {
    format!(
        "({:+.1}, {:+.1}, {:+.1}) mm",
        p[0] * 1000.0,
        p[1] * 1000.0,
        p[2] * 1000.0
    )
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

fn mean<'a>(ps: impl Iterator<Item = &'a [f64; 3]>) -> [f64; 3] {
    let (mut sum, mut n) = ([0.0; 3], 0.0);
    for p in ps {
        for a in 0..3 {
            sum[a] += p[a];
        }
        n += 1.0;
    }
    if n == 0.0 {
        return sum;
    }
    sum.map(|s| s / n)
}

#[cfg(test)]
mod tests;
