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
use std::io;
use std::path::{Path, PathBuf};

/// The first line of every recording in this format (kept by [`crate::io`],
/// which tells a recording from any other file).
pub use crate::io::FORMAT_LINE;
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
mod reader;
mod writer;
pub use label::check_label;
use reader::{Select, gunzip, parse_text};
pub use writer::{
    Digits, MAX_RATE_HZ, MIN_RATE_HZ, RecordingWriter, compress, compress_quickly, decimals_for,
    sync_folder, time_decimals,
};

#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be read, created or written.
    #[error("{}: {}", path.display(), crate::io::said(source))]
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
    /// True when the file is no hapticlab recording at all (its first line
    /// is not the format line, is empty, or is no text: a WAV, an .npz):
    /// another rig's file, for `hapticlab import`.
    pub fn is_not_a_recording(&self) -> bool {
        matches!(self, Self::Malformed { line: 1, reason, .. }
            if reason.starts_with("not a hapticlab recording") || reason.starts_with("invalid UTF-8"))
    }

    /// True when the recording itself is at fault (exit code 2), or a path
    /// that does not exist was named (an argument's fault: exit code 2 as
    /// for every other command); false for another I/O failure or a misuse
    /// of the writer (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        match self {
            Self::Malformed { .. } | Self::Compressed { .. } => true,
            Self::Io { source, .. } => {
                source.kind() == io::ErrorKind::NotFound || crate::io::not_regular(source)
            }
            _ => false,
        }
    }
}

/// One scan, as read from a recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recording {
    pub path: Option<PathBuf>,
    /// `# key = value` lines, in file order (including `aborted` after the rows).
    pub meta: Vec<(String, toml::Value)>,
    /// Every column the header names.
    pub columns: Vec<String>,
    /// Column-major: `data[c][row]`. A column left unread by
    /// [`read_columns`] is empty.
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
    /// The samples of a column, or `None` when the header lacks it (or
    /// [`read_columns`] was not asked for it).
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let c = self.columns.iter().position(|n| n == name)?;
        self.data
            .get(c)
            .filter(|d| d.len() == self.len())
            .map(Vec::as_slice)
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
    read_selected(path, Select::All)
}

/// Reads a recording as [`read`] does, but converts and keeps only `t_s` and
/// the columns named in `wanted`: the others are checked row by row (a file
/// is refused exactly when [`read`] refuses it) and left empty. For a
/// caller that needs a few channels of many, this is most of the reading
/// saved.
pub fn read_columns(path: &Path, wanted: &[&str]) -> Result<Recording, RecordingError> {
    read_selected(path, Select::Only(wanted))
}

fn read_selected(path: &Path, select: Select<'_>) -> Result<Recording, RecordingError> {
    let bytes = crate::io::read_input(path).map_err(|source| RecordingError::Io {
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
    let mut recording = parse_selected(&bytes, &origin, select)?;
    recording.path = Some(path.to_path_buf());
    Ok(recording)
}

/// Parses a recording held in memory (gzip-compressed or not); `origin` names
/// it in error messages.
pub fn parse(bytes: &[u8], origin: &str) -> Result<Recording, RecordingError> {
    parse_selected(bytes, origin, Select::All)
}

/// Parses a recording held in memory as [`read_columns`] reads a file.
pub fn parse_columns(
    bytes: &[u8],
    origin: &str,
    wanted: &[&str],
) -> Result<Recording, RecordingError> {
    parse_selected(bytes, origin, Select::Only(wanted))
}

fn parse_selected(
    bytes: &[u8],
    origin: &str,
    select: Select<'_>,
) -> Result<Recording, RecordingError> {
    if bytes.starts_with(&GZIP_MAGIC) {
        let text = gunzip(bytes, origin)?;
        return parse_text(&text, origin, select);
    }
    parse_text(bytes, origin, select)
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
pub fn check_columns(names: &[&str]) -> Result<(), String> {
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
        } else if metadata.is_file() {
            found.push(path.clone());
        } else {
            // Named on the command line: refused, never read (a FIFO would block).
            return Err(RecordingError::Io {
                path: path.clone(),
                source: io::Error::new(
                    io::ErrorKind::InvalidInput,
                    crate::io::NotRegular {
                        kind: crate::io::kind_of(&metadata),
                    },
                ),
            });
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
    use super::reader::{Comment, classify_comment, gunzip_at_most};
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
    fn reading_some_columns_keeps_those_and_refuses_what_a_full_read_refuses() {
        let some = parse_columns(EXAMPLE.as_bytes(), "example.csv", &["y_m", "nope"]).unwrap();
        let all = parse(EXAMPLE.as_bytes(), "example.csv").unwrap();
        assert_eq!(some.columns, all.columns);
        assert_eq!((some.len(), some.is_complete()), (3, true));
        assert_eq!(some.column("t_s"), all.column("t_s"));
        assert_eq!(some.column("y_m"), all.column("y_m"));
        assert_eq!(some.column("x_m"), None);
        assert!(some.data[1].is_empty());
        let head = "# hapticlab recording v1\nt_s,x_m,y_m\n";
        for rows in [
            "0,1,2\n0.001,abc,2\n",
            "0,1,2\n0.001,,2\n",
            "0,1\n",
            "0,1,2\n0,1,2\n",
        ] {
            let text = format!("{head}{rows}# end samples = 2\n");
            let full = parse(text.as_bytes(), "x.csv").map_err(|e| e.to_string());
            let part = parse_columns(text.as_bytes(), "x.csv", &["y_m"]).map_err(|e| e.to_string());
            assert_eq!(part.clone().err(), full.clone().err(), "{rows:?}");
            assert!(part.is_err() || full.is_ok());
        }
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
