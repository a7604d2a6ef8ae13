//! Guards the servo loop runs on every tick while it drives the probe:
//! each watches one way the motion can go wrong that no single reading
//! shows, and says why the motion must stop. They never act themselves.
//!
//! - [`FollowingGuard`]: the probe stays far from its set-point while the
//!   controller pushes it there. The commanded force is not moving it: the
//!   Falcon's motors have lost their wall power (USB and the encoders keep
//!   working without it), or something holds the probe.
//! - [`IntervalGuard`]: ticks come too far apart for the controller's
//!   gains. Eq. 3.1 sampled every `h` seconds and held (the force stays
//!   until the next tick) on a mass `m` has the characteristic polynomial
//!   z³ + (α(K + D/h) − 2)z² + (1 + αK)z − αD/h, α = h²/2m; Jury's test
//!   gives the longest stable `h` (3.8 ms for the thesis's 2400 N/m and
//!   7.2 N·s/m on 0.06 kg). Late ticks need not be consecutive to drive the
//!   loop into a limit cycle at the force limit, so the guard counts them
//!   over a window, and stops the motion when too many are too late.

/// How far from its set-point (along one axis) the probe must be, with how
/// much force pushing it back along that axis, for how long without moving
/// as far along any axis, before the motion stops. A thesis scan stays far inside both bounds (its largest
/// errors are the ~1 mm it presses into the texture, along the soft y axis
/// where 1 mm asks for 0.27 N, and lags of ~0.5 mm at leg changes); with
/// the motors dead, the set-point walks away from the probe at the path's
/// speed (1 cm/s while stroking), so the bound is met ~100 ms after the
/// power goes and the motion stops ~100 ms later.
pub const FOLLOW_ERROR_M: f64 = 0.001;
pub const FOLLOW_FORCE_N: f64 = 2.0;
pub const FOLLOW_TIME_S: f64 = 0.1;

/// The Falcon's moving mass at the grip (the simulator's, after the thesis
/// profile): what the stability bound of [`IntervalGuard`] assumes.
pub const PROBE_MASS_KG: f64 = 0.06;
/// Of the last `INTERVAL_WINDOW` tick intervals, `[device]
/// late_tick_limit` (by default `INTERVAL_LATE_LIMIT`) longer than the
/// stable bound stop the motion (one stall is ridden out; a starved CPU
/// that keeps coming back late is not).
pub const INTERVAL_WINDOW: usize = crate::profile::device::LATE_TICK_WINDOW;
pub const INTERVAL_LATE_LIMIT: u32 = crate::profile::device::DEFAULT_LATE_TICK_LIMIT;

/// Whether Eq. 3.1 with stiffness `k` and damping `d`, sampled every `h`
/// seconds on mass `m`, is stable (Jury's test on the cubic above).
pub fn stable(h: f64, m: f64, k: f64, d: f64) -> bool {
    let alpha = h * h / (2.0 * m);
    let a2 = alpha * (k + d / h) - 2.0;
    let a1 = 1.0 + alpha * k;
    let a0 = -alpha * d / h;
    1.0 + a2 + a1 + a0 > 0.0
        && 1.0 - a2 + a1 - a0 > 0.0
        && a0.abs() < 1.0
        && (a0 * a0 - 1.0).abs() > (a0 * a2 - a1).abs()
}

