//! Sweeps of keys that change the recordings (`evaluate --simulate --sweep
//! controller.stiffness_n_per_m[1]=…`): each value simulates its own
//! dataset in virtual time, in a temporary folder, and is evaluated.

use std::process::Command;

use hapticlab::evaluate::plan::{Overrides, Plan};
use hapticlab::evaluate::sweep::{
    SimPlan, resolve_key, simulated_dataset, sweep_simulated, with_key,
};
use hapticlab::profile::LoadedProfile;

fn hapticlab(args: &[&str]) -> std::process::Output {
    crate::common::hapticlab().args(args).output().unwrap()
}

#[test]
fn simulation_keys_resolve_by_table_bare_name_or_component() {
    let p = LoadedProfile::thesis().profile;
    let a = resolve_key(&p, "controller.stiffness_n_per_m[1]").unwrap();
    assert_eq!(
        a,
        resolve_key(&p, "controller.stiffness_n_per_m.y").unwrap()
    );
    assert_eq!(a, resolve_key(&p, "stiffness_n_per_m[1]").unwrap());
    assert!(a.needs_simulation());
    assert_eq!(a.name(), "controller.stiffness_n_per_m[1]");
    let s = resolve_key(&p, "speed_m_per_s").unwrap();
    assert_eq!(s.name(), "path.speed_m_per_s");
    assert!(s.needs_simulation());
    assert!(!resolve_key(&p, "k").unwrap().needs_simulation());
    // Not a key, a component of a scalar, a component out of range.
    for bad in [
        "speed",
        "path.speed_m_per_s[0]",
        "controller.stiffness_n_per_m[3]",
        "textures.label",
    ] {
        let e = resolve_key(&p, bad).unwrap_err();
        assert!(e.is_bad_input(), "{bad}");
    }
    // One component changes, the others stay; a whole number becomes a decimal.
    let q = with_key(
        &p,
        "controller.stiffness_n_per_m.y",
        &toml::Value::Integer(90),
    )
    .unwrap();
    assert_eq!(
        q.rig().unwrap().controller.stiffness_n_per_m,
        [2400.0, 90.0, 2400.0]
    );
    let q = with_key(&p, "path.speed_m_per_s", &toml::Value::Float(0.02)).unwrap();
    assert_eq!(q.rig().unwrap().path.speed_m_per_s, 0.02);
    // Values the profile refuses are refused, naming the key.
    let e = with_key(&p, "path.speed_m_per_s", &toml::Value::Float(-1.0)).unwrap_err();
    assert!(
        e.to_string().contains("path.speed_m_per_s"),
        "{}",
        e.to_string()
    );
}

#[test]
fn each_value_simulates_its_own_recordings() {
    let lp = LoadedProfile::thesis();
    let sim = SimPlan {
        per_class: 2,
        threads: 2,
        scratch: &hapticlab::scratch::make,
    };
    let mean_y = |ky: f64| {
        let p = with_key(
            &lp.profile,
            "controller.stiffness_n_per_m[1]",
            &toml::Value::Float(ky),
        )
        .unwrap();
        let lp = LoadedProfile {
            profile: p,
            ..lp.clone()
        };
        let samples = hapticlab::dataset::Options {
            keep: hapticlab::dataset::Keep::Samples,
            ..Default::default()
        };
        let d = simulated_dataset(&lp, sim, &lp.profile.analysis, samples, &|_, _| {}).unwrap();
        assert_eq!(d.scans.len(), 8);
        for s in &d.scans {
            assert!(!s.file.starts_with('/'), "relative names: {}", s.file);
            let k = s
                .meta
                .iter()
                .find(|(k, _)| k == "stiffness_n_per_m")
                .unwrap();
            assert_eq!(k.1.as_array().unwrap()[1].as_float(), Some(ky));
        }
        let ys: Vec<f64> = d
            .scans
            .iter()
            .flat_map(|s| s.signals[0].iter().copied())
            .collect();
        ys.iter().sum::<f64>() / ys.len() as f64
    };
    // A stiffer y spring pulls the probe harder towards its set-point, 1 mm
    // below the crests: deeper into the texture (lower y).
    let (soft, stiff) = (mean_y(30.0), mean_y(2430.0));
    assert!(stiff < soft - 2e-5, "soft {soft} stiff {stiff}");
}

