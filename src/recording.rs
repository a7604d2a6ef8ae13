//! Recording format v1: one scan per file, as plain text.
//!
//! ```text
//! # hapticlab recording v1
//! # label = "S2"                       metadata: `# key = value`, value in TOML
//! t_s,x_m,y_m,z_m,fx_n,fy_n,fz_n       header: t_s first, names end in their unit
//! 0.000000,-0.045000,-0.004800,-0.020000,0.000,-0.310,0.000
//! # end samples = 8970                 trailer: present only on a complete scan
//! ```
//!
//! This module owns the format: reading it (plain or gzip-compressed, with
//! errors that name the file, the line and why), writing it row by row during
//! a scan, and finding recordings under folders. The reader never panics on
//! any input; the writer never allocates per row. Deciding what to do with an
//! incomplete recording, and which metadata to write, is the caller's job.
//!
//! Outside tools: pandas reads a recording as is, `read_csv(f, comment='#')`.
//! numpy's `genfromtxt(names=True)` takes its names from the first line even
//! when it is a comment (here the format line), so give it the other lines:
//! `genfromtxt((l for l in open(f) if not l.startswith('#')), delimiter=',', names=True)`.

use std::collections::HashMap;
use std::fs;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

/// The first line of every recording in this format.
pub const FORMAT_LINE: &str = "# hapticlab recording v1";
const FORMAT_PREFIX: &str = "# hapticlab recording v";
/// The trailer's key: `# end samples = N`.
pub(crate) const TRAILER_KEY: &str = "end samples";
/// The metadata key `abort` writes.
pub const ABORTED_KEY: &str = "aborted";
/// Offending text is quoted in messages up to this many characters.
const QUOTE_CHARS: usize = 24;
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

mod label;
mod number;
mod writer;
pub use label::check_label;
use number::{parse_row_fast, parse_value};
pub use writer::{RecordingWriter, compress, decimals_for, sync_folder};

#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be read, created or written.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: io::Error },
    /// The text breaks the format at a line (1-based).
    #[error("{origin}:{line}: {reason}")]
    Malformed {
        origin: String,
        line: usize,
        reason: String,
    },
    /// The gzip stream around the text is cut short or corrupt.
    #[error("{origin}: {reason}")]
    Compressed { origin: String, reason: String },
    /// The writer was asked for something the format cannot hold (bad column
    /// names or metadata, a row of the wrong length).
    #[error("{}: {reason}", path.display())]
    Write { path: PathBuf, reason: String },
}

impl RecordingError {
    /// True when the recording itself is at fault (exit code 2), false for an
    /// I/O failure or a misuse of the writer (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        matches!(self, Self::Malformed { .. } | Self::Compressed { .. })
    }
}

/// One scan, as read from a recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recording {
    pub path: Option<PathBuf>,
    /// `# key = value` lines, in file order (including `aborted` after the rows).
    pub meta: Vec<(String, toml::Value)>,
    pub columns: Vec<String>,
    /// Column-major: `data[c][row]`.
    pub data: Vec<Vec<f64>>,
    /// `Some(N)` when the trailer `# end samples = N` was present.
    pub trailer_samples: Option<usize>,
    /// The file ended in a row cut short (a write interrupted by `kill -9`,
    /// a power cut or a full disk): that row was dropped, and the recording
    /// is incomplete.
    pub torn_last_row: bool,
}

