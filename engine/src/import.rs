//! Recordings v1 from other rigs' files (the engine of `hapticlab import`):
//! CSV with a column mapping (`csv.rs`), headerless numeric text (`text.rs`),
//! WAV (`wav.rs`), NumPy `.npy`/`.npz` (`npy.rs`) and MATLAB v5 `.mat`
//! (`mat.rs`); the label from [`Request::label`], a label column or the
//! file's folder name; extra metadata `key=value`; long recordings cut
//! into trials (`split.rs`).
//!
//! Written exactly: integer samples as integers, float samples and a CSV's
//! values in the shortest text that reads back as the same number, `t_s`
//! with decimals enough for the rate (within 0.5 % of a sample period).
//!
//! Files are converted on every core into a hidden staging folder under
//! `--out` and moved in place only once all are complete (`place.rs`), so a bad input
//! leaves nothing behind and an interrupted import no half recording.
//! This module reads only the files it is given and writes only under
//! [`Request::out`]. It never prints: warnings and progress go to a
//! [`Report`], failures are an [`ImportError`].

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::io::{check_output_kind, not_regular, same_file_as};
use crate::recording::{Digits, MAX_RATE_HZ, MIN_RATE_HZ, RecordingError, RecordingWriter};

mod checks;
mod csv;
mod mat;
mod npy;
mod place;
mod provenance;
mod split;
mod text;
mod wav;
use checks::{check_written_names, flags_a_wav_ignores, one_folder_for_every_label};
pub use csv::parse_csv;
use place::{LOCK_FILE, Staged, earlier_cuts, remove_abandoned_staging, settle};
pub use provenance::Source;
pub use split::Segment;
pub use wav::parse_wav;

/// What to import and how: the files, the folder, and the mapping of
/// their columns (the command line's flags, one field each). The default
/// names no file and reads one sample of each channel per row.
#[derive(Debug, Clone)]
pub struct Request {
    /// CSV or WAV files to import (the format is taken from the extension).
    pub files: Vec<PathBuf>,
    /// Output folder; recordings go to OUT/<label>/<file stem>.csv.
    pub out: PathBuf,
    /// CSV: the column holding each row's time in seconds.
    pub time_column: Option<String>,
    /// The sampling rate in Hz, from [`MIN_RATE_HZ`] to [`MAX_RATE_HZ`] (CSV
    /// without a time column, headerless text, .npy, .npz and .mat; WAV files
    /// carry their own).
    pub rate: Option<f64>,
    /// CSV: the channel columns, comma-separated (default: every column but the time and label columns).
    pub channels: Vec<String>,
    /// Names of the recorded channels (default: the CSV column names, or ch1, ch2, … for WAV and bursts).
    pub names: Vec<String>,
    /// CSV: samples of each channel per row (the columns of a channel consecutive).
    pub burst: usize,
    /// The texture's label.
    pub label: Option<String>,
    /// CSV: the column holding the label (one value per file).
    pub label_column: Option<String>,
    /// Extra metadata, e.g. --meta session=3 --meta rig=\"bench A\".
    pub meta: Vec<String>,
    /// CSV field separator (default: `,`, or `;` or a tab when the header has one and no comma).
    pub delimiter: Option<char>,
    /// Replace the recordings already at the names this import writes
    /// (OUT/<label>/<stem>.csv or .csv.gz, the other of the two removed);
    /// without it a name taken is refused and nothing is imported.
    pub force: bool,
    /// Compress each recording to OUT/<label>/<file stem>.csv.gz (gzip -9).
    pub gzip: bool,
    /// Cut each input into consecutive trials this many seconds long, at
    /// least 16 samples (<stem>-seg001.csv, …, in time order), for one long
    /// recording per material.
    pub split: Option<f64>,
    /// With --split: seconds from one trial's start to the next, at least a
    /// tenth of the trial's length (default: the length, no overlap).
    pub split_hop: Option<f64>,
    /// Files converted at once (default: the number of cores; 0 means the same).
    pub threads: Option<usize>,
    /// Begin each recording's name with the name of the folder above its
    /// input's own (days/day1/felt/trial1.txt → OUT/felt/day1-trial1.csv).
    pub prefix_parent: bool,
}

