//! The simulated Falcon: a physical model of the end effector and the texture.
//!
//! A point mass (the effective moving mass of the delta mechanism and the
//! probe) under the commanded force, the unbalanced weight of the probe mount
//! (−y), viscous friction of the mechanism, stiff walls at the workspace's
//! edge, and contact with the texture: penalty contact of the sphere's centre
//! against the sphere-dilated surface (compliant cardboard: stiffness and
//! damping), with regularised Coulomb friction against the sliding velocity.
//! The reading carries encoder quantisation and position noise; the applied
//! force saturates at the device's limit. Integration is semi-implicit Euler
//! with sub-steps, advanced to whatever time the caller reads at, so the same
//! model runs in virtual time (datasets) and real time (live use).
//!
//! Faults on demand (`[simulator.faults]`): a failed read, reads that stall
//! (handed to the servo loop's clock through `take_stall`), a NaN position,
//! and vanishing for good, each at a given loop time.
//!
//! Deterministic from its seed. Never sleeps, never allocates after `new`
//! (but for the message of an injected fault).

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::surface::{ProbeTrace, SurfaceError};
use super::{DeviceError, HapticDevice, Reading};
use crate::profile::hardware::SimFaults;
use crate::profile::{DEVICE_MAX_FORCE_N, Profile, Simulator, WORKSPACE_MAX_M, WORKSPACE_MIN_M};

/// Sliding speed below which Coulomb friction is scaled down (regularisation), m/s.
const FRICTION_V_EPS: f64 = 0.001;
/// The mechanism's end stops, a little outside the workspace.
const STOP_MARGIN_M: f64 = 0.005;
const STOP_STIFFNESS_N_PER_M: f64 = 20_000.0;
const GRAVITY: f64 = 9.81;

pub struct SimDevice {
    p: Simulator,
    trace: Option<ProbeTrace>,
    pos: [f64; 3],
    vel: [f64; 3],
    force: [f64; 3],
    /// An external push (the user's hand, in manual mode), newtons.
    hand: [f64; 3],
    t: f64,
    max_step: f64,
    rng: ChaCha8Rng,
    noise: Normal<f64>,
    /// Contact force last applied by the texture (for tests and display).
    contact: [f64; 3],
    faults: FaultState,
}

/// Where the injected faults (`[simulator.faults]`) stand.
#[derive(Debug, Clone, Default)]
struct FaultState {
    read_error_done: bool,
    nan_done: bool,
    stalls_done: u32,
    stall: Option<std::time::Duration>,
    /// Set once the device has vanished: what every call says from then on.
    vanished: Option<String>,
}

impl SimDevice {
    /// A simulated Falcon resting at the path's first waypoint, stroking the
    /// texture `texture` (a label from the profile), or free air when `None`.
    pub fn new(
        profile: &Profile,
        base_dir: &Path,
        texture: Option<&str>,
        seed: u64,
    ) -> Result<SimDevice, SimError> {
        let rig = profile.rig()?;
        let p = profile.simulator.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let trace = match texture {
            None => None,
            Some(label) => {
                let t = profile
                    .texture(label)
                    .ok_or_else(|| SimError::UnknownTexture {
                        label: label.to_string(),
                        known: profile.textures.iter().map(|t| t.label.clone()).collect(),
                    })?;
                let shift = if p.placement_jitter_m > 0.0 {
                    rand::Rng::random_range(&mut rng, 0.0..p.placement_jitter_m)
                } else {
                    0.0
                };
                Some(ProbeTrace::new(
                    &t.surface,
                    p.probe_diameter_m / 2.0,
                    p.surface_origin_x_m + shift,
                    p.surface_top_y_m,
                    (
                        WORKSPACE_MIN_M[0] - STOP_MARGIN_M,
                        WORKSPACE_MAX_M[0] + STOP_MARGIN_M,
                    ),
                    base_dir,
                    &mut rng,
                )?)
            }
        };
        let sigma = p.position_noise_m.max(0.0);
        let max_step = 1.0 / rig.device.rate_hz / f64::from(p.substeps.max(1));
        Ok(SimDevice {
            trace,
            pos: rig.path.waypoints_m[0],
            vel: [0.0; 3],
            force: [0.0; 3],
            hand: [0.0; 3],
            t: 0.0,
            max_step,
            rng,
            noise: Normal::new(0.0, sigma).expect("a finite, non-negative sigma"),
            contact: [0.0; 3],
            faults: FaultState::default(),
            p,
        })
    }