impl Recording {
    /// Number of samples (rows).
    pub fn len(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// A complete scan ends with the trailer; an interrupted one does not.
    pub fn is_complete(&self) -> bool {
        self.trailer_samples.is_some()
    }
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let c = self.columns.iter().position(|n| n == name)?;
        self.data.get(c).map(Vec::as_slice)
    }
    pub fn meta(&self, key: &str) -> Option<&toml::Value> {
        self.meta.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
    pub fn meta_str(&self, key: &str) -> Option<&str> {
        self.meta(key)?.as_str()
    }
    /// A number from the metadata, written either as a float or an integer.
    pub fn meta_f64(&self, key: &str) -> Option<f64> {
        match self.meta(key)? {
            toml::Value::Float(f) => Some(*f),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        }
    }
    /// The texture label (`label` in the metadata).
    pub fn label(&self) -> Option<&str> {
        self.meta_str("label")
    }
    /// The reason given when the scan was aborted, if it was.
    pub fn aborted(&self) -> Option<&str> {
        self.meta_str(ABORTED_KEY)
    }
    /// The file name for messages, or `<memory>` for a parsed buffer.
    pub fn origin(&self) -> String {
        self.path
            .as_ref()
            .map_or_else(|| "<memory>".to_string(), |p| p.display().to_string())
    }
}

/// Reads a recording; a gzip-compressed one (`.gz`, or gzip's magic bytes) is
/// decompressed transparently.
pub fn read(path: &Path) -> Result<Recording, RecordingError> {
    let bytes = fs::read(path).map_err(|source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let origin = path.display().to_string();
    let named_gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    if named_gz && !bytes.starts_with(&GZIP_MAGIC) {
        return Err(RecordingError::Compressed {
            origin,
            reason: "truncated or not a gzip stream (the name ends in .gz but the gzip header is missing)"
                .to_string(),
        });
    }
    let mut recording = parse(&bytes, &origin)?;
    recording.path = Some(path.to_path_buf());
    Ok(recording)
}

/// Parses a recording held in memory (gzip-compressed or not); `origin` names
/// it in error messages.
pub fn parse(bytes: &[u8], origin: &str) -> Result<Recording, RecordingError> {
    if bytes.starts_with(&GZIP_MAGIC) {
        let text = gunzip(bytes, origin)?;
        return parse_text(&text, origin);
    }
    parse_text(bytes, origin)
}

/// A gzipped recording may hold at most this much text, or this many times
/// its compressed size if that is more: a real recording (CSV of decimals)
/// compresses three to five times, a gzip bomb a thousand.
const GZIP_MIN_LIMIT: u64 = 1 << 30;
const GZIP_MAX_RATIO: u64 = 100;

fn gunzip(bytes: &[u8], origin: &str) -> Result<Vec<u8>, RecordingError> {
    let limit = (bytes.len() as u64)
        .saturating_mul(GZIP_MAX_RATIO)
        .max(GZIP_MIN_LIMIT);
    gunzip_at_most(bytes, origin, limit)
}

fn gunzip_at_most(bytes: &[u8], origin: &str, limit: u64) -> Result<Vec<u8>, RecordingError> {
    let mut text = Vec::with_capacity(bytes.len().saturating_mul(4));
    flate2::read::MultiGzDecoder::new(bytes)
        .take(limit.saturating_add(1))
        .read_to_end(&mut text)
        .map_err(|e| RecordingError::Compressed {
            origin: origin.to_string(),
            reason: if e.kind() == io::ErrorKind::UnexpectedEof {
                format!(
                    "truncated gzip stream (it ends after {} bytes of text)",
                    text.len()
                )
            } else {
                format!("corrupt gzip stream ({e})")
            },
        })?;
    if text.len() as u64 > limit {
        return Err(RecordingError::Compressed {
            origin: origin.to_string(),
            reason: format!(
                "it unpacks to more than {limit} bytes ({} compressed): too large for a recording (a gzip bomb?)",
                bytes.len()
            ),
        });
    }
    Ok(text)
}

fn parse_text(bytes: &[u8], origin: &str) -> Result<Recording, RecordingError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let before = bytes.get(..at).unwrap_or_default();
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        RecordingError::Malformed {
            origin: origin.to_string(),
            line: count_newlines(before) + 1,
            reason: format!(
                "invalid UTF-8 (byte 0x{:02x} at column {}); a recording is plain text",
                bytes.get(at).copied().unwrap_or(0),
                at - line_start + 1
            ),
        }
    })?;
    Parser::new(text, origin).run()
}

