//! The profile's hardware sections: `[falcon]` (with `[falcon.emulator]`)
//! for the Novint Falcon and its emulator, and `[[triggers]]` for hands-free
//! HID triggers. Schema and validation only; this module touches no device
//! and no file (the firmware file is checked when the device opens).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::falcon_reach::{self, DEFAULT_ENCODER_OFFSET_DEG, DEFAULT_ORIGIN_M};
use super::{DeviceKind, Invalid, PathSpec, Profile};

/// How to drive a Falcon.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FalconSection {
    /// The firmware image from the user's libnifalcon or Novint install
    /// (nvent_firmware.bin recommended), relative to the profile's folder.
    /// Needed after every power-up; never shipped with hapticlab.
    #[serde(default)]
    pub firmware: Option<PathBuf>,
    /// Where the profile's origin lies in the Falcon's kinematic frame
    /// (x right, y up, z towards the user; the axes are the profile's), metres.
    #[serde(default = "default_origin")]
    pub origin_m: [f64; 3],
    /// The arm angle at encoder count 0 after homing, degrees.
    #[serde(default = "default_encoder_offset")]
    pub encoder_offset_deg: f64,
    /// Which Falcon, when several are plugged in (0 = the first listed).
    #[serde(default)]
    pub index: usize,
    /// Whole firmware loads to try before giving up (real devices need several).
    #[serde(default = "default_firmware_attempts")]
    pub firmware_attempts: u32,
    /// How long `scan` waits for the user to home the grip.
    #[serde(default = "default_homing_timeout")]
    pub homing_timeout_s: f64,
    /// How long a tick waits for the reply to its packet.
    #[serde(default = "default_reply_timeout")]
    pub reply_timeout_ms: f64,
    /// Without any reply for this long, the Falcon counts as gone.
    #[serde(default = "default_link_lost")]
    pub link_lost_after_ms: f64,
    /// How long the probe for a running firmware keeps asking before it
    /// decides none runs (libnifalcon waits about 1 s; fresh firmware can
    /// take that long to start).
    #[serde(default = "default_probe_window")]
    pub probe_window_ms: f64,
    /// Failed USB transfers, reads and writes alike, in a row without a
    /// reply (stalls, overflows, timeouts) after which
    /// the link counts as broken; fewer are counted and ridden out.
    #[serde(default = "default_read_error_streak")]
    pub read_error_streak: u32,
    /// Only for `device.kind = "falcon-emulator"`.
    #[serde(default)]
    pub emulator: EmulatorSection,
}

fn default_origin() -> [f64; 3] {
    DEFAULT_ORIGIN_M
}
fn default_encoder_offset() -> f64 {
    DEFAULT_ENCODER_OFFSET_DEG
}
fn default_firmware_attempts() -> u32 {
    20
}
fn default_homing_timeout() -> f64 {
    120.0
}
fn default_reply_timeout() -> f64 {
    0.9
}
fn default_link_lost() -> f64 {
    250.0
}
fn default_probe_window() -> f64 {
    1000.0
}
fn default_read_error_streak() -> u32 {
    20
}

impl Default for FalconSection {
    fn default() -> Self {
        FalconSection {
            firmware: None,
            origin_m: default_origin(),
            encoder_offset_deg: default_encoder_offset(),
            index: 0,
            firmware_attempts: default_firmware_attempts(),
            homing_timeout_s: default_homing_timeout(),
            reply_timeout_ms: default_reply_timeout(),
            link_lost_after_ms: default_link_lost(),
            probe_window_ms: default_probe_window(),
            read_error_streak: default_read_error_streak(),
            emulator: EmulatorSection::default(),
        }
    }
}

