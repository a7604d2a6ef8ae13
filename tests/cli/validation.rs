//! Honest validation: folds that never leak a group, stratification,
//! seeded reproducibility, macro-F1, sweeps.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

use hapticlab::classify::TrainingExample;
use hapticlab::evaluate::cv::{cross_validate, f1_scores, make_folds};
use hapticlab::evaluate::sweep::{parse_sweep, with_key};
use hapticlab::profile::{Classifier, LoadedProfile, SplitMethod};

use crate::common::{analysis, ex};

/// 12 sessions of 5 scans; every scan of a session is nearly the same point,
/// and the session's label is arbitrary: only leakage can classify it.
fn sessions() -> (Vec<TrainingExample>, Vec<String>) {
    let (mut ex_, mut groups) = (Vec::new(), Vec::new());
    for s in 0..12 {
        let label = ["A", "B", "C"][(s * 7 + s / 3) % 3];
        for i in 0..5 {
            ex_.push(ex(
                &format!("s{s}/{i}.csv"),
                label,
                &[s as f64 * 10.0 + i as f64 * 0.01],
            ));
            groups.push(format!("session-{s}"));
        }
    }
    (ex_, groups)
}

#[test]
fn grouped_folds_never_put_a_group_on_both_sides() {
    let (examples, groups) = sessions();
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    for (method, folds) in [
        (SplitMethod::KFold, 4),
        (SplitMethod::KFold, 12),
        (SplitMethod::LeaveOneOut, 0),
    ] {
        for seed in 0..5 {
            let f = make_folds(&labels, Some(&groups), method, folds, seed).unwrap();
            let mut tested = vec![0; examples.len()];
            for fold in &f {
                let test_groups: BTreeSet<&str> =
                    fold.iter().map(|&i| groups[i].as_str()).collect();
                for (i, g) in groups.iter().enumerate() {
                    if !fold.contains(&i) {
                        assert!(!test_groups.contains(g.as_str()), "{g} leaks in {method:?}");
                    }
                }
                for &i in fold {
                    tested[i] += 1;
                }
            }
            assert!(tested.iter().all(|&t| t == 1), "each example tested once");
        }
    }
    // Too few groups for the folds is an error, not a silent leak.
    assert!(make_folds(&labels, Some(&groups), SplitMethod::KFold, 13, 0).is_err());
}

#[test]
fn grouping_removes_the_optimism_of_leaky_folds() {
    let (examples, groups) = sessions();
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    let knn = Classifier {
        k: 1,
        ..Classifier::default()
    };
    let a = analysis(1);
    let leaky = make_folds(&labels, None, SplitMethod::KFold, 5, 1).unwrap();
    let r = cross_validate(
        &examples,
        &hapticlab::evaluate::cv::Dealt::plain(leaky.clone()),
        "t",
        &a,
        &knn,
        "k-fold",
        1,
        2,
    )
    .unwrap();
    assert_eq!(r.accuracy, 1.0, "a session's twin is always in training");
    let honest = make_folds(&labels, Some(&groups), SplitMethod::KFold, 4, 1).unwrap();
    let r = cross_validate(
        &examples,
        &hapticlab::evaluate::cv::Dealt::plain(honest.clone()),
        "t",
        &a,
        &knn,
        "grouped",
        1,
        2,
    )
    .unwrap();
    assert!(r.accuracy < 0.7, "grouped accuracy {}", r.accuracy);
}

#[test]
fn stratified_folds_hold_each_class_in_proportion() {
    let labels: Vec<&str> = (0..103).map(|i| ["A", "B", "C", "D"][i % 4]).collect();
    let f = make_folds(&labels, None, SplitMethod::KFold, 10, 7).unwrap();
    assert_eq!(f.len(), 10);
    let mut all: Vec<usize> = f.concat();
    all.sort_unstable();
    assert_eq!(all, (0..103).collect::<Vec<_>>());
    for fold in &f {
        let mut per: BTreeMap<&str, usize> = BTreeMap::new();
        for &i in fold {
            *per.entry(labels[i]).or_default() += 1;
        }
        assert!(per.values().all(|&n| (2..=3).contains(&n)), "{per:?}");
    }
    let loo = make_folds(&labels, None, SplitMethod::LeaveOneOut, 0, 0).unwrap();
    assert_eq!(loo.len(), 103);
}

