//! Firmware: the Falcon keeps its firmware in RAM, so after every power-up
//! the host must upload it. This module owns the image file (checked before
//! any USB traffic), the FTDI line settings of the two modes (loader and
//! normal), the probe ("does a firmware answer?", asked for about a second,
//! as long as libnifalcon waits for fresh firmware to start), and the
//! upload's state machine: handshake at 9600 baud, the receive buffer purged,
//! sync byte at ~140 kbaud, the image in 62-byte chunks each echoed and
//! compared, then normal mode and a probe — the whole load retried as real
//! devices need, the device closed and reopened between attempts as
//! libnifalcon does, each failure naming its step. A failed USB read counts
//! as one that brought no bytes. Every timeout is measured on the
//! transport's clock ([`FalconTransport::now`]).
//!
//! The images are Novint's and not redistributable: the project never ships
//! one; the profile names the file the user's libnifalcon or Novint install
//! provides.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::packet::{self, CommandPacket, PacketReader};
use super::{FalconTransport, TransportError, ftdi};

/// The images known to work, by size.
pub const KNOWN_IMAGES: [(&str, usize); 3] = [
    ("nvent_firmware.bin (recommended)", 8492),
    ("test_firmware.bin", 7324),
    ("novint_T0.bin / novint_T2.bin", 7914),
];
/// Where users find an image.
pub const WHERE_TO_GET: &str = "the Falcon's firmware is Novint's and hapticlab cannot ship it: \
copy nvent_firmware.bin from your libnifalcon source tree (its firmware/ folder) or from your \
Novint Falcon driver install, and point the profile's `[falcon] firmware` at it";

/// Bytes per upload chunk (each echoed back).
pub const CHUNK: usize = 62;
const HANDSHAKE: [u8; 3] = [0x0A, 0x43, 0x0D];
const HANDSHAKE_REPLY: [u8; 4] = [0x0A, 0x44, 0x2C, 0x0D];
const SYNC: u8 = 0x41;
const HANDSHAKE_TRIES: u32 = 100;
const HANDSHAKE_TIMEOUT: Duration = Duration::from_millis(50);
const ECHO_TIMEOUT: Duration = Duration::from_millis(250);
/// The probe sends a packet this often while it waits for an answer.
const PROBE_TIMEOUT: Duration = Duration::from_millis(30);

/// How hard to try (from the profile's `[falcon]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadOptions {
    /// Whole uploads before giving up.
    pub attempts: u32,
    /// How long a probe keeps asking for an answer.
    pub probe_window: Duration,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            attempts: 20,
            probe_window: Duration::from_secs(1),
        }
    }
}

/// A firmware image read from disk and checked.
#[derive(Debug, Clone)]
pub struct FirmwareImage {
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// The firmware file is missing or wrong: bad input, before any USB traffic.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FirmwareFileError {
    #[error("{}: cannot read the Falcon firmware: {reason}; {WHERE_TO_GET}", .path.display())]
    Missing { path: PathBuf, reason: String },
    #[error(
        "{}: {len} bytes is not a Falcon firmware image (known sizes: {}); {WHERE_TO_GET}",
        .path.display(),
        KNOWN_IMAGES.iter().map(|(n, s)| format!("{n} {s} B")).collect::<Vec<_>>().join(", ")
    )]
    WrongSize { path: PathBuf, len: usize },
}

/// Read and check a firmware image.
pub fn load_image(path: &Path) -> Result<FirmwareImage, FirmwareFileError> {
    // Only a regular file (a FIFO named by mistake must not hang the
    // console), and nothing larger than the largest image known is read:
    // the reader refuses a larger one by its size, which is told.
    let most = KNOWN_IMAGES.iter().map(|(_, n)| *n).max().unwrap_or(0);
    let bytes = crate::io::read_input_at_most(path, most as u64).map_err(|e| {
        match e
            .get_ref()
            .and_then(|i| i.downcast_ref::<crate::io::TooLarge>())
        {
            Some(big) => FirmwareFileError::WrongSize {
                path: path.to_path_buf(),
                len: usize::try_from(big.size).unwrap_or(usize::MAX),
            },
            None => FirmwareFileError::Missing {
                path: path.to_path_buf(),
                reason: crate::io::said(&e),
            },
        }
    })?;
    if !KNOWN_IMAGES.iter().any(|(_, n)| *n == bytes.len()) {
        return Err(FirmwareFileError::WrongSize {
            path: path.to_path_buf(),
            len: bytes.len(),
        });
    }
    Ok(FirmwareImage {
        path: path.to_path_buf(),
        bytes,
    })
}

