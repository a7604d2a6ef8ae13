//! Recordings that are malformed, incomplete or cut short, and runtime
//! failures: each refused or reported in one line naming the file (and
//! line), with the exit code of the contract.

use std::fs;
use std::path::{Path, PathBuf};

use serde_json::Value;
use tempfile::TempDir;

use crate::cli::{assert_error, assert_ok, copy_tree, recordings, simulate, small_profile};
use crate::common::run::Run;
use crate::common::{hapticlab, p, run};

// ---------------------------------------------------------------- bad recordings

/// Lines of a recording and the 1-based line number of its `n`th data row.
fn lines_and_row(path: &Path, n: usize) -> (Vec<String>, usize) {
    let lines: Vec<String> = fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let header = lines.iter().position(|l| l.starts_with("t_s,")).unwrap();
    (lines, header + 1 + n)
}

#[test]
fn malformed_recordings_are_refused_with_file_and_line() {
    let dir = TempDir::new().unwrap();
    let base = dir.path().join("base");
    simulate(&base, 3, 9);
    let profile = small_profile(dir.path(), 2, 1, 1);

    // Each case: a copy of the dataset with one file broken; the file and
    // line the message must name.
    type Breaker = fn(&Path) -> (PathBuf, usize);
    let cases: [(&str, Breaker); 3] = [
        ("not-a-recording", |d| {
            let f = d.join("S2").join("notes.csv");
            fs::write(&f, "name,value\nspeed,0.01\n").unwrap();
            (f, 1)
        }),
        ("short-row", |d| {
            let f = d.join("S3").join("S3_002.csv");
            let (mut lines, line) = lines_and_row(&f, 40);
            let cells: Vec<&str> = lines[line - 1].split(',').collect();
            lines[line - 1] = cells[..5].join(",");
            fs::write(&f, lines.join("\n") + "\n").unwrap();
            (f, line)
        }),
        ("non-numeric", |d| {
            let f = d.join("S4").join("S4_001.csv");
            let (mut lines, line) = lines_and_row(&f, 1234);
            let mut cells: Vec<String> = lines[line - 1].split(',').map(String::from).collect();
            cells[2] = "-0.00x4".into();
            lines[line - 1] = cells.join(",");
            fs::write(&f, lines.join("\n") + "\n").unwrap();
            (f, line)
        }),
    ];
    for (name, breaker) in cases {
        let d = dir.path().join(name);
        copy_tree(&base, &d);
        let (file, line) = breaker(&d);
        let at = format!("{}:{line}:", file.display());
        let out = dir.path().join(format!("{name}.csv"));
        let msg = assert_error(&run(&["features", p(&d), "--out", p(&out)]), 2);
        assert!(msg.starts_with(&at), "{name}: expected {at}…, got {msg}");
        assert!(!out.exists(), "{name}: features wrote output anyway");
        let msg = assert_error(&run(&["evaluate", "--profile", p(&profile), p(&d)]), 2);
        assert!(msg.starts_with(&at), "{name}: expected {at}…, got {msg}");
    }
}

/// Remove a recording's `# end samples` trailer (every sample kept): it
/// then reads as incomplete.
fn drop_trailer(path: &Path) {
    let text = fs::read_to_string(path).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("# end samples"))
        .collect();
    assert_eq!(kept.len() + 1, text.lines().count());
    fs::write(path, kept.join("\n") + "\n").unwrap();
}

