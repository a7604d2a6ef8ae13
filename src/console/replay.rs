//! Replay: a recording played back as a source of telemetry frames, so the
//! live panels (Position, Force, Traces, Workspace) show it as if the probe
//! were moving now, at 1×, 4× or 16×, paused, or a step at a time.
//!
//! The player is advanced once per frame by the wall time since the last
//! frame ([`Player::advance`]), a pure state change; the browser state
//! ([`Replay`]) holds the list of recordings and the analysis of the one
//! playing. Reading files is the runtime's job, not this module's.

use std::path::{Path, PathBuf};

use crate::recording::Recording;
use crate::servo::stats::LoopStats;
use crate::servo::{Mode, Telemetry};

use super::dataset::ReplayEntry;
use super::feed::Feed;
use super::scan::ScanView;

/// The replay speeds `+`/`-` step through.
pub const SPEEDS: [u32; 3] = [1, 4, 16];
/// How far one single step moves, in recorded seconds.
pub const STEP_S: f64 = 0.05;

#[derive(Debug, Clone, PartialEq)]
pub struct Player {
    t_s: Vec<f64>,
    pos_m: Vec<[f64; 3]>,
    force_n: Vec<[f64; 3]>,
    /// Index of the next sample to play.
    cursor: usize,
    /// Recorded time reached, seconds from the first sample.
    clock_s: f64,
    pub speed: u32,
    pub paused: bool,
}

impl Player {
    /// A player at the start of `rec`; missing columns play as zeros.
    pub fn new(rec: &Recording) -> Player {
        let n = rec.len();
        let col = |name: &str| {
            rec.column(name)
                .map(<[f64]>::to_vec)
                .unwrap_or(vec![0.0; n])
        };
        let t = col("t_s");
        let t0 = t.first().copied().unwrap_or(0.0);
        let (x, y, z) = (col("x_m"), col("y_m"), col("z_m"));
        let (fx, fy, fz) = (col("fx_n"), col("fy_n"), col("fz_n"));
        Player {
            t_s: t.iter().map(|t| t - t0).collect(),
            pos_m: (0..n).map(|i| [x[i], y[i], z[i]]).collect(),
            force_n: (0..n).map(|i| [fx[i], fy[i], fz[i]]).collect(),
            cursor: 0,
            clock_s: 0.0,
            speed: 1,
            paused: false,
        }
    }

    pub fn duration_s(&self) -> f64 {
        self.t_s.last().copied().unwrap_or(0.0)
    }

    pub fn position_s(&self) -> f64 {
        self.clock_s.min(self.duration_s())
    }

    pub fn finished(&self) -> bool {
        self.cursor >= self.t_s.len()
    }

    fn frame(&self, i: usize) -> Telemetry {
        let n = self.t_s.len().max(1);
        Telemetry {
            tick: i as u64,
            t_s: self.t_s[i],
            pos_m: self.pos_m[i],
            setpoint_m: self.pos_m[i],
            force_n: self.force_n[i],
            mode: Mode::Test,
            scanning: true,
            scan_progress: (i + 1) as f64 / n as f64,
            homed: true,
            speed_scale: 1.0,
            stats: LoopStats::default(),
        }
    }

    /// Play the samples up to recorded time `until`.
    fn play_to(&mut self, until: f64, feed: &mut Feed) {
        self.clock_s = until.min(self.duration_s());
        while self.cursor < self.t_s.len() && self.t_s[self.cursor] <= until + 1e-12 {
            feed.push(&self.frame(self.cursor));
            self.cursor += 1;
        }
    }

    /// Move on by `wall_s` seconds of wall time at the current speed.
    pub fn advance(&mut self, wall_s: f64, feed: &mut Feed) {
        if self.paused || self.finished() || !(wall_s.is_finite() && wall_s > 0.0) {
            return;
        }
        let until = self.clock_s + wall_s.min(0.5) * f64::from(self.speed);
        self.play_to(until, feed);
    }

    /// One single step ([`STEP_S`] of recorded time); pauses.
    pub fn step(&mut self, feed: &mut Feed) {
        self.paused = true;
        let until = self.clock_s + STEP_S;
        self.play_to(until, feed);
    }

    /// Back to the start.
    pub fn restart(&mut self, feed: &mut Feed) {
        feed.clear();
        self.cursor = 0;
        self.clock_s = 0.0;
    }

    pub fn faster(&mut self) {
        self.speed = SPEEDS
            .iter()
            .copied()
            .find(|s| *s > self.speed)
            .unwrap_or(self.speed);
    }

    pub fn slower(&mut self) {
        self.speed = SPEEDS
            .iter()
            .rev()
            .copied()
            .find(|s| *s < self.speed)
            .unwrap_or(self.speed);
    }
}

