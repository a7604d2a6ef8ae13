//! Nothing lost, round four: `import --force` removes only the recordings
//! import itself wrote from the same input, a folder holds one cut of each
//! input, two runs into one place never lose either's output (two real
//! processes), and outputs are created no-clobber without `--overwrite`.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Stdio;

use hapticlab::recording;

use crate::common::{hapticlab, p, run};

/// A headered one-channel CSV of `seconds` at 100 Hz at `path`.
fn trace(path: &Path, seconds: usize, seed: u64) {
    let mut s = String::from("acc\n");
    let mut x = seed;
    for _ in 0..seconds * 100 {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let _ = writeln!(s, "{}", (x >> 54) as i64 - 512);
    }
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    fs::write(path, s).unwrap();
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    n.sort();
    n
}

fn import(args: &[&str]) -> crate::common::run::Run {
    let mut a = vec!["import", "--rate", "100"];
    a.extend_from_slice(args);
    run(&a)
}

/// A recording that is not an import: what the simulator writes.
const SIM_RECORDING: &str = "# hapticlab recording v1\n# label = \"S1\"\n# device = \"sim\"\n\
                             # rate_hz = 100.0\nt_s,acc\n0.00,1\n0.01,2\n# end samples = 2\n";

#[test]
fn force_removes_only_the_recordings_import_wrote_from_the_same_input() {
    let dir = tempfile::tempdir().unwrap();
    let (src, other, out) = (
        dir.path().join("s/S1/long.csv"),
        dir.path().join("other/S1/long.csv"),
        dir.path().join("o"),
    );
    trace(&src, 6, 1);
    trace(&other, 6, 2);
    let r = import(&[p(&src), "--out", p(&out), "--split", "2"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let s1 = out.join("S1");
    assert_eq!(
        names(&s1),
        ["long-seg001.csv", "long-seg002.csv", "long-seg003.csv"]
    );
    // Files with a trial's name that import did not write from this input.
    let elsewhere = dir.path().join("elsewhere.csv");
    fs::write(&elsewhere, SIM_RECORDING).unwrap();
    let planted = [
        ("long-seg007.csv", "what,when\nrecalibrated,monday\n"),
        ("long-seg0099.csv", SIM_RECORDING),
    ];
    for (n, text) in planted {
        fs::write(s1.join(n), text).unwrap();
    }
    std::os::unix::fs::symlink(&elsewhere, s1.join("long-seg0042.csv")).unwrap();

    // The whole input, --force: its own trials go (each said), nothing else.
    let r = import(&[p(&src), "--out", p(&out), "--force"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stderr.contains("removed 3 recording(s)")
            && r.stderr
                .contains("long-seg001.csv, long-seg002.csv, long-seg003.csv"),
        "{r:?}"
    );
    assert_eq!(
        names(&s1),
        [
            "long-seg0042.csv",
            "long-seg007.csv",
            "long-seg0099.csv",
            "long.csv"
        ]
    );
    for (n, text) in planted {
        assert_eq!(fs::read_to_string(s1.join(n)).unwrap(), text);
    }
    assert!(
        fs::symlink_metadata(s1.join("long-seg0042.csv"))
            .unwrap()
            .is_symlink()
    );
    assert_eq!(fs::read_to_string(&elsewhere).unwrap(), SIM_RECORDING);
    let whole = recording::read(&s1.join("long.csv")).unwrap();
    assert!(
        whole
            .meta_str("source_sha256")
            .is_some_and(|h| h.len() == 64)
    );
    assert_eq!(
        whole.meta_f64("source_bytes"),
        Some(fs::metadata(&src).unwrap().len() as f64)
    );

    // Another file of the same name: --force does not replace its namesake,
    // and nothing is imported.
    let before = fs::read(s1.join("long.csv")).unwrap();
    let r = import(&[p(&other), "--out", p(&out), "--force"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr
            .contains("--force replaces only recordings imported from")
            && r.stderr.contains(&format!("imported from {}", p(&src))),
        "{r:?}"
    );
    assert_eq!(fs::read(s1.join("long.csv")).unwrap(), before);
    // Cut from the other file, --force: its trials are placed, the whole
    // recording of the first file stays.
    let r = import(&[p(&other), "--out", p(&out), "--force", "--split", "3"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(!r.stderr.contains("removed"), "{r:?}");
    assert_eq!(fs::read(s1.join("long.csv")).unwrap(), before);

    // The first file cut again, --force: the other file's trials sit at
    // the names it writes, and are not its own to replace.
    let r = import(&[p(&src), "--out", p(&out), "--force", "--split", "1"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("long-seg001.csv")
            && r.stderr.contains(&format!("imported from {}", p(&other))),
        "{r:?}"
    );
    assert_eq!(fs::read(s1.join("long.csv")).unwrap(), before);

    // A notes file at a name this import writes: refused even with --force.
    let out2 = dir.path().join("o2");
    fs::create_dir_all(out2.join("S1")).unwrap();
    fs::write(out2.join("S1/long-seg002.csv"), planted[0].1).unwrap();
    let r = import(&[p(&src), "--out", p(&out2), "--force", "--split", "1"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("long-seg002.csv") && r.stderr.contains("it is no recording"),
        "{r:?}"
    );
    assert_eq!(names(&out2.join("S1")), ["long-seg002.csv"]);
}

#[test]
fn a_second_cut_of_an_input_without_force_is_refused_naming_the_first() {
    let dir = tempfile::tempdir().unwrap();
    let (src, out) = (dir.path().join("S1/long.csv"), dir.path().join("o"));
    trace(&src, 4, 3);
    let r = import(&[p(&src), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let r = import(&[p(&src), "--out", p(&out), "--split", "2"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains(p(&out.join("S1/long.csv"))) && r.stderr.contains("--force"),
        "{r:?}"
    );
    assert_eq!(names(&out.join("S1")), ["long.csv"]);
    // The reverse: trials first, then the whole.
    let out2 = dir.path().join("o2");
    assert_eq!(
        import(&[p(&src), "--out", p(&out2), "--split", "1"]).code,
        Some(0)
    );
    let r = import(&[p(&src), "--out", p(&out2)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("4 recordings"), "{r:?}");
    assert_eq!(names(&out2.join("S1")).len(), 4);
}

/// Each recording in `dir` with its `segment_length_s`.
fn cut_lengths(dir: &Path) -> Vec<f64> {
    names(dir)
        .iter()
        .map(|n| {
            recording::read(&dir.join(n))
                .unwrap()
                .meta_f64("segment_length_s")
                .unwrap()
        })
        .collect()
}

#[test]
fn two_imports_into_one_folder_at_once_leave_one_whole_cut() {
    let dir = tempfile::tempdir().unwrap();
    let src: Vec<PathBuf> = (0..4)
        .map(|i| {
            let f = dir.path().join(format!("S1/long{i}.csv"));
            trace(&f, 60, 10 + i);
            f
        })
        .collect();
    let out = dir.path().join("o");
    for round in 0..3 {
        let spawn = |split: &str| {
            let mut c = hapticlab();
            c.args([
                "import", "--rate", "100", "--force", "--split", split, "--out",
            ])
            .arg(&out)
            .args(&src)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
            c.spawn().unwrap()
        };
        let (a, b) = (spawn("1"), spawn("2"));
        let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
        for o in [&a, &b] {
            assert_eq!(
                o.status.code(),
                Some(0),
                "round {round}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        let lengths = cut_lengths(&out.join("S1"));
        let one = lengths[0];
        assert!(
            lengths.iter().all(|&l| l == one),
            "round {round}: two cuts mixed: {lengths:?}"
        );
        let per_input = (60.0 / one) as usize;
        assert_eq!(
            lengths.len(),
            4 * per_input,
            "round {round}: a cut not whole"
        );
    }
}

#[test]
fn two_runs_writing_one_output_at_once_never_replace_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new("tests/data/small/two-labels");
    for round in 0..4 {
        let out = dir.path().join(format!("f{round}.csv"));
        let spawn = || {
            let mut c = hapticlab();
            c.args(["features", "-p", "tests/data/small/tiny.toml"])
                .arg(data)
                .arg("--out")
                .arg(&out)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped());
            c.spawn().unwrap()
        };
        let (a, b) = (spawn(), spawn());
        let outs = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
        let codes: Vec<Option<i32>> = outs.iter().map(|o| o.status.code()).collect();
        let mut sorted = codes.clone();
        sorted.sort();
        assert_eq!(sorted, [Some(0), Some(2)], "round {round}: {codes:?}");
        let refused = outs.iter().find(|o| o.status.code() == Some(2)).unwrap();
        let msg = String::from_utf8_lossy(&refused.stderr);
        assert!(
            msg.contains(p(&out)) && msg.contains("already exists"),
            "round {round}: {msg}"
        );
    }
}

#[test]
fn outputs_are_never_replaced_without_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let data = "tests/data/small/two-labels";
    let tiny = "tests/data/small/tiny.toml";
    let kept = "a note kept by hand\n";
    let cases: Vec<(PathBuf, Vec<String>)> = vec![
        (
            dir.path().join("f.csv"),
            vec!["features".into(), "-p".into(), tiny.into(), data.into()],
        ),
        (
            dir.path().join("m.json"),
            vec!["train".into(), "-p".into(), tiny.into(), data.into()],
        ),
        (
            dir.path().join("p.toml"),
            vec!["profile".into(), "new".into(), "--from".into(), data.into()],
        ),
        (
            dir.path().join("c.svg"),
            vec![
                "plot".into(),
                "features".into(),
                "-p".into(),
                tiny.into(),
                data.into(),
            ],
        ),
    ];
    for (out, args) in &cases {
        fs::write(out, kept).unwrap();
        let mut a = args.clone();
        a.extend(["--out".into(), p(out).into()]);
        let r = run(&a);
        assert_eq!(r.code, Some(2), "{a:?}: {r:?}");
        assert!(
            r.stderr.contains("already exists") && r.stderr.contains("--overwrite"),
            "{a:?}: {r:?}"
        );
        assert_eq!(fs::read_to_string(out).unwrap(), kept, "{a:?}");
        a.push("--overwrite".into());
        let r = run(&a);
        assert_eq!(r.code, Some(0), "{a:?}: {r:?}");
        assert_ne!(fs::read_to_string(out).unwrap(), kept, "{a:?}");
    }
}

#[test]
fn plot_refuses_what_it_cannot_draw_truly() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(&[
        "plot",
        "features",
        "-p",
        "tests/data/small/tiny.toml",
        "tests/data/small/two-labels",
        "--per-class",
        "0",
        "--out",
        p(&dir.path().join("f.png")),
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    for (report, said) in [
        (
            r#"{"labels":["a","b"],"confusion":[[-1,0],[0,2]],"accuracy":1.0}"#,
            "-1, which is no count",
        ),
        (
            r#"{"labels":["a","b"],"confusion":[[1,0],[0,1]],"accuracy":5.0}"#,
            "accuracy 5",
        ),
        (r#"{"labels":[],"confusion":[],"accuracy":1.0}"#, "no label"),
        (
            r#"{"labels":["a","b"],"confusion":[[0,3],[3,0]],"accuracy":1.0}"#,
            "0 of 6 right",
        ),
    ] {
        let f = dir.path().join("r.json");
        fs::write(&f, report).unwrap();
        let out = dir.path().join("c.png");
        let r = run(&["plot", "confusion", p(&f), "--out", p(&out)]);
        assert_eq!(r.code, Some(2), "{report}: {r:?}");
        assert!(r.stderr.contains(said), "{report}: {r:?}");
        assert!(!out.exists());
    }
}

/// Standard output to a full disk is a failure (exit 1, said), for every
/// command that prints; a closed pipe stays quiet.
#[test]
fn output_lost_to_a_full_disk_is_a_failure() {
    if !Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        vec!["doctor", "--udev-rule"],
        vec![
            "features",
            "-p",
            "tests/data/small/tiny.toml",
            "tests/data/small/two-labels",
        ],
        vec!["check", "thesis"],
    ] {
        let full = fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = hapticlab().args(&args).stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("standard output could not be written"),
            "{args:?}: {err}"
        );
    }
    // A reader that goes away: quiet, and no failure.
    let mut c = hapticlab()
        .args(["doctor", "--udev-rule"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(c.stdout.take());
    let o = c.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(o.stderr.is_empty(), "{o:?}");
}

/// `doctor --dataset` on a symlink that leads nowhere says so (the console
/// refuses it), never that the folder can be created.
#[test]
fn doctor_names_a_dataset_symlink_that_leads_nowhere() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ds");
    std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).unwrap();
    let r = run(&["doctor", "--dataset", p(&link)]);
    assert!(
        r.stdout.contains("symlink that leads nowhere") && !r.stdout.contains("can be created"),
        "{r:?}"
    );
}

/// A trial too short to hold a sample says it holds none, never "-0".
#[test]
fn a_split_too_short_for_a_sample_says_it_holds_none() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("S1/long.csv");
    trace(&src, 2, 5);
    let r = import(&[
        p(&src),
        "--out",
        p(&dir.path().join("o")),
        "--split",
        "1e-300",
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("holds 0 sample(s)"), "{r:?}");
}
