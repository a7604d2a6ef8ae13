//! The motor arms' mechanical stops, as the emulated Falcon feels them: an
//! arm turned past its stop is held back by a stiff torque about its own
//! joint, whatever the grip's position. The stops sit where the model puts
//! them ([`kinematics::joint_limits_deg`]: the arm angles on the axis at the
//! workspace box's ends, about −18.3° pushed in and 73.5° pulled out), so
//! the self-test's calibration, which pushes each arm to its stops and
//! reads the encoders there, measures the encoders against them.

use super::EmulatedFalcon;
use crate::device::HapticDevice;
use crate::device::falcon::kinematics::{self, Vec3};

/// The stop's stiffness and damping about the arm's joint (N·m/rad,
/// N·m·s/rad): about 110 kN/m at the grip on the axis, so that a push of
/// 0.05 N·m per arm sinks less than 0.05° into the stop.
const STIFFNESS_NM_PER_RAD: f64 = 60.0;
const DAMPING_NM_S_PER_RAD: f64 = 0.05;
/// Within this of a stop (degrees) the physics runs in [`PIECES`] per tick
/// with the stop's torque renewed in each: held over a whole tick, so stiff
/// a spring would ring.
const NEAR_DEG: f64 = 3.0;
const PIECES: u32 = 8;

/// The arms' stops, radians (lowest, highest motor angle).
pub fn limits_rad() -> (f64, f64) {
    let (lo, hi) = kinematics::joint_limits_deg();
    (lo.to_radians(), hi.to_radians())
}

/// Whether an arm is within [`NEAR_DEG`] of a stop, or past it, with the
/// grip at `p` (Falcon frame).
pub fn near_a_stop(p: Vec3, limits: (f64, f64)) -> bool {
    let near = NEAR_DEG.to_radians();
    kinematics::inverse(p).is_ok_and(|a| {
        a.theta1
            .iter()
            .any(|&t| t < limits.0 + near || t > limits.1 - near)
    })
}

/// The force (N, Falcon frame) with which the stops hold back the grip at
/// `p` moving at `v` (m/s): zero while every arm is within its travel, or
/// where the legs cannot reach (the reach's own force holds it there).
pub fn force(p: Vec3, v: Vec3, limits: (f64, f64)) -> Vec3 {
    let Ok(a) = kinematics::inverse(p) else {
        return [0.0; 3];
    };
    let rates = kinematics::joint_rates(&a);
    let mut tau = [0.0; 3];
    let mut any = false;
    for (i, (&t, row)) in a.theta1.iter().zip(&rates).enumerate() {
        let w = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
        if t < limits.0 {
            tau[i] = STIFFNESS_NM_PER_RAD * (limits.0 - t) - DAMPING_NM_S_PER_RAD * w.min(0.0);
            any = true;
        } else if t > limits.1 {
            tau[i] = -STIFFNESS_NM_PER_RAD * (t - limits.1) - DAMPING_NM_S_PER_RAD * w.max(0.0);
            any = true;
        }
    }
    if !any {
        return [0.0; 3];
    }
    kinematics::jacobian(&a)
        .and_then(|j| kinematics::force_of_torques(&j, tau))
        .unwrap_or([0.0; 3])
}

impl EmulatedFalcon {
    /// The physics from `from` to `to` (servo time): the hand's and the
    /// reach's force held over the tick, and the arms' stops renewed in
    /// pieces when an arm is near one.
    pub(super) fn run_physics(&mut self, from: f64, to: f64) {
        let pieces = if near_a_stop(self.falcon_position(), self.stops_rad) {
            PIECES
        } else {
            1
        };
        for k in 1..=pieces {
            let stop = force(
                self.falcon_position(),
                self.sim.true_velocity(),
                self.stops_rad,
            );
            self.sim
                .set_hand_force(std::array::from_fn(|a| self.outside_n[a] + stop[a]));
            let _ = self
                .sim
                .read(from + (to - from) * f64::from(k) / f64::from(pieces));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stops_push_back_only_past_them_and_towards_the_travel() {
        let limits = limits_rad();
        // The middle of the workspace: free.
        assert_eq!(force([0.0, 0.0, 0.12], [0.0; 3], limits), [0.0; 3]);
        assert!(!near_a_stop([0.0, 0.0, 0.12], limits));
        // Pushed in past the box's end on the axis: held back outwards (+z).
        let f = force([0.0, 0.0, 0.0745], [0.0; 3], limits);
        assert!(
            f[2] > 10.0 && f[0].abs() < 1e-6 && f[1].abs() < 1e-6,
            "{f:?}"
        );
        assert!(near_a_stop([0.0, 0.0, 0.076], limits));
        // Pulled out past it: held back inwards.
        let f = force([0.0, 0.0, 0.1755], [0.0; 3], limits);
        assert!(f[2] < -10.0, "{f:?}");
    }
}
