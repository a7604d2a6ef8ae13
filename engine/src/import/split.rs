//! `import --split SECONDS [--split-hop SECONDS]`: one long recording cut
//! into consecutive trials, for rigs that record one long trace per
//! material. Each trial keeps the input's own times and says where it came
//! from (`segment`, `segment_start_s`, `segment_length_s`; the input is the
//! recording's `source`).

use super::{ImportError, Imported, bad, plain};

/// At most this many trials from one input: a hop far below the length
/// would otherwise write a file per sample.
const MOST_SEGMENTS: usize = 100_000;

/// The fewest samples a trial may hold: fewer give a spectrum of at most
/// eight bins, and `--split 0.001` at 1 kHz wrote 60,000 one-sample files.
pub const MIN_TRIAL_SAMPLES: usize = 16;

/// The shortest hop, as a part of the trial's length: trials overlapping
/// by more than 90 % copy every sample into more than ten files
/// (`--split 2 --split-hop 0.001` wrote 58,001 files, 1.9 GB).
const MIN_HOP_PART: f64 = 0.1;

/// What stands between an input's stem and its trial's number in the
/// trial's file name (`long-seg001.csv`).
pub const MARK: &str = "-seg";

/// The metadata keys each trial gets: its number, start and length.
pub use crate::folds::SEGMENT_KEYS as KEYS;
pub use crate::folds::Segment;

/// `--split` and `--split-hop`, checked: how to cut each input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cut {
    /// Each trial's length, in seconds.
    pub length: f64,
    /// From one trial's start to the next, in seconds.
    pub hop: f64,
}

/// Checks `--split` and `--split-hop` before any file is read; with
/// `--rate` also that a trial holds enough samples.
pub fn check(length: f64, hop: Option<f64>, rate: Option<f64>) -> Result<Cut, ImportError> {
    if !(length.is_finite() && length > 0.0) {
        return Err(bad(format!(
            "--split must be a positive number of seconds, got {}",
            plain(length)
        )));
    }
    if let Some(rate) = rate {
        check_samples(length, 1.0 / rate, "")?;
    }
    let Some(hop) = hop else {
        return Ok(Cut {
            length,
            hop: length,
        });
    };
    if !(hop.is_finite() && hop > 0.0) {
        return Err(bad(format!(
            "--split-hop must be a positive number of seconds, got {}",
            plain(hop)
        )));
    }
    if hop < length * MIN_HOP_PART {
        return Err(bad(format!(
            "--split-hop {} s is below a tenth of --split {} s (trials overlapping by more than \
             90 %, each sample written into about {} files): give --split-hop {} or more",
            plain(hop),
            plain(length),
            (length / hop).round(),
            about(length * MIN_HOP_PART)
        )));
    }
    Ok(Cut { length, hop })
}

/// `x` to six significant digits, plainly: a rate or a period worked out
/// from sample times (999.9999999 Hz reads 1000).
fn about(x: f64) -> String {
    plain(format!("{x:.5e}").parse().unwrap_or(x))
}

/// Refuses trials of `length` s that would hold fewer than
/// [`MIN_TRIAL_SAMPLES`] samples `dt` s apart; `origin` (with its `: `)
/// names the input when the rate is its own.
fn check_samples(length: f64, dt: f64, origin: &str) -> Result<(), ImportError> {
    // The samples at k·dt before the trial's end less a thousandth of a
    // period (as `split` takes them); 16 periods hold 16 samples.
    // Never below none (`--split 1e-300` holds no sample, not "-0").
    let held = (length / dt - 1e-3).ceil().max(0.0);
    if held >= MIN_TRIAL_SAMPLES as f64 {
        return Ok(());
    }
    Err(bad(format!(
        "{origin}--split {} s holds {held} sample(s) at {} Hz, and a trial needs at least \
         {MIN_TRIAL_SAMPLES} for a spectrum: give --split {} or more",
        plain(length),
        about(1.0 / dt),
        about(MIN_TRIAL_SAMPLES as f64 * dt)
    )))
}

