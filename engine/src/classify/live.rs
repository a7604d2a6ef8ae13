//! A live estimate during a scan (issue 13 part 4): as the scan's samples
//! arrive, each sub-window the probe has passed is analysed and classified,
//! and the vote so far is kept; once the scan ends, [`LiveVote::finish`]
//! gives exactly what [`Model::classify_windows`] gives for the stored
//! recording.
//!
//! A sub-window `[s, e]` is taken as complete once the latest sample lies
//! beyond `e + spacing / 2` along the direction of travel (past its last
//! grid bin): on a time axis nothing later can fall inside it, so its
//! features are final. On a position axis a probe can slip back into a
//! sub-window it has left; [`LiveVote::finish`] analyses again any
//! sub-window that a later sample fell into (or that the buffer's direction
//! did not match), so the final result never depends on when the updates
//! came. Never prints; allocates only per completed sub-window.

use std::borrow::Borrow;

use crate::analysis::FeatureExtractor;
use crate::classify::{ClassifyError, Model, RecordingPrediction, WindowVote, vote};

/// Why a live estimate could not go on.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error(transparent)]
    Analysis(#[from] crate::analysis::AnalysisError),
    #[error(transparent)]
    Classify(#[from] ClassifyError),
}

/// The running vote of a scan in progress (see the module documentation).
/// `M` is the model, borrowed (`&Model`) or owned (`Model`), so a front end
/// can keep a live vote beside the model it was started with.
#[derive(Debug)]
pub struct LiveVote<M: Borrow<Model>> {
    model: M,
    ex: FeatureExtractor,
    /// Per completed sub-window (in window order): its vote and the buffer
    /// length it was analysed on.
    done: Vec<(WindowVote, usize)>,
    /// The direction of travel each was analysed with (+1 or −1).
    direction: Vec<f64>,
}

/// The sign of travel from the first sample to the last, as the resampler
/// takes it.
fn direction(axis: &[f64]) -> f64 {
    match (axis.first(), axis.last()) {
        (Some(a), Some(b)) if b < a => -1.0,
        _ => 1.0,
    }
}

impl<M: Borrow<Model>> LiveVote<M> {
    /// A live vote for the model's analysis settings.
    pub fn new(model: M) -> Result<Self, LiveError> {
        Ok(LiveVote {
            ex: FeatureExtractor::try_new(&model.borrow().analysis)?,
            model,
            done: Vec::new(),
            direction: Vec::new(),
        })
    }

    /// Sub-windows in all.
    pub fn windows(&self) -> usize {
        self.ex.sub_windows().len()
    }

    /// Sub-windows completed so far.
    pub fn completed(&self) -> usize {
        self.done.len()
    }

    /// Feed the scan's samples so far (the whole growing buffer: `axis`
    /// and one signal per analysed channel, from the scan's first sample).
    /// Analyses and classifies every sub-window completed since the last
    /// call; returns the vote so far when one or more did, else `None`.
    pub fn update(
        &mut self,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<Option<RecordingPrediction>, LiveError> {
        let (Some(&origin), Some(&last)) = (axis.first(), axis.last()) else {
            return Ok(None);
        };
        let dir = direction(axis);
        let reached = dir * (last - origin);
        let half = 0.5 * self.model.borrow().analysis.spacing;
        let before = self.done.len();
        while self.done.len() < self.windows() {
            let j = self.done.len();
            if reached <= self.ex.sub_windows()[j][1] + half {
                break;
            }
            self.complete(j, axis, signals, dir)?;
        }
        Ok((self.done.len() > before).then(|| self.so_far()))
    }

    fn complete(
        &mut self,
        j: usize,
        axis: &[f64],
        signals: &[&[f64]],
        dir: f64,
    ) -> Result<(), LiveError> {
        let f = self.ex.window_features(j, axis, signals)?;
        let p = self.model.borrow().classify(f)?;
        let v = WindowVote {
            window: j,
            label: p.label,
            votes: p.votes,
        };
        if j < self.done.len() {
            self.done[j] = (v, axis.len());
            self.direction[j] = dir;
        } else {
            self.done.push((v, axis.len()));
            self.direction.push(dir);
        }
        Ok(())
    }

    /// The vote over the sub-windows completed so far (`None` before the first).
    pub fn current(&self) -> Option<RecordingPrediction> {
        (!self.done.is_empty()).then(|| self.so_far())
    }

    fn so_far(&self) -> RecordingPrediction {
        vote(self.done.iter().map(|(v, _)| v.clone()).collect())
            .expect("called with at least one sub-window")
    }

    /// The scan has ended and `axis`/`signals` are all of it: analyse the
    /// sub-windows not yet complete, and again any that a sample after its
    /// analysis fell into; the vote over all of them, equal to
    /// [`Model::classify_windows`] on the stored recording's sub-windows.
    pub fn finish(
        mut self,
        axis: &[f64],
        signals: &[&[f64]],
    ) -> Result<RecordingPrediction, LiveError> {
        let dir = direction(axis);
        let origin = axis.first().copied().unwrap_or(0.0);
        let half = 0.5 * self.model.borrow().analysis.spacing;
        for j in 0..self.done.len() {
            let [s, e] = self.ex.sub_windows()[j];
            let cut = self.done[j].1;
            let touched = self.direction[j] != dir
                || axis[cut.min(axis.len())..].iter().any(|&a| {
                    let d = dir * (a - origin);
                    d >= s - half && d < e + half
                });
            if touched {
                self.complete(j, axis, signals, dir)?;
            }
        }
        for j in self.done.len()..self.windows() {
            self.complete(j, axis, signals, dir)?;
        }
        vote(self.done.into_iter().map(|(v, _)| v).collect())
            .ok_or(LiveError::Classify(ClassifyError::NoWindows))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset;
    use crate::profile::{LoadedProfile, Windows};
    use crate::recording;
    use std::path::{Path, PathBuf};

    #[test]
    fn the_live_vote_grows_window_by_window_and_ends_as_classify_says() {
        let mut a = LoadedProfile::thesis().profile.analysis;
        a.bins = [1, 24];
        a.windows = Some(Windows {
            length: 0.0147,
            hop: 0.0075,
        });
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
        let files: Vec<PathBuf> = dataset::find(&[dir]).unwrap();
        let (train, test): (Vec<_>, Vec<_>) =
            files.iter().enumerate().partition(|(i, _)| i % 10 != 0);
        let train: Vec<PathBuf> = train.into_iter().map(|(_, f)| f.clone()).collect();
        let loaded = dataset::load(&train, &a, dataset::Options::default(), &|| {}).unwrap();
        assert_eq!(loaded.entries.len(), 3 * train.len());
        let classifier = LoadedProfile::thesis().profile.classifier;
        let model = Model::train("windows", &a, &classifier, loaded.into_examples()).unwrap();
        let mut ex = FeatureExtractor::new(&a);
        let mut agreed = 0;
        for (_, f) in test.iter().take(6) {
            let rec = recording::read(f).unwrap();
            let (axis, signals) = dataset::columns_of(&rec, f, &a).unwrap();
            let stored = model
                .classify_windows(&ex.all_window_features(axis, &signals).unwrap())
                .unwrap();
            let mut live = LiveVote::new(&model).unwrap();
            assert_eq!(live.windows(), 3);
            let mut seen = Vec::new();
            // The buffer grows by 100 samples at a time, as a scan's would.
            let mut n = 0;
            while n < axis.len() {
                n = (n + 100).min(axis.len());
                let cut: Vec<&[f64]> = signals.iter().map(|s| &s[..n]).collect();
                if let Some(p) = live.update(&axis[..n], &cut).unwrap() {
                    seen.push(p.windows.len());
                }
            }
            // Sub-windows complete one after another while the scan runs
            // (the last may only complete at the end).
            assert!(seen.len() >= 2, "{seen:?}");
            assert!(seen.windows(2).all(|w| w[0] < w[1]), "{seen:?}");
            let fin = live.finish(axis, &signals).unwrap();
            assert_eq!(fin, stored, "{}", f.display());
            agreed += usize::from(fin.label == rec.label().unwrap_or_default());
        }
        assert!(agreed >= 4, "only {agreed} of 6 right");
    }
}
