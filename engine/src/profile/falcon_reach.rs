//! The Falcon's reach: Stamper's delta geometry (the constants libnifalcon
//! uses), the closed-form inverse kinematics, the workspace box and the
//! profile ↔ Falcon frame. The profile checks its waypoints with these
//! (`[falcon] origin_m`, `path.waypoints_m`), so they live in the ground
//! layer; the device's kinematics (`crate::device::falcon::kinematics`:
//! Jacobian, forward solver, encoders, motor commands) re-exports and builds
//! on them. The model is described there. Pure functions: no I/O, no
//! allocation.

use std::f64::consts::PI;

/// Stamper's constants for the Falcon, metres.
pub const A: f64 = 0.060;
pub const B: f64 = 0.1025;
pub const C: f64 = 0.01443;
pub const D: f64 = 0.01125;
pub const E: f64 = 0.01125;
pub const F: f64 = -0.025;
pub const R: f64 = 0.040;
pub const S: f64 = -0.02309;
/// The legs' angles about z, degrees.
pub const LEG_ANGLES_DEG: [f64; 3] = [105.0, -15.0, -135.0];
/// The arm angle of encoder count 0 after homing, degrees (approximate; the
/// profile's `falcon.encoder_offset_deg` can calibrate it).
pub const DEFAULT_ENCODER_OFFSET_DEG: f64 = 35.0;

/// The Falcon's workspace in its own frame, metres: the 4-inch cube Novint
/// specifies, centred on z = 0.125. Positions must also be reachable by the
/// legs ([`inverse`] succeeds).
pub const FALCON_MIN_M: [f64; 3] = [-0.05, -0.05, 0.075];
pub const FALCON_MAX_M: [f64; 3] = [0.05, 0.05, 0.175];
/// Where the profile's origin lies in the Falcon's frame unless the profile says.
pub const DEFAULT_ORIGIN_M: [f64; 3] = [0.0, 0.0, 0.15];

pub type Vec3 = [f64; 3];

/// All three legs' angles, radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegAngles {
    /// Motor (upper arm) angles.
    pub theta1: Vec3,
    pub theta2: Vec3,
    pub theta3: Vec3,
}

#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    #[error("({:.4}, {:.4}, {:.4}) m is out of reach of leg {leg}", .p[0], .p[1], .p[2])]
    Unreachable { p: Vec3, leg: usize },
    #[error("the forward kinematics did not converge (joint error {residual_rad:.2e} rad)")]
    NoConvergence { residual_rad: f64 },
    #[error("the Jacobian is singular here")]
    Singular,
}

/// Leg `i`'s sine and cosine of φ.
pub fn leg_trig(i: usize) -> (f64, f64) {
    LEG_ANGLES_DEG[i].to_radians().sin_cos()
}

/// A point in leg `i`'s coordinates (u, v, w).
pub fn to_leg(i: usize, p: Vec3) -> Vec3 {
    let (s, c) = leg_trig(i);
    [c * p[0] + s * p[1] - R, -s * p[0] + c * p[1] - S, p[2]]
}

/// Inverse kinematics, closed form: the legs' angles at `p` (Falcon frame).
pub fn inverse(p: Vec3) -> Result<LegAngles, KinematicsError> {
    let mut out = LegAngles::default();
    for i in 0..3 {
        let [u, v, w] = to_leg(i, p);
        let cos3 = (v + F) / B;
        if !(-1.0..=1.0).contains(&cos3) {
            return Err(KinematicsError::Unreachable { p, leg: i });
        }
        let t3 = cos3.acos();
        let l = D + E + B * t3.sin();
        // The constraint as a·(P cos θ1 + w sin θ1) = k/2: a phase-shifted cosine.
        let pu = u + C;
        let k = pu * pu + w * w + A * A - l * l;
        let rho = pu.hypot(w);
        let cos_shift = k / (2.0 * A * rho);
        if !(rho > 0.0 && (-1.0..=1.0).contains(&cos_shift)) {
            return Err(KinematicsError::Unreachable { p, leg: i });
        }
        // Of the two elbow solutions, the Falcon's arms take the lower one.
        let t1 = w.atan2(pu) - cos_shift.acos();
        let t2 = (w - A * t1.sin()).atan2(pu - A * t1.cos());
        out.theta1[i] = wrap(t1);
        out.theta2[i] = t2;
        out.theta3[i] = t3;
    }
    Ok(out)
}

