//! The recording reader over broken files, round trips through the writer,
//! and property tests that no input makes the reader panic.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use hapticlab::recording::{self, FORMAT_LINE, Recording, RecordingError, RecordingWriter};
use proptest::prelude::*;

use crate::common::mutation::{mutate, mutation};

const COLUMNS: [&str; 7] = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"];

fn broken(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/broken")
        .join(name)
}

fn standard_meta() -> Vec<(String, toml::Value)> {
    vec![
        ("label".into(), toml::Value::String("S2".into())),
        ("profile".into(), toml::Value::String("thesis".into())),
        ("device".into(), toml::Value::String("sim".into())),
        ("rate_hz".into(), toml::Value::Float(1000.0)),
        ("seed".into(), toml::Value::Integer(42)),
        (
            "note".into(),
            toml::Value::String("a \"quoted\"\nsecond line\t\\ é".into()),
        ),
        (
            "gains".into(),
            toml::Value::Array(vec![toml::Value::Float(250.5), toml::Value::Integer(3)]),
        ),
        ("simulated".into(), toml::Value::Boolean(true)),
        (
            "started_at".into(),
            toml::Value::Datetime("2026-11-21T22:00:00Z".parse().unwrap()),
        ),
    ]
}

fn sample_row(i: usize) -> [f64; 7] {
    let t = i as f64 / 1000.0;
    [
        t,
        -0.045 + 0.01 * t,
        -0.0048 + 0.0002 * (40.0 * t).sin(),
        -0.02,
        0.05 * (3.0 * t).cos(),
        -0.31 - 0.01 * (40.0 * t).cos(),
        0.0,
    ]
}

fn write_sample(path: &Path, rows: usize) -> usize {
    let mut writer = RecordingWriter::create(path, &standard_meta(), &COLUMNS).unwrap();
    for i in 0..rows {
        writer.write_row(&sample_row(i)).unwrap();
    }
    writer.finish().unwrap()
}

fn assert_matches_sample(recording: &Recording, rows: usize) {
    assert_eq!(recording.columns, COLUMNS);
    assert_eq!(recording.meta, standard_meta());
    assert_eq!(recording.len(), rows);
    assert!(recording.is_complete());
    assert_eq!(recording.trailer_samples, Some(rows));
    assert_eq!(recording.label(), Some("S2"));
    for i in 0..rows {
        for (c, (name, &expected)) in COLUMNS.iter().zip(&sample_row(i)).enumerate() {
            let tolerance = if name.ends_with("_n") { 5e-4 } else { 5e-7 };
            let got = recording.data[c][i];
            assert!(
                (got - expected).abs() <= tolerance,
                "{name}[{i}]: {got} vs {expected}"
            );
        }
    }
}

/// The message for a broken file, checked to name the file and the line.
fn error_for(name: &str, line: Option<usize>) -> String {
    let path = broken(name);
    let err = recording::read(&path).expect_err(name);
    assert!(err.is_bad_input(), "{name}: {err}");
    let message = err.to_string();
    let prefix = match line {
        Some(line) => format!("{}:{line}: ", path.display()),
        None => format!("{}: ", path.display()),
    };
    assert!(
        message.starts_with(&prefix),
        "{name}: {message:?} should start with {prefix:?}"
    );
    message
}

