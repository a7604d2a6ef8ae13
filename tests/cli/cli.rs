//! The real `hapticlab` binary, end to end, in temporary folders: help and
//! argument errors, `check`, `simulate`, `evaluate`, `features`, `train`,
//! `classify`, `scan`, and how each treats bad input (exit code 2, one line
//! naming the file and line) and runtime failures (exit code 1).
//!
//! The contracts checked here are the ones in ARCHITECTURE.md: exit codes,
//! the `evaluate --json` shape, the `features --out` CSV shape, and
//! recording format v1.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;
use tempfile::TempDir;

use crate::common::run::Run;
use crate::common::{REPO, hapticlab, p, run};

const QUICK_SCAN: &str = "tests/data/profiles/quick-scan.toml";

pub(crate) fn assert_ok(r: &Run) {
    assert_eq!(r.code, Some(0), "{r:?}");
    assert_no_panic(r);
}

pub(crate) fn assert_no_panic(r: &Run) {
    for text in [&r.stdout, &r.stderr] {
        assert!(
            !text.contains("panicked") && !text.contains("RUST_BACKTRACE"),
            "panic text: {r:?}"
        );
    }
}

/// A user-facing failure: the exit code, and one line on standard error
/// starting `hapticlab: error: `, returned without that prefix.
pub(crate) fn assert_error(r: &Run, code: i32) -> String {
    assert_eq!(r.code, Some(code), "{r:?}");
    assert_no_panic(r);
    let lines: Vec<&str> = r.stderr.lines().filter(|l| !l.is_empty()).collect();
    assert_eq!(lines.len(), 1, "not one line: {r:?}");
    lines[0]
        .strip_prefix("hapticlab: error: ")
        .unwrap_or_else(|| panic!("no `hapticlab: error: ` prefix: {r:?}"))
        .to_string()
}

/// The thesis profile with a smaller split and `k`, written into `dir`.
pub(crate) fn small_profile(dir: &Path, train: usize, test: usize, k: usize) -> PathBuf {
    let text = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let mut out = String::new();
    let mut replaced = 0;
    for line in text.lines() {
        let new = match line.split(" = ").next() {
            Some("train_per_class") => format!("train_per_class = {train}"),
            Some("test_per_class") => format!("test_per_class = {test}"),
            Some("k") => format!("k = {k}"),
            _ => line.to_string(),
        };
        replaced += usize::from(new != line);
        out.push_str(&new);
        out.push('\n');
    }
    assert_eq!(replaced, 3, "profiles/thesis.toml changed shape");
    let path = dir.join("small.toml");
    fs::write(&path, out).unwrap();
    path
}

pub(crate) fn simulate(out: &Path, per_class: usize, seed: u64) {
    let r = run(&[
        "simulate",
        "--out",
        p(out),
        "--per-class",
        &per_class.to_string(),
        "--seed",
        &seed.to_string(),
    ]);
    assert_ok(&r);
}

/// Recording files under `dir`, sorted.
pub(crate) fn recordings(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(recordings(&path));
        } else if path.extension().is_some_and(|e| e == "csv") {
            found.push(path);
        }
    }
    found.sort();
    found
}

pub(crate) fn copy_tree(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for entry in fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let dest = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_tree(&path, &dest);
        } else {
            fs::copy(&path, &dest).unwrap();
        }
    }
}

fn subcommands() -> Vec<String> {
    <hapticlab::cli::Cli as clap::CommandFactory>::command()
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .collect()
}

// ---------------------------------------------------------------- arguments

#[test]
fn help_for_the_program_and_every_command_shows_an_example() {
    let r = run(&["--help"]);
    assert_ok(&r);
    assert!(r.stdout.contains("Example"), "{r:?}");
    let commands = subcommands();
    for known in [
        "simulate", "scan", "features", "train", "classify", "evaluate", "check",
    ] {
        assert!(commands.iter().any(|c| c == known), "no `{known}`");
    }
    for c in &commands {
        let r = run(&[c.as_str(), "--help"]);
        assert_ok(&r);
        assert!(r.stdout.contains("Example"), "`{c} --help`: {r:?}");
        assert!(r.stdout.contains(&format!("hapticlab {c}")), "{r:?}");
    }
    assert_ok(&run(&["--version"]));
}

