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
//! pushed fully in — by a simulated hand when `auto_home` is on. The arms
//! stop at the model's stops ([`stops`]), and the encoders may be set to
//! read a few degrees off (`encoder_offset_error_deg`), for the self-test's
//! calibration to find.
//!
//! Time on the link is [`timing::Link`]'s: with `[falcon.emulator.timing]`
//! replies come as late as USB and the FTDI chip's latency timer make them,
//! and a read returns nothing when its timeout passes first.
//!
//! Faults on demand: replies dropped, garbled or split in two, uploads that
//! fail (a corrupted echo) a set number of times or until the device is
//! reopened, a stray byte before the sync byte, firmware that starts slowly,
//! unplugging at a given time (every call then fails as a vanished USB
//! device does, and the motors stop), USB reads that fail (stall) from a
//! given time, and exchanges that stall (handed to the servo loop's clock
//! through `take_stall`, as are the link's waits); the wall power lost at a
//! given time (encoders live, motors dead), a link whose replies all come
//! late, and firmware that keeps the last force when commands stop (by
//! default it stops its motors after [`FIRMWARE_SILENCE_S`]). It never
//! sleeps, so the same emulator runs in virtual and in real time.

use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::kinematics::{self, Frame};
use super::packet::{self, PacketReader, ReplyPacket};
use super::{FalconTransport, TransportError, ftdi};
use timing::Link;

mod stops;
pub mod timing;
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

/// How far (m) and how fast (Hz, per axis) the hand sweeps the grip when
/// asked to move it ([`HandTask::MoveGrip`]): a slow Lissajous figure about
/// the middle of the workspace, as a user waving the grip around would.
const HAND_SWEEP_M: f64 = 0.02;
const HAND_SWEEP_HZ: [f64; 3] = [0.5, 0.7, 0.3];

/// What the simulated hand is asked to do (the self-test's requests; see
/// [`EmulatedFalcon::ask_hand`]). Until it is first asked, the hand follows
/// `auto_home`: it homes the grip, brings it to the middle and lets go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandTask {
    /// Pull the grip out past the homing marks, push it in past the others,
    /// then hold it in the middle of the workspace.
    Home,
    /// Sweep the grip around the middle along all three axes.
    MoveGrip,
    /// Hold the grip lightly in the middle (a compliant hold the motors can
    /// push against).
    HoldLightly,
    /// Let go.
    LetGo,
}

