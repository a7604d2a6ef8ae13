//! What was accepted silently but wrong, and messages that did not say
//! where or what to change (issue 19): each refused with exit 2 and one
//! line naming the file, entry or key. The small scans and profiles are in
//! `tests/data/small/` (see its README).

use std::path::Path;

use crate::common::run::Run;
use crate::common::{p, run};

const SMALL: &str = "tests/data/small";
const TINY: &str = "tests/data/small/tiny.toml";

/// `hapticlab ARGS` must exit 2 with one line holding each of `says`.
fn refused(args: &[&str], says: &[&str]) -> Run {
    let r = run(args);
    assert_eq!(r.code, Some(2), "{args:?}: {r:?}");
    assert_eq!(r.stderr.trim_end().lines().count(), 1, "one line: {r:?}");
    for s in says {
        assert!(r.stderr.contains(s), "{args:?}: {s:?} missing: {r:?}");
    }
    assert!(!r.stderr.contains("panicked"), "{r:?}");
    r
}

/// `tiny.toml` with `from` replaced by `to`, written to `dir/name`.
fn tiny_with(dir: &Path, name: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(Path::new(crate::common::REPO).join(TINY)).unwrap();
    assert!(text.contains(from), "{from:?} not in {TINY}");
    let path = dir.join(name);
    std::fs::write(&path, text.replace(from, to)).unwrap();
    p(&path).to_string()
}

#[test]
fn evaluate_refuses_recordings_of_a_single_label_however_it_validates() {
    let one = format!("{SMALL}/one-label");
    let single = format!("{SMALL}/one-label/a/a1.csv");
    for args in [
        vec!["evaluate", "-p", TINY, &one],
        vec!["evaluate", "-p", TINY, "--loo", &one],
        vec!["evaluate", "-p", TINY, "--folds", "2", &one],
        vec!["evaluate", "-p", TINY, "--loo", &single],
    ] {
        refused(&args, &["a1.csv", "labelled \"a\"", "two textures"]);
    }
    // Two labels evaluate.
    let r = run(&["evaluate", "-p", TINY, &format!("{SMALL}/two-labels")]);
    assert_eq!(r.code, Some(0), "{r:?}");
}

#[test]
fn features_train_and_evaluate_refuse_a_sample_whose_spectrum_overflows_alike() {
    let dir = tempfile::tempdir().unwrap();
    let huge = format!("{SMALL}/huge-sample");
    let model = dir.path().join("m.json");
    let out = dir.path().join("f.csv");
    for args in [
        vec!["features", "-p", TINY, &huge],
        vec!["features", "-p", TINY, &huge, "--out", p(&out)],
        vec!["train", "-p", TINY, &huge, "--out", p(&model)],
        vec!["evaluate", "-p", TINY, "--loo", &huge],
    ] {
        refused(
            &args,
            &["huge-sample/a/a1.csv", "feature 1 is not a finite number"],
        );
    }
    assert!(!out.exists() && !model.exists());
}

