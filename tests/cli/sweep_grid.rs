//! Sweeps that keep going and grids: a value the profile refuses is listed
//! "not evaluated" with its reason and the sweep goes on (exit 2 only when
//! nothing was evaluated); two or more `--sweep` flags evaluate every
//! combination, the best marked unless all tie; `plot sweep` draws a
//! two-key grid as a heat map.

use std::fs;

use serde_json::Value;
use tempfile::TempDir;

use hapticlab::evaluate::plan::{Overrides, Plan};
use hapticlab::evaluate::sweep::{SimPlan, Swept, sweep_grid_simulated};
use hapticlab::profile::LoadedProfile;

use crate::common::{json_of, p, run, thesis_windows_profile};

fn points(v: &Value) -> &Vec<Value> {
    v["points"]
        .as_array()
        .unwrap_or_else(|| panic!("no points: {v}"))
}

/// The points marked best.
fn best(v: &Value) -> Vec<&Value> {
    points(v).iter().filter(|p| p["best"] == true).collect()
}

#[test]
fn the_readme_spectrum_sweep_goes_on_past_welch() {
    let args = [
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "5",
        "--sweep",
        "spectrum=magnitude,welch",
    ];
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    let welch = r
        .stdout
        .lines()
        .find(|l| l.starts_with("welch"))
        .unwrap_or_else(|| panic!("no welch row: {}", r.stdout));
    assert!(
        welch.contains("not evaluated: analysis.bins"),
        "the row names the key that the value makes invalid: {welch}"
    );
    assert!(
        r.stdout.contains("best: spectrum = magnitude"),
        "{}",
        r.stdout
    );

    let v = json_of(&[&args[..], &["--json"]].concat());
    let [magnitude, welch] = &points(&v)[..] else {
        panic!("two points: {v}");
    };
    assert_eq!(magnitude["evaluated"], true);
    assert!(magnitude.get("reason").is_none());
    assert!(magnitude["accuracy"].as_f64().unwrap() > 0.9);
    assert_eq!(welch["evaluated"], false);
    assert!(welch["accuracy"].is_null());
    let reason = welch["reason"].as_str().unwrap();
    assert!(reason.contains("analysis.bins"), "{reason}");
    // The contract is additive: the one-key fields are all still there.
    assert_eq!(v["key"], "spectrum");
    assert_eq!(v["keys"], serde_json::json!(["spectrum"]));
    assert_eq!(welch["value"], "welch");
    assert_eq!(welch["error"], welch["reason"]);

    // Nothing evaluated: exit 2, the reason still shown.
    let r = run(&[
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "5",
        "--sweep",
        "spectrum=welch",
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stdout.contains("not evaluated"), "{r:?}");
    assert!(r.stderr.contains("no value could be evaluated"), "{r:?}");
    assert!(!r.stderr.contains("panicked"));
}

#[test]
fn a_two_key_grid_evaluates_every_combination_and_marks_the_best() {
    let dir = TempDir::new().unwrap();
    // One or two DFT bins: the textures are told apart only in part, so
    // the four points differ.
    let args = [
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "5",
        "--sweep",
        "bins=[1,1],[1,2]",
        "--sweep",
        "k=1,10",
    ];
    let v = json_of(&[&args[..], &["--json"]].concat());
    assert_eq!(v["keys"], serde_json::json!(["bins", "k"]));
    let pts = points(&v);
    assert_eq!(pts.len(), 4);
    let combos: Vec<Value> = pts.iter().map(|p| p["values"].clone()).collect();
    assert_eq!(
        combos,
        [
            serde_json::json!(["[1, 1]", "1"]),
            serde_json::json!(["[1, 1]", "10"]),
            serde_json::json!(["[1, 2]", "1"]),
            serde_json::json!(["[1, 2]", "10"]),
        ]
    );
    let acc: Vec<f64> = pts
        .iter()
        .map(|p| p["accuracy"].as_f64().unwrap())
        .collect();
    let top = acc.iter().copied().fold(f64::MIN, f64::max);
    assert!(acc.iter().any(|&a| a < top), "the points differ: {acc:?}");
    let b = best(&v);
    assert!(!b.is_empty());
    for p in &b {
        assert_eq!(p["accuracy"].as_f64().unwrap(), top, "{p}");
    }
    assert_eq!(
        b.len(),
        acc.iter().filter(|&&a| a == top).count(),
        "each of the top points is best, no other"
    );
    // The features are extracted per point: one bin alone scores lower
    // than two at the same k.
    assert!(acc[0] < acc[2] || acc[1] < acc[3], "{acc:?}");

    // The table: a matrix, rows bins, columns k, the best starred.
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("bins \\ k"), "{}", r.stdout);
    assert!(r.stdout.contains("4 combinations (2 × 2)"), "{}", r.stdout);
    let starred = r.stdout.lines().filter(|l| l.contains(" *")).count();
    assert!(starred >= 1, "{}", r.stdout);
    assert!(r.stdout.contains("best"), "{}", r.stdout);

    // plot sweep draws the grid as a heat map, in PNG and SVG.
    let json = dir.path().join("grid.json");
    fs::write(&json, serde_json::to_string(&v).unwrap()).unwrap();
    let (png, svg) = (dir.path().join("grid.png"), dir.path().join("grid.svg"));
    for out in [&png, &svg] {
        let r = run(&["plot", "sweep", p(&json), "--out", p(out)]);
        assert_eq!(r.code, Some(0), "{r:?}");
    }
    let bytes = fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG") && bytes.len() > 5000);
    let text = fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg") && text.contains("</svg>"));
    // Both keys name an axis; every cell's accuracy is written in.
    assert!(
        text.contains("\nbins\n") && text.contains("\nk\n"),
        "axis names"
    );
    for a in &acc {
        assert!(text.contains(&format!("{:.1}", 100.0 * a)), "{a}");
    }
}

