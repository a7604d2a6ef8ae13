//! `[controller]`: Eq. 3.1's spring–damper law and its force clamp. Schema
//! and checks only.

use serde::{Deserialize, Serialize};

use super::device::DEVICE_MAX_FORCE_N;
use super::{Invalid, bad, finite_nonneg, finite_pos};

/// Eq. 3.1's spring–damper law, per axis, in SI units.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Controller {
    pub stiffness_n_per_m: [f64; 3],
    pub damping_n_s_per_m: [f64; 3],
    /// Per-axis clamp on the commanded force.
    pub force_limit_n: f64,
}

/// Check `[controller]`.
pub(super) fn validate(c: &Controller) -> Result<(), Invalid> {
    for i in 0..3 {
        finite_nonneg(
            &format!("controller.stiffness_n_per_m[{i}]"),
            c.stiffness_n_per_m[i],
        )?;
        finite_nonneg(
            &format!("controller.damping_n_s_per_m[{i}]"),
            c.damping_n_s_per_m[i],
        )?;
    }
    finite_pos("controller.force_limit_n", c.force_limit_n)?;
    if c.force_limit_n > DEVICE_MAX_FORCE_N {
        return bad(
            "controller.force_limit_n",
            format!(
                "{} N exceeds the device's {} N",
                c.force_limit_n, DEVICE_MAX_FORCE_N
            ),
        );
    }
    Ok(())
}
