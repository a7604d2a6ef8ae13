//! The servo loop: read the device, run Eq. 3.1 towards a moving set-point,
//! command the force, record the scan leg — once per tick, at the profile's
//! rate, against absolute deadlines.
//!
//! One loop serves every use: `ServoLoop::tick` is the whole cycle; the
//! console and `scan` run it on its own named thread in real time
//! ([`spawn`]), `simulate` calls it directly under a virtual clock. The loop
//! never blocks on a consumer and never allocates per tick: commands come in
//! through a crossbeam channel polled without waiting; telemetry goes out
//! through a bounded channel and what cannot be delivered is counted; scan
//! samples go to the recorder's block pool, which loses none. Every force is
//! checked finite and clamped. Dropping the loop — normal exit, error,
//! panic — zeroes the device's forces.
//!
//! The last line of defence against a front end that has gone: the loop
//! halts on its own (forces zero, any scan kept as aborted) when its command
//! channel disconnects, and — for a front end that opts in by heartbeating
//! ([`ServoHandle::heartbeat`]) — stops the motion when the heartbeat stops
//! for [`WATCHDOG_S`].

pub mod controller;
pub mod guards;
pub mod stats;
pub mod trajectory;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, TryRecvError, TrySendError, bounded};
use serde::Serialize;

use crate::clock::{self, Clock};
use crate::device::{HapticDevice, Reading};
use crate::profile::Rig;
use crate::recorder::{Recorder, Sample, SavedScan, ScanSink};
use controller::SpringDamper;
use guards::{FollowingGuard, IntervalGuard};
use stats::{LoopStats, StatsCollector};
use trajectory::Trajectory;

/// The thesis GUI's operational modes (section 3.1.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Mode {
    /// No forces: the probe moves by hand.
    Manual,
    /// Hold (glide to) a target position.
    Target,
    /// Run the waypoint path; the scan leg is recorded.
    Test,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Manual => "Manual",
            Mode::Target => "Target",
            Mode::Test => "Test",
        }
    }
}

pub enum Command {
    SetMode(Mode),
    /// Target mode: glide to this position (metres).
    SetTarget([f64; 3]),
    /// Test mode: run the path and record the scan leg to `path`.
    StartScan {
        path: PathBuf,
        meta: Vec<(String, toml::Value)>,
    },
    /// Stop the motion and any scan; forces zero (manual mode).
    Abort,
    /// Scale the path speeds (1.0 = the profile's).
    SetSpeedScale(f64),
    /// Stop the motion and any scan for this reason (kept in the scan's
    /// `# aborted` line); forces zero (manual mode).
    Stop(String),
    Shutdown,
}

/// Seconds without a heartbeat, once a front end has started heartbeating,
/// after which the loop stops the motion on its own: the front end is stuck
/// or gone (a terminal that blocks, a thread that died).
pub const WATCHDOG_S: f64 = 1.0;

/// A snapshot of one tick, for displays. Lossy: dropped when nobody reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    pub tick: u64,
    pub t_s: f64,
    pub pos_m: [f64; 3],
    pub setpoint_m: [f64; 3],
    pub force_n: [f64; 3],
    pub mode: Mode,
    pub scanning: bool,
    pub scan_progress: f64,
    pub homed: bool,
    pub speed_scale: f64,
    /// Refreshed four times a second.
    pub stats: LoopStats,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ServoEvent {
    ScanStarted {
        path: PathBuf,
    },
    /// The motion of a scan ended; the recorder reports the file separately.
    ScanEnded {
        path: PathBuf,
        samples: u64,
        aborted: Option<String>,
        /// Loop statistics over this scan's ticks.
        stats: LoopStats,
    },
    /// The motion was stopped for a reason the user should see.
    MotionStopped {
        reason: String,
    },
    /// Something the user should know that stops nothing (said once).
    Notice {
        message: String,
    },
}

