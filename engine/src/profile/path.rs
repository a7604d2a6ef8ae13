//! `[path]`: the waypoints the probe follows, its speeds, the scan leg and
//! the dwell; checked against the workspace every device kind can reach.
//! Schema and checks only.

use serde::{Deserialize, Serialize};

use super::device::{WORKSPACE_MAX_M, WORKSPACE_MIN_M};
use super::{Invalid, bad, dist, finite_nonneg};

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// Waypoints (x, y, z) in metres; the probe starts held at the first.
    pub waypoints_m: Vec<[f64; 3]>,
    /// Set-point speed along the path, m/s.
    pub speed_m_per_s: f64,
    /// Set-point speed on the other legs (default: `speed_m_per_s`).
    #[serde(default)]
    pub transit_speed_m_per_s: Option<f64>,
    /// The scan leg, 1-based: leg N runs from waypoint N to waypoint N+1.
    pub scan_leg: usize,
    /// Time held at the end of the scan leg, still recorded, so the probe settles.
    #[serde(default)]
    pub dwell_s: f64,
}

/// Check `[path]`.
pub(super) fn validate(p: &PathSpec) -> Result<(), Invalid> {
    if p.waypoints_m.len() < 2 {
        return bad("path.waypoints_m", "needs at least two waypoints");
    }
    for (i, w) in p.waypoints_m.iter().enumerate() {
        for a in 0..3 {
            if !w[a].is_finite() || w[a] < WORKSPACE_MIN_M[a] || w[a] > WORKSPACE_MAX_M[a] {
                return bad(
                    format!("path.waypoints_m[{i}]"),
                    format!(
                        "waypoint {} ({:.4}, {:.4}, {:.4}) m is outside the device's workspace: {} must lie in [{}, {}] m",
                        i + 1,
                        w[0],
                        w[1],
                        w[2],
                        ["x", "y", "z"][a],
                        WORKSPACE_MIN_M[a],
                        WORKSPACE_MAX_M[a]
                    ),
                );
            }
        }
    }
    if !(p.speed_m_per_s.is_finite() && p.speed_m_per_s > 0.0 && p.speed_m_per_s <= 0.5) {
        return bad(
            "path.speed_m_per_s",
            format!("must be in (0, 0.5] m/s, got {}", p.speed_m_per_s),
        );
    }
    if let Some(v) = p.transit_speed_m_per_s
        && !(v.is_finite() && v > 0.0 && v <= 0.5)
    {
        return bad(
            "path.transit_speed_m_per_s",
            format!("must be in (0, 0.5] m/s, got {v}"),
        );
    }
    if p.scan_leg == 0 || p.scan_leg >= p.waypoints_m.len() {
        return bad(
            "path.scan_leg",
            format!(
                "must name a leg from 1 to {} (leg N runs from waypoint N to N+1), got {}",
                p.waypoints_m.len() - 1,
                p.scan_leg
            ),
        );
    }
    finite_nonneg("path.dwell_s", p.dwell_s)?;
    let a0 = p.waypoints_m[p.scan_leg - 1];
    let a1 = p.waypoints_m[p.scan_leg];
    let leg_len = dist(a0, a1);
    if leg_len <= 0.0 {
        return bad("path.scan_leg", "the scan leg has zero length");
    }
    Ok(())
}
