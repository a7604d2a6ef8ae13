//! The survey behind `profile new`: every recording of a folder read (on
//! every core) and summed up — labels and counts, the columns all share,
//! the rate, each column's shortest travel, step and spread, how far the
//! recordings reach along an axis, the metadata that varies, where
//! segments of long recordings lie — and the axis and signal columns
//! chosen from that.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

pub use crate::import::Segment;

use crate::dataset;
use crate::recording::{self, Recording};
use crate::support::{Failure, bad, progress_bar, runtime, warn_skipped};

/// What one complete recording tells about the folder.
#[derive(Debug, Clone)]
struct Seen {
    file: String,
    label: String,
    columns: Vec<String>,
    /// The sample rate: `rate_hz` in the metadata, else from `t_s`.
    rate_hz: Option<f64>,
    /// Per column: the travel from the first sample along the direction of
    /// travel (what the analysis measures on an axis), and the spread.
    travel: Vec<f64>,
    step: Vec<f64>,
    spread: Vec<f64>,
    meta: Vec<(String, String)>,
}

/// The folder's recordings, summed up.
#[derive(Debug, Clone, Default)]
pub struct Survey {
    pub complete: usize,
    /// Files left out: incomplete (no `# end samples` trailer).
    pub incomplete: Vec<String>,
    pub labels: BTreeMap<String, usize>,
    /// Columns every complete recording has, in the first one's order.
    pub columns: Vec<String>,
    pub rate_hz: f64,
    /// Per column: the shortest travel over the recordings, and which file.
    pub shortest: BTreeMap<String, (f64, String)>,
    /// Per column: the median over the recordings of the net progress per
    /// sample, and the mean spread.
    pub step: BTreeMap<String, f64>,
    pub spread: BTreeMap<String, f64>,
    /// Metadata keys that take more than one value (session, trial, …).
    pub varying_meta: Vec<String>,
    /// The first recording and the first whose columns differ from its,
    /// each with its columns: named when the shared columns leave nothing
    /// to analyse.
    pub differing: Option<[(String, Vec<String>); 2]>,
    /// Per varying key: the fewest distinct values any label has, and
    /// whether some value is shared by two recordings (so the key groups).
    pub groups: BTreeMap<String, (usize, bool)>,
    /// The distinct sample rates (within 1 %), slowest first.
    pub rates: Vec<RateGroup>,
    /// Per column that can be the axis (`t_s`, the positions): how far the
    /// recordings reach along it.
    pub reach: BTreeMap<String, Reach>,
    /// Per label, in file-name order (the order of a time split): where
    /// each recording lies in its source, when it is a segment of a long
    /// one (`import --split`); empty when none is.
    pub segments: BTreeMap<String, Vec<Option<Segment>>>,
    /// The first two file names of one label that file-name order (the
    /// order of a time split) puts against their numbers: `trial10.csv`
    /// before `trial2.csv`, numbered without leading zeros.
    pub out_of_number_order: Option<(String, String)>,
}

/// How far the recordings reach along an axis: what a window can cover.
#[derive(Debug, Clone, Default)]
pub struct Reach {
    /// The median travel.
    pub median: f64,
    /// The recordings under half the median travel (aborted or cut-short
    /// trials), shortest first: file and travel.
    pub short: Vec<(String, f64)>,
    /// The shortest travel of the others, and its file.
    pub typical: (f64, String),
}

/// A few recordings much shorter than the rest (at most a quarter of
/// them) are taken for aborted trials: the window fits the others. More
/// than that and the lengths simply vary: the window fits the shortest.
fn few(short: usize, all: usize) -> bool {
    short > 0 && short * 4 <= all
}

/// The [`Reach`] of recordings' travels along a column.
pub(super) fn reach<'a>(travels: impl Iterator<Item = (f64, &'a String)>) -> Reach {
    let mut all: Vec<(f64, &String)> = travels.collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then_with(|| a.1.cmp(b.1)));
    let median = all.get(all.len() / 2).map_or(0.0, |t| t.0);
    let cut = all.partition_point(|t| t.0 < median / 2.0);
    Reach {
        median,
        short: all[..cut]
            .iter()
            .map(|(t, f)| (f.to_string(), *t))
            .collect(),
        typical: all
            .get(cut)
            .map_or((0.0, String::new()), |(t, f)| (*t, f.to_string())),
    }
}