/// Why `tick` says the loop should end.
#[derive(Debug, Clone, PartialEq)]
pub enum Halt {
    Shutdown,
    Interrupted,
    DeviceError(String),
}

impl std::fmt::Display for Halt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Halt::Shutdown => write!(f, "shut down"),
            Halt::Interrupted => write!(f, "interrupted"),
            Halt::DeviceError(e) => write!(f, "{e}"),
        }
    }
}

/// The loop's links to the outside, all optional for headless use.
#[derive(Default)]
pub struct Links {
    pub commands: Option<Receiver<Command>>,
    pub telemetry: Option<Sender<Telemetry>>,
    pub events: Option<Sender<ServoEvent>>,
    /// Set by signal handlers: abort any scan and halt.
    pub stop: Option<Arc<AtomicBool>>,
}

/// Catching up after a stall, ticks come no closer than this many periods.
const CATCH_UP_MIN_PERIOD: f64 = 0.5;
/// Further behind than this many periods, the loop skips instead.
const CATCH_UP_LIMIT: f64 = 20.0;

pub struct ServoLoop<D: HapticDevice, C: Clock> {
    device: D,
    clock: C,
    path: crate::profile::PathSpec,
    transit_speed: f64,
    controller: SpringDamper,
    period: f64,
    missed_limit: u32,
    missed_fraction: f64,
    mode: Mode,
    setpoint: [f64; 3],
    trajectory: Option<Trajectory>,
    speed_scale: f64,
    scan_path: Option<PathBuf>,
    scan_meta: Option<Vec<(String, toml::Value)>>,
    scan_t0: Option<f64>,
    sink: ScanSink,
    stats: StatsCollector,
    scan_stats: StatsCollector,
    snapshot: LoopStats,
    links: Links,
    deadline_index: u64,
    last_t: Option<f64>,
    reading: Reading,
    force: [f64; 3],
    halted: Option<Halt>,
    /// The device's link counters when the scan began.
    link_at_scan_start: Option<crate::device::LinkStats>,
    /// The front end's heartbeat (armed by its first beat), the last value
    /// seen and the loop time it was first seen at.
    heartbeat: Option<Arc<AtomicU64>>,
    beat: u64,
    beat_at: f64,
    following: FollowingGuard,
    intervals: IntervalGuard,
    force_limit: f64,
}

impl<D: HapticDevice, C: Clock> ServoLoop<D, C> {
    /// A loop holding the probe where it is, in manual mode, recording into `sink`.
    /// The rig comes from [`crate::profile::Profile::rig`].
    pub fn new(device: D, clock: C, rig: Rig<'_>, sink: ScanSink, links: Links) -> Self {
        let c = rig.controller;
        ServoLoop {
            device,
            clock,
            path: rig.path.clone(),
            transit_speed: rig
                .path
                .transit_speed_m_per_s
                .unwrap_or(rig.path.speed_m_per_s),
            controller: SpringDamper::new(
                c.stiffness_n_per_m,
                c.damping_n_s_per_m,
                c.force_limit_n,
            ),
            period: 1.0 / rig.device.rate_hz,
            missed_limit: rig.device.missed_deadline_streak,
            missed_fraction: rig.device.missed_deadline_fraction,
            mode: Mode::Manual,
            setpoint: rig.path.waypoints_m[0],
            trajectory: None,
            speed_scale: 1.0,
            scan_path: None,
            scan_meta: None,
            scan_t0: None,
            sink,
            stats: StatsCollector::new(rig.device.rate_hz),
            scan_stats: StatsCollector::new(rig.device.rate_hz),
            snapshot: LoopStats::default(),
            links,
            deadline_index: 0,
            last_t: None,
            reading: Reading {
                pos_m: rig.path.waypoints_m[0],
                ..Reading::default()
            },
            force: [0.0; 3],
            halted: None,
            link_at_scan_start: None,
            heartbeat: None,
            beat: 0,
            beat_at: 0.0,
            following: FollowingGuard::default(),
            intervals: IntervalGuard::new(
                c.stiffness_n_per_m,
                c.damping_n_s_per_m,
                rig.device.late_tick_limit,
            ),
            force_limit: c.force_limit_n,
        }
    }

