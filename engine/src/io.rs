//! The one door for files: every file hapticlab reads and every output it
//! writes goes through here, so the guarantees hold everywhere and are
//! tested once.
//!
//! Reading ([`open_input`], [`read_input`], [`read_input_at_most`],
//! [`inflate_at_most`]):
//! - only regular files are read (a symlink to one is fine): opened without
//!   blocking (`O_NONBLOCK`, so a FIFO cannot hold the process), and what was
//!   opened is checked, not what the name pointed at a moment earlier;
//! - a size a caller expects is checked before anything is allocated, and
//!   decompression is streamed with a cap: a bomb is refused, not inflated.
//!
//! Writing ([`write_output`], [`check_output`]):
//! - an output is written to a temporary file beside it, synced, then put in
//!   place in one atomic step: never a half-written file;
//! - without `--overwrite` ([`Existing::Keep`]) that step is a no-replace
//!   link, so of two runs writing one name at once the second refuses,
//!   naming the file, and nothing is replaced;
//! - with it ([`Existing::Replace`]) the name is replaced, never written
//!   through (a symlink there is replaced, not what it points at);
//! - an output is never one of the command's own inputs (same device and
//!   inode), never a recording (first line [`FORMAT_LINE`], plain or
//!   gzipped) and never anything but a regular file (a device, FIFO, socket
//!   or folder). `--overwrite` extends to none of these: only `import
//!   --force` and `simulate --overwrite` replace recordings, with the ones
//!   they write, and `import` replaces only its own ([`check_output_kind`]);
//! - [`FolderLock`]: one writer at a time in a folder (imports), the second
//!   waits and is told which file it waits on.
//!
//! Ground layer: knows the recording's first line and nothing above it;
//! never prints.

use std::fs::{File, Metadata};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// The first line of every recording (format v1): what tells a recording
/// from any other file.
pub const FORMAT_LINE: &str = "# hapticlab recording v1";

/// A path that is not a regular file, as an [`io::Error`] payload (so each
/// caller keeps its own error type); [`not_regular`] finds it again.
#[derive(Debug, thiserror::Error)]
#[error("not a regular file (a {kind}): only regular files are read")]
pub struct NotRegular {
    pub kind: &'static str,
}

/// What kind of thing `m` describes, for messages.
pub fn kind_of(m: &Metadata) -> &'static str {
    let t = m.file_type();
    if t.is_file() {
        "regular file"
    } else if t.is_dir() {
        "folder"
    } else if t.is_fifo() {
        "FIFO"
    } else if t.is_socket() {
        "socket"
    } else if t.is_char_device() || t.is_block_device() {
        "device"
    } else {
        "special file"
    }
}

/// `e` in a lab's words for a message after a path: "no such file or
/// folder" for a path that does not exist, "permission denied" for one
/// that may not be read, otherwise the system's text without its
/// "(os error N)".
pub fn said(e: &io::Error) -> String {
    match e.kind() {
        io::ErrorKind::NotFound => "no such file or folder".into(),
        io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => {
            let text = e.to_string();
            match text.rsplit_once(" (os error ") {
                Some((said, _)) => said.to_string(),
                None => text,
            }
        }
    }
}

/// True when `e` is [`open_input`]'s refusal of a file that is not regular.
pub fn not_regular(e: &io::Error) -> bool {
    e.get_ref().is_some_and(|inner| inner.is::<NotRegular>())
}

/// Opens `path` for reading if it is a regular file (after symlinks); any
/// other kind is refused with [`NotRegular`] and never waited on.
pub fn open_input(path: &Path) -> io::Result<File> {
    // Non-blocking: opening a FIFO with no writer returns at once; the
    // flag does nothing to a regular file's reads.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    let m = file.metadata()?;
    if !m.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            NotRegular { kind: kind_of(&m) },
        ));
    }
    Ok(file)
}

