//! Writing a recording row by row during a scan: the format line, the
//! metadata and the header when created, a row per sample, then the trailer
//! (finished) or an `aborted` line (interrupted). A row costs no allocation;
//! the writer never writes anything the reader would refuse.

use std::fs::{self, File};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::{
    ABORTED_KEY, FORMAT_LINE, RecordingError, TRAILER_KEY, check_columns, is_bare_key, quote,
};

/// The longest value the writer formats, with its comma: `-f64::MAX` has 309
/// digits before the point and at most 17 after ([`time_decimals`]); the
/// shortest text of the smallest subnormal, 326 characters. Reserving this
/// per column means a row never grows the line buffer.
const MAX_VALUE_BYTES: usize = 330;

/// Decimals written for a column: 6 for seconds and metres, 3 for newtons, 6 otherwise.
pub fn decimals_for(column: &str) -> usize {
    if column.ends_with("_n") { 3 } else { 6 }
}

/// How a column's values are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Digits {
    /// A fixed number of decimals: 0 for integer samples (16-bit audio, ADC
    /// counts), which then stay integers.
    Decimals(usize),
    /// The shortest text that reads back as the same f64 (Rust's `{}`):
    /// exact for any value, `-228` for a whole number, never an exponent.
    Shortest,
    /// The shortest text that reads back as the same f32, for samples that
    /// were f32 (float WAV): exact at their precision, half the digits.
    ShortestF32,
}

/// The highest rate whose `t_s` the writer keeps within 0.5 % of a sample
/// period (see [`time_decimals`]); past it, times would be written alike.
pub const MAX_RATE_HZ: f64 = 1e15;

/// The lowest rate an import times samples at: one sample every 1000 s.
/// Slower, `i / rate` runs to hundreds of digits before the point (1e-300
/// Hz) and then overflows (1e-310 Hz); at it, a billion samples still end
/// within 13 digits, and no texture signal is sampled more slowly.
pub const MIN_RATE_HZ: f64 = 1e-3;

/// Decimals for `t_s` at `rate_hz`: a written time is within half a unit
/// of the last decimal of the true one, so `ceil(log10(rate)) + 2` decimals
/// keep it within 0.5 % of a sample period at any rate; never fewer than 6
/// (what a 1 kHz scan has always been written with).
pub fn time_decimals(rate_hz: f64) -> usize {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return 6;
    }
    // Clamped: past 1e15 Hz more decimals only write digits an f64 lacks.
    let needed = rate_hz.log10().ceil().clamp(0.0, 15.0) as usize + 2;
    needed.max(6)
}

/// Writes one scan as it happens, row by row.
#[derive(Debug)]
pub struct RecordingWriter {
    path: PathBuf,
    /// `None` only once finished or aborted.
    out: Option<BufWriter<File>>,
    digits: Vec<Digits>,
    /// The row being formatted, reused so rows cost no allocation.
    line: Vec<u8>,
    rows: usize,
    /// Bytes handed to the buffer so far.
    written: u64,
    /// The file's length and row count at the last successful flush: whole
    /// rows only, where [`RecordingWriter::abort_after_error`] cuts back to.
    good_len: u64,
    good_rows: usize,
    /// fsync when finished or aborted (off for batches synced as a whole).
    sync: bool,
}

impl RecordingWriter {
    /// Creates the file (and parent folders), replacing any file of that
    /// name, writes the format line, the metadata and the header, and flushes.
    pub fn create(
        path: &Path,
        meta: &[(String, toml::Value)],
        columns: &[&str],
    ) -> Result<Self, RecordingError> {
        Self::open(path, meta, columns, false)
    }

    /// Like `create`, but fails if the file already exists, so an earlier
    /// scan is never overwritten.
    pub fn create_new(
        path: &Path,
        meta: &[(String, toml::Value)],
        columns: &[&str],
    ) -> Result<Self, RecordingError> {
        Self::open(path, meta, columns, true)
    }

    /// Like `create`, with how each column's values are written given
    /// (one [`Digits`] per column) instead of taken from its unit.
    pub fn create_with_digits(
        path: &Path,
        meta: &[(String, toml::Value)],
        columns: &[&str],
        digits: &[Digits],
    ) -> Result<Self, RecordingError> {
        if digits.len() != columns.len() {
            return Err(RecordingError::Write {
                path: path.to_path_buf(),
                reason: format!(
                    "{} digit settings for {} columns",
                    digits.len(),
                    columns.len()
                ),
            });
        }
        let mut writer = Self::open(path, meta, columns, false)?;
        writer.digits = digits.to_vec();
        Ok(writer)
    }

