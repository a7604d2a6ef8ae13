//! When ticks happen: real time against absolute deadlines, or virtual time.
//!
//! The real clock sleeps until each absolute deadline on CLOCK_MONOTONIC
//! (`clock_nanosleep` with `TIMER_ABSTIME`, after asking for 1 ns timer
//! slack), so errors never accumulate into drift. The virtual clock makes
//! the same loop run as fast as the CPU allows, and stands in for the USB
//! exchange's timing: each tick arrives a little after its deadline, and now
//! and then up to a quarter period late (the thesis's 800–1000 Hz).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

pub trait Clock: Send {
    /// Wait until `deadline_s` (seconds since the clock's start); return the
    /// time of the tick's device read, measured.
    fn wait_until(&mut self, deadline_s: f64) -> f64;
    /// Seconds since the clock's start.
    fn now(&self) -> f64;
    fn is_virtual(&self) -> bool;
    /// Sit out a stall of `secs` inside a tick (a device read that blocked):
    /// the real clock sleeps, the virtual clock moves on.
    fn stall(&mut self, secs: f64);
}

pub struct RealClock {
    epoch: libc::timespec,
    /// Seconds before a deadline to stop sleeping and spin.
    spin: f64,
}

fn monotonic() -> libc::timespec {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts
}

impl RealClock {
    pub fn start() -> RealClock {
        #[cfg(target_os = "linux")]
        // SAFETY: PR_SET_TIMERSLACK takes an integer and affects only this thread.
        unsafe {
            libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong);
        }
        RealClock {
            epoch: monotonic(),
            spin: 0.0,
        }
    }

    /// Wake `spin_us` before each deadline and spin to it.
    pub fn with_spin(mut self, spin_us: u32) -> RealClock {
        self.spin = f64::from(spin_us) * 1e-6;
        self
    }

    fn since_epoch(&self, ts: libc::timespec) -> f64 {
        (ts.tv_sec - self.epoch.tv_sec) as f64 + (ts.tv_nsec - self.epoch.tv_nsec) as f64 * 1e-9
    }
}

impl Clock for RealClock {
    fn wait_until(&mut self, deadline_s: f64) -> f64 {
        self.sleep_until(deadline_s - self.spin);
        if self.spin > 0.0 {
            loop {
                let now = self.now();
                if now >= deadline_s {
                    return now;
                }
                std::hint::spin_loop();
            }
        }
        self.now()
    }

    fn now(&self) -> f64 {
        self.since_epoch(monotonic())
    }

    fn is_virtual(&self) -> bool {
        false
    }

    fn stall(&mut self, secs: f64) {
        if secs.is_finite() && secs > 0.0 {
            std::thread::sleep(std::time::Duration::from_secs_f64(secs));
        }
    }
}

impl RealClock {
    fn sleep_until(&self, deadline_s: f64) {
        let deadline_s = deadline_s.max(0.0);
        let whole = deadline_s.floor();
        let mut sec = self.epoch.tv_sec + whole as libc::time_t;
        let mut nsec = self.epoch.tv_nsec + ((deadline_s - whole) * 1e9) as libc::c_long;
        if nsec >= 1_000_000_000 {
            sec += 1;
            nsec -= 1_000_000_000;
        }
        let target = libc::timespec {
            tv_sec: sec,
            tv_nsec: nsec,
        };
        loop {
            // SAFETY: a valid timespec; a null remainder is allowed with TIMER_ABSTIME.
            let rc = unsafe {
                libc::clock_nanosleep(
                    libc::CLOCK_MONOTONIC,
                    libc::TIMER_ABSTIME,
                    &target,
                    std::ptr::null_mut(),
                )
            };
            if rc != libc::EINTR {
                break;
            }
        }
    }
}