/// `imp` cut into the whole trials `cut.length` s long that start every
/// `cut.hop` s from its first sample, in time order; `origin` names it.
pub fn split(imp: &Imported, origin: &str, cut: Cut) -> Result<Vec<Imported>, ImportError> {
    let Cut { length, hop } = cut;
    let t0 = imp.time[0];
    let (dt, span, whole) = layout(imp, cut);
    if dt > 0.0 {
        check_samples(length, dt, &format!("{origin}: "))?;
    }
    if whole < 0.0 {
        return Err(bad(format!(
            "{origin}: it lasts {} s, shorter than one --split {} s trial: give a shorter --split",
            about(span),
            plain(length)
        )));
    }
    let count = whole as usize + 1;
    if count > MOST_SEGMENTS || whole > MOST_SEGMENTS as f64 {
        return Err(bad(format!(
            "{origin}: --split {} s every {} s makes {whole:.0} trials, more than {MOST_SEGMENTS}: give a longer --split-hop",
            plain(length),
            plain(hop)
        )));
    }
    let eps = dt * 1e-3;
    let mut out = Vec::with_capacity(count);
    for j in 0..count {
        let start = j as f64 * hop;
        let a = imp.time.partition_point(|t| t - t0 < start - eps);
        let b = imp.time.partition_point(|t| t - t0 < start + length - eps);
        if b <= a {
            return Err(bad(format!(
                "{origin}: trial {} ({} s to {} s) holds no sample: the time column has a gap; give a longer --split",
                j + 1,
                plain(start),
                plain(start + length)
            )));
        }
        let mut meta = imp.meta.clone();
        let [number, start_s, length_s] = KEYS.map(String::from);
        meta.extend([
            (number, toml::Value::Integer(j as i64 + 1)),
            (start_s, toml::Value::Float(start)),
            (length_s, toml::Value::Float(length)),
        ]);
        out.push(Imported {
            label: imp.label.clone(),
            time: imp.time[a..b].to_vec(),
            names: imp.names.clone(),
            channels: imp.channels.iter().map(|c| c[a..b].to_vec()).collect(),
            meta,
            time_digits: imp.time_digits,
            channel_digits: imp.channel_digits.clone(),
        });
    }
    Ok(out)
}

/// The seconds at `imp`'s end that no whole trial covers (a last partial
/// trial, left out), when they are at least one sample period.
pub fn left_over(imp: &Imported, cut: Cut) -> f64 {
    let (dt, span, whole) = layout(imp, cut);
    if whole < 0.0 || dt == 0.0 {
        return 0.0;
    }
    let rest = span - (whole * cut.hop + cut.length);
    if rest >= dt * (1.0 - 1e-3) { rest } else { 0.0 }
}

/// How `cut` lays over `imp`'s samples: one sample period (the mean; 0
/// for a single sample), the seconds the samples span, and the hops
/// after the first whole trial (negative when not even one fits). A
/// trial is whole when its samples reach its end within a thousandth of
/// a period.
fn layout(imp: &Imported, cut: Cut) -> (f64, f64, f64) {
    let n = imp.time.len();
    let (t0, last) = (imp.time[0], imp.time[n - 1]);
    let dt = if n > 1 {
        (last - t0) / (n - 1) as f64
    } else {
        0.0
    };
    let span = last - t0 + dt;
    let whole = ((span + dt * 1e-3 - cut.length) / cut.hop).floor();
    (dt, span, whole)
}