    fn open(
        path: &Path,
        meta: &[(String, toml::Value)],
        columns: &[&str],
        new: bool,
    ) -> Result<Self, RecordingError> {
        let misuse = |reason: String| RecordingError::Write {
            path: path.to_path_buf(),
            reason,
        };
        let io_error = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
        {
            return Err(misuse(
                "the writer writes plain text: write a .csv and compress it once finished".into(),
            ));
        }
        check_columns(columns).map_err(misuse)?;
        let mut head = String::with_capacity(256);
        head.push_str(FORMAT_LINE);
        head.push('\n');
        for (i, (key, value)) in meta.iter().enumerate() {
            if !is_bare_key(key) {
                return Err(misuse(format!(
                    "metadata key {} must be letters, digits, _ and -",
                    quote(key)
                )));
            }
            if key == ABORTED_KEY {
                return Err(misuse(format!(
                    "metadata key `{ABORTED_KEY}` is kept for abort()"
                )));
            }
            if meta[..i].iter().any(|(k, _)| k == key) {
                return Err(misuse(format!("metadata key `{key}` is given twice")));
            }
            head.push_str("# ");
            head.push_str(key);
            head.push_str(" = ");
            write_inline_toml(&mut head, value);
            head.push('\n');
        }
        head.push_str(&columns.join(","));
        head.push('\n');

        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            fs::create_dir_all(parent).map_err(|source| RecordingError::Io {
                path: parent.to_path_buf(),
                source,
            })?;
        }
        let file = if new {
            File::create_new(path)
        } else {
            // Replacing a device or FIFO would write into it (or wait on it).
            refuse_special(path).and_then(|()| File::create(path))
        }
        .map_err(io_error)?;
        let mut out = BufWriter::with_capacity(64 * 1024, file);
        if let Err(e) = out.write_all(head.as_bytes()).and_then(|()| out.flush()) {
            // A head cut short (a full disk) is no recording: leave no file
            // the reader would refuse.
            drop(out.into_parts());
            let _ = fs::remove_file(path);
            return Err(io_error(e));
        }
        let head_len = head.len() as u64;
        Ok(Self {
            path: path.to_path_buf(),
            out: Some(out),
            digits: columns
                .iter()
                .map(|c| Digits::Decimals(decimals_for(c)))
                .collect(),
            line: Vec::with_capacity(MAX_VALUE_BYTES * columns.len()),
            rows: 0,
            written: head_len,
            good_len: head_len,
            good_rows: 0,
            sync: true,
        })
    }

    fn io_error(&self, source: io::Error) -> RecordingError {
        RecordingError::Io {
            path: self.path.clone(),
            source,
        }
    }

    fn closed(&self) -> RecordingError {
        RecordingError::Write {
            path: self.path.clone(),
            reason: "the recording is already closed".into(),
        }
    }

    /// Appends one row, a value per column; non-finite values are written as `nan`.
    pub fn write_row(&mut self, row: &[f64]) -> Result<(), RecordingError> {
        if row.len() != self.digits.len() {
            return Err(RecordingError::Write {
                path: self.path.clone(),
                reason: format!(
                    "row has {} values, the header has {}",
                    row.len(),
                    self.digits.len()
                ),
            });
        }
        self.line.clear();
        for (i, (&value, &digits)) in row.iter().zip(&self.digits).enumerate() {
            if i > 0 {
                self.line.push(b',');
            }
            if value.is_finite() {
                // Writing into a Vec cannot fail; float formatting uses the stack.
                let _ = match digits {
                    Digits::Decimals(decimals) => write!(self.line, "{value:.decimals$}"),
                    Digits::Shortest => write!(self.line, "{value}"),
                    // An f32 sample widened to f64 narrows back exactly.
                    Digits::ShortestF32 => write!(self.line, "{}", value as f32),
                };
            } else {
                self.line.extend_from_slice(b"nan");
            }
        }
        self.line.push(b'\n');
        // One write per row: the buffer only ever hands whole rows to the OS.
        let result = match self.out.as_mut() {
            Some(out) => out.write_all(&self.line),
            None => return Err(self.closed()),
        };
        result.map_err(|e| self.io_error(e))?;
        self.rows += 1;
        self.written += self.line.len() as u64;
        Ok(())
    }

    /// Hands buffered rows to the OS, so an interrupted scan leaves them on disk.
    pub fn flush(&mut self) -> Result<(), RecordingError> {
        let result = match self.out.as_mut() {
            Some(out) => out.flush(),
            None => return Err(self.closed()),
        };
        result.map_err(|e| self.io_error(e))?;
        self.good_len = self.written;
        self.good_rows = self.rows;
        Ok(())
    }

    /// After a failed write or flush (a full disk, a file size limit): cut
    /// the file back to the rows that last reached it whole, so no row is
    /// left cut short, and mark it `# aborted = "reason"` if that still fits.
    /// The recording then reads as incomplete. Returns the rows kept, and
    /// the error if even cutting back failed.
    pub fn abort_after_error(mut self, reason: &str) -> (usize, Option<RecordingError>) {
        let Some(out) = self.out.take() else {
            return (self.good_rows, Some(self.closed()));
        };
        // What is still buffered is dropped, not written.
        let (mut file, _) = out.into_parts();
        let mut line = format!("# {ABORTED_KEY} = ");
        write_inline_toml(&mut line, &toml::Value::String(reason.to_string()));
        line.push('\n');
        let cut = file
            .set_len(self.good_len)
            .and_then(|()| file.seek(SeekFrom::Start(self.good_len)).map(|_| ()));
        if let Err(e) = cut {
            return (self.good_rows, Some(self.io_error(e)));
        }
        if file.write_all(line.as_bytes()).is_err() {
            // The reason does not fit either: the rows alone read as incomplete.
            let _ = file.set_len(self.good_len);
        }
        let _ = file.sync_all();
        (self.good_rows, None)
    }

    /// Writes the trailer `# end samples = N`, flushes and syncs; the row count.
    pub fn finish(mut self) -> Result<usize, RecordingError> {
        let trailer = format!("# {TRAILER_KEY} = {}\n", self.rows);
        self.close(&trailer)
    }

    /// Marks the scan incomplete with `# aborted = "reason"` (no trailer),
    /// flushes and syncs; the row count.
    pub fn abort(mut self, reason: &str) -> Result<usize, RecordingError> {
        let mut line = format!("# {ABORTED_KEY} = ");
        write_inline_toml(&mut line, &toml::Value::String(reason.to_string()));
        line.push('\n');
        self.close(&line)
    }

    fn close(&mut self, last_line: &str) -> Result<usize, RecordingError> {
        let Some(mut out) = self.out.take() else {
            return Err(self.closed());
        };
        out.write_all(last_line.as_bytes())
            .and_then(|()| out.flush())
            .and_then(|()| {
                if self.sync {
                    out.get_ref().sync_all()
                } else {
                    Ok(())
                }
            })
            .map_err(|e| self.io_error(e))?;
        Ok(self.rows)
    }

    /// Leave the fsync at the end to the caller, who syncs a whole batch of
    /// recordings at once (see [`sync_folder`]).
    pub fn defer_sync(&mut self) {
        self.sync = false;
    }

    pub fn rows(&self) -> usize {
        self.rows
    }
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for RecordingWriter {
    /// Keeps what was written (without a trailer: the scan reads as incomplete).
    fn drop(&mut self) {
        if let Some(out) = self.out.as_mut() {
            let _ = out.flush();
        }
    }
}

