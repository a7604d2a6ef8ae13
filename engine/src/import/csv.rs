//! CSV files with a column mapping: a time column (seconds) or a fixed
//! rate; the channel columns; `--burst N` for sensors that pack N
//! consecutive samples of each channel into one row (the columns of one
//! channel consecutive, flattened in order); the label from a
//! `--label-column` (constant within a file).

use super::{ImportError, Imported, Request, bad, plain};
use crate::recording::{Digits, time_decimals};

/// Column names that say a column holds the sample times (compared
/// without case): under `--rate` such a column would be kept as a
/// channel, analysed as a signal, and chosen by `profile new`.
const TIME_NAMES: [&str; 18] = [
    "t",
    "t_s",
    "ts",
    "time",
    "time_s",
    "time_sec",
    "times",
    "time (s)",
    "time(s)",
    "time [s]",
    "time[s]",
    "timestamp",
    "timestamps",
    "seconds",
    "secs",
    "sec",
    "elapsed",
    "elapsed_s",
];

/// Whether a column's (or an array's) name says it holds the sample times.
pub(super) fn is_time_name(name: &str) -> bool {
    TIME_NAMES.iter().any(|t| name.eq_ignore_ascii_case(t))
}

/// The first column whose name says it is the time, if any.
fn time_like(cols: &[String]) -> Option<&str> {
    cols.iter().map(|c| c.as_str()).find(|c| is_time_name(c))
}

/// The header line: where it is, the field separator, the column names.
struct Header {
    /// Its line number, from 1.
    line: usize,
    delim: char,
    cols: Vec<String>,
}

impl Header {
    fn find(&self, name: &str, what: &str, origin: &str) -> Result<usize, ImportError> {
        self.cols.iter().position(|c| c == name).ok_or_else(|| {
            bad(format!(
                "{origin}:{}: no {what} column `{name}` (the header has {})",
                self.line,
                self.cols.join(", ")
            ))
        })
    }
}

/// Which columns hold what: the mapping of `args` applied to a header.
struct Mapping {
    time: Option<usize>,
    label: Option<usize>,
    /// The channel columns, each channel's `burst` columns consecutive.
    channels: Vec<usize>,
    burst: usize,
    names: Vec<String>,
}

/// What the data rows hold.
struct Rows {
    /// The time column's value of each row (empty without one).
    times: Vec<f64>,
    /// `channels[c][sample]`.
    channels: Vec<Vec<f64>>,
    label: Option<String>,
}

/// Parse a CSV file's text with the mapping in `args`.
pub fn parse_csv(text: &str, origin: &str, args: &Request) -> Result<Imported, ImportError> {
    // Excel's "CSV UTF-8" starts with a byte-order mark, invisible in any
    // message: read past it, as the recording reader does.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let (hline, header) = lines.next().ok_or_else(|| {
        bad(format!(
            "{origin}: holds no header and no samples, only blank or comment lines"
        ))
    })?;
    let header = header_of(hline + 1, header, args);
    let map = mapping(&header, origin, args)?;
    let rows = rows(lines, &header, &map, origin)?;
    let n_rows = rows.channels[0].len() / map.burst;
    if n_rows == 0 {
        return Err(bad(format!("{origin}: no data rows")));
    }
    let (time, time_digits) = sample_times(&rows.times, n_rows, &map, args, origin)?;
    let mut meta = Vec::new();
    if let Some(r) = args.rate {
        meta.push(("rate_hz".to_string(), toml::Value::Float(r)));
    }
    Ok(Imported {
        label: rows.label,
        time,
        names: map.names,
        channel_digits: vec![Digits::Shortest; rows.channels.len()],
        channels: rows.channels,
        meta,
        time_digits,
    })
}

/// The header's columns, split at `--delimiter` or else the first of `,`,
/// `;` and tab that it holds.
fn header_of(line: usize, header: &str, args: &Request) -> Header {
    let delim = args.delimiter.unwrap_or_else(|| {
        [',', ';', '\t']
            .into_iter()
            .find(|d| header.contains(*d))
            .unwrap_or(',')
    });
    let cols = header
        .split(delim)
        .map(|c| c.trim().trim_matches('"').to_string())
        .collect();
    Header { line, delim, cols }
}