    /// The same simulator without injected faults (the emulated Falcon's
    /// physics: its faults are the emulator's own, `[falcon.emulator]`).
    pub fn without_faults(mut self) -> SimDevice {
        self.p.faults = SimFaults::default();
        self
    }

    /// The force last commanded and still applied (zero after `make_safe`), newtons.
    pub fn applied_force(&self) -> [f64; 3] {
        self.force
    }

    /// Push the probe by hand (manual mode): an external force, newtons.
    pub fn set_hand_force(&mut self, f: [f64; 3]) {
        self.hand = f;
    }

    /// The true (noise-free) position, for tests.
    pub fn true_position(&self) -> [f64; 3] {
        self.pos
    }

    /// The probe's true velocity, m/s.
    pub fn true_velocity(&self) -> [f64; 3] {
        self.vel
    }

    /// The force the texture last pushed back with, newtons.
    pub fn contact_force(&self) -> [f64; 3] {
        self.contact
    }

    /// The height the probe's centre rides at over the texture at `x`.
    pub fn surface_height(&self, x: f64) -> Option<f64> {
        self.trace.as_ref().map(|t| t.at(x).0)
    }

    fn step(&mut self, h: f64) {
        let m = self.p.mass_kg;
        let mut f = [0.0; 3];
        for (a, fa) in f.iter_mut().enumerate() {
            *fa = self.force[a] + self.hand[a] - self.p.mechanism_damping_n_s_per_m * self.vel[a];
            // End stops.
            let lo = WORKSPACE_MIN_M[a] - STOP_MARGIN_M;
            let hi = WORKSPACE_MAX_M[a] + STOP_MARGIN_M;
            if self.pos[a] < lo {
                *fa += STOP_STIFFNESS_N_PER_M * (lo - self.pos[a]) - 20.0 * self.vel[a].min(0.0);
            } else if self.pos[a] > hi {
                *fa -= STOP_STIFFNESS_N_PER_M * (self.pos[a] - hi) + 20.0 * self.vel[a].max(0.0);
            }
        }
        f[1] -= self.p.unbalanced_weight_n;
        self.contact = [0.0; 3];
        if let Some(trace) = &self.trace {
            let (surf, slope) = trace.at(self.pos[0]);
            let pen = surf - self.pos[1];
            if pen > 0.0 {
                let pen_rate = slope * self.vel[0] - self.vel[1];
                let normal_force = self.p.contact_stiffness_n_per_m * pen
                    + self.p.contact_damping_n_s_per_m * pen_rate;
                if normal_force > 0.0 {
                    let norm = (1.0 + slope * slope).sqrt();
                    let n = [-slope / norm, 1.0 / norm, 0.0];
                    let vn = self.vel[0] * n[0] + self.vel[1] * n[1];
                    let vt = [
                        self.vel[0] - vn * n[0],
                        self.vel[1] - vn * n[1],
                        self.vel[2],
                    ];
                    let speed = (vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]).sqrt();
                    let friction = if speed > 1e-12 {
                        self.p.friction_coefficient * normal_force * (speed / FRICTION_V_EPS).tanh()
                            / speed
                    } else {
                        0.0
                    };
                    for a in 0..3 {
                        let c = normal_force * n[a] - friction * vt[a];
                        self.contact[a] = c;
                        f[a] += c;
                    }
                }
            }
        }
        for ((v, p), fa) in self.vel.iter_mut().zip(self.pos.iter_mut()).zip(f) {
            *v += fa / m * h;
            *p += *v * h;
        }
    }
}

