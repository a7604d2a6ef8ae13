//! Issue 19: nothing lost, nothing hung. No command writes over one of
//! its inputs or anything but a regular file, nor over a recording but
//! `import --force` and `simulate --overwrite`; a FIFO is never
//! read (skipped with a warning inside a dataset, refused when named); two
//! imports into one folder at once never mix.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use crate::common::run::Run;
use crate::common::{REPO, hapticlab, p, run};

/// Three recordings of each of two textures from the thesis set, in `dir/ds`.
fn small_dataset(dir: &Path) -> PathBuf {
    let ds = dir.join("ds");
    for label in ["S1", "S2"] {
        std::fs::create_dir_all(ds.join(label)).unwrap();
        for i in 1..=3 {
            let name = format!("{label}_{i:03}.csv.gz");
            std::fs::copy(
                Path::new(REPO)
                    .join("recordings/thesis-sim")
                    .join(label)
                    .join(&name),
                ds.join(label).join(&name),
            )
            .unwrap();
        }
    }
    ds
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(p(path)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "{path:?}");
}

/// Runs `hapticlab ARGS` to the end. A run that blocks (on a FIFO: the bug
/// these tests guard against) is killed after a generous minute so the
/// suite fails instead of hanging; this is a safety net, not a measure.
fn run_or_kill(args: &[&str]) -> Run {
    let mut child = hapticlab()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let r: Run = child.wait_with_output().unwrap().into();
            panic!("{args:?} blocked: {r:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap().into()
}

#[test]
fn features_and_train_never_write_over_an_input_or_a_recording() {
    let dir = tempfile::tempdir().unwrap();
    let ds = small_dataset(dir.path());
    let a0 = ds.join("S1/S1_001.csv.gz");
    let before = std::fs::read(&a0).unwrap();
    // One of its own inputs, named another way.
    let spelled = ds.join("S2/../S1/S1_001.csv.gz");
    for cmd in ["features", "train"] {
        let r = run(&[cmd, p(&ds), "--out", p(&spelled)]);
        assert_eq!(r.code, Some(2), "{cmd}: {r:?}");
        assert!(r.stderr.contains("S1_001.csv.gz"), "{cmd}: {r:?}");
        assert!(r.stderr.contains("own inputs"), "{cmd}: {r:?}");
    }
    assert_eq!(std::fs::read(&a0).unwrap(), before);
    // A recording elsewhere (plain text here), not an input: still refused.
    let other = dir.path().join("other.csv");
    let rec =
        std::fs::read_to_string(Path::new(REPO).join("tests/data/broken/missing_trailer.csv"))
            .unwrap();
    std::fs::write(&other, &rec).unwrap();
    let r = run(&["train", p(&ds), "--out", p(&other)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("is a recording"), "{r:?}");
    assert_eq!(std::fs::read_to_string(&other).unwrap(), rec);
    // The profile read is an input too.
    let profile = dir.path().join("prof.toml");
    std::fs::copy(Path::new(REPO).join("profiles/thesis.toml"), &profile).unwrap();
    let r = run(&["features", "-p", p(&profile), p(&ds), "--out", p(&profile)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("prof.toml"), "{r:?}");
    // A file of its own kind is replaced with --overwrite, never without.
    let table = dir.path().join("table.csv");
    std::fs::write(&table, "old\n").unwrap();
    let r = run(&["features", p(&ds), "--out", p(&table)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert_eq!(std::fs::read_to_string(&table).unwrap(), "old\n");
    let r = run(&["features", p(&ds), "--out", p(&table), "--overwrite"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        std::fs::read_to_string(&table)
            .unwrap()
            .starts_with("file,label")
    );
}

/// A profile is never written over a recording, `--overwrite` or not, and
/// the refusal says which commands do replace recordings; `import --force`
/// is one: it replaces the recording at the name it writes, which without
/// it is refused.
#[test]
fn only_the_commands_that_write_recordings_replace_one_and_only_when_told() {
    let dir = tempfile::tempdir().unwrap();
    let ds = small_dataset(dir.path());
    let rec = ds.join("S1/S1_001.csv.gz");
    let before = std::fs::read(&rec).unwrap();
    let r = run(&[
        "profile",
        "new",
        "--from",
        p(&ds),
        "--out",
        p(&rec),
        "--overwrite",
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    for s in [
        "this is a recording",
        "--overwrite included",
        "only import --force and simulate --overwrite replace recordings",
    ] {
        assert!(r.stderr.contains(s), "{s:?} missing: {r:?}");
    }
    assert!(!r.stderr.contains("--force included"), "{r:?}");
    assert_eq!(std::fs::read(&rec).unwrap(), before);

    let input = dir.path().join("trace.txt");
    let out = dir.path().join("out");
    let import = |values: &str, more: &[&str]| {
        std::fs::write(&input, values).unwrap();
        let mut args = vec!["import", "--rate", "100", "--label", "S", "--out", p(&out)];
        args.extend(more);
        args.push(p(&input));
        run(&args)
    };
    assert_eq!(import("1\n2\n", &[]).code, Some(0));
    let r = import("3\n4\n", &[]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr
            .contains("already exists (use --force to replace it)"),
        "{r:?}"
    );
    let r = import("3\n4\n", &["--force"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let again = hapticlab::recording::read(&out.join("S/trace.csv")).unwrap();
    assert_eq!(again.column("ch1").unwrap(), [3.0, 4.0]);
    let help = run(&["import", "--help"]).stdout;
    assert!(
        help.contains("Replace the recordings already at the names this import writes"),
        "{help}"
    );
}

#[test]
fn outputs_that_are_not_regular_files_are_refused_overwrite_or_not() {
    let dir = tempfile::tempdir().unwrap();
    let ds = small_dataset(dir.path());
    let fifo = dir.path().join("out.toml");
    mkfifo(&fifo);
    for out in ["/dev/null", p(&fifo), p(dir.path())] {
        let r = run_or_kill(&[
            "profile",
            "new",
            "--from",
            p(&ds),
            "--out",
            out,
            "--overwrite",
        ]);
        assert_eq!(r.code, Some(2), "{out}: {r:?}");
        assert!(r.stderr.contains("not a regular file"), "{out}: {r:?}");
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    let r = run_or_kill(&["features", p(&ds), "--out", "/dev/null"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    let r = run_or_kill(&["train", p(&ds), "--out", p(&fifo)]);
    assert_eq!(r.code, Some(2), "{r:?}");
}

#[test]
fn a_fifo_in_a_dataset_is_skipped_with_a_warning_and_one_named_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ds = small_dataset(dir.path());
    let fifo = ds.join("S1/zz.csv");
    mkfifo(&fifo);
    let model = dir.path().join("m.json");
    let table = dir.path().join("f.csv");
    let profile = dir.path().join("p.toml");
    for args in [
        vec!["features", p(&ds), "--out", p(&table)],
        vec!["train", p(&ds), "--out", p(&model)],
        vec!["evaluate", "--loo", p(&ds)],
        vec!["inspect", p(&ds)],
        vec!["profile", "new", "--from", p(&ds), "--out", p(&profile)],
        vec!["classify", "--model", p(&model), p(&ds)],
    ] {
        let r = run_or_kill(&args);
        assert_eq!(r.code, Some(0), "{args:?}: {r:?}");
        // A warning; inspect lists it among the unreadable in its report.
        let said = format!("{}{}", r.stderr, r.stdout);
        assert!(
            said.contains("zz.csv: not a regular file (a FIFO)"),
            "{args:?}: {r:?}"
        );
    }
    let fifo_json = dir.path().join("s.json");
    mkfifo(&fifo_json);
    let fifo_wav = dir.path().join("x.wav");
    mkfifo(&fifo_wav);
    let png = dir.path().join("x.png");
    for args in [
        vec!["classify", "--model", p(&model), p(&fifo)],
        vec!["classify", "--model", p(&fifo_json), p(&ds)],
        vec!["features", p(&fifo)],
        vec!["check", p(&fifo)],
        vec!["evaluate", "-p", p(&fifo), p(&ds)],
        vec!["plot", "sweep", p(&fifo_json), "--out", p(&png)],
        vec!["plot", "trace", p(&fifo), "--out", p(&png)],
        vec![
            "import",
            p(&fifo_wav),
            "--label",
            "A",
            "--out",
            p(&dir.path().join("imp")),
        ],
    ] {
        let r = run_or_kill(&args);
        assert_eq!(r.code, Some(2), "{args:?}: {r:?}");
        assert!(r.stderr.contains("not a regular file"), "{args:?}: {r:?}");
    }
}

/// `n` CSVs `t{i}.csv` of one channel, each value `value`, in `dir`.
fn csv_batch(dir: &Path, n: usize, value: &str) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).unwrap();
    (0..n)
        .map(|i| {
            let f = dir.join(format!("t{i:02}.csv"));
            let rows: String = (0..50)
                .map(|k| format!("{},{value}\n", k as f64 / 1000.0))
                .collect();
            std::fs::write(&f, format!("time,v\n{rows}")).unwrap();
            f
        })
        .collect()
}

fn import(files: &[PathBuf], out: &Path) -> Command {
    let mut c = hapticlab();
    c.args([
        "import",
        "--label",
        "A",
        "--time-column",
        "time",
        "--out",
        p(out),
    ])
    .args(files)
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    c
}

/// Every recording under `out/A`, by the input it came from (`source`).
fn sources(out: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(out.join("A")) else {
        return Vec::new();
    };
    entries
        .map(|e| {
            let rec = hapticlab::recording::read(&e.unwrap().path()).unwrap();
            let src = rec.meta_str("source").unwrap();
            Path::new(src).parent().unwrap().display().to_string()
        })
        .collect()
}

#[test]
fn two_imports_of_the_same_names_at_once_never_mix() {
    for round in 0..4 {
        let dir = tempfile::tempdir().unwrap();
        let one = csv_batch(&dir.path().join("one"), 20, "1");
        let two = csv_batch(&dir.path().join("two"), 20, "2");
        let out = dir.path().join("out");
        let children: Vec<Child> = [&one, &two]
            .map(|files| import(files, &out).spawn().unwrap())
            .into_iter()
            .collect();
        let runs: Vec<Run> = children
            .into_iter()
            .map(|c| c.wait_with_output().unwrap().into())
            .collect();
        let ok = runs.iter().filter(|r| r.code == Some(0)).count();
        for r in runs.iter().filter(|r| r.code != Some(0)) {
            assert_eq!(r.code, Some(2), "round {round}: {r:?}");
            assert!(r.stderr.contains("already exists"), "round {round}: {r:?}");
            assert!(r.stderr.contains(".csv"), "round {round}: {r:?}");
        }
        let found = sources(&out);
        // One batch whole, or (both refused) none: never a mix.
        assert!(ok <= 1, "round {round}: both imported: {runs:?}");
        assert_eq!(
            found.len(),
            if ok == 1 { 20 } else { 0 },
            "round {round}: {found:?}"
        );
        assert!(
            found.windows(2).all(|w| w[0] == w[1]),
            "round {round}: {found:?}"
        );
    }
}

#[test]
fn an_import_that_meets_a_name_taken_removes_only_what_it_placed() {
    let dir = tempfile::tempdir().unwrap();
    let one = csv_batch(&dir.path().join("one"), 5, "1");
    let two = csv_batch(&dir.path().join("two"), 5, "2");
    let out = dir.path().join("out");
    // The first batch holds t03 only: the second places t00..t02, meets
    // t03 taken at the very end, and takes its own three back.
    let r: Run = import(&one[3..4], &out).output().unwrap().into();
    assert_eq!(r.code, Some(0), "{r:?}");
    let r: Run = import(&two, &out).output().unwrap().into();
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("t03.csv: already exists"), "{r:?}");
    let found = sources(&out);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].ends_with("one"), "{found:?}");
}
