//! Every example in every command's `--help` runs as printed: the examples
//! are read from the help text itself (the lines under `Example:` or
//! `Examples:`), run by the shell in a temporary folder that holds the
//! shipped recordings and profiles, and must exit 0. Those that cannot run
//! here are named with the reason.

use std::path::Path;
use std::process::Command;

use crate::common::{BIN, REPO, not_run_in_tests, shipped_workspace};

/// Examples that cannot run in a test, by a word they contain, and why,
/// beyond `common::NOT_RUN_IN_TESTS`.
const SKIPPED: &[(&str, &str)] = &[
    ("thesis-falcon.toml", "needs a Novint Falcon on USB"),
    (
        "thesis-emulator.toml --yes",
        "a self-test, run by the emulator tests",
    ),
    ("recordings/lab", "a lab's own recordings"),
    ("rig/", "a rig's own files to import"),
    ("raw/", "a rig's own files to import"),
    ("sound/", "a rig's own files to import"),
    ("recordings/rig", "a rig's own recordings"),
    ("rec/finger", "a rig's own recordings"),
    ("rec/sound", "a rig's own recordings"),
];

fn help(args: &[&str]) -> String {
    let out = Command::new(BIN).args(args).arg("--help").output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{args:?} --help");
    String::from_utf8(out.stdout).unwrap()
}

/// The subcommands a help text lists under `Commands:`.
fn subcommands(text: &str) -> Vec<String> {
    text.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// The example command lines of a help text, comments dropped.
fn examples(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for l in text.lines() {
        if l.starts_with("Example:") || l.starts_with("Examples:") {
            inside = true;
        } else if inside && l.trim_start().starts_with("hapticlab") {
            let cmd = l.split("   #").next().unwrap_or(l).trim();
            out.push(cmd.to_string());
        } else if inside && !l.trim().is_empty() {
            inside = false;
        }
    }
    out
}

/// Every help text: the top one and each command's, nested commands too.
fn every_help() -> Vec<(String, String)> {
    let mut todo = vec![Vec::<String>::new()];
    let mut out = Vec::new();
    while let Some(path) = todo.pop() {
        let args: Vec<&str> = path.iter().map(String::as_str).collect();
        let text = help(&args);
        for c in subcommands(&text) {
            let mut p = path.clone();
            p.push(c);
            todo.push(p);
        }
        out.push((path.join(" "), text));
    }
    out
}

/// The arguments of an example that name the shipped recordings or
/// profiles, without the files the help's examples write (`--out`).
fn shipped_paths<'a>(example: &'a str, written: &[&str]) -> Vec<&'a str> {
    example
        .split_whitespace()
        .filter(|a| a.starts_with("recordings/thesis-sim") || a.starts_with("profiles/"))
        .filter(|a| !written.contains(a))
        .collect()
}

/// The files a help's examples write: the arguments after `--out`.
fn outputs(examples: &[String]) -> Vec<&str> {
    examples
        .iter()
        .flat_map(|ex| {
            let args: Vec<&str> = ex.split_whitespace().collect();
            let outs: Vec<&str> = args
                .windows(2)
                .filter(|w| w[0] == "--out")
                .map(|w| w[1])
                .collect();
            outs
        })
        .collect()
}

/// A fresh folder with the shipped recordings and profiles, and the model
/// `train`'s example writes (`classify`'s example reads it).
fn workspace(model: &Path) -> tempfile::TempDir {
    let dir = shipped_workspace();
    std::fs::copy(model, dir.path().join("thesis.model.json")).unwrap();
    dir
}

#[test]
fn every_example_in_every_help_runs_as_printed() {
    let models = tempfile::tempdir().unwrap();
    let model = models.path().join("thesis.model.json");
    let train = Command::new(BIN)
        .args(["train", "recordings/thesis-sim", "--out"])
        .arg(&model)
        .current_dir(REPO)
        .output()
        .unwrap();
    assert_eq!(train.status.code(), Some(0), "{train:?}");
    let bin_dir = Path::new(BIN).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let (mut ran, mut named) = (0, 0);
    for (name, text) in every_help() {
        // Each help's examples in order in a fresh folder (they may chain).
        let dir = workspace(&model);
        let examples = examples(&text);
        let written = outputs(&examples);
        // An example that trains the model writes it anew: outputs are
        // never replaced without --overwrite, so it is not there first.
        for w in &written {
            let _ = std::fs::remove_file(dir.path().join(w));
        }
        for ex in &examples {
            if let Some(why) = not_run_in_tests(ex, SKIPPED) {
                // Not run, but the shipped files it names are there as
                // printed (`S2_003.csv` where the file is `.csv.gz` failed).
                for arg in shipped_paths(ex, &written) {
                    assert!(
                        dir.path().join(arg).exists(),
                        "`hapticlab {name} --help`'s example names {arg}, which is not shipped: {ex}"
                    );
                    named += 1;
                }
                eprintln!("skipped ({why}): {ex}");
                continue;
            }
            let out = Command::new("sh")
                .arg("-c")
                .arg(ex)
                .current_dir(dir.path())
                .env("PATH", &path)
                .output()
                .unwrap();
            assert_eq!(
                out.status.code(),
                Some(0),
                "`hapticlab {name} --help`'s example failed: {ex}\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
            ran += 1;
        }
    }
    assert!(ran >= 12, "only {ran} examples ran");
    assert!(
        named >= 3,
        "only {named} shipped files named by skipped examples"
    );
}
