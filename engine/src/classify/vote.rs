//! A recording classified by the vote of its sub-windows: each sub-window's
//! k-NN outcome, the tally over them and how sure it is. Pure: outcomes in,
//! a decision out (the same rule for `classify`, `evaluate` and the
//! console's live estimate).

use std::collections::BTreeMap;

use serde::Serialize;

#[cfg(doc)]
use super::Prediction;

/// One sub-window's k-NN outcome within a recording's vote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowVote {
    /// The sub-window's index along the window (0 first).
    pub window: usize,
    /// Its k-NN prediction.
    pub label: String,
    /// Its neighbours' votes, as [`Prediction::votes`].
    pub votes: Vec<(String, usize)>,
}

/// One class's share of a recording's vote over its sub-windows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowTally {
    pub label: String,
    /// Sub-windows predicting this class.
    pub windows: usize,
    /// Neighbour votes for this class summed over all the sub-windows.
    pub neighbour_votes: usize,
}

/// A recording classified by the vote of its sub-windows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingPrediction {
    /// The class of most sub-windows; a tie goes to the class with more
    /// neighbour votes summed over all sub-windows, then to the first label
    /// in sorted order. `tally[0].label`.
    pub label: String,
    /// Every class any sub-window's neighbours voted for, in deciding order.
    pub tally: Vec<WindowTally>,
    /// Each sub-window's outcome, in window order.
    pub windows: Vec<WindowVote>,
}

impl RecordingPrediction {
    /// How sure the vote is: the share of sub-windows that chose the label (0..1).
    pub fn agreement(&self) -> f64 {
        match self.tally.first() {
            Some(t) if !self.windows.is_empty() => t.windows as f64 / self.windows.len() as f64,
            _ => 0.0,
        }
    }
}

/// The vote over sub-windows' outcomes (see [`RecordingPrediction::label`]);
/// `None` for no sub-window.
pub fn vote(windows: Vec<WindowVote>) -> Option<RecordingPrediction> {
    let mut tally: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    for w in &windows {
        tally.entry(w.label.as_str()).or_default().0 += 1;
        for (label, n) in &w.votes {
            tally.entry(label.as_str()).or_default().1 += n;
        }
    }
    // Sorted by label already (BTreeMap); a stable sort keeps that order
    // among full ties.
    let mut tally: Vec<WindowTally> = tally
        .into_iter()
        .map(|(label, (windows, neighbour_votes))| WindowTally {
            label: label.to_string(),
            windows,
            neighbour_votes,
        })
        .collect();
    tally.sort_by(|a, b| {
        b.windows
            .cmp(&a.windows)
            .then(b.neighbour_votes.cmp(&a.neighbour_votes))
    });
    let label = tally.first()?.label.clone();
    Some(RecordingPrediction {
        label,
        tally,
        windows,
    })
}