/// The bytes of a regular file ([`open_input`]).
pub fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    let mut file = open_input(path)?;
    let mut bytes = Vec::with_capacity(file.metadata().map_or(0, |m| m.len() as usize));
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The text of a regular file ([`open_input`]).
pub fn read_input_to_string(path: &Path) -> io::Result<String> {
    String::from_utf8(read_input(path)?).map_err(|_| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// The bytes of a regular file ([`open_input`]) of at most `limit` bytes:
/// a larger one is refused before it is read ([`TooLarge`] as the payload).
pub fn read_input_at_most(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = open_input(path)?;
    let len = file.metadata()?.len();
    if len > limit {
        return Err(too_large(len, limit));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // Read at most one byte past the limit: a file growing meanwhile is refused too.
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// A file or a stream larger than hapticlab reads, as an [`io::Error`]
/// payload.
#[derive(Debug, thiserror::Error)]
#[error("{size} bytes, more than the {limit} bytes read at most")]
pub struct TooLarge {
    pub size: u64,
    pub limit: u64,
}

fn too_large(size: u64, limit: u64) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, TooLarge { size, limit })
}

/// How compressed bytes are framed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Packing {
    /// gzip members, one after another (`.gz`).
    Gzip,
    /// A zlib stream (MATLAB's compressed variables).
    Zlib,
    /// Raw deflate (zip members: `.npz`).
    Deflate,
}

/// Why compressed bytes could not be inflated.
#[derive(Debug, thiserror::Error)]
pub enum InflateError {
    #[error(
        "it unpacks to more than {limit} bytes ({compressed} compressed): refused as a decompression bomb"
    )]
    TooLarge { limit: u64, compressed: u64 },
    #[error("the compressed data is cut short (it ends after {got} bytes unpacked)")]
    Truncated { got: u64 },
    #[error("the compressed data is corrupt ({0})")]
    Corrupt(io::Error),
}

/// The limit on what `compressed` bytes may unpack to: a hundred times
/// their size (real signals compress two to five times, a bomb a thousand),
/// at least 64 MiB and at most 1 GiB.
pub fn inflate_limit(compressed: u64) -> u64 {
    compressed.saturating_mul(100).clamp(64 << 20, 1 << 30)
}

/// `compressed` inflated, streamed and stopped past `limit` bytes (a bomb
/// is refused having unpacked at most `limit + 1` bytes; nothing a file
/// declares about its size is trusted for the allocation).
pub fn inflate_at_most(
    compressed: &[u8],
    packing: Packing,
    limit: u64,
) -> Result<Vec<u8>, InflateError> {
    let cap = (compressed.len() as u64).saturating_mul(4).min(limit) as usize;
    let mut out = Vec::with_capacity(cap);
    let bounded = limit.saturating_add(1);
    let read = match packing {
        Packing::Gzip => flate2::read::MultiGzDecoder::new(compressed)
            .take(bounded)
            .read_to_end(&mut out),
        Packing::Zlib => flate2::read::ZlibDecoder::new(compressed)
            .take(bounded)
            .read_to_end(&mut out),
        Packing::Deflate => flate2::read::DeflateDecoder::new(compressed)
            .take(bounded)
            .read_to_end(&mut out),
    };
    match read {
        Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => Err(InflateError::Truncated {
            got: out.len() as u64,
        }),
        Err(e) => Err(InflateError::Corrupt(e)),
        Ok(_) if out.len() as u64 > limit => Err(InflateError::TooLarge {
            limit,
            compressed: compressed.len() as u64,
        }),
        Ok(_) => Ok(out),
    }
}

/// Moves `from` to `to` unless `to` exists, in one atomic step: a hard
/// link (which fails with `AlreadyExists` when the name is taken, even by
/// another process a moment earlier), then the old name removed. Both
/// must be on one file system.
pub fn move_no_replace(from: &Path, to: &Path) -> io::Result<()> {
    std::fs::hard_link(from, to)?;
    std::fs::remove_file(from)
}

/// Why an output was not written: refused (each names the file and what
/// to do; bad input) or an I/O failure.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error(
        "{}: this is one of the command's own inputs ({}); nothing was written: give another output file",
        out.display(), input.display()
    )]
    IsInput { out: PathBuf, input: PathBuf },
    #[error(
        "{}: this is a recording; nothing was written (a profile, model, table or figure never replaces a recording, --overwrite included; only import --force and simulate --overwrite replace recordings, with the ones they write): give another output file",
        out.display()
    )]
    IsRecording { out: PathBuf },
    #[error(
        "{}: exists and is not a regular file (a {kind}); nothing was written: give the path of a regular file",
        out.display()
    )]
    NotRegular { out: PathBuf, kind: &'static str },
    #[error(
        "{}: already exists; nothing was written: give another output file, or --overwrite to replace it",
        out.display()
    )]
    Exists { out: PathBuf },
    #[error("{}: cannot write: {}", out.display(), said(source))]
    Io { out: PathBuf, source: io::Error },
}

impl OutputError {
    /// A refusal is the user's to fix (exit code 2); an I/O failure is not.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, OutputError::Io { .. })
    }
}

/// Checks that `out` is absent or a regular file, whatever it holds: for
/// commands that write recordings and may replace one when told to.
/// Returns its metadata when it exists.
pub fn check_output_kind(out: &Path) -> Result<Option<Metadata>, OutputError> {
    match std::fs::metadata(out) {
        Ok(m) if m.is_file() => Ok(Some(m)),
        Ok(m) => Err(OutputError::NotRegular {
            out: out.to_path_buf(),
            kind: kind_of(&m),
        }),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(OutputError::Io {
            out: out.to_path_buf(),
            source,
        }),
    }
}