/// An angle wrapped into (−π, π].
pub fn wrap(a: f64) -> f64 {
    let mut a = a;
    while a > PI {
        a -= 2.0 * PI;
    }
    while a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// Whether `p` (Falcon frame) lies in the workspace box and in reach.
pub fn in_workspace(p: Vec3) -> bool {
    (0..3).all(|a| p[a] >= FALCON_MIN_M[a] && p[a] <= FALCON_MAX_M[a]) && inverse(p).is_ok()
}

/// How close (degrees) a waypoint may bring a motor arm to its stops.
pub const JOINT_MARGIN_DEG: f64 = 5.0;

/// The motor arms' travel, degrees (lowest, highest θ1): the angles on the
/// axis at the workspace box's ends, grip fully pushed in (z 0.075 m,
/// ≈ −18.3°) and fully pulled out (z 0.175 m, ≈ 73.5°). The mechanical stops
/// lie about there; they are not measured on a device.
pub fn joint_limits_deg() -> (f64, f64) {
    let at = |z: f64| inverse([0.0, 0.0, z]).map_or(f64::NAN, |a| a.theta1[0].to_degrees());
    (at(FALCON_MIN_M[2]), at(FALCON_MAX_M[2]))
}

/// The motor arm nearest its stops at `p` (Falcon frame): (leg, θ1 in
/// degrees, degrees left before the stop; negative beyond it).
pub fn joint_clearance(p: Vec3) -> Result<(usize, f64, f64), KinematicsError> {
    let a = inverse(p)?;
    let (lo, hi) = joint_limits_deg();
    let mut worst = (0, 0.0, f64::INFINITY);
    for (leg, t) in a.theta1.iter().enumerate() {
        let deg = t.to_degrees();
        let clearance = (deg - lo).min(hi - deg);
        if clearance < worst.2 {
            worst = (leg, deg, clearance);
        }
    }
    Ok(worst)
}

/// The profile frame ↔ the Falcon's: same axes, shifted origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Where the profile's origin lies in the Falcon's frame, metres.
    pub origin_m: Vec3,
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            origin_m: DEFAULT_ORIGIN_M,
        }
    }
}

impl Frame {
    pub fn to_falcon(&self, p: Vec3) -> Vec3 {
        [
            p[0] + self.origin_m[0],
            p[1] + self.origin_m[1],
            p[2] + self.origin_m[2],
        ]
    }
    pub fn to_profile(&self, p: Vec3) -> Vec3 {
        [
            p[0] - self.origin_m[0],
            p[1] - self.origin_m[1],
            p[2] - self.origin_m[2],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_arms_travel_from_the_pushed_in_to_the_pulled_out_grip() {
        let (lo, hi) = joint_limits_deg();
        assert!(
            (lo - -18.3).abs() < 0.1 && (hi - 73.5).abs() < 0.1,
            "{lo} {hi}"
        );
        // The case: the thesis's waypoint 3 at Falcon z = 0.14 puts
        // leg 1 at 69.5°, 4° from the stop.
        let (leg, deg, clearance) = joint_clearance([-0.045, 0.01, 0.14]).unwrap();
        assert_eq!(leg, 1);
        assert!(
            (deg - 69.5).abs() < 0.05 && clearance < JOINT_MARGIN_DEG,
            "{deg}"
        );
        // The workspace's centre is far from both stops.
        assert!(joint_clearance([0.0, 0.0, 0.12]).unwrap().2 > 30.0);
    }
}
