//! `tune` end to end (issue 21): it writes a profile that `check` accepts
//! and `evaluate` scores as tune's outer estimate, `--json` carries the
//! search, a seed gives byte-identical output, an input is never its
//! `--out`, plans that cannot test are refused in one line, and the outer
//! estimate is reported apart from the inner scores.

use std::fs;
use std::path::{Path, PathBuf};

use hapticlab::recording::RecordingWriter;

use crate::common::{p, run};

/// A small deterministic generator.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// `trials` one-second recordings at 1 kHz per label in `dir/<label>/`,
/// named in time order: a tone of 40 + 25·class Hz in noise; from trial
/// `late` on, 30 times louder and 12.5 Hz higher, half-way to the next
/// label's (a drift no earlier trial shows, so the inner folds, drawn from
/// the early trials, score differently from the later test part).
fn recordings(dir: &Path, labels: &[&str], trials: usize, late: usize) -> PathBuf {
    let mut rng = Lcg(7);
    for (c, label) in labels.iter().enumerate() {
        for t in 0..trials {
            let path = dir
                .join(label)
                .join(format!("{label}-trial{:02}.csv", t + 1));
            let meta = vec![("label".to_string(), toml::Value::String(label.to_string()))];
            let mut w = RecordingWriter::create(&path, &meta, &["t_s", "x"]).unwrap();
            let (gain, shift) = if t >= late { (30.0, 12.5) } else { (1.0, 0.0) };
            let f = 40.0 + 25.0 * c as f64 + shift;
            for i in 0..1000 {
                let time = i as f64 * 0.001;
                let v = gain * ((std::f64::consts::TAU * f * time).sin() + 3.0 * rng.next());
                w.write_row(&[time, (v * 100.0).round()]).unwrap();
            }
            w.finish().unwrap();
        }
    }
    dir.to_path_buf()
}

/// An analysis-only profile over those recordings with `evaluation` as its
/// `[evaluation]` section, written to `dir/NAME.toml`.
fn profile(dir: &Path, name: &str, evaluation: &str) -> PathBuf {
    let text = format!(
        "name = \"{name}\"\n\n[analysis]\nchannel = \"x\"\naxis = \"t_s\"\nwindow = [0.0, 0.999]\n\
         spacing = 0.001\nspectrum = \"log-welch\"\n\n[classifier]\nk = 1\n\n[evaluation]\n{evaluation}\n"
    );
    let path = dir.join(format!("{name}.toml"));
    fs::write(&path, text).unwrap();
    path
}

const TIME_SPLIT: &str = "method = \"holdout\"\ntrain_per_class = 5\ntest_per_class = 5";

/// `tune` with a budget of 48 settings (one feature setting).
fn tune_48(rec: &Path, prof: &Path, out: &Path) -> crate::common::run::Run {
    run(&[
        "tune",
        p(rec),
        "-p",
        p(prof),
        "--out",
        p(out),
        "--budget",
        "48",
    ])
}

