//! `hapticlab import`: recordings v1 from other rigs' files.
//!
//! - CSV with a column mapping: a time column (seconds) or a fixed rate; the
//!   channel columns; `--burst N` for sensors that pack N consecutive
//!   samples of each channel into one row (the columns of one channel
//!   consecutive, flattened in order); the label from `--label`, a
//!   `--label-column` (constant within a file) or the file's folder name;
//!   extra metadata `--meta key=value`.
//! - WAV (RIFF): PCM 8/16/24/32-bit integer or 32/64-bit float, any number of
//!   channels. Integer samples are kept as integer counts (exact), with
//!   `full_scale` in the metadata to normalise them; float samples as they are.
//!
//! Written exactly: integer samples as integers, float samples and a CSV's
//! values in the shortest text that reads back as the same number, `t_s`
//! with decimals enough for the rate (within 0.5 % of a sample period).
//!
//! Files are converted on every core into a hidden staging folder under
//! `--out` and moved in place only once all are complete, so a bad input
//! leaves nothing behind and an interrupted import no half recording.
//! This module reads only the files it is given and writes only under `--out`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use clap::Args;

use crate::recording::files::{
    check_output_kind, move_no_replace, not_regular, read_input, same_file_as,
};
use crate::recording::{Digits, MAX_RATE_HZ, RecordingError, RecordingWriter, time_decimals};
use crate::support::Failure;

mod checks;
mod mat;
mod npy;
mod split;
mod text;
use checks::{check_written_names, csv_only_flags_for_wav};

#[derive(Debug, Args, Clone, Default)]
pub struct ImportArgs {
    /// CSV or WAV files to import (the format is taken from the extension).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Output folder; recordings go to OUT/<label>/<file stem>.csv.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// CSV: the column holding each row's time in seconds.
    #[arg(long, value_name = "NAME", conflicts_with = "rate")]
    pub time_column: Option<String>,
    /// The sampling rate in Hz (CSV without a time column; WAV files carry their own).
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// CSV: the channel columns, comma-separated (default: every column but the time and label columns).
    #[arg(long, value_name = "A,B,…", value_delimiter = ',')]
    pub channels: Vec<String>,
    /// Names of the recorded channels (default: the CSV column names, or ch1, ch2, … for WAV and bursts).
    #[arg(long, value_name = "A,B,…", value_delimiter = ',')]
    pub names: Vec<String>,
    /// CSV: samples of each channel per row (the columns of a channel consecutive).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub burst: usize,
    /// The texture's label.
    #[arg(long, value_name = "LABEL", conflicts_with = "label_column")]
    pub label: Option<String>,
    /// CSV: the column holding the label (one value per file).
    #[arg(long, value_name = "NAME")]
    pub label_column: Option<String>,
    /// Extra metadata, e.g. --meta session=3 --meta rig=\"bench A\".
    #[arg(long, value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
    /// CSV field separator (default: `,`, or `;` or a tab when the header has one and no comma).
    #[arg(long, value_name = "CHAR")]
    pub delimiter: Option<char>,
    /// Replace existing recordings.
    #[arg(long)]
    pub force: bool,
    /// Compress each recording to OUT/<label>/<file stem>.csv.gz (Zopfli; gzip -9 past 4 MiB of text).
    #[arg(long)]
    pub gzip: bool,
    /// Cut each input into consecutive trials this many seconds long
    /// (<stem>-seg001.csv, …, in time order), for one long recording per material.
    #[arg(long, value_name = "SECONDS")]
    pub split: Option<f64>,
    /// With --split: seconds from one trial's start to the next (default: the
    /// trial's length, no overlap).
    #[arg(long, value_name = "SECONDS", requires = "split")]
    pub split_hop: Option<f64>,
    /// Files converted at once (default: the number of cores; 0 means the same).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// A signal read from a file, ready to be written as a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    pub label: Option<String>,
    pub time: Vec<f64>,
    pub names: Vec<String>,
    /// `channels[c][sample]`.
    pub channels: Vec<Vec<f64>>,
    pub meta: Vec<(String, toml::Value)>,
    /// How `t_s` is written: decimals enough for the rate, or the time
    /// column's own values exactly.
    pub time_digits: Digits,
    /// How each channel is written: integers as integers, others exactly.
    pub channel_digits: Vec<Digits>,
}

fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

/// `key=value` with the value in TOML (a bare word is taken as a string).
pub fn parse_meta(kv: &str) -> Result<(String, toml::Value), Failure> {
    let (k, v) = kv
        .split_once('=')
        .ok_or_else(|| bad(format!("--meta {kv:?}: expected key=value")))?;
    let k = k.trim();
    if k.is_empty()
        || !k
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return Err(bad(format!(
            "--meta {kv:?}: the key must be letters, digits, _ or -"
        )));
    }
    if ["label", "rate_hz", "end"].contains(&k) {
        return Err(bad(format!("--meta {k}: set by the import itself")));
    }
    let v = v.trim();
    let value = toml::from_str::<toml::Table>(&format!("v = {v}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(v.to_string()));
    Ok((k.to_string(), value))
}

/// The channel columns' indices: `--channels` in order (each named once),
/// else every column but the time and label columns.
fn channel_columns(
    cols: &[String],
    time: Option<usize>,
    label_col: Option<usize>,
    args: &ImportArgs,
    find: &dyn Fn(&str, &str) -> Result<usize, Failure>,
) -> Result<Vec<usize>, Failure> {
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

/// Parse a CSV file's text with the mapping in `args`.
pub fn parse_csv(text: &str, origin: &str, args: &ImportArgs) -> Result<Imported, Failure> {
    // Excel's "CSV UTF-8" starts with a byte-order mark, invisible in any
    // message: read past it, as the recording reader does.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let (hline, header) = lines
        .next()
        .ok_or_else(|| bad(format!("{origin}: no header line")))?;
    let delim = args.delimiter.unwrap_or_else(|| {
        if header.contains(',') {
            ','
        } else if header.contains(';') {
            ';'
        } else if header.contains('\t') {
            '\t'
        } else {
            ','
        }
    });
    let cols: Vec<String> = header
        .split(delim)
        .map(|c| c.trim().trim_matches('"').to_string())
        .collect();
    let find = |name: &str, what: &str| {
        cols.iter().position(|c| c == name).ok_or_else(|| {
            bad(format!(
                "{origin}:{}: no {what} column `{name}` (the header has {})",
                hline + 1,
                cols.join(", ")
            ))
        })
    };
    let time = args
        .time_column
        .as_deref()
        .map(|t| find(t, "time"))
        .transpose()?;
    let label_col = args
        .label_column
        .as_deref()
        .map(|l| find(l, "label"))
        .transpose()?;
    let channel_idx = channel_columns(&cols, time, label_col, args, &find)?;
    let burst = args.burst;
    if burst == 0 {
        return Err(bad(
            "--burst 0: a row holds at least one sample of each channel (--burst 1, the default)",
        ));
    }
    if channel_idx.is_empty() || !channel_idx.len().is_multiple_of(burst) {
        return Err(bad(format!(
            "{origin}: {} channel column(s) cannot be split into bursts of {burst}",
            channel_idx.len()
        )));
    }
    let n_channels = channel_idx.len() / burst;
    let names: Vec<String> = if !args.names.is_empty() {
        if args.names.len() != n_channels {
            return Err(bad(format!(
                "--names gives {} name(s) but there are {n_channels} channel(s)",
                args.names.len()
            )));
        }
        args.names.clone()
    } else if burst == 1 {
        channel_idx.iter().map(|&i| cols[i].clone()).collect()
    } else {
        (1..=n_channels).map(|c| format!("ch{c}")).collect()
    };
    if time.is_none() && args.rate.is_none() {
        return Err(bad(format!("{origin}: give --time-column or --rate")));
    }
    let mut row_times = Vec::new();
    let mut channels = vec![Vec::new(); n_channels];
    let mut label: Option<String> = None;
    for (ln, line) in lines {
        let fields: Vec<&str> = line
            .split(delim)
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
        if let Some(t) = time {
            row_times.push(num(t)?);
        }
        if let Some(l) = label_col {
            match &label {
                None => label = Some(fields[l].to_string()),
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
        for (c, ch) in channels.iter_mut().enumerate() {
            for b in 0..burst {
                ch.push(num(channel_idx[c * burst + b])?);
            }
        }
    }
    let rows = channels[0].len() / burst;
    if rows == 0 {
        return Err(bad(format!("{origin}: no data rows")));
    }
    let n = rows * burst;
    // The time column's own values are written as they are; times this
    // computes, with decimals enough for their rate.
    let mut time_digits = Digits::Shortest;
    let time: Vec<f64> = match (time, args.rate) {
        (None, Some(rate)) => {
            time_digits = Digits::Decimals(time_decimals(rate));
            (0..n).map(|i| i as f64 / rate).collect()
        }
        (Some(_), rate) => {
            if row_times.windows(2).any(|w| w[1] <= w[0]) {
                return Err(bad(format!(
                    "{origin}: the time column must increase row by row"
                )));
            }
            // Within a burst, samples are 1/rate apart; without a rate, the
            // median row interval shared evenly.
            let dt = match rate {
                Some(r) => 1.0 / r,
                None if burst == 1 => 0.0,
                None if rows < 2 => {
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
        (None, None) => unreachable!("checked above"),
    };
    // A rate too small, or times too far apart, overflow to inf (or NaN).
    if let Some(i) = time.iter().position(|t| !t.is_finite()) {
        let from = match args.rate {
            // Only a rate below about 1e-300 overflows: print it as such.
            Some(r) => format!("--rate {r:e}"),
            None => "the time column's intervals".to_string(),
        };
        return Err(bad(format!(
            "{origin}: the time of sample {} overflows (it is {}, from {from})",
            i + 1,
            time[i]
        )));
    }
    let mut meta = Vec::new();
    if let Some(r) = args.rate {
        meta.push(("rate_hz".to_string(), toml::Value::Float(r)));
    }
    Ok(Imported {
        label,
        time,
        names,
        channel_digits: vec![Digits::Shortest; channels.len()],
        channels,
        meta,
        time_digits,
    })
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}
fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Parse a WAV file's bytes.
pub fn parse_wav(bytes: &[u8], origin: &str) -> Result<Imported, Failure> {
    let err = |m: &str| bad(format!("{origin}: not a WAV file this reads: {m}"));
    if bytes.len() < 12 || &bytes[0..4] != b"RIFF" || &bytes[8..12] != b"WAVE" {
        return Err(err("no RIFF/WAVE header"));
    }
    let mut at = 12;
    let mut fmt: Option<(u16, u16, u32, u16)> = None;
    let mut data: Option<&[u8]> = None;
    while at + 8 <= bytes.len() {
        let id = &bytes[at..at + 4];
        let len = u32_at(bytes, at + 4) as usize;
        let body = &bytes[at + 8..(at + 8 + len).min(bytes.len())];
        if id == b"fmt " {
            if fmt.is_some() {
                // Which one a reader takes is a guess: the samples' meaning
                // would hang on it.
                return Err(err("two fmt chunks (a file has one)"));
            }
            if body.len() < 16 {
                return Err(err("the fmt chunk is too short"));
            }
            let mut format = u16_at(body, 0);
            if format == 0xFFFE && body.len() >= 26 {
                format = u16_at(body, 24); // WAVE_FORMAT_EXTENSIBLE: the sub-format's tag
            }
            fmt = Some((format, u16_at(body, 2), u32_at(body, 4), u16_at(body, 14)));
        } else if id == b"data" {
            if body.len() < len {
                return Err(err(&format!(
                    "the data chunk is cut short ({} of {len} bytes)",
                    body.len()
                )));
            }
            data = Some(body);
        }
        at += 8 + len + (len & 1);
    }
    let (format, channels, rate, bits) = fmt.ok_or_else(|| err("no fmt chunk"))?;
    let data = data.ok_or_else(|| err("no data chunk"))?;
    if channels == 0 || rate == 0 {
        return Err(err("zero channels or a zero sample rate"));
    }
    let width = usize::from(bits / 8);
    let (kind, full_scale) = match (format, bits) {
        (1, 8 | 16 | 24 | 32) => ("int", Some(2f64.powi(i32::from(bits) - 1))),
        (3, 32 | 64) => ("float", None),
        _ => {
            return Err(err(&format!(
                "format tag {format} with {bits} bits (PCM 8/16/24/32-bit or float 32/64-bit only)"
            )));
        }
    };
    let frame = width * usize::from(channels);
    let n = data.len() / frame;
    let mut out = vec![Vec::with_capacity(n); usize::from(channels)];
    for f in 0..n {
        for (c, ch) in out.iter_mut().enumerate() {
            let s = &data[f * frame + c * width..f * frame + (c + 1) * width];
            let v = match (kind, width) {
                ("int", 1) => f64::from(s[0]) - 128.0, // 8-bit WAV is unsigned
                ("int", 2) => f64::from(i16::from_le_bytes([s[0], s[1]])),
                ("int", 3) => f64::from(i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8),
                ("int", 4) => f64::from(i32::from_le_bytes([s[0], s[1], s[2], s[3]])),
                ("float", 4) => f64::from(f32::from_le_bytes([s[0], s[1], s[2], s[3]])),
                _ => f64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]]),
            };
            if !v.is_finite() {
                return Err(err(&format!(
                    "sample {f} of channel {} is not finite",
                    c + 1
                )));
            }
            ch.push(v);
        }
    }
    if n == 0 {
        return Err(err("no samples"));
    }
    let rate = f64::from(rate);
    let mut meta = vec![
        ("rate_hz".to_string(), toml::Value::Float(rate)),
        (
            "wav_format".to_string(),
            toml::Value::String(format!("{kind}{bits}")),
        ),
    ];
    if let Some(fs) = full_scale {
        meta.push(("full_scale".to_string(), toml::Value::Float(fs)));
    }
    // Integer counts stay integers; float samples are written exactly.
    let digits = match (kind, bits) {
        ("int", _) => Digits::Decimals(0),
        (_, 32) => Digits::ShortestF32,
        _ => Digits::Shortest,
    };
    Ok(Imported {
        label: None,
        time: (0..n).map(|i| i as f64 / rate).collect(),
        names: (1..=channels).map(|c| format!("ch{c}")).collect(),
        channel_digits: vec![digits; out.len()],
        channels: out,
        meta,
        time_digits: Digits::Decimals(time_decimals(rate)),
    })
}

/// Writes `imp` as a recording at `path` (a `.csv`), each column with the
/// digits `imp` asks for, then gzips it to `path.gz` when `gzip`; the file
/// written. Not fsynced: the caller syncs the batch.
pub fn write_recording(
    path: &Path,
    imp: &Imported,
    label: &str,
    gzip: bool,
) -> Result<PathBuf, Failure> {
    let mut meta = vec![
        ("label".to_string(), toml::Value::String(label.to_string())),
        ("device".to_string(), toml::Value::String("import".into())),
    ];
    meta.extend(imp.meta.iter().cloned());
    let mut columns: Vec<&str> = vec!["t_s"];
    columns.extend(imp.names.iter().map(String::as_str));
    let mut digits = vec![imp.time_digits];
    digits.extend(imp.channel_digits.iter().copied());
    let mut w =
        RecordingWriter::create_with_digits(path, &meta, &columns, &digits).map_err(|e| {
            match e {
                // A folder that cannot be made or written is no fault of the input.
                RecordingError::Io { .. } => Failure::Runtime(e.to_string()),
                _ => Failure::BadInput(format!("{}: {e}", path.display())),
            }
        })?;
    w.defer_sync();
    let mut row = vec![0.0; columns.len()];
    for (i, &t) in imp.time.iter().enumerate() {
        row[0] = t;
        for (c, ch) in imp.channels.iter().enumerate() {
            row[c + 1] = ch[i];
        }
        w.write_row(&row)
            .map_err(|e| Failure::Runtime(e.to_string()))?;
    }
    w.finish().map_err(|e| Failure::Runtime(e.to_string()))?;
    if gzip {
        crate::recording::compress_quickly(path).map_err(|e| Failure::Runtime(e.to_string()))
    } else {
        Ok(path.to_path_buf())
    }
}

/// Checks the options that apply to every file (`--meta`, `--rate`,
/// `--label`); the extra metadata they give.
pub fn check_options(args: &ImportArgs) -> Result<Vec<(String, toml::Value)>, Failure> {
    let extra: Vec<(String, toml::Value)> = args
        .meta
        .iter()
        .map(|m| parse_meta(m))
        .collect::<Result<_, _>>()?;
    for (i, (k, _)) in extra.iter().enumerate() {
        if extra[..i].iter().any(|(seen, _)| seen == k) {
            return Err(bad(format!(
                "--meta {k} is given twice: give each key once"
            )));
        }
    }
    if let Some(r) = args.rate
        && !(r.is_finite() && r > 0.0 && r <= MAX_RATE_HZ)
    {
        return Err(bad(format!(
            "--rate must be a positive number of Hz up to {MAX_RATE_HZ:e} (beyond it `t_s` \
             cannot be written apart sample by sample), got {r:e}"
        )));
    }
    if let Some(l) = &args.label {
        crate::recording::check_label(l).map_err(|e| bad(format!("--label: {e}")))?;
    }
    if let Some(length) = args.split {
        split::check(length, args.split_hop)?;
    }
    Ok(extra)
}

/// Parses one input file's bytes, in the format its extension `ext` names
/// (`csv`, `txt`, `tsv`, `dat`, `wav`, `wave`, `npy`, `npz`, `mat`; any case), with
/// the mapping in `args`; text whose first line is all numbers is headerless.
/// `origin` names it in messages.
pub fn parse_file(
    bytes: Vec<u8>,
    origin: &str,
    ext: &str,
    args: &ImportArgs,
) -> Result<Imported, Failure> {
    match ext.to_ascii_lowercase().as_str() {
        "wav" | "wave" => {
            let mut w = parse_wav(&bytes, origin)?;
            if !args.names.is_empty() {
                if args.names.len() != w.names.len() {
                    return Err(bad(format!(
                        "--names gives {} name(s) but {origin} has {} channel(s)",
                        args.names.len(),
                        w.names.len()
                    )));
                }
                w.names = args.names.clone();
            }
            Ok(w)
        }
        "csv" | "txt" | "tsv" | "dat" => {
            let text =
                String::from_utf8(bytes).map_err(|_| bad(format!("{origin}: not UTF-8 text")))?;
            if text::is_headerless(&text) {
                text::parse(&text, origin, args)
            } else {
                parse_csv(&text, origin, args)
            }
        }
        "npy" => npy::parse_npy_file(&bytes, origin, args),
        "npz" => npy::parse_npz_file(&bytes, origin, args),
        "mat" => mat::parse_mat_file(&bytes, origin, args),
        _ => Err(bad(format!(
            "{origin}: unknown format (expected .csv, .txt, .dat, .wav, .npy, .npz or .mat)"
        ))),
    }
}

/// One input converted into the staging folder, waiting to be moved in place.
struct Staged {
    /// Where it goes, and the other name of the same recording (`.csv`
    /// beside `.csv.gz`), replaced with it under `--force`.
    path: PathBuf,
    other: PathBuf,
    staged: PathBuf,
}

/// The label of input `f`: `--label`, the label column, or its folder's name.
fn label_of(
    f: &Path,
    origin: &str,
    args: &ImportArgs,
    from_file: Option<String>,
) -> Result<String, Failure> {
    let label = match (&args.label, from_file) {
        (Some(l), _) => l.clone(),
        (None, Some(l)) => l,
        (None, None) => f
            .canonicalize()
            .ok()
            .and_then(|p| {
                p.parent()
                    .and_then(|d| d.file_name())
                    .map(|n| n.to_string_lossy().into_owned())
            })
            .ok_or_else(|| {
                bad(format!(
                    "{origin}: no --label, no --label-column and no folder to name it"
                ))
            })?,
    };
    crate::recording::check_label(&label)
        .map_err(|e| bad(format!("{origin}: label {label:?}: {e}")))?;
    Ok(label)
}

/// Reads, parses and writes input `f` under `staging` (as `<label>/<stem>.csv`
/// or `.csv.gz`; with `--split`, one `<stem>-segNNN` per trial).
fn stage(
    f: &Path,
    args: &ImportArgs,
    extra: &[(String, toml::Value)],
    staging: &Path,
) -> Result<Vec<Staged>, Failure> {
    let origin = f.display().to_string();
    let bytes = read_input(f).map_err(|e| {
        let m = format!("{origin}: {e}");
        // A file named that does not exist, or not a regular file, is the argument's fault.
        if e.kind() == std::io::ErrorKind::NotFound || not_regular(&e) {
            Failure::BadInput(m)
        } else {
            Failure::Runtime(m)
        }
    })?;
    let ext = f
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = f
        .file_stem()
        .map_or("import".into(), |s| s.to_string_lossy().into_owned());
    if stem.starts_with('.') {
        // OUT/<label>/.name.csv would be hidden, and every command skips it.
        return Err(bad(format!(
            "{origin}: a hidden file name would give a hidden recording, which every \
             command skips: rename the file without the leading '.'"
        )));
    }
    let mut imp = parse_file(bytes, &origin, &ext, args)?;
    let label = label_of(f, &origin, args, imp.label.take())?;
    imp.meta
        .push(("source".to_string(), toml::Value::String(origin.clone())));
    check_written_names(&imp, extra, &origin, args)?;
    imp.meta.extend(extra.iter().cloned());
    let Some(length) = args.split else {
        return Ok(vec![stage_one(f, &imp, &label, &stem, args, staging)?]);
    };
    let (length, hop) = split::check(length, args.split_hop)?;
    let parts = split::split(&imp, &origin, length, hop)?;
    parts
        .iter()
        .enumerate()
        .map(|(j, part)| {
            let name = split::stem(&stem, j, parts.len());
            stage_one(f, part, &label, &name, args, staging)
        })
        .collect()
}

/// Writes `imp` under `staging` as `<label>/<stem>.csv` (or `.csv.gz`),
/// unless the place it goes is taken.
fn stage_one(
    f: &Path,
    imp: &Imported,
    label: &str,
    stem: &str,
    args: &ImportArgs,
    staging: &Path,
) -> Result<Staged, Failure> {
    let csv = Path::new(label).join(format!("{stem}.csv"));
    let gz = Path::new(label).join(format!("{stem}.csv.gz"));
    let (name, other) = if args.gzip {
        (gz, csv.clone())
    } else {
        (csv.clone(), gz)
    };
    let (path, other) = (args.out.join(&name), args.out.join(other));
    // --force or not: never a device or FIFO, never the file being read.
    for p in [&path, &other] {
        let kind = check_output_kind(p).map_err(bad)?;
        if kind.is_some_and(|m| same_file_as(&m, std::slice::from_ref(&f.to_path_buf())).is_some())
        {
            return Err(bad(format!(
                "{}: this is the input itself; nothing was imported: give another --out",
                p.display()
            )));
        }
    }
    if !args.force
        && let Some(there) = [&path, &other].into_iter().find(|p| p.exists())
    {
        return Err(bad(format!(
            "{}: already exists (use --force to replace it)",
            there.display()
        )));
    }
    let staged = write_recording(&staging.join(&csv), imp, label, args.gzip)?;
    Ok(Staged {
        path,
        other,
        staged,
    })
}

/// Runs `job` over `0..n` on `threads` threads, each taking the next index;
/// once one fails no new index is taken, so the first failure in index order
/// is always among the results (every index below it was taken first).
fn run_jobs<T: Send>(
    n: usize,
    threads: usize,
    job: &(dyn Fn(usize) -> Result<T, Failure> + Sync),
) -> Vec<Option<Result<T, Failure>>> {
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let parts: Vec<Vec<(usize, Result<T, Failure>)>> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.clamp(1, n.max(1)))
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    while !failed.load(Ordering::SeqCst) {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        if i >= n {
                            break;
                        }
                        let result = job(i);
                        if result.is_err() {
                            failed.store(true, Ordering::SeqCst);
                        }
                        done.push((i, result));
                    }
                    done
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let mut results: Vec<Option<Result<T, Failure>>> = (0..n).map(|_| None).collect();
    for (i, r) in parts.into_iter().flatten() {
        results[i] = Some(r);
    }
    results
}

/// `hapticlab import`: returns the recordings written, in the order of the
/// inputs.
///
/// Every input is converted on `--threads` threads (default: every core)
/// into a hidden staging folder under `--out`; only when all of them are
/// good are they synced and moved in place. A bad input leaves nothing; an
/// interrupted import leaves at most the hidden staging folder, never a half
/// recording where datasets are read. The output does not depend on the
/// number of threads.
pub fn run(args: &ImportArgs) -> Result<Vec<PathBuf>, Failure> {
    let extra = check_options(args)?;
    if let Some(warning) = csv_only_flags_for_wav(args)? {
        crate::errln!("{warning}");
    }
    let threads = match args.threads {
        None | Some(0) => crate::dataset::cores(),
        Some(t) => t,
    };
    let out_existed = args.out.exists();
    if out_existed && !args.out.is_dir() {
        // Said before the staging folder inside it is named. A bad
        // argument (exit 2), like every other `--out` the user can fix.
        return Err(bad(format!(
            "--out {}: not a folder; name a folder (it is made if missing)",
            args.out.display()
        )));
    }
    remove_abandoned_staging(&args.out);
    let staging = args.out.join(format!(".import-{}", std::process::id()));
    let pb = crate::support::progress_bar(args.files.len() as u64, "importing");
    let results = run_jobs(args.files.len(), threads, &|i| {
        let staged = stage(&args.files[i], args, &extra, &staging);
        pb.inc(1);
        staged
    });
    pb.finish_and_clear();
    let moved = settle(args, &staging, results);
    let _ = std::fs::remove_dir_all(&staging);
    if moved.is_err() && !out_existed {
        // Only empty folders go: the ones this import made.
        let _ = std::fs::remove_dir(&args.out);
    }
    moved
}

/// Remove the staging folders (`.import-<pid>`) of imports that were killed:
/// those whose process is gone. A running import's folder is left alone.
fn remove_abandoned_staging(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(".import-"))
            .and_then(|p| p.parse::<libc::pid_t>().ok())
        else {
            continue;
        };
        // SAFETY: kill with signal 0 sends nothing; it only asks whether
        // the process exists (EPERM: it does, under another user).
        let alive = pid > 0
            && (unsafe { libc::kill(pid, 0) } == 0
                || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM));
        if !alive && entry.path().is_dir() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// The first failure in input order, or every staged recording synced and
/// moved in place.
fn settle(
    args: &ImportArgs,
    staging: &Path,
    results: Vec<Option<Result<Vec<Staged>, Failure>>>,
) -> Result<Vec<PathBuf>, Failure> {
    let mut staged: Vec<Staged> = Vec::new();
    let mut places = std::collections::HashSet::new();
    for r in results {
        // A job not taken comes after a failure, which is met first.
        for s in r.ok_or_else(|| Failure::Runtime("an input was skipped".into()))?? {
            if !places.insert(s.path.clone()) {
                return Err(bad(format!(
                    "two inputs would both write {}",
                    s.path.display()
                )));
            }
            staged.push(s);
        }
    }
    if staged.is_empty() {
        return Ok(Vec::new());
    }
    crate::recording::sync_folder(staging).map_err(|e| Failure::Runtime(e.to_string()))?;
    place(&staged, args.force)
}

/// Moves every staged recording in place. Without `force` each move is
/// one atomic step that fails when the name is taken ([`move_no_replace`]),
/// so of two imports of the same names at once one gets each name; the one
/// that meets a name taken removes the recordings it placed itself and
/// refuses, naming it: a folder never ends with a mix of two batches.
fn place(staged: &[Staged], force: bool) -> Result<Vec<PathBuf>, Failure> {
    let mut written = Vec::with_capacity(staged.len());
    for s in staged {
        if let Err(e) = place_one(s, force) {
            // Only ours go: each was placed by this run a moment ago.
            for p in &written {
                let _ = std::fs::remove_file(p);
            }
            return Err(e);
        }
        written.push(s.path.clone());
    }
    Ok(written)
}

fn place_one(s: &Staged, force: bool) -> Result<(), Failure> {
    let fail = |p: &Path, e: std::io::Error| Failure::Runtime(format!("{}: {e}", p.display()));
    if let Some(d) = s.path.parent() {
        std::fs::create_dir_all(d).map_err(|e| fail(d, e))?;
    }
    if force {
        std::fs::rename(&s.staged, &s.path).map_err(|e| fail(&s.path, e))?;
        if s.other.exists() {
            std::fs::remove_file(&s.other).map_err(|e| fail(&s.other, e))?;
        }
        return Ok(());
    }
    let taken = |p: &Path| {
        bad(format!(
            "{}: already exists (placed by another import running at the same time, or there before); nothing was imported: import into another --out, or use --force to replace it",
            p.display()
        ))
    };
    match move_no_replace(&s.staged, &s.path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(taken(&s.path)),
        Err(e) => return Err(fail(&s.path, e)),
    }
    if s.other.exists() {
        // The same recording under its other name (.csv beside .csv.gz).
        let _ = std::fs::remove_file(&s.path);
        return Err(taken(&s.other));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A staged file `name` holding `text`, bound for `out/name`.
    fn staged(staging: &Path, out: &Path, name: &str, text: &str) -> Staged {
        std::fs::create_dir_all(staging).unwrap();
        let s = staging.join(name);
        std::fs::write(&s, text).unwrap();
        Staged {
            path: out.join(name),
            other: out.join(format!("{name}.gz")),
            staged: s,
        }
    }

    #[test]
    fn a_name_taken_while_placing_undoes_only_this_runs_files() {
        let dir = tempfile::tempdir().unwrap();
        let (staging, out) = (dir.path().join(".import-1"), dir.path().join("out"));
        let batch: Vec<Staged> = ["a.csv", "b.csv", "c.csv"]
            .iter()
            .map(|n| staged(&staging, &out, n, "ours"))
            .collect();
        // Another import placed c.csv after this one's check, before its move.
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("c.csv"), "theirs").unwrap();
        let e = place(&batch, false).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(
            e.message().contains("c.csv: already exists"),
            "{}",
            e.message()
        );
        let mut left: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["c.csv"]);
        assert_eq!(
            std::fs::read_to_string(out.join("c.csv")).unwrap(),
            "theirs"
        );
        // The other name of a recording placed is a collision too.
        let one = [staged(&staging, &out, "d.csv", "ours")];
        std::fs::write(out.join("d.csv.gz"), "theirs").unwrap();
        let e = place(&one, false).unwrap_err();
        assert!(
            e.message().contains("d.csv.gz: already exists"),
            "{}",
            e.message()
        );
        assert!(!out.join("d.csv").exists());
        // With --force the batch replaces.
        let forced = [staged(&staging, &out, "c.csv", "ours")];
        assert_eq!(place(&forced, true).unwrap(), [out.join("c.csv")]);
        assert_eq!(std::fs::read_to_string(out.join("c.csv")).unwrap(), "ours");
    }
}