/// The emulated Falcon's state and faults.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EmulatorSection {
    /// The firmware is already running; when false the driver uploads
    /// `falcon.firmware` (any file of a known size will do for the emulator).
    pub firmware_loaded: bool,
    /// The first N uploads fail (a corrupted echo).
    pub upload_failures: u32,
    /// Per reply: the chance it is lost, garbled, or split in two reads.
    pub drop_rate: f64,
    pub garble_rate: f64,
    pub split_rate: f64,
    /// Pull the cable this many seconds after the loop starts.
    pub unplug_after_s: Option<f64>,
    /// USB reads fail (a stall, as a real bulk IN endpoint can) this many
    /// seconds after the loop starts, `read_errors` of them in a row.
    pub read_error_after_s: Option<f64>,
    pub read_errors: u32,
    /// The device stops answering for `stall_ms`, `stalls` times in a row,
    /// from this many seconds after the loop starts.
    pub stall_after_s: Option<f64>,
    pub stall_ms: f64,
    pub stalls: u32,
    /// A simulated hand homes the grip (pulls it out and pushes it in).
    pub auto_home: bool,
    /// Fresh firmware answers packets only this long after the upload ends.
    pub firmware_start_ms: f64,
    /// A stray byte reaches the host when the loader's baud changes, before
    /// the sync byte (a driver that does not purge reads it as the echo).
    pub stale_byte_before_sync: bool,
    /// The boot loader does not answer until the host has closed and
    /// reopened the device once.
    pub upload_needs_reopen: bool,
    /// The link's timing; absent, every byte is there at once.
    pub timing: Option<EmulatorTiming>,
    /// Motor N (0, 1 or 2, as the legs are numbered) is wired backwards:
    /// it turns against its command, so a force comes out bent or reversed
    /// (what `devices --self-test`'s force pulses are there to catch).
    pub reversed_motor: Option<u8>,
    /// The wall power fails this many seconds after the loop starts: USB
    /// and the encoders keep working, the motors do nothing.
    pub motor_power_lost_after_s: Option<f64>,
    /// Every reply comes this much later (a slow link: a hub, a loaded
    /// host); over about a tick, the lockstep exchange misses replies.
    pub slow_link_ms: f64,
    /// The firmware keeps applying the last force it was sent when
    /// commands stop (otherwise it stops its motors after
    /// 100 ms without one: what Novint's firmware does is not known).
    pub keeps_last_force: bool,
    /// The emulated encoders read this many degrees off: encoder count 0
    /// stands for `[falcon] encoder_offset_deg` + this, so the driver's arm
    /// angles are this much too low (what the self-test's calibration is
    /// there to catch).
    pub encoder_offset_error_deg: f64,
}

/// The emulated link's timing model (`[falcon.emulator.timing]`); the FTDI
/// latency timer is the one the driver sets (1 ms normal, 16 ms loading).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EmulatorTiming {
    /// One USB crossing between the host and the FTDI chip, each way.
    pub usb_latency_ms: f64,
    /// The firmware's time to answer a packet.
    pub firmware_ms: f64,
    /// Standard deviation of the host's extra delay in taking a reply.
    pub jitter_ms: f64,
    /// The chance that a reply is late, by up to `late_ms` more.
    pub late_rate: f64,
    pub late_ms: f64,
}

impl Default for EmulatorTiming {
    fn default() -> Self {
        EmulatorTiming {
            usb_latency_ms: 0.125,
            firmware_ms: 0.05,
            jitter_ms: 0.05,
            late_rate: 0.002,
            late_ms: 2.0,
        }
    }
}

impl Default for EmulatorSection {
    fn default() -> Self {
        EmulatorSection {
            firmware_loaded: true,
            upload_failures: 0,
            drop_rate: 0.0,
            garble_rate: 0.0,
            split_rate: 0.0,
            unplug_after_s: None,
            read_error_after_s: None,
            read_errors: 1,
            stall_after_s: None,
            stall_ms: 0.0,
            stalls: 1,
            auto_home: true,
            firmware_start_ms: 0.0,
            stale_byte_before_sync: false,
            upload_needs_reopen: false,
            timing: None,
            reversed_motor: None,
            motor_power_lost_after_s: None,
            slow_link_ms: 0.0,
            keeps_last_force: false,
            encoder_offset_error_deg: 0.0,
        }
    }
}