    /// Watch a front end's heartbeat: once it has beaten at all, the motion
    /// stops (forces zero, any scan kept as aborted) when it stays unchanged
    /// for [`WATCHDOG_S`] seconds of loop time.
    pub fn watch_heartbeat(&mut self, beat: Arc<AtomicU64>) {
        self.beat = beat.load(Ordering::Relaxed);
        self.heartbeat = Some(beat);
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The device's last reading.
    pub fn reading(&self) -> Reading {
        self.reading
    }

    pub fn device(&self) -> &D {
        &self.device
    }

    pub fn device_mut(&mut self) -> &mut D {
        &mut self.device
    }

    /// A scan requested or running.
    pub fn scan_pending(&self) -> bool {
        self.scan_path.is_some()
    }

    pub fn stats(&self) -> LoopStats {
        let mut s = self.stats.snapshot();
        s.recorder_blocks_grown = self.sink.grown;
        s.link = self.device.link_stats();
        s
    }

    pub fn halted(&self) -> Option<&Halt> {
        self.halted.as_ref()
    }

    pub fn apply(&mut self, cmd: Command) {
        match cmd {
            Command::SetMode(m) => self.set_mode(m),
            Command::SetTarget(p) => {
                self.mode = Mode::Target;
                self.trajectory = Some(Trajectory::glide(self.setpoint, p, self.transit_speed));
            }
            Command::StartScan { path, meta } => self.start_scan(path, meta),
            Command::Abort => self.stop_motion("aborted by the user"),
            Command::Stop(reason) => self.stop_motion(&reason),
            Command::SetSpeedScale(s) => {
                if s.is_finite() && s > 0.0 {
                    self.speed_scale = s.clamp(0.1, 4.0);
                }
            }
            Command::Shutdown => self.halted = Some(Halt::Shutdown),
        }
    }

    fn set_mode(&mut self, m: Mode) {
        if self.sink.is_active() || self.scan_path.is_some() {
            self.stop_motion("the mode changed during the scan");
        }
        self.mode = m;
        self.trajectory = None;
        self.setpoint = self.reading.pos_m;
        self.controller.reset();
    }

    /// Test mode: run the path from the current set-point, recording the scan leg.
    pub fn start_scan(&mut self, path: PathBuf, meta: Vec<(String, toml::Value)>) {
        if self.sink.is_active() {
            self.stop_motion("a new scan was started");
        }
        self.mode = Mode::Test;
        if self.trajectory.is_none() {
            self.setpoint = self.reading.pos_m;
        }
        self.trajectory = Some(Trajectory::for_path(&self.path, self.setpoint));
        self.scan_path = Some(path);
        self.scan_meta = Some(meta);
        self.scan_t0 = None;
    }

    /// Stop any motion and scan: forces zero (manual mode), the scan kept as aborted.
    pub fn stop_motion(&mut self, reason: &str) {
        let was_scanning = self.sink.is_active() || self.scan_path.is_some();
        self.end_scan(Some(reason.to_string()));
        self.mode = Mode::Manual;
        self.trajectory = None;
        self.force = [0.0; 3];
        self.device.make_safe();
        if was_scanning || reason != "aborted by the user" {
            self.event(ServoEvent::MotionStopped {
                reason: reason.to_string(),
            });
        }
    }

    fn end_scan(&mut self, aborted: Option<String>) {
        if let Some(path) = self.scan_path.take() {
            let samples = self.sink.rows();
            let was_active = self.sink.is_active();
            self.sink.end(aborted.clone());
            self.scan_meta = None;
            self.scan_t0 = None;
            if was_active || aborted.is_some() {
                let mut stats = self.scan_stats.snapshot();
                stats.dropped_telemetry = self.stats.dropped_telemetry;
                stats.recorder_blocks_grown = self.sink.grown;
                stats.link = match (self.device.link_stats(), self.link_at_scan_start) {
                    (Some(now), Some(start)) => Some(now.since(&start)),
                    (now, _) => now,
                };
                self.event(ServoEvent::ScanEnded {
                    path,
                    samples,
                    aborted,
                    stats,
                });
            }
        }
    }

    fn event(&mut self, e: ServoEvent) {
        if let Some(tx) = &self.links.events
            && tx.try_send(e).is_err()
        {
            self.stats.dropped_events += 1;
        }
    }

    /// One servo cycle. `Err` when the loop must end (the device is then safe).
    pub fn tick(&mut self) -> Result<(), Halt> {
        if let Some(h) = &self.halted {
            return Err(h.clone());
        }
        self.take_commands()?;
        let (now, missed) = self.wait_for_deadline();
        let reading = self.read_device(now)?;
        let dt = self.last_t.map_or(self.period, |t| now - t);
        self.last_t = Some(now);
        self.check_heartbeat(now);

        let (scanning, progress) = self.advance_setpoint(reading, dt);
        let force = self.drive(now, reading, dt);
        if let Err(e) = self.device.command(force) {
            let reason = format!("device write failed: {e}");
            self.halt(Halt::DeviceError(reason.clone()), &reason);
            return Err(Halt::DeviceError(reason));
        }
        self.force = force;
        self.record(now, reading, scanning);
        self.count_tick(now, missed);
        self.send_telemetry(now, reading, progress);
        Ok(())
    }

    /// Commands (a few per tick, never waiting), the stop flag and a
    /// shutdown: `Err` when the loop must end.
    fn take_commands(&mut self) -> Result<(), Halt> {
        for _ in 0..8 {
            let Some(rx) = self.links.commands.as_ref() else {
                break;
            };
            match rx.try_recv() {
                Ok(cmd) => self.apply(cmd),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    // Nobody can steer the loop any more: make the device safe and end.
                    let reason = "the front end is gone (its command channel closed)";
                    self.halt(Halt::Interrupted, reason);
                    return Err(Halt::Interrupted);
                }
            }
        }
        if self
            .links
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
        {
            self.halt(Halt::Interrupted, "interrupted by a signal");
            return Err(Halt::Interrupted);
        }
        if let Some(h) = self.halted.clone() {
            self.halt(h.clone(), "the servo loop was shut down");
            return Err(h);
        }
        Ok(())
    }