#[test]
fn bad_arguments_exit_2() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("D");
    let cases: &[&[&str]] = &[
        &["--bogus"],
        &["no-such-command"],
        &["simulate", "--out", p(&out), "--bogus"],
        &["simulate"],
        &["simulate", "--out", p(&out), "--per-class", "many"],
        &["simulate", "--out", p(&out), "--seed", "-1"],
        &["features"],
        &["evaluate"],
        &["train", "recordings"],
        &["classify", "recordings/x.csv"],
        &["scan", "--count", "1"],
        &["check"],
    ];
    for args in cases {
        let r = run(args);
        assert_eq!(r.code, Some(2), "{args:?}: {r:?}");
        assert_no_panic(&r);
        assert!(r.stderr.contains("error"), "{args:?}: {r:?}");
        assert!(r.stdout.is_empty(), "{args:?}: {r:?}");
    }
    assert!(!out.exists(), "a refused command wrote its output");
}

// ---------------------------------------------------------------- profiles

#[test]
fn check_accepts_the_thesis_profile() {
    let r = run(&["check", "profiles/thesis.toml"]);
    assert_ok(&r);
    assert!(r.stdout.contains("profiles/thesis.toml: ok"), "{r:?}");
    assert_ok(&run(&["check", QUICK_SCAN]));
}