#[test]
fn broken_files_name_the_file_the_line_and_why() {
    let cases: &[(&str, Option<usize>, &str)] = &[
        (
            "wrong_column_count.csv",
            Some(12),
            "row has 6 values, the header has 7",
        ),
        (
            "non_numeric.csv",
            Some(14),
            "the value of fy_n is not a number: \"-0.3l0\"",
        ),
        (
            "trailer_mismatch.csv",
            Some(20),
            "the trailer says 13 samples, but 12 rows were read",
        ),
        (
            "not_a_recording.csv",
            Some(1),
            "not a hapticlab recording (the first line must be \"# hapticlab recording v1\")",
        ),
        (
            "wrong_version.csv",
            Some(1),
            "unsupported recording format v2",
        ),
        (
            "cr_line_ends.csv",
            Some(1),
            "its lines end in a carriage return alone",
        ),
        (
            "bad_metadata.csv",
            Some(4),
            "metadata `device`: the value is not valid TOML",
        ),
        ("missing_header.csv", Some(7), "missing header"),
        (
            "time_not_first.csv",
            Some(7),
            "the first column must be t_s",
        ),
        (
            "duplicate_column.csv",
            Some(7),
            "column fy_n appears twice (columns 6 and 7)",
        ),
        (
            "row_after_trailer.csv",
            Some(20),
            "a row after the trailer on line 19",
        ),
        (
            "invalid_utf8.csv",
            Some(11),
            "invalid UTF-8 (byte 0xff at column 20)",
        ),
        ("truncated.csv.gz", None, "truncated gzip stream"),
        (
            "time_nan.csv",
            Some(13),
            "t_s is NaN: the time must be a finite number of seconds",
        ),
        (
            "time_goes_back.csv",
            Some(15),
            "t_s goes back from 0.006 s (line 14) to 0.004 s",
        ),
        (
            "time_never_increases.csv",
            Some(19),
            "t_s never increases: all 12 samples are at 0 s",
        ),
        (
            "label_empty.csv",
            Some(2),
            "metadata `label`: label \"\" must have 1 to 64 characters",
        ),
        (
            "label_newline.csv",
            Some(2),
            "metadata `label`: label \"S2\\nS3\" must not hold a control character",
        ),
        (
            "label_path.csv",
            Some(2),
            "metadata `label`: label \"../../etc\" must not start with '.'",
        ),
    ];
    for (name, line, why) in cases {
        let message = error_for(name, *line);
        assert!(
            message.contains(why),
            "{name}: {message:?} should say {why:?}"
        );
    }
}

#[test]
fn a_recording_without_trailer_reads_but_is_incomplete() {
    let recording = recording::read(&broken("missing_trailer.csv")).unwrap();
    assert_eq!(recording.len(), 12);
    assert!(!recording.is_complete());
    assert_eq!(recording.trailer_samples, None);
    assert_eq!(recording.label(), Some("S2"));
    assert_eq!(recording.meta_f64("rate_hz"), Some(1000.0));
    assert_eq!(
        recording.path.as_deref(),
        Some(broken("missing_trailer.csv").as_path())
    );
}

/// A file that does not exist was named wrongly: an I/O error naming it,
/// counted as bad input (exit code 2, as for any argument), and so is a
/// folder read as a file (not a regular file).
#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let path = broken("no_such_file.csv");
    let err = recording::read(&path).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }));
    assert!(err.is_bad_input());
    assert!(err.to_string().starts_with(&path.display().to_string()));
    // A folder named as a recording is not a regular file: refused as bad
    // input too (only regular files are read, so nothing can block).
    let dir = tempfile::tempdir().unwrap();
    let err = recording::read(dir.path()).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }), "{err}");
    assert!(err.is_bad_input(), "{err}");
    assert!(err.to_string().contains("not a regular file"), "{err}");
}

#[test]
fn round_trip_through_the_writer() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("recordings/S2/001.csv");
    assert_eq!(write_sample(&path, 2500), 2500);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with(&format!("{FORMAT_LINE}\n# label = \"S2\"\n")));
    assert!(text.contains("\nt_s,x_m,y_m,z_m,fx_n,fy_n,fz_n\n0.000000,-0.045000,-0.004800,-0.020000,0.050,-0.320,0.000\n"));
    assert!(text.ends_with("\n# end samples = 2500\n"));
    assert_matches_sample(&recording::read(&path).unwrap(), 2500);
}

#[test]
fn gzip_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("001.csv");
    write_sample(&plain, 1200);
    let text = std::fs::read(&plain).unwrap();
    let gz = dir.path().join("001.csv.gz");
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(&text).unwrap();
    std::fs::write(&gz, encoder.finish().unwrap()).unwrap();
    let recording = recording::read(&gz).unwrap();
    assert_matches_sample(&recording, 1200);
    assert_eq!(
        recording,
        Recording {
            path: Some(gz.clone()),
            ..recording::read(&plain).unwrap()
        }
    );
    // Gzip is recognised by its magic bytes whatever the name.
    let renamed = dir.path().join("002.csv");
    std::fs::rename(&gz, &renamed).unwrap();
    assert_matches_sample(&recording::read(&renamed).unwrap(), 1200);
}