/// Writes a TOML value on one line (toml's own writer may use multi-line strings).
fn write_inline_toml(out: &mut String, value: &toml::Value) {
    use std::fmt::Write as _;
    match value {
        toml::Value::String(s) => write_toml_string(out, s),
        toml::Value::Integer(i) => {
            let _ = write!(out, "{i}");
        }
        toml::Value::Float(f) if f.is_nan() => out.push_str("nan"),
        toml::Value::Float(f) if f.is_infinite() => {
            out.push_str(if *f > 0.0 { "inf" } else { "-inf" })
        }
        // Debug keeps a `.0` or an exponent, which TOML needs to see a float.
        toml::Value::Float(f) => {
            let _ = write!(out, "{f:?}");
        }
        toml::Value::Boolean(b) => {
            let _ = write!(out, "{b}");
        }
        toml::Value::Datetime(d) => {
            let _ = write!(out, "{d}");
        }
        toml::Value::Array(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_inline_toml(out, item);
            }
            out.push(']');
        }
        toml::Value::Table(table) => {
            out.push('{');
            for (i, (key, item)) in table.iter().enumerate() {
                out.push_str(if i > 0 { ", " } else { " " });
                if is_bare_key(key) {
                    out.push_str(key);
                } else {
                    write_toml_string(out, key);
                }
                out.push_str(" = ");
                write_inline_toml(out, item);
            }
            out.push_str(if table.is_empty() { "}" } else { " }" });
        }
    }
}