#[test]
fn a_seeded_evaluation_gives_the_same_numbers_twice() {
    let examples: Vec<TrainingExample> = (0..60)
        .map(|i| {
            let l = ["A", "B", "C"][i % 3];
            let x = (i % 3) as f64 + ((i * 37 % 11) as f64 - 5.0) * 0.15;
            ex(&format!("{i}.csv"), l, &[x, (i * 13 % 7) as f64 * 0.1])
        })
        .collect();
    let labels: Vec<&str> = examples.iter().map(|e| e.label.as_str()).collect();
    let knn = Classifier {
        k: 3,
        ..Classifier::default()
    };
    let run = |seed, threads| {
        let f = make_folds(&labels, None, SplitMethod::KFold, 6, seed).unwrap();
        cross_validate(
            &examples,
            &hapticlab::evaluate::cv::Dealt::plain(f.clone()),
            "t",
            &analysis(2),
            &knn,
            "k-fold",
            seed,
            threads,
        )
        .unwrap()
    };
    let (a, b) = (run(42, 1), run(42, 2));
    assert_eq!(a, b);
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
    assert_ne!(a.test, run(43, 1).test, "another seed deals other folds");
    assert_eq!(a.folds.len(), 6);
    assert!(a.accuracy_std >= 0.0 && a.macro_f1 > 0.0);
}

#[test]
fn macro_f1_from_a_confusion_matrix() {
    // A: 8 of 10 right, 2 called B; B: 5 of 5 right.
    let c = vec![vec![8, 2], vec![0, 5]];
    let f = f1_scores(&c);
    assert!((f[0] - 2.0 * 1.0 * 0.8 / 1.8).abs() < 1e-12);
    assert!((f[1] - 2.0 * (5.0 / 7.0) / (5.0 / 7.0 + 1.0)).abs() < 1e-12);
    assert!(f1_scores(&[vec![0, 0], vec![1, 1]])[0].is_nan());
}

#[test]
fn sweep_values_and_keys() {
    let (k, v) = parse_sweep("k=1..15").unwrap();
    assert_eq!((k.as_str(), v.len()), ("k", 15));
    assert_eq!(parse_sweep("k=1..15:2").unwrap().1.len(), 8);
    let (_, v) = parse_sweep("band=[0.0,0.5],[0.5,1.0]").unwrap();
    assert_eq!(v.len(), 2);
    assert!(v[0].is_array());
    let (_, v) = parse_sweep("metric=euclidean,cosine").unwrap();
    assert_eq!(v[1].as_str(), Some("cosine"));
    // Decimal ranges keep the decimals written (no 0.015000000000000001).
    let (_, v) = parse_sweep("path.speed_m_per_s=0.005..0.02:0.005").unwrap();
    let v: Vec<f64> = v.iter().map(|x| x.as_float().unwrap()).collect();
    assert_eq!(v, [0.005, 0.01, 0.015, 0.02]);
    assert!(parse_sweep("k=3..1").is_err());
    assert!(parse_sweep("k=1..x").is_err());
    assert!(parse_sweep("k").is_err());

    let p = LoadedProfile::thesis().profile;
    let q = with_key(&p, "k", &toml::Value::Integer(3)).unwrap();
    assert_eq!(q.classifier.k, 3);
    let q = with_key(&p, "spectrum", &toml::Value::String("welch".into())).unwrap_err();
    assert!(q.to_string().contains("analysis.bins"), "{}", q.to_string());
    let q = with_key(&p, "taper", &toml::Value::String("hann".into())).unwrap();
    assert_eq!(q.analysis.taper, hapticlab::profile::Taper::Hann);
    assert!(with_key(&p, "nonsense", &toml::Value::Integer(1)).is_err());
}

