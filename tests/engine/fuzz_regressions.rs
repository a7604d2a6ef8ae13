//! The fuzz targets' inputs, on the stable toolchain: every crasher kept
//! under `tests/fuzz-regressions/<target>/` and every seed under
//! `fuzz/seeds/<target>/` goes through the same entry point as in
//! `cargo fuzz run <target>` (`fuzz/src/lib.rs`), which must return `Ok` or
//! `Err`, never panic nor break an invariant it checks.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use crate::entries;

type Entry = fn(&[u8]) -> entries::Outcome;

/// The files in `dir`, sorted; none when the folder does not exist.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .map(|e| e.expect("a readable folder entry").path())
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default();
    found.sort();
    found
}

/// Runs every seed and kept crasher of `target`; the seeds must include at
/// least one input the library accepts and one it refuses.
fn run(target: &str, entry: Entry) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let seeds = files(&root.join("fuzz/seeds").join(target));
    let crashers = files(&root.join("tests/fuzz-regressions").join(target));
    assert!(!seeds.is_empty(), "no seeds for {target}");
    let (mut accepted, mut refused, mut panicked) = (0, 0, Vec::new());
    for path in seeds.iter().chain(&crashers) {
        let bytes = std::fs::read(path).expect("a readable input");
        match catch_unwind(AssertUnwindSafe(|| entry(&bytes))) {
            Ok(Ok(())) => accepted += 1,
            Ok(Err(message)) => {
                assert!(!message.is_empty(), "{}: an empty message", path.display());
                refused += 1;
            }
            Err(_) => panicked.push(path.display().to_string()),
        }
    }
    assert!(panicked.is_empty(), "{target}: panicked on {panicked:?}");
    assert!(
        accepted > 0 && refused > 0,
        "{target}: {accepted} accepted and {refused} refused of {} inputs",
        seeds.len() + crashers.len()
    );
}

#[test]
fn recording() {
    run("recording", entries::recording);
}

#[test]
fn profile() {
    run("profile", entries::profile);
}

#[test]
fn falcon_packet() {
    run("falcon_packet", entries::falcon_packet);
}

#[test]
fn import_csv() {
    run("import_csv", entries::import_csv);
}

#[test]
fn import_wav() {
    run("import_wav", entries::import_wav);
}

#[test]
fn import_text() {
    run("import_text", entries::import_text);
}

#[test]
fn import_numpy() {
    run("import_numpy", entries::import_numpy);
}

#[test]
fn import_mat() {
    run("import_mat", entries::import_mat);
}
