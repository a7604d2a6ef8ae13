//! `[analysis] windows` through the front ends: `features --out` writes one
//! row per sub-window with its index, and `classify --json` gives each
//! recording's vote with every sub-window's outcome.

use std::fs;
use std::path::Path;

use serde_json::Value;
use tempfile::TempDir;

use crate::common::{REPO, p, run, thesis_windows_profile};

#[test]
fn features_write_one_row_per_sub_window_and_classify_votes_over_them() {
    let dir = TempDir::new().unwrap();
    let profile = thesis_windows_profile(dir.path());
    let data = Path::new(REPO).join("recordings/thesis-sim");
    let s1 = data.join("S1");
    let out = dir.path().join("F.csv");
    let r = run(&[
        "features",
        "--profile",
        p(&profile),
        p(&s1),
        "--out",
        p(&out),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = ["file", "label", "window"]
        .into_iter()
        .map(String::from)
        .chain((1..=24).map(|i| format!("f{i}")))
        .collect();
    assert_eq!(lines.next().unwrap(), header.join(","));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let files = fs::read_dir(&s1).unwrap().count();
    assert_eq!(rows.len(), 3 * files);
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 27);
        assert_eq!(row[2], (i % 3).to_string(), "{row:?}");
        assert_eq!(
            row[0],
            rows[i - i % 3][0],
            "a recording's rows are together"
        );
    }

    let model = dir.path().join("M.json");
    let r = run(&[
        "train",
        "--profile",
        p(&profile),
        p(&data),
        "--out",
        p(&model),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let held = data.join("S2").join("S2_001.csv.gz");
    let r = run(&[
        "classify",
        "--profile",
        p(&profile),
        "--model",
        p(&model),
        "--json",
        p(&held),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v: Value = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    let row = &v.as_array().unwrap()[0];
    let windows = row["windows"].as_array().unwrap();
    assert_eq!(windows.len(), 3);
    for (j, w) in windows.iter().enumerate() {
        assert_eq!(w["window"], j);
        assert!(w["label"].is_string() && w["votes"].is_array(), "{w}");
    }
    let tally = row["tally"].as_array().unwrap();
    assert_eq!(row["predicted"], tally[0]["label"]);
    let counted: u64 = tally.iter().map(|t| t["windows"].as_u64().unwrap()).sum();
    assert_eq!(counted, 3);
    // The plain line names the vote.
    let r = run(&[
        "classify",
        "--profile",
        p(&profile),
        "--model",
        p(&model),
        p(&held),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains("of 3 windows, window votes "),
        "{}",
        r.stdout
    );
}