#[test]
fn evaluate_cli_cross_validates_reproducibly() {
    let run = || {
        let out = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
            .args([
                "evaluate",
                "recordings/thesis-sim",
                "--folds",
                "5",
                "--seed",
                "9",
                "--json",
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    let a = run();
    assert_eq!(a, run());
    let v: serde_json::Value = serde_json::from_slice(&a).unwrap();
    for key in [
        "labels",
        "confusion",
        "accuracy",
        "per_class",
        "train",
        "test",
        "predictions",
        "folds",
        "accuracy_std",
        "macro_f1",
    ] {
        assert!(v.get(key).is_some(), "{key}");
    }
    assert_eq!(v["folds"].as_array().unwrap().len(), 5);
    assert_eq!(v["test"].as_array().unwrap().len(), 120);

    let out = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args([
            "evaluate",
            "recordings/thesis-sim",
            "--folds",
            "3",
            "--sweep",
            "k=1..5:2",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        text.lines()
            .filter(|l| l.starts_with(['1', '3', '5']))
            .count(),
        3,
        "{text}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args(["evaluate", "recordings/thesis-sim", "--group-by", "nope"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// How unevenly the folds share each class: the mean over classes of the
/// (population) standard deviation across folds of fold count / class count.
fn class_imbalance(labels: &[&str], folds: &[Vec<usize>]) -> f64 {
    let classes: BTreeSet<&str> = labels.iter().copied().collect();
    let mut total = 0.0;
    for c in &classes {
        let n = labels.iter().filter(|l| *l == c).count() as f64;
        let shares: Vec<f64> = folds
            .iter()
            .map(|f| f.iter().filter(|&&i| labels[i] == *c).count() as f64 / n)
            .collect();
        let m = shares.iter().sum::<f64>() / shares.len() as f64;
        total +=
            (shares.iter().map(|s| (s - m) * (s - m)).sum::<f64>() / shares.len() as f64).sqrt();
    }
    total / classes.len() as f64
}

/// Grouped folds as they were dealt before stratification: shuffled, then
/// largest first into the fold with the fewest examples.
fn size_balanced_folds(groups: &[String], folds: usize, seed: u64) -> Vec<Vec<usize>> {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, g) in groups.iter().enumerate() {
        by.entry(g).or_default().push(i);
    }
    let mut gs: Vec<Vec<usize>> = by.into_values().collect();
    gs.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    gs.sort_by_key(|g| std::cmp::Reverse(g.len()));
    let mut out = vec![Vec::new(); folds];
    for g in gs {
        let f = (0..folds).min_by_key(|&f| (out[f].len(), f)).unwrap();
        out[f].extend(g);
    }
    out
}

/// Trials of one texture each, of uneven lengths: (labels, groups).
fn trials() -> (Vec<&'static str>, Vec<String>) {
    let sizes: [(&str, &[usize]); 3] = [
        ("A", &[6, 4, 4, 2, 2, 3]),
        ("B", &[5, 5, 3, 3, 1, 1]),
        ("C", &[8, 2, 2, 2, 2, 4]),
    ];
    let (mut labels, mut groups) = (Vec::new(), Vec::new());
    for (label, trials) in sizes {
        for (t, &n) in trials.iter().enumerate() {
            for _ in 0..n {
                labels.push(label);
                groups.push(format!("{label}-trial-{t}"));
            }
        }
    }
    (labels, groups)
}

#[test]
fn grouped_folds_are_stratified_as_far_as_the_groups_allow() {
    let (labels, groups) = trials();
    let (mut strat, mut naive) = (0.0, 0.0);
    for seed in 0..30 {
        let f = make_folds(&labels, Some(&groups), SplitMethod::KFold, 3, seed).unwrap();
        assert!(f.iter().all(|fold| !fold.is_empty()));
        let (s, n) = (
            class_imbalance(&labels, &f),
            class_imbalance(&labels, &size_balanced_folds(&groups, 3, seed)),
        );
        assert!(
            s <= n + 1e-12,
            "seed {seed}: stratified {s:.3} vs size-balanced {n:.3}"
        );
        // Every fold tests every class here (each class has 6 trials for 3 folds).
        for fold in &f {
            let present: BTreeSet<&str> = fold.iter().map(|&i| labels[i]).collect();
            assert_eq!(present.len(), 3, "seed {seed}: {present:?}");
        }
        (strat, naive) = (strat + s, naive + n);
    }
    assert!(
        strat < 0.5 * naive,
        "stratified {strat:.3} vs size-balanced {naive:.3}"
    );

    // Two classes of four equal trials into four folds: one of each per fold.
    let labels: Vec<&str> = (0..40).map(|i| if i < 20 { "A" } else { "B" }).collect();
    let groups: Vec<String> = (0..40).map(|i| format!("t{}", i / 5)).collect();
    for seed in 0..20 {
        let f = make_folds(&labels, Some(&groups), SplitMethod::KFold, 4, seed).unwrap();
        for fold in &f {
            let a = fold.iter().filter(|&&i| labels[i] == "A").count();
            assert_eq!((a, fold.len()), (5, 10), "seed {seed}");
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
    #[test]
    fn stratified_grouped_folds_never_leak_and_test_everything_once(
        rows in proptest::collection::vec((0usize..4, 0usize..12), 2..120),
        folds in 2usize..8,
        seed in 0u64..1000,
    ) {
        let labels: Vec<&str> = rows.iter().map(|(c, _)| ["A", "B", "C", "D"][*c]).collect();
        let groups: Vec<String> = rows.iter().map(|(_, g)| format!("g{g}")).collect();
        let n_groups = groups.iter().collect::<BTreeSet<_>>().len();
        let made = make_folds(&labels, Some(&groups), SplitMethod::KFold, folds, seed);
        // A label in one group only is tested with nothing of it to train on: refused.
        let mut per_label: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
        for (l, g) in labels.iter().zip(&groups) {
            per_label.entry(*l).or_default().insert(g.as_str());
        }
        if folds > n_groups || per_label.values().any(|g| g.len() < 2) {
            proptest::prop_assert!(made.is_err());
            return Ok(());
        }
        let f = made.unwrap();
        proptest::prop_assert_eq!(&f, &make_folds(&labels, Some(&groups), SplitMethod::KFold, folds, seed).unwrap());
        let mut tested = vec![0; labels.len()];
        for fold in &f {
            proptest::prop_assert!(!fold.is_empty());
            let inside: BTreeSet<&str> = fold.iter().map(|&i| groups[i].as_str()).collect();
            for (i, g) in groups.iter().enumerate() {
                if !fold.contains(&i) {
                    proptest::prop_assert!(!inside.contains(g.as_str()), "{} leaks", g);
                }
            }
            for &i in fold {
                tested[i] += 1;
            }
        }
        proptest::prop_assert!(tested.iter().all(|&t| t == 1));
    }
}

#[test]
fn a_holdout_through_plan_validate_takes_the_same_split_as_plain_evaluate() {
    // 12 scans of each of two classes, named so file-name order and any
    // shuffle differ.
    let examples: Vec<TrainingExample> = (0..24)
        .map(|i| {
            let label = if i % 2 == 0 { "A" } else { "B" };
            ex(
                &format!("{label}/{label}_{i:03}.csv"),
                label,
                &[i as f64, 1.0],
            )
        })
        .collect();
    let mut lp = LoadedProfile::thesis();
    lp.profile.analysis = analysis(2);
    lp.profile.classifier.k = 1;
    lp.profile.evaluation.train_per_class = 8;
    lp.profile.evaluation.test_per_class = 4;
    let p = &lp.profile;
    let plain = hapticlab::evaluate::split(examples.clone(), &p.evaluation).unwrap();
    let want: BTreeSet<String> = plain.test.iter().map(|e| e.file.clone()).collect();

    let plan =
        hapticlab::evaluate::plan::Plan::new(p, &hapticlab::evaluate::plan::Overrides::default());
    assert!(
        plan.describe().contains("file-name order"),
        "{}",
        plan.describe()
    );
    let report =
        hapticlab::evaluate::plan::validate(p, examples.clone(), Default::default(), &plan)
            .unwrap();
    let got: BTreeSet<String> = report.test.iter().cloned().collect();
    assert_eq!(got, want);

    // Asked for a seed, it shuffles, as `evaluate --shuffle-seed` does.
    let args = hapticlab::evaluate::plan::Overrides {
        seed: Some(7),
        ..Default::default()
    };
    let plan = hapticlab::evaluate::plan::Plan::new(p, &args);
    let report =
        hapticlab::evaluate::plan::validate(p, examples.clone(), Default::default(), &plan)
            .unwrap();
    let mut eval = p.evaluation.clone();
    eval.shuffle_seed = Some(7);
    let shuffled = hapticlab::evaluate::split(examples, &eval).unwrap();
    let want: BTreeSet<String> = shuffled.test.iter().map(|e| e.file.clone()).collect();
    assert_eq!(report.test.iter().cloned().collect::<BTreeSet<_>>(), want);
}

/// Runs the binary in the crate's folder: (exit code, stderr).
fn hapticlab(args: &[&str]) -> (Option<i32>, String) {
    let out = crate::common::hapticlab().args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_cli_refuses_what_is_not_a_recording_naming_file_line_and_key() {
    for (file, line, key_and_why) in [
        ("time_nan.csv", 13, "t_s is NaN"),
        ("time_goes_back.csv", 15, "t_s goes back"),
        ("time_never_increases.csv", 19, "t_s never increases"),
        ("label_empty.csv", 2, "metadata `label`: label \"\""),
        (
            "label_newline.csv",
            2,
            "metadata `label`: label \"S2\\nS3\"",
        ),
        ("label_path.csv", 2, "metadata `label`: label \"../../etc\""),
    ] {
        let path = format!("tests/data/broken/{file}");
        let expected = format!("{path}:{line}: {key_and_why}");
        let (code, stderr) = hapticlab(&["features", &path]);
        assert_eq!(code, Some(2), "features {file}: {stderr}");
        assert!(stderr.contains(&expected), "features {file}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "one message: {stderr}");
        // `inspect` reports a dataset's health: the file is unreadable, on one line.
        let out = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
            .args(["inspect", &path])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout
                .lines()
                .any(|l| l.starts_with("unreadable: ") && l.contains(&expected)),
            "inspect {file}: {stdout}"
        );
    }
}

#[test]
fn the_cli_refuses_bins_that_are_not_a_pair() {
    let (code, stderr) = hapticlab(&["check", "profiles/invalid/bins-three-numbers.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("profiles/invalid/bins-three-numbers.toml:59:8: bins must be [first, last], two numbers; got more"),
        "{stderr}"
    );
    // Two million entries: refused at the key, not read as [1, 1].
    let dir = tempfile::tempdir().unwrap();
    let thesis =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/profiles/thesis.toml"))
            .unwrap();
    assert!(thesis.contains("\nbins = [1, 49]\n"));
    let huge = format!("[{}]", vec!["1"; 2_000_000].join(", "));
    let path = dir.path().join("huge-bins.toml");
    std::fs::write(
        &path,
        thesis.replace("\nbins = [1, 49]\n", &format!("\nbins = {huge}\n")),
    )
    .unwrap();
    let line = thesis.lines().position(|l| l == "bins = [1, 49]").unwrap() + 1;
    let (code, stderr) = hapticlab(&["check", path.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "huge-bins.toml:{line}:8: bins must be [first, last], two numbers; got more"
        )),
        "{stderr}"
    );
    for (bins, why) in [("[1]", "got one"), ("[]", "got none")] {
        std::fs::write(
            &path,
            thesis.replace("\nbins = [1, 49]\n", &format!("\nbins = {bins}\n")),
        )
        .unwrap();
        let (code, stderr) = hapticlab(&["check", path.to_str().unwrap()]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!(
                ":{line}:8: bins must be [first, last], two numbers; {why}"
            )),
            "{stderr}"
        );
    }
}

/// The `hapticlab-simulate-*` folders under `tmp`.
fn scratch_folders(tmp: &std::path::Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(tmp)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("hapticlab-simulate-"))
        })
        .collect()
}

/// Whether any file under `dir` ends in `.csv`.
fn holds_a_scan(dir: &std::path::Path) -> bool {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .any(|e| {
            let p = e.path();
            if p.is_dir() {
                holds_a_scan(&p)
            } else {
                p.extension().is_some_and(|x| x == "csv")
            }
        })
}

/// Polls `cond` until it holds, for at most `limit`.
fn wait_for(limit: std::time::Duration, mut cond: impl FnMut() -> bool) -> bool {
    let start = std::time::Instant::now();
    while start.elapsed() < limit {
        if cond() {
            return true;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    cond()
}

#[test]
fn ctrl_c_during_evaluate_simulate_removes_its_temporary_folder() {
    use std::time::Duration;
    let tmp = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_hapticlab"))
        .args([
            "evaluate",
            "--simulate",
            "--per-class",
            "400",
            "--threads",
            "2",
        ])
        .env("TMPDIR", tmp.path())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Mid-simulation: the folder exists and holds scans.
    let started = wait_for(Duration::from_secs(60), || {
        scratch_folders(tmp.path()).iter().any(|d| holds_a_scan(d))
    });
    if !started {
        let _ = child.kill();
        panic!("no simulated scan appeared in {}", tmp.path().display());
    }
    let interrupt = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(interrupt.success());
    let mut status = None;
    wait_for(Duration::from_secs(60), || {
        status = child.try_wait().unwrap();
        status.is_some()
    });
    let Some(status) = status else {
        let _ = child.kill();
        panic!("evaluate --simulate still runs 60 s after Ctrl-C");
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("interrupted: removed the temporary folder"),
        "{stderr}"
    );
    assert_eq!(
        scratch_folders(tmp.path()),
        Vec::<std::path::PathBuf>::new(),
        "{stderr}"
    );
}
