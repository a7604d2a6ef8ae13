//! The Novint Falcon driver: one [`FalconDevice`] over any [`FalconTransport`]
//! — USB ([`usb::UsbTransport`], `device.kind = "falcon"`) or the byte-level
//! emulator ([`emulator::EmulatedFalcon`], `"falcon-emulator"`).
//!
//! This module owns the lockstep exchange and the device's state: it probes
//! and loads the firmware ([`firmware`]), sends one 16-byte command per tick
//! and takes one reply ([`packet`]), turns encoder counts into a position
//! and forces into motor commands ([`kinematics`]), keeps the LEDs red until
//! the device is homed and blue after, applies no force until it is, drops
//! force components that would push the grip further out of its workspace,
//! and counts bad packets and missed replies. It never decides forces and
//! never allocates per tick.
//!
//! The exchange is pipelined: `command` writes the packet for this tick, and
//! the next `read` collects its reply (waiting at most `reply_timeout`). A
//! reply that does not come is counted as missed and the last position is
//! held; after two misses the packet is sent again; after `link_lost_after`
//! without any reply the device counts as gone. A failed USB transfer, IN or
//! OUT (a stall, an overflow, a timeout), counts as one that moved no bytes,
//! as libnifalcon treats it; only `read_error_streak` failures in a row
//! (IN and OUT in one streak, ended by a reply), or a vanished device, end
//! the session.
//!
//! Making the device safe sends a zero-force packet and waits (at most
//! [`SAFE_FLUSH`]) until it has left the host: closing the device cancels
//! queued writes, and the firmware may keep the last force it was sent.

pub mod emulator;
pub mod firmware;
pub mod kinematics;
pub mod packet;
pub mod self_test;
pub mod usb;

use std::time::{Duration, Instant};

use super::{DeviceError, HapticDevice, LinkStats, Reading};
use firmware::{FirmwareImage, FirmwareReport};
use kinematics::{ForwardSolver, Frame};
use packet::{CommandPacket, PacketReader, ReplyPacket};

/// The FTDI vendor requests the Falcon's USB-serial chip understands
/// (request type 0x40: vendor, device, host to device; index 0).
pub mod ftdi {
    pub const REQUEST_TYPE: u8 = 0x40;
    pub const PURGE: u8 = 0;
    pub const MODEM: u8 = 1;
    pub const FLOW: u8 = 2;
    pub const BAUD: u8 = 3;
    pub const LINE: u8 = 4;
    pub const LATENCY: u8 = 9;
    pub const PURGE_RX: u16 = 1;
    pub const PURGE_TX: u16 = 2;
    /// Modem control: high byte = which lines to set, low byte = their levels.
    pub const DTR_HIGH: u16 = 0x0101;
    pub const DTR_LOW: u16 = 0x0100;
    pub const RTS_HIGH: u16 = 0x0202;
    pub const RTS_LOW: u16 = 0x0200;
    pub const FLOW_NONE: u16 = 0;
    pub const LINE_8N1: u16 = 0x0008;
    /// Baud divisors on the FTDI's 3 MHz base: 9600 baud, ~140 kbaud, ~1.5 Mbaud.
    pub const BAUD_9600: u16 = 0x4138;
    pub const BAUD_LOADER: u16 = 0x0015;
    pub const BAUD_NORMAL: u16 = 0x0002;
    /// Vendor and product id of a Falcon.
    pub const VENDOR_ID: u16 = 0x0403;
    pub const PRODUCT_ID: u16 = 0xCB48;
}

/// Why a transport failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TransportError {
    #[error("the Falcon is disconnected: {0}")]
    Disconnected(String),
    #[error("USB I/O failed: {0}")]
    Io(String),
    /// A read that failed but may well succeed next time (a stalled or
    /// overflowing bulk IN transfer, a timeout): no bytes, counted.
    #[error("a USB read failed: {0}")]
    Transient(String),
}

