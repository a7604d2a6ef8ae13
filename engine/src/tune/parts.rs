//! The parts a search runs on: the outer split's training and test parts
//! (the profile's `[evaluation]`, as `evaluate` deals it) and, inside each
//! training part, the inner folds that score the settings, dealt as the
//! outer split is ([`InnerSplit`]). Folds come from the one place every
//! split asks ([`crate::evaluate::cv`] over [`crate::folds`]).

use std::collections::BTreeMap;

use serde::Serialize;

use super::{Data, INNER_FOLDS, Part, TuneError, plan_error};
use crate::classify::{TrainingExample, plural};
use crate::dataset::Entry;
use crate::evaluate::cv::{Dealt, deal, deal_forward, make_folds};
use crate::evaluate::plan::Plan;
use crate::evaluate::split;
use crate::folds::Shared;
use crate::import::Segment;
use crate::profile::{Profile, SplitMethod};

/// The outer parts of the profile's plan over the scans (one per outer
/// fold; a holdout has one).
pub fn outer_parts(
    profile: &Profile,
    scans: &[Entry],
    plan: &Plan,
) -> Result<Vec<Part>, TuneError> {
    let data = Data::new(scans, plan.group_by.as_deref())?;
    let all: Vec<usize> = (0..scans.len()).collect();
    if plan.method == SplitMethod::Holdout {
        let stubs: Vec<TrainingExample> = scans
            .iter()
            .map(|s| TrainingExample {
                file: s.file.clone(),
                label: s.label.clone(),
                features: Vec::new(),
            })
            .collect();
        let mut eval = profile.evaluation.clone();
        eval.shuffle_seed = plan.holdout_shuffle;
        let sp = split(stubs, &eval)?;
        let index: BTreeMap<&str, usize> = scans
            .iter()
            .enumerate()
            .map(|(i, s)| (s.file.as_str(), i))
            .collect();
        let pick = |v: &[TrainingExample]| -> Vec<usize> {
            v.iter().map(|e| index[e.file.as_str()]).collect()
        };
        let test = pick(&sp.test);
        // Trials overlapping a tested one never train (segments of one recording).
        let gone = shared_of(scans, &all).neighbours(&test);
        return Ok(vec![Part {
            train: pick(&sp.train)
                .into_iter()
                .filter(|i| gone.binary_search(i).is_err())
                .collect(),
            test,
        }]);
    }
    let dealt = deal(
        &data.label_refs(&all),
        data.group_of(&all).as_deref(),
        &shared_of(scans, &all),
        plan.method,
        plan.folds,
        plan.seed,
    )?;
    Ok(dealt_to_parts(&all, &dealt))
}

/// The segments of `within`'s scans, in its order ([`Shared`]).
fn shared_of(scans: &[Entry], within: &[usize]) -> Shared {
    Shared::new(within.iter().map(|&i| span_of(&scans[i])).collect())
}

/// Folds (positions in `within`) as parts over `within`'s indices, each
/// fold's purged positions (overlapping a tested one) trained on by none.
fn dealt_to_parts(within: &[usize], dealt: &Dealt) -> Vec<Part> {
    dealt
        .folds
        .iter()
        .zip(&dealt.purged)
        .map(|(f, gone)| {
            let mut out = vec![false; within.len()];
            for &p in f.iter().chain(gone) {
                out[p] = true;
            }
            Part {
                train: (0..within.len())
                    .filter(|&p| !out[p])
                    .map(|p| within[p])
                    .collect(),
                test: f.iter().map(|&p| within[p]).collect(),
            }
        })
        .collect()
}

/// The segment a trial's metadata describes (`import --split`), when its
/// start and length are finite.
pub(super) fn span_of(e: &Entry) -> Option<Segment> {
    Segment::of(|key| e.meta_text(key)).filter(|s| s.start.is_finite() && s.length.is_finite())
}

/// How a search's inner folds deal its training part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum InnerSplit {
    /// Stratified folds, shuffled with the seed (the outer split is shuffled).
    Shuffled,
    /// Whole groups (`group_by`).
    Grouped,
    /// Consecutive blocks of each source's overlapping trials, the trials
    /// overlapping a fold's test ones left out of its training.
    Blocks,
    /// Forward in time, as a time split tests: each fold trains on the
    /// earlier trials of each label and tests the next ones ([`deal_forward`]).
    Forward,
}