/// The step of one upload attempt that failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UploadStep {
    #[error("setting the FTDI loader mode (9600 baud 8N1, latency 16 ms, DTR/RTS) failed: {0}")]
    Setup(TransportError),
    #[error("the handshake: no 0A 44 2C 0D answer to 0A 43 0D at 9600 baud in {tries} tries")]
    Handshake { tries: u32 },
    #[error("the baud switch: the 0x41 sync byte was not echoed at 140 kbaud (got {got:02X?})")]
    Sync { got: Vec<u8> },
    #[error("chunk {chunk} of {chunks} (bytes {offset}..{end}): {what}")]
    Chunk {
        chunk: usize,
        chunks: usize,
        offset: usize,
        end: usize,
        what: String,
    },
    #[error("after the upload: setting normal mode failed: {0}")]
    NormalMode(TransportError),
    #[error("after the upload: the firmware does not answer packets within {window_ms} ms")]
    NoAnswer { window_ms: u64 },
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FirmwareError {
    #[error(transparent)]
    File(#[from] FirmwareFileError),
    #[error(
        "the Falcon has no firmware loaded and the profile names no firmware file (`[falcon] firmware`); {WHERE_TO_GET}"
    )]
    NoImage,
    #[error(
        "uploading the firmware failed {attempts} times; the last attempt failed at {last}. Plug the Falcon directly into the computer (not a hub), check its power supply, and try again"
    )]
    UploadFailed { attempts: u32, last: UploadStep },
    #[error("the link to the Falcon failed while {during}: {error}")]
    Link {
        during: &'static str,
        error: TransportError,
    },
}

/// How the firmware came to be running.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FirmwareReport {
    pub already_loaded: bool,
    /// Upload attempts made (0 when it was already loaded).
    pub attempts: u32,
    /// Why each failed attempt failed.
    pub failures: Vec<String>,
}

/// Normal mode: latency 1 ms, ~1.5 Mbaud (divisor 2), 8N1, no flow control, purged.
pub fn set_normal_mode<T: FalconTransport + ?Sized>(t: &mut T) -> Result<(), TransportError> {
    t.control(ftdi::LATENCY, 1)?;
    t.control(ftdi::BAUD, ftdi::BAUD_NORMAL)?;
    t.control(ftdi::LINE, ftdi::LINE_8N1)?;
    t.control(ftdi::FLOW, ftdi::FLOW_NONE)?;
    t.control(ftdi::PURGE, ftdi::PURGE_RX)?;
    t.control(ftdi::PURGE, ftdi::PURGE_TX)?;
    Ok(())
}

/// Loader mode: purged, latency 16 ms, 9600 baud 8N1, no flow control, RTS
/// low, DTR low then high (which resets the Falcon into its boot loader).
pub fn set_loader_mode<T: FalconTransport + ?Sized>(t: &mut T) -> Result<(), TransportError> {
    t.control(ftdi::PURGE, ftdi::PURGE_RX)?;
    t.control(ftdi::PURGE, ftdi::PURGE_TX)?;
    t.control(ftdi::LATENCY, 16)?;
    t.control(ftdi::BAUD, ftdi::BAUD_9600)?;
    t.control(ftdi::LINE, ftdi::LINE_8N1)?;
    t.control(ftdi::FLOW, ftdi::FLOW_NONE)?;
    t.control(ftdi::MODEM, ftdi::RTS_LOW)?;
    t.control(ftdi::MODEM, ftdi::DTR_LOW)?;
    t.control(ftdi::MODEM, ftdi::DTR_HIGH)?;
    Ok(())
}