/// The replay browser: recordings to choose from and the one playing.
#[derive(Debug, Clone, PartialEq)]
pub struct Replay {
    /// The file or folder being replayed.
    pub source: PathBuf,
    pub entries: Vec<ReplayEntry>,
    pub selected: usize,
    /// Predictions for the list are being worked out.
    pub listing: bool,
    pub player: Option<Player>,
    pub scan: Option<ScanView>,
    /// Why the selected recording could not be opened.
    pub error: Option<String>,
    /// Only this label's recordings are shown.
    pub filter: Option<String>,
}

impl Replay {
    pub fn new(source: PathBuf, files: Vec<PathBuf>) -> Replay {
        Replay {
            source,
            entries: files
                .into_iter()
                .map(|path| ReplayEntry {
                    path,
                    label: None,
                    predicted: None,
                    complete: None,
                })
                .collect(),
            selected: 0,
            listing: false,
            player: None,
            scan: None,
            error: None,
            filter: None,
        }
    }

    /// The entries shown (the filter's label, or all), by index.
    pub fn visible(&self) -> Vec<usize> {
        (0..self.entries.len())
            .filter(|&i| {
                self.filter
                    .as_ref()
                    .is_none_or(|f| self.entries[i].label_or_folder() == *f)
            })
            .collect()
    }

    /// A recording moved by curating: `from` is now `to` (none: deleted);
    /// one put back (by an undo) is listed again. `label`: the label it is
    /// now stored under, when that changed (else it keeps its own).
    pub fn moved(&mut self, from: Option<&Path>, to: Option<&Path>, label: Option<&str>) {
        let at = from.and_then(|f| self.entries.iter().position(|e| e.path == f));
        match (at, to) {
            (Some(i), Some(to)) => {
                // The same samples: the model's prediction still holds; the
                // label is the one stored under, or unchanged.
                let e = &mut self.entries[i];
                e.path = to.to_path_buf();
                if let Some(label) = label {
                    e.label = Some(label.to_string());
                }
            }
            (Some(i), None) => {
                self.entries.remove(i);
            }
            (None, Some(to)) => {
                self.entries.push(ReplayEntry {
                    path: to.to_path_buf(),
                    label: label.map(str::to_string),
                    predicted: None,
                    complete: None,
                });
            }
            (None, None) => {}
        }
        // File-name order, as the list was built; the selection follows the file.
        self.entries.sort_by(|a, b| a.path.cmp(&b.path));
        let last = self.entries.len().saturating_sub(1);
        if let Some(i) = to.and_then(|t| self.entries.iter().position(|e| e.path == t)) {
            self.selected = i;
        }
        self.selected = self.selected.min(last);
    }

    pub fn selected_path(&self) -> Option<&PathBuf> {
        self.entries.get(self.selected).map(|e| &e.path)
    }

    /// Predictions right / known.
    pub fn score(&self) -> (usize, usize) {
        let known = self.entries.iter().filter_map(ReplayEntry::right);
        known.fold((0, 0), |(r, n), ok| (r + usize::from(ok), n + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(n: usize) -> Recording {
        let t: Vec<f64> = (0..n).map(|i| 5.0 + i as f64 * 0.001).collect();
        let x: Vec<f64> = (0..n).map(|i| i as f64 * 1e-5).collect();
        Recording {
            path: None,
            meta: vec![],
            columns: vec!["t_s".into(), "x_m".into(), "fy_n".into()],
            data: vec![t, x, vec![-0.3; n]],
            trailer_samples: Some(n),
            torn_last_row: false,
        }
    }

    #[test]
    fn plays_at_speed_pauses_and_steps() {
        let mut p = Player::new(&rec(2001));
        let mut feed = Feed::default();
        assert!((p.duration_s() - 2.0).abs() < 1e-9);
        p.advance(0.1, &mut feed);
        assert_eq!(feed.frames, 101);
        p.faster();
        assert_eq!(p.speed, 4);
        p.advance(0.1, &mut feed);
        assert_eq!(feed.frames, 501);
        let last = feed.latest.unwrap();
        assert!((last.pos_m[0] - 0.005).abs() < 1e-9);
        assert_eq!(last.force_n[1], -0.3);
        p.paused = true;
        p.advance(0.1, &mut feed);
        assert_eq!(feed.frames, 501);
        p.step(&mut feed);
        assert_eq!(feed.frames, 551);
        p.faster();
        p.faster();
        assert_eq!(p.speed, 16);
        p.slower();
        assert_eq!(p.speed, 4);
        p.paused = false;
        for _ in 0..100 {
            p.advance(0.1, &mut feed);
        }
        assert!(p.finished());
        assert_eq!(feed.frames, 2001);
        p.restart(&mut feed);
        assert_eq!(p.position_s(), 0.0);
        assert!(feed.latest.is_none());
    }
}
