//! What the live panels show: the latest telemetry frame and a short,
//! decimated history of the probe's height and vertical force.
//!
//! A feed is filled from the servo's telemetry channel (drained once per
//! frame) or by the replay player from a recording; the panels cannot tell
//! the two apart. Pushing is cheap and bounded: the history keeps one point
//! per [`TRACE_STEP_S`] over the last [`TRACE_SPAN_S`] seconds.

use std::collections::VecDeque;

use crate::servo::Telemetry;

/// Seconds of history the Traces panel shows.
pub const TRACE_SPAN_S: f64 = 10.0;
/// One history point per this many seconds (100 Hz).
pub const TRACE_STEP_S: f64 = 0.01;

/// One point of the Traces panel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracePoint {
    pub t_s: f64,
    pub y_m: f64,
    pub fy_n: f64,
}

#[derive(Debug, Clone, Default)]
pub struct Feed {
    pub latest: Option<Telemetry>,
    pub history: VecDeque<TracePoint>,
    /// Frames received in all.
    pub frames: u64,
}

impl Feed {
    pub fn push(&mut self, t: &Telemetry) {
        self.frames += 1;
        let due = self
            .history
            .back()
            .is_none_or(|p| t.t_s - p.t_s >= TRACE_STEP_S - 1e-9 || t.t_s < p.t_s);
        if due {
            if self.history.back().is_some_and(|p| t.t_s < p.t_s) {
                // Time went backwards (a new source): start afresh.
                self.history.clear();
            }
            self.history.push_back(TracePoint {
                t_s: t.t_s,
                y_m: t.pos_m[1],
                fy_n: t.force_n[1],
            });
            while self
                .history
                .front()
                .is_some_and(|p| t.t_s - p.t_s > TRACE_SPAN_S)
            {
                self.history.pop_front();
            }
        }
        self.latest = Some(*t);
    }

    pub fn clear(&mut self) {
        *self = Feed::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::servo::Mode;
    use crate::servo::stats::LoopStats;

    pub fn frame(t_s: f64) -> Telemetry {
        Telemetry {
            tick: (t_s * 1000.0) as u64,
            t_s,
            pos_m: [0.0, t_s * 1e-3, 0.0],
            setpoint_m: [0.0; 3],
            force_n: [0.0, -0.2, 0.0],
            mode: Mode::Manual,
            scanning: false,
            scan_progress: 0.0,
            homed: true,
            speed_scale: 1.0,
            stats: LoopStats::default(),
        }
    }

    #[test]
    fn history_is_decimated_and_bounded() {
        let mut f = Feed::default();
        for i in 0..30_000 {
            f.push(&frame(i as f64 * 0.001));
        }
        assert_eq!(f.frames, 30_000);
        let n = f.history.len();
        assert!((990..=1002).contains(&n), "{n}");
        let span = f.history.back().unwrap().t_s - f.history.front().unwrap().t_s;
        assert!(span <= TRACE_SPAN_S + 1e-9);
        f.push(&frame(0.0));
        assert_eq!(f.history.len(), 1);
    }
}
