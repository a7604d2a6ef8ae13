//! An emulated Falcon at the byte level, behind [`FalconTransport`]: with it
//! every layer of the real driver runs except USB itself.
//!
//! It owns a model of what the host would find at the end of the cable: the
//! FTDI chip's settings (baud divisor, DTR/RTS, purges), a boot loader that
//! answers the handshake, echoes the sync byte and the image, and starts the
//! firmware when the host switches to normal mode after a whole upload; and
//! the firmware's 16-byte exchange. Behind the exchange runs the simulator's
//! physics ([`SimDevice`], in the profile frame): replies carry encoder
//! counts from the true position through the inverse kinematics (relative
//! counts until homed), motor commands become forces through the Jacobian,
//! and the homing flags rise once the grip has been pulled fully out and
//! pushed fully in — by a simulated hand when `auto_home` is on.
//!
//! Faults on demand: replies dropped, garbled or split in two, uploads that
//! fail (a corrupted echo) a set number of times, unplugging at a given
//! time (every call then fails as a vanished USB device does, and the motors
//! stop), a USB read that fails at a given time, and exchanges that stall
//! (handed to the servo loop's clock through `take_stall`). It never sleeps:
//! a read that finds nothing returns at once, so the same emulator runs in
//! virtual and in real time.

use std::collections::VecDeque;
use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::kinematics::{self, Frame};
use super::packet::{self, PacketReader, ReplyPacket};
use super::{FalconTransport, TransportError, ftdi};
use crate::device::HapticDevice;
use crate::device::sim::SimDevice;
use crate::profile::hardware::EmulatorSection;
use crate::profile::{WORKSPACE_MAX_M, WORKSPACE_MIN_M};

/// Falcon z (m) the grip must pass, pulled out, then pushed in, to home:
/// each arm homes when its angle passes the angle it has there on the axis.
pub const HOME_OUT_Z_M: f64 = 0.155;
pub const HOME_IN_Z_M: f64 = 0.095;
/// The simulated hand that homes the device: a spring towards each end.
const HAND_STIFFNESS: f64 = 60.0;
const HAND_DAMPING: f64 = 5.0;
const HAND_MAX_N: f64 = 1.0;
/// Once homed, the hand brings the grip this close to the middle of the
/// workspace, this slowly, and lets go (or sooner, when the motors push).
const HAND_LET_GO_M: f64 = 0.005;
const HAND_LET_GO_M_PER_S: f64 = 0.01;
/// The middle of the workspace (profile frame).
const WORKSPACE_CENTRE_M: [f64; 3] = [
    (WORKSPACE_MIN_M[0] + WORKSPACE_MAX_M[0]) / 2.0,
    (WORKSPACE_MIN_M[1] + WORKSPACE_MAX_M[1]) / 2.0,
    (WORKSPACE_MIN_M[2] + WORKSPACE_MAX_M[2]) / 2.0,
];
/// An arm's motor angle (rad) with the grip on the Falcon's axis at `z_m`.
fn arm_angle_on_axis(z_m: f64) -> f64 {
    kinematics::inverse([0.0, 0.0, z_m]).map_or(0.0, |a| a.theta1[0])
}

/// Beyond the arms' reach the mechanism holds the grip back, stiffly.
const REACH_STIFFNESS_N_PER_M: f64 = 20_000.0;
const REACH_DAMPING_N_S_PER_M: f64 = 20.0;
/// Uploads shorter than this never start a firmware.
const MIN_IMAGE: usize = 1024;

/// What to emulate (from the profile's `[falcon.emulator]`).
#[derive(Debug, Clone, PartialEq)]
pub struct EmulatorConfig {
    /// The state and faults the profile's `[falcon.emulator]` asks for.
    pub device: EmulatorSection,
    /// The boot loader answers the handshake with a leading 0x00.
    pub leading_zero: bool,
    pub seed: u64,
    pub frame: Frame,
    pub encoder_offset_deg: f64,
    /// Standard deviation of the grip's position jitter, metres.
    pub position_noise_m: f64,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        EmulatorConfig {
            device: EmulatorSection::default(),
            leading_zero: false,
            seed: 1,
            frame: Frame::default(),
            encoder_offset_deg: kinematics::DEFAULT_ENCODER_OFFSET_DEG,
            position_noise_m: 0.0,
        }
    }
}