/// A byte pipe to a Falcon's FTDI chip: vendor control requests, and bulk
/// bytes each way with the FTDI's modem-status bytes already stripped.
pub trait FalconTransport: Send {
    /// `"falcon"` or `"falcon-emulator"`: what recordings call the device.
    fn kind(&self) -> &'static str;
    /// An FTDI vendor request (see [`ftdi`]).
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError>;
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError>;
    /// Received bytes into `buf`, waiting up to `timeout` for the first;
    /// `Ok(0)` when none came in time.
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError>;
    /// The link's clock, which every read timeout is measured on: the wall
    /// clock for a real device, the emulator's own time for the emulator.
    fn now(&self) -> Instant {
        Instant::now()
    }
    /// Close the device and open it again (between firmware attempts, as
    /// libnifalcon does): pending transfers and buffered bytes are dropped.
    fn reopen(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
    /// Wait (at most `timeout`) until every byte written has left the host;
    /// an error when some has not (it may still be cancelled on closing).
    fn flush(&mut self, _timeout: Duration) -> Result<(), TransportError> {
        Ok(())
    }
    /// The motor commands the device itself is applying, where the
    /// transport can know it (the emulator); `None` for a real Falcon.
    fn applied_motor(&self) -> Option<[i16; 3]> {
        None
    }
    /// The servo loop's time (seconds): the emulator runs its physics up to
    /// it; a real device ignores it.
    fn advance_to(&mut self, _t_s: f64) {}
    /// An injected stall of the last exchange (the emulator only; see
    /// [`HapticDevice::take_stall`]).
    fn take_stall(&mut self) -> Option<Duration> {
        None
    }
}

/// How to drive a Falcon (from the profile's `[falcon]` section).
#[derive(Debug, Clone)]
pub struct FalconConfig {
    pub frame: Frame,
    pub encoder_offset_deg: f64,
    pub firmware: Option<FirmwareImage>,
    pub firmware_attempts: u32,
    /// How long a `read` waits for the reply to the last packet.
    pub reply_timeout: Duration,
    /// Consecutive missed replies after which the device counts as gone.
    pub link_lost_after: u32,
    /// How long the probe for a running firmware keeps asking.
    pub probe_window: Duration,
    /// Failed USB transfers (IN or OUT) in a row, with no reply between,
    /// after which the link counts as broken.
    pub read_error_streak: u32,
}

/// How long making the device safe waits for its zero-force packet to
/// leave: a bulk OUT of 16 bytes takes about a millisecond at full speed.
pub const SAFE_FLUSH: Duration = Duration::from_millis(20);

impl Default for FalconConfig {
    fn default() -> Self {
        FalconConfig {
            frame: Frame::default(),
            encoder_offset_deg: kinematics::DEFAULT_ENCODER_OFFSET_DEG,
            firmware: None,
            firmware_attempts: 20,
            reply_timeout: Duration::from_micros(900),
            link_lost_after: 250,
            probe_window: Duration::from_secs(1),
            read_error_streak: 20,
        }
    }
}

/// Counters for the lab (and the console's Device panel).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FalconStats {
    pub packets_sent: u64,
    pub replies: u64,
    pub missed_replies: u64,
    pub resends: u64,
    /// Garbled or partial packets thrown away while resynchronising.
    pub bad_packets: u64,
    pub discarded_bytes: u64,
    /// USB transfers (reads and writes) that failed and were ridden out.
    pub usb_errors: u64,
    /// Zero-force packets sent by `make_safe` and seen to leave the host,
    /// and those that did not leave within [`SAFE_FLUSH`] (or failed).
    pub safe_confirmed: u64,
    pub safe_unconfirmed: u64,
    /// Forward-kinematics Newton steps per solution: `fk_iterations[n]` counts solutions taking n.
    pub fk_iterations: [u64; 16],
    pub fk_restarts: u64,
    pub fk_failures: u64,
    /// Ticks on which a force component was dropped at the workspace's edge.
    pub workspace_clamps: u64,
    /// Ticks on which a motor command reached ±4095 and all three were
    /// scaled down together (the force's direction kept, its size not).
    pub saturated_ticks: u64,
    /// Replies received when homing completed.
    pub homed_after_replies: Option<u64>,
    pub firmware: FirmwareReport,
}

impl FalconStats {
    /// The largest number of Newton steps any solution took.
    pub fn fk_max_iterations(&self) -> usize {
        self.fk_iterations.iter().rposition(|&n| n > 0).unwrap_or(0)
    }
}

/// Round trips (packet written to its reply read, on the link's clock) in
/// buckets of `ROUND_TRIP_BUCKET_S`; the last bucket holds everything longer.
#[derive(Debug, Clone, PartialEq)]
pub struct RoundTrips {
    counts: Vec<u64>,
}

