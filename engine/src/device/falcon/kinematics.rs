//! The Falcon's delta kinematics after R. E. Stamper's model (the geometry
//! libnifalcon uses), derived and written for this project: inverse
//! kinematics in closed form, forward kinematics by Newton's method warm-
//! started from the last solution, the Jacobian, Cartesian force → motor
//! commands, encoder counts ↔ motor angles, and the map between the Falcon's
//! frame and the profile's.
//!
//! ## The leg model
//! Each leg i is rotated by φᵢ (105°, −15°, −135°) about the Falcon's z axis.
//! In leg coordinates (u, v, w) = (cosφ x + sinφ y − r, −sinφ x + cosφ y − s, z)
//! the end effector sits at
//!
//! ```text
//! u = a cos θ1 − c + L cos θ2
//! w = a sin θ1     + L sin θ2        L = d + e + b sin θ3
//! v = b cos θ3 − f
//! ```
//!
//! where θ1 is the motor's angle (the upper arm, length a), and θ2, θ3 are
//! the passive angles of the parallelogram (length b). Eliminating θ2 gives
//! one constraint per leg, `G = (u + c − a cos θ1)² + (w − a sin θ1)² − L² = 0`,
//! from which both the inverse kinematics (solve for θ1) and the Jacobian
//! (implicit differentiation: ∂θ1/∂p = −∇ₚG / ∂G/∂θ1) follow.
//!
//! ## Frames
//! The Falcon's kinematic frame: x to the right, y up, z towards the user
//! (z grows as the grip is pulled out), metres, origin on the axis of
//! symmetry at the motors' plane; the workspace's centre is near z = 0.12.
//! The profile's frame (the thesis's): x along the stroke, y vertical and up,
//! z towards the user. The axes agree; [`Frame`] only shifts the origin:
//! `profile = falcon − origin`, with `origin` from the profile's
//! `[falcon] origin_m` (default (0, 0, 0.15): the thesis's waypoints, at
//! z = −6…−2 cm, land at Falcon z = 0.09…0.13, every motor arm at least 8°
//! from its stops).
//!
//! The geometry, the inverse kinematics and the frame live in the profile
//! (`crate::profile::falcon_reach`), which checks waypoints against the
//! Falcon's reach without depending on the device layer; they are re-exported
//! here. Pure functions and a small solver state: no I/O, no allocation.

pub use crate::profile::falcon_reach::{
    A, B, C, D, DEFAULT_ENCODER_OFFSET_DEG, DEFAULT_ORIGIN_M, E, F, FALCON_MAX_M, FALCON_MIN_M,
    Frame, KinematicsError, LEG_ANGLES_DEG, LegAngles, R, S, Vec3, in_workspace, inverse,
    joint_limits_deg, leg_trig, to_leg, wrap,
};

/// Encoder: 320 slots × 4 edges per motor turn, through the 0.110/0.01425 capstan drive.
pub const COUNTS_PER_MOTOR_TURN: f64 = 1280.0;
pub const DRIVE_RATIO: f64 = 0.110 / 0.01425;
/// Motor command units per newton-metre of joint torque, and the largest
/// command sent (Novint's own SDK never exceeds it; the 16-bit field would wrap).
pub const COMMAND_PER_NM: f64 = 10_000.0;
pub const MAX_COMMAND: i16 = 4095;

/// The forward solver's first guess (and fallback), Falcon frame.
pub const START_GUESS_M: [f64; 3] = [0.0, 0.0, 0.12];

pub type Mat3 = [[f64; 3]; 3];