/// What the emulator saw and did, for tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmulatorCounters {
    pub handshakes: u64,
    pub uploads_started: u32,
    pub uploads_completed: u32,
    pub commands: u64,
    pub bad_commands: u64,
    pub replies: u64,
    pub dropped: u64,
    pub garbled: u64,
    pub split: u64,
    /// The largest motor command seen (absolute).
    pub max_motor: i16,
    /// Steps the grip spent beyond the arms' reach (held back there).
    pub unreachable: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Boot {
    /// Waiting for the handshake.
    Idle,
    /// Handshake answered; waiting for the sync byte at the loader baud.
    Handshaken,
    /// Echoing the image.
    Loading {
        received: usize,
        corrupt_at: Option<usize>,
        corrupted: bool,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Firmware {
    Boot(Boot),
    Running,
}

pub struct EmulatedFalcon {
    sim: SimDevice,
    cfg: EmulatorConfig,
    rng: ChaCha8Rng,
    noise: Normal<f64>,
    baud: u16,
    dtr: bool,
    fw: Firmware,
    boot_tail: [u8; 3],
    from_host: PacketReader,
    to_host: VecDeque<u8>,
    replies_due: u32,
    motor: [i16; 3],
    flags: u8,
    /// Per-axis homed flags (bit i: arm i), as the firmware reports them.
    homed_axes: u8,
    /// Which arms have swung past their homing mark pulled out.
    seen_out: [bool; 3],
    /// Each arm's motor angle (rad) with the grip on the axis at the
    /// pulled-out and the pushed-in homing marks.
    home_out_rad: f64,
    home_in_rad: f64,
    /// The simulated hand has let go of the grip after homing it.
    released: bool,
    /// The last grip position (profile frame) the arms could reach.
    reachable: [f64; 3],
    offsets: [i16; 3],
    last_counts: [i16; 3],
    t: f64,
    unplugged: bool,
    read_error_done: bool,
    stalls_done: u32,
    stall: Option<Duration>,
    pub counters: EmulatorCounters,
}

impl EmulatedFalcon {
    /// An emulated Falcon whose grip moves by `sim`'s physics.
    pub fn new(sim: SimDevice, cfg: EmulatorConfig) -> EmulatedFalcon {
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ 0xFA1C_0000);
        // Until homed the counts are relative to wherever the arms were at power-up.
        let offsets = [0; 3].map(|_: i16| rng.random_range(-200..=200));
        let noise = Normal::new(0.0, cfg.position_noise_m.max(0.0)).expect("a finite sigma");
        EmulatedFalcon {
            fw: if cfg.device.firmware_loaded {
                Firmware::Running
            } else {
                Firmware::Boot(Boot::Idle)
            },
            sim,
            rng,
            noise,
            baud: ftdi::BAUD_9600,
            dtr: false,
            boot_tail: [0; 3],
            from_host: PacketReader::new(),
            to_host: VecDeque::with_capacity(4096),
            replies_due: 0,
            motor: [0; 3],
            flags: 0,
            homed_axes: 0,
            seen_out: [false; 3],
            home_out_rad: arm_angle_on_axis(HOME_OUT_Z_M),
            home_in_rad: arm_angle_on_axis(HOME_IN_Z_M),
            released: false,
            reachable: WORKSPACE_CENTRE_M,
            offsets,
            last_counts: [0; 3],
            t: 0.0,
            unplugged: false,
            read_error_done: false,
            stalls_done: 0,
            stall: None,
            counters: EmulatorCounters::default(),
            cfg,
        }
    }

    pub fn sim(&self) -> &SimDevice {
        &self.sim
    }

    pub fn firmware_running(&self) -> bool {
        self.fw == Firmware::Running
    }

    pub fn is_homed(&self) -> bool {
        self.homed_axes == packet::ALL_HOMED
    }

    /// The motor commands the firmware is applying (zero once made safe or unplugged).
    pub fn motor(&self) -> [i16; 3] {
        self.motor
    }

    /// Pull the cable now.
    pub fn unplug(&mut self) {
        self.unplugged = true;
        self.motor = [0; 3];
        self.sim.make_safe();
    }

    fn check(&self) -> Result<(), TransportError> {
        if self.unplugged {
            Err(TransportError::Disconnected(format!(
                "the emulated Falcon was unplugged at {:.3} s",
                self.t
            )))
        } else {
            Ok(())
        }
    }

    /// The true grip position in the Falcon's frame.
    fn falcon_position(&self) -> [f64; 3] {
        self.cfg.frame.to_falcon(self.sim.true_position())
    }

    fn reset_to_boot_loader(&mut self) {
        self.fw = Firmware::Boot(Boot::Idle);
        self.homed_axes = 0;
        self.seen_out = [false; 3];
        self.released = false;
        self.motor = [0; 3];
        self.sim.make_safe();
        self.replies_due = 0;
        self.from_host.clear();
    }

    fn boot_byte(&mut self, b: u8) {
        let Firmware::Boot(stage) = self.fw else {
            return;
        };
        match stage {
            Boot::Idle => {
                self.boot_tail = [self.boot_tail[1], self.boot_tail[2], b];
                if self.baud == ftdi::BAUD_9600 && self.dtr && self.boot_tail == [0x0A, 0x43, 0x0D]
                {
                    self.counters.handshakes += 1;
                    if self.cfg.leading_zero {
                        self.to_host.push_back(0x00);
                    }
                    self.to_host.extend([0x0A, 0x44, 0x2C, 0x0D]);
                    self.fw = Firmware::Boot(Boot::Handshaken);
                }
            }
            Boot::Handshaken => {
                if b == 0x41 && self.baud == ftdi::BAUD_LOADER && !self.dtr {
                    self.to_host.push_back(0x41);
                    self.counters.uploads_started += 1;
                    let fail = self.counters.uploads_started <= self.cfg.device.upload_failures;
                    let corrupt_at = fail.then(|| 62 * 40 + self.rng.random_range(0..62));
                    self.fw = Firmware::Boot(Boot::Loading {
                        received: 0,
                        corrupt_at,
                        corrupted: false,
                    });
                }
            }
            Boot::Loading {
                received,
                corrupt_at,
                corrupted,
            } => {
                if self.baud != ftdi::BAUD_LOADER {
                    return;
                }
                let bad = corrupt_at == Some(received);
                self.to_host.push_back(if bad { b ^ 0x5A } else { b });
                self.fw = Firmware::Boot(Boot::Loading {
                    received: received + 1,
                    corrupt_at,
                    corrupted: corrupted || bad,
                });
            }
        }
    }

    fn apply_command(&mut self, c: packet::CommandPacket) {
        self.counters.commands += 1;
        self.motor = c.motor;
        self.flags = c.flags;
        let m = c
            .motor
            .iter()
            .map(|v| v.saturating_abs())
            .max()
            .unwrap_or(0);
        self.counters.max_motor = self.counters.max_motor.max(m);
        self.replies_due += 1;
        // Torques through the Jacobian at the true position.
        let tau = kinematics::torques_of_commands(c.motor);
        let force = kinematics::inverse(self.falcon_position())
            .and_then(|a| kinematics::jacobian(&a))
            .and_then(|j| kinematics::force_of_torques(&j, tau))
            .unwrap_or([0.0; 3]);
        // Same axes in both frames.
        let _ = self.sim.command(force);
    }

    fn reply(&mut self) -> ReplyPacket {
        let p = self.sim.true_position();
        let noisy = p.map(|v| v + self.noise.sample(&mut self.rng));
        if let Ok(a) = kinematics::inverse(self.cfg.frame.to_falcon(noisy)) {
            self.last_counts = a
                .theta1
                .map(|t| kinematics::count_of_angle(t, self.cfg.encoder_offset_deg));
        }
        let mut encoder = self.last_counts;
        // Each arm's count is relative to where it powered up until that arm
        // is homed; then it jumps to the absolute angle.
        for (i, (e, o)) in encoder.iter_mut().zip(self.offsets).enumerate() {
            if self.homed_axes & (1 << i) == 0 {
                *e = e.wrapping_add(o);
            }
        }
        ReplyPacket {
            encoder,
            buttons: 0,
            homed: self.homed_axes,
        }
    }

    /// The forces on the grip from outside the motors: the simulated hand
    /// (homing it, then bringing it back to the middle of the workspace and
    /// letting go, as a user does) and the arms' reach, which stops the grip
    /// like an end stop where the simulator's box would let it wander off.
    fn outside_forces(&mut self) {
        let homing = self.fw == Firmware::Running && self.flags & packet::FLAG_HOMING != 0;
        if homing
            && !self.is_homed()
            && let Ok(a) = kinematics::inverse(self.falcon_position())
        {
            // Each arm homes on its own: swung past its outer mark, then
            // back past its inner one.
            let out = (self.home_out_rad - self.home_in_rad).signum();
            for (i, &t) in a.theta1.iter().enumerate() {
                if (t - self.home_out_rad) * out >= 0.0 {
                    self.seen_out[i] = true;
                }
                if self.seen_out[i] && (t - self.home_in_rad) * out <= 0.0 {
                    self.homed_axes |= 1 << i;
                }
            }
        }
        let homed = self.is_homed();
        let p = self.sim.true_position();
        let v = self.sim.true_velocity();
        let target = if !self.cfg.device.auto_home || self.released {
            None
        } else if !homed {
            // Out past the homing marks, then in past the others.
            homing.then(|| {
                let z = if self.seen_out.iter().all(|&s| s) {
                    HOME_IN_Z_M - 0.004
                } else {
                    HOME_OUT_Z_M + 0.004
                };
                self.cfg.frame.to_profile([0.0, 0.0, z])
            })
        } else {
            let c = WORKSPACE_CENTRE_M;
            let off = (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt();
            let speed = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            // Or as soon as the motors take over.
            let driven = self.motor.iter().any(|&m| m != 0);
            if driven || (off < HAND_LET_GO_M && speed < HAND_LET_GO_M_PER_S) {
                self.released = true;
                None
            } else {
                Some(c)
            }
        };
        let mut hand = [0.0; 3];
        if let Some(target) = target {
            for a in 0..3 {
                hand[a] = HAND_STIFFNESS * (target[a] - p[a]) - HAND_DAMPING * v[a];
            }
            let n = (hand[0] * hand[0] + hand[1] * hand[1] + hand[2] * hand[2]).sqrt();
            if n > HAND_MAX_N {
                hand = hand.map(|h| h * HAND_MAX_N / n);
            }
        }
        if kinematics::inverse(self.cfg.frame.to_falcon(p)).is_ok() {
            self.reachable = p;
        } else {
            self.counters.unreachable += 1;
            for a in 0..3 {
                hand[a] += REACH_STIFFNESS_N_PER_M * (self.reachable[a] - p[a])
                    - REACH_DAMPING_N_S_PER_M * v[a];
            }
        }
        self.sim.set_hand_force(hand);
    }
}

impl FalconTransport for EmulatedFalcon {
    fn kind(&self) -> &'static str {
        "falcon-emulator"
    }

    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.check()?;
        match request {
            ftdi::PURGE => {
                if value & ftdi::PURGE_RX != 0 {
                    self.to_host.clear();
                }
                if value & ftdi::PURGE_TX != 0 {
                    self.from_host.clear();
                }
            }
            ftdi::BAUD => {
                self.baud = value;
                if value == ftdi::BAUD_NORMAL
                    && let Firmware::Boot(Boot::Loading {
                        received,
                        corrupted,
                        ..
                    }) = self.fw
                {
                    if received >= MIN_IMAGE && !corrupted {
                        self.fw = Firmware::Running;
                        self.counters.uploads_completed += 1;
                    } else {
                        self.fw = Firmware::Boot(Boot::Idle);
                    }
                }
            }
            ftdi::MODEM => {
                let (mask, level) = ((value >> 8) as u8, value as u8);
                if mask & 1 != 0 {
                    let dtr = level & 1 != 0;
                    // A rising DTR resets the microcontroller into its boot loader.
                    if dtr && !self.dtr {
                        self.reset_to_boot_loader();
                    }
                    self.dtr = dtr;
                }
            }
            ftdi::FLOW | ftdi::LINE | ftdi::LATENCY => {}
            other => {
                return Err(TransportError::Io(format!(
                    "the emulated FTDI chip does not know request {other}"
                )));
            }
        }
        Ok(())
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.check()?;
        match self.fw {
            Firmware::Boot(_) => {
                for &b in bytes {
                    self.boot_byte(b);
                }
            }
            Firmware::Running => {
                if self.baud != ftdi::BAUD_NORMAL {
                    return Ok(());
                }
                self.from_host.push(bytes);
                while let Some(p) = self.from_host.next_packet() {
                    match packet::decode_command(&p) {
                        Some(c) => self.apply_command(c),
                        None => self.counters.bad_commands += 1,
                    }
                }
            }
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> Result<usize, TransportError> {
        self.check()?;
        if !self.read_error_done
            && self
                .cfg
                .device
                .read_error_after_s
                .is_some_and(|a| self.t >= a)
        {
            self.read_error_done = true;
            return Err(TransportError::Io(format!(
                "the emulated Falcon's USB read failed at {:.3} s, as `[falcon.emulator] read_error_after_s` asks (on a real one: check the USB cable and hub)",
                self.t
            )));
        }
        while self.replies_due > 0 {
            self.replies_due -= 1;
            let r = self.reply();
            if self
                .rng
                .random_bool(self.cfg.device.drop_rate.clamp(0.0, 1.0))
            {
                self.counters.dropped += 1;
                continue;
            }
            let mut bytes = packet::encode_reply(&r);
            if self
                .rng
                .random_bool(self.cfg.device.garble_rate.clamp(0.0, 1.0))
            {
                let i = self.rng.random_range(1..15);
                bytes[i] = b'z';
                self.counters.garbled += 1;
            }
            self.counters.replies += 1;
            self.to_host.extend(bytes);
        }
        let mut n = buf.len().min(self.to_host.len());
        if n > 1
            && self
                .rng
                .random_bool(self.cfg.device.split_rate.clamp(0.0, 1.0))
        {
            n = self.rng.random_range(1..n);
            self.counters.split += 1;
        }
        for (slot, b) in buf.iter_mut().zip(self.to_host.drain(..n)) {
            *slot = b;
        }
        Ok(n)
    }

    fn advance_to(&mut self, t_s: f64) {
        if !(t_s.is_finite() && t_s > self.t) {
            return;
        }
        self.t = t_s;
        if !self.unplugged && self.cfg.device.unplug_after_s.is_some_and(|u| t_s >= u) {
            self.unplug();
        }
        if self.stalls_done < self.cfg.device.stalls
            && self.cfg.device.stall_after_s.is_some_and(|a| t_s >= a)
        {
            self.stalls_done += 1;
            self.stall = Some(Duration::from_secs_f64(self.cfg.device.stall_ms / 1000.0));
        }
        if !self.unplugged {
            self.outside_forces();
        } else {
            self.sim.set_hand_force([0.0; 3]);
        }
        // The physics runs whether or not anyone listens.
        let _ = self.sim.read(t_s);
    }

    fn take_stall(&mut self) -> Option<Duration> {
        self.stall.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::Reading;
    use crate::device::falcon::{FalconConfig, FalconDevice, firmware};
    use crate::profile::LoadedProfile;
    use std::path::Path;

    fn emulator(cfg: EmulatorConfig) -> EmulatedFalcon {
        let lp = LoadedProfile::thesis();
        let sim = SimDevice::new(&lp.profile, Path::new("."), None, 3).unwrap();
        EmulatedFalcon::new(sim, cfg)
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
        let r = firmware::ensure_loaded(&mut e, None, 3, &mut |_| {}).unwrap();
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
        let r =
            firmware::ensure_loaded(&mut e, Some(&image()), 5, &mut |m| log.push(m.to_string()))
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
        let r = firmware::ensure_loaded(&mut e, Some(&image()), 20, &mut |_| {}).unwrap();
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
        let err = firmware::ensure_loaded(&mut e, Some(&image()), 3, &mut |_| {})
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
        let err = firmware::ensure_loaded(&mut e, None, 3, &mut |_| {})
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
        let err = firmware::ensure_loaded(&mut e, Some(&image()), 3, &mut |_| {})
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
    fn past_the_arms_reach_the_grip_is_held_back_and_still_read() {
        let e = emulator(EmulatorConfig::default());
        let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
        let t = drive(&mut dev, 0.0, 3.0, |_| [0.0; 3]);
        assert!(dev.transport().is_homed());
        // Push hard outwards (+z, away from the Falcon's body), towards the
        // simulator's box wall, which lies beyond what the arms reach.
        let t = drive(&mut dev, t, 2.0, |_| [0.0, 0.0, 6.0]);
        let emu = dev.transport();
        assert!(
            emu.counters.unreachable > 0,
            "the grip never left the reach"
        );
        let p = emu.sim().true_position();
        let overshoot = (0..3)
            .map(|a| (p[a] - emu.reachable[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(
            overshoot < 5e-4,
            "the grip went {overshoot} m past its reach"
        );
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
}