/// The first of `inputs` that is the same file as `out` (device and inode).
pub fn same_file_as<'a>(out: &Metadata, inputs: &'a [PathBuf]) -> Option<&'a PathBuf> {
    inputs
        .iter()
        .find(|p| std::fs::metadata(p).is_ok_and(|i| i.dev() == out.dev() && i.ino() == out.ino()))
}

/// What an output does when its name is taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Existing {
    /// Refuse, naming the file: the default of every command. Checked before
    /// any work and again when the output is put in place, in one atomic
    /// step, so a file that appears meanwhile (another run) is not replaced.
    Keep,
    /// Replace it (`--overwrite`), but never an input, a recording or a
    /// file that is not regular.
    Replace,
}

impl Existing {
    /// [`Existing::Replace`] when `overwrite`, else [`Existing::Keep`].
    pub fn replace_if(overwrite: bool) -> Existing {
        if overwrite {
            Existing::Replace
        } else {
            Existing::Keep
        }
    }
}

/// Writes `out` through a temporary file beside it, synced then put in
/// place after [`check_output`]: never a half-written file, never a lost
/// input or recording, and under [`Existing::Keep`] never a file that is
/// there (the temporary file is linked to `out`, which fails when the name
/// is taken, even by another process a moment earlier).
pub fn write_output(
    out: &Path,
    inputs: &[PathBuf],
    existing: Existing,
    write: impl FnOnce(&mut io::BufWriter<File>) -> io::Result<()>,
) -> Result<(), OutputError> {
    check_output(out, inputs, existing)?;
    let io_error = |source| OutputError::Io {
        out: out.to_path_buf(),
        source,
    };
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(io_error)?;
    let tmp = tempfile::Builder::new()
        .prefix(".hapticlab-")
        .suffix(".tmp")
        // As `File::create` would: the umask decides, not tempfile's 0600.
        .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666))
        .tempfile_in(dir)
        .map_err(io_error)?;
    let mut w = io::BufWriter::new(tmp.reopen().map_err(io_error)?);
    write(&mut w).map_err(io_error)?;
    let file = w.into_inner().map_err(|e| io_error(e.into_error()))?;
    file.sync_all().map_err(io_error)?;
    match existing {
        Existing::Keep => match tmp.persist_noclobber(out) {
            Ok(_) => Ok(()),
            Err(e) if e.error.kind() == io::ErrorKind::AlreadyExists => Err(OutputError::Exists {
                out: out.to_path_buf(),
            }),
            Err(e) => Err(io_error(e.error)),
        },
        Existing::Replace => {
            // Checked again: what is there now is what gets replaced.
            check_output(out, inputs, existing)?;
            tmp.persist(out).map(|_| ()).map_err(|e| io_error(e.error))
        }
    }
}

/// Checks that writing `out` loses nothing: it does not exist, or (under
/// [`Existing::Replace`] only) it is a regular file that is neither one of
/// `inputs` (compared by device and inode, so another spelling of the same
/// file is caught) nor a recording. A name taken by a symlink, even one
/// that leads nowhere, is taken. Inputs that cannot be read are passed
/// over: the command reports them.
pub fn check_output(out: &Path, inputs: &[PathBuf], existing: Existing) -> Result<(), OutputError> {
    match std::fs::symlink_metadata(out) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(OutputError::Io {
                out: out.to_path_buf(),
                source,
            });
        }
        Ok(_) => {}
    }
    // What is there, after links: the most telling refusal first.
    if let Some(m) = check_output_kind(out)? {
        if let Some(input) = same_file_as(&m, inputs) {
            return Err(OutputError::IsInput {
                out: out.to_path_buf(),
                input: input.clone(),
            });
        }
        if is_recording(out) {
            return Err(OutputError::IsRecording {
                out: out.to_path_buf(),
            });
        }
    }
    match existing {
        Existing::Keep => Err(OutputError::Exists {
            out: out.to_path_buf(),
        }),
        Existing::Replace => Ok(()),
    }
}

/// True when `path` is a regular file whose first line is the recording
/// format line, as text or gzip-compressed.
pub fn is_recording(path: &Path) -> bool {
    read_head(path, FORMAT_LINE.len() as u64).is_some_and(|head| head == FORMAT_LINE.as_bytes())
}