fn write_toml_string(out: &mut String, s: &str) {
    use std::fmt::Write as _;
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// Text up to this size is gzipped by Zopfli; larger text (an imported
/// audio clip: a 10 s, 44.1 kHz clip is 6.9 MB) by deflate at its best
/// level, ten times faster there for 7 % more bytes.
const ZOPFLI_MAX_BYTES: usize = 4 << 20;

/// Replace a finished recording `X.csv` by `X.csv.gz` (gzip by Zopfli: a
/// fifth smaller than `gzip -9`, slower to write, as fast to read; above
/// [`ZOPFLI_MAX_BYTES`] of text, `gzip -9`), through a temporary file, so
/// neither is ever half-written. The same text always gives the same bytes.
/// For archiving datasets; live scans are written plain, so that an
/// interrupted scan stays readable. Not fsynced: see [`sync_folder`].
pub fn compress(path: &Path) -> Result<PathBuf, RecordingError> {
    compress_by(path, ZOPFLI_MAX_BYTES)
}

/// [`compress`] by deflate at its best level whatever the size (`gzip -9`):
/// for `import`, whose audio clips of a few MB Zopfli would take seconds
/// each (a 5 s 44.1 kHz clip: about 3 s of CPU against 0.2 s).
pub fn compress_quickly(path: &Path) -> Result<PathBuf, RecordingError> {
    compress_by(path, 0)
}

/// An error ([`crate::io::NotRegular`]) when `path` exists and is not a
/// regular file.
fn refuse_special(path: &Path) -> io::Result<()> {
    match fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            crate::io::NotRegular {
                kind: crate::io::kind_of(&m),
            },
        )),
        _ => Ok(()),
    }
}

fn compress_by(path: &Path, zopfli_max: usize) -> Result<PathBuf, RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let bytes = fs::read(path).map_err(io)?;
    let mut gz_name = path.as_os_str().to_os_string();
    gz_name.push(".gz");
    let gz = PathBuf::from(gz_name);
    let mut tmp_name = gz.as_os_str().to_os_string();
    tmp_name.push(".tmp");
    let tmp = PathBuf::from(tmp_name);
    let write = || -> io::Result<()> {
        let mut out = BufWriter::new(File::create(&tmp)?);
        let options = zopfli::Options {
            iteration_count: std::num::NonZeroU64::new(1).expect("non-zero"),
            ..zopfli::Options::default()
        };
        if bytes.len() <= zopfli_max {
            zopfli::compress(options, zopfli::Format::Gzip, &bytes[..], &mut out)?;
        } else {
            // No name and no time in the header: the output is the text's alone.
            let mut gz = flate2::write::GzEncoder::new(&mut out, flate2::Compression::best());
            gz.write_all(&bytes)?;
            gz.finish()?;
        }
        out.flush()?;
        fs::rename(&tmp, &gz)?;
        fs::remove_file(path)
    };
    write().map_err(|source| {
        let _ = fs::remove_file(&tmp);
        RecordingError::Io {
            path: gz.clone(),
            source,
        }
    })?;
    Ok(gz)
}

/// Flush everything written under `dir` to stable storage: one `syncfs` for a
/// whole batch of recordings instead of an fsync per file.
pub fn sync_folder(dir: &Path) -> Result<(), RecordingError> {
    let f = File::open(dir).map_err(|source| RecordingError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: syncfs takes a valid open descriptor, which `f` owns.
        if unsafe { libc::syncfs(f.as_raw_fd()) } != 0 {
            return Err(RecordingError::Io {
                path: dir.to_path_buf(),
                source: std::io::Error::last_os_error(),
            });
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    f.sync_all().map_err(|source| RecordingError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_values_are_written_on_one_line_and_read_back() {
        let mut table = toml::Table::new();
        table.insert("bare".into(), toml::Value::Integer(-3));
        table.insert("not bare".into(), toml::Value::Array(vec![]));
        let values = [
            toml::Value::String("line\nbreak \"q\" \\ \u{7f}\u{1} tab\t é".into()),
            toml::Value::Float(1000.0),
            toml::Value::Float(1e300),
            toml::Value::Float(-2.5e-7),
            toml::Value::Float(f64::INFINITY),
            toml::Value::Integer(i64::MIN),
            toml::Value::Boolean(false),
            toml::Value::Datetime("2026-11-21T22:00:00.5+01:00".parse().unwrap()),
            toml::Value::Table(table),
            toml::Value::Table(toml::Table::new()),
        ];
        for value in values {
            let mut line = "k = ".to_string();
            write_inline_toml(&mut line, &value);
            assert!(!line.contains('\n'), "{line}");
            let back: toml::Table = toml::from_str(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
            assert_eq!(back["k"], value, "{line}");
        }
        let mut line = String::new();
        write_inline_toml(&mut line, &toml::Value::Float(f64::NAN));
        assert_eq!(line, "nan");
    }
}
