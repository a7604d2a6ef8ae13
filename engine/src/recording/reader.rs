//! Reading format v1: the text (or its gzip stream) to a [`Recording`], with
//! errors that name the file, the line and why. Never panics on any input.
//!
//! Rows go through a fast path for plain decimals (what the writer writes)
//! and fall back, line by line, to a careful path that reads any number
//! `str::parse` reads and says exactly what is wrong. A caller that needs
//! only some columns names them: the others are still checked on every row
//! (a file is refused exactly when reading every column would refuse it) but
//! not converted or kept, which is most of the work saved.

use std::collections::HashMap;

use super::number::{parse_row_fast, parse_value};
use super::{
    FORMAT_LINE, FORMAT_PREFIX, QUOTE_CHARS, Recording, RecordingError, TRAILER_KEY, check_columns,
    check_label, is_bare_key, quote,
};

/// A gzipped recording unpacks to at most [`crate::io::inflate_limit`] of
/// its size: a hundred times it (a real recording, CSV of decimals,
/// compresses three to five times, a gzip bomb a thousand), at least 64 MiB
/// and at most 1 GiB.
pub(super) fn gunzip(bytes: &[u8], origin: &str) -> Result<Vec<u8>, RecordingError> {
    gunzip_at_most(bytes, origin, crate::io::inflate_limit(bytes.len() as u64))
}

pub(super) fn gunzip_at_most(
    bytes: &[u8],
    origin: &str,
    limit: u64,
) -> Result<Vec<u8>, RecordingError> {
    use crate::io::{InflateError, Packing, inflate_at_most};
    inflate_at_most(bytes, Packing::Gzip, limit).map_err(|e| RecordingError::Compressed {
        origin: origin.to_string(),
        reason: match e {
            InflateError::Truncated { got } => {
                format!("truncated gzip stream (it ends after {got} bytes of text)")
            }
            InflateError::Corrupt(e) => format!("corrupt gzip stream ({e})"),
            InflateError::TooLarge { limit, compressed } => format!(
                "it unpacks to more than {limit} bytes ({compressed} compressed): too large for a recording (a gzip bomb?)"
            ),
        },
    })
}

/// Which columns a reader converts and keeps: every one, or `t_s` and
/// those named (names the header lacks are passed over; the caller reports
/// a missing column as it would for a full read).
#[derive(Debug, Clone, Copy)]
pub(super) enum Select<'w> {
    All,
    Only(&'w [&'w str]),
}

pub(super) fn parse_text(
    bytes: &[u8],
    origin: &str,
    select: Select<'_>,
) -> Result<Recording, RecordingError> {
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
    Parser::new(text, origin, select).run()
}

fn count_newlines(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count()
}

/// What a `#` line holds.
pub(super) enum Comment<'a> {
    /// `# end samples = …`, with the text after the key.
    Trailer(&'a str),
    /// `# key = value`, with the key and the whole `key = value` text.
    Meta(&'a str, &'a str),
    Other,
}

pub(super) fn classify_comment(line: &str) -> Comment<'_> {
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

struct Parser<'a> {
    origin: &'a str,
    select: Select<'a>,
    /// Per column: converted and kept (`t_s` always is).
    read: Vec<bool>,
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
    fn new(text: &'a str, origin: &'a str, select: Select<'a>) -> Self {
        Self {
            origin,
            select,
            read: Vec::new(),
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
        if first.starts_with(FORMAT_LINE) && first.contains('\r') {
            // Classic Mac OS line ends: the whole file reads as one line.
            return Err(self.error(
                "its lines end in a carriage return alone (CR, old Mac OS style): \
                 convert the line ends to LF or CRLF",
            ));
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
        self.read = names
            .iter()
            .enumerate()
            .map(|(c, name)| match self.select {
                Select::All => true,
                Select::Only(wanted) => c == 0 || wanted.contains(name),
            })
            .collect();
        self.recording.columns = names.iter().map(|n| n.to_string()).collect();
        Ok(())
    }

    fn rows(&mut self) -> Result<(), RecordingError> {
        let columns = self.recording.columns.len();
        let bytes = self.text.as_bytes();
        let rows = rows_expected(bytes.get(self.pos..).unwrap_or_default(), columns);
        let read = std::mem::take(&mut self.read);
        self.recording.data = read
            .iter()
            .map(|&r| Vec::with_capacity(if r { rows } else { 0 }))
            .collect();
        let kept: Vec<usize> = (0..columns).filter(|&c| read[c]).collect();
        let mut row = vec![0.0; columns];
        while let Some(&first_byte) = bytes.get(self.pos) {
            if first_byte != b'#'
                && self.trailer.is_none()
                && let Some(end) = parse_row_fast(bytes, self.pos, &mut row, &read)
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
            for &c in &kept {
                self.recording.data[c].push(row[c]);
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

/// The rows to reserve room for, from the text after the header: the
/// trailer's count when the text ends with it (the usual case, exact), else
/// an estimate from the first row's length. Either way at most what the text
/// could hold (two bytes a value), whatever it claims.
fn rows_expected(rest: &[u8], columns: usize) -> usize {
    let most = rest.len() / (2 * columns) + 1;
    let trailer = trailer_count(rest);
    let estimate = trailer.unwrap_or_else(|| {
        let first = rest
            .iter()
            .position(|&b| b == b'\n')
            .map_or(rest.len(), |i| i + 1);
        // Rows differ in length by a few digits; an eighth more covers it.
        let rows = rest.len() / first.max(1) + 1;
        rows + rows / 8
    });
    estimate.min(most)
}

/// `N` from a last line `# end samples = N` (line ends and blank lines
/// after it allowed), without reading the rest.
fn trailer_count(rest: &[u8]) -> Option<usize> {
    let text = rest.trim_ascii_end();
    let start = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let (key, count) = std::str::from_utf8(&text[start..]).ok()?.split_once('=')?;
    let key = key.trim().strip_prefix('#')?.trim();
    (key == TRAILER_KEY).then(|| count.trim().parse().ok())?
}