impl Default for Request {
    fn default() -> Request {
        Request {
            files: Vec::new(),
            out: PathBuf::new(),
            time_column: None,
            rate: None,
            channels: Vec::new(),
            names: Vec::new(),
            burst: 1,
            label: None,
            label_column: None,
            meta: Vec::new(),
            delimiter: None,
            force: false,
            gzip: false,
            split: None,
            split_hop: None,
            threads: None,
            prefix_parent: false,
        }
    }
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

/// Why an import wrote nothing.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The inputs or the flags are at fault (exit code 2): the message
    /// names the file or the flag and what to change.
    #[error("{0}")]
    BadInput(String),
    /// Reading or writing failed (exit code 1).
    #[error("{0}")]
    Runtime(String),
}

impl ImportError {
    pub fn is_bad_input(&self) -> bool {
        matches!(self, ImportError::BadInput(_))
    }
}

/// What an import tells its caller while it runs.
pub trait Report: Sync {
    /// A warning to show (the import goes on).
    fn warn(&self, message: &str);
    /// One more input converted.
    fn file_done(&self);
}

/// A [`Report`] that shows nothing.
pub struct Quiet;

impl Report for Quiet {
    fn warn(&self, _: &str) {}
    fn file_done(&self) {}
}

/// The largest input import reads: its samples are held as text and as
/// numbers at once, and a run stays within 2 GB.
const MAX_INPUT_BYTES: u64 = 512 << 20;

/// The largest integer a sample (a 64-bit float) holds exactly: 2^53.
const EXACT_INTEGER: f64 = 9_007_199_254_740_992.0;

/// An integer sample beyond [`EXACT_INTEGER`]: refused, never rounded.
fn inexact_integer(at: &str, value: usize, text: &str) -> ImportError {
    bad(format!(
        "{at}: value {value} ({text}) is an integer beyond 2^53 = 9007199254740992, which a \
         recording's samples (64-bit floats) cannot hold exactly: subtract an offset or scale it \
         before importing"
    ))
}

fn bad(m: impl std::fmt::Display) -> ImportError {
    ImportError::BadInput(m.to_string())
}

/// `x` as a person would write it in a message: `0`, `-1000`, `0.001`,
/// and `1e-310` or `1e16` only where the digits would run on.
fn plain(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `key=value` with the value in TOML (a bare word is taken as a string).
pub fn parse_meta(kv: &str) -> Result<(String, toml::Value), ImportError> {
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

/// Writes `imp` as a recording at `path` (a `.csv`), each column with the
/// digits `imp` asks for, then gzips it to `path.gz` when `gzip`; the file
/// written. Not fsynced: the caller syncs the batch. What the format cannot
/// hold is a [`ImportError::BadInput`] naming neither file.
pub fn write_recording(
    path: &Path,
    imp: &Imported,
    label: &str,
    gzip: bool,
) -> Result<PathBuf, ImportError> {
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
                // What the recording cannot hold, without the path written
                // to (a staging file): the caller names the input.
                RecordingError::Write { reason, .. } => ImportError::BadInput(reason),
                // A folder that cannot be made or written is no fault of the input.
                _ => ImportError::Runtime(e.to_string()),
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
            .map_err(|e| ImportError::Runtime(e.to_string()))?;
    }
    w.finish()
        .map_err(|e| ImportError::Runtime(e.to_string()))?;
    if gzip {
        crate::recording::compress_quickly(path).map_err(|e| ImportError::Runtime(e.to_string()))
    } else {
        Ok(path.to_path_buf())
    }
}

/// Checks the options that apply to every file (`--meta`, `--rate`,
/// `--label`); the extra metadata they give.
pub fn check_options(args: &Request) -> Result<Vec<(String, toml::Value)>, ImportError> {
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
    // Checked for every format before any file is read: slower, the
    // sample times run to hundreds of digits or overflow; faster, `t_s`
    // cannot tell one sample from the next.
    if let Some(r) = args.rate
        && (r.is_nan() || r <= 0.0)
    {
        return Err(bad(format!(
            "--rate must be a positive number of samples per second (Hz), got {}",
            plain(r)
        )));
    }
    if let Some(r) = args.rate
        && !(r.is_finite() && (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&r))
    {
        return Err(bad(format!(
            "--rate must be from {} Hz (a sample every {} s) to {MAX_RATE_HZ:e} Hz, got {}: \
             slower, the sample times would not be finite or would run to hundreds of digits; \
             faster, `t_s` could not tell the samples apart",
            plain(MIN_RATE_HZ),
            plain(1.0 / MIN_RATE_HZ),
            plain(r)
        )));
    }
    if args.burst == 0 {
        return Err(bad(
            "--burst 0: a row holds at least one sample of each channel (--burst 1, the default)",
        ));
    }
    if let Some(l) = &args.label {
        crate::recording::check_label(l).map_err(|e| bad(format!("--label: {e}")))?;
    }
    if let Some(length) = args.split {
        split::check(length, args.split_hop, args.rate)?;
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
    args: &Request,
) -> Result<Imported, ImportError> {
    if bytes.is_empty() {
        return Err(bad(format!(
            "{origin}: the file is empty (0 bytes): nothing to import"
        )));
    }
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
            // A byte-order mark is no part of the first value or name.
            let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
            if !text::has_lines(text) {
                return Err(bad(format!(
                    "{origin}: holds no header and no samples, only blank or comment lines"
                )));
            }
            if text::is_headerless(text) {
                checks::csv_only_flags(args, origin, "a file without a header")?;
                text::parse(text, origin, args)
            } else {
                parse_csv(text, origin, args)
            }
        }
        "npy" => {
            checks::csv_only_flags(args, origin, "a .npy file")?;
            npy::parse_npy_file(&bytes, origin, args)
        }
        "npz" => {
            checks::csv_only_flags(args, origin, "a .npz file")?;
            npy::parse_npz_file(&bytes, origin, args)
        }
        "mat" => {
            checks::csv_only_flags(args, origin, "a .mat file")?;
            mat::parse_mat_file(&bytes, origin, args)
        }
        _ => Err(bad(format!(
            "{origin}: unknown format (expected .csv, .txt, .dat, .wav, .npy, .npz or .mat)"
        ))),
    }
}