#[test]
fn a_simulated_sweep_reports_each_value_and_repeats_exactly() {
    let lp = LoadedProfile::thesis();
    let args = Overrides {
        folds: Some(4),
        ..Overrides::default()
    };
    let plan = Plan::new(&lp.profile, &args);
    // 4 folds of 16 scans leave 12 to train the thesis's k = 10.
    let sim = SimPlan {
        per_class: 4,
        threads: 2,
        scratch: &hapticlab::scratch::make,
    };
    let values = [toml::Value::Integer(90), toml::Value::Integer(810)];
    let run = || {
        sweep_simulated(
            &lp,
            "controller.stiffness_n_per_m.y",
            &values,
            &plan,
            sim,
            &|_, _, _| {},
        )
        .unwrap()
    };
    let a = run();
    assert_eq!(a.key, "controller.stiffness_n_per_m[1]");
    assert_eq!(a.points.len(), 2);
    assert_eq!(a.points[0].value, "90");
    for p in &a.points {
        assert_eq!(p.recordings, 16);
        assert!(p.error.is_none());
        assert!((0.0..=1.0).contains(&p.accuracy));
        assert_eq!(p.k.len(), 4);
    }
    assert_eq!(a.simulated.as_ref().unwrap().per_class, 4);
    let b = run();
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
}

#[test]
fn a_value_whose_recordings_cannot_be_analysed_is_reported_not_fatal() {
    let lp = LoadedProfile::thesis();
    let args = Overrides {
        folds: Some(4),
        ..Overrides::default()
    };
    let plan = Plan::new(&lp.profile, &args);
    let sim = SimPlan {
        per_class: 4,
        threads: 2,
        scratch: &hapticlab::scratch::make,
    };
    // At 0.4 m/s and 1 kHz the samples lie 0.4 mm apart: gaps in a 0.3 mm resampling.
    let values = [toml::Value::Float(0.01), toml::Value::Float(0.4)];
    let s = sweep_simulated(
        &lp,
        "path.speed_m_per_s",
        &values,
        &plan,
        sim,
        &|_, _, _| {},
    )
    .unwrap();
    assert!(s.points[0].error.is_none() && s.points[0].accuracy.is_finite());
    assert!(s.points[1].accuracy.is_nan());
    assert!(s.points[1].error.as_deref().unwrap().contains("spacing"));
    assert!(s.table().contains("not evaluated"));
    assert!(s.table().contains("best: path.speed_m_per_s = 0.01"));
    // The JSON has null numbers and the reason; the figure draws the rest.
    let json = serde_json::to_value(&s).unwrap();
    assert!(json["points"][1]["accuracy"].is_null());
    assert!(json["points"][1]["error"].is_string());
    let dir = tempfile::tempdir().unwrap();
    let (j, png) = (dir.path().join("s.json"), dir.path().join("s.png"));
    std::fs::write(&j, json.to_string()).unwrap();
    let out = hapticlab(&[
        "plot",
        "sweep",
        j.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

#[test]
fn the_cli_sweeps_simulation_keys_only_with_simulate() {
    // Over recordings on disk: exit 2, pointing at --simulate.
    let out = hapticlab(&[
        "evaluate",
        "recordings/thesis-sim",
        "--sweep",
        "controller.stiffness_n_per_m[1]=90,270",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--simulate"), "{err}");
    // --simulate takes no PATH; --per-class needs --simulate; too few for the holdout split.
    for args in [
        &["evaluate", "recordings/thesis-sim", "--simulate"][..],
        &["evaluate", "recordings/thesis-sim", "--per-class", "3"],
        &["evaluate", "--simulate", "--per-class", "3"],
        &["evaluate", "--simulate", "--per-class", "0", "--folds", "2"],
        &[
            "evaluate",
            "--simulate",
            "--folds",
            "2",
            "--sweep",
            "path.speed_m_per_s=-1",
        ],
        &[
            "evaluate",
            "--simulate",
            "--folds",
            "2",
            "--sweep",
            "speed=0.01",
        ],
    ] {
        let out = hapticlab(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }

    // The scans go to a temporary folder, removed afterwards.
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .env("TMPDIR", tmp.path())
        .args([
            "evaluate",
            "--simulate",
            "--per-class",
            "4",
            "--folds",
            "4",
            "--json",
            "--sweep",
            "controller.stiffness_n_per_m[1]=90,810",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "nothing left behind"
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty(), "no progress bar when piped");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["key"], "controller.stiffness_n_per_m[1]");
    assert_eq!(v["points"].as_array().unwrap().len(), 2);
    assert_eq!(v["points"][1]["value"], "810");
    assert_eq!(v["simulated"]["per_class"], 4);
    for p in v["points"].as_array().unwrap() {
        assert!(p.get("error").is_none(), "{p}");
        assert!(p["accuracy"].as_f64().unwrap() > 0.9, "{p}");
    }

    // The sweep's JSON draws as a figure.
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("s.json");
    std::fs::write(&json, &out.stdout).unwrap();
    let svg = dir.path().join("s.svg");
    let out = hapticlab(&[
        "plot",
        "sweep",
        json.to_str().unwrap(),
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("(N/m)"), "the axis names the unit");

    // An analysis key swept on one simulated dataset.
    let out = hapticlab(&[
        "evaluate",
        "--simulate",
        "--per-class",
        "3",
        "--folds",
        "3",
        "--sweep",
        "k=1,3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("12 simulated recordings"), "{text}");
}
