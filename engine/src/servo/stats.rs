//! Loop statistics: achieved rate, period error percentiles, missed
//! deadlines, dropped telemetry. Fixed-size histogram: no allocation per tick.

use serde::Serialize;

/// Histogram resolution and range of period errors.
const BIN_US: f64 = 1.0;
const BINS: usize = 20_000;

#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LoopStats {
    pub ticks: u64,
    pub elapsed_s: f64,
    pub rate_hz: f64,
    pub period_error_p50_us: f64,
    pub period_error_p99_us: f64,
    pub period_error_max_us: f64,
    /// Ticks that started late, plus deadlines skipped after a long stall.
    pub missed_deadlines: u64,
    pub longest_missed_streak: u32,
    pub dropped_telemetry: u64,
    pub dropped_events: u64,
    /// Sample blocks the recorder had to allocate because the writer lagged.
    pub recorder_blocks_grown: u64,
    /// The device's link counters (the Falcon's packets), when it has a link.
    pub link: Option<crate::device::LinkStats>,
}

pub struct StatsCollector {
    hist: Box<[u32; BINS]>,
    overflow: u64,
    max_err: f64,
    first_t: Option<f64>,
    last_t: Option<f64>,
    period: f64,
    pub ticks: u64,
    pub missed: u64,
    pub streak: u32,
    pub longest_streak: u32,
    pub dropped_telemetry: u64,
    pub dropped_events: u64,
    pub blocks_grown: u64,
}

impl StatsCollector {
    pub fn new(rate_hz: f64) -> StatsCollector {
        StatsCollector {
            hist: Box::new([0; BINS]),
            overflow: 0,
            max_err: 0.0,
            first_t: None,
            last_t: None,
            period: 1.0 / rate_hz,
            ticks: 0,
            missed: 0,
            streak: 0,
            longest_streak: 0,
            dropped_telemetry: 0,
            dropped_events: 0,
            blocks_grown: 0,
        }
    }

    /// Start afresh (the histogram is reused, not reallocated).
    pub fn reset(&mut self) {
        self.hist.fill(0);
        self.overflow = 0;
        self.max_err = 0.0;
        self.first_t = None;
        self.last_t = None;
        self.ticks = 0;
        self.missed = 0;
        self.streak = 0;
        self.longest_streak = 0;
    }

    /// Record a tick measured at `t` (seconds); `missed` when it started late.
    pub fn tick(&mut self, t: f64, missed: bool) {
        self.ticks += 1;
        if let Some(prev) = self.last_t {
            let err_us = ((t - prev) - self.period).abs() * 1e6;
            self.max_err = self.max_err.max(err_us);
            let bin = (err_us / BIN_US) as usize;
            if bin < BINS {
                self.hist[bin] += 1;
            } else {
                self.overflow += 1;
            }
        } else {
            self.first_t = Some(t);
        }
        self.last_t = Some(t);
        if missed {
            self.missed += 1;
            self.streak += 1;
            self.longest_streak = self.longest_streak.max(self.streak);
        } else {
            self.streak = 0;
        }
    }

    fn percentile_us(&self, q: f64) -> f64 {
        let n: u64 = self.hist.iter().map(|&c| u64::from(c)).sum::<u64>() + self.overflow;
        if n == 0 {
            return 0.0;
        }
        let want = ((n as f64) * q).ceil().max(1.0) as u64;
        let mut seen = 0u64;
        for (i, &c) in self.hist.iter().enumerate() {
            seen += u64::from(c);
            if seen >= want {
                return (i as f64 + 0.5) * BIN_US;
            }
        }
        self.max_err
    }

    pub fn snapshot(&self) -> LoopStats {
        let elapsed = match (self.first_t, self.last_t) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        };
        LoopStats {
            ticks: self.ticks,
            elapsed_s: elapsed,
            rate_hz: if elapsed > 0.0 {
                (self.ticks - 1) as f64 / elapsed
            } else {
                0.0
            },
            period_error_p50_us: self.percentile_us(0.5),
            period_error_p99_us: self.percentile_us(0.99),
            period_error_max_us: self.max_err,
            missed_deadlines: self.missed,
            longest_missed_streak: self.longest_streak,
            dropped_telemetry: self.dropped_telemetry,
            dropped_events: self.dropped_events,
            recorder_blocks_grown: self.blocks_grown,
            link: None,
        }
    }
}

impl LoopStats {
    /// One line for people: `1000.0 Hz, period error p50 3 µs p99 41 µs max 120 µs, …`.
    pub fn summary(&self) -> String {
        format!(
            "{} ticks in {:.2} s: {:.2} Hz, period error p50 {:.0} µs p99 {:.0} µs max {:.0} µs, {} missed deadlines (longest streak {}), {} telemetry dropped",
            self.ticks,
            self.elapsed_s,
            self.rate_hz,
            self.period_error_p50_us,
            self.period_error_p99_us,
            self.period_error_max_us,
            self.missed_deadlines,
            self.longest_missed_streak,
            self.dropped_telemetry
        ) + &self.link.map_or(String::new(), |l| {
            format!(
                "; link: {} packets, {} replies, {} bad packets, {} missed replies, {} USB errors, {} saturated ticks",
                l.packets, l.replies, l.bad_packets, l.missed_replies, l.usb_errors, l.saturated_ticks
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_rate_and_streaks() {
        let mut s = StatsCollector::new(1000.0);
        for k in 0..1000 {
            // Every tenth period is 100 µs long.
            let t = k as f64 * 0.001 + if k % 10 == 5 { 0.0001 } else { 0.0 };
            s.tick(t, (500..503).contains(&k));
        }
        let snap = s.snapshot();
        assert_eq!(snap.ticks, 1000);
        assert!((snap.rate_hz - 1000.0).abs() < 0.5, "{}", snap.rate_hz);
        assert!(snap.period_error_p50_us < 1.0);
        assert!(
            (snap.period_error_p99_us - 100.5).abs() < 1.0,
            "{}",
            snap.period_error_p99_us
        );
        assert!((snap.period_error_max_us - 100.0).abs() < 0.01);
        assert_eq!(snap.missed_deadlines, 3);
        assert_eq!(snap.longest_missed_streak, 3);
    }
}