fn count_newlines(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count()
}

/// What a `#` line holds.
enum Comment<'a> {
    /// `# end samples = …`, with the text after the key.
    Trailer(&'a str),
    /// `# key = value`, with the key and the whole `key = value` text.
    Meta(&'a str, &'a str),
    Other,
}

fn classify_comment(line: &str) -> Comment<'_> {
    let body = line.trim().strip_prefix('#').unwrap_or(line).trim();
    if let Some(rest) = body.strip_prefix(TRAILER_KEY)
        && (rest.is_empty() || rest.starts_with([' ', '\t', '=']))
    {
        return Comment::Trailer(rest.trim_start());
    }
    match body.split_once('=') {
        Some((key, _)) if is_bare_key(key.trim()) => Comment::Meta(key.trim(), body),
        _ => Comment::Other,
    }
}

/// TOML's bare keys: ASCII letters, digits, `_` and `-`.
pub(crate) fn is_bare_key(key: &str) -> bool {
    !key.is_empty()
        && key
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

/// Quotes offending text for a message, cut to a readable length.
pub(crate) fn quote(text: &str) -> String {
    let mut chars = text.chars();
    let short: String = chars.by_ref().take(QUOTE_CHARS).collect();
    if chars.next().is_some() {
        format!("{short:?}…")
    } else {
        format!("{short:?}")
    }
}

/// Checks a header's names; the reason when they break the format.
pub(crate) fn check_columns(names: &[&str]) -> Result<(), String> {
    match names.first() {
        Some(&"t_s") => {}
        Some(first) => {
            return Err(format!(
                "the first column must be t_s (time in seconds), not {}",
                quote(first)
            ));
        }
        None => return Err("the header names no columns".to_string()),
    }
    if names.len() < 2 {
        return Err("the header names only t_s; a recording needs at least one channel".into());
    }
    let mut seen: HashMap<&str, usize> = HashMap::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        let valid = name.bytes().next().is_some_and(|b| b.is_ascii_alphabetic())
            && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_');
        if name.is_empty() {
            return Err(format!("column {} has no name", i + 1));
        }
        if !valid {
            return Err(format!(
                "column name {} must start with a letter and hold only letters, digits and _",
                quote(name)
            ));
        }
        if let Some(first) = seen.insert(name, i + 1) {
            return Err(format!(
                "column {name} appears twice (columns {first} and {})",
                i + 1
            ));
        }
    }
    Ok(())
}

