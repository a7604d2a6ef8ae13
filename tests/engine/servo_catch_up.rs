//! After a stall the servo loop catches up on its absolute schedule, with
//! ticks no closer than half a period, so the mean rate holds; a stall too
//! long to catch up is skipped and its deadlines counted as missed.

use std::sync::{Arc, Mutex};

use hapticlab::clock::Clock;
use hapticlab::device::sim::SimDevice;
use hapticlab::device::{DeviceError, HapticDevice, Reading};
use hapticlab::profile::LoadedProfile;
use hapticlab::servo::{Links, ServoLoop};

/// Virtual time that wakes exactly at each deadline, except once, when the
/// machine stalls for `stall_s`.
struct OneStall {
    now: f64,
    ticks: u64,
    at_tick: u64,
    stall_s: f64,
}

impl Clock for OneStall {
    fn wait_until(&mut self, deadline_s: f64) -> f64 {
        self.ticks += 1;
        self.now = self.now.max(deadline_s);
        if self.ticks == self.at_tick {
            self.now += self.stall_s;
        }
        self.now
    }
    fn now(&self) -> f64 {
        self.now
    }
    fn is_virtual(&self) -> bool {
        true
    }
    fn stall(&mut self, secs: f64) {
        self.now += secs;
    }
}

/// The simulator, noting the time of every read.
struct Timed {
    inner: SimDevice,
    reads: Arc<Mutex<Vec<f64>>>,
}

impl HapticDevice for Timed {
    fn kind(&self) -> &'static str {
        "timed"
    }
    fn read(&mut self, t: f64) -> Result<Reading, DeviceError> {
        self.reads.lock().unwrap().push(t);
        self.inner.read(t)
    }
    fn command(&mut self, f: [f64; 3]) -> Result<(), DeviceError> {
        self.inner.command(f)
    }
    fn make_safe(&mut self) {
        self.inner.make_safe()
    }
}

/// Run 3 s of loop with one stall after 1 s; the read times and the stats.
fn run(stall_s: f64) -> (Vec<f64>, hapticlab::servo::stats::LoopStats) {
    let lp = LoadedProfile::thesis();
    let p = &lp.profile;
    let reads = Arc::new(Mutex::new(Vec::new()));
    let dev = Timed {
        inner: SimDevice::new(p, &lp.base_dir, Some("S2"), 1).unwrap(),
        reads: reads.clone(),
    };
    let clock = OneStall {
        now: 0.0,
        ticks: 0,
        at_tick: 1000,
        stall_s,
    };
    let (_recorder, sink) = hapticlab::recorder::start();
    let mut servo = ServoLoop::new(dev, clock, p.rig().unwrap(), sink, Links::default());
    loop {
        servo.tick().unwrap();
        if reads.lock().unwrap().last().is_some_and(|&t| t >= 3.0) {
            break;
        }
    }
    let stats = servo.stats();
    drop(servo);
    let reads = reads.lock().unwrap().clone();
    (reads, stats)
}

#[test]
fn a_short_stall_is_caught_up_at_no_more_than_twice_the_rate() {
    let (reads, stats) = run(0.0075);
    // Every deadline of the 3 s was served: the mean rate holds.
    assert_eq!(reads.len(), 3000, "{} ticks", reads.len());
    assert!((stats.rate_hz - 1000.0).abs() < 0.5, "{}", stats.rate_hz);
    // Never closer than half a period.
    let min_gap = reads
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::MAX, f64::min);
    assert!(min_gap >= 0.0005 - 1e-12, "ticks {min_gap} s apart");
    // Back on the absolute schedule within 16 ticks of the stall.
    for (i, &t) in reads.iter().enumerate().skip(1000 + 16) {
        assert!(
            (t - (i + 1) as f64 * 0.001).abs() < 1e-9,
            "tick {i} at {t} s, off schedule"
        );
    }
    // Only the stalled tick itself started late.
    assert_eq!(stats.missed_deadlines, 1);
    assert_eq!(stats.longest_missed_streak, 1);
}

#[test]
fn a_long_stall_is_skipped_and_its_deadlines_counted_missed() {
    let (reads, stats) = run(0.100);
    // 100 deadlines passed during the stall are not made up.
    let lost = 3000 - reads.len();
    assert!((99..=101).contains(&lost), "{lost} ticks lost");
    assert!(stats.missed_deadlines >= 100, "{}", stats.missed_deadlines);
    // Still no burst.
    let min_gap = reads
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::MAX, f64::min);
    assert!(min_gap >= 0.0005 - 1e-12, "ticks {min_gap} s apart");
}