#[test]
fn check_refuses_each_invalid_profile_with_file_line_and_column() {
    let mut files: Vec<PathBuf> = fs::read_dir(Path::new(REPO).join("profiles/invalid"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 12, "only {} invalid profiles", files.len());
    for file in &files {
        let shown = format!(
            "profiles/invalid/{}",
            file.file_name().unwrap().to_str().unwrap()
        );
        let r = run(&["check", &shown]);
        let msg = assert_error(&r, 2);
        let rest = msg
            .strip_prefix(&format!("{shown}:"))
            .unwrap_or_else(|| panic!("{shown}: message does not start with the path: {msg}"));
        let mut parts = rest.splitn(3, ':');
        let line: usize = parts.next().unwrap().parse().expect("a line number");
        let col: usize = parts.next().unwrap().parse().expect("a column number");
        assert!(line >= 1 && col >= 1, "{msg}");
        let reason = parts.next().unwrap_or("");
        assert!(reason.trim().len() > 5, "no reason: {msg}");
        // The reason the file itself says it should be refused for.
        let text = fs::read_to_string(file).unwrap();
        if let Some(expect) = text.lines().find_map(|l| l.strip_prefix("# expect: ")) {
            assert!(msg.contains(expect), "{msg} lacks {expect:?}");
        }
        assert!(r.stdout.is_empty(), "{r:?}");
    }
}

#[test]
fn missing_paths_and_profiles_exit_2_naming_them() {
    let dir = TempDir::new().unwrap();
    let nope = dir.path().join("no-such-folder");
    let nope_toml = dir.path().join("no-such-profile.toml");
    let nope_model = dir.path().join("no-such-model.json");
    let out = dir.path().join("out");
    let model = dir.path().join("m.json");
    for args in [
        vec!["evaluate", p(&nope)],
        vec!["features", p(&nope)],
        vec!["train", p(&nope), "--out", p(&model)],
        vec!["classify", "--model", p(&nope_model), "profiles"],
        vec!["inspect", p(&nope)],
        vec!["plot", "features", p(&nope), "--out", p(&out)],
        vec!["replay", p(&nope)],
        vec!["import", p(&nope), "--out", p(&out)],
        vec!["profile", "new", "--from", p(&nope), "--out", p(&model)],
    ] {
        let msg = assert_error(&run(&args), 2);
        assert!(
            msg.contains(p(&nope)) || msg.contains(p(&nope_model)),
            "{args:?}: {msg}"
        );
        // In the lab's words, without the system's "(os error 2)".
        assert!(msg.contains("no such file or folder"), "{args:?}: {msg}");
        assert!(!msg.contains("os error"), "{args:?}: {msg}");
    }
    for args in [
        vec!["check", p(&nope_toml)],
        vec!["evaluate", "--profile", p(&nope_toml), "profiles"],
        vec!["simulate", "--profile", p(&nope_toml), "--out", p(&out)],
        vec![
            "scan",
            "--profile",
            p(&nope_toml),
            "--label",
            "S2",
            "--out",
            p(&out),
        ],
    ] {
        let msg = assert_error(&run(&args), 2);
        assert!(msg.starts_with(p(&nope_toml)), "{args:?}: {msg}");
        assert!(msg.contains("cannot read the profile"), "{args:?}: {msg}");
    }
    assert!(!out.exists() && !model.exists());
    // A folder with no recordings in it.
    let empty = dir.path().join("empty");
    fs::create_dir(&empty).unwrap();
    let msg = assert_error(&run(&["evaluate", p(&empty)]), 2);
    assert!(
        msg.contains("no recordings") && msg.contains(p(&empty)),
        "{msg}"
    );
}

// ---------------------------------------------------------------- simulate, evaluate

#[test]
fn simulate_then_evaluate_classifies_the_held_out_scans() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 12, 3);
    assert_eq!(recordings(&data).len(), 48);
    let profile = small_profile(dir.path(), 8, 4, 5);

    // The table.
    let r = run(&["evaluate", "--profile", p(&profile), p(&data)]);
    assert_ok(&r);
    let row = |name: &str| -> Vec<f64> {
        let line = r
            .stdout
            .lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_else(|| panic!("no {name} row: {r:?}"));
        line[name.len()..]
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let sr = row("SR(%)");
    let er = row("ER(%)");
    assert_eq!(sr.len(), 4, "{r:?}");
    for (s, e) in sr.iter().zip(&er) {
        assert!((s + e - 100.0).abs() < 0.11, "{r:?}");
    }
    let accuracy = r
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("accuracy: "))
        .unwrap_or_else(|| panic!("no accuracy line: {r:?}"));
    let (right, total) = accuracy
        .split_whitespace()
        .next()
        .unwrap()
        .split_once('/')
        .unwrap();
    let (right, total): (usize, usize) = (right.parse().unwrap(), total.parse().unwrap());
    assert_eq!(total, 16, "{r:?}");
    assert!(right >= 15, "{r:?}");

    // The JSON report.
    let r = run(&["evaluate", "--profile", p(&profile), "--json", p(&data)]);
    assert_ok(&r);
    let v: Value = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    let obj = v.as_object().unwrap();
    for key in [
        "labels",
        "confusion",
        "accuracy",
        "per_class",
        "train",
        "test",
        "predictions",
    ] {
        assert!(obj.contains_key(key), "no `{key}`: {v}");
    }
    let labels: Vec<&str> = v["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert_eq!(labels, ["S1", "S2", "S3", "S4"]);
    let index = |l: &str| labels.iter().position(|x| *x == l).unwrap();
    let confusion: Vec<Vec<usize>> = serde_json::from_value(v["confusion"].clone()).unwrap();
    assert_eq!(confusion.len(), 4);
    assert!(confusion.iter().all(|r| r.len() == 4));
    let test: Vec<String> = serde_json::from_value(v["test"].clone()).unwrap();
    let train: Vec<String> = serde_json::from_value(v["train"].clone()).unwrap();
    assert_eq!(test.len(), 16);
    assert_eq!(train.len(), 32);
    assert!(
        test.iter().all(|t| !train.contains(t)),
        "test files trained on"
    );
    let total: usize = confusion.iter().flatten().sum();
    assert_eq!(total, test.len());

    // Rows are the true class: rebuild the matrix from the predictions.
    let predictions = v["predictions"].as_array().unwrap();
    assert_eq!(predictions.len(), 16);
    let mut rebuilt = vec![vec![0usize; 4]; 4];
    for pr in predictions {
        let file = pr["file"].as_str().unwrap();
        let label = pr["label"].as_str().unwrap();
        let predicted = pr["predicted"].as_str().unwrap();
        assert!(test.iter().any(|t| t == file), "{file} is not a test file");
        assert!(
            file.contains(&format!("/{label}/")),
            "{file} labelled {label}"
        );
        let votes = pr["votes"].as_array().unwrap();
        let total_votes: u64 = votes.iter().map(|v| v[1].as_u64().unwrap()).sum();
        assert_eq!(total_votes, 5, "k = 5: {pr}");
        assert_eq!(votes[0][0].as_str(), Some(predicted), "{pr}");
        rebuilt[index(label)][index(predicted)] += 1;
    }
    assert_eq!(rebuilt, confusion);
    let trace: usize = (0..4).map(|i| confusion[i][i]).sum();
    assert!(trace >= 15, "{confusion:?}");
    assert!((v["accuracy"].as_f64().unwrap() - trace as f64 / 16.0).abs() < 1e-12);
    let per_class = v["per_class"].as_array().unwrap();
    assert_eq!(per_class.len(), 4);
    for (i, c) in per_class.iter().enumerate() {
        assert_eq!(c["label"].as_str(), Some(labels[i]));
        let n = c["n"].as_u64().unwrap() as usize;
        assert_eq!(n, confusion[i].iter().sum::<usize>());
        assert_eq!(n, 4);
        let sr = c["success_rate"].as_f64().unwrap();
        let er = c["error_rate"].as_f64().unwrap();
        assert!(
            (sr - confusion[i][i] as f64 / n as f64).abs() < 1e-12,
            "{c}"
        );
        assert!((sr + er - 1.0).abs() < 1e-12, "{c}");
    }
}