    /// Wait for the next absolute deadline: the time, and whether it was
    /// missed. After a stall the loop catches up on that schedule with
    /// periods no shorter than half a period (so the mean rate holds and the
    /// controller's rate estimate stays sane); beyond CATCH_UP_LIMIT periods
    /// behind it skips the passed deadlines.
    fn wait_for_deadline(&mut self) -> (f64, bool) {
        self.deadline_index += 1;
        let deadline = self.deadline_index as f64 * self.period;
        let target = match self.last_t {
            Some(prev) => deadline.max(prev + CATCH_UP_MIN_PERIOD * self.period),
            None => deadline,
        };
        // Spin to punctual ticks only while the loop drives the probe or a
        // scan records (spinning costs CPU; the idle console stays cheap).
        self.clock
            .set_precise(self.mode != Mode::Manual || self.sink.is_active());
        let now = self.clock.wait_until(target);
        let missed = now - target > self.missed_fraction * self.period;
        let behind = now - deadline;
        if behind > CATCH_UP_LIMIT * self.period {
            // Each skipped deadline counts as missed.
            let skipped = (behind / self.period).floor() as u64;
            self.deadline_index += skipped;
            self.stats.missed += skipped;
            if self.sink.is_active() {
                self.scan_stats.missed += skipped;
            }
        }
        (now, missed)
    }