#[test]
fn incomplete_recordings_are_skipped_with_a_warning() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 4, 10);
    // Drop the trailer: the scan reads as incomplete.
    let cut = data.join("S2").join("S2_002.csv");
    drop_trailer(&cut);
    // What `kill -9` mid-write leaves: no trailer, the last row cut short.
    let torn = data.join("S3").join("S3_002.csv");
    let (lines, line) = lines_and_row(&torn, 500);
    let mut text = lines[..line - 1].join("\n");
    text.push('\n');
    text.push_str(&lines[line - 1][..12]);
    fs::write(&torn, text).unwrap();

    let out = dir.path().join("F.csv");
    let r = run(&["features", p(&data), "--out", p(&out)]);
    assert_ok(&r);
    let warnings: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 2, "{r:?}");
    assert!(warnings.iter().all(|w| w.contains("incomplete")), "{r:?}");
    assert!(warnings.iter().any(|w| w.contains(p(&cut))), "{r:?}");
    assert!(
        warnings
            .iter()
            .any(|w| w.contains(p(&torn)) && w.contains("cut short")),
        "{r:?}"
    );
    let csv = fs::read_to_string(&out).unwrap();
    assert_eq!(csv.lines().count(), 1 + 14);
    assert!(!csv.contains(p(&cut)));

    let profile = small_profile(dir.path(), 2, 1, 1);
    let r = run(&["evaluate", "--profile", p(&profile), "--json", p(&data)]);
    assert_ok(&r);
    assert!(r.stderr.contains(p(&cut)), "{r:?}");
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let used: Vec<&str> = ["train", "test"]
        .iter()
        .flat_map(|k| v[k].as_array().unwrap())
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(used.len(), 12);
    assert!(!used.contains(&p(&cut)));
}

/// `classify` of an aborted scan: classified (with a warning) when its
/// samples cover the window; one error naming both the window and the abort
/// when they do not — never a warning followed by an error.
#[test]
fn classify_says_why_an_aborted_scan_cannot_be_classified() {
    let dir = TempDir::new().unwrap();
    let data = dir.path().join("D");
    simulate(&data, 3, 10);
    let model = dir.path().join("m.json");
    assert_ok(&run(&["train", p(&data), "--out", p(&model)]));
    // The trailer dropped: every sample is there.
    let whole = data.join("S2").join("S2_001.csv");
    drop_trailer(&whole);
    let r = run(&["classify", "--model", p(&model), p(&whole)]);
    assert_ok(&r);
    assert!(r.stdout.contains("S2"), "{r:?}");
    assert!(
        r.stderr.contains("incomplete scan") && r.stderr.contains("classified anyway"),
        "{r:?}"
    );
    // Cut after 300 rows, before the probe reaches the window.
    let short = data.join("S3").join("S3_001.csv");
    let (lines, line) = lines_and_row(&short, 300);
    fs::write(&short, lines[..line].join("\n") + "\n").unwrap();
    // (The model's note on k comes first: 3 scans per texture.)
    let r = run(&["classify", "--model", p(&model), p(&short)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(!r.stderr.contains("warning"), "{r:?}");
    let msg = r
        .stderr
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("hapticlab: error: "))
        .unwrap_or_else(|| panic!("no error line last: {r:?}"));
    assert!(
        msg.starts_with(p(&short))
            && msg.contains("window needs")
            && msg.contains("incomplete scan"),
        "{msg}"
    );
}

// ---------------------------------------------------------------- runtime failures

#[test]
fn simulate_into_a_read_only_folder_fails_with_exit_1() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;

    let dir = TempDir::new().unwrap();
    let ro = dir.path().join("read-only");
    fs::create_dir(&ro).unwrap();
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).unwrap();
    let mut cmd = hapticlab();
    cmd.args(["simulate", "--out", p(&ro), "--per-class", "1"]);
    let probe = ro.join("probe");
    if fs::write(&probe, b"").is_ok() {
        // Root writes anywhere: run the binary as `nobody` instead, if it can.
        fs::remove_file(&probe).unwrap();
        if unsafe { libc::geteuid() } != 0 {
            eprintln!("skipped: the read-only folder is writable");
            return;
        }
        fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o755)).unwrap();
        cmd.uid(65534).gid(65534);
    }
    let r: Run = match cmd.output() {
        Ok(o) => o.into(),
        // `nobody` cannot reach the binary (a checkout under a private
        // folder, as `mktemp -d` makes): nothing to prove here.
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => {
            fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
            eprintln!("skipped: `nobody` cannot run the binary here: {e}");
            return;
        }
        Err(e) => panic!("run hapticlab: {e}"),
    };
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
    if r.code == Some(0) && unsafe { libc::geteuid() } == 0 {
        eprintln!("skipped: even `nobody` could write the read-only folder: {r:?}");
        return;
    }
    let msg = assert_error(&r, 1);
    assert!(msg.contains(p(&ro)), "{msg}");
    assert!(msg.contains("permission denied"), "{msg}");
    assert_eq!(recordings(&ro).len(), 0);
}