impl HapticDevice for SimDevice {
    fn kind(&self) -> &'static str {
        "sim"
    }

    fn read(&mut self, t_s: f64) -> Result<Reading, DeviceError> {
        if !t_s.is_finite() {
            return Err(DeviceError::BadReading(format!("time {t_s} is not finite")));
        }
        let due = |at: Option<f64>| at.is_some_and(|a| t_s >= a);
        if let Some(m) = &self.faults.vanished {
            return Err(DeviceError::Disconnected(m.clone()));
        }
        if due(self.p.faults.vanish_after_s) {
            let m = format!(
                "the simulated Falcon vanished at {t_s:.3} s, as `[simulator.faults] vanish_after_s` asks (a real one was unplugged or lost power: check its cable and power)"
            );
            self.faults.vanished = Some(m.clone());
            self.force = [0.0; 3];
            return Err(DeviceError::Disconnected(m));
        }
        let span = t_s - self.t;
        if span > 0.0 {
            let n = (span / self.max_step).ceil().max(1.0);
            let h = span / n;
            for _ in 0..n as u64 {
                self.step(h);
            }
            self.t = t_s;
        }
        let q = self.p.encoder_resolution_m;
        let mut pos = [0.0; 3];
        for (a, out) in pos.iter_mut().enumerate() {
            let noisy = self.pos[a] + self.noise.sample(&mut self.rng);
            *out = if q > 0.0 {
                (noisy / q).round() * q
            } else {
                noisy
            };
        }
        if pos.iter().any(|v| !v.is_finite()) {
            return Err(DeviceError::BadReading(
                "the simulated position diverged".into(),
            ));
        }
        if !self.faults.read_error_done && due(self.p.faults.read_error_after_s) {
            self.faults.read_error_done = true;
            return Err(DeviceError::Io(format!(
                "the simulated Falcon's read failed at {t_s:.3} s, as `[simulator.faults] read_error_after_s` asks (on a real one: check the USB cable and hub)"
            )));
        }
        if !self.faults.nan_done && due(self.p.faults.nan_after_s) {
            // The position is garbage, as from a device whose firmware misbehaves.
            self.faults.nan_done = true;
            pos[0] = f64::NAN;
        }
        if self.faults.stalls_done < self.p.faults.stalls && due(self.p.faults.stall_after_s) {
            self.faults.stalls_done += 1;
            self.faults.stall = Some(std::time::Duration::from_secs_f64(
                self.p.faults.stall_ms / 1000.0,
            ));
        }
        Ok(Reading {
            pos_m: pos,
            buttons: 0,
            homed: true,
        })
    }

    fn command(&mut self, force_n: [f64; 3]) -> Result<(), DeviceError> {
        if let Some(m) = &self.faults.vanished {
            return Err(DeviceError::Disconnected(m.clone()));
        }
        for (a, f) in force_n.iter().enumerate() {
            self.force[a] = if f.is_finite() {
                f.clamp(-DEVICE_MAX_FORCE_N, DEVICE_MAX_FORCE_N)
            } else {
                0.0
            };
        }
        Ok(())
    }

    fn make_safe(&mut self) {
        self.force = [0.0; 3];
    }

    fn take_stall(&mut self) -> Option<std::time::Duration> {
        self.faults.stall.take()
    }
}