    /// The device's reading at `now`; a failed read, or a position that is
    /// not a number, halts the loop.
    fn read_device(&mut self, now: f64) -> Result<Reading, Halt> {
        let reading = match self.device.read(now) {
            // A position that is not a number never reaches the controller,
            // the device or the recording: the device is not to be trusted.
            Ok(r) if r.pos_m.iter().any(|v| !v.is_finite()) => {
                Err(crate::device::DeviceError::BadReading(format!(
                    "position ({}, {}, {}) m at {now:.3} s is not a number",
                    r.pos_m[0], r.pos_m[1], r.pos_m[2]
                )))
            }
            other => other,
        };
        let reading = match reading {
            Ok(r) => r,
            Err(e) => {
                let reason = format!("device read failed: {e}");
                self.halt(Halt::DeviceError(reason.clone()), &reason);
                return Err(Halt::DeviceError(reason));
            }
        };
        // A read that blocked: its time passes before the force goes out, and
        // the deadlines it overran count as missed on the next tick.
        if let Some(d) = self.device.take_stall() {
            self.clock.stall(d.as_secs_f64());
        }
        self.reading = reading;
        Ok(reading)
    }

    /// Move the set-point on; whether this tick is recorded and how far
    /// the scan has come.
    fn advance_setpoint(&mut self, reading: Reading, dt: f64) -> (bool, f64) {
        match self.mode {
            Mode::Manual => {
                self.setpoint = reading.pos_m;
                self.controller.reset();
                (false, 0.0)
            }
            Mode::Target | Mode::Test => {
                let Some(t) = self.trajectory.as_mut() else {
                    return (false, 0.0);
                };
                let step = t.advance(dt, self.speed_scale);
                self.setpoint = step.setpoint;
                if step.done {
                    self.trajectory = None;
                }
                (step.scanning, step.scan_progress)
            }
        }
    }

    /// The force for this tick (zero in manual mode or before homing), and
    /// the guards on the motion it drives.
    fn drive(&mut self, now: f64, reading: Reading, dt: f64) -> [f64; 3] {
        if self.mode == Mode::Manual || !reading.homed {
            self.following.reset();
            self.intervals.reset();
            return [0.0; 3];
        }
        let force = match self.controller.force(reading.pos_m, self.setpoint, dt) {
            Ok(f) => f,
            Err(_) => {
                self.stop_motion("the controller produced a non-finite force");
                return [0.0; 3];
            }
        };
        let saturated = force.iter().any(|f| f.abs() >= self.force_limit);
        if let Some(reason) = self.intervals.check(dt, saturated) {
            self.stop_motion(&reason);
            return [0.0; 3];
        }
        if let Some(reason) = self
            .following
            .check(now, reading.pos_m, self.setpoint, force)
        {
            self.stop_motion(&reason);
            return [0.0; 3];
        }
        force
    }

    /// Recording: the scan leg and its dwell.
    fn record(&mut self, now: f64, reading: Reading, scanning: bool) {
        if scanning && self.scan_path.is_some() && !self.sink.is_active() {
            let path = self.scan_path.clone().expect("checked above");
            let mut meta = self.scan_meta.take().unwrap_or_default();
            meta.push((
                "started_at".into(),
                toml::Value::String(
                    humantime::format_rfc3339_millis(std::time::SystemTime::now()).to_string(),
                ),
            ));
            self.sink.begin(&path, meta);
            self.scan_t0 = Some(now);
            self.scan_stats.reset();
            self.link_at_scan_start = self.device.link_stats();
            self.event(ServoEvent::ScanStarted { path });
        }
        if self.sink.is_active() {
            if scanning {
                self.sink.push(Sample {
                    t_s: now - self.scan_t0.unwrap_or(now),
                    pos_m: reading.pos_m,
                    force_n: self.force,
                });
            } else {
                self.end_scan(None);
            }
        } else if self.scan_path.is_some() && self.trajectory.is_none() {
            // The path ended without a scan leg having run.
            self.end_scan(Some("the path ended before the scan leg".into()));
        }
        if self.sink.write_failed() {
            // A full disk: no point stroking on; the recorder has the details.
            self.stop_motion("the recording could not be written");
        }
    }

