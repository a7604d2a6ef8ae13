//! `hapticlab evaluate` with `[analysis] windows`: every method (holdout,
//! k-fold, leave-one-out, grouped folds) splits by recording and reports one
//! row per recording with its sub-windows' vote (`--json` adds `windows`),
//! sweeps score by that vote, and no recording's sub-windows ever reach
//! both sides of a split.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

use serde_json::Value;
use tempfile::TempDir;

use crate::common::{REPO, json_of, p, run, thesis_windows_profile};

fn files(v: &Value, key: &str) -> Vec<String> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no `{key}` in {v}"))
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect()
}

/// One prediction row per test recording, each with its three sub-windows'
/// votes; the `windows` votes follow the rows.
fn check_rows_by_recording(v: &Value, windows_per_recording: u64) {
    let rows = v["predictions"].as_array().unwrap();
    let test = files(v, "test");
    assert_eq!(rows.len(), test.len());
    let distinct: BTreeSet<&String> = test.iter().collect();
    assert_eq!(distinct.len(), test.len(), "a recording tested twice");
    let votes = v["windows"].as_array().expect("`windows` with sub-windows");
    assert_eq!(votes.len(), rows.len());
    for (row, w) in rows.iter().zip(votes) {
        assert_eq!(row["file"], w["file"]);
        let counted: u64 = row["votes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p[1].as_u64().unwrap())
            .sum();
        assert_eq!(counted, windows_per_recording, "{row}");
        assert_eq!(
            w["windows"].as_array().unwrap().len() as u64,
            windows_per_recording
        );
        assert_eq!(row["predicted"], w["label"]);
    }
}

#[test]
fn every_method_on_the_thesis_recordings_votes_per_recording() {
    let dir = TempDir::new().unwrap();
    let profile = thesis_windows_profile(dir.path());
    let data = Path::new(REPO).join("recordings/thesis-sim");
    let n = dataset_size(&data);

    // The holdout: the recordings the split picks without windows, whole.
    let v = json_of(&["evaluate", "--profile", p(&profile), p(&data), "--json"]);
    check_rows_by_recording(&v, 3);
    let plain = json_of(&["evaluate", p(&data), "--json"]);
    assert_eq!(files(&v, "test"), files(&plain, "test"));
    assert_eq!(files(&v, "train"), files(&plain, "train"));
    assert!(v["accuracy"].as_f64().unwrap() >= 0.9, "{}", v["accuracy"]);

    for args in [
        &["--folds", "5"][..],
        &["--loo"][..],
        &["--folds", "5", "--group-by", "seed", "--seed", "3"][..],
    ] {
        let mut all = vec!["evaluate", "--profile", p(&profile), p(&data), "--json"];
        all.extend_from_slice(args);
        let v = json_of(&all);
        check_rows_by_recording(&v, 3);
        assert_eq!(files(&v, "test").len(), n, "{args:?}: every recording once");
        assert!(v["accuracy"].as_f64().unwrap() >= 0.9, "{args:?}: {v}");
        assert!(v["method"].is_string() && v["folds"].is_array());
    }

    // The table names recordings and windows.
    let r = run(&["evaluate", "--profile", p(&profile), p(&data), "--loo"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout
            .contains(&format!("{n} recordings, {} windows", 3 * n)),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains(&format!("/{n} (")), "{}", r.stdout);
    let r = run(&["evaluate", "--profile", p(&profile), p(&data)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("windows"), "{}", r.stdout);

    // A sweep scores each value by recording: as many tested as recordings.
    for spec in ["k=1,10", "spacing=0.0002,0.0003", "detrend=mean,linear"] {
        let v = json_of(&[
            "evaluate",
            "--profile",
            p(&profile),
            p(&data),
            "--folds",
            "5",
            "--sweep",
            spec,
            "--json",
        ]);
        for point in v["points"].as_array().unwrap() {
            assert_eq!(point["recordings"], n, "{spec}: {point}");
            assert!(
                point["accuracy"].as_f64().unwrap() >= 0.9,
                "{spec}: {point}"
            );
        }
    }
}

fn dataset_size(dir: &Path) -> usize {
    fs::read_dir(dir)
        .unwrap()
        .map(|d| d.unwrap().path())
        .filter(|d| d.is_dir())
        .map(|d| fs::read_dir(d).unwrap().count())
        .sum()
}

/// Ten recordings `r00`..`r09`, labelled A, B, A, B, …, each one sinusoid
/// at 25 Hz (six periods per 0.24 s sub-window, so a recording's four
/// sub-windows have the same spectrum) with its own amplitude. Sorted by
/// amplitude the labels alternate (and the gaps grow, so no two distances
/// tie), in an order where the file-name holdout (3 + 2 per class) tests
/// recordings whose nearest training recording has the other label. A
/// k = 1 model that has seen a sibling sub-window of a test recording is
/// right about it (distance 0); one that has not takes the label of the
/// training recording nearest in amplitude. `session` pairs r00 with r01,
/// r02 with r03, ….
fn interleaved(dir: &Path) -> (PathBuf, PathBuf, Vec<(String, String, f64)>) {
    let data = dir.join("interleaved");
    fs::create_dir_all(&data).unwrap();
    // Rank by amplitude of each file: A0 B0 A3 B3 A1 B1 A4 B4 A2 B2.
    let rank = [0usize, 1, 4, 5, 8, 9, 2, 3, 6, 7];
    let mut recs = Vec::new();
    for (i, &r) in rank.iter().enumerate() {
        let label = if i % 2 == 0 { "A" } else { "B" };
        let amp = 1.0 + 0.1 * r as f64 + 0.002 * (r * r) as f64;
        let mut text = format!(
            "# hapticlab recording v1\n# label = \"{label}\"\n# session = \"s{}\"\nt_s,pac\n",
            i / 2
        );
        let n = 1000;
        for j in 0..n {
            let t = j as f64 / 1000.0;
            let v = amp * (2.0 * std::f64::consts::PI * 25.0 * t).sin();
            text.push_str(&format!("{t:.3},{v:.9}\n"));
        }
        text.push_str(&format!("# end samples = {n}\n"));
        let file = data.join(format!("r{i:02}.csv"));
        fs::write(&file, text).unwrap();
        recs.push((file.display().to_string(), label.to_string(), amp));
    }
    let thesis = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let start = thesis.find("[analysis]").unwrap();
    let end = thesis.find("[evaluation]").unwrap();
    let rest = &thesis[end..];
    let after = rest[1..].find("\n[").map_or(rest.len(), |i| i + 2);
    let text = format!(
        "{}[analysis]\nchannel = \"pac\"\naxis = \"t_s\"\nwindow = [0.0, 0.96]\nspacing = 0.001\n\
         detrend = \"mean\"\nspectrum = \"magnitude\"\nbins = [1, 20]\n\
         windows = {{ length = 0.24, hop = 0.24 }}\n\n\
         [classifier]\nk = 1\nmetric = \"euclidean\"\n\n\
         [evaluation]\ntrain_per_class = 3\ntest_per_class = 2\n\n{}",
        &thesis[..start],
        &rest[after..]
    );
    let profile = dir.join("interleaved.toml");
    fs::write(&profile, text).unwrap();
    (profile, data, recs)
}

/// Every method keeps recordings whole: each test recording gets the label
/// of the training recording nearest in amplitude among those its fold (the
/// folds are `predictions` in order, `folds[].tested` each) left to train,
/// never its own label through a sibling sub-window. On this data that is
/// wrong about every recording of the holdout and of leave-one-out, so
/// even one leaked recording fails the test.
#[test]
fn no_method_lets_a_recordings_windows_reach_both_sides() {
    let dir = TempDir::new().unwrap();
    let (profile, data, recs) = interleaved(dir.path());
    let nearest = |file: &str, train: &BTreeSet<&str>| -> String {
        let amp = recs.iter().find(|r| r.0 == file).unwrap().2;
        let best = recs
            .iter()
            .filter(|r| train.contains(r.0.as_str()))
            .min_by(|a, b| (a.2 - amp).abs().total_cmp(&(b.2 - amp).abs()))
            .expect("a training recording");
        best.1.clone()
    };
    for (args, wrong_about_all) in [
        (&[][..], true),
        (&["--loo"][..], true),
        (&["--folds", "5", "--seed", "1"][..], false),
        (&["--folds", "5", "--group-by", "session"][..], false),
        (&["--loo", "--group-by", "session"][..], false),
    ] {
        let mut all = vec!["evaluate", "--profile", p(&profile), p(&data), "--json"];
        all.extend_from_slice(args);
        let v = json_of(&all);
        check_rows_by_recording(&v, 4);
        let rows = v["predictions"].as_array().unwrap();
        // The test recordings of each fold: the holdout's one, or the
        // folds' in turn.
        let sizes: Vec<usize> = match v["folds"].as_array() {
            Some(f) => f
                .iter()
                .map(|f| f["tested"].as_u64().unwrap() as usize)
                .collect(),
            None => vec![rows.len()],
        };
        assert_eq!(sizes.iter().sum::<usize>(), rows.len());
        let mut at = 0;
        for size in sizes {
            let fold = &rows[at..at + size];
            at += size;
            let tested: BTreeSet<&str> = fold.iter().map(|r| r["file"].as_str().unwrap()).collect();
            let train: BTreeSet<&str> = if v["folds"].is_array() {
                recs.iter()
                    .map(|r| r.0.as_str())
                    .filter(|f| !tested.contains(f))
                    .collect()
            } else {
                v["train"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|f| f.as_str().unwrap())
                    .collect()
            };
            assert!(train.is_disjoint(&tested), "{args:?}: {train:?} {tested:?}");
            for row in fold {
                let file = row["file"].as_str().unwrap();
                assert_eq!(
                    row["predicted"].as_str().unwrap(),
                    nearest(file, &train),
                    "{args:?}: {file} was not classified by the other recordings alone"
                );
            }
        }
        if wrong_about_all {
            assert_eq!(v["accuracy"].as_f64().unwrap(), 0.0, "{args:?}: {v}");
        }
    }
    // The table counts recordings and their windows.
    let r = run(&["evaluate", "--profile", p(&profile), p(&data), "--loo"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains("10 recordings, 40 windows"),
        "{}",
        r.stdout
    );
}