/// Physics helpers the tests and the docs use.
impl SimDevice {
    /// Static sag of the probe under `stiffness_y` in free air, metres.
    pub fn free_air_sag(&self, stiffness_y: f64) -> f64 {
        self.p.unbalanced_weight_n / stiffness_y
    }
    /// The moving mass's weight equivalent, for documentation.
    pub fn mass_weight_n(&self) -> f64 {
        self.p.mass_kg * GRAVITY
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("the simulator has no texture {label:?}; the profile's textures are {known:?}")]
    UnknownTexture { label: String, known: Vec<String> },
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// An analysis-only profile: nothing to simulate.
    #[error(transparent)]
    NoRig(#[from] crate::profile::MissingRig),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::LoadedProfile;

    fn thesis() -> Profile {
        LoadedProfile::thesis().profile
    }

    /// Hold the probe with a plain spring–damper at `target` for `secs`.
    fn hold(
        dev: &mut SimDevice,
        target: [f64; 3],
        k: [f64; 3],
        d: [f64; 3],
        secs: f64,
    ) -> [f64; 3] {
        let dt = 0.001;
        let mut prev: Option<[f64; 3]> = None;
        let mut last = [0.0; 3];
        for i in 1..=(secs / dt) as usize {
            let r = dev.read(i as f64 * dt).unwrap();
            let mut f = [0.0; 3];
            for a in 0..3 {
                let e = r.pos_m[a] - target[a];
                let de = prev.map_or(0.0, |p| (e - (p[a] - target[a])) / dt);
                f[a] = -k[a] * e - d[a] * de;
            }
            prev = Some(r.pos_m);
            dev.command(f).unwrap();
            last = dev.true_position();
        }
        last
    }

    #[test]
    fn loaded_probe_sags_about_0_8_mm_in_free_air() {
        let p = thesis();
        let mut dev = SimDevice::new(&p, Path::new("."), None, 1).unwrap();
        let target = [0.0, 0.0, -0.02];
        let end = hold(
            &mut dev,
            target,
            p.rig().unwrap().controller.stiffness_n_per_m,
            p.rig().unwrap().controller.damping_n_s_per_m,
            3.0,
        );
        let sag = target[1] - end[1];
        assert!((sag - 0.0008).abs() < 0.0001, "sag {sag}");
        assert!((dev.free_air_sag(270.0) - 0.0008).abs() < 1e-9);
    }

    #[test]
    fn the_probe_rests_on_the_texture_and_presses_in() {
        let p = thesis();
        let mut dev = SimDevice::new(&p, Path::new("."), Some("S1"), 3).unwrap();
        // Set-point 1 mm below the crests: the probe stops on the surface, pressed in a little.
        let target = [0.0, -0.0048, -0.02];
        let end = hold(
            &mut dev,
            target,
            p.rig().unwrap().controller.stiffness_n_per_m,
            p.rig().unwrap().controller.damping_n_s_per_m,
            3.0,
        );
        let surf = dev.surface_height(end[0]).unwrap();
        let pen = surf - end[1];
        // Spring (270 N/m x ~1 mm) plus weight against 3000 N/m cardboard: ~0.15 mm in.
        assert!(pen > 0.00005 && pen < 0.0004, "penetration {pen}");
        assert!(dev.contact_force()[1] > 0.3, "{:?}", dev.contact_force());
    }

    #[test]
    fn readings_are_quantised_and_deterministic() {
        let p = thesis();
        let mut a = SimDevice::new(&p, Path::new("."), Some("S2"), 9).unwrap();
        let mut b = SimDevice::new(&p, Path::new("."), Some("S2"), 9).unwrap();
        for i in 1..100 {
            let t = i as f64 * 0.001;
            let ra = a.read(t).unwrap();
            assert_eq!(ra, b.read(t).unwrap());
            let q = p.simulator.encoder_resolution_m;
            for v in ra.pos_m {
                assert!(((v / q) - (v / q).round()).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn forces_saturate_and_non_finite_commands_are_dropped() {
        let p = thesis();
        let mut dev = SimDevice::new(&p, Path::new("."), None, 1).unwrap();
        dev.command([100.0, f64::NAN, -100.0]).unwrap();
        assert_eq!(dev.force, [DEVICE_MAX_FORCE_N, 0.0, -DEVICE_MAX_FORCE_N]);
        dev.make_safe();
        assert_eq!(dev.force, [0.0; 3]);
    }

    #[test]
    fn injected_faults_come_at_their_time() {
        let mut p = thesis();
        let f = &mut p.simulator.faults;
        f.read_error_after_s = Some(0.010);
        f.stall_after_s = Some(0.020);
        f.stall_ms = 5.0;
        f.stalls = 2;
        f.nan_after_s = Some(0.030);
        f.vanish_after_s = Some(0.040);
        let mut dev = SimDevice::new(&p, Path::new("."), None, 1).unwrap();
        let mut errors = Vec::new();
        let mut stalls = Vec::new();
        let mut nans = Vec::new();
        for i in 1..=50 {
            let t = i as f64 * 0.001;
            match dev.read(t) {
                Ok(r) if r.pos_m[0].is_nan() => nans.push(i),
                Ok(_) => {}
                Err(e) => errors.push((i, e)),
            }
            if let Some(d) = dev.take_stall() {
                assert_eq!(d, std::time::Duration::from_millis(5));
                stalls.push(i);
            }
            let _ = dev.command([1.0, 0.0, 0.0]);
        }
        assert_eq!(stalls, [20, 21]);
        assert_eq!(nans, [30]);
        assert!(matches!(errors[0], (10, DeviceError::Io(_))), "{errors:?}");
        // Gone for good from 40 ms: reads and commands fail, forces are zero.
        assert_eq!(errors.len(), 1 + 11, "{errors:?}");
        assert!(
            errors[1..]
                .iter()
                .all(|(i, e)| *i >= 40 && matches!(e, DeviceError::Disconnected(_)))
        );
        assert!(dev.command([1.0, 0.0, 0.0]).is_err());
        assert_eq!(dev.applied_force(), [0.0; 3]);
        // The emulated Falcon's physics carries none of them.
        let mut clean = SimDevice::new(&p, Path::new("."), None, 1)
            .unwrap()
            .without_faults();
        assert!((1..=50).all(|i| clean.read(i as f64 * 0.001).is_ok()));
        assert_eq!(clean.take_stall(), None);
    }

    #[test]
    fn unknown_textures_are_named() {
        let p = thesis();
        let e = SimDevice::new(&p, Path::new("."), Some("S9"), 1)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("S9") && e.contains("S1"), "{e}");
    }
}