/// Faults the simulator injects (`[simulator.faults]`, `device.kind = "sim"`).
/// Times are seconds of servo-loop time: from the start of the session (the
/// loop starts just before the first scan's path; the thesis path reaches its
/// scan leg about 3.4 s in). Each fault happens once, at the first servo
/// tick at or after its time.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SimFaults {
    /// A read fails with an I/O error.
    pub read_error_after_s: Option<f64>,
    /// Reads stall for `stall_ms`, `stalls` in a row.
    pub stall_after_s: Option<f64>,
    pub stall_ms: f64,
    pub stalls: u32,
    /// A read returns a position of NaN.
    pub nan_after_s: Option<f64>,
    /// The device vanishes: every call fails from then on (as if unplugged).
    pub vanish_after_s: Option<f64>,
}

impl Default for SimFaults {
    fn default() -> Self {
        SimFaults {
            read_error_after_s: None,
            stall_after_s: None,
            stall_ms: 0.0,
            stalls: 1,
            nan_after_s: None,
            vanish_after_s: None,
        }
    }
}

impl SimFaults {
    /// Whether any fault is asked for.
    pub fn any(&self) -> bool {
        self.read_error_after_s.is_some()
            || self.stall_after_s.is_some()
            || self.nan_after_s.is_some()
            || self.vanish_after_s.is_some()
    }
}

/// A fault's time: positive seconds (`prefix.key`).
fn fault_time(prefix: &str, key: &str, v: Option<f64>) -> Result<(), Invalid> {
    if let Some(t) = v
        && !(t.is_finite() && t > 0.0)
    {
        return bad(
            format!("{prefix}.{key}"),
            format!("must be a positive number of seconds, got {t}"),
        );
    }
    Ok(())
}

/// A stall: its length and count, checked the same way for every device.
fn stall(prefix: &str, after: Option<f64>, ms: f64, count: u32) -> Result<(), Invalid> {
    fault_time(prefix, "stall_after_s", after)?;
    if !(ms.is_finite() && (0.0..=10_000.0).contains(&ms)) {
        return bad(
            format!("{prefix}.stall_ms"),
            format!("must be from 0 to 10000 ms, got {ms}"),
        );
    }
    if after.is_some() && ms == 0.0 {
        return bad(
            format!("{prefix}.stall_after_s"),
            "needs `stall_ms`, how long each stall lasts (e.g. 5.0 for five servo periods at 1 kHz)",
        );
    }
    if !(1..=100_000).contains(&count) {
        return bad(
            format!("{prefix}.stalls"),
            format!("must be from 1 to 100000, got {count}"),
        );
    }
    Ok(())
}

/// Check `[simulator.faults]` (called by `Profile::validate`).
pub fn validate_sim_faults(p: &Profile) -> Result<(), Invalid> {
    let f = &p.simulator.faults;
    let prefix = "simulator.faults";
    fault_time(prefix, "read_error_after_s", f.read_error_after_s)?;
    stall(prefix, f.stall_after_s, f.stall_ms, f.stalls)?;
    fault_time(prefix, "nan_after_s", f.nan_after_s)?;
    fault_time(prefix, "vanish_after_s", f.vanish_after_s)?;
    let kind = p.device.as_ref().map(|d| d.kind);
    if let Some(kind) = kind
        && f.any()
        && kind != DeviceKind::Sim
    {
        let first = [
            ("read_error_after_s", f.read_error_after_s),
            ("stall_after_s", f.stall_after_s),
            ("nan_after_s", f.nan_after_s),
            ("vanish_after_s", f.vanish_after_s),
        ]
        .into_iter()
        .find(|(_, v)| v.is_some())
        .map_or("read_error_after_s", |(k, _)| k);
        return bad(
            format!("{prefix}.{first}"),
            format!(
                "`[simulator.faults]` applies to device.kind = \"sim\" only, not {:?}; the emulated Falcon's faults go in `[falcon.emulator]` (read_error_after_s, stall_after_s, unplug_after_s, …)",
                kind.name()
            ),
        );
    }
    Ok(())
}

