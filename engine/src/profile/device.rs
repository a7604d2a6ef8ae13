//! `[device]`: which device drives the probe, the servo rate, the missed-
//! deadline rules and the opt-in real-time setup; and what the device kinds
//! can reach (the workspace box, the largest force). Schema and checks only.

use serde::{Deserialize, Serialize};

use super::{Invalid, bad};

/// What the device kinds can reach, in the profile frame (the thesis's frame:
/// x along the stroke, y vertical and up, z towards the user), in metres.
/// The Novint SDK frame the thesis used spans about 10 cm on each axis
/// (section 3.1.1); its z range is offset because Table 3.1 works at z = −2…−6 cm.
pub const WORKSPACE_MIN_M: [f64; 3] = [-0.05, -0.05, -0.07];
pub const WORKSPACE_MAX_M: [f64; 3] = [0.05, 0.05, 0.03];
/// The Falcon's largest continuous force (CHAI3D's figure), per axis, in newtons.
pub const DEVICE_MAX_FORCE_N: f64 = 8.0;

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DeviceKind {
    /// The physical simulation of the Falcon and the texture (the default).
    Sim,
    /// A real Novint Falcon on USB.
    Falcon,
    /// The real driver stack over a byte-level emulated Falcon.
    FalconEmulator,
}

impl DeviceKind {
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Sim => "sim",
            DeviceKind::Falcon => "falcon",
            DeviceKind::FalconEmulator => "falcon-emulator",
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Device {
    pub kind: DeviceKind,
    /// Servo rate in Hz (the thesis: 1 kHz).
    pub rate_hz: f64,
    /// Consecutive missed deadlines that abort a motion.
    #[serde(default = "default_missed_streak")]
    pub missed_deadline_streak: u32,
    /// A tick counts as missed when it starts this late, as a fraction of the period.
    #[serde(default = "default_missed_fraction")]
    pub missed_deadline_fraction: f64,
    /// Of the last 100 ticks while driving, this many too far apart for
    /// the controller's gains, with the force at its limit as often, stop
    /// the motion (the starved servo's limit cycle; 1–100).
    #[serde(default = "default_late_tick_limit")]
    pub late_tick_limit: u32,
    /// Ask the OS for real-time scheduling of the servo thread (opt-in).
    #[serde(default)]
    pub realtime: Option<Realtime>,
    /// While the loop drives the probe (Target and Test modes) or a scan
    /// records, wake this many microseconds before each deadline and spin to
    /// it: trades CPU (spin / period of a core, never in Manual mode) for
    /// punctual ticks where the OS wakes threads late. 0 sleeps all the way.
    #[serde(default)]
    pub spin_us: u32,
}

/// Real-time setup of the servo thread: SCHED_FIFO at `priority`, memory
/// locked, optionally pinned to one core. When the system refuses (no
/// privilege, no RT limits), the loop says so once and runs on without it.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Realtime {
    /// SCHED_FIFO priority, 1–99.
    pub priority: u8,
    /// Lock the process's memory (mlockall) so page faults cannot stall a tick.
    #[serde(default)]
    pub lock_memory: bool,
    /// Pin the servo thread to this core.
    #[serde(default)]
    pub cpu: Option<usize>,
}

/// The servo loop's tick-interval guard counts late ticks over this many
/// ticks; by default this many of them stop the motion (see
/// `servo::guards::IntervalGuard`).
pub const LATE_TICK_WINDOW: usize = 100;
pub const DEFAULT_LATE_TICK_LIMIT: u32 = 10;

fn default_missed_streak() -> u32 {
    50
}
fn default_missed_fraction() -> f64 {
    0.5
}
fn default_late_tick_limit() -> u32 {
    DEFAULT_LATE_TICK_LIMIT
}

/// Check `[device]`.
pub(super) fn validate(d: &Device) -> Result<(), Invalid> {
    if !(d.rate_hz.is_finite() && (10.0..=10_000.0).contains(&d.rate_hz)) {
        return bad(
            "device.rate_hz",
            format!("must be between 10 and 10000 Hz, got {}", d.rate_hz),
        );
    }
    if d.missed_deadline_streak == 0 {
        return bad("device.missed_deadline_streak", "must be at least 1");
    }
    let window = LATE_TICK_WINDOW as u32;
    if !(1..=window).contains(&d.late_tick_limit) {
        return bad(
            "device.late_tick_limit",
            format!(
                "must be from 1 to {window} (late ticks of the last {window}), got {}",
                d.late_tick_limit
            ),
        );
    }
    if let Some(rt) = &d.realtime
        && !(1..=99).contains(&rt.priority)
    {
        return bad(
            "device.realtime.priority",
            format!("must be from 1 to 99, got {}", rt.priority),
        );
    }
    if f64::from(d.spin_us) * 1e-6 * d.rate_hz >= 0.9 {
        return bad(
            "device.spin_us",
            format!(
                "{} µs is most of the {:.0} µs period; keep it under 90 %",
                d.spin_us,
                1e6 / d.rate_hz
            ),
        );
    }
    if !(d.missed_deadline_fraction > 0.0 && d.missed_deadline_fraction <= 10.0) {
        return bad("device.missed_deadline_fraction", "must be in (0, 10]");
    }
    Ok(())
}
