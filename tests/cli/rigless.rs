//! Analysis-only profiles (no [device], [controller] or [path]): they
//! evaluate recordings; the commands that make scans refuse them naming the
//! missing sections (exit 2); `profile new` writes one for a folder of
//! recordings that `check` accepts and `evaluate` runs on.

use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::Path;

use crate::common::{REPO, p, run};

/// The thesis's analysis, classifier and split, and nothing of the rig.
const THESIS_ANALYSIS_ONLY: &str = r#"name = "thesis-analysis"

[analysis]
channel = "y_m"
axis = "x_m"
window = [0.060, 0.0897]
spacing = 0.0003
bins = [1, 49]

[classifier]
k = 10

[evaluation]
train_per_class = 20
test_per_class = 10
"#;

fn write_profile(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    p(&path).to_string()
}

#[test]
fn an_analysis_only_profile_evaluates_the_thesis_recordings_as_the_thesis_does() {
    let dir = tempfile::tempdir().unwrap();
    let profile = write_profile(dir.path(), "ao.toml", THESIS_ANALYSIS_ONLY);
    let r = run(&["evaluate", "recordings/thesis-sim", "-p", &profile]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("accuracy: 40/40 (100.0 %)"), "{r:?}");
    let r = run(&["check", &profile]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("analysis only"), "{r:?}");
    assert!(r.stdout.contains("not for scan, simulate"), "{r:?}");
}

#[test]
fn the_commands_that_make_scans_refuse_an_analysis_only_profile_naming_the_sections() {
    let dir = tempfile::tempdir().unwrap();
    let profile = write_profile(dir.path(), "ao.toml", THESIS_ANALYSIS_ONLY);
    let out = dir.path().join("out");
    let ds = dir.path().join("ds");
    for (what, args) in [
        ("scan", vec!["scan", "--label", "S2", "--out", p(&out)]),
        ("simulate", vec!["simulate", "--out", p(&out)]),
        ("console", vec!["console", "--dataset", p(&ds)]),
        ("doctor", vec!["doctor", "--dataset", p(&ds)]),
        (
            "evaluate --simulate",
            vec!["evaluate", "--simulate", "--loo"],
        ),
    ] {
        let mut args = args;
        args.extend(["--profile", &profile]);
        let r = run(&args);
        assert_eq!(r.code, Some(2), "{what}: {r:?}");
        let line = r.stderr.trim();
        assert_eq!(line.lines().count(), 1, "{what}: one message: {r:?}");
        assert!(
            line.contains(&format!(
                "{what}: {profile}: no [device], [controller] or [path] section"
            )),
            "{what}: {r:?}"
        );
        assert!(!r.stderr.contains("panicked"), "{what}: {r:?}");
    }
    assert!(!out.exists(), "nothing was written");
    // The console points to what still works without a rig.
    let r = run(&["console", "--dataset", p(&ds), "--profile", &profile]);
    assert!(r.stderr.contains("hapticlab replay DIR"), "{r:?}");
}

#[test]
fn a_profile_lacking_only_its_path_names_only_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let thesis = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    // Drop [path] (its header to the next section), keep the rest.
    let start = thesis.find("\n[path]").unwrap();
    let end = start + 1 + thesis[start + 1..].find("\n[").unwrap();
    let text = format!("{}{}", &thesis[..start], &thesis[end..]);
    let profile = write_profile(dir.path(), "no-path.toml", &text);
    let r = run(&["check", &profile]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains("analysis only (no [path] section)"),
        "{r:?}"
    );
    let r = run(&[
        "simulate",
        "--out",
        p(&dir.path().join("o")),
        "-p",
        &profile,
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains(": no [path] section:"), "{r:?}");
}

/// A recording v1 of an accelerometer-like signal at `rate` Hz: a texture's
/// tone `f` Hz with its second harmonic, broadband noise, and a level that
/// drifts from trial to trial. Without the trailer when `complete` is false.
fn vibration(label: &str, f: f64, trial: usize, rate: f64, secs: f64, complete: bool) -> String {
    let mut s = format!(
        "# hapticlab recording v1\n# label = \"{label}\"\n# device = \"accelerometer\"\n# rate_hz = {rate:.1}\n# trial = {trial}\nt_s,acc\n"
    );
    let n = (rate * secs) as usize;
    let gain = 1.0 + 0.4 * trial as f64;
    let mut seed: u64 = (f as u64) * 7919 + trial as u64 * 104_729 + 1;
    for i in 0..n {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let noise = ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
        let t = i as f64 / rate;
        let tau = std::f64::consts::TAU;
        let v = gain * ((tau * f * t).sin() + 0.5 * (tau * 2.0 * f * t + 0.3).sin() + 0.8 * noise);
        let _ = writeln!(s, "{t:.6},{v:.6}");
    }
    if complete {
        let _ = writeln!(s, "# end samples = {n}");
    }
    s
}

