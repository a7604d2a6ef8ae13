//! The `[evaluation]` of a drafted profile: the method that can test every
//! label written out, the others as commented groups, and for segments of
//! long recordings (`import --split`) a split in time that leaves out the
//! segments sharing signal across its boundary ([`time_split`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::Plan;
use super::survey::Segment;
use super::writer::{Doc, OptionGroup};

/// The evaluation methods that can test every label, the first choice
/// written out and the others as groups.
pub(super) fn evaluation_table(doc: &mut Doc, p: &Plan) {
    let min = p.min_count;
    let folds = min.clamp(2, 10);
    let TimeSplit {
        train,
        gap,
        test,
        shared,
        overlapping,
    } = p.split;
    // Shuffled folds put a segment beside its overlapping neighbour.
    let flatters = if overlapping {
        "; the segments overlap, so neighbours sharing signal fall on both sides: this flatters"
    } else {
        ""
    };
    let grouping = group_by_group(p);
    let by_source = grouping
        .as_ref()
        .is_some_and(|g| g.keys.contains(&("group_by", "\"source\"".into())));
    let loo = OptionGroup {
        when: format!(
            "each recording tested against all the others: few recordings per label{flatters}"
        ),
        keys: vec![("method", "\"leave-one-out\"".into())],
    };
    let kfold = OptionGroup {
        when: format!(
            "stratified {folds}-fold cross-validation: several recordings per label{flatters}"
        ),
        keys: vec![
            ("method", "\"k-fold\"".into()),
            ("folds", folds.to_string()),
        ],
    };
    let left_out = match gap {
        0 => String::new(),
        g => format!(", the next {g} are left out"),
    };
    let mut holdout = OptionGroup {
        when: format!(
            "a fixed split in time: per label the first {train} recordings (file-name order) train{left_out} and the next {test} test; for recordings made in order, the later ones drifting"
        ),
        keys: vec![
            ("method", "\"holdout\"".into()),
            ("train_per_class", train.to_string()),
            ("test_per_class", test.to_string()),
        ],
    };
    if gap > 0 {
        holdout.keys.push(("gap_per_class", gap.to_string()));
    }
    let (why, first, others) = if min < 2 {
        (
            format!(
                "Only {min} recording of some label: nothing to test it against. Record more, or cut\n\
                 long recordings into trials: `hapticlab import … --split SECONDS` (evaluate refuses this)."
            ),
            loo,
            Vec::new(),
        )
    } else if p.segments {
        (
            format!(
                "The recordings are consecutive segments of longer ones (`import --split`): neighbours\n\
                 resemble each other, so the first {train} segments of each label train and the next {test} test.{}{}",
                overlap_note(gap, shared),
                if by_source {
                    "\nA label with several source files: the split runs through them in file-name order, one\n\
                     source after another; the group_by group below keeps each source on one side instead."
                } else {
                    ""
                }
            ),
            holdout,
            vec![kfold, loo],
        )
    } else if min < 5 {
        (
            format!(
                "Fewer than 5 recordings of some label ({min}): each is tested against all the others."
            ),
            loo,
            vec![kfold, holdout],
        )
    } else {
        (
            format!(
                "{min} or more recordings per label: stratified {folds}-fold cross-validation."
            ),
            kfold,
            vec![loo, holdout],
        )
    };
    doc.table("evaluation");
    doc.comment(&why);
    for (k, v) in &first.keys {
        let _ = writeln!(doc.0, "{k} = {v}");
    }
    if !others.is_empty() {
        doc.comment("(a method group below replaces every line above: comment them all out)");
    }
    doc.blank();
    let mut groups = others;
    groups.extend(grouping);
    doc.groups(&groups);
}

/// The split in time of a draft: per label, the first `train` recordings
/// train, the next `gap` are left out, the next `test` test.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct TimeSplit {
    pub train: usize,
    pub gap: usize,
    pub test: usize,
    /// Test segments that share signal with training ones when there are
    /// too few to leave them out (no gap then): a caution.
    pub shared: usize,
    /// Some label's consecutive segments overlap.
    pub overlapping: bool,
}