/// The flags' columns found in the header, and the channels' names.
fn mapping(header: &Header, origin: &str, args: &Request) -> Result<Mapping, ImportError> {
    let find = |name: &str, what: &str| header.find(name, what, origin);
    let time = args
        .time_column
        .as_deref()
        .map(|t| find(t, "time"))
        .transpose()?;
    let label = args
        .label_column
        .as_deref()
        .map(|l| find(l, "label"))
        .transpose()?;
    if time.is_none() {
        check_no_time_kept(header, label, origin, args)?;
    }
    let channels = channel_columns(&header.cols, time, label, args, &find)?;
    // `--burst 0` is refused by `check_options`, before any file.
    let burst = args.burst.max(1);
    if channels.is_empty() || !channels.len().is_multiple_of(burst) {
        return Err(bad(format!(
            "{origin}: {} channel column(s) cannot be split into bursts of {burst}",
            channels.len()
        )));
    }
    let n_channels = channels.len() / burst;
    let names: Vec<String> = if !args.names.is_empty() {
        if args.names.len() != n_channels {
            let columns: Vec<&str> = channels.iter().map(|&i| header.cols[i].as_str()).collect();
            return Err(bad(format!(
                "--names gives {} name(s) but {origin} has {n_channels} channel(s) ({})",
                args.names.len(),
                columns.join(", ")
            )));
        }
        args.names.clone()
    } else if burst == 1 {
        channels.iter().map(|&i| header.cols[i].clone()).collect()
    } else {
        (1..=n_channels).map(|c| format!("ch{c}")).collect()
    };
    Ok(Mapping {
        time,
        label,
        channels,
        burst,
        names,
    })
}

/// Without a time column: a rate is needed, and a column named like the
/// time must not become a channel unnoticed (with `--channels` the user
/// has chosen the columns).
fn check_no_time_kept(
    header: &Header,
    label: Option<usize>,
    origin: &str,
    args: &Request,
) -> Result<(), ImportError> {
    let label = label.map(|i| header.cols[i].as_str());
    let time = time_like(&header.cols).filter(|&t| Some(t) != label);
    match (args.rate, time) {
        (None, None) => Err(bad(format!("{origin}: give --time-column or --rate"))),
        (None, Some(t)) => Err(bad(format!(
            "{origin}: give --time-column or --rate (column `{t}` looks like the time: \
             --time-column {t}, if it holds seconds)"
        ))),
        (Some(_), Some(t)) if args.channels.is_empty() => {
            let others: Vec<&str> = header
                .cols
                .iter()
                .map(String::as_str)
                .filter(|&c| c != t && Some(c) != label)
                .collect();
            let or = if others.is_empty() {
                format!("or keep it as a signal with --channels {t}")
            } else {
                format!("or leave it out with --channels {}", others.join(","))
            };
            Err(bad(format!(
                "{origin}: column `{t}` looks like the time, and with --rate it would be kept \
                 as a channel: take the times from it with --time-column {t} instead of \
                 --rate (if it holds seconds), {or}"
            )))
        }
        (Some(_), _) => Ok(()),
    }
}

/// The channel columns' indices: `--channels` in order (each named once),
/// else every column but the time and label columns.
fn channel_columns(
    cols: &[String],
    time: Option<usize>,
    label_col: Option<usize>,
    args: &Request,
    find: &dyn Fn(&str, &str) -> Result<usize, ImportError>,
) -> Result<Vec<usize>, ImportError> {
    if args.channels.is_empty() {
        return Ok((0..cols.len())
            .filter(|i| Some(*i) != time && Some(*i) != label_col)
            .collect());
    }
    if let Some((i, c)) = args
        .channels
        .iter()
        .enumerate()
        .find(|(i, c)| args.channels[..*i].contains(c))
    {
        return Err(bad(format!(
            "--channels names `{c}` twice (entries {} and {}): name each column once",
            args.channels.iter().position(|x| x == c).unwrap_or(0) + 1,
            i + 1
        )));
    }
    args.channels.iter().map(|c| find(c, "channel")).collect()
}