const ROUND_TRIP_BUCKET_S: f64 = 0.000_05;
const ROUND_TRIP_BUCKETS: usize = 400;

impl RoundTrips {
    fn new() -> RoundTrips {
        RoundTrips {
            counts: vec![0; ROUND_TRIP_BUCKETS],
        }
    }

    fn add(&mut self, d: Duration) {
        let i = (d.as_secs_f64() / ROUND_TRIP_BUCKET_S) as usize;
        self.counts[i.min(ROUND_TRIP_BUCKETS - 1)] += 1;
    }

    pub fn count(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// The round trip (seconds, the top of its bucket) that a share `q`
    /// (0..=1) of them took at most; `None` when there are none.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        let n = self.count();
        if n == 0 {
            return None;
        }
        let want = ((q.clamp(0.0, 1.0) * n as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= want {
                return Some((i + 1) as f64 * ROUND_TRIP_BUCKET_S);
            }
        }
        None
    }
}

/// The driver over a transport. See the module's documentation.
pub struct FalconDevice<T: FalconTransport> {
    transport: T,
    config: FalconConfig,
    reader: PacketReader,
    solver: ForwardSolver,
    rx: [u8; 64],
    motor: [i16; 3],
    awaiting: bool,
    missed_streak: u32,
    usb_error_streak: u32,
    homed: bool,
    /// LEDs shown instead of the homing colours (the self-test's cycle).
    leds: Option<u8>,
    buttons: u8,
    /// Profile frame.
    pos: [f64; 3],
    have_position: bool,
    gone: Option<String>,
    stats: FalconStats,
    /// When the packet awaiting its reply was written (the link's clock).
    sent_at: Instant,
    round_trips: RoundTrips,
    /// The motor arms' angles (rad) from the last homed reply's counts.
    arm_angles: Option<[f64; 3]>,
}

impl<T: FalconTransport> FalconDevice<T> {
    /// Bring a Falcon up: firmware probed (and uploaded if needed), normal
    /// mode, the first packet exchanged. `log` hears each step.
    pub fn open(
        mut transport: T,
        config: FalconConfig,
        log: &mut dyn FnMut(&str),
    ) -> Result<FalconDevice<T>, firmware::FirmwareError> {
        let report = firmware::ensure_loaded(
            &mut transport,
            config.firmware.as_ref(),
            &firmware::LoadOptions {
                attempts: config.firmware_attempts,
                probe_window: config.probe_window,
            },
            log,
        )?;
        firmware::set_normal_mode(&mut transport).map_err(|error| {
            firmware::FirmwareError::Link {
                during: "setting normal mode",
                error,
            }
        })?;
        let pos = config.frame.to_profile(kinematics::START_GUESS_M);
        Ok(FalconDevice {
            transport,
            config,
            reader: PacketReader::new(),
            solver: ForwardSolver::new(),
            rx: [0; 64],
            motor: [0; 3],
            awaiting: false,
            missed_streak: 0,
            usb_error_streak: 0,
            homed: false,
            leds: None,
            buttons: 0,
            pos,
            have_position: false,
            gone: None,
            stats: FalconStats {
                firmware: report,
                ..FalconStats::default()
            },
            sent_at: Instant::now(),
            round_trips: RoundTrips::new(),
            arm_angles: None,
        })
    }

    pub fn stats(&self) -> FalconStats {
        let mut s = self.stats.clone();
        s.bad_packets = self.reader.stats.bad_packets;
        s.discarded_bytes = self.reader.stats.discarded_bytes;
        s
    }

    /// The round trips measured since the last [`Self::reset_round_trips`].
    pub fn round_trips(&self) -> &RoundTrips {
        &self.round_trips
    }

    pub fn reset_round_trips(&mut self) {
        self.round_trips.counts.fill(0);
    }

    pub fn transport(&self) -> &T {
        &self.transport
    }

    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    pub fn is_homed(&self) -> bool {
        self.homed
    }

    /// The arm angle (degrees) the profile says encoder count 0 stands for
    /// (`[falcon] encoder_offset_deg`).
    pub fn encoder_offset_deg(&self) -> f64 {
        self.config.encoder_offset_deg
    }