/// The recordings that share a sample rate (within 1 % of the slowest of
/// them).
#[derive(Debug, Clone)]
pub struct RateGroup {
    pub hz: f64,
    pub count: usize,
    /// One of them.
    pub file: String,
    /// How many of them each label has.
    pub labels: BTreeMap<String, usize>,
}

impl Survey {
    /// What a window along `column` fits, and its file: the shortest
    /// recording that is not one of a few much shorter ones ([`Reach`]).
    /// The second value: those left uncovered.
    pub fn window_reach(&self, column: &str) -> ((f64, String), &[(String, f64)]) {
        match self.reach.get(column) {
            Some(r) if few(r.short.len(), self.complete) => (r.typical.clone(), &r.short),
            _ => (self.shortest.get(column).cloned().unwrap_or_default(), &[]),
        }
    }

    /// The rate a time axis is resampled at: the slowest, so that every
    /// point holds a sample of each recording.
    pub fn slowest_rate(&self) -> f64 {
        self.rates.first().map_or(self.rate_hz, |r| r.hz)
    }
}

/// Read every recording under `dir` (on every core) and sum them up.
pub fn survey(dir: &Path) -> Result<Survey, Failure> {
    let files = recording::collect_files(&[dir.to_path_buf()]).map_err(|e| {
        if e.is_bad_input() || matches!(e, recording::RecordingError::Io { .. }) {
            bad(e)
        } else {
            runtime(e)
        }
    })?;
    if files.is_empty() {
        return Err(bad(format!(
            "{}: no recordings (*.csv, *.csv.gz) to write a profile from; {}",
            dir.display(),
            crate::support::IMPORT_HINT
        )));
    }
    let pb = progress_bar(files.len() as u64, "reading");
    let threads = dataset::cores().clamp(1, files.len());
    let chunk = files.len().div_ceil(threads);
    let results: Vec<Result<Option<Seen>, Failure>> = std::thread::scope(|scope| {
        let handles: Vec<_> = files
            .chunks(chunk)
            .map(|part| {
                let pb = &pb;
                scope.spawn(move || {
                    part.iter()
                        .map(|f| {
                            let r = look_at(f);
                            pb.inc(1);
                            r
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|_| vec![Err(runtime("a reader thread failed"))])
            })
            .collect()
    });
    pb.finish_and_clear();
    let mut seen = Vec::new();
    let mut incomplete = Vec::new();
    for (f, r) in files.iter().zip(results) {
        match r? {
            Some(s) => seen.push(s),
            None => incomplete.push(f.display().to_string()),
        }
    }
    if seen.is_empty() {
        return Err(bad(format!(
            "{}: none of the {} recording(s) is complete (each lacks the `# end samples = N` trailer): nothing to fit a window to",
            dir.display(),
            files.len()
        )));
    }
    Ok(sum_up(&seen, incomplete))
}

/// One recording's summary; `None` when it is incomplete, or not a
/// regular file (a FIFO named like a recording: warned about, never read).
fn look_at(file: &Path) -> Result<Option<Seen>, Failure> {
    let rec = match recording::read(file) {
        Ok(rec) => rec,
        Err(recording::RecordingError::Io { source, .. }) if crate::io::not_regular(&source) => {
            warn_skipped(&[dataset::Skipped::Unusable {
                file: file.display().to_string(),
                reason: source.to_string(),
                unreadable: true,
            }]);
            return Ok(None);
        }
        // Another rig's file: what turns it into a recording.
        Err(e) if e.is_not_a_recording() => {
            return Err(bad(format!("{e}; {}", crate::support::IMPORT_HINT)));
        }
        Err(e) => return Err(if e.is_bad_input() { bad(e) } else { runtime(e) }),
    };
    if !rec.is_complete() || rec.len() < 2 {
        return Ok(None);
    }
    let label = dataset::label_of(&rec, file).map_err(bad)?;
    Ok(Some(summarise(&rec, file, label)))
}

fn summarise(rec: &Recording, file: &Path, label: String) -> Seen {
    let n = rec.len();
    let mut travel = Vec::new();
    let mut step = Vec::new();
    let mut spread = Vec::new();
    for c in 0..rec.columns.len() {
        let v = &rec.data[c];
        let dir = if v[n - 1] >= v[0] { 1.0 } else { -1.0 };
        travel.push(v.iter().map(|x| dir * (x - v[0])).fold(0.0, f64::max));
        // The net progress per sample: encoder steps and noise average out.
        step.push((v[n - 1] - v[0]).abs() / (n - 1) as f64);
        let mean = v.iter().sum::<f64>() / n as f64;
        spread.push((v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt());
    }
    let time = rec.columns.iter().position(|c| c == "t_s");
    let t_step = time.map(|i| step[i]).filter(|s| *s > 0.0);
    // The rate said in the metadata is exact but for float noise; one
    // measured from `t_s` is as good as the samples' timing.
    let rate_hz = match rec
        .meta_f64("rate_hz")
        .filter(|r| r.is_finite() && *r > 0.0)
    {
        Some(r) => Some(tidy_rate(r, FLOAT_NOISE)),
        None => {
            t_step.map(|s| tidy_rate(1.0 / s, time.map_or(FLOAT_NOISE, |i| timing(&rec.data[i]))))
        }
    };
    Seen {
        file: file.display().to_string(),
        label,
        columns: rec.columns.clone(),
        rate_hz,
        travel,
        step,
        spread,
        meta: rec
            .meta
            .iter()
            .map(|(k, v)| (k.clone(), dataset::meta_text(v)))
            .collect(),
    }
}

/// The relative error of a rate that is only float noise (a sum of many
/// sample times, or a rate written by a program as 999.9999999999998).
const FLOAT_NOISE: f64 = 1e-9;

/// The relative uncertainty of the mean sample period of `t`: twice the
/// standard error of the periods (their jitter over the root of their
/// number), at least [`FLOAT_NOISE`].
fn timing(t: &[f64]) -> f64 {
    let n = t.len().saturating_sub(1);
    if n < 2 {
        return FLOAT_NOISE;
    }
    let mean = (t[n] - t[0]) / n as f64;
    let var = t
        .windows(2)
        .map(|w| (w[1] - w[0] - mean).powi(2))
        .sum::<f64>()
        / (n - 1) as f64;
    (2.0 * var.sqrt() / (mean.abs() * (n as f64).sqrt())).max(FLOAT_NOISE)
}

/// `rate` to the fewest significant digits (up to 6) that agree with it
/// within `tolerance` (relative): 1999 periods written as 0.001 s give
/// 1000 Hz, not 999.9999999999998, whose period (the spacing) would be
/// 0.001000000000000001. A rate the samples pin down more finely than 6
/// digits allow stays as measured.
pub fn tidy_rate(rate: f64, tolerance: f64) -> f64 {
    (1..=6)
        .map(|d| crate::profile::fitted::significant(rate, d))
        .find(|r| ((r - rate) / rate).abs() <= tolerance)
        .unwrap_or(rate)
}

/// Keys every hapticlab recording carries that say nothing about grouping
/// (an imported file's size and hash: `source` and `source_path` name it,
/// and files of one size are not alike for that).
const PLAIN_META: [&str; 16] = [
    "label",
    "profile",
    "profile_sha256",
    "device",
    "rate_hz",
    "software",
    "started_at",
    "seed",
    "texture",
    "clock",
    "stiffness_n_per_m",
    "damping_n_s_per_m",
    "scan_from_m",
    "scan_to_m",
    "source_bytes",
    "source_sha256",
];

/// The first two recordings of one label, adjacent in file-name order,
/// whose names that order puts against their numbers (see
/// [`Survey::out_of_number_order`]).
fn out_of_number_order(seen: &[Seen]) -> Option<(String, String)> {
    let name = |r: &Seen| {
        Path::new(&r.file)
            .file_name()
            .map_or(r.file.clone(), |n| n.to_string_lossy().into_owned())
    };
    let mut last: BTreeMap<&str, String> = BTreeMap::new();
    for r in seen {
        let this = name(r);
        if let Some(before) = last.get(r.label.as_str())
            && by_number(before, &this) == std::cmp::Ordering::Greater
        {
            return Some((before.clone(), this));
        }
        last.insert(&r.label, this);
    }
    None
}

/// Names compared as a person numbers them: runs of digits by their
/// value (`trial2` before `trial10`), the rest as text.
fn by_number(a: &str, b: &str) -> std::cmp::Ordering {
    fn runs(s: &str) -> Vec<(bool, &str)> {
        let mut out = Vec::new();
        let mut start = 0;
        let digit = |c: char| c.is_ascii_digit();
        for (i, c) in s.char_indices() {
            if i > start && digit(c) != s[start..].starts_with(digit) {
                out.push((s[start..].starts_with(digit), &s[start..i]));
                start = i;
            }
        }
        if start < s.len() {
            out.push((s[start..].starts_with(digit), &s[start..]));
        }
        out
    }
    let (ra, rb) = (runs(a), runs(b));
    for ((da, x), (db, y)) in ra.iter().zip(&rb) {
        let o = if *da && *db {
            let (x, y) = (x.trim_start_matches('0'), y.trim_start_matches('0'));
            x.len().cmp(&y.len()).then_with(|| x.cmp(y))
        } else {
            x.cmp(y)
        };
        if o != std::cmp::Ordering::Equal {
            return o;
        }
    }
    ra.len().cmp(&rb.len())
}

fn sum_up(seen: &[Seen], incomplete: Vec<String>) -> Survey {
    // Each recording's column positions, looked up once: linear in the
    // columns (a WAV of 65,535 channels took seconds when searched).
    let index: Vec<HashMap<&str, usize>> = seen
        .iter()
        .map(|r| {
            r.columns
                .iter()
                .enumerate()
                .map(|(i, c)| (c.as_str(), i))
                .collect()
        })
        .collect();
    let columns: Vec<String> = seen[0]
        .columns
        .iter()
        .filter(|c| index.iter().all(|ix| ix.contains_key(c.as_str())))
        .cloned()
        .collect();
    let mut s = Survey {
        complete: seen.len(),
        incomplete,
        columns: columns.clone(),
        differing: seen.iter().find(|r| r.columns != seen[0].columns).map(|r| {
            [
                (seen[0].file.clone(), seen[0].columns.clone()),
                (r.file.clone(), r.columns.clone()),
            ]
        }),
        ..Survey::default()
    };
    for r in seen {
        *s.labels.entry(r.label.clone()).or_default() += 1;
    }
    s.out_of_number_order = out_of_number_order(seen);
    let segments: Vec<Option<Segment>> = seen
        .iter()
        .map(|r| {
            Segment::of(|key| {
                r.meta
                    .iter()
                    .find(|(k, _)| k == key)
                    .map(|(_, v)| v.clone())
            })
        })
        .collect();
    if segments.iter().any(Option::is_some) {
        for (r, segment) in seen.iter().zip(segments) {
            s.segments.entry(r.label.clone()).or_default().push(segment);
        }
    }
    let mut rates: Vec<f64> = seen.iter().filter_map(|r| r.rate_hz).collect();
    rates.sort_by(f64::total_cmp);
    s.rate_hz = rates.get(rates.len() / 2).copied().unwrap_or(1000.0);
    for c in &columns {
        // Every recording has `c` (the columns are those all share).
        let at: Vec<usize> = index.iter().map(|ix| ix[c.as_str()]).collect();
        let shortest = seen
            .iter()
            .zip(&at)
            .map(|(r, &i)| (r.travel[i], r))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or((0.0, String::new()), |(t, r)| (t, r.file.clone()));
        s.shortest.insert(c.clone(), shortest);
        if c == "t_s" || POSITIONS.contains(&c.as_str()) {
            let travels = seen.iter().zip(&at).map(|(r, &i)| (r.travel[i], &r.file));
            s.reach.insert(c.clone(), reach(travels));
        }
        let mut steps: Vec<f64> = seen.iter().zip(&at).map(|(r, &i)| r.step[i]).collect();
        steps.sort_by(f64::total_cmp);
        s.step.insert(c.clone(), steps[steps.len() / 2]);
        let spread =
            seen.iter().zip(&at).map(|(r, &i)| r.spread[i]).sum::<f64>() / seen.len() as f64;
        s.spread.insert(c.clone(), spread);
    }
    s.rates = distinct_rates(seen);
    let mut keys: BTreeMap<&str, std::collections::BTreeSet<&str>> = BTreeMap::new();
    for r in seen {
        for (k, v) in &r.meta {
            keys.entry(k).or_default().insert(v);
        }
    }
    s.varying_meta = keys
        .iter()
        .filter(|(k, v)| v.len() > 1 && !PLAIN_META.contains(k))
        .map(|(k, _)| k.to_string())
        .collect();
    for key in &s.varying_meta {
        s.groups.insert(key.clone(), grouping(seen, key));
    }
    s
}

/// For metadata `key`: the fewest distinct values a label has, and whether
/// two recordings share a value (a recording without the key is its own).
fn grouping(seen: &[Seen], key: &str) -> (usize, bool) {
    fn value<'a>(r: &'a Seen, key: &str) -> Option<&'a str> {
        r.meta
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    let mut per_label: BTreeMap<&str, std::collections::BTreeSet<&str>> = BTreeMap::new();
    let mut all = std::collections::BTreeSet::new();
    let mut with = 0;
    for r in seen {
        if let Some(v) = value(r, key) {
            per_label.entry(&r.label).or_default().insert(v);
            all.insert(v);
            with += 1;
        }
    }
    let fewest = per_label.values().map(|v| v.len()).min().unwrap_or(0);
    (fewest, all.len() < with)
}

/// The recordings' rates, those within 1 % of each other counted as one.
fn distinct_rates(seen: &[Seen]) -> Vec<RateGroup> {
    let mut rated: Vec<(f64, &Seen)> = seen
        .iter()
        .filter_map(|r| r.rate_hz.map(|h| (h, r)))
        .collect();
    rated.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<RateGroup> = Vec::new();
    for (hz, r) in rated {
        match out.last_mut() {
            Some(last) if hz <= last.hz * 1.01 => last.count += 1,
            _ => out.push(RateGroup {
                hz,
                count: 1,
                file: r.file.clone(),
                labels: BTreeMap::new(),
            }),
        }
        if let Some(last) = out.last_mut() {
            *last.labels.entry(r.label.clone()).or_default() += 1;
        }
    }
    out
}

/// The axis and channels chosen, and why.
#[derive(Debug, Clone)]
pub struct Choice {
    pub axis: String,
    pub signals: Vec<String>,
    pub why: String,
}

const POSITIONS: [&str; 3] = ["x_m", "y_m", "z_m"];
/// At most this many signal columns analysed together by default.
const MAX_CHANNELS: usize = 4;

impl Survey {
    /// A position axis when the probe travels (a stroke of 1 mm or more in
    /// every recording but a few much shorter ones, [`Reach`]): the one it
    /// travels most along, the thesis's way; otherwise time.
    pub fn choice(&self) -> Choice {
        // An aborted stroke or two do not make the probe stationary.
        let travel = |c: &str| self.window_reach(c).0.0;
        let stroke = POSITIONS
            .iter()
            .filter(|c| self.columns.iter().any(|x| x == *c))
            .max_by(|a, b| travel(a).total_cmp(&travel(b)))
            .filter(|c| travel(c) >= 0.001);
        let varies = |c: &String| self.spread.get(c).is_some_and(|s| *s > 0.0);
        match stroke {
            Some(axis) => {
                // The probe's height across the stroke when there is one (the
                // thesis's y_m), else the position that moves most.
                let height = ["y_m", "z_m", "x_m"]
                    .into_iter()
                    .map(str::to_string)
                    .find(|c| c != axis && self.columns.contains(c) && varies(c));
                let signal = height.or_else(|| {
                    self.columns
                        .iter()
                        .filter(|c| c.as_str() != *axis && *c != "t_s" && varies(c))
                        .max_by(|a, b| self.spread[*a].total_cmp(&self.spread[*b]))
                        .cloned()
                });
                Choice {
                    axis: axis.to_string(),
                    signals: signal.into_iter().collect(),
                    why: format!(
                        "the probe strokes along {axis} (at least {:.1} mm in every recording{}): resampled by position, as the thesis",
                        travel(axis) * 1000.0,
                        if self.window_reach(axis).1.is_empty() {
                            ""
                        } else {
                            " but the few much shorter ones"
                        }
                    ),
                }
            }
            None => Choice {
                axis: "t_s".into(),
                signals: self
                    .columns
                    .iter()
                    .filter(|c| *c != "t_s" && !POSITIONS.contains(&c.as_str()) && varies(c))
                    .take(MAX_CHANNELS)
                    .cloned()
                    .collect(),
                why: "no probe stroke in the recordings: resampled by time".into(),
            },
        }
    }

    /// The signal columns analysed along `axis`.
    pub fn channels(&self, axis: &str) -> Vec<String> {
        let c = self.choice();
        if c.axis == axis {
            c.signals
        } else {
            Vec::new()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_compared_by_their_numbers() {
        use std::cmp::Ordering::*;
        assert_eq!(by_number("trial2.csv", "trial10.csv"), Less);
        assert_eq!(by_number("trial10.csv", "trial2.csv"), Greater);
        assert_eq!(by_number("trial02.csv", "trial10.csv"), Less);
        assert_eq!(by_number("a-seg001.csv", "a-seg002.csv"), Less);
        assert_eq!(by_number("b1.csv", "a2.csv"), Greater);
        assert_eq!(by_number("x.csv", "x.csv"), Equal);
        let seen = |label: &str, file: &str| Seen {
            file: format!("rec/{label}/{file}"),
            label: label.into(),
            columns: Vec::new(),
            rate_hz: None,
            travel: Vec::new(),
            step: Vec::new(),
            spread: Vec::new(),
            meta: Vec::new(),
        };
        // File-name order, as the dataset reads them.
        let padded = [
            seen("a", "t01.csv"),
            seen("a", "t02.csv"),
            seen("a", "t10.csv"),
        ];
        assert_eq!(out_of_number_order(&padded), None);
        let bare = [
            seen("a", "t1.csv"),
            seen("a", "t10.csv"),
            seen("a", "t11.csv"),
            seen("a", "t2.csv"),
            seen("b", "t1.csv"),
        ];
        assert_eq!(
            out_of_number_order(&bare),
            Some(("t11.csv".into(), "t2.csv".into()))
        );
    }

    #[test]
    fn a_rate_is_rounded_only_as_far_as_the_sample_times_allow() {
        // Float noise rounds away; a rate written to 3 digits stays.
        assert_eq!(tidy_rate(999.999_999_999_999_8, FLOAT_NOISE), 1000.0);
        assert_eq!(tidy_rate(44_100.000_000_01, FLOAT_NOISE), 44_100.0);
        // A clock 0.04 % slow, timed exactly, is not 1 kHz.
        let slow: Vec<f64> = (0..2000).map(|i| i as f64 / 999.6).collect();
        assert_eq!(tidy_rate(999.6, timing(&slow)), 999.6);
        // 1 kHz with 50 µs of jitter on each sample: 1000 Hz is within it.
        let jittered: Vec<f64> = (0..2000)
            .map(|i| i as f64 * 0.001 + 5e-5 * ((i * 7919 % 13) as f64 / 6.0 - 1.0))
            .collect();
        let measured = 1999.0 / (jittered[1999] - jittered[0]);
        assert_ne!(measured, 1000.0);
        assert_eq!(tidy_rate(measured, timing(&jittered)), 1000.0);
    }
}