/// One read, a failed one counting as one that brought no bytes.
fn read_some<T: FalconTransport + ?Sized>(
    t: &mut T,
    buf: &mut [u8],
    timeout: Duration,
) -> Result<usize, TransportError> {
    match t.read(buf, timeout) {
        Err(TransportError::Transient(_)) => Ok(0),
        other => other,
    }
}

/// Read until `want` bytes arrived or `timeout` passed; returns what came.
fn read_for<T: FalconTransport + ?Sized>(
    t: &mut T,
    buf: &mut [u8],
    want: usize,
    timeout: Duration,
) -> Result<usize, TransportError> {
    let deadline = t.now() + timeout;
    let mut got = 0;
    while got < want {
        let left = deadline.saturating_duration_since(t.now());
        let n = read_some(t, &mut buf[got..want], left)?;
        if n == 0 {
            break;
        }
        got += n;
    }
    Ok(got)
}

/// Whether a firmware answers: in normal mode, send a zero-force packet
/// every 30 ms and look for a valid reply, for `window` in all.
pub fn probe<T: FalconTransport + ?Sized>(
    t: &mut T,
    window: Duration,
) -> Result<bool, TransportError> {
    set_normal_mode(t)?;
    let mut reader = PacketReader::new();
    let mut buf = [0u8; 64];
    let zero = packet::encode_command(&CommandPacket {
        motor: [0; 3],
        flags: packet::FLAG_HOMING | packet::LED_RED,
    });
    let end = t.now() + window;
    // At least one packet, however short the window.
    let mut first = true;
    while first || t.now() < end {
        first = false;
        t.write(&zero)?;
        let deadline = (t.now() + PROBE_TIMEOUT).min(end);
        loop {
            let left = deadline.saturating_duration_since(t.now());
            if left.is_zero() {
                break;
            }
            let n = read_some(t, &mut buf, left)?;
            if n == 0 {
                break;
            }
            reader.push(&buf[..n]);
            while let Some(p) = reader.next_packet() {
                if packet::decode_reply(&p).is_some() {
                    t.control(ftdi::PURGE, ftdi::PURGE_RX)?;
                    return Ok(true);
                }
            }
        }
    }
    Ok(false)
}

/// One upload attempt, step by step; `probe_window` for the firmware to start.
pub fn upload_once<T: FalconTransport + ?Sized>(
    t: &mut T,
    image: &[u8],
    probe_window: Duration,
) -> Result<(), UploadStep> {
    set_loader_mode(t).map_err(UploadStep::Setup)?;
    let mut buf = [0u8; 64];
    let mut ok = false;
    for _ in 0..HANDSHAKE_TRIES {
        t.write(&HANDSHAKE).map_err(UploadStep::Setup)?;
        let n = read_for(t, &mut buf, 5, HANDSHAKE_TIMEOUT).map_err(UploadStep::Setup)?;
        // Some devices answer with a leading 0x00.
        let answer: &[u8] = match buf[..n].iter().position(|&b| b != 0) {
            Some(i) => &buf[i..n],
            None => &[],
        };
        if answer.starts_with(&HANDSHAKE_REPLY) {
            ok = true;
            break;
        }
    }
    if !ok {
        return Err(UploadStep::Handshake {
            tries: HANDSHAKE_TRIES,
        });
    }
    // Whatever is left over from the handshake or the baud change must not
    // be taken for the sync byte's echo.
    t.control(ftdi::MODEM, ftdi::DTR_LOW)
        .and_then(|()| t.control(ftdi::BAUD, ftdi::BAUD_LOADER))
        .and_then(|()| t.control(ftdi::PURGE, ftdi::PURGE_RX))
        .map_err(UploadStep::Setup)?;
    t.write(&[SYNC]).map_err(UploadStep::Setup)?;
    let n = read_for(t, &mut buf, 1, ECHO_TIMEOUT).map_err(UploadStep::Setup)?;
    if n != 1 || buf[0] != SYNC {
        return Err(UploadStep::Sync {
            got: buf[..n].to_vec(),
        });
    }
    let chunks = image.len().div_ceil(CHUNK);
    for (k, chunk) in image.chunks(CHUNK).enumerate() {
        let offset = k * CHUNK;
        let end = offset + chunk.len();
        let step = |what: String| UploadStep::Chunk {
            chunk: k + 1,
            chunks,
            offset,
            end,
            what,
        };
        t.write(chunk)
            .map_err(|e| step(format!("writing failed: {e}")))?;
        let n = read_for(t, &mut buf, chunk.len(), ECHO_TIMEOUT)
            .map_err(|e| step(format!("reading the echo failed: {e}")))?;
        if n < chunk.len() {
            return Err(step(format!(
                "only {n} of {} bytes were echoed",
                chunk.len()
            )));
        }
        if let Some(i) = (0..n).find(|&i| buf[i] != chunk[i]) {
            return Err(step(format!(
                "the echo differs at byte {} (sent {:02X}, got {:02X})",
                offset + i,
                chunk[i],
                buf[i]
            )));
        }
    }
    set_normal_mode(t).map_err(UploadStep::NormalMode)?;
    match probe(t, probe_window) {
        Ok(true) => Ok(()),
        Ok(false) => Err(UploadStep::NoAnswer {
            window_ms: probe_window.as_millis() as u64,
        }),
        Err(e) => Err(UploadStep::NormalMode(e)),
    }
}

