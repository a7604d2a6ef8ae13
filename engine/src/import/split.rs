//! `import --split SECONDS [--split-hop SECONDS]`: one long recording cut
//! into consecutive trials, for rigs that record one long trace per
//! material. Each trial keeps the input's own times and says where it came
//! from (`segment`, `segment_start_s`, `segment_length_s`; the input is the
//! recording's `source`).

use super::{ImportError, Imported, bad};

/// At most this many trials from one input: a hop far below the length
/// would otherwise write a file per sample.
const MOST_SEGMENTS: usize = 100_000;

/// Checks `--split` and `--split-hop`: (length, hop) in seconds.
pub fn check(length: f64, hop: Option<f64>) -> Result<(f64, f64), ImportError> {
    if !(length.is_finite() && length > 0.0) {
        return Err(bad(format!(
            "--split must be a positive number of seconds, got {length}"
        )));
    }
    let hop = hop.unwrap_or(length);
    if !(hop.is_finite() && hop > 0.0) {
        return Err(bad(format!(
            "--split-hop must be a positive number of seconds, got {hop}"
        )));
    }
    Ok((length, hop))
}

/// `imp` cut into the whole segments `length` s long that start every
/// `hop` s from its first sample, in time order; `origin` names it.
pub fn split(
    imp: &Imported,
    origin: &str,
    length: f64,
    hop: f64,
) -> Result<Vec<Imported>, ImportError> {
    let n = imp.time.len();
    let (t0, last) = (imp.time[0], imp.time[n - 1]);
    // One sample period (the mean): a segment is whole when its samples
    // reach its end within a thousandth of one.
    let dt = if n > 1 {
        (last - t0) / (n - 1) as f64
    } else {
        0.0
    };
    if hop < dt {
        return Err(bad(format!(
            "{origin}: --split-hop {hop} s is below one sample period ({dt:e} s): give a hop of at least one sample"
        )));
    }
    let span = last - t0 + dt;
    let whole = ((span + dt * 1e-3 - length) / hop).floor();
    if whole < 0.0 {
        return Err(bad(format!(
            "{origin}: it lasts {span} s, shorter than one --split {length} s trial: give a shorter --split"
        )));
    }
    let count = whole as usize + 1;
    if count > MOST_SEGMENTS || whole > MOST_SEGMENTS as f64 {
        return Err(bad(format!(
            "{origin}: --split {length} s every {hop} s makes {whole:.0} trials, more than {MOST_SEGMENTS}: give a longer --split-hop"
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
                "{origin}: trial {} ({start} s to {} s) holds no sample: the time column has a gap; give a longer --split",
                j + 1,
                start + length
            )));
        }
        let mut meta = imp.meta.clone();
        meta.extend([
            ("segment".to_string(), toml::Value::Integer(j as i64 + 1)),
            ("segment_start_s".to_string(), toml::Value::Float(start)),
            ("segment_length_s".to_string(), toml::Value::Float(length)),
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

/// The file stem of trial `j` (from 0) of `count`: numbered from 1 with
/// leading zeros, so file-name order is time order.
pub fn stem(stem: &str, j: usize, count: usize) -> String {
    let width = count.to_string().len().max(3);
    format!("{stem}-seg{:0width$}", j + 1)
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

    #[test]
    fn a_minute_at_100_hz_cut_every_2_s_gives_30_whole_trials_in_order() {
        let parts = split(&signal(6000, 100.0), "long.csv", 2.0, 2.0).unwrap();
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
        let parts = split(&signal(1050, 100.0), "x", 2.0, 1.0).unwrap();
        assert_eq!(parts.len(), 9);
        assert_eq!(parts[8].channels[0][0], 800.0);
        assert_eq!(parts[8].time.len(), 200);
    }

    #[test]
    fn bad_lengths_hops_and_short_inputs_are_refused_naming_them() {
        assert!(check(0.0, None).is_err());
        assert!(check(f64::NAN, None).is_err());
        assert!(check(1.0, Some(-1.0)).is_err());
        let e = message(split(&signal(150, 100.0), "short.csv", 2.0, 2.0).unwrap_err());
        assert!(e.contains("short.csv") && e.contains("shorter"), "{e}");
        let e = message(split(&signal(6000, 100.0), "x", 2.0, 0.001).unwrap_err());
        assert!(e.contains("below one sample period"), "{e}");
        let e = message(split(&signal(300_000, 100.0), "x", 2.0, 0.01).unwrap_err());
        assert!(e.contains("more than 100000"), "{e}");
    }
}