#[test]
fn a_grid_where_every_point_ties_has_no_best() {
    let args = [
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "3",
        "--sweep",
        "k=1,5",
        "--sweep",
        "metric=euclidean,cosine",
    ];
    let v = json_of(&[&args[..], &["--json"]].concat());
    assert_eq!(points(&v).len(), 4);
    let first = &points(&v)[0]["accuracy"];
    assert!(points(&v).iter().all(|p| p["accuracy"] == *first), "{v}");
    assert!(best(&v).is_empty(), "{v}");
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains("no best: every combination gives"),
        "{}",
        r.stdout
    );
    assert!(!r.stdout.contains(" *"), "{}", r.stdout);
}

#[test]
fn three_keys_give_a_row_per_combination_and_bad_grids_are_refused() {
    let dir = TempDir::new().unwrap();
    let v = json_of(&[
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "3",
        "--sweep",
        "k=1,5",
        "--sweep",
        "bins=[1,1],[1,2]",
        "--sweep",
        "spectrum=magnitude,welch",
        "--json",
    ]);
    let pts = points(&v);
    assert_eq!(pts.len(), 8);
    // Welch allows these bins too: every combination is evaluated.
    assert!(pts.iter().all(|p| p["evaluated"] == true), "{v}");
    assert_eq!(
        pts[7]["values"],
        serde_json::json!(["5", "[1, 2]", "welch"])
    );
    // plot sweep draws one or two keys, and says so.
    let json = dir.path().join("three.json");
    fs::write(&json, serde_json::to_string(&v).unwrap()).unwrap();
    let out = dir.path().join("three.png");
    let r = run(&["plot", "sweep", p(&json), "--out", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("two (a heat map)"), "{r:?}");

    for (args, says) in [
        (&["--sweep", "k=1,3", "--sweep", "k=5"][..], "swept twice"),
        (
            &[
                "--sweep",
                "k=1..1000",
                "--sweep",
                "spacing=0.0001..0.0005:0.00001",
            ][..],
            "too many",
        ),
        (
            &["--sweep", "k=1,3", "--sweep", "nonsense=1"][..],
            "nonsense",
        ),
    ] {
        let mut all = vec!["evaluate", "recordings/thesis-sim", "--folds", "3"];
        all.extend_from_slice(args);
        let r = run(&all);
        assert_eq!(r.code, Some(2), "{args:?}: {r:?}");
        assert!(r.stderr.contains(says), "{args:?}: {r:?}");
        assert!(!r.stderr.contains("panicked"));
    }
}

#[test]
fn a_grid_with_sub_windows_scores_by_recording() {
    let dir = TempDir::new().unwrap();
    let profile = thesis_windows_profile(dir.path());
    let v = json_of(&[
        "evaluate",
        "--profile",
        p(&profile),
        "recordings/thesis-sim",
        "--folds",
        "5",
        "--sweep",
        "k=1,10",
        "--sweep",
        "detrend=mean,linear",
        "--json",
    ]);
    let pts = points(&v);
    assert_eq!(pts.len(), 4);
    for point in pts {
        assert_eq!(point["recordings"], 120, "{point}");
        assert!(point["accuracy"].as_f64().unwrap() >= 0.9, "{point}");
    }
}

#[test]
fn a_simulated_grid_reports_a_path_too_fast_and_goes_on() {
    let lp = LoadedProfile::thesis();
    let plan = Plan::new(
        &lp.profile,
        &Overrides {
            folds: Some(3),
            ..Overrides::default()
        },
    );
    let sim = SimPlan {
        per_class: 3,
        threads: 2,
        scratch: &hapticlab::scratch::make,
    };
    let swept = [
        Swept::parse("path.speed_m_per_s=0.01,0.4").unwrap(),
        Swept::parse("k=1,3").unwrap(),
    ];
    let s = sweep_grid_simulated(&lp, &swept, &plan, sim, &|_, _, _| {}).unwrap();
    // Named by table, as simulated sweeps name their keys.
    assert_eq!(s.keys, ["path.speed_m_per_s", "classifier.k"]);
    assert_eq!(s.points.len(), 4);
    for p in &s.points[..2] {
        assert!(p.evaluated && p.accuracy.is_finite(), "{p:?}");
        assert_eq!(p.recordings, 12);
    }
    // At 0.4 m/s the 1 kHz samples lie 0.4 mm apart: too sparse for 0.3 mm.
    for p in &s.points[2..] {
        assert!(!p.evaluated && p.accuracy.is_nan(), "{p:?}");
        assert!(p.reason.as_deref().unwrap().contains("spacing"), "{p:?}");
    }
    // The keys in the other order: the same points (each speed simulated
    // once, the same seed), the grid transposed.
    let swapped = [swept[1].clone(), swept[0].clone()];
    let t = sweep_grid_simulated(&lp, &swapped, &plan, sim, &|_, _, _| {}).unwrap();
    for (i, p) in s.points.iter().enumerate() {
        let q = &t.points[(i % 2) * 2 + i / 2];
        assert_eq!(q.values, [p.values[1].clone(), p.values[0].clone()]);
        assert_eq!(q.evaluated, p.evaluated);
        assert_eq!(q.accuracy.to_bits(), p.accuracy.to_bits(), "{p:?} {q:?}");
    }
    let table = s.table();
    assert!(
        table.contains("path.speed_m_per_s \\ classifier.k"),
        "{table}"
    );
    assert!(table.contains("(1) not evaluated:"), "{table}");
}