/// A recording's lines without the wall-clock `started_at`.
fn without_started_at(path: &Path) -> Vec<String> {
    fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("# started_at"))
        .map(str::to_string)
        .collect()
}

/// The data rows of a recording.
fn sample_rows(path: &Path) -> Vec<String> {
    without_started_at(path)
        .into_iter()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t_s"))
        .collect()
}

#[test]
fn simulate_is_reproducible_from_its_seed() {
    let dir = TempDir::new().unwrap();
    let (a, b, c) = (
        dir.path().join("a"),
        dir.path().join("b"),
        dir.path().join("c"),
    );
    // Same seed, different worker counts: identical scans.
    let args = |out: &Path, seed: &str, threads: &str| {
        let r = run(&[
            "simulate",
            "--out",
            p(out),
            "--per-class",
            "2",
            "--seed",
            seed,
            "--threads",
            threads,
        ]);
        assert_ok(&r);
    };
    args(&a, "11", "1");
    args(&b, "11", "2");
    args(&c, "12", "2");
    let files_a = recordings(&a);
    assert_eq!(files_a.len(), 8);
    let names = |fs: &[PathBuf], root: &Path| -> Vec<PathBuf> {
        fs.iter()
            .map(|f| f.strip_prefix(root).unwrap().to_path_buf())
            .collect()
    };
    assert_eq!(names(&files_a, &a), names(&recordings(&b), &b));
    assert_eq!(names(&files_a, &a), names(&recordings(&c), &c));
    for fa in &files_a {
        let rel = fa.strip_prefix(&a).unwrap();
        let rows = sample_rows(fa);
        assert!(rows.len() > 9000, "{}: {} rows", fa.display(), rows.len());
        assert_eq!(
            without_started_at(fa),
            without_started_at(&b.join(rel)),
            "{} differs between two runs with the same seed",
            rel.display()
        );
        assert_ne!(
            rows,
            sample_rows(&c.join(rel)),
            "{} is the same under another seed",
            rel.display()
        );
    }
}

// ---------------------------------------------------------------- features

#[test]
fn features_writes_one_csv_row_per_recording() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 2, 4);
    let files = recordings(&data);
    let out = dir.path().join("out").join("F.csv");
    let r = run(&["features", p(&data), "--out", p(&out)]);
    assert_ok(&r);
    let text = fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = std::iter::once("file".to_string())
        .chain(std::iter::once("label".to_string()))
        .chain((1..=49).map(|i| format!("f{i}")))
        .collect();
    assert_eq!(lines.next().unwrap(), header.join(","));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), files.len());
    let mut seen = Vec::new();
    for row in &rows {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), 51, "{row}");
        let file = PathBuf::from(cells[0]);
        let folder = file.parent().unwrap().file_name().unwrap();
        assert_eq!(folder.to_str(), Some(cells[1]), "{row}");
        for v in &cells[2..] {
            let x: f64 = v.parse().unwrap_or_else(|e| panic!("{v}: {e}"));
            assert!(x.is_finite() && x >= 0.0, "{row}");
        }
        seen.push(file);
    }
    seen.sort();
    assert_eq!(seen, files);
    // Without --out, the same CSV on standard output.
    let r = run(&["features", p(&data)]);
    assert_ok(&r);
    assert_eq!(r.stdout, text);
}