fn tune_json(rec: &Path, prof: &Path, out: &Path) -> (String, serde_json::Value) {
    let r = run(&[
        "tune",
        p(rec),
        "-p",
        p(prof),
        "--out",
        p(out),
        "--budget",
        "96",
        "--seed",
        "3",
        "--json",
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let v = serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:?}"));
    (r.stdout, v)
}

#[test]
fn tune_writes_a_profile_check_accepts_and_evaluate_scores_as_the_outer_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recordings(&dir.path().join("rec"), &["A", "B", "C"], 10, 5);
    let prof = profile(dir.path(), "split", TIME_SPLIT);
    let out = dir.path().join("tuned.toml");
    let (stdout, v) = tune_json(&rec, &prof, &out);

    assert_eq!(v["configurations"], 96, "{v}");
    // A time split: the inner folds go forward in time over the 5
    // training trials of each label (4 folds, each testing the next trial).
    assert_eq!(v["inner_folds"], 4, "{v}");
    assert_eq!(v["inner_split"], "forward", "{v}");
    assert_eq!(v["method"], "holdout", "{v}");
    assert_eq!(v["outer"]["test"].as_array().map(Vec::len), Some(15), "{v}");
    let outer = v["outer_accuracy"].as_f64().expect("outer_accuracy");
    let inner = v["chosen"]["inner_accuracy"]
        .as_f64()
        .expect("chosen.inner_accuracy");
    assert!(v["chosen"]["options"].is_array(), "{v}");
    let table = v["table"].as_array().expect("table");
    assert_eq!(table.len(), 10);
    assert_eq!(table[0]["inner_accuracy"].as_f64(), Some(inner));
    // The later trials drift: the chosen setting's inner score (on the
    // early trials) is not what it scores on the later ones, and tune
    // reports the latter.
    assert!(
        (outer - inner).abs() > 0.05,
        "outer {outer} inner {inner}: the data no longer separates the two"
    );

    let text = fs::read_to_string(&out).unwrap();
    let pct = |x: f64| format!("{:.1} %", 100.0 * x);
    let right = (outer * 15.0).round() as usize;
    assert!(
        text.contains(&format!(
            "# Outer estimate: {} ({right}/15 test recordings): the figure to quote. The inner scores below are not an estimate."
        , pct(outer))),
        "{text}"
    );
    assert!(
        text.contains("# Best settings by inner score (mean accuracy over the inner folds):"),
        "{text}"
    );
    assert!(text.contains(&format!("# {:>7}", pct(inner))), "{text}");
    assert!(text.contains("  # tune\n"), "{text}");
    // The code that chose it, as `--version` names it.
    let software = format!("# software = \"{}\"\n", crate::version::software());
    assert!(text.contains(&software), "{software}{text}");

    let r = run(&["check", p(&out)]);
    assert_eq!(
        r.code,
        Some(0),
        "check refuses the tuned profile: {r:?}\n{text}"
    );
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout.contains(&format!("accuracy: {right}/15")),
        "evaluate with the written profile is not tune's outer estimate ({right}/15): {r:?}"
    );
    assert!(
        r.stdout.contains(&format!(
            "this holdout's test part was never seen by the search, so this is tune's outer estimate ({})",
            pct(outer)
        )),
        "{r:?}"
    );

    // The same seed: the same bytes, printed and written.
    let again = dir.path().join("again.toml");
    let (stdout2, _) = tune_json(&rec, &prof, &again);
    assert_eq!(stdout, stdout2);
    assert_eq!(text, fs::read_to_string(&again).unwrap());
}

#[test]
fn tune_never_writes_over_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recordings(&dir.path().join("rec"), &["A", "B"], 4, 4);
    let prof = profile(dir.path(), "split", "method = \"k-fold\"\nfolds = 2");
    let recording = rec.join("A").join("A-trial01.csv");
    let before = (fs::read(&prof).unwrap(), fs::read(&recording).unwrap());
    for out in [&prof, &recording] {
        let r = run(&[
            "tune",
            p(&rec),
            "-p",
            p(&prof),
            "--out",
            p(out),
            "--budget",
            "48",
            "--overwrite",
        ]);
        assert_eq!(r.code, Some(2), "--out {}: {r:?}", out.display());
        assert!(
            r.stderr.contains(p(out)),
            "the message names the file: {r:?}"
        );
    }
    assert_eq!(
        before,
        (fs::read(&prof).unwrap(), fs::read(&recording).unwrap())
    );
}