    /// The motor arms' angles (degrees) from the last reply, once homed.
    pub fn arm_angles_deg(&self) -> Option<[f64; 3]> {
        self.arm_angles.map(|a| a.map(f64::to_degrees))
    }

    /// Command joint torques (N·m, each motor's own) instead of a force:
    /// for the self-test's calibration, which pushes each arm to its stop
    /// whatever the position says (so neither the Jacobian nor the
    /// workspace's edge, both taken from the encoders it is checking, come
    /// in). Nothing until homed, like any force; the caller bounds them.
    pub fn command_torques(&mut self, tau_nm: [f64; 3]) -> Result<(), DeviceError> {
        if let Some(m) = &self.gone {
            return Err(DeviceError::Disconnected(m.clone()));
        }
        self.motor = [0; 3];
        if self.homed && tau_nm.iter().all(|t| t.is_finite()) {
            let (motor, saturated) = kinematics::motor_commands_scaled(tau_nm);
            self.motor = motor;
            self.stats.saturated_ticks += u64::from(saturated);
        }
        if !self.awaiting {
            self.send()?;
        }
        Ok(())
    }

    /// Show these LEDs (`packet::LED_*`) from the next packet on, or the
    /// homing colours again (red until homed, blue after) with `None`.
    pub fn show_leds(&mut self, leds: Option<u8>) {
        self.leds = leds;
    }

    /// The motor commands the last packet carried (or will carry).
    pub fn motor_commands(&self) -> [i16; 3] {
        self.motor
    }

    fn flags(&self) -> u8 {
        let homing_colour = if self.homed {
            packet::LED_BLUE
        } else {
            packet::LED_RED
        };
        packet::FLAG_HOMING | self.leds.unwrap_or(homing_colour)
    }

    fn lost(&mut self, e: TransportError) -> DeviceError {
        match e {
            TransportError::Disconnected(m) => {
                let m = format!("the Falcon was unplugged or lost power ({m})");
                self.gone = Some(m.clone());
                DeviceError::Disconnected(m)
            }
            TransportError::Io(m) | TransportError::Transient(m) => DeviceError::Io(m),
        }
    }

    fn send(&mut self) -> Result<(), DeviceError> {
        let p = packet::encode_command(&CommandPacket {
            motor: self.motor,
            flags: self.flags(),
        });
        match self.transport.write(&p) {
            Ok(()) => {
                self.awaiting = true;
                self.stats.packets_sent += 1;
                self.sent_at = self.transport.now();
                Ok(())
            }
            // Not sent: the next tick sends again; only a streak breaks the link.
            Err(TransportError::Transient(m)) => self.usb_failed(&m, "write"),
            Err(e) => Err(self.lost(e)),
        }
    }

    /// One failed USB transfer ridden out; the link is broken after
    /// `read_error_streak` of them (IN and OUT alike) without a reply.
    fn usb_failed(&mut self, m: &str, what: &str) -> Result<(), DeviceError> {
        self.stats.usb_errors += 1;
        self.usb_error_streak += 1;
        if self.usb_error_streak >= self.config.read_error_streak {
            return Err(DeviceError::Io(format!(
                "{} USB transfers in a row failed without a reply (the last, a {what}: {m}): the link is broken; unplug the Falcon, plug it in directly (not through a hub) and start again",
                self.usb_error_streak
            )));
        }
        Ok(())
    }

    /// The newest reply that arrives within the timeout.
    fn collect_reply(&mut self) -> Result<Option<ReplyPacket>, DeviceError> {
        let mut newest = None;
        let deadline = self.transport.now() + self.config.reply_timeout;
        loop {
            while let Some(p) = self.reader.next_packet() {
                if let Some(r) = packet::decode_reply(&p) {
                    newest = Some(r);
                }
            }
            if newest.is_some() {
                return Ok(newest);
            }
            let left = deadline.saturating_duration_since(self.transport.now());
            let n = match self.transport.read(&mut self.rx, left) {
                Ok(n) => n,
                Err(TransportError::Transient(m)) => {
                    // No bytes this time; only a streak breaks the link.
                    self.usb_failed(&m, "read")?;
                    0
                }
                Err(e) => return Err(self.lost(e)),
            };
            if n == 0 {
                return Ok(None);
            }
            let (rx, reader) = (&self.rx, &mut self.reader);
            reader.push(&rx[..n]);
        }
    }

