//! Helpers shared by the integration test binaries (`tests/cli`,
//! `tests/engine`, `tests/console`), declared once in each binary's
//! `main.rs` as `#[path = "../common/mod.rs"] mod common;`. The counting
//! allocator (`counting_alloc.rs`) is not here: it installs a global
//! allocator, so only `tests/alloc` declares it.

// Each binary uses a part of these.
#![allow(dead_code)]

pub mod mutation;
pub mod run;

use std::path::Path;
use std::process::Command;

use hapticlab::classify::TrainingExample;
use hapticlab::profile::{Analysis, Detrend, SpectrumKind};

use run::Run;

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_hapticlab");
/// The repository: the binary runs from here, so `profiles/…` and
/// `tests/data/…` paths resolve.
pub const REPO: &str = env!("CARGO_MANIFEST_DIR");

/// Commands a documented example may hold that cannot run in a test, by a
/// word they contain, and why: the README's and docs' commands
/// (`cli::docs`) and the `--help` examples (`cli::help_examples`) skip
/// these, each adding its own.
pub const NOT_RUN_IN_TESTS: &[(&str, &str)] = &[
    ("hapticlab console", "opens the console on the terminal"),
    ("hapticlab --dataset", "opens the console on the terminal"),
    (
        "hapticlab replay",
        "opens the replay console on the terminal",
    ),
    ("hapticlab scan", "drives the servo in real time"),
    (
        "--simulate",
        "minutes of simulation: the sweep_simulated tests run it smaller",
    ),
];

/// The reason `command` cannot run in a test, from `NOT_RUN_IN_TESTS` or
/// the caller's own `more`.
pub fn not_run_in_tests(command: &str, more: &[(&str, &'static str)]) -> Option<&'static str> {
    NOT_RUN_IN_TESTS
        .iter()
        .chain(more)
        .find(|(word, _)| command.contains(word))
        .map(|(_, why)| *why)
}

/// A fresh folder holding the shipped recordings (`recordings/thesis-sim`)
/// and `profiles/` as links to the repository's, for documented commands
/// that name them; the caller adds what else its commands read.
pub fn shipped_workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("recordings")).unwrap();
    let repo = Path::new(REPO);
    std::os::unix::fs::symlink(
        repo.join("recordings/thesis-sim"),
        dir.path().join("recordings/thesis-sim"),
    )
    .unwrap();
    std::os::unix::fs::symlink(repo.join("profiles"), dir.path().join("profiles")).unwrap();
    dir
}

/// The binary, run from the repository (so `profiles/…` paths resolve).
pub fn hapticlab() -> Command {
    let mut c = Command::new(BIN);
    c.current_dir(REPO).env_remove("RUST_BACKTRACE");
    c
}

/// `hapticlab ARGS` from the repository, run to the end.
pub fn run<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Run {
    hapticlab()
        .args(args)
        .output()
        .expect("run hapticlab")
        .into()
}

/// `hapticlab ARGS` that must succeed, its standard output read as JSON.
pub fn json_of(args: &[&str]) -> serde_json::Value {
    let r = run(args);
    assert_eq!(r.code, Some(0), "{args:?}: {r:?}");
    serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"))
}

/// The thesis profile with three sub-windows along the stroke (14.7 mm
/// every 7.5 mm of the 29.7 mm window), 24 bins each, written to
/// `dir/windows.toml`.
pub fn thesis_windows_profile(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let text = text.replace(
        "\nbins = [1, 49]\n",
        "\nbins = [1, 24]\nwindows = { length = 0.0147, hop = 0.0075 }\n",
    );
    assert!(text.contains("windows = {"));
    let path = dir.join("windows.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A temporary path as a command-line argument.
pub fn p(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 temporary path")
}

/// The thesis's analysis with a window from 0 that gives `features`
/// features (bins 1..=features of a 300-point window).
pub fn analysis(features: usize) -> Analysis {
    Analysis {
        channel: "y_m".into(),
        axis: "x_m".into(),
        window: [0.0, 0.0897],
        spacing: 0.0003,
        detrend: Detrend::Mean,
        spectrum: SpectrumKind::Magnitude,
        bins: [1, features],
        ..Analysis::default()
    }
}

/// A labelled feature vector, as if read from `file`.
pub fn ex(file: &str, label: &str, features: &[f64]) -> TrainingExample {
    TrainingExample {
        file: file.into(),
        label: label.into(),
        features: features.to_vec(),
    }
}