/// Beyond the arms' reach the mechanism holds the grip back, stiffly.
const REACH_STIFFNESS_N_PER_M: f64 = 20_000.0;
const REACH_DAMPING_N_S_PER_M: f64 = 20.0;
/// Without `keeps_last_force`, the emulated firmware stops its motors after
/// this long without a command (servo time).
pub const FIRMWARE_SILENCE_S: f64 = 0.1;
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
    /// Times the host closed and reopened the device.
    pub reopens: u32,
    /// Failed USB reads injected (`read_error_after_s`).
    pub read_errors: u32,
    /// Packets ignored because the fresh firmware had not started yet.
    pub ignored_while_starting: u64,
    /// Commands asking for force after the motors lost power (none came).
    pub unpowered_commands: u64,
    /// Times the firmware stopped its motors for want of commands.
    pub silence_stops: u32,
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
    link: Link,
    /// The link's creation, for [`FalconTransport::now`].
    epoch: Instant,
    /// Link time from which a fresh firmware answers.
    fw_ready_at: f64,
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
    read_errors_left: Option<u32>,
    stalls_done: u32,
    stall: Option<Duration>,
    /// What the hand was last asked to do, and when (servo time).
    hand_task: Option<(HandTask, f64)>,
    /// The wall power is off: the motors do nothing.
    power_lost: bool,
    /// Servo time of the last command applied.
    commanded_at: f64,
    /// The force of the hand and the arms' reach this tick (N, profile frame).
    outside_n: [f64; 3],
    /// The arms' mechanical stops, radians.
    stops_rad: (f64, f64),
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
            link: Link::new(cfg.device.timing.clone(), cfg.seed),
            epoch: Instant::now(),
            fw_ready_at: 0.0,
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
            read_errors_left: None,
            stalls_done: 0,
            stall: None,
            hand_task: None,
            power_lost: false,
            commanded_at: 0.0,
            outside_n: [0.0; 3],
            stops_rad: stops::limits_rad(),
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

    /// Ask the simulated hand to do something (from now on it does only
    /// what it is asked; `auto_home` no longer applies).
    pub fn ask_hand(&mut self, task: HandTask) {
        self.hand_task = Some((task, self.t));
    }

    /// Switch the wall power off now: the encoders keep working, the
    /// motors do nothing (as `motor_power_lost_after_s` does at its time).
    pub fn lose_motor_power(&mut self) {
        self.power_lost = true;
        self.sim.make_safe();
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
        self.from_host.clear();
    }

    /// What the link did (waits, late replies).
    pub fn link_counters(&self) -> timing::LinkCounters {
        self.link.counters
    }

    /// The boot loader sends `bytes`, the first in the chip at `at`.
    fn boot_send(&mut self, bytes: &[u8], at: f64, byte_s: f64) {
        self.link.begin_message();
        for (i, &b) in bytes.iter().enumerate() {
            self.link.device_send(b, at + i as f64 * byte_s);
        }
    }

    /// A byte for the boot loader, in the Falcon at `at` (link time).
    fn boot_byte(&mut self, b: u8, at: f64, byte_s: f64) {
        let Firmware::Boot(stage) = self.fw else {
            return;
        };
        match stage {
            Boot::Idle => {
                self.boot_tail = [self.boot_tail[1], self.boot_tail[2], b];
                let stuck = self.cfg.device.upload_needs_reopen && self.counters.reopens == 0;
                if self.baud == ftdi::BAUD_9600
                    && self.dtr
                    && !stuck
                    && self.boot_tail == [0x0A, 0x43, 0x0D]
                {
                    self.counters.handshakes += 1;
                    let answer: &[u8] = if self.cfg.leading_zero {
                        &[0x00, 0x0A, 0x44, 0x2C, 0x0D]
                    } else {
                        &[0x0A, 0x44, 0x2C, 0x0D]
                    };
                    self.boot_send(answer, at + byte_s, byte_s);
                    self.fw = Firmware::Boot(Boot::Handshaken);
                }
            }
            Boot::Handshaken => {
                if b == 0x41 && self.baud == ftdi::BAUD_LOADER && !self.dtr {
                    self.boot_send(&[0x41], at + byte_s, byte_s);
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
                // The echo's host-side delay is drawn once per chunk.
                if received % super::firmware::CHUNK == 0 {
                    self.link.begin_message();
                }
                self.link
                    .device_send(if bad { b ^ 0x5A } else { b }, at + byte_s);
                self.fw = Firmware::Boot(Boot::Loading {
                    received: received + 1,
                    corrupt_at,
                    corrupted: corrupted || bad,
                });
            }
        }
    }

    /// A command packet, whole in the Falcon at `at` (link time): applied,
    /// and its reply sent.
    fn apply_command(&mut self, c: packet::CommandPacket, at: f64, byte_s: f64) {
        self.counters.commands += 1;
        self.motor = c.motor;
        self.flags = c.flags;
        self.commanded_at = self.t;
        let mut turning = c.motor;
        if let Some(m) = self.cfg.device.reversed_motor {
            // Wired backwards: the motor turns against its command.
            let m = usize::from(m).min(2);
            turning[m] = turning[m].saturating_neg();
        }
        let m = c
            .motor
            .iter()
            .map(|v| v.saturating_abs())
            .max()
            .unwrap_or(0);
        self.counters.max_motor = self.counters.max_motor.max(m);
        if self.power_lost {
            // The firmware takes the command; the motors have no power.
            self.counters.unpowered_commands += u64::from(turning != [0; 3]);
            turning = [0; 3];
        }
        // Torques through the Jacobian at the true position.
        let tau = kinematics::torques_of_commands(turning);
        let force = kinematics::inverse(self.falcon_position())
            .and_then(|a| kinematics::jacobian(&a))
            .and_then(|j| kinematics::force_of_torques(&j, tau))
            .unwrap_or([0.0; 3]);
        // Same axes in both frames.
        let _ = self.sim.command(force);
        self.send_reply(at + self.link.firmware_s(), byte_s);
    }

    /// The reply to the last command, its first byte in the chip at `at`
    /// (lost or garbled as the faults ask).
    fn send_reply(&mut self, at: f64, byte_s: f64) {
        let r = self.reply();
        if self
            .rng
            .random_bool(self.cfg.device.drop_rate.clamp(0.0, 1.0))
        {
            self.counters.dropped += 1;
            return;
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
        self.link
            .begin_message_after(self.cfg.device.slow_link_ms / 1000.0);
        for (i, b) in bytes.into_iter().enumerate() {
            self.link.device_send(b, at + (i + 1) as f64 * byte_s);
        }
    }

    fn reply(&mut self) -> ReplyPacket {
        let p = self.sim.true_position();
        let noisy = p.map(|v| v + self.noise.sample(&mut self.rng));
        if let Ok(a) = kinematics::inverse(self.cfg.frame.to_falcon(noisy)) {
            // Count 0 where this device's arm really is (the profile's
            // offset plus the injected error).
            let offset = self.cfg.encoder_offset_deg + self.cfg.device.encoder_offset_error_deg;
            self.last_counts = a.theta1.map(|t| kinematics::count_of_angle(t, offset));
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
        let target = if let Some((task, since)) = self.hand_task {
            self.asked_target(task, self.t - since, homing)
        } else if !self.cfg.device.auto_home || self.released {
            None
        } else if !homed {
            homing.then(|| self.homing_target())
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
        self.outside_n = hand;
    }
}

impl EmulatedFalcon {
    /// Out past the homing marks, then in past the others (profile frame).
    fn homing_target(&self) -> [f64; 3] {
        let z = if self.seen_out.iter().all(|&s| s) {
            HOME_IN_Z_M - 0.004
        } else {
            HOME_OUT_Z_M + 0.004
        };
        self.cfg.frame.to_profile([0.0, 0.0, z])
    }

    /// Where the hand takes the grip for `task`, asked `since_s` ago.
    fn asked_target(&self, task: HandTask, since_s: f64, homing: bool) -> Option<[f64; 3]> {
        let c = WORKSPACE_CENTRE_M;
        match task {
            HandTask::Home if !self.is_homed() => homing.then(|| self.homing_target()),
            HandTask::Home | HandTask::HoldLightly => Some(c),
            HandTask::MoveGrip => Some(std::array::from_fn(|a| {
                let phase = std::f64::consts::TAU * HAND_SWEEP_HZ[a] * since_s;
                c[a] + HAND_SWEEP_M * phase.sin()
            })),
            HandTask::LetGo => None,
        }
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
                    self.link.purge();
                }
                if value & ftdi::PURGE_TX != 0 {
                    self.from_host.clear();
                }
            }
            ftdi::BAUD => {
                self.baud = value;
                self.link.set_baud(value);
                if value == ftdi::BAUD_LOADER
                    && self.cfg.device.stale_byte_before_sync
                    && self.fw == Firmware::Boot(Boot::Handshaken)
                {
                    // The line glitches as the baud changes: a framing-error byte.
                    let byte_s = 10.0 / timing::baud_of_divisor(value);
                    self.boot_send(&[0x00], self.link.now() + byte_s, byte_s);
                }
                if value == ftdi::BAUD_NORMAL
                    && let Firmware::Boot(Boot::Loading {
                        received,
                        corrupted,
                        ..
                    }) = self.fw
                {
                    if received >= MIN_IMAGE && !corrupted {
                        self.fw = Firmware::Running;
                        self.fw_ready_at =
                            self.link.now() + self.cfg.device.firmware_start_ms / 1000.0;
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
            ftdi::LATENCY => self.link.set_latency_ms(value),
            ftdi::FLOW | ftdi::LINE => {}
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
        let (first, byte_s) = self.link.host_write(bytes.len());
        match self.fw {
            Firmware::Boot(_) => {
                for (i, &b) in bytes.iter().enumerate() {
                    self.boot_byte(b, first + i as f64 * byte_s, byte_s);
                }
            }
            Firmware::Running => {
                if self.baud != ftdi::BAUD_NORMAL {
                    return Ok(());
                }
                let last = first + bytes.len().saturating_sub(1) as f64 * byte_s;
                if last < self.fw_ready_at {
                    // Fresh firmware still starting: the packet is lost on it.
                    self.counters.ignored_while_starting += 1;
                    return Ok(());
                }
                self.from_host.push(bytes);
                while let Some(p) = self.from_host.next_packet() {
                    match packet::decode_command(&p) {
                        Some(c) => self.apply_command(c, last, byte_s),
                        None => self.counters.bad_commands += 1,
                    }
                }
            }
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.check()?;
        if self.read_errors_left.is_none()
            && self
                .cfg
                .device
                .read_error_after_s
                .is_some_and(|a| self.t >= a)
        {
            self.read_errors_left = Some(self.cfg.device.read_errors);
        }
        if let Some(left) = self.read_errors_left.as_mut()
            && *left > 0
        {
            *left -= 1;
            self.counters.read_errors += 1;
            return Err(TransportError::Transient(format!(
                "the emulated Falcon's USB read failed (endpoint stalled) at {:.3} s, as `[falcon.emulator] read_error_after_s` asks",
                self.t
            )));
        }
        let mut n = buf
            .len()
            .min(self.link.wait_for_bytes(timeout.as_secs_f64()));
        if n > 1
            && self
                .rng
                .random_bool(self.cfg.device.split_rate.clamp(0.0, 1.0))
        {
            n = self.rng.random_range(1..n);
            self.counters.split += 1;
        }
        self.link.take(buf, n);
        Ok(n)
    }

    fn now(&self) -> Instant {
        self.epoch + Duration::from_secs_f64(self.link.now())
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.check()?;
        self.counters.reopens += 1;
        // Whatever the host had pending is gone with its handle.
        self.link.purge();
        self.from_host.clear();
        Ok(())
    }

    fn advance_to(&mut self, t_s: f64) {
        if !(t_s.is_finite() && t_s > self.t) {
            return;
        }
        let from = self.t;
        self.t = t_s;
        self.link.follow(t_s);
        self.link.clear_waited();
        if !self.unplugged && self.cfg.device.unplug_after_s.is_some_and(|u| t_s >= u) {
            self.unplug();
        }
        if !self.power_lost
            && self
                .cfg
                .device
                .motor_power_lost_after_s
                .is_some_and(|p| t_s >= p)
        {
            self.lose_motor_power();
        }
        let silent = t_s - self.commanded_at > FIRMWARE_SILENCE_S;
        if !self.cfg.device.keeps_last_force && silent && self.motor != [0; 3] {
            self.motor = [0; 3];
            self.sim.make_safe();
            self.counters.silence_stops += 1;
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
            self.outside_n = [0.0; 3];
        }
        // The physics runs whether or not anyone listens.
        self.run_physics(from, t_s);
    }

    fn applied_motor(&self) -> Option<[i16; 3]> {
        Some(self.motor)
    }

    fn take_stall(&mut self) -> Option<Duration> {
        // The link's waits in this tick's reads, and any injected stall.
        let waited = self.link.take_waited().map(Duration::from_secs_f64);
        match (self.stall.take(), waited) {
            (Some(a), Some(b)) => Some(a + b),
            (a, b) => a.or(b),
        }
    }
}

#[cfg(test)]
mod tests;