    fn take_reply(&mut self, r: ReplyPacket) {
        self.stats.replies += 1;
        if self.awaiting {
            let rt = self.transport.now().saturating_duration_since(self.sent_at);
            self.round_trips.add(rt);
        }
        self.awaiting = false;
        self.missed_streak = 0;
        self.usb_error_streak = 0;
        self.buttons = r.buttons;
        let homed = r.is_homed();
        if homed && !self.homed {
            // The counts jump to the absolute frame when homing completes.
            self.solver.reset();
            self.stats.homed_after_replies = Some(self.stats.replies);
        }
        self.homed = homed;
        let off = self.config.encoder_offset_deg;
        let theta = r.encoder.map(|c| kinematics::angle_of_count(c, off));
        // Before homing the counts are relative: no angle to speak of.
        self.arm_angles = homed.then_some(theta);
        match self.solver.solve(theta) {
            Ok(s) => {
                let n = (s.iterations as usize).min(self.stats.fk_iterations.len() - 1);
                self.stats.fk_iterations[n] += 1;
                if s.restarted {
                    self.stats.fk_restarts += 1;
                }
                self.pos = self.config.frame.to_profile(s.p);
                self.have_position = true;
            }
            // Before homing the counts are relative and may name no
            // reachable point: hold the last position.
            Err(_) => self.stats.fk_failures += 1,
        }
    }
}

impl<T: FalconTransport> HapticDevice for FalconDevice<T> {
    fn kind(&self) -> &'static str {
        self.transport.kind()
    }

    fn read(&mut self, t_s: f64) -> Result<Reading, DeviceError> {
        if let Some(m) = &self.gone {
            return Err(DeviceError::Disconnected(m.clone()));
        }
        self.transport.advance_to(t_s);
        if !self.awaiting {
            self.send()?;
        }
        match self.collect_reply()? {
            Some(r) => self.take_reply(r),
            None => {
                self.stats.missed_replies += 1;
                self.missed_streak += 1;
                if self.missed_streak >= self.config.link_lost_after {
                    let m = format!(
                        "no reply from the Falcon in {} packets: the link is lost (unplugged, powered off, or a hub in the way)",
                        self.missed_streak
                    );
                    self.gone = Some(m.clone());
                    return Err(DeviceError::Disconnected(m));
                }
                if self.missed_streak.is_multiple_of(2) {
                    // Lost rather than late: send again.
                    self.awaiting = false;
                    self.stats.resends += 1;
                }
            }
        }
        Ok(Reading {
            pos_m: self.pos,
            buttons: self.buttons,
            homed: self.homed && self.have_position,
        })
    }

    fn command(&mut self, force_n: [f64; 3]) -> Result<(), DeviceError> {
        if let Some(m) = &self.gone {
            return Err(DeviceError::Disconnected(m.clone()));
        }
        self.motor = [0; 3];
        if self.homed && self.have_position && force_n.iter().all(|f| f.is_finite()) {
            let p = self.config.frame.to_falcon(self.pos);
            let mut f = force_n;
            // Never push the grip further out of its workspace.
            for a in 0..3 {
                let out_low = p[a] < kinematics::FALCON_MIN_M[a] && f[a] < 0.0;
                let out_high = p[a] > kinematics::FALCON_MAX_M[a] && f[a] > 0.0;
                if out_low || out_high {
                    f[a] = 0.0;
                    self.stats.workspace_clamps += 1;
                }
            }
            if let Some(j) = self.solver.jacobian() {
                let (motor, saturated) =
                    kinematics::motor_commands_scaled(kinematics::torques(j, f));
                self.motor = motor;
                self.stats.saturated_ticks += u64::from(saturated);
            }
        }
        if !self.awaiting {
            self.send()?;
        }
        Ok(())
    }

    fn make_safe(&mut self) {
        self.motor = [0; 3];
        if self.gone.is_some() {
            return;
        }
        // Outside the lockstep: a zero packet now, and wait until it has
        // left (a write still queued when the device closes is cancelled).
        let p = packet::encode_command(&CommandPacket {
            motor: [0; 3],
            flags: self.flags(),
        });
        let sent = self.transport.write(&p).is_ok();
        if sent {
            self.awaiting = true;
            self.stats.packets_sent += 1;
        }
        if sent && self.transport.flush(SAFE_FLUSH).is_ok() {
            self.stats.safe_confirmed += 1;
        } else {
            self.stats.safe_unconfirmed += 1;
        }
    }