/// The longest stable tick interval for the gains (the shortest over the
/// axes), seconds; 0 when none is (a spring without damping).
pub fn longest_stable_period(m: f64, k: [f64; 3], d: [f64; 3]) -> f64 {
    (0..3)
        .map(|a| {
            if k[a] <= 0.0 {
                return f64::INFINITY;
            }
            // Grow h until unstable: 1 % steps from 10 µs (cheap, once).
            let mut h = 1e-5;
            while h < 1.0 && stable(h * 1.01, m, k[a], d[a]) {
                h *= 1.01;
            }
            if stable(h, m, k[a], d[a]) { h } else { 0.0 }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Watches the interval between ticks (see the module's documentation).
#[derive(Debug)]
pub struct IntervalGuard {
    bound_s: f64,
    late: [bool; INTERVAL_WINDOW],
    saturated: [bool; INTERVAL_WINDOW],
    next: usize,
    count: u32,
    count_saturated: u32,
    /// Late (and saturated) ticks of the window that stop the motion.
    limit: u32,
}

impl IntervalGuard {
    pub fn new(stiffness: [f64; 3], damping: [f64; 3], limit: u32) -> IntervalGuard {
        IntervalGuard {
            limit,
            bound_s: longest_stable_period(PROBE_MASS_KG, stiffness, damping),
            late: [false; INTERVAL_WINDOW],
            saturated: [false; INTERVAL_WINDOW],
            next: 0,
            count: 0,
            count_saturated: 0,
        }
    }

    /// The longest stable interval, seconds.
    pub fn bound_s(&self) -> f64 {
        self.bound_s
    }

    pub fn reset(&mut self) {
        self.late = [false; INTERVAL_WINDOW];
        self.saturated = [false; INTERVAL_WINDOW];
        self.count = 0;
        self.count_saturated = 0;
    }

    /// One tick `dt` after the last, while driving, the force at its limit
    /// or not: why the motion must stop. Late ticks alone only slow the
    /// path; late ticks while the force keeps hitting its limit are the
    /// limit cycle starting.
    pub fn check(&mut self, dt: f64, saturated: bool) -> Option<String> {
        let late = dt > self.bound_s;
        let i = self.next;
        self.count = self.count + u32::from(late) - u32::from(self.late[i]);
        self.count_saturated =
            self.count_saturated + u32::from(saturated) - u32::from(self.saturated[i]);
        self.late[i] = late;
        self.saturated[i] = saturated;
        self.next = (self.next + 1) % INTERVAL_WINDOW;
        if self.count < self.limit || self.count_saturated < self.limit {
            return None;
        }
        let message = format!(
            "{} of the last {INTERVAL_WINDOW} ticks came more than {:.1} ms apart (the last {:.1} ms), too far apart for the controller's gains, and the force kept hitting its limit (an oscillation starting): motion stopped, forces off; give the servo loop a core (close other programs; allow real-time scheduling: see `hapticlab doctor`) or lower [controller] stiffness_n_per_m",
            self.count,
            self.bound_s * 1000.0,
            dt * 1000.0
        );
        self.reset();
        Some(message)
    }
}

/// Watches the following error (see the module's documentation).
#[derive(Debug, Default)]
pub struct FollowingGuard {
    /// Loop time the probe was first found far while pushed, and the
    /// largest error and force seen since.
    since: Option<f64>,
    worst_m: f64,
    worst_n: f64,
    /// Where the probe was when the episode began.
    start: [f64; 3],
}

impl FollowingGuard {
    /// Forget the episode (the motion stopped or the mode changed).
    pub fn reset(&mut self) {
        *self = FollowingGuard::default();
    }

    /// One tick of a driven probe at `pos` towards `setpoint` with `force`
    /// commanded: why the motion must stop, when it must.
    pub fn check(
        &mut self,
        now: f64,
        pos: [f64; 3],
        setpoint: [f64; 3],
        force: [f64; 3],
    ) -> Option<String> {
        let mut far = None;
        for a in 0..3 {
            let err = pos[a] - setpoint[a];
            // Pushed back towards the set-point, hard, and still far from it.
            let pushed = force[a] * err < 0.0 && force[a].abs() >= FOLLOW_FORCE_N;
            if pushed && err.abs() >= FOLLOW_ERROR_M {
                far = Some((err.abs(), force[a].abs()));
            }
        }
        let Some((err, f)) = far else {
            self.reset();
            return None;
        };
        if self.since.is_none() {
            self.since = Some(now);
            self.start = pos;
        }
        let since = self.since.unwrap_or(now);
        // A probe that moves is following, however far behind (a glide
        // saturating the force after homing); a dead motor moves nothing.
        let moved = (0..3).any(|a| (pos[a] - self.start[a]).abs() >= FOLLOW_ERROR_M);
        if moved {
            self.since = Some(now);
            self.start = pos;
            return None;
        }
        self.worst_m = self.worst_m.max(err);
        self.worst_n = self.worst_n.max(f);
        if now - since < FOLLOW_TIME_S {
            return None;
        }
        let message = format!(
            "the probe stayed {:.1} mm from its set-point for {:.0} ms while {:.1} N pushed it back: the motors are not moving it (their power is off, or something holds the probe); check the Falcon's power supply",
            self.worst_m * 1000.0,
            (now - since) * 1000.0,
            self.worst_n
        );
        self.reset();
        Some(message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thesis_gains_are_stable_below_about_4_ms() {
        let h = longest_stable_period(0.06, [2400.0, 270.0, 2400.0], [7.2, 2.4, 7.2]);
        assert!((0.0036..0.0040).contains(&h), "{h}");
        // Without damping the sampled spring is never stable.
        assert_eq!(longest_stable_period(0.06, [2400.0; 3], [0.0; 3]), 0.0);
        // Simulated: at 0.9 h the error decays, at 1.1 h it grows.
        let run = |h: f64| {
            let (m, k, d) = (0.06, 2400.0, 7.2);
            let (mut x, mut v, mut prev) = (0.001f64, 0.0f64, 0.001f64);
            for _ in 0..((2.0 / h) as usize) {
                let f = -k * x - d * (x - prev) / h;
                prev = x;
                // Exact motion under a held force over h.
                x += v * h + f / m * h * h / 2.0;
                v += f / m * h;
            }
            x.abs()
        };
        assert!(run(0.9 * h) < 1e-4, "{}", run(0.9 * h));
        assert!(run(1.1 * h) > 1e-2, "{}", run(1.1 * h));
    }

    #[test]
    fn scattered_late_ticks_trip_the_interval_guard_and_one_stall_does_not() {
        let mut g = IntervalGuard::new(
            [2400.0, 270.0, 2400.0],
            [7.2, 2.4, 7.2],
            INTERVAL_LATE_LIMIT,
        );
        // One 20 ms stall, then half-period catch-up: fine.
        assert_eq!(g.check(0.020, true), None);
        for _ in 0..1000 {
            assert_eq!(g.check(0.0005, true), None);
            assert_eq!(g.check(0.001, true), None);
        }
        // A starved CPU alone, the force well inside its limit: no trip
        // (a guard of its own, so no saturated tick from above is in its window).
        let mut g = IntervalGuard::new(
            [2400.0, 270.0, 2400.0],
            [7.2, 2.4, 7.2],
            INTERVAL_LATE_LIMIT,
        );
        for k in 0..1000 {
            let dt = if k % 4 == 0 { 0.006 } else { 0.001 };
            assert_eq!(g.check(dt, false), None);
        }
        // One tick in eight comes 6 ms late: not consecutive, still tripped.
        let mut tripped = None;
        for k in 0..200 {
            let dt = if k % 8 == 0 { 0.006 } else { 0.001 };
            if let Some(m) = g.check(dt, true) {
                tripped = Some((k, m));
                break;
            }
        }
        let (k, m) = tripped.expect("the guard trips");
        assert!(k < 100, "{k}");
        assert!(
            m.contains("too far apart for the controller's gains"),
            "{m}"
        );
    }

    #[test]
    fn a_probe_that_follows_never_trips_and_one_held_back_does() {
        let mut g = FollowingGuard::default();
        // 0.9 mm behind with 2.2 N: close enough, for any time.
        for k in 0..1000 {
            let t = f64::from(k) * 0.001;
            assert_eq!(
                g.check(t, [0.0; 3], [0.0009, 0.0, 0.0], [2.2, 0.0, 0.0]),
                None
            );
        }
        // Far, but not pushed back hard (a soft axis): no trip either.
        for k in 0..1000 {
            let t = 1.0 + f64::from(k) * 0.001;
            assert_eq!(
                g.check(t, [0.0; 3], [0.0, 0.005, 0.0], [0.0, 1.35, 0.0]),
                None
            );
        }
        // A probe that moves, even far behind and pushed hard: no trip.
        for k in 0..1000 {
            let t = 1.5 + f64::from(k) * 0.001;
            let p = [0.05 * (t - 1.5), 0.0, 0.0];
            assert_eq!(g.check(t, p, [0.07, 0.0, 0.0], [8.0, 0.0, 0.0]), None);
        }
        // The set-point walks away at 1 cm/s from a probe that does not move.
        let mut tripped = None;
        for k in 0..1000 {
            let t = 2.0 + f64::from(k) * 0.001;
            let sp = 0.01 * (t - 2.0);
            if let Some(m) = g.check(t, [0.0; 3], [sp, 0.0, 0.0], [2400.0 * sp, 0.0, 0.0]) {
                tripped = Some((t - 2.0, m));
                break;
            }
        }
        let (after, m) = tripped.expect("the guard trips");
        assert!((0.19..0.22).contains(&after), "{after}");
        assert!(m.contains("check the Falcon's power supply"), "{m}");
        // A force pushing away from the set-point is not the guard's.
        g.reset();
        for k in 0..1000 {
            let t = 3.0 + f64::from(k) * 0.001;
            assert_eq!(
                g.check(t, [0.0; 3], [0.005, 0.0, 0.0], [-3.0, 0.0, 0.0]),
                None
            );
        }
    }
}