/// ∂θ1/∂p: row i is how leg i's motor angle changes with the position
/// (rad/m), from the constraint by implicit differentiation.
pub fn joint_rates(angles: &LegAngles) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        let (t1, t2, t3) = (angles.theta1[i], angles.theta2[i], angles.theta3[i]);
        let denom = A * (t2 - t1).sin() * t3.sin();
        // Gradient in leg coordinates (u, v, w), then rotated back by φ.
        let gu = t2.cos() * t3.sin() / denom;
        let gv = t3.cos() / denom;
        let gw = t2.sin() * t3.sin() / denom;
        let (s, c) = leg_trig(i);
        *row = [c * gu - s * gv, s * gu + c * gv, gw];
    }
    m
}

pub fn det(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

pub fn invert(m: &Mat3) -> Result<Mat3, KinematicsError> {
    let dt = det(m);
    if !(dt.is_finite() && dt.abs() > 1e-12) {
        return Err(KinematicsError::Singular);
    }
    let mut inv = [[0.0; 3]; 3];
    for (r, row) in inv.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            // Cofactor of (c, r), transposed.
            let (r1, r2) = ((c + 1) % 3, (c + 2) % 3);
            let (c1, c2) = ((r + 1) % 3, (r + 2) % 3);
            *v = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / dt;
        }
    }
    Ok(inv)
}