// ---------------------------------------------------------------- train, classify

/// Under a profile that reads two channels (`y_m` and `fy_n`), the
/// console's Predict (`console::scan::analyse`, then `predict`) sees the
/// features `train` and `classify` make: 98 per scan, and the same
/// prediction, votes and neighbour distances as `classify --json`.
#[test]
fn the_consoles_predict_and_classify_see_the_same_features_under_two_channels() {
    use hapticlab::analysis::FeatureExtractor;
    use hapticlab::classify::Model;
    use hapticlab::profile::LoadedProfile;
    let dir = TempDir::new().unwrap();
    let thesis = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let two = thesis.replacen(
        "channel = \"y_m\"\n",
        "channel = \"y_m\"\nchannels = [\"fy_n\"]\n",
        1,
    );
    assert_ne!(two, thesis, "the thesis profile names its channel");
    let profile = dir.path().join("two-channels.toml");
    fs::write(&profile, two).unwrap();
    // Three scans of each texture to train on, the fourth of S3 held out.
    let shipped = Path::new(REPO).join("recordings/thesis-sim");
    let data = dir.path().join("D");
    for label in ["S1", "S2", "S3", "S4"] {
        fs::create_dir_all(data.join(label)).unwrap();
        for i in 1..=3 {
            let name = format!("{label}_00{i}.csv.gz");
            fs::copy(
                shipped.join(label).join(&name),
                data.join(label).join(&name),
            )
            .unwrap();
        }
    }
    let held = shipped.join("S3").join("S3_004.csv.gz");
    let model_path = dir.path().join("M.json");
    let r = run(&[
        "train",
        "--profile",
        p(&profile),
        p(&data),
        "--out",
        p(&model_path),
    ]);
    assert_ok(&r);
    let r = run(&[
        "classify",
        "--profile",
        p(&profile),
        "--model",
        p(&model_path),
        "--json",
        p(&held),
    ]);
    assert_ok(&r);
    let v: Value = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    let row = &v.as_array().unwrap()[0];

    let lp = LoadedProfile::load(&profile).unwrap();
    let model = Model::load(&model_path).unwrap();
    assert_eq!(lp.profile.analysis.feature_count(), 98);
    assert!(model.examples.iter().all(|e| e.features.len() == 98));
    let rec = hapticlab::recording::read(&held).unwrap();
    let mut ex = FeatureExtractor::new(&lp.profile.analysis);
    let view = hapticlab::console::scan::analyse(&rec, &held, &mut ex);
    let features = view.features.clone().unwrap();
    assert_eq!(features.len(), 98);
    // The same vector `classify` computes for this file.
    let mut ex = FeatureExtractor::new(&model.analysis);
    assert_eq!(
        hapticlab::dataset::features_of(&rec, &held, &mut ex).unwrap(),
        features
    );
    // And the same prediction, votes and neighbours as `classify --json`.
    let predicted = hapticlab::console::scan::predict_view(&model, &view)
        .unwrap()
        .unwrap();
    assert!(!predicted.left_out);
    let pr = &predicted.prediction;
    assert_eq!(row["predicted"].as_str(), Some(pr.label.as_str()), "{row}");
    assert_eq!(
        row["votes"],
        serde_json::to_value(&pr.votes).unwrap(),
        "{row}"
    );
    assert_eq!(
        row["neighbours"],
        serde_json::to_value(&pr.neighbours).unwrap(),
        "{row}"
    );
    // A training scan opened in the console gives the features `train`
    // stored for it.
    let first = data.join("S1").join("S1_001.csv.gz");
    let rec = hapticlab::recording::read(&first).unwrap();
    let view = hapticlab::console::scan::analyse(&rec, &first, &mut ex);
    let stored = model
        .examples
        .iter()
        .find(|e| e.file == first.display().to_string())
        .unwrap();
    assert_eq!(view.features.unwrap(), stored.features);
}

