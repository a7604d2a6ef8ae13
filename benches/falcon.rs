//! The Falcon driver's work per servo tick, and the forward kinematics'
//! iteration counts at stroke speeds.
//!
//! - `falcon/driver_tick`: decode a reply, encoder counts → angles, forward
//!   kinematics warm-started from the last tick (Newton), the Jacobian, a
//!   Cartesian force → motor commands (clamped), encode the next command —
//!   the driver's whole per-tick computation, without I/O. Budget: 20 µs.
//! - `falcon/fk_warm` and `falcon/ik`: the kinematics alone.
//! - `falcon/emulated_tick`: a whole `read` + `command` through the
//!   emulator (driver + emulated device + physics), for scale.
//!
//! Before the timings it prints how many Newton steps the forward
//! kinematics took per tick along the thesis's stroke at 1, 10 and 30 cm/s
//! (the requirement: at most 4).
//!
//! cargo bench --bench falcon

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use hapticlab::device::HapticDevice;
use hapticlab::device::falcon::kinematics::{self, ForwardSolver, Frame, Vec3};
use hapticlab::device::falcon::packet::{self, CommandPacket, ReplyPacket};
use hapticlab::device::falcon::{FalconConfig, FalconDevice, emulator};
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;

const OFFSET: f64 = kinematics::DEFAULT_ENCODER_OFFSET_DEG;

/// Encoded replies along the thesis's stroke (Falcon frame), one per tick at `speed`.
fn stroke_replies(speed: f64, ticks: usize) -> Vec<[u8; 16]> {
    let frame = Frame::default();
    (0..ticks)
        .map(|k| {
            let x = -0.045 + speed * 0.001 * k as f64;
            // A corrugation-like ripple in height, as on texture S2.
            let y = -0.0048 + 0.0004 * (x * 2.0 * std::f64::consts::PI / 0.00424).sin();
            let p = frame.to_falcon([x.min(0.0447), y, -0.02]);
            let a = kinematics::inverse(p).expect("the stroke is reachable");
            packet::encode_reply(&ReplyPacket {
                encoder: a.theta1.map(|t| kinematics::count_of_angle(t, OFFSET)),
                buttons: 0,
                homed: packet::ALL_HOMED,
            })
        })
        .collect()
}

/// The driver's per-tick computation on one reply; returns the next command's bytes.
fn driver_tick(solver: &mut ForwardSolver, reply: &[u8; 16], force: Vec3) -> [u8; 16] {
    let r = packet::decode_reply(reply).expect("a valid reply");
    let theta = r.encoder.map(|c| kinematics::angle_of_count(c, OFFSET));
    let _ = solver.solve(theta).expect("converges");
    let j = solver.jacobian().copied().expect("a Jacobian");
    let motor = kinematics::motor_commands(kinematics::torques(&j, force));
    packet::encode_command(&CommandPacket {
        motor,
        flags: packet::FLAG_HOMING | packet::LED_BLUE,
    })
}

fn report_iterations() {
    for speed in [0.01, 0.1, 0.3] {
        let replies = stroke_replies(speed, (0.0897 / speed * 1000.0) as usize);
        let mut solver = ForwardSolver::new();
        let mut hist = [0usize; 16];
        for (k, r) in replies.iter().enumerate() {
            let rp = packet::decode_reply(r).unwrap();
            let s = solver
                .solve(rp.encoder.map(|c| kinematics::angle_of_count(c, OFFSET)))
                .unwrap();
            // The first tick is a cold start.
            if k > 0 {
                hist[s.iterations as usize] += 1;
            }
        }
        let max = hist.iter().rposition(|&n| n > 0).unwrap_or(0);
        let spread: Vec<String> = hist
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(i, n)| format!("{i} steps: {n}"))
            .collect();
        eprintln!(
            "FK Newton steps per tick at {:.0} cm/s over the stroke ({} ticks): max {max}; {}",
            speed * 100.0,
            replies.len() - 1,
            spread.join(", ")
        );
    }
}

fn bench(c: &mut Criterion) {
    report_iterations();
    let replies = stroke_replies(0.01, 8970);
    let mut g = c.benchmark_group("falcon");
    g.bench_function("driver_tick", |b| {
        let mut solver = ForwardSolver::new();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % replies.len();
            if k == 0 {
                solver.reset();
            }
            black_box(driver_tick(
                &mut solver,
                &replies[k],
                black_box([0.3, -0.5, 0.1]),
            ))
        })
    });
    g.bench_function("fk_warm", |b| {
        let thetas: Vec<Vec3> = replies
            .iter()
            .map(|r| {
                packet::decode_reply(r)
                    .unwrap()
                    .encoder
                    .map(|c| kinematics::angle_of_count(c, OFFSET))
            })
            .collect();
        let mut solver = ForwardSolver::new();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % thetas.len();
            if k == 0 {
                solver.reset();
            }
            black_box(solver.solve(thetas[k]).unwrap())
        })
    });
    g.bench_function("ik", |b| {
        b.iter(|| black_box(kinematics::inverse(black_box([0.01, -0.004, 0.14]))))
    });
    g.bench_function("emulated_tick", |b| {
        let lp = LoadedProfile::thesis();
        let sim = SimDevice::new(&lp.profile, Path::new("."), Some("S2"), 1).unwrap();
        let emu = emulator::EmulatedFalcon::new(sim, emulator::EmulatorConfig::default());
        let mut dev = FalconDevice::open(emu, FalconConfig::default(), &mut |_| {}).unwrap();
        let mut t = 0.0;
        b.iter(|| {
            t += 0.001;
            let r = dev.read(t).unwrap();
            let f = if r.homed {
                [0, 1, 2].map(|a| 100.0 * (-0.04 * (a == 2) as u8 as f64 - r.pos_m[a]))
            } else {
                [0.0; 3]
            };
            dev.command(f).unwrap();
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