/// The file stem of trial `j` (from 0) of `count`: numbered from 1 with
/// leading zeros, so file-name order is time order.
pub fn stem(stem: &str, j: usize, count: usize) -> String {
    let width = count.to_string().len().max(3);
    format!("{stem}{MARK}{:0width$}", j + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Digits;

    fn message(e: ImportError) -> String {
        match e {
            ImportError::BadInput(m) | ImportError::Runtime(m) => m,
        }
    }

    fn signal(n: usize, rate: f64) -> Imported {
        Imported {
            label: None,
            time: (0..n).map(|i| i as f64 / rate).collect(),
            names: vec!["acc".into()],
            channels: vec![(0..n).map(|i| i as f64).collect()],
            meta: vec![("source".into(), toml::Value::String("long.csv".into()))],
            time_digits: Digits::Decimals(2),
            channel_digits: vec![Digits::Shortest],
        }
    }

    /// `--split length [--split-hop hop]` at `rate`, checked as the import does.
    fn cut(length: f64, hop: Option<f64>) -> Cut {
        check(length, hop, None).unwrap()
    }

    #[test]
    fn a_minute_at_100_hz_cut_every_2_s_gives_30_whole_trials_in_order() {
        let parts = split(&signal(6000, 100.0), "long.csv", cut(2.0, None)).unwrap();
        assert_eq!(parts.len(), 30);
        for (j, p) in parts.iter().enumerate() {
            assert_eq!(p.time.len(), 200, "trial {j}");
            assert_eq!(p.channels[0][0], (j * 200) as f64);
            assert!(
                p.meta
                    .contains(&("segment".into(), toml::Value::Integer(j as i64 + 1)))
            );
            assert!(p.meta.iter().any(|(k, _)| k == "source"));
        }
        assert_eq!(stem("L1", 0, 30), "L1-seg001");
        assert_eq!(stem("L1", 1233, 2000), "L1-seg1234");
    }

    #[test]
    fn overlapping_trials_and_a_partial_last_one_left_out() {
        // 10.5 s: 2 s trials every 1 s start at 0..=8 s (9 whole ones).
        let parts = split(&signal(1050, 100.0), "x", cut(2.0, Some(1.0))).unwrap();
        assert_eq!(parts.len(), 9);
        assert_eq!(parts[8].channels[0][0], 800.0);
        assert_eq!(parts[8].time.len(), 200);
        // A hop of a tenth of the trial is the most overlap taken.
        assert_eq!(
            split(&signal(1050, 100.0), "x", cut(2.0, Some(0.2)))
                .unwrap()
                .len(),
            43
        );
    }

    #[test]
    fn bad_lengths_hops_and_short_inputs_are_refused_naming_them() {
        assert!(check(0.0, None, None).is_err());
        assert!(check(f64::NAN, None, None).is_err());
        assert!(check(1.0, Some(-1.0), None).is_err());
        let e = message(split(&signal(150, 100.0), "short.csv", cut(2.0, None)).unwrap_err());
        assert!(e.contains("short.csv") && e.contains("shorter"), "{e}");
        let e =
            message(split(&signal(300_000, 10_000.0), "x", cut(0.0016, Some(0.0002))).unwrap_err());
        assert!(e.contains("more than 100000"), "{e}");
    }

    #[test]
    fn trials_too_short_for_a_spectrum_and_hops_past_90_percent_overlap_are_refused() {
        // Fewer than 16 samples, whether the rate is given or the input's own.
        let e = message(check(0.001, None, Some(1000.0)).unwrap_err());
        assert_eq!(
            e,
            "--split 0.001 s holds 1 sample(s) at 1000 Hz, and a trial needs at least 16 for \
             a spectrum: give --split 0.016 or more"
        );
        let e = message(split(&signal(6000, 1000.0), "x.wav", cut(0.0001, None)).unwrap_err());
        assert!(
            e.starts_with("x.wav: --split 0.0001 s holds 1 sample(s) at 1000 Hz")
                && e.contains("--split 0.016 or more")
                && !e.contains("--split-hop"),
            "{e}"
        );
        assert_eq!(
            split(&signal(6000, 1000.0), "x", cut(0.016, None))
                .unwrap()
                .len(),
            375
        );
        assert_eq!(
            split(&signal(6000, 1000.0), "x", cut(0.016, None)).unwrap()[0]
                .time
                .len(),
            16
        );
        let e = message(check(2.0, Some(0.001), None).unwrap_err());
        assert_eq!(
            e,
            "--split-hop 0.001 s is below a tenth of --split 2 s (trials overlapping by more \
             than 90 %, each sample written into about 2000 files): give --split-hop 0.2 or more"
        );
        assert!(check(2.0, Some(0.2), None).is_ok());
    }
}