/// Reads the data rows (numbered lines after the header): every field
/// present, every mapped value a finite number, the label constant.
fn rows<'a>(
    lines: impl Iterator<Item = (usize, &'a str)>,
    header: &Header,
    map: &Mapping,
    origin: &str,
) -> Result<Rows, ImportError> {
    let cols = &header.cols;
    let mut out = Rows {
        times: Vec::new(),
        channels: vec![Vec::new(); map.channels.len() / map.burst],
        label: None,
    };
    for (ln, line) in lines {
        let fields: Vec<&str> = line
            .split(header.delim)
            .map(|f| f.trim().trim_matches('"'))
            .collect();
        if fields.len() != cols.len() {
            return Err(bad(format!(
                "{origin}:{}: {} fields but the header has {}",
                ln + 1,
                fields.len(),
                cols.len()
            )));
        }
        let num = |i: usize| {
            fields[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "{origin}:{}: column `{}`: {:?} is not a finite number",
                        ln + 1,
                        cols[i],
                        fields[i]
                    ))
                })
        };
        if let Some(t) = map.time {
            let time = num(t)?;
            if let Some(&before) = out.times.last()
                && time <= before
            {
                return Err(bad(format!(
                    "{origin}:{}: the time column `{}` goes from {} to {}: it must increase \
                     row by row",
                    ln + 1,
                    cols[t],
                    plain(before),
                    plain(time)
                )));
            }
            out.times.push(time);
        }
        if let Some(l) = map.label {
            match &out.label {
                None => out.label = Some(fields[l].to_string()),
                Some(prev) if prev != fields[l] => {
                    return Err(bad(format!(
                        "{origin}:{}: the label changes from {prev:?} to {:?}; one file is one scan of one texture",
                        ln + 1,
                        fields[l]
                    )));
                }
                _ => {}
            }
        }
        for (c, ch) in out.channels.iter_mut().enumerate() {
            for b in 0..map.burst {
                ch.push(num(map.channels[c * map.burst + b])?);
            }
        }
    }
    Ok(out)
}

/// Each sample's time and how it is written: the time column's own values
/// exactly (spread over a burst), or times computed from `--rate` with
/// decimals enough for it.
fn sample_times(
    row_times: &[f64],
    n_rows: usize,
    map: &Mapping,
    args: &Request,
    origin: &str,
) -> Result<(Vec<f64>, Digits), ImportError> {
    let burst = map.burst;
    let mut time_digits = Digits::Shortest;
    let time: Vec<f64> = match (map.time, args.rate) {
        (None, Some(rate)) => {
            time_digits = Digits::Decimals(time_decimals(rate));
            (0..n_rows * burst).map(|i| i as f64 / rate).collect()
        }
        (Some(_), rate) => {
            // `rows` has checked that the times increase.
            // Within a burst, samples are 1/rate apart; without a rate, the
            // median row interval shared evenly.
            let dt = match rate {
                Some(r) => 1.0 / r,
                None if burst == 1 => 0.0,
                None if n_rows < 2 => {
                    return Err(bad(format!(
                        "{origin}: one row of a burst needs --rate to time its samples"
                    )));
                }
                None => {
                    let mut d: Vec<f64> = row_times.windows(2).map(|w| w[1] - w[0]).collect();
                    d.sort_by(f64::total_cmp);
                    d[d.len() / 2] / burst as f64
                }
            };
            if burst > 1 {
                time_digits = Digits::Decimals(time_decimals(1.0 / dt));
            }
            row_times
                .iter()
                .flat_map(|&t| (0..burst).map(move |b| t + b as f64 * dt))
                .collect()
        }
        (None, None) => unreachable!("mapping() refuses a file with neither"),
    };
    // Times too far apart overflow to inf (or NaN) when shared within a
    // burst; a rate too small for its times is refused before any file.
    if let Some(i) = time.iter().position(|t| !t.is_finite()) {
        return Err(bad(format!(
            "{origin}: the time of sample {} overflows (it is {}, from the time column's intervals)",
            i + 1,
            time[i]
        )));
    }
    Ok((time, time_digits))
}
