//! `hapticlab import` refuses what it would otherwise get silently wrong
//! (a second WAV `fmt` chunk, a hidden input name, CSV-only flags on a WAV,
//! a rate `t_s` cannot be written at, `--burst 0`, a blank label), reads a
//! CSV's byte-order mark, and blames a bad name on the input and the flag,
//! never on its staging folder. Inputs live in `tests/data/import/`.

use std::path::Path;

use hapticlab::recording;

use crate::common::run::Run;
use crate::common::{REPO, p, run};

const DATA: &str = "tests/data/import";

/// `import ARGS --out OUT` must refuse with exit 2, a one-line message that
/// holds each of `says`, and leave nothing under `--out`.
fn refused(args: &[&str], says: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut all = vec!["import", "--out", p(&out)];
    all.extend(args);
    let r = run(&all);
    assert_eq!(r.code, Some(2), "{all:?}: {r:?}");
    assert_eq!(r.stderr.lines().count(), 1, "one line: {r:?}");
    for s in says {
        assert!(r.stderr.contains(s), "{s:?} missing: {r:?}");
    }
    assert!(
        !r.stderr.contains(".import-"),
        "names the staging folder: {r:?}"
    );
    assert!(!out.exists(), "left {out:?} behind");
    r
}

#[test]
fn a_wav_with_two_fmt_chunks_is_refused_naming_the_file() {
    let f = format!("{DATA}/two_fmt_chunks.wav");
    refused(&["--label", "S", &f], &[&f, "two fmt chunks"]);
}

#[test]
fn a_hidden_input_name_is_refused_as_it_would_make_a_hidden_recording() {
    let dir = tempfile::tempdir().unwrap();
    let hidden = dir.path().join(".hidden.wav");
    std::fs::copy(Path::new(REPO).join(DATA).join("mono.wav"), &hidden).unwrap();
    refused(
        &["--label", "S", p(&hidden)],
        &[".hidden.wav", "hidden", "rename"],
    );
}