#[test]
fn non_finite_values_are_written_as_nan_and_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.csv");
    let mut writer = RecordingWriter::create(&path, &[], &["t_s", "pac"]).unwrap();
    writer.write_row(&[0.0, f64::NAN]).unwrap();
    writer.write_row(&[0.001, f64::INFINITY]).unwrap();
    writer.write_row(&[0.002, -1.5]).unwrap();
    writer.finish().unwrap();
    assert!(
        std::fs::read_to_string(&path)
            .unwrap()
            .contains("0.001000,nan\n")
    );
    let pac = recording::read(&path)
        .unwrap()
        .column("pac")
        .unwrap()
        .to_vec();
    assert!(pac[0].is_nan() && pac[1].is_nan());
    assert_eq!(pac[2], -1.5);
}

#[test]
fn flushed_dropped_and_aborted_scans_read_as_incomplete() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a/b/scan.csv");
    let mut writer = RecordingWriter::create(&path, &standard_meta(), &COLUMNS).unwrap();
    // The header is on disk as soon as the writer exists.
    assert_eq!(recording::read(&path).unwrap().len(), 0);
    for i in 0..10 {
        writer.write_row(&sample_row(i)).unwrap();
    }
    writer.flush().unwrap();
    let partial = recording::read(&path).unwrap();
    assert_eq!((partial.len(), partial.is_complete()), (10, false));
    assert_eq!(writer.rows(), 10);
    assert_eq!(writer.path(), path);
    writer.write_row(&sample_row(10)).unwrap();
    drop(writer);
    let dropped = recording::read(&path).unwrap();
    assert_eq!((dropped.len(), dropped.is_complete()), (11, false));

    let mut writer = RecordingWriter::create(&path, &standard_meta(), &COLUMNS).unwrap();
    for i in 0..5 {
        writer.write_row(&sample_row(i)).unwrap();
    }
    assert_eq!(writer.abort("probe left the \"surface\"").unwrap(), 5);
    let aborted = recording::read(&path).unwrap();
    assert_eq!((aborted.len(), aborted.is_complete()), (5, false));
    assert_eq!(aborted.aborted(), Some("probe left the \"surface\""));
}

#[test]
fn the_writer_refuses_what_the_format_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.csv");
    let refuse = |meta: &[(String, toml::Value)], columns: &[&str], why: &str| {
        let err = RecordingWriter::create(&path, meta, columns).unwrap_err();
        assert!(err.to_string().contains(why), "{err} should say {why:?}");
    };
    refuse(&[], &["x_m", "t_s"], "the first column must be t_s");
    refuse(&[], &["t_s"], "at least one channel");
    refuse(&[], &["t_s", "x m"], "must start with a letter");
    refuse(&[], &["t_s", "x_m", "x_m"], "appears twice");
    let one = ("label".to_string(), toml::Value::Integer(1));
    refuse(&[one.clone(), one], &COLUMNS, "given twice");
    refuse(
        &[("end samples".into(), toml::Value::Integer(1))],
        &COLUMNS,
        "metadata key",
    );
    refuse(
        &[("aborted".into(), toml::Value::Boolean(true))],
        &COLUMNS,
        "kept for abort()",
    );
    let err = RecordingWriter::create(&dir.path().join("x.csv.gz"), &[], &COLUMNS).unwrap_err();
    assert!(err.to_string().contains("plain text"));

    let mut writer = RecordingWriter::create(&path, &[], &COLUMNS).unwrap();
    let err = writer.write_row(&[0.0; 6]).unwrap_err();
    assert!(
        err.to_string()
            .ends_with("row has 6 values, the header has 7")
    );
    writer.finish().unwrap();
    let err = RecordingWriter::create_new(&path, &[], &COLUMNS).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }));
}

#[test]
fn collect_files_walks_folders_for_recordings_sorted() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    for name in [
        "S2/002.csv",
        "S2/001.csv.gz",
        "S1/sub/003.csv",
        "S1/notes.txt",
        ".hidden/004.csv",
        "S1/.005.csv",
    ] {
        let path = root.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, "").unwrap();
    }
    let single = root.join("S1/notes.txt");
    let found =
        recording::collect_files(&[root.to_path_buf(), single.clone(), root.join("S2")]).unwrap();
    let expected: Vec<PathBuf> = [
        "S1/notes.txt",
        "S1/sub/003.csv",
        "S2/001.csv.gz",
        "S2/002.csv",
    ]
    .iter()
    .map(|n| root.join(n))
    .collect();
    assert_eq!(found, expected);
    let err = recording::collect_files(&[root.join("nope")]).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }));
}

