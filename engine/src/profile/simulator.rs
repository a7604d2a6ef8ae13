//! `[simulator]`: the physical model behind `device.kind = "sim"` — the
//! mechanism, the probe, the contact, the encoder, the timing jitter — and
//! its injected faults (`[simulator.faults]`, in `hardware`). Schema and
//! checks only; the model itself is `crate::device::sim`.

use serde::{Deserialize, Serialize};

use super::hardware;
use super::{Invalid, bad, finite_nonneg, finite_pos};

/// The physical model behind `device.kind = "sim"`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Simulator {
    pub seed: u64,
    /// Effective moving mass of the end effector, per axis.
    pub mass_kg: f64,
    /// Weight the mechanism does not balance (the probe mount), pulling −y.
    pub unbalanced_weight_n: f64,
    /// Viscous friction of the mechanism.
    pub mechanism_damping_n_s_per_m: f64,
    pub probe_diameter_m: f64,
    /// Height of the sphere centre when it rests on the texture's crests.
    pub surface_top_y_m: f64,
    /// Where along x the texture's first period starts (before placement jitter).
    pub surface_origin_x_m: f64,
    /// Each scan's texture is shifted by a uniform random amount up to this (re-mounting).
    pub placement_jitter_m: f64,
    pub contact_stiffness_n_per_m: f64,
    pub contact_damping_n_s_per_m: f64,
    pub friction_coefficient: f64,
    /// Encoder resolution (the Falcon's 400 dpi ≈ 0.0635 mm).
    pub encoder_resolution_m: f64,
    pub position_noise_m: f64,
    /// Per-tick chance that the USB exchange slips by up to a quarter period
    /// (the thesis's loop ran at 800–1000 Hz); virtual time only.
    pub period_jitter_fraction: f64,
    /// Standard deviation of the ordinary tick-time jitter; virtual time only.
    pub period_jitter_s: f64,
    /// Physics sub-steps per servo tick.
    pub substeps: u32,
    /// Injected faults (`[simulator.faults]`, device.kind = "sim" only).
    #[serde(skip_serializing_if = "is_default_faults")]
    pub faults: hardware::SimFaults,
}

fn is_default_faults(f: &hardware::SimFaults) -> bool {
    *f == hardware::SimFaults::default()
}

impl Default for Simulator {
    fn default() -> Self {
        Simulator {
            seed: 1,
            mass_kg: 0.06,
            unbalanced_weight_n: 0.216,
            mechanism_damping_n_s_per_m: 0.5,
            probe_diameter_m: 0.002,
            surface_top_y_m: -0.0038,
            surface_origin_x_m: -0.045,
            placement_jitter_m: 0.01,
            contact_stiffness_n_per_m: 3000.0,
            contact_damping_n_s_per_m: 3.0,
            friction_coefficient: 0.3,
            encoder_resolution_m: 0.0000635,
            position_noise_m: 0.00001,
            period_jitter_fraction: 0.1,
            period_jitter_s: 0.000_02,
            substeps: 4,
            faults: hardware::SimFaults::default(),
        }
    }
}

/// Check `[simulator]` (its period jitter against the servo rate).
pub(super) fn validate(s: &Simulator, rate_hz: Option<f64>) -> Result<(), Invalid> {
    finite_pos("simulator.mass_kg", s.mass_kg)?;
    finite_nonneg("simulator.unbalanced_weight_n", s.unbalanced_weight_n)?;
    finite_nonneg(
        "simulator.mechanism_damping_n_s_per_m",
        s.mechanism_damping_n_s_per_m,
    )?;
    finite_pos("simulator.probe_diameter_m", s.probe_diameter_m)?;
    if s.probe_diameter_m > 0.02 {
        return bad("simulator.probe_diameter_m", "must be at most 20 mm");
    }
    if !s.surface_top_y_m.is_finite() {
        return bad("simulator.surface_top_y_m", "must be a number");
    }
    if !s.surface_origin_x_m.is_finite() {
        return bad("simulator.surface_origin_x_m", "must be a number");
    }
    finite_nonneg("simulator.placement_jitter_m", s.placement_jitter_m)?;
    finite_pos(
        "simulator.contact_stiffness_n_per_m",
        s.contact_stiffness_n_per_m,
    )?;
    finite_nonneg(
        "simulator.contact_damping_n_s_per_m",
        s.contact_damping_n_s_per_m,
    )?;
    finite_nonneg("simulator.friction_coefficient", s.friction_coefficient)?;
    if s.friction_coefficient > 2.0 {
        return bad("simulator.friction_coefficient", "must be at most 2");
    }
    finite_nonneg("simulator.encoder_resolution_m", s.encoder_resolution_m)?;
    finite_nonneg("simulator.position_noise_m", s.position_noise_m)?;
    if !(0.0..=1.0).contains(&s.period_jitter_fraction) {
        return bad("simulator.period_jitter_fraction", "must be in [0, 1]");
    }
    finite_nonneg("simulator.period_jitter_s", s.period_jitter_s)?;
    if rate_hz.is_some_and(|rate_hz| s.period_jitter_s * rate_hz > 0.2) {
        return bad(
            "simulator.period_jitter_s",
            "must be under a fifth of the servo period",
        );
    }
    if !(1..=64).contains(&s.substeps) {
        return bad("simulator.substeps", "must be from 1 to 64");
    }
    Ok(())
}
