//! `import` of headerless text, NumPy `.npy`/`.npz` and MATLAB `.mat` v5
//! (tests/data/formats, written by its make.py): the channels, names and
//! values each holds; a v7.3 `.mat` and a damaged file refused (exit 2)
//! with nothing written.

use std::fs;
use std::path::Path;

use hapticlab::recording;

use crate::common::{REPO, p, run};

fn sine(i: usize) -> f64 {
    let v = (std::f64::consts::TAU * 50.0 * i as f64 / 1000.0).sin();
    (v * 1000.0).round() / 1000.0
}

/// Imports `file` at 1 kHz (with `more` flags); the recording written.
fn import(dir: &Path, file: &str, more: &[&str]) -> recording::Recording {
    let src = Path::new(REPO).join("tests/data/formats").join(file);
    let out = dir.join(file.replace('.', "-"));
    let mut args = vec![
        "import",
        p(&src),
        "--rate",
        "1000",
        "--label",
        "x",
        "--out",
        p(&out),
    ];
    args.extend(more);
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{file}: {r:?}");
    let written = out
        .join("x")
        .join(format!("{}.csv", file.split('.').next().unwrap()));
    recording::read(&written).unwrap()
}

#[test]
fn text_numpy_and_matlab_files_import_with_their_channels() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let col = |r: &recording::Recording, c: &str| {
        r.data[r.columns.iter().position(|x| x == c).unwrap()].clone()
    };
    let want: Vec<f64> = (0..300).map(sine).collect();

    let r = import(d, "lmt.txt", &[]);
    assert_eq!(r.columns, ["t_s", "ch1"]);
    assert_eq!(col(&r, "ch1"), want);
    assert_eq!(r.data[0][299], 0.299);
    let r = import(d, "multi.txt", &["--names", "ax,ay,az"]);
    assert_eq!(r.columns, ["t_s", "ax", "ay", "az"]);
    assert_eq!(
        col(&r, "az")[5],
        3.0,
        "sin(pi/2) tripled, as the text has it"
    );

    let r = import(d, "one.npy", &[]);
    assert_eq!(
        (r.columns.clone(), col(&r, "ch1")),
        (vec!["t_s".into(), "ch1".into()], want.clone())
    );
    let r = import(d, "two.npy", &["--names", "up,down"]);
    assert_eq!(col(&r, "down")[299], -299.0);
    let r = import(d, "arrays.npz", &[]);
    assert_eq!(r.columns, ["t_s", "acc", "force"]);
    assert_eq!((col(&r, "acc"), col(&r, "force")[3]), (want.clone(), 1.5));
    assert_eq!(r.meta_f64("fs"), Some(1000.0), "a scalar array is metadata");

    let r = import(d, "signal.mat", &[]);
    assert_eq!(r.columns, ["t_s", "acc", "force"]);
    assert_eq!(
        (col(&r, "acc"), col(&r, "force")[299]),
        (want.clone(), 299.0)
    );
    assert_eq!(r.meta_f64("fs"), Some(1000.0));
    let r = import(d, "compressed.mat", &[]);
    assert_eq!(r.columns, ["t_s", "acc", "xyz_1", "xyz_2", "xyz_3"]);
    assert_eq!(col(&r, "xyz_3")[5], 3.0 * want[5]);
}

#[test]
fn a_v73_mat_a_damaged_npy_and_a_missing_rate_are_refused_writing_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let data = Path::new(REPO).join("tests/data/formats");
    let r = run(&[
        "import",
        p(&data.join("v73.mat")),
        "--rate",
        "1000",
        "--label",
        "x",
        "--out",
        p(&out),
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("v7.3") && r.stderr.contains("-v7") && r.stderr.contains("csv"),
        "{r:?}"
    );
    let cut = dir.path().join("cut.npy");
    let bytes = fs::read(data.join("one.npy")).unwrap();
    fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let r = run(&[
        "import",
        p(&cut),
        "--rate",
        "1000",
        "--label",
        "x",
        "--out",
        p(&out),
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("cut.npy") && r.stderr.contains("more data than the file holds"),
        "{r:?}"
    );
    let r = run(&[
        "import",
        p(&data.join("one.npy")),
        "--label",
        "x",
        "--out",
        p(&out),
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("one.npy") && r.stderr.contains("--rate"),
        "{r:?}"
    );
    assert!(!out.exists(), "nothing written");
}