    /// The tick counted; a streak of missed deadlines stops the motion.
    fn count_tick(&mut self, now: f64, missed: bool) {
        self.stats.tick(now, missed);
        if self.sink.is_active() {
            self.scan_stats.tick(now, missed);
        }
        // While nothing moves (Manual, no path, no scan) there is no motion
        // to stop: the late ticks show on the Device panel instead.
        let idle =
            self.mode == Mode::Manual && self.trajectory.is_none() && self.scan_path.is_none();
        if self.stats.streak >= self.missed_limit && idle {
            self.stats.streak = 0;
        } else if self.stats.streak >= self.missed_limit {
            let reason = format!(
                "{} consecutive missed deadlines: the loop (or the device it waits on) cannot keep {} Hz",
                self.stats.streak,
                (1.0 / self.period).round()
            );
            self.stats.streak = 0;
            self.stop_motion(&reason);
        }
        if self.stats.ticks % 250 == 1 {
            self.snapshot = self.stats();
        }
    }

    fn send_telemetry(&mut self, now: f64, reading: Reading, progress: f64) {
        let Some(tx) = &self.links.telemetry else {
            return;
        };
        let t = Telemetry {
            tick: self.stats.ticks,
            t_s: now,
            pos_m: reading.pos_m,
            setpoint_m: self.setpoint,
            force_n: self.force,
            mode: self.mode,
            scanning: self.sink.is_active(),
            scan_progress: progress,
            homed: reading.homed,
            speed_scale: self.speed_scale,
            stats: self.snapshot,
        };
        if let Err(TrySendError::Full(_)) = tx.try_send(t) {
            self.stats.dropped_telemetry += 1;
        }
    }

    /// The watchdog: a front end that heartbeat and then stopped is stuck or
    /// gone; whatever moves is stopped (once: the loop is then in manual mode).
    fn check_heartbeat(&mut self, now: f64) {
        let Some(hb) = &self.heartbeat else {
            return;
        };
        let v = hb.load(Ordering::Relaxed);
        if v != self.beat {
            self.beat = v;
            self.beat_at = now;
            return;
        }
        let moving = self.mode != Mode::Manual || self.scan_path.is_some() || self.sink.is_active();
        if v > 0 && moving && now - self.beat_at > WATCHDOG_S {
            let reason = format!(
                "the front end stopped responding (no heartbeat for {:.1} s): motion stopped, forces off",
                now - self.beat_at
            );
            self.stop_motion(&reason);
        }
    }

    fn halt(&mut self, h: Halt, reason: &str) {
        self.end_scan(Some(reason.to_string()));
        self.trajectory = None;
        self.mode = Mode::Manual;
        self.force = [0.0; 3];
        self.device.make_safe();
        if !matches!(h, Halt::Shutdown) {
            self.event(ServoEvent::MotionStopped {
                reason: reason.to_string(),
            });
        }
        self.halted = Some(h);
    }

    /// Tick until the loop halts.
    pub fn run(&mut self) -> Halt {
        loop {
            if let Err(h) = self.tick() {
                return h;
            }
        }
    }
}

impl<D: HapticDevice, C: Clock> Drop for ServoLoop<D, C> {
    fn drop(&mut self) {
        // Every exit path, panics included: forces zero, any scan kept as aborted.
        self.device.make_safe();
        if self.sink.is_active() {
            self.sink
                .end(Some("the servo loop stopped during the scan".into()));
        }
    }
}

/// A servo loop running on its own thread.
pub struct ServoHandle {
    pub commands: Sender<Command>,
    pub telemetry: Receiver<Telemetry>,
    pub events: Receiver<ServoEvent>,
    recorder: Option<Recorder>,
    pub stop: Arc<AtomicBool>,
    /// Bumped by [`ServoHandle::heartbeat`]; watched by the loop.
    beat: Arc<AtomicU64>,
    thread: Option<JoinHandle<(Halt, LoopStats)>>,
}

