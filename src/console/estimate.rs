//! The live estimate (issue 13 part 4): while a scan runs and the model
//! votes over sub-windows (`[analysis] windows`), the scan's samples are
//! gathered from the telemetry the console drains once a frame, and each
//! sub-window the probe has passed is classified as it completes
//! ([`LiveVote`]): the Prediction panel shows the vote so far.
//!
//! The estimate is only a preview: telemetry is lossy (a full channel drops
//! frames) and carries the values before the recorder rounds them, so the
//! final prediction is not this vote but the stored recording's, made when
//! the file comes back ([`super::scan::predict_view`], as `classify` makes
//! it). Gathering a sample is a push; analysis runs once a frame and only
//! for sub-windows completed since the last frame. Never draws, never
//! touches the servo thread.

use crate::classify::live::LiveVote;
use crate::classify::{Model, RecordingPrediction};
use crate::servo::Telemetry;

/// A telemetry value that stands for a recording column.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Source {
    /// `t_s`: time since the scan's first sample.
    Time,
    /// `x_m`, `y_m`, `z_m`.
    Position(usize),
    /// `fx_n`, `fy_n`, `fz_n`: the force commanded.
    Force(usize),
}

/// Which telemetry value a recording column is (the recorder writes these
/// columns from the same tick's values); `None` for a column telemetry
/// does not carry.
fn source(column: &str) -> Option<Source> {
    Some(match column {
        "t_s" => Source::Time,
        "x_m" => Source::Position(0),
        "y_m" => Source::Position(1),
        "z_m" => Source::Position(2),
        "fx_n" => Source::Force(0),
        "fy_n" => Source::Force(1),
        "fz_n" => Source::Force(2),
        _ => return None,
    })
}

/// The running vote of the scan in progress.
#[derive(Debug)]
pub struct Estimate {
    vote: Option<LiveVote<Model>>,
    /// Axis first, then each analysed channel.
    sources: Vec<Source>,
    /// The scan's samples so far, one column per source.
    columns: Vec<Vec<f64>>,
    /// Telemetry time of the scan's first sample.
    t0: f64,
    /// Samples the vote last saw.
    seen: usize,
    /// Sub-windows classified once the scan ended and the vote was
    /// finished (the vote is spent then).
    finished: usize,
    /// Each sub-window's `[start, end]` along the axis.
    pub sub_windows: Vec<[f64; 2]>,
    /// The analysis axis, for its unit.
    pub axis: String,
    /// The vote over the sub-windows completed so far.
    pub current: Option<RecordingPrediction>,
    /// The scan is still running (frames still come).
    pub running: bool,
    /// Why there is no estimate (a column telemetry lacks, a failed
    /// analysis); the scan goes on regardless.
    pub error: Option<String>,
}

impl Estimate {
    /// An estimate for a scan whose first sample is `first`, with a copy of
    /// the model (the app's may be retrained meanwhile).
    pub fn start(model: &Model, first: &Telemetry) -> Estimate {
        let a = &model.analysis;
        let names: Vec<&str> = std::iter::once(a.axis.as_str())
            .chain(a.all_channels())
            .collect();
        let sources: Option<Vec<Source>> = names.iter().map(|c| source(c)).collect();
        let (vote, error) = match sources {
            None => {
                let lacking: Vec<&str> = names
                    .iter()
                    .copied()
                    .filter(|c| source(c).is_none())
                    .collect();
                (
                    None,
                    Some(format!(
                        "the analysis reads {}, which the device's telemetry does not carry",
                        lacking.join(", ")
                    )),
                )
            }
            Some(_) => match LiveVote::new(model.clone()) {
                Ok(v) => (Some(v), None),
                Err(e) => (None, Some(e.to_string())),
            },
        };
        let sources = sources.unwrap_or_default();
        let mut e = Estimate {
            vote,
            columns: vec![Vec::with_capacity(16_384); sources.len()],
            sources,
            t0: first.t_s,
            seen: 0,
            finished: 0,
            sub_windows: a.sub_windows(),
            axis: a.axis.clone(),
            current: None,
            running: true,
            error,
        };
        e.push(first);
        e
    }

    /// One more sample of the scan (a telemetry frame with `scanning` set).
    pub fn push(&mut self, t: &Telemetry) {
        if self.vote.is_none() || !self.running {
            return;
        }
        for (col, s) in self.columns.iter_mut().zip(&self.sources) {
            col.push(match *s {
                Source::Time => t.t_s - self.t0,
                Source::Position(i) => t.pos_m[i],
                Source::Force(i) => t.force_n[i],
            });
        }
    }

    /// Sub-windows in all.
    pub fn windows(&self) -> usize {
        self.sub_windows.len()
    }

    /// Sub-windows completed and classified so far.
    pub fn completed(&self) -> usize {
        self.vote
            .as_ref()
            .map_or(self.finished, LiveVote::completed)
    }

    /// Samples gathered so far.
    pub fn samples(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Once a frame: classify the sub-windows completed since the last
    /// call; once the scan has ended, the ones still open (the last ends
    /// with the stroke), so the vote covers every sub-window. Whether the
    /// vote changed.
    pub fn update(&mut self) -> bool {
        let n = self.samples();
        if self.error.is_some() || (self.running && n == self.seen) {
            return false;
        }
        self.seen = n;
        let (axis, signals) = match self.columns.split_first() {
            Some((axis, signals)) if !axis.is_empty() => (axis, signals),
            _ => return false,
        };
        let signals: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
        let done = if self.running {
            let Some(vote) = self.vote.as_mut() else {
                return false;
            };
            vote.update(axis, &signals)
        } else {
            let Some(vote) = self.vote.take() else {
                return false;
            };
            self.finished = self.windows();
            vote.finish(axis, &signals).map(Some)
        };
        match done {
            Ok(Some(p)) => {
                self.current = Some(p);
                true
            }
            Ok(None) => false,
            Err(e) => {
                self.error = Some(e.to_string());
                true
            }
        }
    }
}

#[cfg(test)]
mod tests;