/// Apply the profile's real-time request to the calling thread. Returns a
/// note for the user for each part the system refused (none when all took).
pub fn request_realtime(rt: &crate::profile::Realtime) -> Vec<String> {
    let mut refused = Vec::new();
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param {
            sched_priority: i32::from(rt.priority),
        };
        // SAFETY: pid 0 is the calling thread; `param` is a valid sched_param.
        if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
            refused.push(format!(
                "real-time scheduling (SCHED_FIFO {}) refused: {}; running at normal priority (see `ulimit -r`, or grant CAP_SYS_NICE)",
                rt.priority,
                std::io::Error::last_os_error()
            ));
        }
        // SAFETY: mlockall takes flags only.
        if rt.lock_memory && unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
            refused.push(format!(
                "locking memory refused: {}; running unlocked (see `ulimit -l`)",
                std::io::Error::last_os_error()
            ));
        }
        if let Some(cpu) = rt.cpu {
            // SAFETY: a zeroed cpu_set_t is empty; CPU_SET stays within it for cpu < CPU_SETSIZE.
            let ok = cpu < libc::CPU_SETSIZE as usize
                && unsafe {
                    let mut set: libc::cpu_set_t = std::mem::zeroed();
                    libc::CPU_SET(cpu, &mut set);
                    libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
                };
            if !ok {
                refused.push(format!(
                    "pinning the servo thread to core {cpu} refused: {}; running unpinned",
                    std::io::Error::last_os_error()
                ));
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    refused.push(format!(
        "real-time scheduling is only supported on Linux; running at normal priority ({rt:?})"
    ));
    refused
}

pub struct VirtualClock {
    now: f64,
    period: f64,
    rng: ChaCha8Rng,
    jitter: Normal<f64>,
    slip_chance: f64,
}

impl VirtualClock {
    pub fn new(rate_hz: f64, jitter_s: f64, slip_chance: f64, seed: u64) -> VirtualClock {
        VirtualClock {
            now: 0.0,
            period: 1.0 / rate_hz,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_c10c),
            jitter: Normal::new(0.0, jitter_s.max(0.0)).expect("finite jitter"),
            slip_chance: slip_chance.clamp(0.0, 1.0),
        }
    }
}

impl Clock for VirtualClock {
    fn wait_until(&mut self, deadline_s: f64) -> f64 {
        let mut late = self.jitter.sample(&mut self.rng).abs();
        if self.slip_chance > 0.0 && self.rng.random_bool(self.slip_chance) {
            late += self.rng.random_range(0.0..0.25) * self.period;
        }
        // Time never runs backwards, whatever the jitter.
        self.now = (deadline_s + late).max(self.now);
        self.now
    }

    fn now(&self) -> f64 {
        self.now
    }

    fn is_virtual(&self) -> bool {
        true
    }

    fn stall(&mut self, secs: f64) {
        if secs.is_finite() && secs > 0.0 {
            self.now += secs;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn virtual_time_follows_deadlines_with_jitter() {
        let mut c = VirtualClock::new(1000.0, 0.00002, 0.1, 1);
        let mut prev = 0.0;
        let mut late_ticks = 0;
        for k in 1..=10_000 {
            let d = k as f64 * 0.001;
            let t = c.wait_until(d);
            assert!(t >= d && t >= prev);
            if t - d > 0.0001 {
                late_ticks += 1;
            }
            prev = t;
        }
        // About one tick in ten slips by more than 0.1 ms (most slips do).
        assert!((600..=1100).contains(&late_ticks), "{late_ticks}");
        // No drift: the last tick is within a quarter period of its deadline.
        assert!(prev - 10.0 < 0.00026);
    }

    #[test]
    fn real_clock_sleeps_to_absolute_deadlines() {
        let mut c = RealClock::start();
        let t0 = c.now();
        let t = c.wait_until(t0 + 0.005);
        assert!(t >= t0 + 0.005);
        // A deadline in the past returns at once.
        let t2 = c.wait_until(0.0);
        assert!(t2 >= t);
        // Spinning the last 300 µs still never returns before the deadline.
        let mut s = RealClock::start().with_spin(300);
        for k in 1..=20 {
            let d = k as f64 * 0.001;
            assert!(s.wait_until(d) >= d);
        }
    }
}