/// Channel sizes: telemetry holds a few frames' worth at 1 kHz.
pub const TELEMETRY_CAPACITY: usize = 4096;

/// Start the loop on a named thread, in real time. `make` builds the device
/// on that thread (some devices must live where they are polled).
pub fn spawn<D, F>(rig: Rig<'_>, make: F) -> std::io::Result<ServoHandle>
where
    D: HapticDevice + 'static,
    F: FnOnce() -> D + Send + 'static,
{
    let (cmd_tx, cmd_rx) = bounded(256);
    let (tel_tx, tel_rx) = bounded(TELEMETRY_CAPACITY);
    let (ev_tx, ev_rx) = bounded(256);
    let stop = Arc::new(AtomicBool::new(false));
    let beat = Arc::new(AtomicU64::new(0));
    let watched = beat.clone();
    let (recorder, sink) = crate::recorder::start();
    let links = Links {
        commands: Some(cmd_rx),
        telemetry: Some(tel_tx),
        events: Some(ev_tx),
        stop: Some(stop.clone()),
    };
    let (device_spec, controller, path) =
        (rig.device.clone(), rig.controller.clone(), rig.path.clone());
    let thread = std::thread::Builder::new()
        .name("servo".into())
        .spawn(move || {
            let rig = Rig {
                device: &device_spec,
                controller: &controller,
                path: &path,
            };
            let notices = rig
                .device
                .realtime
                .as_ref()
                .map(clock::request_realtime)
                .unwrap_or_default();
            // One notice for the whole real-time setup, so a status line
            // that shows the latest message shows all of it.
            if let Some(tx) = &links.events
                && !notices.is_empty()
            {
                let message = notices.join("; ");
                let _ = tx.try_send(ServoEvent::Notice { message });
            }
            let device = make();
            let clock = clock::RealClock::start().with_spin(rig.device.spin_us);
            let mut servo = ServoLoop::new(device, clock, rig, sink, links);
            servo.watch_heartbeat(watched);
            let halt = servo.run();
            let stats = servo.stats();
            (halt, stats)
        })?;
    Ok(ServoHandle {
        commands: cmd_tx,
        telemetry: tel_rx,
        events: ev_rx,
        recorder: Some(recorder),
        stop,
        beat,
        thread: Some(thread),
    })
}

impl ServoHandle {
    pub fn send(&self, c: Command) {
        let _ = self.commands.send(c);
    }

    /// Say the front end is alive (once a frame). The first beat arms the
    /// loop's watchdog: from then on, no beat for [`WATCHDOG_S`] stops the
    /// motion. Front ends that never beat (headless `scan`) are not watched.
    pub fn heartbeat(&self) {
        self.beat.fetch_add(1, Ordering::Relaxed);
    }

    /// Stop the loop and wait for it (and the recorder) to finish.
    pub fn shutdown(mut self) -> (Result<(Halt, LoopStats), String>, Vec<SavedScan>) {
        let _ = self.commands.send(Command::Shutdown);
        let result = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => Ok(r),
            Some(Err(p)) => Err(panic_message(&p)),
            None => Err("the servo thread was already joined".into()),
        };
        let saved = self.recorder.take().map(Recorder::join).unwrap_or_default();
        (result, saved)
    }

    /// Scans the recorder has finished writing since the last call.
    pub fn saved(&self) -> Vec<SavedScan> {
        self.recorder
            .as_ref()
            .map(|r| r.saved.try_iter().collect())
            .unwrap_or_default()
    }

    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }
}

impl Drop for ServoHandle {
    fn drop(&mut self) {
        if let Some(t) = self.thread.take() {
            self.stop.store(true, Ordering::Relaxed);
            let _ = t.join();
        }
    }
}

pub fn panic_message(p: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "the servo thread panicked".into()
    }
}
