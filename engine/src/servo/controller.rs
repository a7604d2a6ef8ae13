//! Eq. 3.1's spring–damper position law and the checks every command passes.
//!
//! As printed, Eq. 3.1 adds `+D·Δ(p − f)/Δt`: with F = −K(p − f) that term
//! pushes along the velocity, an anti-damper. We use the physical sign,
//! F = −K(p − f) − D·Δ(p − f)/Δt, which is what gives the under-damped
//! second-order response of Eqs. 3.2–3.3 the thesis describes.

/// Why a command cannot be sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NonFinite;

pub struct SpringDamper {
    stiffness: [f64; 3],
    damping: [f64; 3],
    limit: f64,
    prev_err: Option<[f64; 3]>,
}

impl SpringDamper {
    pub fn new(stiffness: [f64; 3], damping: [f64; 3], limit: f64) -> SpringDamper {
        SpringDamper {
            stiffness,
            damping,
            limit,
            prev_err: None,
        }
    }

    /// Forget the previous error (after a pause), so the damper does not kick.
    pub fn reset(&mut self) {
        self.prev_err = None;
    }

    /// The force towards `setpoint` for the measured `pos`, `dt` seconds after
    /// the previous call, clamped per axis to the force limit.
    pub fn force(
        &mut self,
        pos: [f64; 3],
        setpoint: [f64; 3],
        dt: f64,
    ) -> Result<[f64; 3], NonFinite> {
        let mut f = [0.0; 3];
        let mut err = [0.0; 3];
        for a in 0..3 {
            err[a] = pos[a] - setpoint[a];
            let rate = match self.prev_err {
                Some(prev) if dt > 0.0 => (err[a] - prev[a]) / dt,
                _ => 0.0,
            };
            f[a] = -self.stiffness[a] * err[a] - self.damping[a] * rate;
        }
        self.prev_err = Some(err);
        clamp_force(f, self.limit)
    }
}

/// Clamp each axis to ±limit; a non-finite component is an error, never sent.
pub fn clamp_force(f: [f64; 3], limit: f64) -> Result<[f64; 3], NonFinite> {
    let mut out = [0.0; 3];
    for a in 0..3 {
        if !f[a].is_finite() {
            return Err(NonFinite);
        }
        out[a] = f[a].clamp(-limit, limit);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spring_pulls_towards_the_setpoint_and_damper_opposes_motion() {
        let mut c = SpringDamper::new([100.0; 3], [10.0; 3], 8.0);
        let f = c.force([0.01, 0.0, 0.0], [0.0; 3], 0.001).unwrap();
        assert_eq!(f, [-1.0, 0.0, 0.0]);
        // Moving further away at 1 m/s: the damper adds −10 N, clamped to −8.
        let f = c.force([0.011, 0.0, 0.0], [0.0; 3], 0.001).unwrap();
        assert_eq!(f[0], -8.0);
        // Moving back towards the set-point: the damper brakes (positive force).
        let mut c = SpringDamper::new([0.0; 3], [10.0; 3], 8.0);
        c.force([0.01, 0.0, 0.0], [0.0; 3], 0.001).unwrap();
        let f = c.force([0.0099, 0.0, 0.0], [0.0; 3], 0.001).unwrap();
        assert!((f[0] - 1.0).abs() < 1e-9, "{f:?}");
    }

    #[test]
    fn non_finite_forces_never_pass() {
        assert_eq!(clamp_force([f64::NAN, 0.0, 0.0], 8.0), Err(NonFinite));
        assert_eq!(clamp_force([0.0, f64::INFINITY, 0.0], 8.0), Err(NonFinite));
        assert_eq!(clamp_force([9.0, -9.0, 1.0], 8.0), Ok([8.0, -8.0, 1.0]));
        let mut c = SpringDamper::new([1.0; 3], [1.0; 3], 8.0);
        assert_eq!(
            c.force([f64::NAN, 0.0, 0.0], [0.0; 3], 0.001),
            Err(NonFinite)
        );
    }
}