/// The time split: half and half (the thesis's own split was 20 + 10 of
/// 30); 70 / 30 for segments of long recordings, so more of each trains,
/// with the segments that overlap a training one left out between
/// (`gap_per_class`) so no signal is on both sides.
pub(super) fn time_split(
    segments: &BTreeMap<String, Vec<Option<Segment>>>,
    min: usize,
    cut: bool,
) -> TimeSplit {
    if !cut {
        let train = min.div_ceil(2);
        return TimeSplit {
            train,
            test: min.saturating_sub(train),
            ..TimeSplit::default()
        };
    }
    let seventy = |n: usize| (n * 7).div_ceil(10).min(n.saturating_sub(1)).max(1);
    let overlapping = segments.values().any(|s| {
        s.windows(2)
            .any(|w| matches!(w, [Some(a), Some(b)] if a.overlaps(b)))
    });
    // The gap depends on where the boundary falls and the boundary on the
    // gap; segments of one length and hop settle at once.
    let (mut train, mut gap) = (seventy(min), 0);
    for _ in 0..4 {
        let needed = sharing(segments, train).0;
        if needed <= gap {
            break;
        }
        gap = needed;
        train = seventy(min.saturating_sub(gap));
    }
    if sharing(segments, train).0 > gap || train + gap >= min {
        // Too few segments to leave any out: split as before, and count.
        let train = seventy(min);
        return TimeSplit {
            train,
            test: min.saturating_sub(train),
            shared: sharing(segments, train).1,
            overlapping,
            ..TimeSplit::default()
        };
    }
    TimeSplit {
        train,
        gap,
        test: min - train - gap,
        shared: 0,
        overlapping,
    }
}

/// With the first `train` segments of each label training: how many
/// after them to leave out so that none tested overlaps one trained on
/// (the most any label needs), and how many overlap one in all.
fn sharing(segments: &BTreeMap<String, Vec<Option<Segment>>>, train: usize) -> (usize, usize) {
    let (mut gap, mut count) = (0, 0);
    for list in segments.values() {
        let (trained, rest) = list.split_at(train.min(list.len()));
        for (i, s) in rest.iter().enumerate() {
            let Some(s) = s else { continue };
            if trained.iter().flatten().any(|t| t.overlaps(s)) {
                gap = gap.max(i + 1);
                count += 1;
            }
        }
    }
    (gap, count)
}

/// What the `[evaluation]` comment says of overlapping segments.
fn overlap_note(gap: usize, shared: usize) -> String {
    if gap > 0 {
        format!(
            "\nThe segments overlap (`--split-hop` shorter than `--split`): the {gap} after each label's\n\
             training ones share signal with them, so gap_per_class = {gap} leaves them out of both sides."
        )
    } else if shared > 0 {
        format!("\nCaution: {}.", super::wrap(&shared_caution(shared), 90))
    } else {
        String::new()
    }
}

/// The caution, for stderr and the profile, when overlapping segments
/// could not be left out of the time split.
pub(super) fn shared_caution(shared: usize) -> String {
    format!(
        "{shared} test segment(s) of the time split share signal with training ones (`import --split-hop` shorter \
         than `--split`), and there are too few segments to leave them out (gap_per_class): its score flatters; \
         import again with a hop of at least the length, or record more"
    )
}

/// Leave-one-out keeping together the recordings that share a metadata
/// value: offered for a key that groups recordings (some share a value)
/// and gives every label at least two groups (so each can be tested);
/// the source file first (segments of one recording).
fn group_by_group(p: &Plan) -> Option<OptionGroup> {
    // A segment's index or start is shared across recordings by position,
    // not by what makes them alike.
    let fits = |k: &&String| {
        !k.starts_with("segment")
            && p.s
                .groups
                .get(*k)
                .is_some_and(|(fewest, shared)| *fewest >= 2 && *shared)
    };
    let key =
        p.s.varying_meta
            .iter()
            .filter(fits)
            .min_by_key(|k| k.as_str() != "source")?;
    Some(OptionGroup {
        when: format!(
            "recordings sharing a {key} stay on one side of every split: trials or sessions that resemble each other"
        ),
        keys: vec![
            ("method", "\"leave-one-out\"".into()),
            ("group_by", format!("{key:?}")),
        ],
    })
}
