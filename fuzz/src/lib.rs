//! The fuzz targets' entry points: each takes the raw bytes of one input,
//! hands them to hapticlab's public API the way the command line does, and
//! returns `Ok` or the library's message. A panic, or a broken invariant
//! (checked with `assert!`), is a finding.
//!
//! Shared with `tests/engine/fuzz_regressions.rs`, which feeds the kept crashers
//! and the seeds to these same functions on the stable toolchain.

use std::io::Write;
use std::path::Path;

use clap::Parser;
use hapticlab::commands::import::ImportArgs;
use hapticlab::device::falcon::packet::{
    self, PACKET_LEN, PacketReader, decode_command, decode_reply, encode_command, encode_reply,
};
use hapticlab::device::falcon::usb::strip_modem_status;
use hapticlab::import::{self, ImportError, Imported, Request};
use hapticlab::profile::{self, LoadedProfile};
use hapticlab::recording::{self, Recording};

/// What an entry point reports: `Err` holds the library's message.
pub type Outcome = Result<(), String>;

/// A recording, plain or gzip-compressed, as `recording::read` parses a
/// file's bytes. A plain input is also gzipped and parsed again: the result
/// must be the same.
pub fn recording(data: &[u8]) -> Outcome {
    const ORIGIN: &str = "fuzz.csv";
    let plain = recording::parse(data, ORIGIN);
    check_recording(&plain);
    if !data.starts_with(&[0x1f, 0x8b]) {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        gz.write_all(data).expect("writing to memory");
        let gz = gz.finish().expect("writing to memory");
        let unzipped = recording::parse(&gz, ORIGIN);
        check_recording(&unzipped);
        // Debug, because a NaN sample is unequal to itself.
        assert_eq!(
            format!("{:?}", plain.as_ref().map_err(ToString::to_string)),
            format!("{:?}", unzipped.as_ref().map_err(ToString::to_string)),
            "the gzipped input reads differently"
        );
    }
    plain.map(drop).map_err(|e| e.to_string())
}

fn check_recording(r: &Result<Recording, recording::RecordingError>) {
    match r {
        Ok(r) => {
            assert!(r.columns.len() >= 2, "{:?}", r.columns);
            assert_eq!(r.columns[0], "t_s");
            assert_eq!(r.data.len(), r.columns.len());
            assert!(r.data.iter().all(|c| c.len() == r.len()));
            if let Some(n) = r.trailer_samples {
                assert_eq!(n, r.len(), "a trailer that disagrees with the rows");
            }
        }
        Err(e) => {
            assert!(e.is_bad_input(), "not a bad-input error: {e}");
            assert!(e.to_string().starts_with("fuzz.csv"), "{e}");
        }
    }
}

/// A profile's text, as `LoadedProfile::load` reads a file (which must be
/// UTF-8); a profile that loads must keep the promises `validate` makes.
pub fn profile(data: &[u8]) -> Outcome {
    let text = std::str::from_utf8(data).map_err(|e| e.to_string())?;
    match LoadedProfile::from_str(text, "fuzz.toml", Path::new(".")) {
        Ok(loaded) => {
            let p = &loaded.profile;
            let an = &p.analysis;
            let n = an.points();
            assert!((4..=1 << 20).contains(&n), "{n} points");
            assert!(an.dft_points() <= n && an.dft_points() >= 2);
            let [first, last] = an.kept_bins();
            assert!(first <= last && last <= an.dft_points() / 2);
            assert!(an.feature_count() >= 1);
            assert!(an.bin_width().is_finite() && an.bin_width() > 0.0);
            if let Ok(rig) = p.rig() {
                assert!(rig.scan_leg_length_m().is_finite());
            }
            assert!(p.console.bindings().is_ok());
            for t in &p.textures {
                assert!(profile::check_label(&t.label).is_ok());
            }
            Ok(())
        }
        Err(e) => {
            let message = e.to_string();
            assert!(message.starts_with("fuzz.toml"), "{message}");
            Err(message)
        }
    }
}

