//! `evaluate --json` byte for byte against outputs captured before the
//! evaluation moved into one engine entry point (issue 20): holdout,
//! `--folds 5`, `--loo`, a one-key sweep, a two-key grid, and the holdout
//! and 5-fold runs of the sub-window profile; and the plain-text Table 4.1
//! of the thesis's holdout (40/40). A deliberate change of the contract
//! rewrites the file in tests/data/golden/ in the same commit.

use std::fs;
use std::path::Path;

use tempfile::TempDir;

use crate::common::{REPO, p, run, thesis_windows_profile};

/// The standard output of `hapticlab evaluate recordings/thesis-sim ARGS`,
/// which must exit 0, against tests/data/golden/NAME.
fn same_as(name: &str, args: &[&str]) {
    let all = [&["evaluate", "recordings/thesis-sim"][..], args].concat();
    let r = run(&all);
    assert_eq!(r.code, Some(0), "{all:?}: {r:?}");
    let path = Path::new(REPO).join("tests/data/golden").join(name);
    let expected = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        r.stdout == expected,
        "{all:?}: the output differs from {}\n--- got\n{}\n--- expected\n{expected}",
        path.display(),
        r.stdout
    );
}

#[test]
fn holdout_json_is_unchanged() {
    same_as("evaluate-holdout.json", &["--json"]);
}

#[test]
fn table_4_1_is_unchanged() {
    same_as("table-4.1.txt", &[]);
}

#[test]
fn five_fold_json_is_unchanged() {
    same_as("evaluate-folds5.json", &["--folds", "5", "--json"]);
}

#[test]
fn leave_one_out_json_is_unchanged() {
    same_as("evaluate-loo.json", &["--loo", "--json"]);
}

#[test]
fn sweep_json_is_unchanged() {
    same_as(
        "evaluate-sweep-k.json",
        &["--sweep", "k=1,3,5,10", "--json"],
    );
}

#[test]
fn grid_json_is_unchanged() {
    same_as(
        "evaluate-grid.json",
        &[
            "--folds",
            "5",
            "--sweep",
            "k=1,5",
            "--sweep",
            "spectrum=magnitude,welch",
            "--json",
        ],
    );
}

#[test]
fn sub_window_json_is_unchanged() {
    let dir = TempDir::new().unwrap();
    let profile = thesis_windows_profile(dir.path());
    same_as(
        "evaluate-windows-holdout.json",
        &["-p", p(&profile), "--json"],
    );
    same_as(
        "evaluate-windows-folds5.json",
        &["-p", p(&profile), "--folds", "5", "--json"],
    );
}
