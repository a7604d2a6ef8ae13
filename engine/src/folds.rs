//! Which recordings share signal, for every split that deals recordings
//! into training and test: trials cut from one long recording (`import
//! --split`) are segments of one source, and two that overlap in time
//! (`--split-hop` below `--split`) hold the same samples. A split that
//! tests one and trains on its overlapping neighbour scores memory, not
//! texture: white noise cut into overlapping segments scored 74 to 80 %
//! (chance 33 %) under shuffled folds.
//!
//! So every split asks this module: [`Shared::neighbours`] are left out of
//! a fold's training ([`Shared::purge`]), and [`Shared::time_blocks`] deals
//! each source's segments into folds as consecutive blocks in time, so a
//! fold tests a stretch of the recording and trains on the rest. Ground
//! layer: reads no files, never prints.

use std::collections::BTreeMap;

/// The metadata keys each trial of `import --split` gets: its number,
/// start and length (its source is the recording's `source`).
pub const SEGMENT_KEYS: [&str; 3] = ["segment", "segment_start_s", "segment_length_s"];

/// Where a trial lies in the long recording it was cut from, as its
/// metadata says ([`SEGMENT_KEYS`] and `source`): read by every split,
/// `profile new` (the time split's gap) and `tune`, so all judge overlap
/// alike.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub source: String,
    /// Seconds from the source's first sample.
    pub start: f64,
    pub length: f64,
}

impl Segment {
    /// The segment a recording's metadata describes, each value as text
    /// (`meta("segment_start_s")`); `None` when a key is missing or a value
    /// is not finite.
    pub fn of(meta: impl Fn(&str) -> Option<String>) -> Option<Segment> {
        Some(Segment {
            source: meta("source")?,
            start: meta(SEGMENT_KEYS[1])?.parse().ok()?,
            length: meta(SEGMENT_KEYS[2])?.parse().ok()?,
        })
    }

    /// How far two segments may overlap and still only meet end to start
    /// (float noise in `j * hop`): this part of the longer one's length.
    pub const TOUCH: f64 = 1e-9;

    /// Whether the two share signal: the same source, overlapping in time
    /// (segments that only meet end to start do not).
    pub fn overlaps(&self, other: &Segment) -> bool {
        let touch = Self::TOUCH * self.length.max(other.length);
        self.source == other.source
            && self.start < other.start + other.length - touch
            && other.start < self.start + self.length - touch
    }
}

/// The segments of the items a split deals (one per item: an example, a
/// recording; `None` for an item that is no segment).
#[derive(Debug, Clone, Default)]
pub struct Shared {
    spans: Vec<Option<Segment>>,
    /// Each source's items, in time order.
    by_source: BTreeMap<String, Vec<usize>>,
    /// Each item's place in its source's list, and that source's longest
    /// segment (how far back an overlapping one may start).
    place: Vec<Option<(usize, f64)>>,
}

impl Shared {
    /// The segments of `spans`' items; a span that is not finite counts as none.
    pub fn new(spans: Vec<Option<Segment>>) -> Shared {
        let spans: Vec<Option<Segment>> = spans
            .into_iter()
            .map(|s| s.filter(|s| s.start.is_finite() && s.length.is_finite() && s.length > 0.0))
            .collect();
        let mut by_source: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (i, s) in spans.iter().enumerate() {
            if let Some(s) = s {
                by_source.entry(s.source.clone()).or_default().push(i);
            }
        }
        let start = |i: usize| spans[i].as_ref().map_or(0.0, |s| s.start);
        let mut place = vec![None; spans.len()];
        for items in by_source.values_mut() {
            items.sort_by(|&a, &b| start(a).total_cmp(&start(b)));
            let longest = items
                .iter()
                .filter_map(|&i| spans[i].as_ref().map(|s| s.length))
                .fold(0.0, f64::max);
            for (p, &i) in items.iter().enumerate() {
                place[i] = Some((p, longest));
            }
        }
        Shared {
            spans,
            by_source,
            place,
        }
    }

    /// Items that are no segments at all: nothing shared.
    pub fn none(n: usize) -> Shared {
        Shared::new(vec![None; n])
    }

    pub fn len(&self) -> usize {
        self.spans.len()
    }

    pub fn is_empty(&self) -> bool {
        self.spans.is_empty()
    }

    /// The most segments any one source has among the items.
    pub fn longest_source(&self) -> usize {
        self.by_source.values().map(Vec::len).max().unwrap_or(0)
    }

    /// Whether some source was cut into more than one of these items: its
    /// segments are not independent, and a split must deal them in time.
    pub fn has_segments(&self) -> bool {
        self.by_source.values().any(|v| v.len() > 1)
    }

    /// Whether two items overlap in time (they hold the same samples).
    pub fn overlapping(&self) -> bool {
        self.by_source.values().any(|items| {
            items.windows(2).any(|w| {
                matches!((&self.spans[w[0]], &self.spans[w[1]]), (Some(a), Some(b)) if a.overlaps(b))
            })
        })
    }