/// A model trained by `profile` on the two-label set, as JSON to edit.
fn trained(dir: &Path, profile: &str) -> serde_json::Value {
    let model = dir.join("trained.json");
    let r = run(&[
        "train",
        "-p",
        profile,
        &format!("{SMALL}/two-labels"),
        "--out",
        p(&model),
        "--overwrite",
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap()
}

#[test]
fn classify_refuses_a_model_whose_scaling_or_k_cannot_be_right() {
    let dir = tempfile::tempdir().unwrap();
    let std_profile = format!("{SMALL}/tiny-standardized.toml");
    let scaled = trained(dir.path(), &std_profile);
    assert!(scaled["scaling"].is_object(), "{scaled}");
    let query = format!("{SMALL}/two-labels/b/b1.csv");
    let classify = |name: &str, model: &serde_json::Value, profile: &str, says: &[&str]| {
        let path = dir.path().join(name);
        std::fs::write(&path, serde_json::to_string_pretty(model).unwrap()).unwrap();
        let mut all = vec![p(&path)];
        all.extend(says);
        refused(
            &["classify", "-p", profile, "--model", p(&path), &query],
            &all,
        );
    };
    let mut huge_mean = scaled.clone();
    huge_mean["scaling"]["mean"][0] = serde_json::json!(1e308);
    huge_mean["scaling"]["scale"][0] = serde_json::json!(1e-300);
    classify("huge-mean.json", &huge_mean, &std_profile, &["too large"]);
    let mut unscaled = scaled.clone();
    unscaled.as_object_mut().unwrap().remove("scaling");
    classify(
        "unscaled.json",
        &unscaled,
        &std_profile,
        &["standardize = true but it has no scaling"],
    );
    let plain = trained(dir.path(), TINY);
    for (i, k) in [
        serde_json::json!(-1),
        serde_json::json!(2.5),
        serde_json::json!(18446744073709551616.0),
    ]
    .into_iter()
    .enumerate()
    {
        let mut bad_k = plain.clone();
        bad_k["classifier"]["k"] = k;
        classify(
            &format!("k{i}.json"),
            &bad_k,
            TINY,
            &["k must be a whole number ≥ 1 or \"auto\""],
        );
    }
    // The model as trained classifies.
    let good = dir.path().join("good.json");
    std::fs::write(&good, serde_json::to_string(&scaled).unwrap()).unwrap();
    let r = run(&["classify", "-p", &std_profile, "--model", p(&good), &query]);
    assert_eq!(r.code, Some(0), "{r:?}");
}

#[test]
fn sweeps_say_what_k_must_be_and_offer_only_keys_that_apply() {
    let two = format!("{SMALL}/two-labels");
    for (k, got) in [
        ("k=1.5..3", "got 1.5"),
        ("k=99999999999999999999", "got \"9999"),
    ] {
        // Each value is reported beside the point; none could be evaluated.
        let r = run(&["evaluate", "-p", TINY, "--loo", &two, "--sweep", k]);
        assert_eq!(r.code, Some(2), "{r:?}");
        assert!(
            r.stdout
                .contains("not evaluated: k must be a whole number ≥ 1 or \"auto\", "),
            "{r:?}"
        );
        assert!(r.stdout.contains(got), "{r:?}");
        assert!(!r.stdout.contains("untagged"), "{r:?}");
    }
    let r = refused(
        &[
            "evaluate",
            "-p",
            TINY,
            &two,
            "--sweep",
            "path.speed_m_per_s=0.01,0.02",
        ],
        &[
            "--sweep path.speed_m_per_s",
            "not a key",
            "has no [controller], [path]",
        ],
    );
    assert!(!r.stderr.contains("e.g. k, spacing, taper,"), "{r:?}");
}

#[test]
fn plot_sweep_refuses_accuracies_that_are_not_shares_and_json_that_is_not_utf8() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("s.png");
    for (i, acc) in ["-5", "1e308", "1.5"].iter().enumerate() {
        let json = dir.path().join(format!("s{i}.json"));
        std::fs::write(
            &json,
            format!(
                r#"{{"keys": ["k"], "method": "leave-one-out", "points": [
                    {{"values": ["1"], "accuracy": 0.5, "accuracy_std": 0.1}},
                    {{"values": ["3"], "accuracy": {acc}, "accuracy_std": 0.1}}]}}"#
            ),
        )
        .unwrap();
        refused(
            &["plot", "sweep", p(&json), "--out", p(&png)],
            &[p(&json), "points[1] (3)", "not a share from 0 to 1"],
        );
    }
    let json = dir.path().join("utf16.json");
    let text = r#"{"keys": ["k"], "points": [{"values": ["1"], "accuracy": 0.5}]}"#;
    let mut bytes = vec![0xff, 0xfe];
    bytes.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    std::fs::write(&json, bytes).unwrap();
    refused(
        &["plot", "sweep", p(&json), "--out", p(&png)],
        &[p(&json), "not UTF-8 JSON"],
    );
    assert!(!png.exists());
}