impl InnerSplit {
    /// How the folds were made, for the report and the tuned profile.
    pub fn describe(self) -> &'static str {
        match self {
            InnerSplit::Shuffled => "stratified, shuffled",
            InnerSplit::Grouped => "whole groups",
            InnerSplit::Blocks => "blocks in time, overlapping trials left out",
            InnerSplit::Forward => {
                "forward in time: each trains on the earlier trials of each label and tests the next"
            }
        }
    }

    /// How the inner folds of a search under `plan` deal a training part:
    /// forward in time when the outer split is a time split (a holdout in
    /// file-name order), so the inner folds test the drift the outer one
    /// does; whole groups with `group_by`; else blocks in time over
    /// overlapping trials, shuffled otherwise ([`inner_parts`] decides
    /// between those two per part).
    pub fn of(plan: &Plan) -> InnerSplit {
        if plan.group_by.is_some() {
            InnerSplit::Grouped
        } else if plan.method == SplitMethod::Holdout && plan.holdout_shuffle.is_none() {
            InnerSplit::Forward
        } else {
            InnerSplit::Shuffled
        }
    }
}

/// The inner folds of a training part, [`INNER_FOLDS`] of them or as many
/// as there are recordings or groups: forward in time when `split` says so;
/// grouped with groups; without groups, over trials that overlap in time
/// (`import --split` with `--split-hop`), consecutive blocks of each
/// source's trials, the trials overlapping a fold's test ones left out of
/// its training, as every split deals them ([`deal`]: shuffled folds would
/// test a trial beside its own overlapping neighbour and flatter the
/// settings that memorise); stratified and shuffled otherwise. Returns the
/// parts and how they were made.
pub fn inner_parts(
    scans: &[Entry],
    group_by: Option<&str>,
    train: &[usize],
    seed: u64,
    split: InnerSplit,
) -> Result<(Vec<Part>, InnerSplit), TuneError> {
    let data = Data::new(scans, group_by)?;
    let shared = shared_of(scans, train);
    if split == InnerSplit::Forward && group_by.is_none() {
        let dealt = deal_forward(&data.label_refs(train), &shared, INNER_FOLDS).map_err(|e| {
            plan_error(format!(
                "the time split's training part cannot be folded forward in time: {e}"
            ))
        })?;
        return Ok((dealt_to_parts(train, &dealt), InnerSplit::Forward));
    }
    if group_by.is_none() && shared.overlapping() {
        let folds = INNER_FOLDS.min(shared.longest_source());
        if folds >= 2 {
            let dealt = deal(
                &data.label_refs(train),
                None,
                &shared,
                SplitMethod::KFold,
                folds,
                seed,
            )
            .map_err(|e| {
                plan_error(format!(
                    "a training part's overlapping trials cannot be folded in time: {e}"
                ))
            })?;
            return Ok((dealt_to_parts(train, &dealt), InnerSplit::Blocks));
        }
    }
    let groups = data.group_of(train);
    let units = match &groups {
        Some(g) => {
            let mut g: Vec<&String> = g.iter().collect();
            g.sort_unstable();
            g.dedup();
            g.len()
        }
        None => train.len(),
    };
    let folds = INNER_FOLDS.min(units);
    if folds < 2 {
        let (one, many) = if groups.is_some() {
            ("group", "groups")
        } else {
            ("recording", "recordings")
        };
        return Err(plan_error(format!(
            "a training part has {}: the search needs at least 2 to score settings inside it; give the training part more",
            plural(units, one, many)
        )));
    }
    let f = make_folds(
        &data.label_refs(train),
        groups.as_deref(),
        SplitMethod::KFold,
        folds,
        seed,
    )?;
    let made = if groups.is_some() {
        InnerSplit::Grouped
    } else {
        InnerSplit::Shuffled
    };
    Ok((dealt_to_parts(train, &Dealt::plain(f)), made))
}

/// The recordings every one of `folds` trains on (none of them tests
/// one, as a fold never tests what it trains on), in the first fold's
/// order: under a time split, the earliest block of trials. Empty with
/// fewer than two folds, and when the folds test every recording once
/// (shuffled, grouped and block folds).
pub fn trained_on_by_all(folds: &[Part]) -> Vec<usize> {
    match folds.split_first() {
        Some((first, rest)) if !rest.is_empty() => {
            // `trained_by[r]`: how many of the other folds, one after
            // another from the first, train on recording `r` (each fold
            // counted once): one pass over each fold, not a search of
            // every fold for every recording.
            let top = folds
                .iter()
                .flat_map(|f| f.train.iter())
                .max()
                .map_or(0, |&r| r + 1);
            let mut trained_by = vec![0usize; top];
            for (i, f) in rest.iter().enumerate() {
                for &r in &f.train {
                    if trained_by[r] == i {
                        trained_by[r] = i + 1;
                    }
                }
            }
            first
                .train
                .iter()
                .copied()
                .filter(|&r| trained_by[r] == rest.len())
                .collect()
        }
        _ => Vec::new(),
    }
}

/// Every recording `folds` train or test on, sorted, each once.
pub fn recordings_of<'a>(folds: impl IntoIterator<Item = &'a Part>) -> Vec<usize> {
    let mut used: Vec<usize> = folds
        .into_iter()
        .flat_map(|f| f.train.iter().chain(&f.test).copied())
        .collect();
    used.sort_unstable();
    used.dedup();
    used
}