    /// The items outside `test` that overlap one in `test`: what a fold
    /// testing `test` must leave out of its training. Each tested segment's
    /// neighbours are found by walking its source's list (in time order)
    /// only as far as an overlap can reach: linear in what is near it.
    pub fn neighbours(&self, test: &[usize]) -> Vec<usize> {
        if self.by_source.is_empty() {
            return Vec::new();
        }
        let mut tested = vec![false; self.spans.len()];
        for &t in test {
            if t < tested.len() {
                tested[t] = true;
            }
        }
        let mut out = Vec::new();
        for &t in test {
            let (Some(Some(st)), Some(Some((p, longest)))) = (self.spans.get(t), self.place.get(t))
            else {
                continue;
            };
            let items = &self.by_source[&st.source];
            let mut near = |i: usize| {
                if let Some(si) = &self.spans[i]
                    && !tested[i]
                    && si.overlaps(st)
                {
                    out.push(i);
                }
            };
            for &i in items[..*p].iter().rev() {
                // Sorted by start: one starting a longest segment or more
                // before this one ends before it starts.
                if self.spans[i]
                    .as_ref()
                    .is_some_and(|s| s.start + longest <= st.start)
                {
                    break;
                }
                near(i);
            }
            for &i in &items[p + 1..] {
                if self.spans[i]
                    .as_ref()
                    .is_some_and(|s| s.start >= st.start + st.length)
                {
                    break;
                }
                near(i);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// For each fold (its test items), the items left out of its training.
    pub fn purge(&self, folds: &[Vec<usize>]) -> Vec<Vec<usize>> {
        folds.iter().map(|test| self.neighbours(test)).collect()
    }

    /// `folds` folds in which each source's segments among `items` go in
    /// consecutive blocks in time (fold `f` takes block `f` of every
    /// source); the items that are no segments are dealt by `deal` (the
    /// usual shuffled, stratified way), given those items and the folds.
    pub fn time_blocks(
        &self,
        items: &[usize],
        folds: usize,
        deal: impl FnOnce(&[usize]) -> Vec<Vec<usize>>,
    ) -> Vec<Vec<usize>> {
        let mut inside = vec![false; self.spans.len()];
        for &i in items {
            inside[i] = true;
        }
        let mut out = vec![Vec::new(); folds];
        for source in self.by_source.values() {
            let mine: Vec<usize> = source.iter().copied().filter(|&i| inside[i]).collect();
            let n = mine.len();
            for (j, &i) in mine.iter().enumerate() {
                out[j * folds / n.max(1)].push(i);
            }
        }
        let loose: Vec<usize> = items
            .iter()
            .copied()
            .filter(|&i| self.spans[i].is_none())
            .collect();
        if !loose.is_empty() {
            for (f, dealt) in deal(&loose).into_iter().enumerate() {
                out[f % folds].extend(dealt);
            }
        }
        for f in &mut out {
            f.sort_unstable();
        }
        out.retain(|f| !f.is_empty());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(source: &str, start: f64, length: f64) -> Option<Segment> {
        Some(Segment {
            source: source.into(),
            start,
            length,
        })
    }

    #[test]
    fn overlapping_neighbours_are_left_out_and_blocks_are_in_time() {
        // a: 0-1, 0.5-1.5, 1-2, 1.5-2.5 (hop 0.5); b: 0-1, 1-2 (adjacent); one loose item.
        let spans = vec![
            seg("a", 1.0, 1.0),
            seg("a", 0.0, 1.0),
            seg("a", 0.5, 1.0),
            seg("a", 1.5, 1.0),
            seg("b", 0.0, 1.0),
            seg("b", 1.0, 1.0),
            None,
        ];
        let s = Shared::new(spans);
        assert!(s.has_segments() && s.overlapping());
        // a's 1-2 overlaps 0.5-1.5 and 1.5-2.5, and only meets 0-1.
        assert_eq!(s.neighbours(&[0]), [2, 3]);
        // Adjacent segments share no samples.
        assert!(s.neighbours(&[4]).is_empty());
        let blocks = s.time_blocks(&[0, 1, 2, 3, 4, 5, 6], 2, |loose| vec![loose.to_vec()]);
        // Fold 0: a's first half (0-1, 0.5-1.5), b's 0-1, and the loose item.
        assert_eq!(blocks, [vec![1, 2, 4, 6], vec![0, 3, 5]]);
        assert_eq!(s.purge(&blocks)[0], [0]);
        let adjacent = Shared::new(vec![seg("b", 0.0, 1.0), seg("b", 1.0, 1.0)]);
        assert!(adjacent.has_segments() && !adjacent.overlapping());
        assert!(!Shared::none(3).has_segments());
    }
}
