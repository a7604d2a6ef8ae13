//! `--version` names the commit the binary was built from (or says it is
//! unknown), and the same line is what a recording's `software`, a model's
//! `software_version` and a tuned profile's comment say; files written
//! before the commit was recorded (`software = "hapticlab 0.1.0"`) still read.

use std::fs;

use crate::common::{p, run};

/// `hapticlab --version`'s line: `hapticlab 0.1.0 (commit 67c70ce[, modified])`
/// or `hapticlab 0.1.0 (unknown commit)`.
pub fn software() -> String {
    let r = run(&["--version"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stderr.is_empty(), "{r:?}");
    r.stdout.trim_end().to_string()
}

#[test]
fn version_names_the_commit_or_says_it_is_unknown() {
    let line = software();
    let version = env!("CARGO_PKG_VERSION");
    let inner = line
        .strip_prefix(&format!("hapticlab {version} ("))
        .and_then(|s| s.strip_suffix(')'))
        .unwrap_or_else(|| panic!("not `hapticlab {version} (…)`: {line}"));
    let named = inner.strip_prefix("commit ").is_some_and(|c| {
        let hash = c.strip_suffix(", modified").unwrap_or(c);
        hash.len() >= 7 && hash.bytes().all(|b| b.is_ascii_hexdigit())
    });
    assert!(named || inner == "unknown commit", "{line}");
    assert_eq!(run(&["-V"]).stdout.trim_end(), line);
    // Built in the repository (not from a tarball) the hash is HEAD's, when
    // git can say it: cargo reruns the build script when HEAD moves. A
    // repository further up (a tarball unpacked inside one) is not ours.
    let repo = env!("CARGO_MANIFEST_DIR");
    let head = std::process::Command::new("git")
        .args(["-C", repo, "rev-parse", "--show-toplevel", "HEAD"])
        .output();
    if let Ok(o) = head
        && o.status.success()
        && let Some((top, head)) = String::from_utf8_lossy(&o.stdout).trim().split_once('\n')
        && std::path::Path::new(top).canonicalize().ok()
            == std::path::Path::new(repo).canonicalize().ok()
    {
        let head = head.to_string();
        let hash = inner.strip_prefix("commit ").unwrap_or_else(|| {
            panic!(
                "git knows HEAD ({}) but the build did not: {line}",
                head.trim()
            )
        });
        let hash = hash.trim_end_matches(", modified");
        assert!(head.starts_with(hash), "built from {hash}, HEAD is {head}");
    }
}

#[test]
fn a_simulated_recording_and_a_model_carry_the_version_line() {
    let line = software();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("sim");
    let r = run(&[
        "simulate",
        "--out",
        p(&rec),
        "--per-class",
        "1",
        "--seed",
        "3",
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let file = fs::read_dir(rec.join("S2"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let text = fs::read_to_string(&file).unwrap();
    let key = text
        .lines()
        .find(|l| l.starts_with("# software = "))
        .unwrap_or_else(|| panic!("no software key: {}", &text[..400.min(text.len())]));
    assert_eq!(key, format!("# software = \"{line}\""));

    let model = dir.path().join("m.json");
    let r = run(&["train", p(&rec), "--out", p(&model)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let m: serde_json::Value = serde_json::from_str(&fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(
        m["software_version"]
            .as_str()
            .map(|v| format!("hapticlab {v}")),
        Some(line),
        "{}",
        m["software_version"]
    );
}

/// The shipped recordings were written as `software = "hapticlab 0.1.0"`,
/// and a model as `"software_version": "0.1.0"`: both still read.
#[test]
fn files_from_before_the_commit_was_recorded_still_read() {
    let old = "recordings/thesis-sim/S2/S2_001.csv.gz";
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut flate2::read::GzDecoder::new(
            fs::File::open(format!("{}/{old}", env!("CARGO_MANIFEST_DIR"))).unwrap(),
        ),
        &mut text,
    )
    .unwrap();
    assert!(
        text.contains("\n# software = \"hapticlab 0.1.0\"\n"),
        "the shipped recording changed"
    );
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    let r = run(&[
        "train",
        "recordings/thesis-sim/S2",
        "recordings/thesis-sim/S3",
        "--out",
        p(&model),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    // As a model from before was written.
    let mut m: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&model).unwrap()).unwrap();
    m["software_version"] = "0.1.0".into();
    fs::write(&model, serde_json::to_string(&m).unwrap()).unwrap();
    let r = run(&["classify", "--model", p(&model), old]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("S2"), "{r:?}");
}

/// An imported recording says which hapticlab wrote it too, and `--meta`
/// cannot say otherwise.
#[test]
fn an_imported_recording_carries_the_version_line() {
    let line = software();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("S1/trial.csv");
    fs::create_dir_all(csv.parent().unwrap()).unwrap();
    let rows: String = (0..64)
        .map(|i| format!("{}\n", (i as f64 * 0.3).sin()))
        .collect();
    fs::write(&csv, format!("acc\n{rows}")).unwrap();
    let out = dir.path().join("rec");
    let r = run(&["import", p(&csv), "--rate", "100", "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(out.join("S1/trial.csv")).unwrap();
    assert!(
        text.lines()
            .any(|l| l == format!("# software = \"{line}\"")),
        "{text}"
    );
    let again = dir.path().join("rec2");
    let r = run(&[
        "import",
        p(&csv),
        "--rate",
        "100",
        "--out",
        p(&again),
        "--meta",
        "software=mine",
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("--meta software"), "{r:?}");
    assert!(!again.exists(), "{r:?}");
}
