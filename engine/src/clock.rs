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
    /// Whether ticks should be as punctual as the clock can make them (a
    /// real clock spins before deadlines then, if configured to).
    fn set_precise(&mut self, _on: bool) {}

    /// Sit out a stall of `secs` inside a tick (a device read that blocked):
    /// the real clock sleeps, the virtual clock moves on.
    fn stall(&mut self, secs: f64);
}

pub struct RealClock {
    epoch: libc::timespec,
    /// Seconds before a deadline to stop sleeping and spin, when precise.
    spin: f64,
    precise: bool,
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
            precise: false,
        }
    }

    /// Wake `spin_us` before each deadline and spin to it, while precise
    /// ticks are asked for ([`Clock::set_precise`]).
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
        let spin = if self.precise { self.spin } else { 0.0 };
        self.sleep_until(deadline_s - spin);
        if spin > 0.0 {
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

    fn set_precise(&mut self, on: bool) {
        self.precise = on;
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
    if let Err(e) = set_fifo_priority(rt.priority) {
        refused.push(format!(
            "real-time scheduling (SCHED_FIFO {}) refused: {e}; running at normal priority (see `ulimit -r`, or grant CAP_SYS_NICE)",
            rt.priority
        ));
    }
    if rt.lock_memory
        && let Err(e) = lock_memory()
    {
        refused.push(format!(
            "locking memory refused: {e}; running unlocked (see `ulimit -l`)"
        ));
    }
    if let Some(cpu) = rt.cpu
        && let Err(e) = pin_to_cpu(cpu)
    {
        refused.push(format!(
            "pinning the servo thread to core {cpu} refused: {e}; running unpinned"
        ));
    }
    refused
}

#[cfg(not(target_os = "linux"))]
fn linux_only() -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::Unsupported, "only supported on Linux")
}

/// SCHED_FIFO at `priority` for the calling thread.
pub fn set_fifo_priority(priority: u8) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param {
            sched_priority: i32::from(priority),
        };
        // SAFETY: pid 0 is the calling thread; `param` is a valid sched_param.
        if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = priority;
        Err(linux_only())
    }
}

/// Lock the whole process's memory, now and to come (mlockall).
pub fn lock_memory() -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: mlockall takes flags only.
        if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    Err(linux_only())
}

/// Pin the calling thread to core `cpu`.
pub fn pin_to_cpu(cpu: usize) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        if cpu >= libc::CPU_SETSIZE as usize {
            return Err(std::io::Error::from_raw_os_error(libc::EINVAL));
        }
        // SAFETY: a zeroed cpu_set_t is empty; CPU_SET stays within it for cpu < CPU_SETSIZE.
        let ok = unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(cpu, &mut set);
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
        };
        if !ok {
            return Err(std::io::Error::last_os_error());
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = cpu;
        Err(linux_only())
    }
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
    fn a_refused_part_of_the_realtime_request_is_named() {
        // On a scratch thread: a granted SCHED_FIFO must not outlive the test.
        let notes = std::thread::spawn(|| {
            request_realtime(&crate::profile::Realtime {
                priority: 1,
                lock_memory: false,
                cpu: Some(1 << 20),
            })
        })
        .join()
        .unwrap();
        let pin: Vec<&String> = notes.iter().filter(|n| n.starts_with("pinning")).collect();
        assert_eq!(pin.len(), 1, "{notes:?}");
        assert!(
            pin[0].contains("core 1048576") && pin[0].ends_with("running unpinned"),
            "{notes:?}"
        );
        assert!(pin_to_cpu(1 << 20).is_err());
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
        s.set_precise(true);
        for k in 1..=20 {
            let d = k as f64 * 0.001;
            assert!(s.wait_until(d) >= d);
        }
    }
}