    fn take_stall(&mut self) -> Option<Duration> {
        self.transport.take_stall()
    }

    fn link_stats(&self) -> Option<LinkStats> {
        Some(LinkStats {
            packets: self.stats.packets_sent,
            replies: self.stats.replies,
            bad_packets: self.reader.stats.bad_packets,
            missed_replies: self.stats.missed_replies,
            usb_errors: self.stats.usb_errors,
            saturated_ticks: self.stats.saturated_ticks,
        })
    }
}

impl<T: FalconTransport> Drop for FalconDevice<T> {
    fn drop(&mut self) {
        self.make_safe();
    }
}

/// Why a Falcon could not be opened: the user's input (exit code 2) or the
/// device (exit code 1).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OpenError {
    #[error("{0}")]
    BadInput(String),
    #[error("{0}")]
    Device(String),
}

/// The driver's settings from a profile; the firmware file (if named) is
/// read and checked here, before any USB traffic.
pub fn config_from_profile(lp: &crate::profile::LoadedProfile) -> Result<FalconConfig, OpenError> {
    let section = lp.profile.falcon.clone().unwrap_or_default();
    let firmware = match &section.firmware {
        Some(path) => Some(
            firmware::load_image(&lp.resolve(path))
                .map_err(|e| OpenError::BadInput(e.to_string()))?,
        ),
        None => None,
    };
    let rig = lp.rig().map_err(|e| OpenError::BadInput(e.to_string()))?;
    let period_ms = 1000.0 / rig.device.rate_hz;
    Ok(FalconConfig {
        frame: Frame {
            origin_m: section.origin_m,
        },
        encoder_offset_deg: section.encoder_offset_deg,
        firmware,
        firmware_attempts: section.firmware_attempts,
        reply_timeout: Duration::from_secs_f64(section.reply_timeout_ms / 1000.0),
        link_lost_after: (section.link_lost_after_ms / period_ms).ceil().max(2.0) as u32,
        probe_window: Duration::from_secs_f64(section.probe_window_ms / 1000.0),
        read_error_streak: section.read_error_streak,
    })
}

fn firmware_failure(e: firmware::FirmwareError) -> OpenError {
    match e {
        firmware::FirmwareError::File(_) | firmware::FirmwareError::NoImage => {
            OpenError::BadInput(e.to_string())
        }
        other => OpenError::Device(other.to_string()),
    }
}

/// The emulated Falcon of a profile, stroking `texture` (free air when
/// `None`), its physics seeded with `seed`.
pub fn open_emulated(
    lp: &crate::profile::LoadedProfile,
    texture: Option<&str>,
    seed: u64,
    log: &mut dyn FnMut(&str),
) -> Result<FalconDevice<emulator::EmulatedFalcon>, OpenError> {
    let config = config_from_profile(lp)?;
    let section = lp.profile.falcon.clone().unwrap_or_default();
    let e = &section.emulator;
    let sim = super::sim::SimDevice::new(&lp.profile, &lp.base_dir, texture, seed)
        .map_err(|e| OpenError::BadInput(e.to_string()))?
        .without_faults();
    let emu = emulator::EmulatedFalcon::new(
        sim,
        emulator::EmulatorConfig {
            device: e.clone(),
            leading_zero: seed % 2 == 1,
            seed,
            frame: config.frame,
            encoder_offset_deg: config.encoder_offset_deg,
            position_noise_m: lp.profile.simulator.position_noise_m,
        },
    );
    FalconDevice::open(emu, config, log).map_err(firmware_failure)
}

/// The real Falcon of a profile, over USB.
pub fn open_usb(
    lp: &crate::profile::LoadedProfile,
    log: &mut dyn FnMut(&str),
) -> Result<FalconDevice<usb::UsbTransport>, OpenError> {
    let config = config_from_profile(lp)?;
    let index = lp.profile.falcon.as_ref().map_or(0, |f| f.index);
    let transport = usb::UsbTransport::open(index).map_err(|e| OpenError::Device(e.to_string()))?;
    log(&format!("opened {}", transport.describe()));
    FalconDevice::open(transport, config, log).map_err(firmware_failure)
}

#[cfg(test)]
mod tests;