/// Make sure firmware runs: probe, and upload (up to `opts.attempts` times,
/// the device reopened between attempts) when nothing answers. `log` hears
/// each step for the user.
pub fn ensure_loaded<T: FalconTransport + ?Sized>(
    t: &mut T,
    image: Option<&FirmwareImage>,
    opts: &LoadOptions,
    log: &mut dyn FnMut(&str),
) -> Result<FirmwareReport, FirmwareError> {
    let link =
        |during: &'static str| move |error: TransportError| FirmwareError::Link { during, error };
    if probe(t, opts.probe_window).map_err(link("probing for firmware"))? {
        log("firmware already running");
        return Ok(FirmwareReport {
            already_loaded: true,
            ..FirmwareReport::default()
        });
    }
    let image = image.ok_or(FirmwareError::NoImage)?;
    let mut report = FirmwareReport::default();
    let attempts = opts.attempts.max(1);
    for attempt in 1..=attempts {
        report.attempts = attempt;
        if attempt > 1 {
            // A fresh handle, as libnifalcon takes between attempts.
            log("closing and reopening the Falcon");
            t.reopen().map_err(link("reopening the Falcon"))?;
        }
        log(&format!(
            "uploading firmware {} ({} bytes), attempt {attempt} of {attempts}",
            image.path.display(),
            image.bytes.len()
        ));
        match upload_once(t, &image.bytes, opts.probe_window) {
            Ok(()) => {
                log("firmware running");
                return Ok(report);
            }
            Err(step) => {
                // A vanished device will not come back by retrying.
                if let UploadStep::Setup(e @ TransportError::Disconnected(_))
                | UploadStep::NormalMode(e @ TransportError::Disconnected(_)) = &step
                {
                    return Err(FirmwareError::Link {
                        during: "uploading the firmware",
                        error: e.clone(),
                    });
                }
                log(&format!("attempt {attempt} failed at {step}"));
                report.failures.push(step.to_string());
                if attempt == attempts {
                    return Err(FirmwareError::UploadFailed {
                        attempts,
                        last: step,
                    });
                }
            }
        }
    }
    unreachable!("the loop returns on its last attempt")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    #[test]
    fn missing_and_wrong_size_images_say_where_to_get_one() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nvent_firmware.bin");
        let e = load_image(&missing).unwrap_err().to_string();
        assert!(
            e.contains("nvent_firmware.bin") && e.contains("libnifalcon"),
            "{e}"
        );
        std::fs::write(&missing, [0u8; 100]).unwrap();
        let e = load_image(&missing).unwrap_err().to_string();
        assert!(
            e.contains("100 bytes") && e.contains("8492") && e.contains("Novint"),
            "{e}"
        );
        std::fs::write(&missing, vec![7u8; 8492]).unwrap();
        assert_eq!(load_image(&missing).unwrap().bytes.len(), 8492);
        // Larger than any image: its size is told, nothing is read.
        std::fs::write(&missing, vec![7u8; 1 << 20]).unwrap();
        let e = load_image(&missing).unwrap_err().to_string();
        assert!(e.contains("1048576 bytes"), "{e}");
        // Missing in the lab's words; a FIFO is refused, not waited on.
        std::fs::remove_file(&missing).unwrap();
        let e = load_image(&missing).unwrap_err().to_string();
        assert!(e.contains("no such file") && !e.contains("os error"), "{e}");
        let c = std::ffi::CString::new(missing.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = load_image(&missing).unwrap_err().to_string();
        assert!(e.contains("FIFO"), "{e}");
    }

    /// A Falcon whose boot loader never answers (e.g. no wall power):
    /// FTDI requests succeed, bytes vanish.
    struct Silent {
        controls: Vec<(u8, u16)>,
        now: Instant,
        reopens: u32,
    }
    impl FalconTransport for Silent {
        fn kind(&self) -> &'static str {
            "silent"
        }
        fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
            self.controls.push((request, value));
            Ok(())
        }
        fn write(&mut self, _: &[u8]) -> Result<(), TransportError> {
            Ok(())
        }
        fn read(&mut self, _: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
            // Nothing comes; the read waits out its timeout (on this clock).
            self.now += timeout;
            Ok(0)
        }
        fn now(&self) -> Instant {
            self.now
        }
        fn reopen(&mut self) -> Result<(), TransportError> {
            self.reopens += 1;
            Ok(())
        }
    }

    #[test]
    fn a_silent_boot_loader_fails_at_the_handshake_after_every_attempt() {
        let start = Instant::now();
        let mut t = Silent {
            controls: vec![],
            now: start,
            reopens: 0,
        };
        let image = FirmwareImage {
            path: "nvent_firmware.bin".into(),
            bytes: vec![0; 8492],
        };
        let mut log = Vec::new();
        let opts = LoadOptions {
            attempts: 2,
            ..LoadOptions::default()
        };
        let e = ensure_loaded(&mut t, Some(&image), &opts, &mut |m| {
            log.push(m.to_string())
        })
        .unwrap_err();
        assert_eq!(
            e,
            FirmwareError::UploadFailed {
                attempts: 2,
                last: UploadStep::Handshake { tries: 100 }
            }
        );
        let msg = e.to_string();
        assert!(msg.contains("0A 43 0D") && msg.contains("hub"), "{msg}");
        assert_eq!(
            log.iter()
                .filter(|m| m.contains("failed at the handshake"))
                .count(),
            2
        );
        // The probe asked for a second before the first upload; the device
        // was reopened before the second.
        assert!(t.now - start >= Duration::from_secs(1));
        assert_eq!(t.reopens, 1);
        assert!(log.iter().any(|m| m.contains("reopening")), "{log:?}");
        // Loader mode as the facts give it: 16 ms latency, 9600 baud, RTS low, DTR low then high.
        let loader: Vec<(u8, u16)> = t
            .controls
            .iter()
            .copied()
            .skip_while(|c| *c != (ftdi::LATENCY, 16))
            .take(6)
            .collect();
        assert_eq!(
            loader,
            vec![
                (ftdi::LATENCY, 16),
                (ftdi::BAUD, ftdi::BAUD_9600),
                (ftdi::LINE, ftdi::LINE_8N1),
                (ftdi::FLOW, ftdi::FLOW_NONE),
                (ftdi::MODEM, ftdi::RTS_LOW),
                (ftdi::MODEM, ftdi::DTR_LOW),
            ]
        );
    }
}