#[test]
fn train_then_classify_held_out_scans() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 6, 8);
    // Hold out the sixth scan of each texture.
    let held = dir.path().join("held-out");
    for label in ["S1", "S2", "S3", "S4"] {
        fs::create_dir_all(held.join(label)).unwrap();
        let name = format!("{label}_006.csv");
        fs::rename(data.join(label).join(&name), held.join(label).join(&name)).unwrap();
    }
    let profile = small_profile(dir.path(), 8, 4, 5);
    let model = dir.path().join("M.json");
    let r = run(&[
        "train",
        "--profile",
        p(&profile),
        p(&data),
        "--out",
        p(&model),
    ]);
    assert_ok(&r);
    let m: Value = serde_json::from_str(&fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(m["examples"].as_array().unwrap().len(), 20);

    // One file, for people.
    let s2 = held.join("S2").join("S2_006.csv");
    let r = run(&["classify", "--model", p(&model), p(&s2)]);
    assert_ok(&r);
    assert!(
        r.stdout.starts_with(&format!("{}: S2 ", s2.display())),
        "{r:?}"
    );
    // Every held-out file, for scripts.
    let r = run(&["classify", "--model", p(&model), "--json", p(&held)]);
    assert_ok(&r);
    let v: Value = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), 4, "{v}");
    for row in rows {
        let file = row["file"].as_str().unwrap();
        assert!(file.starts_with(p(&held)), "{row}");
        assert_eq!(row["label"], row["predicted"], "{row}");
        assert_eq!(row["neighbours"].as_array().unwrap().len(), 5, "{row}");
    }

    // A model whose analysis settings are not the profile's is refused.
    let mut other = m.clone();
    other["analysis"]["spacing"] = serde_json::json!(0.00025);
    let other_path = dir.path().join("other.json");
    fs::write(&other_path, serde_json::to_string_pretty(&other).unwrap()).unwrap();
    let msg = assert_error(&run(&["classify", "--model", p(&other_path), p(&s2)]), 2);
    assert!(msg.contains("analysis.spacing"), "{msg}");
    assert!(msg.contains(p(&other_path)), "{msg}");
}

// ---------------------------------------------------------------- live scans

#[test]
fn a_quick_live_scan_writes_a_complete_recording() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    let r = run(&[
        "scan",
        "--profile",
        QUICK_SCAN,
        "--label",
        "S2",
        "--count",
        "1",
        "--out",
        p(&data),
    ]);
    assert_ok(&r);
    let loop_line = r
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("loop:"))
        .unwrap_or_else(|| panic!("no loop statistics: {r:?}"));
    assert!(
        loop_line.contains("Hz") && loop_line.contains("p99"),
        "{loop_line}"
    );
    let files = recordings(&data);
    assert_eq!(files, [data.join("S2").join("S2_001.csv")]);
    let rec = hapticlab::recording::read(&files[0]).unwrap();
    assert!(rec.is_complete(), "{:?}", rec.meta);
    assert_eq!(rec.trailer_samples, Some(rec.len()));
    assert_eq!(rec.label(), Some("S2"));
    assert_eq!(rec.meta_str("profile"), Some("quick-scan"));
    assert_eq!(rec.meta_str("clock"), Some("real"));
    assert!(rec.aborted().is_none());
    let t = rec.column("t_s").unwrap();
    assert!(t.windows(2).all(|w| w[1] > w[0]), "time runs backwards");
    // The stroke runs from x = -4.5 cm to -3.0 cm.
    let x = rec.column("x_m").unwrap();
    assert!((x[0] + 0.045).abs() < 0.001, "starts at {}", x[0]);
    let last = x[x.len() - 1];
    assert!((last + 0.030).abs() < 0.001, "ends at {last}");
    // And it is a scan the profile's analysis can use.
    let r = run(&["features", "--profile", QUICK_SCAN, p(&data)]);
    assert_ok(&r);
    assert_eq!(r.stdout.lines().count(), 2, "{r:?}");
    assert!(r.stdout.lines().next().unwrap().ends_with(",f20"), "{r:?}");
}