#[test]
fn csv_only_flags_given_for_a_wav_are_refused_by_name() {
    let f = format!("{DATA}/mono.wav");
    for (flag, value) in [
        ("--rate", "1000"),
        ("--channels", "a"),
        ("--label-column", "label"),
        ("--time-column", "t"),
        ("--burst", "2"),
    ] {
        let mut args = vec!["--label", "S", flag, value, &f];
        if flag == "--label-column" {
            args.drain(0..2);
        }
        let scope = if flag == "--rate" {
            "--rate applies to files without a rate of their own (CSV, text, .npy, .npz, .mat)"
        } else {
            "applies to CSV files only"
        };
        refused(&args, &[&f, flag, scope, "leave it out"]);
    }
    // Beside a CSV they apply to it, and the WAV is named in a warning.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let untimed = dir.path().join("untimed.csv");
    std::fs::write(&untimed, "acc\n1\n2\n").unwrap();
    let csv = p(&untimed).to_string();
    let r = run(&[
        "import",
        "--label",
        "S",
        "--rate",
        "1000",
        "--out",
        p(&out),
        &f,
        &csv,
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stderr
            .contains("warning: --rate applies to files without a rate of their own (CSV, text, .npy, .npz, .mat); tests/data/import/mono.wav"),
        "{r:?}"
    );
    // Without them the same file imports.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let r = run(&["import", "--label", "S", "--out", p(&out), &f]);
    assert_eq!(r.code, Some(0), "{r:?}");
}

#[test]
fn rates_whose_times_cannot_be_written_and_burst_zero_are_refused() {
    let f = format!("{DATA}/bom.csv");
    for rate in ["1e308", "1e16", "inf"] {
        refused(&["--label", "S", "--rate", rate, &f], &["--rate", "1e15"]);
    }
    // A negative rate is the rate's fault, not taken for a file name.
    for rate in ["0", "-5"] {
        refused(
            &["--label", "S", "--rate", rate, &f],
            &[&format!(
                "--rate must be a positive number of samples per second (Hz), got {rate}"
            )],
        );
    }
    refused(
        &["--label", "S", "--rate", "1000", "--burst", "0", &f],
        &["--burst 0"],
    );
}

/// Every format timed by `--rate` (headerless text as .txt, .dat and
/// .csv, .npy, .npz, .mat): a rate whose times overflow (1e-310 Hz) or run
/// to hundreds of digits (1e-300 Hz), or too fast to tell samples apart,
/// is refused before anything is written; the slowest rate taken writes
/// times of a few digits.
#[test]
fn rates_too_slow_or_too_fast_for_the_times_are_refused_for_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let formats = Path::new(REPO).join("tests/data/formats");
    let lmt = std::fs::read(formats.join("lmt.txt")).unwrap();
    let mut inputs = vec![formats.join("lmt.txt")];
    for ext in ["dat", "csv"] {
        let f = dir.path().join(format!("headerless.{ext}"));
        std::fs::write(&f, &lmt).unwrap();
        inputs.push(f);
    }
    for f in ["one.npy", "arrays.npz", "signal.mat"] {
        inputs.push(formats.join(f));
    }
    for f in &inputs {
        for (rate, said) in [
            ("1e-310", "got 1e-310"),
            ("1e-300", "got 1e-300"),
            ("0.0009", "got 0.0009"),
            ("2e15", "got 2e15"),
        ] {
            refused(
                &["--label", "S", "--rate", rate, p(f)],
                &["--rate must be from 0.001 Hz", "to 1e15 Hz", said],
            );
        }
    }
    let out = dir.path().join("out");
    let r = run(&[
        "import",
        "--label",
        "S",
        "--rate",
        "0.001",
        "--out",
        p(&out),
        p(&inputs[0]),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let rec = recording::read(&out.join("S/lmt.csv")).unwrap();
    assert_eq!(rec.data[0][299], 299_000.0);
    let text = std::fs::read_to_string(out.join("S/lmt.csv")).unwrap();
    assert!(
        text.lines()
            .filter(|l| !l.starts_with('#'))
            .all(|l| l.len() < 30),
        "{text}"
    );
}

#[test]
fn a_blank_label_or_one_with_spaces_at_its_ends_is_refused() {
    let f = format!("{DATA}/bom.csv");
    for label in [" ", "  ", " S2", "S2 "] {
        refused(
            &["--rate", "1000", "--label", label, &f],
            &["--label", "space"],
        );
    }
}

#[test]
fn a_csv_with_a_byte_order_mark_imports_as_without() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let f = format!("{DATA}/bom.csv");
    let r = run(&[
        "import",
        "--time-column",
        "time",
        "--label",
        "S",
        "--out",
        p(&out),
        &f,
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let rec = recording::read(&out.join("S/bom.csv")).unwrap();
    assert_eq!(rec.columns, ["t_s", "acc"]);
    assert_eq!(rec.column("acc").unwrap(), [1.0, 2.0, 3.0]);
}

#[test]
fn bad_names_are_blamed_on_the_input_and_the_flag_not_the_staging_folder() {
    let dup = format!("{DATA}/duplicate_column_names.csv");
    let empty = format!("{DATA}/empty_column_name.csv");
    let csv = format!("{DATA}/bom.csv");
    let t = ["--time-column", "time", "--label", "S"];
    let with = |more: &[&'static str], f: &str| -> Vec<String> {
        t.iter()
            .chain(more)
            .map(|s| s.to_string())
            .chain([f.to_string()])
            .collect()
    };
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (with(&[], &dup), vec![&dup, "acc", "twice"]),
        (with(&[], &empty), vec![&empty, "no name"]),
        (
            with(&["--names", "x,x"], &dup),
            vec![&dup, "--names", "twice"],
        ),
        (
            with(&["--channels", "acc,acc"], &csv),
            vec!["--channels", "`acc` twice"],
        ),
        (
            with(&["--meta", "a=1", "--meta", "a=2"], &csv),
            vec!["--meta a", "twice"],
        ),
        (
            with(&["--meta", "source=x"], &csv),
            vec![&csv, "--meta source"],
        ),
    ];
    for (args, says) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&args, says);
    }
    // An --out that is a file: a bad argument (exit 2), named, and left as
    // it was.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("taken");
    std::fs::write(&file, "mine").unwrap();
    let r = run(&[
        "import",
        "--rate",
        "1000",
        "--label",
        "S",
        "--out",
        p(&file),
        &csv,
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("--out") && r.stderr.contains("not a folder"),
        "{r:?}"
    );
    assert!(!r.stderr.contains(".import-"), "{r:?}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}

/// A CSV whose column is named like the time (`time`, `t_s`, any case):
/// with `--rate` it is refused rather than kept as a channel `profile new`
/// would choose, naming `--time-column` and the other columns; without a
/// rate, the message names the column to take the times from.
#[test]
fn a_time_column_is_not_kept_as_a_channel_under_rate() {
    let dir = tempfile::tempdir().unwrap();
    let csv = |name: &str, text: &str| {
        let f = dir.path().join(name);
        std::fs::write(&f, text).unwrap();
        p(&f).to_string()
    };
    let three = csv("three.csv", "time,acc,force\n0,1,2\n0.001,3,4\n");
    refused(
        &["--label", "S", "--rate", "1000", &three],
        &[
            &three,
            "column `time` looks like the time",
            "--time-column time instead of --rate",
            "--channels acc,force",
        ],
    );
    let ts = csv("ts.csv", "t_s,acc\n0,1\n0.001,3\n");
    let r = refused(
        &["--label", "S", "--rate", "1000", &ts],
        &[&ts, "column `t_s`", "--time-column t_s"],
    );
    assert!(!r.stderr.contains("appears twice"), "{r:?}");
    refused(
        &[
            "--label",
            "S",
            "--rate",
            "1000",
            "--channels",
            "t_s,acc",
            &ts,
        ],
        &[&ts, "`t_s` (--channels)", "--time-column t_s"],
    );
    let stamp = csv("stamp.csv", "Timestamp,acc\n0,1\n0.001,3\n");
    refused(
        &["--label", "S", &stamp],
        &[
            &stamp,
            "give --time-column or --rate",
            "`Timestamp` looks like the time: --time-column Timestamp",
        ],
    );
    // The ways out: the times from the column, or the channels named.
    for way in [
        &["--time-column", "time"][..],
        &["--rate", "1000", "--channels", "acc,force"],
    ] {
        let out = dir.path().join(format!("out{}", way.len()));
        let mut args = vec!["import", "--label", "S", "--out", p(&out), &three];
        args.extend(way);
        let r = run(&args);
        assert_eq!(r.code, Some(0), "{args:?}: {r:?}");
        let rec = recording::read(&out.join("S/three.csv")).unwrap();
        assert_eq!(rec.columns, ["t_s", "acc", "force"]);
    }
}

/// Each refusal names the input once (never the staging folder), the line
/// where there is one, and numbers as written: `--meta` of a key `--split`
/// writes, `--names` counted against a CSV, a time column that goes back,
/// empty files, an `.npz`/`.mat` whose scalar looks like the rate, `--rate`
/// 0 and -1e3.
#[test]
fn messages_name_the_input_once_and_the_numbers_plainly() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, text: &str| {
        let f = dir.path().join(name);
        std::fs::write(&f, text).unwrap();
        p(&f).to_string()
    };
    let trace = file("trace.txt", &"1\n2\n3\n".repeat(100));
    let r = refused(
        &[
            "--label",
            "S",
            "--rate",
            "100",
            "--meta",
            "segment=1",
            "--split",
            "0.5",
            &trace,
        ],
        &["--meta segment", "with --split", "choose another key"],
    );
    assert_eq!(r.stderr.matches("trace.txt").count(), 1, "{r:?}");
    let two = file("two.csv", "time,acc,force\n0,1,2\n0.001,3,4\n");
    refused(
        &[
            "--label",
            "S",
            "--time-column",
            "time",
            "--names",
            "a",
            &two,
        ],
        &[&format!(
            "--names gives 1 name(s) but {two} has 2 channel(s) (acc, force)"
        )],
    );
    let back = file("back.csv", "t,acc\n0,1\n0.1,2\n0.05,3\n");
    refused(
        &["--label", "S", "--time-column", "t", &back],
        &[&format!(
            "{back}:4: the time column `t` goes from 0.1 to 0.05"
        )],
    );
    for empty in ["empty.txt", "empty.mat", "empty.npy"] {
        let f = file(empty, "");
        refused(
            &["--label", "S", "--rate", "100", &f],
            &[&format!("{f}: the file is empty")],
        );
    }
    let notes = file("notes.txt", "# a header comment\n\n% another\n");
    refused(
        &["--label", "S", "--rate", "100", &notes],
        &[&notes, "no samples, only blank or comment lines"],
    );
    for f in ["arrays.npz", "signal.mat"] {
        let f = format!("tests/data/formats/{f}");
        refused(
            &["--label", "S", &f],
            &[&f, "scalar `fs` = 1000 looks like one", "give --rate 1000"],
        );
    }
    for (rate, got) in [
        ("--rate=0", "(Hz), got 0"),
        ("--rate=-1e3", "(Hz), got -1000"),
    ] {
        refused(&["--label", "S", rate, &trace], &[got]);
    }
}