/// The label of input `f`: `--label`, the label column, or its folder's name.
fn label_of(
    f: &Path,
    origin: &str,
    args: &Request,
    from_file: Option<String>,
) -> Result<String, ImportError> {
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

/// The name of the folder above input `f`'s own (`day1` for
/// `days/day1/felt/trial1.txt`), if it has one.
fn folder_above(f: &Path) -> Option<String> {
    let path = f.canonicalize().ok()?;
    let name = path.parent()?.parent()?.file_name()?;
    Some(name.to_string_lossy().into_owned())
}

/// `--prefix-parent`'s prefix for input `f`: the folder above its own.
fn prefix_of(f: &Path, origin: &str) -> Result<String, ImportError> {
    let prefix = folder_above(f).ok_or_else(|| {
        bad(format!(
            "{origin}: --prefix-parent: its folder has no folder above it to name the recording by"
        ))
    })?;
    if prefix.starts_with('.') {
        // OUT/<label>/.x-name.csv would be hidden, and every command skips it.
        return Err(bad(format!(
            "{origin}: --prefix-parent: the folder above its own, {prefix:?}, is hidden and \
             would give a hidden recording: leave out --prefix-parent, or rename the folder"
        )));
    }
    Ok(prefix)
}

/// Reads, parses and writes input `f` under `staging` (as `<label>/<stem>.csv`
/// or `.csv.gz`; with `--split`, one `<stem>-segNNN` per trial).
fn stage(
    f: &Path,
    args: &Request,
    extra: &[(String, toml::Value)],
    staging: &Path,
) -> Result<Vec<Staged>, ImportError> {
    let origin = f.display().to_string();
    let bytes = crate::io::read_input_at_most(f, MAX_INPUT_BYTES).map_err(|e| {
        let m = if e.get_ref().is_some_and(|i| i.is::<crate::io::TooLarge>()) {
            format!(
                "{origin}: {e}: import reads inputs of up to 512 MiB (what it holds is kept in \
                 memory twice over); cut it into parts first"
            )
        } else {
            format!("{origin}: {}", crate::io::said(&e))
        };
        // A file named that does not exist, not a regular file, or too
        // large, is the argument's fault.
        if e.kind() == std::io::ErrorKind::NotFound
            || not_regular(&e)
            || e.kind() == std::io::ErrorKind::InvalidData
        {
            ImportError::BadInput(m)
        } else {
            ImportError::Runtime(m)
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
    let stem = if args.prefix_parent {
        format!("{}-{stem}", prefix_of(f, &origin)?)
    } else {
        stem
    };
    let source = std::sync::Arc::new(Source::of(f, &bytes));
    let mut imp = parse_file(bytes, &origin, &ext, args)?;
    let label = label_of(f, &origin, args, imp.label.take())?;
    imp.meta.extend(source.meta());
    // Which hapticlab wrote it, as every recording says (and `--meta
    // software=…` is refused as a key the import writes).
    imp.meta.push((
        "software".to_string(),
        toml::Value::String(crate::version::SOFTWARE.into()),
    ));
    check_written_names(&imp, extra, &origin, args)?;
    imp.meta.extend(extra.iter().cloned());
    let Some(length) = args.split else {
        let staged = vec![stage_one(f, &imp, &label, &stem, args, staging, &source)?];
        return one_cut(staged, args);
    };
    let cut = split::check(length, args.split_hop, args.rate)?;
    let parts = split::split(&imp, &origin, cut)?;
    let mut staged = parts
        .iter()
        .enumerate()
        .map(|(j, part)| {
            let name = split::stem(&stem, j, parts.len());
            stage_one(f, part, &label, &name, args, staging, &source)
        })
        .collect::<Result<Vec<Staged>, ImportError>>()?;
    if let Some(first) = staged.first_mut() {
        first.left_out_s = split::left_over(&imp, cut);
    }
    one_cut(staged, args)
}

/// Without `--force`, an input a folder already holds cut another way (a
/// whole recording beside its trials, or trials of another length) is
/// refused, naming that cut: a folder holds one cut of each input.
fn one_cut(staged: Vec<Staged>, args: &Request) -> Result<Vec<Staged>, ImportError> {
    if args.force {
        return Ok(staged);
    }
    let earlier = earlier_cuts(&staged);
    let (Some(first), Some(s)) = (earlier.first(), staged.first()) else {
        return Ok(staged);
    };
    Err(bad(format!(
        "{}: {} already holds {} an earlier import cut from it another way ({}{}); a folder \
         holds one cut of each input, so nothing was imported: --force replaces that cut with \
         this one, or import into another --out",
        s.input.display(),
        first.parent().unwrap_or(&args.out).display(),
        match earlier.len() {
            1 => "a recording".to_string(),
            n => format!("{n} recordings"),
        },
        first.display(),
        match earlier.last() {
            Some(last) if earlier.len() > 1 => format!(" … {}", last.display()),
            _ => String::new(),
        }
    )))
}

/// Writes `imp` under `staging` as `<label>/<stem>.csv` (or `.csv.gz`),
/// unless the place it goes is taken.
fn stage_one(
    f: &Path,
    imp: &Imported,
    label: &str,
    stem: &str,
    args: &Request,
    staging: &Path,
    source: &std::sync::Arc<Source>,
) -> Result<Staged, ImportError> {
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
    // A name taken, by anything (a symlink that leads nowhere too): without
    // --force refused; with it, only a recording import wrote from this input.
    for there in [&path, &other]
        .into_iter()
        .filter(|p| std::fs::symlink_metadata(p).is_ok())
    {
        if !args.force {
            return Err(bad(format!(
                "{}: already exists (use --force to replace it)",
                there.display()
            )));
        }
        source
            .wrote(there)
            .map_err(|why| place::not_ours(there, f, &why))?;
    }
    let staged =
        write_recording(&staging.join(&csv), imp, label, args.gzip).map_err(|e| match e {
            ImportError::BadInput(m) => bad(format!("{}: {m}", f.display())),
            runtime => runtime,
        })?;
    Ok(Staged {
        input: f.to_path_buf(),
        path,
        other,
        staged,
        left_out_s: 0.0,
        source: source.clone(),
    })
}

/// What `--force` removed of an input's earlier cut, each one named: one
/// line an input.
fn removed_cut(input: &Path, gone: &[PathBuf]) -> String {
    let folder = gone[0].parent().unwrap_or(Path::new(""));
    let names: Vec<String> = gone
        .iter()
        .map(|p| match p.parent() {
            Some(d) if d == folder => p.file_name().unwrap_or_default().to_string_lossy().into(),
            _ => p.display().to_string(),
        })
        .collect();
    format!(
        "--force: removed {} recording(s) an earlier import cut another way from {} (a folder \
         holds one cut of each input), from {}: {}",
        gone.len(),
        input.display(),
        folder.display(),
        names.join(", ")
    )
}

/// With `--split`: the inputs whose end no whole trial covers, in one
/// line (the longest tail left out, an example, and how to keep more).
fn left_out_tails(results: &[Option<Result<Vec<Staged>, ImportError>>]) -> Option<String> {
    let tails: Vec<(&Path, f64)> = results
        .iter()
        .flatten()
        .filter_map(|r| r.as_ref().ok())
        .filter_map(|staged| staged.first())
        .filter(|s| s.left_out_s > 0.0)
        .map(|s| (s.input.as_path(), s.left_out_s))
        .collect();
    let longest = tails.iter().map(|t| t.1).fold(0.0, f64::max);
    let (example, _) = tails.iter().find(|t| t.1 == longest)?;
    Some(format!(
        "--split: the end of {} no whole trial covers was left out (up to {} s, as in {}); \
         a --split or --split-hop that divides the inputs' length keeps it",
        match tails.len() {
            1 => "1 input".to_string(),
            n => format!("{n} inputs"),
        },
        plain(crate::profile::fitted::significant(longest, 6)),
        example.display()
    ))
}

/// Runs `job` over `0..n` on `threads` threads, each taking the next index;
/// once one fails no new index is taken, so the first failure in index order
/// is always among the results (every index below it was taken first).
fn run_jobs<T: Send>(
    n: usize,
    threads: usize,
    job: &(dyn Fn(usize) -> Result<T, ImportError> + Sync),
) -> Vec<Option<Result<T, ImportError>>> {
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let parts: Vec<Vec<(usize, Result<T, ImportError>)>> = std::thread::scope(|s| {
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
    let mut results: Vec<Option<Result<T, ImportError>>> = (0..n).map(|_| None).collect();
    for (i, r) in parts.into_iter().flatten() {
        results[i] = Some(r);
    }
    results
}

/// Imports `args.files` into `args.out`: returns the recordings written, in
/// the order of the inputs; `report` hears of warnings and each file done.
///
/// Every input is converted on `--threads` threads (default: every core)
/// into a hidden staging folder under `--out`; only when all of them are
/// good are they synced and moved in place. A bad input leaves nothing; an
/// interrupted import leaves at most the hidden staging folder, never a half
/// recording where datasets are read. The output does not depend on the
/// number of threads.
pub fn run(args: &Request, report: &dyn Report) -> Result<Vec<PathBuf>, ImportError> {
    let extra = check_options(args)?;
    if let Some(warning) = flags_a_wav_ignores(args)? {
        report.warn(&warning);
    }
    let threads = match args.threads {
        None | Some(0) => std::thread::available_parallelism().map_or(1, usize::from),
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
    // One import at a time into a folder: the checks, placing and clean-up
    // below are one step under this lock (released when `_lock` drops, or
    // by the system if the process dies).
    let _lock = crate::io::FolderLock::acquire(&args.out, LOCK_FILE, |held| {
        report.warn(&format!(
            "another import is writing into {}: waiting for it to finish ({} is locked)",
            args.out.display(),
            held.display()
        ))
    })
    .map_err(|e| {
        ImportError::Runtime(format!(
            "{}: cannot take the import lock: {e}",
            args.out.join(LOCK_FILE).display()
        ))
    })?;
    remove_abandoned_staging(&args.out);
    let staging = args.out.join(format!(".import-{}", std::process::id()));
    let results = run_jobs(args.files.len(), threads, &|i| {
        let staged = stage(&args.files[i], args, &extra, &staging);
        report.file_done();
        staged
    });
    let cut_short = left_out_tails(&results);
    let moved = settle(args, &staging, results);
    let _ = std::fs::remove_dir_all(&staging);
    if moved.is_err() && !out_existed {
        // Only what this import made: the folder if empty, once the lock
        // (whose file is in it) is let go.
        drop(_lock);
        let _ = std::fs::remove_dir(&args.out);
    }
    if let Ok(settled) = &moved {
        for (input, gone) in &settled.removed {
            report.warn(&removed_cut(input, gone));
        }
    }
    let moved = moved.map(|s| s.written);
    if moved.is_ok()
        && let Some(warning) = cut_short
    {
        report.warn(&warning);
    }
    // Said once the import is done, so a refusal stays one line.
    if moved.is_ok()
        && let Some(warning) = one_folder_for_every_label(args)
    {
        report.warn(&warning);
    }
    moved
}