/// A small valid recording, with a trailer or not.
fn valid_text(rows: usize, trailer: bool) -> Vec<u8> {
    let mut text = format!("{FORMAT_LINE}\n# label = \"S1\"\n# rate_hz = 1000.0\nt_s,y_m,fy_n\n");
    for i in 0..rows {
        let row = sample_row(i);
        text.push_str(&format!("{:.6},{:.6},{:.3}\n", row[0], row[2], row[5]));
    }
    if trailer {
        text.push_str(&format!("# end samples = {rows}\n"));
    }
    text.into_bytes()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// Whatever happens, the reader answers: a recording that holds together, or an error.
fn check_never_panics(bytes: &[u8]) {
    match recording::parse(bytes, "fuzz.csv") {
        Ok(r) => {
            assert!(r.columns.len() >= 2);
            assert_eq!(r.columns[0], "t_s");
            assert_eq!(r.data.len(), r.columns.len());
            assert!(r.data.iter().all(|c| c.len() == r.len()));
            if let Some(n) = r.trailer_samples {
                assert_eq!(n, r.len());
            }
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.csv:")),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        check_never_panics(&bytes);
    }

    #[test]
    fn arbitrary_text_after_the_format_line_never_panics(tail in "[-+#=,.\\n\\r 0-9a-z_\"\\[\\]{}]{0,300}") {
        check_never_panics(format!("{FORMAT_LINE}\n{tail}").as_bytes());
        check_never_panics(format!("{FORMAT_LINE}\nt_s,x_m\n{tail}").as_bytes());
    }

    #[test]
    fn mutated_recordings_never_panic(
        rows in 0usize..30,
        trailer in any::<bool>(),
        mutations in prop::collection::vec(mutation(b",#\n\r.-+e= 0x\""), 1..6),
    ) {
        let valid = valid_text(rows, trailer);
        check_never_panics(&mutate(valid.clone(), &mutations));
        check_never_panics(&mutate(gzip(&valid), &mutations));
    }
}

#[test]
fn a_row_cut_short_at_the_end_is_left_out_and_the_scan_reads_as_incomplete() {
    // What `kill -9` or a full disk can leave in the middle of a write.
    let rec = recording::read(&broken("truncated_mid_row.csv")).unwrap();
    assert!(rec.torn_last_row);
    assert!(!rec.is_complete());
    assert_eq!(rec.len(), 9, "the nine whole rows are kept");
    assert_eq!(rec.column("t_s").unwrap()[8], 0.008);
    // A whole last row without its line end is left out too: it cannot be
    // told from one cut inside its last value.
    let text = std::fs::read_to_string(broken("truncated_mid_row.csv")).unwrap();
    let cut = text.rfind('\n').unwrap();
    let rec = recording::parse(&text.as_bytes()[..cut], "t").unwrap();
    assert!(rec.torn_last_row);
    assert_eq!(rec.len(), 8);
    // After the trailer a cut row is still an error.
    let complete = std::fs::read_to_string(broken("missing_trailer.csv")).unwrap();
    let n = recording::parse(complete.as_bytes(), "t").unwrap().len();
    let with_tail = format!("{complete}# end samples = {n}\n0.5,-0.04");
    let err = recording::parse(with_tail.as_bytes(), "t")
        .unwrap_err()
        .to_string();
    assert!(err.contains("after the trailer"), "{err}");
}

#[test]
fn equal_neighbouring_times_read_but_infinite_ones_and_a_label_that_is_no_string_do_not() {
    let head = "# hapticlab recording v1\n# label = \"S2\"\nt_s,pac\n";
    // Two samples in one microsecond (a loop catching up): kept.
    let r = recording::parse(
        format!("{head}0.001,1\n0.001,2\n0.002,3\n").as_bytes(),
        "x.csv",
    )
    .unwrap();
    assert_eq!(r.len(), 3);
    // One sample: nothing to increase.
    assert_eq!(
        recording::parse(format!("{head}0,1\n").as_bytes(), "x.csv")
            .unwrap()
            .len(),
        1
    );
    let err = recording::parse(format!("{head}0,1\ninf,2\n").as_bytes(), "x.csv").unwrap_err();
    assert!(err.is_bad_input());
    assert!(err.to_string().starts_with("x.csv:5: t_s is inf"), "{err}");
    let err = recording::parse(
        b"# hapticlab recording v1\n# label = 3\nt_s,pac\n0,1\n",
        "x.csv",
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("x.csv:2: metadata `label`: must be a string"),
        "{err}"
    );
}