pub fn mul(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

pub fn mul_transposed(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// The Jacobian J = ∂p/∂θ1 (m/rad) at the legs' angles: column j is how
/// the end effector moves when motor j turns.
pub fn jacobian(angles: &LegAngles) -> Result<Mat3, KinematicsError> {
    invert(&joint_rates(angles))
}

/// Joint torques (N·m) that make force `f` (N, Falcon frame): τ = Jᵀ·F.
pub fn torques(j: &Mat3, f: Vec3) -> Vec3 {
    mul_transposed(j, f)
}

/// The force (N, Falcon frame) that joint torques make: F = J⁻ᵀ·τ.
pub fn force_of_torques(j: &Mat3, tau: Vec3) -> Result<Vec3, KinematicsError> {
    let inv = invert(j)?;
    Ok(mul_transposed(&inv, tau))
}

/// Motor commands for joint torques: −10000 per N·m. When any command would
/// exceed ±4095 all three are scaled by the same factor, so the torques keep
/// their ratios and the force keeps its direction (clamping each motor on its
/// own would bend it); the second value says whether that happened.
pub fn motor_commands_scaled(tau: Vec3) -> ([i16; 3], bool) {
    let raw = tau.map(|t| -COMMAND_PER_NM * t);
    if raw.iter().any(|v| !v.is_finite()) {
        return ([0; 3], false);
    }
    let max = f64::from(MAX_COMMAND);
    let peak = raw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = if peak > max { max / peak } else { 1.0 };
    let out = raw.map(|v| (v * scale).round().clamp(-max, max) as i16);
    (out, peak > max)
}

/// [`motor_commands_scaled`] without the saturation flag.
pub fn motor_commands(tau: Vec3) -> [i16; 3] {
    motor_commands_scaled(tau).0
}

/// The joint torques (N·m) that motor commands produce.
pub fn torques_of_commands(cmd: [i16; 3]) -> Vec3 {
    cmd.map(|c| -f64::from(c) / COMMAND_PER_NM)
}

/// Degrees of arm rotation per encoder count (≈ 0.036435°).
pub fn degrees_per_count() -> f64 {
    360.0 / (COUNTS_PER_MOTOR_TURN * DRIVE_RATIO)
}

/// A motor's arm angle (rad) from its encoder count.
pub fn angle_of_count(count: i16, offset_deg: f64) -> f64 {
    (f64::from(count) * degrees_per_count() + offset_deg).to_radians()
}

/// The encoder count nearest an arm angle (rad), saturating at the i16 range.
pub fn count_of_angle(theta: f64, offset_deg: f64) -> i16 {
    let c = ((theta.to_degrees() - offset_deg) / degrees_per_count()).round();
    c.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
}

/// steps reach a nanometre.
/// Newton's method on the inverse kinematics: p ← p + J(p)·(θ − IK(p)).
/// Warm-started from the last solution, so at stroke speeds one or two
/// steps reach a nanometre.
pub struct ForwardSolver {
    last: Vec3,
    /// The angles and Jacobian at the last solution (for force mapping).
    last_angles: LegAngles,
    last_jacobian: Option<Mat3>,
    /// Joint error (rad) below which a solution is accepted.
    pub tolerance_rad: f64,
    pub max_iterations: u32,
}

/// One forward solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    pub p: Vec3,
    /// Newton steps taken.
    pub iterations: u32,
    /// Restarted from the first guess (the warm start failed).
    pub restarted: bool,
}

impl Default for ForwardSolver {
    fn default() -> Self {
        Self::new()
    }
}

impl ForwardSolver {
    pub fn new() -> ForwardSolver {
        ForwardSolver {
            last: START_GUESS_M,
            last_angles: LegAngles::default(),
            last_jacobian: None,
            tolerance_rad: 1e-10,
            max_iterations: 15,
        }
    }

    /// The last solution (Falcon frame).
    pub fn position(&self) -> Vec3 {
        self.last
    }

    /// The Jacobian at the last solution, if one was found.
    pub fn jacobian(&self) -> Option<&Mat3> {
        self.last_jacobian.as_ref()
    }

    pub fn angles(&self) -> &LegAngles {
        &self.last_angles
    }

    /// Forget the warm start (after a jump, e.g. homing).
    pub fn reset(&mut self) {
        self.last = START_GUESS_M;
        self.last_jacobian = None;
    }

    /// The position whose motor angles are `theta1` (rad).
    pub fn solve(&mut self, theta1: Vec3) -> Result<Solution, KinematicsError> {
        match self.newton(self.last, theta1) {
            Ok((p, iterations)) => Ok(Solution {
                p,
                iterations,
                restarted: false,
            }),
            Err(_) => {
                let (p, iterations) = self.continuation(theta1)?;
                Ok(Solution {
                    p,
                    iterations,
                    restarted: true,
                })
            }
        }
    }

    /// A cold start: walk the joint angles from the first guess's to the
    /// target in small steps, solving each from the last, so that every
    /// Newton step starts close (far from the guess, a direct step can leave
    /// the reachable region).
    fn continuation(&mut self, theta1: Vec3) -> Result<(Vec3, u32), KinematicsError> {
        let start = inverse(START_GUESS_M)?.theta1;
        for pieces in [4u32, 16, 64] {
            let mut p = START_GUESS_M;
            let mut ok = true;
            let mut total = 0;
            for k in 1..=pieces {
                let l = f64::from(k) / f64::from(pieces);
                let target = [
                    start[0] + l * (theta1[0] - start[0]),
                    start[1] + l * (theta1[1] - start[1]),
                    start[2] + l * (theta1[2] - start[2]),
                ];
                match self.newton(p, target) {
                    Ok((q, n)) => {
                        p = q;
                        total += n;
                    }
                    Err(_) => {
                        ok = false;
                        break;
                    }
                }
            }
            if ok {
                return Ok((p, total));
            }
        }
        Err(KinematicsError::NoConvergence {
            residual_rad: f64::NAN,
        })
    }

    fn newton(&mut self, start: Vec3, theta1: Vec3) -> Result<(Vec3, u32), KinematicsError> {
        let mut p = start;
        let mut angles = inverse(p)?;
        let mut residual = max_abs(sub(theta1, angles.theta1));
        let mut steps = 0;
        while residual > self.tolerance_rad {
            if steps >= self.max_iterations {
                return Err(KinematicsError::NoConvergence {
                    residual_rad: residual,
                });
            }
            let j = jacobian(&angles)?;
            let dp = mul(&j, sub(theta1, angles.theta1));
            // Halve the step while it leaves the reachable region or grows the error.
            let mut scale = 1.0;
            loop {
                let q = [
                    p[0] + scale * dp[0],
                    p[1] + scale * dp[1],
                    p[2] + scale * dp[2],
                ];
                if let Ok(a) = inverse(q) {
                    let r = max_abs(sub(theta1, a.theta1));
                    if r < residual || scale < 1e-3 {
                        p = q;
                        angles = a;
                        residual = r;
                        break;
                    }
                }
                scale *= 0.5;
                if scale < 1e-3 {
                    return Err(KinematicsError::NoConvergence {
                        residual_rad: residual,
                    });
                }
            }
            steps += 1;
        }
        self.last = p;
        self.last_angles = angles;
        self.last_jacobian = jacobian(&angles).ok();
        Ok((p, steps))
    }
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn max_abs(v: Vec3) -> f64 {
    v[0].abs().max(v[1].abs()).max(v[2].abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist(a: Vec3, b: Vec3) -> f64 {
        let d = sub(a, b);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    /// A grid over the workspace box, reachable points only.
    fn grid(step: f64) -> Vec<Vec3> {
        let mut pts = Vec::new();
        let n = |a: usize| ((FALCON_MAX_M[a] - FALCON_MIN_M[a]) / step).round() as usize;
        for i in 0..=n(0) {
            for j in 0..=n(1) {
                for k in 0..=n(2) {
                    let p = [
                        FALCON_MIN_M[0] + i as f64 * step,
                        FALCON_MIN_M[1] + j as f64 * step,
                        FALCON_MIN_M[2] + k as f64 * step,
                    ];
                    if inverse(p).is_ok() {
                        pts.push(p);
                    }
                }
            }
        }
        pts
    }

    #[test]
    fn fk_of_ik_is_the_point_within_a_micrometre_over_the_workspace() {
        let pts = grid(0.01);
        assert!(pts.len() > 700, "only {} reachable grid points", pts.len());
        let mut solver = ForwardSolver::new();
        let mut worst: f64 = 0.0;
        for &p in &pts {
            let a = inverse(p).unwrap();
            // Cold: from the first guess, as after a reset.
            solver.reset();
            let s = solver
                .solve(a.theta1)
                .unwrap_or_else(|e| panic!("{p:?}: {e}"));
            let e = dist(s.p, p);
            worst = worst.max(e);
            assert!(e < 1e-6, "{p:?}: FK(IK(p)) is {e:.2e} m off");
        }
        eprintln!(
            "worst FK(IK(p)) error over {} points: {worst:.2e} m",
            pts.len()
        );
    }

    #[test]
    fn the_thesis_path_is_reachable_through_the_default_frame() {
        let frame = Frame::default();
        let lp = crate::profile::LoadedProfile::thesis();
        for w in &lp.rig().unwrap().path.waypoints_m {
            let q = frame.to_falcon(*w);
            assert!(in_workspace(q), "{w:?} -> {q:?}");
        }
    }

    #[test]
    fn joint_angles_are_equal_on_the_axis_of_symmetry() {
        for z in [0.09, 0.11, 0.125, 0.15] {
            let a = inverse([0.0, 0.0, z]).unwrap();
            for i in 1..3 {
                assert!((a.theta1[i] - a.theta1[0]).abs() < 1e-12, "{a:?}");
                assert!((a.theta2[i] - a.theta2[0]).abs() < 1e-12);
                assert!((a.theta3[i] - a.theta3[0]).abs() < 1e-12);
            }
            // Pulling the grip out raises every arm.
            let b = inverse([0.0, 0.0, z + 0.001]).unwrap();
            assert!(b.theta1[0] > a.theta1[0]);
        }
    }

    #[test]
    fn the_jacobian_matches_finite_differences() {
        let h = 1e-7;
        for p in [
            [0.0, 0.0, 0.11],
            [0.03, -0.02, 0.13],
            [-0.045, 0.01, 0.145],
            [0.02, 0.04, 0.09],
        ] {
            let a = inverse(p).unwrap();
            let m = joint_rates(&a);
            for col in 0..3 {
                let mut hi = p;
                let mut lo = p;
                hi[col] += h;
                lo[col] -= h;
                let (ah, al) = (inverse(hi).unwrap(), inverse(lo).unwrap());
                for (row, m_row) in m.iter().enumerate() {
                    let fd = (ah.theta1[row] - al.theta1[row]) / (2.0 * h);
                    let rel = (fd - m_row[col]).abs() / m_row[col].abs().max(1.0);
                    assert!(rel < 1e-6, "{p:?} [{row}][{col}]: {} vs {fd}", m_row[col]);
                }
            }
            // J = ∂p/∂θ1 is its inverse.
            let j = jacobian(&a).unwrap();
            let id = [
                mul(&j, [m[0][0], m[1][0], m[2][0]]),
                mul(&j, [m[0][1], m[1][1], m[2][1]]),
            ];
            assert!((id[0][0] - 1.0).abs() < 1e-9 && id[0][1].abs() < 1e-9);
            assert!((id[1][1] - 1.0).abs() < 1e-9 && id[1][2].abs() < 1e-9);
        }
    }

    #[test]
    fn forces_map_to_commands_and_back_with_the_clamp() {
        let a = inverse([0.0, 0.0, 0.11]).unwrap();
        let j = jacobian(&a).unwrap();
        // One newton up: a few hundred counts per motor (≈ 325 on average).
        let cmd = motor_commands(torques(&j, [0.0, 1.0, 0.0]));
        let mean = cmd.iter().map(|c| f64::from(c.abs())).sum::<f64>() / 3.0;
        assert!((250.0..450.0).contains(&mean), "{cmd:?}");
        // Back through the Jacobian: the same force, to the command's rounding.
        let f = force_of_torques(&j, torques_of_commands(cmd)).unwrap();
        assert!(
            (f[1] - 1.0).abs() < 0.01 && f[0].abs() < 0.01 && f[2].abs() < 0.01,
            "{f:?}"
        );
        // Far beyond the device: the largest command is ±4095, the rest scaled with it.
        let (cmd, saturated) = motor_commands_scaled(torques(&j, [0.0, 100.0, 0.0]));
        assert!(saturated);
        assert!(cmd.iter().all(|c| c.abs() <= MAX_COMMAND), "{cmd:?}");
        assert!(cmd.iter().any(|c| c.abs() == MAX_COMMAND), "{cmd:?}");
        assert!(!motor_commands_scaled(torques(&j, [0.0, 1.0, 0.0])).1);
        assert_eq!(motor_commands([f64::NAN, 0.0, 0.0])[0], 0);
    }

    fn angle_deg(a: Vec3, b: Vec3) -> f64 {
        let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let n = |v: Vec3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (dot / (n(a) * n(b))).clamp(-1.0, 1.0).acos().to_degrees()
    }

    proptest::proptest! {
        /// Anywhere in the workspace, any force up to 60 N: whenever a motor
        /// saturates, the applied torques point along Jᵀ·F and the force they
        /// make along F; no command ever exceeds ±4095.
        #[test]
        fn saturation_keeps_the_force_direction(
            fx in 0.0f64..1.0, fy in 0.0f64..1.0, fz in 0.0f64..1.0,
            dx in -1.0f64..1.0, dy in -1.0f64..1.0, dz in -1.0f64..1.0,
            magnitude in 0.1f64..60.0,
        ) {
            let p = [
                FALCON_MIN_M[0] + fx * (FALCON_MAX_M[0] - FALCON_MIN_M[0]),
                FALCON_MIN_M[1] + fy * (FALCON_MAX_M[1] - FALCON_MIN_M[1]),
                FALCON_MIN_M[2] + fz * (FALCON_MAX_M[2] - FALCON_MIN_M[2]),
            ];
            let n = (dx * dx + dy * dy + dz * dz).sqrt();
            proptest::prop_assume!(n > 0.05);
            let Ok(a) = inverse(p) else { return Ok(()) };
            let j = jacobian(&a).unwrap();
            let f = [dx / n * magnitude, dy / n * magnitude, dz / n * magnitude];
            let tau = torques(&j, f);
            let (cmd, saturated) = motor_commands_scaled(tau);
            proptest::prop_assert!(cmd.iter().all(|c| c.abs() <= MAX_COMMAND), "{:?}", cmd);
            let peak = tau.iter().fold(0.0f64, |m, t| m.max((COMMAND_PER_NM * t).abs()));
            proptest::prop_assert_eq!(saturated, peak > f64::from(MAX_COMMAND));
            if saturated {
                proptest::prop_assert!(cmd.iter().any(|c| c.abs() == MAX_COMMAND), "{:?}", cmd);
                let applied = torques_of_commands(cmd);
                let t_err = angle_deg(applied, tau);
                proptest::prop_assert!(t_err < 0.05, "torques bent by {}° at {:?}", t_err, p);
                let f_applied = force_of_torques(&j, applied).unwrap();
                let f_err = angle_deg(f_applied, f);
                proptest::prop_assert!(f_err < 0.5, "force bent by {}° at {:?}", f_err, p);
            }
        }
    }

    #[test]
    fn clamping_each_motor_alone_would_bend_the_force() {
        // The case the scaling exists for: one motor far past the limit, the
        // others not. Clamped one by one, the force would turn by degrees.
        let a = inverse([0.0, 0.0, 0.11]).unwrap();
        let j = jacobian(&a).unwrap();
        let f = [20.0, 5.0, 0.0];
        let tau = torques(&j, f);
        let clamped = tau.map(|t| {
            let m = f64::from(MAX_COMMAND);
            -(-COMMAND_PER_NM * t).clamp(-m, m) / COMMAND_PER_NM
        });
        let bent = angle_deg(force_of_torques(&j, clamped).unwrap(), f);
        assert!(bent > 1.0, "{bent}");
        let (cmd, saturated) = motor_commands_scaled(tau);
        assert!(saturated);
        let kept = angle_deg(force_of_torques(&j, torques_of_commands(cmd)).unwrap(), f);
        assert!(kept < 0.1, "{kept}");
    }

    #[test]
    fn encoder_counts_round_trip() {
        assert!((degrees_per_count() - 0.036435).abs() < 1e-5);
        for c in [-3000i16, -1, 0, 1, 2500] {
            let th = angle_of_count(c, 35.0);
            assert_eq!(count_of_angle(th, 35.0), c);
        }
        assert!((angle_of_count(0, 35.0).to_degrees() - 35.0).abs() < 1e-12);
    }

    #[test]
    fn warm_started_fk_takes_few_steps_at_stroke_speed() {
        let mut solver = ForwardSolver::new();
        let mut worst = 0;
        // 1 cm/s (the thesis's stroke) and 10 cm/s (a fast transit), 1 kHz.
        for speed in [0.01, 0.1] {
            let dt = 0.001;
            let mut p: Vec3 = [-0.045, 0.01, 0.14];
            solver.reset();
            for step in 0..900 {
                p[0] += speed * dt;
                p[1] = 0.01 + 0.001 * (p[0] * 2000.0).sin();
                let a = inverse(p).unwrap();
                let s = solver.solve(a.theta1).unwrap();
                assert!(dist(s.p, p) < 1e-9);
                if step > 0 {
                    worst = worst.max(s.iterations);
                }
            }
        }
        assert!(worst <= 4, "{worst} iterations");
    }

    #[test]
    fn unreachable_points_are_refused() {
        assert!(inverse([0.0, 0.0, 0.5]).is_err());
        assert!(!in_workspace([0.0, 0.0, 0.2]));
        assert!(in_workspace([0.0, 0.0, 0.12]));
    }
}