struct Parser<'a> {
    origin: &'a str,
    text: &'a str,
    /// Start of the next line.
    pos: usize,
    /// Number of the line last taken (1-based).
    line: usize,
    recording: Recording,
    /// The line of each metadata key, to point at the first when one repeats.
    meta_lines: HashMap<String, usize>,
    /// (N, line) of the trailer once seen.
    trailer: Option<(usize, usize)>,
    /// The line of the last row read.
    last_row_line: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, origin: &'a str) -> Self {
        Self {
            origin,
            text,
            pos: 0,
            line: 0,
            recording: Recording::default(),
            meta_lines: HashMap::new(),
            trailer: None,
            last_row_line: 0,
        }
    }

    fn next_line(&mut self) -> Option<&'a str> {
        let rest = self.text.get(self.pos..).filter(|r| !r.is_empty())?;
        let (line, used) = match rest.find('\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += used;
        self.line += 1;
        Some(line.strip_suffix('\r').unwrap_or(line))
    }

    fn error_at(&self, line: usize, reason: impl Into<String>) -> RecordingError {
        RecordingError::Malformed {
            origin: self.origin.to_string(),
            line,
            reason: reason.into(),
        }
    }

    fn error(&self, reason: impl Into<String>) -> RecordingError {
        self.error_at(self.line, reason)
    }

    /// Said of a row error on a last line that has no line end.
    fn cut_short_note(&self) -> &'static str {
        if self.pos >= self.text.len() && !self.text.ends_with('\n') {
            " (the file ends in the middle of this row)"
        } else {
            ""
        }
    }

    fn run(mut self) -> Result<Recording, RecordingError> {
        self.format_line()?;
        self.metadata_and_header()?;
        let torn = self.cut_torn_row();
        self.rows()?;
        if torn && let Some((_, at)) = self.trailer {
            return Err(self.error_at(
                self.line + 1,
                format!(
                    "a row after the trailer on line {at}; the trailer must come last \
                     (the file ends in the middle of this row)"
                ),
            ));
        }
        self.recording.torn_last_row = torn;
        if let Some((count, at)) = self.trailer {
            let read = self.recording.len();
            if count != read {
                return Err(self.error_at(
                    at,
                    format!("the trailer says {count} samples, but {read} rows were read"),
                ));
            }
            self.recording.trailer_samples = Some(count);
        }
        Ok(self.recording)
    }

    /// A last line with no line end that is not a comment is a row whose
    /// write was cut short (the writer hands the OS whole rows, so only an
    /// interrupted write leaves one): leave it out. True when one was.
    fn cut_torn_row(&mut self) -> bool {
        if self.text.ends_with('\n') {
            return false;
        }
        let start = self.text.rfind('\n').map_or(0, |i| i + 1);
        let last = self.text[start..].trim();
        if start < self.pos || last.is_empty() || last.starts_with('#') {
            return false;
        }
        self.text = &self.text[..start];
        true
    }

    fn format_line(&mut self) -> Result<(), RecordingError> {
        let first = self.next_line().unwrap_or_default();
        self.line = 1;
        let first = first.strip_prefix('\u{feff}').unwrap_or(first).trim_end();
        if first == FORMAT_LINE {
            return Ok(());
        }
        Err(self.error(match first.strip_prefix(FORMAT_PREFIX) {
            Some(version) => format!(
                "unsupported recording format v{} (this build reads v1)",
                version.chars().take(QUOTE_CHARS).collect::<String>()
            ),
            None if self.text.is_empty() => "not a hapticlab recording (the file is empty)".into(),
            None => format!("not a hapticlab recording (the first line must be \"{FORMAT_LINE}\")"),
        }))
    }

    /// The metadata up to the header, then the header.
    fn metadata_and_header(&mut self) -> Result<(), RecordingError> {
        let header = loop {
            let Some(line) = self.next_line() else {
                return Err(
                    self.error("no header: the file ends before the line of column names (t_s,…)")
                );
            };
            let line = line.trim();
            if line.starts_with('#') {
                self.comment(line)?;
            } else if !line.is_empty() {
                break line;
            }
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        if names.first().and_then(|n| parse_value(n)).is_some() {
            return Err(self.error(
                "missing header: found a row of values where the column names (t_s,…) should be",
            ));
        }
        check_columns(&names).map_err(|reason| self.error(reason))?;
        self.recording.columns = names.iter().map(|n| n.to_string()).collect();
        Ok(())
    }

    fn rows(&mut self) -> Result<(), RecordingError> {
        let columns = self.recording.columns.len();
        let bytes = self.text.as_bytes();
        let rest = bytes.get(self.pos..).unwrap_or_default();
        // A row takes at least two bytes a value, which bounds the
        // reservation whatever the input.
        let rows = (count_newlines(rest) + 1).min(rest.len() / (2 * columns) + 1);
        self.recording.data = (0..columns).map(|_| Vec::with_capacity(rows)).collect();
        let mut row = vec![0.0; columns];
        while let Some(&first_byte) = bytes.get(self.pos) {
            if first_byte != b'#'
                && self.trailer.is_none()
                && let Some(end) = parse_row_fast(bytes, self.pos, &mut row)
            {
                self.pos = end;
                self.line += 1;
            } else {
                let Some(line) = self.next_line() else { break };
                let trimmed = line.trim();
                if trimmed.starts_with('#') {
                    self.comment(trimmed)?;
                    continue;
                } else if trimmed.is_empty() {
                    continue;
                } else if let Some((_, at)) = self.trailer {
                    return Err(self.error(format!(
                        "a row after the trailer on line {at}; the trailer must come last"
                    )));
                }
                self.row_carefully(line, &mut row)?;
            }
            self.check_time(row[0])?;
            for (column, &value) in self.recording.data.iter_mut().zip(&row) {
                column.push(value);
            }
        }
        if let (Some(&first), Some(&last)) = (
            self.recording.data[0].first(),
            self.recording.data[0].last(),
        ) && self.recording.len() > 1
            && last <= first
        {
            return Err(self.error_at(
                self.last_row_line,
                format!(
                    "t_s never increases: all {} samples are at {last} s",
                    self.recording.len()
                ),
            ));
        }
        Ok(())
    }

    /// The time of the row just read (on `self.line`): a finite number of
    /// seconds, never less than the row before's. Equal neighbours pass:
    /// `t_s` is written to the microsecond, and two ticks of a loop catching
    /// up can fall in one.
    fn check_time(&mut self, t: f64) -> Result<(), RecordingError> {
        if !t.is_finite() {
            return Err(self.error(format!(
                "t_s is {t}: the time must be a finite number of seconds"
            )));
        }
        if let Some(&before) = self.recording.data[0].last()
            && t < before
        {
            return Err(self.error(format!(
                "t_s goes back from {before} s (line {}) to {t} s: the time must never decrease",
                self.last_row_line
            )));
        }
        self.last_row_line = self.line;
        Ok(())
    }

    /// A row the fast path turned down: parse it or say exactly what is wrong.
    fn row_carefully(&self, line: &str, row: &mut [f64]) -> Result<(), RecordingError> {
        let names = &self.recording.columns;
        let count = line.split(',').count();
        if count != names.len() {
            return Err(self.error(format!(
                "row has {count} values, the header has {}{}",
                names.len(),
                self.cut_short_note()
            )));
        }
        for ((slot, field), name) in row.iter_mut().zip(line.split(',')).zip(names) {
            let field = field.trim();
            *slot = parse_value(field).ok_or_else(|| {
                let what = if field.is_empty() {
                    "is empty".to_string()
                } else {
                    format!("is not a number: {}", quote(field))
                };
                self.error(format!(
                    "the value of {name} {what}{}",
                    self.cut_short_note()
                ))
            })?;
        }
        Ok(())
    }

    /// A `#` line: the trailer, metadata, or a comment to pass over.
    fn comment(&mut self, line: &str) -> Result<(), RecordingError> {
        match classify_comment(line) {
            Comment::Trailer(text) => {
                if self.recording.columns.is_empty() {
                    return Err(
                        self.error("the trailer `# end samples = N` comes before the header")
                    );
                }
                if let Some((_, at)) = self.trailer {
                    return Err(self.error(format!("a second trailer (the first is on line {at})")));
                }
                let count = text
                    .strip_prefix('=')
                    .and_then(|n| n.trim().parse::<usize>().ok())
                    .ok_or_else(|| {
                        self.error(format!(
                            "malformed trailer {}: expected `# end samples = N`",
                            quote(line)
                        ))
                    })?;
                self.trailer = Some((count, self.line));
            }
            Comment::Meta(key, body) => self.meta(key, body)?,
            Comment::Other => {}
        }
        Ok(())
    }

    fn meta(&mut self, key: &str, body: &str) -> Result<(), RecordingError> {
        if let Some(first) = self.meta_lines.get(key) {
            return Err(self.error(format!(
                "metadata `{key}` is given twice (first on line {first})"
            )));
        }
        let mut table: toml::Table = toml::from_str(body).map_err(|e| {
            self.error(format!(
                "metadata `{key}`: the value is not valid TOML ({})",
                e.message()
            ))
        })?;
        let value = table.remove(key).ok_or_else(|| {
            self.error(format!("metadata `{key}`: the line holds no value for it"))
        })?;
        if key == "label" {
            let label = value.as_str().ok_or_else(|| {
                self.error("metadata `label`: must be a string (the texture's name)")
            })?;
            check_label(label)
                .map_err(|reason| self.error(format!("metadata `label`: {reason}")))?;
        }
        self.meta_lines.insert(key.to_string(), self.line);
        self.recording.meta.push((key.to_string(), value));
        Ok(())
    }
}