/// Three textures × four trials at 2 kHz, one of them gzipped, and one
/// incomplete recording (left out); the shortest complete one lasts 0.9 s.
fn vibration_set(dir: &Path) {
    for (label, f) in [("felt", 90.0), ("mesh", 230.0), ("wood", 410.0)] {
        let sub = dir.join(label);
        fs::create_dir_all(&sub).unwrap();
        for trial in 0..4 {
            let secs = if label == "mesh" && trial == 2 {
                0.9
            } else {
                1.2
            };
            let text = vibration(label, f, trial, 2000.0, secs, true);
            if label == "wood" && trial == 0 {
                let file = fs::File::create(sub.join(format!("{label}_{trial}.csv.gz"))).unwrap();
                let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
                gz.write_all(text.as_bytes()).unwrap();
                gz.finish().unwrap();
            } else {
                fs::write(sub.join(format!("{label}_{trial}.csv")), text).unwrap();
            }
        }
    }
    fs::write(
        dir.join("felt").join("felt_9.csv"),
        vibration("felt", 90.0, 9, 2000.0, 0.1, false),
    )
    .unwrap();
}

#[test]
fn profile_new_writes_a_profile_that_check_accepts_and_evaluate_runs_on() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rig");
    vibration_set(&rec);
    let out = dir.path().join("rig.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("acc along t_s at 2 kHz"), "{r:?}");
    assert!(r.stdout.contains("1 incomplete left out"), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    for expected in [
        "channel = \"acc\"",
        "axis = \"t_s\"",
        "spacing = 0.0005",
        "window = [0.0, 0.899]",
        "mesh_2.csv",
        "#   felt: 4",
        "#   wood: 4",
        "method = \"leave-one-out\"",
        "# group_by = \"trial\"",
        "# spectrum = \"log-welch\"",
        "# cepstra = ",
    ] {
        assert!(text.contains(expected), "{expected:?} missing:\n{text}");
    }
    assert!(
        !text.contains("[device]\n") && !text.contains("[path]\n"),
        "{text}"
    );
    let r = run(&["check", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("analysis only"), "{r:?}");
    let r = run(&["evaluate", p(&rec), "-p", p(&out), "--json"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["method"], "leave-one-out", "{v}");
    assert_eq!(v["predictions"].as_array().unwrap().len(), 12, "{v}");
    assert!(v["accuracy"].as_f64().unwrap() >= 0.9, "{v}");
}

#[test]
fn profile_new_on_the_thesis_recordings_reads_the_stroke_and_evaluates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim.toml");
    let r = run(&[
        "profile",
        "new",
        "--from",
        "recordings/thesis-sim",
        "--out",
        p(&out),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    // Each line followed by its option's advice.
    assert!(text.contains("\nchannel = \"y_m\"   # "), "{text}");
    assert!(text.contains("\naxis = \"x_m\"   # "), "{text}");
    assert!(text.contains("spacing = 0.0003"), "{text}");
    assert!(text.contains("#   S4: 30"), "{text}");
    let r = run(&["evaluate", "recordings/thesis-sim", "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains("accuracy: 120/120"), "{r:?}");
}

#[test]
fn profile_new_refuses_to_overwrite_an_empty_folder_and_only_incomplete_recordings() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rig");
    vibration_set(&rec);
    let out = dir.path().join("mine.toml");
    fs::write(&out, "# my own profile\n").unwrap();
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("already exists") && r.stderr.contains("--overwrite"),
        "{r:?}"
    );
    assert_eq!(fs::read_to_string(&out).unwrap(), "# my own profile\n");
    let r = run(&[
        "profile",
        "new",
        "--from",
        p(&rec),
        "--out",
        p(&out),
        "--overwrite",
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(fs::read_to_string(&out).unwrap().contains("[analysis]"));

    let empty = dir.path().join("empty");
    fs::create_dir_all(&empty).unwrap();
    let other = dir.path().join("other.toml");
    let r = run(&["profile", "new", "--from", p(&empty), "--out", p(&other)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("no recordings"), "{r:?}");

    let torn = dir.path().join("torn");
    fs::create_dir_all(torn.join("felt")).unwrap();
    fs::write(
        torn.join("felt").join("felt_0.csv"),
        vibration("felt", 90.0, 0, 2000.0, 0.2, false),
    )
    .unwrap();
    let r = run(&["profile", "new", "--from", p(&torn), "--out", p(&other)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(
        r.stderr.contains("none of the 1 recording(s) is complete"),
        "{r:?}"
    );
    assert!(!other.exists(), "nothing written");
}

#[test]
fn evaluate_simulate_without_train_per_class_simulates_thirty_per_texture() {
    let dir = tempfile::tempdir().unwrap();
    let thesis = fs::read_to_string(Path::new(REPO).join("profiles/thesis.toml")).unwrap();
    let text = thesis
        .replace("train_per_class = 20\n", "method = \"leave-one-out\"\n")
        .replace("test_per_class = 10\n", "");
    assert_ne!(text, thesis);
    let profile = write_profile(dir.path(), "loo.toml", &text);
    let r = run(&["evaluate", "--simulate", "-p", &profile]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains("leave-one-out, 120 simulated recordings"),
        "{r:?}"
    );
}