/// The first `max` bytes of a regular file's text ([`open_input`]), plain
/// or gzip-compressed (unpacked, never past `max`); `None` when it cannot
/// be opened or read.
pub fn read_head(path: &Path, max: u64) -> Option<Vec<u8>> {
    use std::io::BufRead;
    let file = open_input(path).ok()?;
    let mut reader = io::BufReader::new(file);
    let gzipped = reader.fill_buf().ok()?.starts_with(&[0x1f, 0x8b]);
    let mut head = Vec::new();
    if gzipped {
        flate2::read::MultiGzDecoder::new(reader)
            .take(max)
            .read_to_end(&mut head)
            .ok()?;
    } else {
        reader.take(max).read_to_end(&mut head).ok()?;
    }
    Some(head)
}

/// One writer at a time in a folder: an exclusive lock (`flock`) on a
/// hidden file in it, held until dropped (or the process ends, however it
/// ends: the system lets go of it). Every run that writes the folder's
/// files takes it first, so their checks, clean-ups and placing cannot
/// interleave. The lock file is removed when the lock is let go, so a
/// folder is left as it was; a taker checks, once it holds the lock, that
/// the name still leads to the file it locked (else it locked a file just
/// removed, and takes the new one).
#[derive(Debug)]
pub struct FolderLock {
    file: File,
    path: PathBuf,
}

impl FolderLock {
    /// Takes the lock on `dir/name` (the folder is made if missing), calling
    /// `waiting` with the lock file's path once if another process holds
    /// it, then waiting for it. The lock file is never a symlink or anything
    /// but a regular file.
    pub fn acquire(dir: &Path, name: &str, waiting: impl FnOnce(&Path)) -> io::Result<FolderLock> {
        use std::os::fd::AsRawFd;
        std::fs::create_dir_all(dir)?;
        let path = dir.join(name);
        let mut waiting = Some(waiting);
        loop {
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
                .open(&path)?;
            let m = file.metadata()?;
            if !m.is_file() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    NotRegular { kind: kind_of(&m) },
                ));
            }
            let fd = file.as_raw_fd();
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(fd, libc::LOCK_EX | libc::LOCK_NB) } != 0 {
                let e = io::Error::last_os_error();
                if e.raw_os_error() != Some(libc::EWOULDBLOCK) {
                    return Err(e);
                }
                if let Some(w) = waiting.take() {
                    w(&path);
                }
                // SAFETY: as above; blocks until the holder lets go.
                while unsafe { libc::flock(fd, libc::LOCK_EX) } != 0 {
                    let e = io::Error::last_os_error();
                    if e.kind() != io::ErrorKind::Interrupted {
                        return Err(e);
                    }
                }
            }
            // Still the file at that name? (The holder removes it on release.)
            let here = std::fs::symlink_metadata(&path);
            if here.is_ok_and(|h| h.dev() == m.dev() && h.ino() == m.ino()) {
                return Ok(FolderLock { file, path });
            }
        }
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while held, so a waiter on this file sees it gone and
        // takes a new one; then the descriptor closes and the lock goes.
        let _ = std::fs::remove_file(&self.path);
        let _ = &self.file;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("a.csv");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = open_input(&fifo).unwrap_err();
        assert!(not_regular(&e), "{e}");
        assert!(e.to_string().contains("FIFO"), "{e}");
        let e = check_output(&fifo, &[], Existing::Replace).unwrap_err();
        assert!(
            matches!(e, OutputError::NotRegular { kind: "FIFO", .. }),
            "{e}"
        );
    }

    #[test]
    fn recordings_are_known_plain_or_gzipped_and_inputs_by_inode() {
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("r.csv");
        std::fs::write(&plain, format!("{FORMAT_LINE}\nt_s,z_m\n")).unwrap();
        let gz = dir.path().join("r.csv.gz");
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(format!("{FORMAT_LINE}\n# label = \"A\"\n").as_bytes())
            .unwrap();
        std::fs::write(&gz, e.finish().unwrap()).unwrap();
        let other = dir.path().join("table.csv");
        std::fs::write(&other, "file,label\n").unwrap();
        assert!(is_recording(&plain) && is_recording(&gz) && !is_recording(&other));
        assert!(matches!(
            check_output(&gz, &[], Existing::Replace),
            Err(OutputError::IsRecording { .. })
        ));
        // Another spelling of an input is that input.
        let again = dir.path().join(".").join("table.csv");
        assert!(matches!(
            check_output(&again, std::slice::from_ref(&other), Existing::Replace),
            Err(OutputError::IsInput { .. })
        ));
        assert!(check_output(&other, &[], Existing::Replace).is_ok());
        assert!(check_output(&dir.path().join("new.csv"), &[other], Existing::Keep).is_ok());
        assert!(matches!(
            check_output(Path::new("/dev/null"), &[], Existing::Replace),
            Err(OutputError::NotRegular { kind: "device", .. })
        ));
        assert!(matches!(
            check_output(dir.path(), &[], Existing::Replace),
            Err(OutputError::NotRegular { kind: "folder", .. })
        ));
    }
}