/// All recordings under `paths`: files as given, folders walked recursively
/// for `*.csv` and `*.csv.gz` (hidden entries skipped), sorted by path.
pub fn collect_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, RecordingError> {
    let mut found = Vec::new();
    let mut visited = Vec::new();
    for path in paths {
        let metadata = fs::metadata(path).map_err(|source| RecordingError::Io {
            path: path.clone(),
            source,
        })?;
        if metadata.is_dir() {
            walk(path, &mut found, &mut visited)?;
        } else {
            found.push(path.clone());
        }
    }
    found.sort();
    found.dedup();
    Ok(found)
}

fn is_recording_name(name: &str) -> bool {
    let name = name.to_ascii_lowercase();
    name.ends_with(".csv") || name.ends_with(".csv.gz")
}

fn walk(
    dir: &Path,
    found: &mut Vec<PathBuf>,
    visited: &mut Vec<PathBuf>,
) -> Result<(), RecordingError> {
    let io_error = |source| RecordingError::Io {
        path: dir.to_path_buf(),
        source,
    };
    // Symlinked folders are followed once each, so a cycle ends.
    let canonical = fs::canonicalize(dir).map_err(io_error)?;
    if visited.contains(&canonical) {
        return Ok(());
    }
    visited.push(canonical);
    for entry in fs::read_dir(dir).map_err(io_error)? {
        let entry = entry.map_err(io_error)?;
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with('.') {
            continue;
        }
        let path = entry.path();
        match fs::metadata(&path) {
            Ok(m) if m.is_dir() => walk(&path, found, visited)?,
            // A broken link named like a recording is kept, so reading it reports it.
            _ if is_recording_name(&name) => found.push(path),
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gzip_stream_that_unpacks_too_far_is_refused() {
        use std::io::Write;
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        gz.write_all(&vec![b'0'; 1 << 20]).unwrap();
        let bytes = gz.finish().unwrap();
        assert!(bytes.len() < 4096, "{} bytes", bytes.len());
        let err = gunzip_at_most(&bytes, "bomb.csv.gz", 100_000).unwrap_err();
        assert!(err.to_string().contains("too large"), "{err}");
        assert_eq!(
            gunzip_at_most(&bytes, "ok.csv.gz", 1 << 20).unwrap().len(),
            1 << 20
        );
    }

    const EXAMPLE: &str = "# hapticlab recording v1\n# label = \"S2\"\n# profile = \"thesis\"\n\
        # rate_hz = 1000.0   # a TOML comment\n# a note, not metadata\n\
        t_s,x_m,y_m,z_m,fx_n,fy_n,fz_n\n\
        0.000000,-0.045000,-0.004800,-0.020000,0.000,-0.310,0.000\n\
        0.001000,-0.044990,-0.004790,-0.020000,1e-3,nan,+0.5\n\
        \n# a comment between rows\n\
        0.002000 , -0.044980,-0.004780,-0.020000,0.000,-0.300,-0.000\n\
        # end samples = 3\n# after = \"the trailer\"\n";

    #[test]
    fn reads_the_example() {
        let r = parse(EXAMPLE.as_bytes(), "example.csv").unwrap();
        assert_eq!(
            r.columns,
            ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"]
        );
        let keys: Vec<&str> = r.meta.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(keys, ["label", "profile", "rate_hz", "after"]);
        assert_eq!(r.label(), Some("S2"));
        assert_eq!(r.meta_f64("rate_hz"), Some(1000.0));
        assert_eq!(
            (r.len(), r.is_complete(), r.path.is_none()),
            (3, true, true)
        );
        assert_eq!(r.column("t_s"), Some(&[0.0, 0.001, 0.002][..]));
        assert_eq!(r.column("fx_n"), Some(&[0.0, 0.001, 0.0][..]));
        assert!(r.column("fy_n").unwrap()[1].is_nan());
        assert_eq!(r.column("fz_n").unwrap()[1], 0.5);
        assert!(r.column("fz_n").unwrap()[2].is_sign_negative());
        assert_eq!(r.column("nope"), None);
    }

    #[test]
    fn crlf_line_ends_and_a_byte_order_mark_are_accepted() {
        let text = format!("\u{feff}{}", EXAMPLE.replace('\n', "\r\n"));
        let crlf = parse(text.as_bytes(), "crlf.csv").unwrap();
        let lf = parse(EXAMPLE.as_bytes(), "example.csv").unwrap();
        // Debug, because the NaN in the example is unequal to itself.
        assert_eq!(format!("{crlf:?}"), format!("{lf:?}"));
    }

    #[test]
    fn messages_say_what_is_wrong() {
        let case = |text: &str| parse(text.as_bytes(), "x.csv").unwrap_err().to_string();
        let head = "# hapticlab recording v1\nt_s,x_m\n";
        assert_eq!(
            case(""),
            "x.csv:1: not a hapticlab recording (the file is empty)"
        );
        assert!(case("# hapticlab recording v1\n# a = 1\n").starts_with("x.csv:2: no header"));
        assert!(
            case("# hapticlab recording v1\n# a = 1\n# a = 2\n")
                .contains("x.csv:3: metadata `a` is given twice (first on line 2)")
        );
        assert!(
            case("# hapticlab recording v1\n# end samples = 0\nt_s,x\n")
                .contains("x.csv:2: the trailer")
        );
        assert!(
            case("# hapticlab recording v1\nt_s\n").contains("x.csv:2: the header names only t_s")
        );
        assert!(case("# hapticlab recording v1\nt_s,,x\n").contains("column 2 has no name"));
        assert_eq!(
            case(&format!(
                "{head}0,1\n# end samples = 1\n# end samples = 1\n"
            )),
            "x.csv:5: a second trailer (the first is on line 4)"
        );
        assert!(
            case(&format!("{head}# end samples = many\n"))
                .contains("x.csv:3: malformed trailer \"# end samples = many\"")
        );
        assert_eq!(
            case(&format!("{head}0,\n")),
            "x.csv:3: the value of x_m is empty"
        );
        let long = "y".repeat(100);
        assert!(case(&format!("{head}0,{long}\n")).ends_with(&format!(
            "is not a number: \"{}\"…",
            "y".repeat(QUOTE_CHARS)
        )));
    }

    #[test]
    fn an_empty_scan_with_its_trailer_is_complete() {
        let r = parse(
            b"# hapticlab recording v1\nt_s,x_m\n# end samples = 0\n",
            "e.csv",
        )
        .unwrap();
        assert!(r.is_complete() && r.is_empty());
        assert_eq!(r.data, vec![Vec::<f64>::new(), Vec::new()]);
    }

    #[test]
    fn comments_are_told_apart() {
        assert!(matches!(
            classify_comment("# end samples = 3"),
            Comment::Trailer("= 3")
        ));
        assert!(matches!(
            classify_comment("#end samples"),
            Comment::Trailer("")
        ));
        assert!(matches!(
            classify_comment("# end_samples = 3"),
            Comment::Meta("end_samples", _)
        ));
        assert!(matches!(classify_comment("# note: x = 3"), Comment::Other));
        assert!(matches!(classify_comment("# = 3"), Comment::Other));
        assert!(matches!(classify_comment("# just words"), Comment::Other));
    }
}
