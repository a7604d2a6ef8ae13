//! `import --split`: one long recording per material cut into trials in
//! time order; `profile new` then offers the time split, and `evaluate`
//! refuses a plan that cannot test a label.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use hapticlab::recording;

use crate::common::{p, run};

/// One 60 s trace at 100 Hz per label in `dir/<label>/<label>.csv`
/// (header `acc`, no time column): a tone by label, with noise.
fn long_traces(dir: &Path) -> Vec<String> {
    let mut files = Vec::new();
    for (l, (label, f)) in [("L1", 7.0), ("L2", 19.0), ("L3", 31.0)].iter().enumerate() {
        let mut s = String::from("acc\n");
        let mut x: u64 = 99 + l as u64;
        for i in 0..6000 {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let noise = ((x >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
            let v = (std::f64::consts::TAU * f * i as f64 / 100.0).sin() + noise;
            let _ = writeln!(s, "{:.0}", v * 400.0);
        }
        fs::create_dir_all(dir.join(label)).unwrap();
        let file = dir.join(label).join(format!("{label}.csv"));
        fs::write(&file, s).unwrap();
        files.push(p(&file).to_string());
    }
    files
}

#[test]
fn a_long_recording_per_material_is_cut_into_trials_and_evaluated_on_a_time_split() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let rec = dir.path().join("rec");
    let mut args = vec!["import", "--rate", "100", "--split", "2", "--out", p(&rec)];
    args.extend(files.iter().map(String::as_str));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stderr.contains("imported 90 recording(s)"), "{r:?}");
    let mut names: Vec<String> = fs::read_dir(rec.join("L2"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names.len(), 30);
    assert_eq!(
        (names[0].as_str(), names[29].as_str()),
        ("L2-seg001.csv", "L2-seg030.csv")
    );
    let r10 = recording::read(&rec.join("L2").join("L2-seg010.csv")).unwrap();
    assert_eq!(r10.len(), 200);
    assert_eq!(r10.meta_f64("segment"), Some(10.0));
    assert_eq!(r10.meta_f64("segment_start_s"), Some(18.0));
    assert_eq!(r10.data[0][0], 18.0, "the trial keeps the input's times");
    assert!(
        r10.meta_str("source")
            .is_some_and(|s| s.ends_with("L2.csv"))
    );

    let profile = dir.path().join("long.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&profile)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&profile).unwrap();
    for line in [
        "method = \"holdout\"\n",
        "train_per_class = 21\n",
        "test_per_class = 9\n",
    ] {
        assert!(text.contains(line), "{line:?} missing:\n{text}");
    }
    let r = run(&["evaluate", p(&rec), "-p", p(&profile)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("accuracy: 27/27"), "{r:?}");
}

#[test]
fn evaluate_refuses_leave_one_out_with_one_recording_of_a_label() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let rec = dir.path().join("whole");
    let mut args = vec!["import", "--rate", "100", "--out", p(&rec)];
    args.extend(files.iter().map(String::as_str));
    assert_eq!(run(&args).code, Some(0));
    let profile = dir.path().join("whole.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&profile)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&profile).unwrap();
    assert!(text.contains("--split SECONDS"), "{text}");
    let r = run(&["evaluate", p(&rec), "-p", p(&profile)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("\"L1\" has only one recording") && r.stderr.contains("--split"),
        "{r:?}"
    );
    assert_eq!(r.stderr.trim().lines().count(), 1, "{r:?}");
}

/// The 2 s trials at 100 Hz cut into sub-windows every 0.495 s: the second
/// starts half a sample period off the samples, so every sample sits on a
/// bin's edge (issue 21's hand-written profile). Each bin still gets its
/// sample and `evaluate` scores the trials as `contrib/reference.py` does
/// (27/27 there, with features equal to 10 digits).
#[test]
fn sub_windows_half_a_sample_period_off_the_samples_evaluate() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let rec = dir.path().join("rec");
    let mut args = vec!["import", "--rate", "100", "--split", "2", "--out", p(&rec)];
    args.extend(files.iter().map(String::as_str));
    assert_eq!(run(&args).code, Some(0));
    let profile = dir.path().join("half.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&profile)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&profile).unwrap();
    for line in [
        "window = [0.0, 1.98]",
        "spacing = 0.01",
        "welch_segment = 32",
    ] {
        assert!(text.contains(line), "{line:?} missing:\n{text}");
    }
    let text = text.replacen(
        "\nwelch_segment = 32",
        "\nwindows = { length = 0.99, hop = 0.495 }\nwelch_segment = 32",
        1,
    );
    fs::write(&profile, text).unwrap();
    let r = run(&["evaluate", p(&rec), "-p", p(&profile), "--json"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["accuracy"].as_f64(), Some(1.0), "{v}");
    assert_eq!(v["test"].as_array().unwrap().len(), 27, "{v}");
    let votes = v["windows"].as_array().expect("sub-window votes");
    assert!(
        votes
            .iter()
            .all(|w| w["windows"].as_array().unwrap().len() == 3),
        "{v}"
    );
}

/// `import ARGS --out OUT` must refuse with exit 2 and one line holding
/// each of `says` (and none of `not`), leaving nothing under `--out`.
fn refused(files: &[String], args: &[&str], says: &[&str], not: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut all = vec!["import", "--out", p(&out)];
    all.extend(args);
    all.extend(files.iter().map(String::as_str));
    let r = run(&all);
    assert_eq!(r.code, Some(2), "{all:?}: {r:?}");
    assert_eq!(r.stderr.lines().count(), 1, "one line: {r:?}");
    for s in says {
        assert!(r.stderr.contains(s), "{s:?} missing: {r:?}");
    }
    for s in not {
        assert!(!r.stderr.contains(s), "{s:?} said: {r:?}");
    }
    assert!(!out.exists(), "left {out:?} behind");
}

/// Typos that wrote tens of thousands of files: a hop of a thousandth of
/// the trial (58,001 files), trials of one sample (60,000 files). Both are
/// refused before anything is written, saying what to give; a trial too
/// short at the input's own rate (its time column) speaks of --split.
#[test]
fn trials_too_short_for_a_spectrum_and_hops_past_90_percent_overlap_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    refused(
        &files,
        &["--rate", "100", "--split", "2", "--split-hop", "0.001"],
        &[
            "--split-hop 0.001 s is below a tenth of --split 2 s",
            "90 %",
            "give --split-hop 0.2 or more",
        ],
        &[],
    );
    refused(
        &files,
        &["--rate", "100", "--split", "0.01"],
        &[
            "--split 0.01 s holds 1 sample(s) at 100 Hz",
            "at least 16",
            "give --split 0.16 or more",
        ],
        &["--split-hop"],
    );
    let timed = dir.path().join("timed.csv");
    let mut text = String::from("t,acc\n");
    for i in 0..3000 {
        let _ = writeln!(text, "{},{}", i as f64 / 1000.0, i % 7);
    }
    fs::write(&timed, text).unwrap();
    refused(
        &[p(&timed).to_string()],
        &["--time-column", "t", "--label", "L", "--split", "0.0001"],
        &[
            "timed.csv: --split 0.0001 s holds 1 sample(s) at 1000 Hz",
            "give --split 0.016 or more",
        ],
        &["--split-hop", "sample period"],
    );
}

/// `import raw/long/*.csv --split 2`: every trial is labelled "long", the
/// inputs' one folder. It imports (the label is each file's folder) and
/// says so in one warning; inputs in a folder per label get none.
#[test]
fn inputs_all_in_one_folder_are_imported_with_a_warning_that_they_share_its_label() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let long = dir.path().join("raw").join("long");
    fs::create_dir_all(&long).unwrap();
    let mut together = Vec::new();
    for f in &files {
        let to = long.join(Path::new(f).file_name().unwrap());
        fs::copy(f, &to).unwrap();
        together.push(p(&to).to_string());
    }
    let rec = dir.path().join("rec");
    let mut args = vec!["import", "--rate", "100", "--split", "2", "--out", p(&rec)];
    args.extend(together.iter().map(String::as_str));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    let warnings: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{r:?}");
    for s in [
        "all 3 inputs are in one folder",
        p(&long),
        "labelled \"long\"",
        "the label is each file's folder",
        "--label",
    ] {
        assert!(warnings[0].contains(s), "{s:?} missing: {r:?}");
    }
    assert_eq!(fs::read_dir(rec.join("long")).unwrap().count(), 90);

    let apart = dir.path().join("apart");
    let mut args = vec![
        "import",
        "--rate",
        "100",
        "--split",
        "2",
        "--out",
        p(&apart),
    ];
    args.extend(files.iter().map(String::as_str));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(!r.stderr.contains("warning"), "{r:?}");
}

#[test]
fn importing_again_with_force_cut_another_way_leaves_one_cut_of_each_input() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let rec = dir.path().join("rec");
    // `split` None: each input whole.
    let import = |split: Option<&str>, force: bool| {
        let mut args = vec!["import", "--rate", "100", "--out", p(&rec)];
        if let Some(s) = split {
            args.extend(["--split", s]);
        }
        if force {
            args.push("--force");
        }
        args.extend(files.iter().map(String::as_str));
        run(&args)
    };
    let names = || {
        let mut n: Vec<String> = fs::read_dir(rec.join("L2"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        n.sort();
        n
    };
    assert_eq!(import(Some("2"), false).code, Some(0));
    // Another recording of L2 that is no cut of L2.csv stays.
    fs::copy(
        rec.join("L2").join("L2-seg001.csv"),
        rec.join("L2").join("other.csv"),
    )
    .unwrap();
    // A longer cut: the 2 s cut's trials past 15 go.
    let r = import(Some("4"), true);
    assert_eq!(r.code, Some(0), "{r:?}");
    // One line an input, each recording removed named.
    assert_eq!(
        r.stderr.matches("removed 15 recording(s)").count(),
        3,
        "{r:?}"
    );
    assert!(r.stderr.contains("L2-seg016.csv, L2-seg017.csv"), "{r:?}");
    let n = names();
    assert_eq!(n.len(), 16, "{n:?}");
    assert_eq!(
        (n[14].as_str(), n[15].as_str()),
        ("L2-seg015.csv", "other.csv")
    );
    let r15 = recording::read(&rec.join("L2").join("L2-seg015.csv")).unwrap();
    assert_eq!(r15.len(), 400, "the 4 s cut");
    // Whole: every trial goes.
    let r = import(None, true);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert_eq!(
        r.stderr.matches("removed 15 recording(s)").count(),
        3,
        "{r:?}"
    );
    assert_eq!(names(), ["L2.csv", "other.csv"]);
    // Cut again: the whole one goes.
    let r = import(Some("2"), true);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert_eq!(
        r.stderr.matches("removed 1 recording(s)").count(),
        3,
        "{r:?}"
    );
    let n = names();
    assert_eq!(n.len(), 31, "{n:?}");
    assert!(!n.contains(&"L2.csv".to_string()));

    // An input that sits where a whole recording of it would go is cut,
    // never removed as an earlier cut of itself.
    let inside = rec.join("L2").join("inside.csv");
    fs::copy(&files[1], &inside).unwrap();
    let r = run(&[
        "import",
        "--rate",
        "100",
        "--split",
        "2",
        "--label",
        "L2",
        "--force",
        "--out",
        p(&rec),
        p(&inside),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(inside.exists(), "the input was removed: {r:?}");
    assert!(rec.join("L2").join("inside-seg030.csv").exists());
}

#[test]
fn the_end_no_whole_trial_covers_is_said_to_be_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let files = long_traces(&dir.path().join("in"));
    let cut = |split: &str, out: &str| {
        let rec = dir.path().join(out);
        let mut args = vec![
            "import",
            "--rate",
            "100",
            "--split",
            split,
            "--out",
            p(&rec),
        ];
        args.extend(files.iter().map(String::as_str));
        run(&args)
    };
    // 60 s in 7 s trials: 8 of them, the last 4 s left out.
    let r = cut("7", "seven");
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stderr.contains(
            "--split: the end of 3 inputs no whole trial covers was left out (up to 4 s, as in "
        ),
        "{r:?}"
    );
    // 60 s in 6 s trials: nothing left, nothing said.
    let r = cut("6", "six");
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(!r.stderr.contains("left out"), "{r:?}");
}