#[test]
fn an_interrupted_scan_exits_1_and_keeps_its_samples() {
    let dir = TempDir::new().unwrap();
    // The quick profile with a 3 s stroke, so there is time to interrupt it.
    let text = fs::read_to_string(Path::new(REPO).join(QUICK_SCAN)).unwrap();
    assert!(text.contains("\nspeed_m_per_s = 0.02\n"));
    let slow = dir.path().join("slow.toml");
    fs::write(
        &slow,
        text.replace("\nspeed_m_per_s = 0.02\n", "\nspeed_m_per_s = 0.005\n"),
    )
    .unwrap();
    let data = dir.path().join("D");
    let file = data.join("S2").join("S2_001.csv");
    let mut child = hapticlab()
        .args(["scan", "--profile", p(&slow), "--label", "S2"])
        .args(["--out", p(&data)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();

    // Wait until the stroke is being recorded (the recorder flushes every
    // quarter second), let it run a little more, then interrupt.
    let give_up = Instant::now() + Duration::from_secs(30);
    loop {
        let rows = fs::read_to_string(&file)
            .map(|t| t.lines().filter(|l| l.starts_with(['0', '1'])).count())
            .unwrap_or(0);
        if rows > 0 {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the scan ended before it was interrupted: {status}");
        }
        assert!(Instant::now() < give_up, "the scan never started recording");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(500));
    // Ctrl-C twice, as an impatient user does: the second only raises the
    // same stop again (it must not end the process before the scan is
    // stopped, saved and the forces zeroed).
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let give_up = Instant::now() + Duration::from_secs(30);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > give_up {
            let _ = child.kill();
            panic!("the scan did not stop after SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let r: Run = child.wait_with_output().unwrap().into();
    assert_eq!(r.code, Some(1), "{r:?}");
    assert_no_panic(&r);
    // `scan` announces itself on standard error first; the error comes last.
    let msg = r
        .stderr
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("hapticlab: error: "))
        .unwrap_or_else(|| panic!("no error line last: {r:?}"));
    assert!(msg.contains("interrupted"), "{msg}");
    assert!(msg.contains("forces are off"), "{msg}");
    assert!(r.stdout.contains("interrupted"), "{r:?}");

    let rec = hapticlab::recording::read(&file).unwrap();
    assert!(!rec.is_complete(), "an interrupted scan reads as complete");
    assert!(
        rec.aborted().is_some_and(|a| a.contains("interrupted")),
        "{:?}",
        rec.meta
    );
    assert!(rec.len() >= 250, "only {} samples kept", rec.len());
    // Stopped part-way along the 1.5 cm stroke.
    let x = rec.column("x_m").unwrap();
    assert!(x[x.len() - 1] < -0.031, "{}", x[x.len() - 1]);
}

#[test]
fn simulate_never_overwrites_recordings_unless_asked() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 1, 3);
    let first = data.join("S2").join("S2_001.csv");
    let before = fs::read(&first).unwrap();
    let args = [
        "simulate",
        "--out",
        p(&data),
        "--per-class",
        "1",
        "--seed",
        "4",
    ];
    let msg = assert_error(&run(&args), 2);
    assert!(msg.contains("already exists"), "{msg}");
    assert!(msg.contains("--overwrite"), "{msg}");
    assert_eq!(fs::read(&first).unwrap(), before, "a recording was touched");
    let mut with = args.to_vec();
    with.push("--overwrite");
    assert_ok(&run(&with));
    assert_ne!(
        fs::read(&first).unwrap(),
        before,
        "seed 4 differs from seed 3"
    );
}

#[test]
fn the_console_refuses_a_missing_firmware_file_as_bad_input() {
    let dir = TempDir::new().unwrap();
    let text = fs::read_to_string(Path::new(REPO).join("profiles/thesis-emulator.toml")).unwrap();
    assert!(text.contains("firmware_loaded = true") && text.contains("\n[falcon]\n"));
    let text = text
        .replace("firmware_loaded = true", "firmware_loaded = false")
        .replace("\n[falcon]\n", "\n[falcon]\nfirmware = \"nowhere.bin\"\n");
    let profile = dir.path().join("no-firmware.toml");
    fs::write(&profile, text).unwrap();
    let ds = dir.path().join("ds");
    let msg = assert_error(
        &run(&["console", "--profile", p(&profile), "--dataset", p(&ds)]),
        2,
    );
    assert!(
        msg.contains("nowhere.bin") && msg.contains("firmware"),
        "{msg}"
    );
}