/// What a trigger button does.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum TriggerAction {
    /// Start a measurement (a scan).
    Start,
    /// Store the last measurement.
    Store,
    /// Abort the running measurement.
    Abort,
}

impl TriggerAction {
    pub fn name(self) -> &'static str {
        match self {
            TriggerAction::Start => "start",
            TriggerAction::Store => "store",
            TriggerAction::Abort => "abort",
        }
    }
}

/// A HID device (foot switch, button box) whose buttons trigger actions.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TriggerSpec {
    /// A name for messages (default: the ids).
    #[serde(default)]
    pub name: String,
    pub vendor_id: u16,
    pub product_id: u16,
    /// Bytes at the start of each input report before the button bits
    /// (e.g. 1 for devices that send a report id).
    #[serde(default)]
    pub report_offset: usize,
    /// Button N is bit N−1 of the report after the offset (bit 0 of the first byte is button 1).
    pub buttons: Vec<ButtonAction>,
}

impl TriggerSpec {
    pub fn display_name(&self) -> String {
        if self.name.is_empty() {
            format!("HID {:04x}:{:04x}", self.vendor_id, self.product_id)
        } else {
            format!(
                "{} ({:04x}:{:04x})",
                self.name, self.vendor_id, self.product_id
            )
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ButtonAction {
    pub button: u32,
    pub action: TriggerAction,
}

fn bad(key: impl Into<String>, reason: impl Into<String>) -> Result<(), Invalid> {
    Err(Invalid {
        key: key.into(),
        reason: reason.into(),
    })
}

fn rate(key: &str, v: f64) -> Result<(), Invalid> {
    if !(v.is_finite() && (0.0..0.5).contains(&v)) {
        return bad(key, format!("must be in [0, 0.5), got {v}"));
    }
    Ok(())
}

/// Check the hardware sections (called by `Profile::validate`).
pub fn validate(p: &Profile) -> Result<(), Invalid> {
    let kind = p.device.as_ref().map(|d| d.kind);
    let falcon_kind = matches!(kind, Some(DeviceKind::Falcon | DeviceKind::FalconEmulator));
    if kind == Some(DeviceKind::Falcon)
        && p.falcon
            .as_ref()
            .and_then(|f| f.firmware.as_ref())
            .is_none()
    {
        return bad(
            "device.kind",
            "kind = \"falcon\" needs `[falcon] firmware = \"…/nvent_firmware.bin\"`: the Falcon's firmware is Novint's and not shipped with hapticlab; take it from your libnifalcon source tree (firmware/) or your Novint driver install",
        );
    }
    if let Some(f) = &p.falcon {
        validate_falcon(f, p)?;
        validate_emulator(&f.emulator)?;
        if !f.emulator.firmware_loaded && f.firmware.is_none() {
            return bad(
                "falcon.emulator.firmware_loaded",
                "is false, so the driver must upload firmware: name the file in `[falcon] firmware`",
            );
        }
    }
    if falcon_kind && let Some(path) = &p.path {
        validate_reach(p, path)?;
    }
    validate_triggers(p)
}

/// The `[falcon]` section's own keys.
fn validate_falcon(f: &FalconSection, p: &Profile) -> Result<(), Invalid> {
    if f.origin_m.iter().any(|v| !v.is_finite()) {
        return bad("falcon.origin_m", "must be three numbers (metres)");
    }
    if !(f.encoder_offset_deg.is_finite() && f.encoder_offset_deg.abs() <= 180.0) {
        return bad("falcon.encoder_offset_deg", "must be within ±180°");
    }
    if f.firmware
        .as_ref()
        .is_some_and(|p| p.as_os_str().is_empty())
    {
        return bad("falcon.firmware", "must name the firmware file");
    }
    if !(1..=100).contains(&f.firmware_attempts) {
        return bad("falcon.firmware_attempts", "must be from 1 to 100");
    }
    if f.index > 15 {
        return bad("falcon.index", "must be from 0 to 15");
    }
    if !(f.homing_timeout_s.is_finite() && f.homing_timeout_s > 0.0 && f.homing_timeout_s <= 3600.0)
    {
        return bad("falcon.homing_timeout_s", "must be in (0, 3600] s");
    }
    if !(f.reply_timeout_ms.is_finite() && f.reply_timeout_ms > 0.0 && f.reply_timeout_ms <= 100.0)
    {
        return bad("falcon.reply_timeout_ms", "must be in (0, 100] ms");
    }
    // Without a [device] the servo rate is unknown: the thesis's 1 kHz.
    let period_ms = 1000.0 / p.device.as_ref().map_or(1000.0, |d| d.rate_hz);
    if !(f.link_lost_after_ms.is_finite()
        && f.link_lost_after_ms >= 2.0 * period_ms
        && f.link_lost_after_ms <= 10_000.0)
    {
        return bad(
            "falcon.link_lost_after_ms",
            format!(
                "must be from two servo periods ({:.1} ms) to 10000 ms",
                2.0 * period_ms
            ),
        );
    }
    if !(f.probe_window_ms.is_finite() && (100.0..=30_000.0).contains(&f.probe_window_ms)) {
        return bad(
            "falcon.probe_window_ms",
            format!(
                "must be from 100 to 30000 ms (1000, as libnifalcon waits, unless you know better), got {}",
                f.probe_window_ms
            ),
        );
    }
    if !(1..=10_000).contains(&f.read_error_streak) {
        return bad(
            "falcon.read_error_streak",
            format!("must be from 1 to 10000, got {}", f.read_error_streak),
        );
    }
    Ok(())
}

/// The emulator's state and faults (`[falcon.emulator]`).
fn validate_emulator(e: &EmulatorSection) -> Result<(), Invalid> {
    rate("falcon.emulator.drop_rate", e.drop_rate)?;
    rate("falcon.emulator.garble_rate", e.garble_rate)?;
    rate("falcon.emulator.split_rate", e.split_rate)?;
    if e.upload_failures > 100 {
        return bad("falcon.emulator.upload_failures", "must be at most 100");
    }
    if let Some(u) = e.unplug_after_s
        && !(u.is_finite() && u > 0.0)
    {
        return bad(
            "falcon.emulator.unplug_after_s",
            "must be a positive number of seconds",
        );
    }
    fault_time(
        "falcon.emulator",
        "read_error_after_s",
        e.read_error_after_s,
    )?;
    stall("falcon.emulator", e.stall_after_s, e.stall_ms, e.stalls)?;
    if !(1..=100_000).contains(&e.read_errors) {
        return bad(
            "falcon.emulator.read_errors",
            format!("must be from 1 to 100000, got {}", e.read_errors),
        );
    }
    if !(e.firmware_start_ms.is_finite() && (0.0..=10_000.0).contains(&e.firmware_start_ms)) {
        return bad(
            "falcon.emulator.firmware_start_ms",
            format!("must be from 0 to 10000 ms, got {}", e.firmware_start_ms),
        );
    }
    if let Some(t) = &e.timing {
        for (key, v, max) in [
            ("usb_latency_ms", t.usb_latency_ms, 100.0),
            ("firmware_ms", t.firmware_ms, 100.0),
            ("jitter_ms", t.jitter_ms, 100.0),
            ("late_ms", t.late_ms, 1000.0),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                return bad(
                    format!("falcon.emulator.timing.{key}"),
                    format!("must be from 0 to {max} ms, got {v}"),
                );
            }
        }
        rate("falcon.emulator.timing.late_rate", t.late_rate)?;
    }
    if let Some(m) = e.reversed_motor
        && m > 2
    {
        return bad(
            "falcon.emulator.reversed_motor",
            format!("must be 0, 1 or 2 (a leg's motor), got {m}"),
        );
    }
    fault_time(
        "falcon.emulator",
        "motor_power_lost_after_s",
        e.motor_power_lost_after_s,
    )?;
    if !(e.slow_link_ms.is_finite() && (0.0..=100.0).contains(&e.slow_link_ms)) {
        return bad(
            "falcon.emulator.slow_link_ms",
            format!(
                "must be from 0 to 100 ms (extra delay of every reply), got {}",
                e.slow_link_ms
            ),
        );
    }
    let err = e.encoder_offset_error_deg;
    if !(err.is_finite() && err.abs() <= 30.0) {
        return bad(
            "falcon.emulator.encoder_offset_error_deg",
            format!("must be within ±30° (how far the emulated encoders read off), got {err}"),
        );
    }
    Ok(())
}

/// Every waypoint inside the Falcon's workspace and clear of its arms' stops.
fn validate_reach(p: &Profile, path: &PathSpec) -> Result<(), Invalid> {
    let frame = falcon_reach::Frame {
        origin_m: p.falcon.as_ref().map_or(DEFAULT_ORIGIN_M, |f| f.origin_m),
    };
    for (i, w) in path.waypoints_m.iter().enumerate() {
        let q = frame.to_falcon(*w);
        if !falcon_reach::in_workspace(q) {
            return bad(
                format!("path.waypoints_m[{i}]"),
                format!(
                    "waypoint {} ({:.4}, {:.4}, {:.4}) m is outside the Falcon's workspace: in the Falcon's frame it is ({:.4}, {:.4}, {:.4}) m, which must lie in x, y ±0.05 m, z 0.075…0.175 m and within the legs' reach (move the waypoint or `[falcon] origin_m`)",
                    i + 1,
                    w[0],
                    w[1],
                    w[2],
                    q[0],
                    q[1],
                    q[2]
                ),
            );
        }
        if let Ok((leg, deg, clearance)) = falcon_reach::joint_clearance(q)
            && clearance < falcon_reach::JOINT_MARGIN_DEG
        {
            let (lo, hi) = falcon_reach::joint_limits_deg();
            return bad(
                format!("path.waypoints_m[{i}]"),
                format!(
                    "waypoint {} ({:.4}, {:.4}, {:.4}) m puts leg {leg}'s arm at {deg:.1}°, {clearance:.1}° from its stops ({lo:.1}° grip pushed in, {hi:.1}° pulled out; keep {:.0}° clear): move the waypoint inward or `[falcon] origin_m`",
                    i + 1,
                    w[0],
                    w[1],
                    w[2],
                    falcon_reach::JOINT_MARGIN_DEG
                ),
            );
        }
    }
    Ok(())
}

/// Each trigger maps buttons 1..=256, each once.
fn validate_triggers(p: &Profile) -> Result<(), Invalid> {
    for (i, t) in p.triggers.iter().enumerate() {
        let key = format!("triggers[{i}]");
        if t.buttons.is_empty() {
            return bad(
                format!("{key}.buttons"),
                "must map at least one button to an action",
            );
        }
        if t.report_offset > 64 {
            return bad(format!("{key}.report_offset"), "must be at most 64 bytes");
        }
        let mut seen = std::collections::BTreeSet::new();
        for b in &t.buttons {
            if !(1..=256).contains(&b.button) {
                return bad(
                    format!("{key}.buttons"),
                    format!("button {} must be from 1 to 256", b.button),
                );
            }
            if !seen.insert(b.button) {
                return bad(
                    format!("{key}.buttons"),
                    format!("button {} is mapped twice", b.button),
                );
            }
        }
    }
    Ok(())
}