#[test]
fn check_names_the_window_in_numbers_people_can_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            tiny_with(
                d,
                "hop.toml",
                "bins = [1, 8]",
                "bins = [1, 4]\nwindows = { length = 0.01, hop = 1e-300 }",
            ),
            vec!["analysis.windows", "hop 1e-300 s"],
        ),
        (
            tiny_with(
                d,
                "huge.toml",
                "window = [0.0, 0.015]",
                "window = [0.0, 1e300]",
            ),
            vec!["analysis.window", "window (1e300)", "shorten the window"],
        ),
        (
            tiny_with(
                d,
                "short.toml",
                "window = [0.0, 0.015]",
                "window = [0.0, 0.0005]",
            ),
            vec![
                "analysis.window",
                "(0.0005)",
                "spacing 0.001",
                "lengthen the window",
            ],
        ),
        (
            tiny_with(
                d,
                "both.toml",
                "bins = [1, 8]",
                "bins = [1, 8]\nbands = { count = 2, from = 100.0, to = 400.0 }",
            ),
            vec!["analysis.bands", "`bins` and `bands`"],
        ),
    ];
    for (profile, says) in &cases {
        let r = refused(&["check", profile], says);
        assert!(r.stderr.len() < 300, "{} characters: {r:?}", r.stderr.len());
        assert!(!r.stderr.contains("only 0"), "{r:?}");
    }
}

#[test]
fn train_with_sub_windows_counts_recordings_and_sub_windows_apart() {
    let dir = tempfile::tempdir().unwrap();
    let profile = tiny_with(
        dir.path(),
        "windows.toml",
        "bins = [1, 8]",
        "bins = [1, 4]\nwindows = { length = 0.008, hop = 0.004 }",
    );
    let model = dir.path().join("m.json");
    let r = run(&[
        "train",
        "-p",
        &profile,
        &format!("{SMALL}/two-labels"),
        "--out",
        p(&model),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout
            .contains(" on 6 recordings (12 sub-windows) of 2 classes"),
        "{r:?}"
    );
}

#[test]
fn profile_new_on_recordings_sharing_no_channel_names_two_that_differ() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("new.toml");
    refused(
        &[
            "profile",
            "new",
            "--from",
            &format!("{SMALL}/no-shared-channel"),
            "--out",
            p(&out),
        ],
        &["share no channel", "acc.csv", "force.csv"],
    );
    assert!(!out.exists());
}

/// A profile's `[console] keys` that puts two actions on one key is refused
/// at load (exit 2, before any terminal or device), naming the key, both
/// actions, the entry the user wrote and which binding is a default: a
/// remapping written before the browser's keys (`d` delete, `x` exclude…)
/// existed meets them here, not as a key that silently does something else.
#[test]
fn a_console_key_bound_to_two_actions_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let thesis =
        std::fs::read_to_string(Path::new(crate::common::REPO).join("profiles/thesis.toml"))
            .unwrap();
    let ds = dir.path().join("ds");
    for (keys, says) in [
        (
            r#"{ start = "d" }"#,
            &[
                "console.keys.start",
                "key d is bound to both \"start\" (console.keys.start) and \"delete\" (delete's default key)",
            ][..],
        ),
        (
            r#"{ quit = "F5", start = "F5" }"#,
            &[
                "console.keys.start",
                "key F5 is bound to both \"quit\" (console.keys.quit) and \"start\" (console.keys.start)",
            ][..],
        ),
    ] {
        let profile = dir.path().join("keys.toml");
        std::fs::write(&profile, format!("{thesis}\n[console]\nkeys = {keys}\n")).unwrap();
        for cmd in ["console", "replay"] {
            let target = if cmd == "console" {
                vec!["console", "--profile", p(&profile), "--dataset", p(&ds)]
            } else {
                vec!["replay", "recordings/thesis-sim", "--profile", p(&profile)]
            };
            let r = refused(&target, says);
            assert!(r.stderr.contains("keys.toml:"), "the file named: {r:?}");
        }
        assert!(!ds.exists(), "nothing made before the refusal");
    }
    // The same remapping with delete moved away loads.
    let profile = dir.path().join("moved.toml");
    std::fs::write(
        &profile,
        format!("{thesis}\n[console]\nkeys = {{ start = \"d\", delete = \"D\" }}\n"),
    )
    .unwrap();
    let r = run(&["check", p(&profile)]);
    assert_eq!(r.code, Some(0), "{r:?}");
}
