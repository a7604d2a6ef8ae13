//! The Falcon self-test (`hapticlab devices --self-test`): what a lab runs
//! the first time it plugs a Falcon in, and pastes into an issue.
//!
//! Step by step: open the device (loading the firmware if it is not
//! running, each step told), cycle the LEDs, ask the user to home the grip
//! and wait for the homing bits, read the encoders while the user moves the
//! grip (positions told as they come), push the grip with a small force
//! pulse each way along each axis and check it moved the way it was pushed
//! ([`motion`]), push each arm to its stops and read the encoders there
//! against the model ([`calibration`]), then zero the forces. Each step
//! ends PASS, FAIL or SKIPPED with its figures in a [`Report`].
//!
//! The user is an [`Operator`]: told what to do, asked before any force,
//! and told how things go. The terminal is one operator, a test script
//! another, and the emulator's simulated hand does what it is asked through
//! the transport it is handed. This module never prints and never decides
//! how long a human takes: it waits for conditions (homing bits, motion),
//! each with a timeout. Forces are on only inside [`ForcesOff`], whose
//! `Drop` zeroes them on every way out (an error, a panic, an early return).

use std::sync::atomic::{AtomicBool, Ordering};

use super::emulator::HandTask;
use super::{FalconDevice, FalconTransport, OpenError, packet};
use crate::clock::Clock;
use crate::device::{DeviceError, HapticDevice, LinkStats, Reading};

mod calibration;
mod motion;
mod report;

use report::per_1000;
pub use report::{
    Calibration, LinkQuality, LinkReport, PulseResponse, Report, Step, StopAngles, Verdict,
};

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
    /// Hands off: the motors push the grip fully in, then pull it fully
    /// out (with about `grip_force_n` at the grip).
    HandsOffForStops { grip_force_n: f64 },
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
            Request::HandsOffForStops { grip_force_n } => format!(
                "hands off the grip: the motors will push it all the way in, then pull it all the way out (about {grip_force_n:.1} N), to read the encoders at the arms' stops"
            ),
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
            Request::HandsOffForStops { .. } | Request::LetGo => Some(HandTask::LetGo),
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
    /// Apply the forces without asking (`--yes`).
    pub assume_yes: bool,
    /// The link is measured this long; it passes with at most this many
    /// missed replies per 1000 packets (the round trip's 99th percentile
    /// must stay under two servo periods: the exchange is lockstep, so a
    /// reply read at the next tick measures one period by construction, and
    /// one later than two holds the position for two ticks or more).
    pub link_s: f64,
    pub max_missed_per_1000: f64,
    /// The calibration pushes each arm towards a stop with this torque (at
    /// most [`MAX_STOP_TORQUE_NM`]) for at least `stop_settle_s` and until
    /// every arm moved less than `stop_rest_deg` in the last
    /// `rest_window_s`, at most `stop_timeout_s`; it passes when every arm
    /// reads within `calibration_tolerance_deg` of the model's stop.
    pub stop_torque_nm: f64,
    pub stop_settle_s: f64,
    pub stop_rest_deg: f64,
    pub stop_timeout_s: f64,
    pub calibration_tolerance_deg: f64,
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
            stop_torque_nm: 0.04,
            stop_settle_s: 0.2,
            stop_rest_deg: 0.2,
            stop_timeout_s: 3.0,
            calibration_tolerance_deg: 1.0,
        }
    }
}

/// The largest pulse the self-test applies, newtons.
pub const MAX_PULSE_N: f64 = 1.0;
/// The largest torque the calibration pushes an arm with, N·m (about 5 N
/// at the grip against the stops).
pub const MAX_STOP_TORQUE_NM: f64 = 0.06;

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

/// What a tick commands: a force at the grip (N, profile frame), or each
/// motor's torque (N·m; the calibration's push to the stops).
#[derive(Debug, Clone, Copy)]
enum Drive {
    Force([f64; 3]),
    Torques([f64; 3]),
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
    /// One exchange: read, sit out the link's waits, command `drive`.
    fn tick<T: FalconTransport>(
        &mut self,
        dev: &mut FalconDevice<T>,
        drive: Drive,
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
        match drive {
            Drive::Force(f) => dev.command(f)?,
            Drive::Torques(tau) => dev.command_torques(tau)?,
        }
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

/// What every step works with: the device (forces zeroed when this ends),
/// the ticks that pace it, the user, how the test runs, and the report.
struct StepContext<'s, 'd, 'c, T: FalconTransport, C: Clock> {
    dev: ForcesOff<'d, T>,
    ticker: Ticker<'c, C>,
    operator: &'s mut dyn Operator<T>,
    options: &'s Options,
    report: &'s mut Report,
    /// The user's answer to the one question before any force, once asked.
    forces_agreed: Option<bool>,
}

impl<T: FalconTransport, C: Clock> StepContext<'_, '_, '_, T, C> {
    /// One exchange commanding `force_n` (N, profile frame).
    fn tick(&mut self, force_n: [f64; 3]) -> Result<Reading, Halt> {
        self.ticker.tick(self.dev.0, Drive::Force(force_n))
    }

