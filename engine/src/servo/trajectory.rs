//! The moving set-point: straight legs between waypoints at a set speed.
//!
//! A trajectory is built when a motion starts (that is the only allocation);
//! each tick advances it by the elapsed time and yields the set-point and
//! whether the probe is on the scan leg (or its dwell), which is recorded.

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    pub from: [f64; 3],
    pub to: [f64; 3],
    pub speed: f64,
    /// Recorded: the scan leg.
    pub scan: bool,
    /// Hold at the end of the leg, seconds.
    pub dwell: f64,
}

impl Leg {
    fn length(&self) -> f64 {
        crate::profile::dist(self.from, self.to)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    pub setpoint: [f64; 3],
    /// On the scan leg or in its dwell.
    pub scanning: bool,
    /// Progress through the scan leg and dwell, 0..=1 (0 before it starts).
    pub scan_progress: f64,
    pub done: bool,
}

pub struct Trajectory {
    legs: Vec<Leg>,
    leg: usize,
    along: f64,
    dwelt: f64,
    scan_leg_done: bool,
}

impl Trajectory {
    pub fn new(legs: Vec<Leg>) -> Trajectory {
        Trajectory {
            legs,
            leg: 0,
            along: 0.0,
            dwelt: 0.0,
            scan_leg_done: false,
        }
    }

    /// The profile's path, preceded by a transit from `from` to its first waypoint.
    pub fn for_path(path: &crate::profile::PathSpec, from: [f64; 3]) -> Trajectory {
        let transit = path.transit_speed_m_per_s.unwrap_or(path.speed_m_per_s);
        let mut legs = Vec::with_capacity(path.waypoints_m.len());
        let first = path.waypoints_m[0];
        if crate::profile::dist(from, first) > 1e-9 {
            legs.push(Leg {
                from,
                to: first,
                speed: transit,
                scan: false,
                dwell: 0.0,
            });
        }
        for (i, w) in path.waypoints_m.windows(2).enumerate() {
            let scan = i + 1 == path.scan_leg;
            legs.push(Leg {
                from: w[0],
                to: w[1],
                speed: if scan { path.speed_m_per_s } else { transit },
                scan,
                dwell: if scan { path.dwell_s } else { 0.0 },
            });
        }
        Trajectory::new(legs)
    }

    /// A single glide to `to` (target mode).
    pub fn glide(from: [f64; 3], to: [f64; 3], speed: f64) -> Trajectory {
        Trajectory::new(vec![Leg {
            from,
            to,
            speed,
            scan: false,
            dwell: 0.0,
        }])
    }

    pub fn has_scan(&self) -> bool {
        self.legs.iter().any(|l| l.scan)
    }

    /// Advance by `dt` seconds with the speeds scaled by `speed_scale`.
    pub fn advance(&mut self, dt: f64, speed_scale: f64) -> Step {
        let mut budget = dt.max(0.0);
        while self.leg < self.legs.len() {
            let leg = self.legs[self.leg];
            let len = leg.length();
            let speed = (leg.speed * speed_scale).max(1e-9);
            if self.along < len {
                let room = (len - self.along) / speed;
                if budget < room {
                    self.along += budget * speed;
                    break;
                }
                budget -= room;
                self.along = len;
            }
            if self.dwelt < leg.dwell {
                let room = leg.dwell - self.dwelt;
                if budget < room {
                    self.dwelt += budget;
                    break;
                }
                budget -= room;
                self.dwelt = leg.dwell;
            }
            if leg.scan {
                self.scan_leg_done = true;
            }
            self.leg += 1;
            self.along = 0.0;
            self.dwelt = 0.0;
        }
        self.current()
    }

    pub fn current(&self) -> Step {
        let done = self.leg >= self.legs.len();
        let Some(leg) = self
            .legs
            .get(self.leg.min(self.legs.len().saturating_sub(1)))
            .copied()
        else {
            return Step {
                setpoint: [0.0; 3],
                scanning: false,
                scan_progress: 0.0,
                done: true,
            };
        };
        let setpoint = if done {
            leg.to
        } else {
            let len = leg.length();
            let f = if len > 0.0 { self.along / len } else { 1.0 };
            [
                leg.from[0] + f * (leg.to[0] - leg.from[0]),
                leg.from[1] + f * (leg.to[1] - leg.from[1]),
                leg.from[2] + f * (leg.to[2] - leg.from[2]),
            ]
        };
        let scanning = !done && leg.scan;
        let scan_progress = if self.scan_leg_done {
            1.0
        } else if scanning {
            let total = leg.length() / leg.speed + leg.dwell;
            ((self.along / leg.speed + self.dwelt) / total).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Step {
            setpoint,
            scanning,
            scan_progress,
            done,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::LoadedProfile;

    #[test]
    fn the_thesis_path_runs_each_leg_at_its_speed() {
        let lp = LoadedProfile::thesis();
        let path = lp.rig().unwrap().path;
        let mut t = Trajectory::for_path(path, path.waypoints_m[0]);
        let dt = 0.001;
        let mut scan_ticks = 0;
        let mut ticks = 0;
        let mut first_scan = None;
        loop {
            let s = t.advance(dt, 1.0);
            ticks += 1;
            if s.scanning {
                scan_ticks += 1;
                first_scan.get_or_insert(s.setpoint);
            }
            if s.done {
                assert_eq!(s.setpoint, path.waypoints_m[4]);
                break;
            }
        }
        // 89.7 mm at 10 mm/s plus 0.3 s dwell.
        assert!((scan_ticks as i64 - 9270).abs() <= 2, "{scan_ticks}");
        let transit = (0.046_1 + 0.04 + 0.0148) / 0.03;
        assert!(((ticks - scan_ticks) as f64 * dt - transit).abs() < 0.01);
        let start = first_scan.unwrap();
        assert!((start[0] + 0.045).abs() < 1e-4 && (start[1] + 0.0048).abs() < 1e-9);
    }

    #[test]
    fn progress_and_speed_scale() {
        let leg = Leg {
            from: [0.0; 3],
            to: [0.01, 0.0, 0.0],
            speed: 0.01,
            scan: true,
            dwell: 0.0,
        };
        let mut t = Trajectory::new(vec![leg]);
        let s = t.advance(0.25, 2.0);
        assert!((s.setpoint[0] - 0.005).abs() < 1e-12);
        assert!((s.scan_progress - 0.5).abs() < 1e-9);
        let s = t.advance(10.0, 1.0);
        assert!(s.done && !s.scanning && s.scan_progress == 1.0);
    }
}