/// Bytes from the Falcon's USB link: the first byte picks the USB packet
/// size, the rest arrive as bulk transfers of two USB packets each, as
/// `UsbTransport::read` strips their modem-status bytes and the driver
/// feeds a `PacketReader` and decodes what it finds. Every 16-byte piece
/// is also decoded on its own, both ways.
pub fn falcon_packet(data: &[u8]) -> Outcome {
    let Some((&size, stream)) = data.split_first() else {
        return Err("empty input".into());
    };
    for piece in stream.chunks_exact(PACKET_LEN) {
        let p: &[u8; PACKET_LEN] = piece.try_into().expect("16 bytes");
        if let Some(r) = decode_reply(p) {
            let mut again = encode_reply(&r);
            again[14] = p[14]; // the unused byte
            assert_eq!(&again, p, "a reply does not re-encode to its bytes");
        }
        if let Some(c) = decode_command(p) {
            let mut again = encode_command(&c);
            again[14] = p[14];
            assert_eq!(&again, p, "a command does not re-encode to its bytes");
        }
    }
    let max_packet = usize::from(size % 128);
    let mut reader = PacketReader::new();
    let (mut pushed, mut packets, mut replies) = (0u64, 0u64, 0u64);
    for transfer in stream.chunks((2 * max_packet).max(1)) {
        strip_modem_status(transfer, max_packet, |payload| {
            reader.push(payload);
            pushed += payload.len() as u64;
        });
        while let Some(p) = reader.next_packet() {
            assert!(p[0] == packet::START && p[PACKET_LEN - 1] == packet::END);
            packets += 1;
            replies += u64::from(decode_reply(&p).is_some());
        }
        assert!(reader.buffered() <= PacketReader::CAPACITY);
    }
    assert_eq!(
        packets, replies,
        "the reader passed a packet that does not decode"
    );
    // Every byte is a packet's, thrown away (and counted), or still buffered.
    assert_eq!(
        pushed,
        packets * PACKET_LEN as u64 + reader.stats.discarded_bytes + reader.buffered() as u64,
        "{:?}",
        reader.stats
    );
    if packets == 0 {
        return Err("no packet".into());
    }
    Ok(())
}

/// `hapticlab import` as the command line parses it.
#[derive(Debug, Parser)]
#[command(name = "import")]
struct ImportCli {
    #[command(flatten)]
    args: ImportArgs,
}

/// A CSV import: the first line holds the mapping as `hapticlab import`'s
/// options (e.g. `--time-column t --channels fx,fz --label-column texture`),
/// the rest is the file. The options are checked and the file parsed as
/// `import::run` does for a `.csv`.
pub fn import_csv(data: &[u8]) -> Outcome {
    let (options, file) = match data.iter().position(|&b| b == b'\n') {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let options = std::str::from_utf8(options).map_err(|e| e.to_string())?;
    let argv = ["import", "--out", "out", "fuzz.csv"]
        .into_iter()
        .chain(options.split_whitespace());
    let cli = ImportCli::try_parse_from(argv).map_err(|e| e.to_string())?;
    imported(&Request::from(cli.args), file.to_vec(), "csv")
}

/// Headerless text (or, when its first line is no numbers, CSV) at
/// `--rate 1000`, as `import::run` does for a `.txt`.
pub fn import_text(data: &[u8]) -> Outcome {
    imported(&at_a_rate("txt"), data.to_vec(), "txt")
}

/// NumPy: the first byte picks the kind (even: `.npy`, odd: `.npz`), the
/// rest is the file, imported at `--rate 1000`.
pub fn import_numpy(data: &[u8]) -> Outcome {
    let Some((&kind, file)) = data.split_first() else {
        return Err("empty".into());
    };
    let ext = if kind % 2 == 0 { "npy" } else { "npz" };
    imported(&at_a_rate(ext), file.to_vec(), ext)
}

/// A MATLAB `.mat` file imported at `--rate 1000`.
pub fn import_mat(data: &[u8]) -> Outcome {
    imported(&at_a_rate("mat"), data.to_vec(), "mat")
}

fn at_a_rate(ext: &str) -> Request {
    Request {
        files: vec![format!("fuzz.{ext}").into()],
        out: "out".into(),
        rate: Some(1000.0),
        label: Some("fuzz".into()),
        ..Request::default()
    }
}

/// A WAV import of the file's bytes, as `import::run` does for a `.wav`.
pub fn import_wav(data: &[u8]) -> Outcome {
    let args = Request {
        files: vec!["fuzz.wav".into()],
        out: "out".into(),
        ..Request::default()
    };
    imported(&args, data.to_vec(), "wav")
}

fn imported(args: &Request, bytes: Vec<u8>, ext: &str) -> Outcome {
    let origin = format!("fuzz.{ext}");
    let result = import::check_options(args).and_then(|_| {
        let imp = import::parse_file(bytes, &origin, ext, args)?;
        if let (None, Some(label)) = (&args.label, &imp.label) {
            profile::check_label(label).map_err(ImportError::BadInput)?;
        }
        Ok(imp)
    });
    match result {
        Ok(imp) => {
            check_imported(&imp);
            Ok(())
        }
        Err(e) => {
            // A bad file is bad input (exit 2), never a runtime failure.
            assert!(e.is_bad_input(), "{e}");
            Err(e.to_string())
        }
    }
}

fn check_imported(imp: &Imported) {
    let n = imp.time.len();
    assert!(n > 0, "an import without samples");
    assert!(!imp.channels.is_empty());
    assert_eq!(imp.names.len(), imp.channels.len());
    for (name, ch) in imp.names.iter().zip(&imp.channels) {
        assert_eq!(
            ch.len(),
            n,
            "channel {name}: {} samples, {n} times",
            ch.len()
        );
        assert!(
            ch.iter().all(|v| v.is_finite()),
            "channel {name}: not finite"
        );
    }
    assert!(
        imp.time.iter().all(|t| t.is_finite()),
        "a time is not finite"
    );
}