    /// One exchange commanding each motor's torque (N·m).
    fn tick_torques(&mut self, tau_nm: [f64; 3]) -> Result<Reading, Halt> {
        self.ticker.tick(self.dev.0, Drive::Torques(tau_nm))
    }

    fn ticks(&self, secs: f64) -> u64 {
        self.ticker.ticks(secs)
    }

    fn request(&mut self, request: &Request) {
        self.operator.request(request, self.dev.0.transport_mut());
    }

    /// Whether forces may be applied: asked once (the pulses and the
    /// calibration's push), unless `--yes`.
    fn forces_agreed(&mut self, grip_force_n: f64) -> bool {
        if self.options.assume_yes {
            return true;
        }
        if let Some(yes) = self.forces_agreed {
            return yes;
        }
        let o = self.options;
        let question = format!(
            "apply force pulses of {:.1} N for {:.0} ms, each way along x, y and z, then push the grip to its stops (about {grip_force_n:.1} N)?",
            o.pulse_n.clamp(0.0, MAX_PULSE_N),
            o.pulse_s * 1000.0
        );
        let yes = self.operator.confirm(&question);
        self.forces_agreed = Some(yes);
        yes
    }
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

type StepFn<T, C> = fn(&mut StepContext<'_, '_, '_, T, C>) -> Result<(), Halt>;

/// Every step after opening, on an open device. Forces are zero when it returns.
fn run_steps<T: FalconTransport, C: Clock>(
    device: &mut FalconDevice<T>,
    pace: Pace<'_, C>,
    operator: &mut dyn Operator<T>,
    options: &Options,
    report: &mut Report,
) {
    let mut cx = StepContext {
        dev: ForcesOff(device),
        ticker: Ticker {
            clock: pace.clock,
            stop: pace.stop,
            period: 1.0 / options.rate_hz,
            k: 0,
            t: 0.0,
        },
        operator,
        options,
        report,
        forces_agreed: None,
    };
    let steps: [(&str, StepFn<T, C>); 6] = [
        ("leds", leds),
        ("link", link),
        ("homing", homing),
        ("encoders", encoders),
        ("pulses", motion::pulses),
        ("calibration", calibration::calibration),
    ];
    let mut failed = false;
    let mut halted = false;
    for (name, step) in steps {
        if failed {
            cx.report
                .push(name, Verdict::Skipped, "not run: an earlier step failed");
            continue;
        }
        cx.operator.note(&format!("step: {name}"));
        match step(&mut cx) {
            Ok(()) => {}
            Err(Halt::Device(e)) => {
                halted = true;
                cx.report
                    .push(name, Verdict::Fail, format!("the device failed: {e}"));
            }
            Err(Halt::Interrupted) => {
                halted = true;
                cx.report.push(name, Verdict::Fail, "interrupted (Ctrl-C)");
            }
        }
        // A slow link is reported, and the steps after it still run: they
        // measure directions, distances and angles, not timing. Any other
        // failure, or a halt, ends the test.
        failed = halted
            || cx
                .report
                .steps
                .iter()
                .any(|s| s.verdict == Verdict::Fail && s.name != "link");
    }
    cx.dev.0.make_safe();
    cx.report.duration_s = cx.ticker.t;
    cx.request(&Request::LetGo);
}

fn leds<T: FalconTransport, C: Clock>(cx: &mut StepContext<'_, '_, '_, T, C>) -> Result<(), Halt> {
    cx.request(&Request::WatchLeds);
    let mut answered = Vec::new();
    for (colour, bits) in [
        ("red", packet::LED_RED),
        ("green", packet::LED_GREEN),
        ("blue", packet::LED_BLUE),
    ] {
        cx.dev.0.show_leds(Some(bits));
        let before = cx.dev.0.stats();
        for _ in 0..cx.ticks(cx.options.led_s) {
            cx.tick([0.0; 3])?;
        }
        let after = cx.dev.0.stats();
        answered.push((
            colour,
            after.packets_sent - before.packets_sent,
            after.replies - before.replies,
        ));
    }
    cx.dev.0.show_leds(None);
    let silent = answered.iter().any(|(_, _, replies)| *replies == 0);
    let figures: Vec<String> = answered
        .iter()
        .map(|(c, p, r)| format!("{c} {r} of {p}"))
        .collect();
    let detail = format!(
        "replies while each colour showed: {} (the Falcon cannot see its LEDs: look)",
        figures.join(", ")
    );
    let verdict = if silent { Verdict::Fail } else { Verdict::Pass };
    cx.report.push("leds", verdict, detail);
    Ok(())
}

/// The link with the grip let go: round trips and missed replies over
/// `link_s`, against two servo periods and `max_missed_per_1000`.
fn link<T: FalconTransport, C: Clock>(cx: &mut StepContext<'_, '_, '_, T, C>) -> Result<(), Halt> {
    cx.dev.0.reset_round_trips();
    let before = cx.dev.0.stats();
    for _ in 0..cx.ticks(cx.options.link_s) {
        cx.tick([0.0; 3])?;
    }
    let after = cx.dev.0.stats();
    let packets = after.packets_sent - before.packets_sent;
    let missed = after.missed_replies - before.missed_replies;
    let rt = cx.dev.0.round_trips();
    let ms = |q: f64| rt.quantile(q).map(|s| s * 1000.0);
    let q = LinkQuality {
        round_trip_p50_ms: ms(0.5),
        round_trip_p99_ms: ms(0.99),
        missed_per_1000: per_1000(missed, packets),
        limit_p99_ms: 2.0 * 1000.0 * cx.ticker.period,
        limit_missed_per_1000: cx.options.max_missed_per_1000,
    };
    let shown = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v:.2} ms"));
    let detail = format!(
        "round trip p50 {}, p99 {}; {:.1} missed replies per 1000 packets over {:.1} s (passes with p99 under {:.2} ms, two servo periods, and at most {:.0} missed per 1000)",
        shown(q.round_trip_p50_ms),
        shown(q.round_trip_p99_ms),
        q.missed_per_1000,
        cx.options.link_s,
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
    cx.report.push("link", verdict, detail);
    cx.report.link = Some(LinkReport {
        counts: LinkStats::default(),
        quality: Some(q),
    });
    Ok(())
}

fn homing<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
) -> Result<(), Halt> {
    if cx.tick([0.0; 3])?.homed {
        cx.report
            .push("homing", Verdict::Pass, "already homed (LEDs blue)");
        return Ok(());
    }
    let timeout_s = cx.options.homing_timeout_s;
    cx.request(&Request::Home { timeout_s });
    let start = cx.ticker.t;
    for _ in 0..cx.ticks(timeout_s) {
        if cx.tick([0.0; 3])?.homed {
            let detail = format!(
                "homed {:.2} s after asking; grip at {}",
                cx.ticker.t - start,
                mm(cx.dev.0.pos)
            );
            cx.report.push("homing", Verdict::Pass, detail);
            return Ok(());
        }
    }
    let homed_bits = if cx.dev.0.is_homed() {
        "homing bits up but no position"
    } else {
        "homing bits never all up"
    };
    cx.report.push(
        "homing",
        Verdict::Fail,
        format!(
            "not homed within {timeout_s:.0} s ({homed_bits}); if the LEDs stay red, check the Falcon's wall power (homing needs the motors)"
        ),
    );
    Ok(())
}

fn encoders<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
) -> Result<(), Halt> {
    let (span_m, timeout_s) = (cx.options.move_span_m, cx.options.move_timeout_s);
    cx.request(&Request::MoveGrip { span_m, timeout_s });
    let fk_failures = cx.dev.0.stats().fk_failures;
    let start = cx.ticker.t;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let tell_every = cx.ticks(cx.options.tell_every_s);
    let mut covered = false;
    for k in 0..cx.ticks(timeout_s) {
        let r = cx.tick([0.0; 3])?;
        for a in 0..3 {
            lo[a] = lo[a].min(r.pos_m[a]);
            hi[a] = hi[a].max(r.pos_m[a]);
        }
        if k % tell_every == 0 {
            cx.operator.note(&format!("  grip at {}", mm(r.pos_m)));
        }
        if (0..3).all(|a| hi[a] - lo[a] >= span_m) {
            covered = true;
            break;
        }
    }
    let span: [f64; 3] = std::array::from_fn(|a| (hi[a] - lo[a]).max(0.0));
    let new_failures = cx.dev.0.stats().fk_failures - fk_failures;
    let detail = format!(
        "grip moved {:.1} / {:.1} / {:.1} mm along x / y / z in {:.1} s (x {:+.1}…{:+.1}, y {:+.1}…{:+.1}, z {:+.1}…{:+.1} mm); {new_failures} positions not solved",
        span[0] * 1000.0,
        span[1] * 1000.0,
        span[2] * 1000.0,
        cx.ticker.t - start,
        lo[0] * 1000.0,
        hi[0] * 1000.0,
        lo[1] * 1000.0,
        hi[1] * 1000.0,
        lo[2] * 1000.0,
        hi[2] * 1000.0,
    );
    if covered && new_failures == 0 {
        cx.report.push("encoders", Verdict::Pass, detail);
        return Ok(());
    }
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
    cx.report
        .push("encoders", Verdict::Fail, format!("{detail}: {why}"));
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

#[cfg(test)]
mod tests;
