//! Reading inputs and placing outputs without losing or hanging on anything.
//!
//! - Inputs are read only from regular files (a symlink to one is fine):
//!   [`open_input`] opens without blocking (`O_NONBLOCK`, so a FIFO cannot
//!   hold the process) and checks what it opened, not what the name
//!   pointed at a moment earlier.
//! - An output ([`check_output`]) is never one of the command's own inputs
//!   (same device and inode), never an existing recording (first line
//!   [`FORMAT_LINE`], plain or gzipped) and never anything but a regular
//!   file (a device, FIFO, socket or folder). `--overwrite`/`--force`
//!   extend to neither: they only let a command replace a file of its own
//!   kind (`import --force` and `simulate --overwrite` replace recordings
//!   with the recordings they write, by [`check_output_kind`]).
//!
//! Ground layer: knows the recording's first line and nothing above it;
//! never prints.

use std::fs::{File, Metadata};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use super::FORMAT_LINE;

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
    #[error("{}: cannot write: {source}", out.display())]
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

/// Writes `out` through a temporary file beside it, synced then renamed
/// over it, after [`check_output`]: never a half-written file, never a
/// lost input or recording.
pub fn write_output(
    out: &Path,
    inputs: &[PathBuf],
    write: impl FnOnce(&mut io::BufWriter<File>) -> io::Result<()>,
) -> Result<(), OutputError> {
    check_output(out, inputs)?;
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
    tmp.persist(out).map_err(|e| io_error(e.error))?;
    Ok(())
}

/// Checks that writing `out` loses nothing: it does not exist, or it is a
/// regular file that is neither one of `inputs` (compared by device and
/// inode, so another spelling of the same file is caught) nor a recording.
/// Inputs that cannot be read are passed over: the command reports them.
pub fn check_output(out: &Path, inputs: &[PathBuf]) -> Result<(), OutputError> {
    let Some(m) = check_output_kind(out)? else {
        return Ok(());
    };
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
    Ok(())
}

/// True when `path` is a regular file whose first line is the recording
/// format line, as text or gzip-compressed.
pub fn is_recording(path: &Path) -> bool {
    let Ok(file) = open_input(path) else {
        return false;
    };
    let mut head = Vec::with_capacity(64);
    let mut magic = [0u8; 2];
    let mut reader = io::BufReader::new(file);
    let gzipped = {
        use std::io::BufRead;
        let buf = reader.fill_buf().unwrap_or(&[]);
        let n = buf.len().min(2);
        magic[..n].copy_from_slice(&buf[..n]);
        magic == [0x1f, 0x8b]
    };
    let want = FORMAT_LINE.len() as u64;
    let read = if gzipped {
        flate2::read::MultiGzDecoder::new(reader)
            .take(want)
            .read_to_end(&mut head)
    } else {
        reader.take(want).read_to_end(&mut head)
    };
    read.is_ok() && head == FORMAT_LINE.as_bytes()
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
        let e = check_output(&fifo, &[]).unwrap_err();
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
            check_output(&gz, &[]),
            Err(OutputError::IsRecording { .. })
        ));
        // Another spelling of an input is that input.
        let again = dir.path().join(".").join("table.csv");
        assert!(matches!(
            check_output(&again, std::slice::from_ref(&other)),
            Err(OutputError::IsInput { .. })
        ));
        assert!(check_output(&other, &[]).is_ok());
        assert!(check_output(&dir.path().join("new.csv"), &[other]).is_ok());
        assert!(matches!(
            check_output(Path::new("/dev/null"), &[]),
            Err(OutputError::NotRegular { kind: "device", .. })
        ));
        assert!(matches!(
            check_output(dir.path(), &[]),
            Err(OutputError::NotRegular { kind: "folder", .. })
        ));
    }
}