#[test]
fn tune_refuses_plans_that_cannot_test_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "one-label",
            &["A"][..],
            4,
            "method = \"k-fold\"\nfolds = 2",
            "single label",
            "add recordings of another label",
        ),
        (
            "one-recording",
            &["A", "B"][..],
            1,
            "method = \"leave-one-out\"",
            "has only one recording",
            "cut its long recordings into shorter trials",
        ),
        (
            "few",
            &["A", "B"][..],
            2,
            "method = \"k-fold\"\nfolds = 10",
            "10 folds need at least as many recordings, and there are 4",
            "set [evaluation] folds to 4 or fewer",
        ),
    ];
    for (name, labels, trials, evaluation, what, todo) in cases {
        let rec = recordings(&dir.path().join(name), labels, trials, trials);
        let prof = profile(dir.path(), name, evaluation);
        let out = dir.path().join(format!("{name}-tuned.toml"));
        let r = tune_48(&rec, &prof, &out);
        assert_eq!(r.code, Some(2), "{name}: {r:?}");
        let message = r.stderr.trim();
        assert_eq!(message.lines().count(), 1, "{name}: one line: {r:?}");
        assert!(message.contains(what), "{name}: {r:?}");
        assert!(message.contains(todo), "{name}: says what to do: {r:?}");
        assert!(!out.exists(), "{name}: nothing written");
    }
}

#[test]
fn after_a_k_fold_search_the_figure_to_quote_is_the_outer_one() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recordings(&dir.path().join("rec"), &["A", "B", "C"], 6, 6);
    let prof = profile(dir.path(), "folds", "method = \"k-fold\"\nfolds = 3");
    let out = dir.path().join("tuned.toml");
    let r = tune_48(&rec, &prof, &out);
    assert_eq!(r.code, Some(0), "{r:?}");
    // The hint names the figure to quote, not an evaluate that flatters.
    let hint = r.stdout.lines().last().unwrap_or_default();
    assert!(
        hint.starts_with("quote the outer estimate (") && hint.contains("flatters"),
        "{r:?}"
    );
    assert!(hint.contains("hapticlab evaluate NEW_DIR -p"), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("# tuned_on = { "), "{text}");
    assert!(
        text.contains("so `hapticlab evaluate` of this profile on"),
        "{text}"
    );
    // evaluate on the recordings searched says its figure flatters...
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout
            .contains("note: this profile was tuned on these recordings (3-fold cross-validation"),
        "{r:?}\n{text}"
    );
    assert!(r.stdout.contains("quote tune's outer estimate, "), "{r:?}");
    // ...and on others (here one fewer) it does not.
    fs::remove_file(rec.join("A").join("A-trial06.csv")).unwrap();
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(!r.stdout.contains("tuned on these"), "{r:?}");
}

#[test]
fn leave_one_out_says_its_folds_in_a_line_and_names_what_it_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recordings(&dir.path().join("rec"), &["A", "B", "C"], 8, 8);
    let prof = profile(dir.path(), "loo", "method = \"leave-one-out\"");
    let out = dir.path().join("tuned.toml");
    let tune = |extra: &[&str]| {
        let mut args = vec!["tune", p(&rec), "-p", p(&prof), "--out", p(&out)];
        args.extend_from_slice(extra);
        run(&args)
    };
    let r = tune(&["--budget", "48", "--max-minutes", "0.0001"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    // 24 outer folds of one recording: one line, not 24.
    assert!(!r.stdout.contains("outer fold:"), "{r:?}");
    assert!(
        r.stdout.contains("  24 outer folds, ") && r.stdout.contains("(every fold: --json)"),
        "{r:?}"
    );
    // The kernels, refitted in every fold, cost more than a few
    // milliseconds of CPU here: left out, with what would search them.
    let line = r
        .stdout
        .lines()
        .find(|l| l.starts_with("left out: "))
        .unwrap_or_else(|| panic!("{r:?}"));
    assert!(
        line.contains(" kernels feature setting(s) (") && line.contains("; --max-minutes "),
        "{line}"
    );
    // Not a number of minutes above zero: refused in one line.
    for bad in ["0", "-3", "soon", "NaN"] {
        let r = tune(&["--overwrite", &format!("--max-minutes={bad}")]);
        assert_eq!(r.code, Some(2), "{bad}: {r:?}");
        assert!(
            r.stderr.contains("not a number of minutes above 0"),
            "{r:?}"
        );
    }
}
