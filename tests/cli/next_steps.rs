//! A newcomer's first commands on their own data point to the next step:
//! the built-in thesis profile on another rig's recordings, and another
//! rig's files where recordings are expected.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use crate::common::{p, run};

/// Two labels × four recordings v1 of `t_s,ch1` at 1 kHz, as `import` writes.
fn rig_recordings(dir: &Path) {
    for label in ["a", "b"] {
        fs::create_dir_all(dir.join(label)).unwrap();
        for i in 0..4 {
            let mut s = format!("# hapticlab recording v1\n# label = \"{label}\"\nt_s,ch1\n");
            for j in 0..500 {
                let _ = writeln!(s, "{:.3},{}", j as f64 / 1000.0, (j * (i + 3)) % 11);
            }
            s.push_str("# end samples = 500\n");
            fs::write(dir.join(label).join(format!("{label}-{i}.csv")), s).unwrap();
        }
    }
}

#[test]
fn evaluate_without_a_profile_on_another_rigs_recordings_says_to_give_or_make_one() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("csv");
    rig_recordings(&rec);
    let r = run(&["evaluate", p(&rec)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    for said in [
        "no column `x_m`: the recordings have columns t_s, ch1",
        "the built-in thesis profile (used when no -p is given) analyses y_m along x_m",
        "give their profile with -p P.toml",
        &format!("hapticlab profile new --from {} --out P.toml", p(&rec)),
    ] {
        assert!(r.stderr.contains(said), "{said:?} not in {r:?}");
    }
    assert_eq!(r.stderr.lines().count(), 1, "{r:?}");
    // features and train say the same.
    let model = dir.path().join("m.json");
    for args in [
        vec!["features", p(&rec)],
        vec!["train", p(&rec), "--out", p(&model)],
    ] {
        let r = run(&args);
        assert_eq!(r.code, Some(2), "{r:?}");
        assert!(
            r.stderr.contains("give their profile with -p P.toml"),
            "{r:?}"
        );
    }
}

#[test]
fn inspect_without_a_profile_says_the_reason_once_and_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("csv");
    rig_recordings(&rec);
    let r = run(&["inspect", p(&rec)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let unusable: Vec<&str> = r
        .stdout
        .lines()
        .filter(|l| l.starts_with("unusable: "))
        .collect();
    assert_eq!(unusable.len(), 1, "{r:?}");
    assert!(
        unusable[0]
            .starts_with("unusable: 8 recordings: no column `x_m` (the recording has t_s, ch1) (")
            && unusable[0].ends_with(" and 5 more)"),
        "{r:?}"
    );
    assert!(
        r.stderr.contains(&format!(
            "warning: none of the 8 recordings could be analysed by the built-in thesis profile (used when no -p is given; it analyses y_m along x_m of the thesis's Falcon scans): give their profile with -p P.toml, or make one: hapticlab profile new --from {} --out P.toml",
            p(&rec)
        )),
        "{r:?}"
    );
}

#[test]
fn profile_new_on_another_rigs_files_suggests_import() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("raw");
    fs::create_dir_all(raw.join("a")).unwrap();
    fs::write(raw.join("a").join("t1.csv"), "time,acc\n0.0,1\n0.001,2\n").unwrap();
    let out = dir.path().join("p.toml");
    let r = run(&["profile", "new", "--from", p(&raw), "--out", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    for said in [
        "t1.csv:1: not a hapticlab recording",
        "convert other rigs' files first: hapticlab import FILE... --out DIR (CSV, headerless text, WAV, NumPy .npy/.npz, MATLAB .mat v5;",
    ] {
        assert!(r.stderr.contains(said), "{said:?} not in {r:?}");
    }
    // A folder with no *.csv at all (WAVs, say) is pointed the same way.
    let wavs = dir.path().join("wavs");
    fs::create_dir_all(&wavs).unwrap();
    fs::write(wavs.join("x.wav"), b"RIFF").unwrap();
    let r = run(&["profile", "new", "--from", p(&wavs), "--out", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("hapticlab import FILE..."), "{r:?}");
    // A binary file named as a recording (an .npz, say) too, in evaluate.
    let npz = dir.path().join("x.npz");
    fs::write(&npz, b"PK\x03\x04\x14\x00\xff\xfe").unwrap();
    let r = run(&["evaluate", p(&npz)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("invalid UTF-8") && r.stderr.contains("hapticlab import FILE..."),
        "{r:?}"
    );
}
