//! The search's honesty: the outer score is reported (not the inner best),
//! choices are made on training folds only, groups and sub-windows stay on
//! one side, a seed gives one answer, and plans that cannot test are refused.

use super::parts::span_of;
use super::score::{Fold, Voting, extract, score_fold};
use super::*;
use crate::dataset::Entry;
use crate::profile::LoadedProfile;
use std::path::Path;

fn profile_text(evaluation: &str) -> String {
    format!(
        "name = \"t\"\n[analysis]\nchannel = \"x\"\naxis = \"t_s\"\nwindow = [0.0, 0.999]\n\
         spacing = 0.001\n[classifier]\nk = 1\n[evaluation]\n{evaluation}\n"
    )
}

fn profile(evaluation: &str) -> Profile {
    LoadedProfile::from_str(&profile_text(evaluation), "t.toml", Path::new("."))
        .unwrap()
        .profile
}

const HOLDOUT: &str = "method = \"holdout\"\ntrain_per_class = 5\ntest_per_class = 5";

/// A small deterministic generator.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// `classes` × `trials` one-second scans at 1 kHz; `signal(class, trial,
/// rng)` gives each. Files are named trial first, so file-name order is
/// trial order whatever the label.
fn scans(
    classes: usize,
    trials: usize,
    signal: impl Fn(usize, usize, &mut Lcg) -> Vec<f64>,
) -> Vec<Entry> {
    let mut rng = Lcg(99);
    let mut out = Vec::new();
    for c in 0..classes {
        for t in 0..trials {
            out.push(Entry {
                file: format!("t{t:02}-c{c}.csv"),
                label: format!("L{c}"),
                meta: vec![("session".into(), toml::Value::Integer((t / 2) as i64))],
                features: Vec::new(),
                axis: (0..1000).map(|i| i as f64 * 0.001).collect(),
                signals: vec![signal(c, t, &mut rng)],
                window: None,
            });
        }
    }
    // Loaded recordings come in file-name order.
    out.sort_by(|a, b| a.file.cmp(&b.file));
    out
}

fn tone(freq: f64, gain: f64, noise: f64, rng: &mut Lcg) -> Vec<f64> {
    (0..1000)
        .map(|i| {
            let t = i as f64 * 0.001;
            gain * ((std::f64::consts::TAU * freq * t).sin() + noise * rng.next())
        })
        .collect()
}

/// Tones 40 + 25·class Hz in noise; the later (test) trials are 30 times
/// louder and noisier, and 12 Hz higher (nearly half way to the next
/// class): a drift no training trial shows.
fn drifting() -> Vec<Entry> {
    scans(3, 10, |c, t, rng| {
        let late = t >= 5;
        tone(
            40.0 + 25.0 * c as f64 + if late { 12.0 } else { 0.0 },
            if late { 30.0 } else { 1.0 },
            if late { 6.0 } else { 3.0 },
            rng,
        )
    })
}

fn options(budget: usize, seed: u64) -> Options {
    Options {
        budget,
        seed,
        threads: 2,
        max_minutes: super::MAX_MINUTES,
    }
}

fn run(p: &Profile, s: &[Entry], budget: usize, seed: u64) -> TuneReport {
    tune("t", p, s, &options(budget, seed), &|_, _| {}).unwrap()
}

#[test]
fn the_outer_score_is_reported_not_the_inner_best() {
    let p = profile(HOLDOUT);
    let s = drifting();
    let r = run(&p, &s, 10_000, 0);
    assert_eq!(r.configurations, r.grid, "the whole grid fits the budget");
    let plan = Plan::new(&p, &Overrides::default());
    let part = &outer_parts(&p, &s, &plan).unwrap()[0];
    // Every setting's accuracy on the test part, as the fast path counts it.
    let settings = grid((&p.analysis, &p.classifier));
    let mut on_test = Vec::new();
    for st in &settings {
        let f = extract(&s, &st.analysis, 2).unwrap();
        let classes: Vec<usize> = s.iter().map(|e| e.label[1..].parse().unwrap()).collect();
        let fold = Fold {
            train: &part.train,
            test: &part.test,
        };
        let c = st.classifier.clone();
        let voting = Voting {
            classes: &classes,
            n_classes: 3,
            metric: c.metric,
            standardize: c.standardize,
        };
        let right = score_fold(&f, &voting, &fold, &[(c.k, c.weights)], None);
        on_test.push(right[0].correct as f64 / part.test.len() as f64);
    }
    let chosen = r.chosen_setting.as_ref().unwrap();
    let i = settings.iter().position(|st| st == chosen).unwrap();
    // Its inner score is not its test score: tune reports the latter
    // (that the choice never saw the test part is
    // `the_choice_is_made_on_training_folds_only`).
    assert_eq!(r.outer_accuracy, on_test[i]);
    assert_ne!(r.outer_accuracy, r.chosen.inner_accuracy);
    assert_eq!(r.outer.tested(), 15);
}

#[test]
fn a_seed_gives_one_answer_and_the_budget_caps_the_settings() {
    let p = profile(HOLDOUT);
    let s = drifting();
    let a = run(&p, &s, 96, 5);
    let b = run(&p, &s, 96, 5);
    assert_eq!(a, b);
    assert_eq!(a.configurations, 96);
    assert_eq!(
        a.feature_settings, 4,
        "the families in turn, fewest settings first: a kernels and a competing kernels setting (2 each), a spectrum (50 classifier settings), a quantiles setting (the rest)"
    );
    let c = run(&p, &s, 96, 6);
    assert_eq!(c.configurations, 96);
}

#[test]
fn the_choice_is_made_on_training_folds_only() {
    let p = profile(HOLDOUT);
    let s = drifting();
    let plan = Plan::new(&p, &Overrides::default());
    let part = outer_parts(&p, &s, &plan).unwrap()[0].clone();
    // Shuffle the test part's labels among themselves (each label keeps
    // its count there, and the files still sort after the training ones).
    let mut permuted = s.clone();
    let labels: Vec<String> = part.test.iter().map(|&i| s[i].label.clone()).collect();
    for (n, &i) in part.test.iter().enumerate() {
        permuted[i].label = labels[(n + 7) % labels.len()].clone();
    }
    assert_ne!(permuted, s);
    let again = outer_parts(&p, &permuted, &plan).unwrap()[0].clone();
    assert_eq!(again.train, part.train);
    let a = run(&p, &s, 200, 1);
    let b = run(&p, &permuted, 200, 1);
    assert_eq!(a.chosen, b.chosen);
    assert_eq!(a.table, b.table);
}

#[test]
fn groups_never_sit_on_both_sides() {
    let p = profile("method = \"k-fold\"\nfolds = 3\ngroup_by = \"session\"");
    let s = drifting();
    let plan = Plan::new(&p, &Overrides::default());
    let session = |i: usize| s[i].meta_text("session").unwrap();
    let disjoint = |part: &Part| {
        part.train
            .iter()
            .all(|&a| part.test.iter().all(|&b| session(a) != session(b)))
    };
    let outer = outer_parts(&p, &s, &plan).unwrap();
    assert_eq!(outer.len(), 3);
    for o in &outer {
        assert!(disjoint(o));
        let inner = inner_parts(&s, Some("session"), &o.train, 0, InnerSplit::Shuffled)
            .unwrap()
            .0;
        // 5 sessions at most in a training part of 3 folds over 5 sessions.
        assert!(inner.len() >= 2);
        for i in &inner {
            assert!(disjoint(i));
            assert!(i.train.iter().chain(&i.test).all(|r| o.train.contains(r)));
        }
    }
    let r = run(&p, &s, 48, 0);
    assert_eq!(r.outer.tested(), 30);
    assert_eq!(r.outer_folds.len(), 3);
}

/// Every recording's sub-windows are one point on a line, and both its
/// neighbours on the line carry the other label: a recording whose own
/// windows were among the training windows would find them at distance 0
/// and be named right; kept with their recording, none is. The inner
/// folds test each recording once, whole.
#[test]
fn sub_windows_stay_with_their_recording() {
    let features: score::Features = (0..12).map(|r| vec![vec![r as f64 * 10.0]; 3]).collect();
    let classes: Vec<usize> = (0..12).map(|r| r % 2).collect();
    let s = scans(2, 6, |_, _, rng| tone(50.0, 1.0, 1.0, rng));
    let all: Vec<usize> = (0..12).collect();
    let inner = inner_parts(&s, None, &all, 0, InnerSplit::Shuffled)
        .unwrap()
        .0;
    assert_eq!(inner.len(), 5);
    for r in 0..12 {
        let train: Vec<usize> = (0..12).filter(|&o| o != r).collect();
        let fold = Fold {
            train: &train,
            test: &[r],
        };
        let voting = Voting {
            classes: &classes,
            n_classes: 2,
            metric: crate::profile::Metric::Euclidean,
            standardize: false,
        };
        let right = score_fold(
            &features,
            &voting,
            &fold,
            &[(1, crate::profile::Weights::Uniform)],
            None,
        );
        assert_eq!(right[0].correct, 0, "recording {r}");
    }
    let mut tested: Vec<usize> = inner.iter().flat_map(|p| p.test.iter().copied()).collect();
    tested.sort_unstable();
    assert_eq!(tested, all, "each recording tested once, whole");
    // With sub-windows searched, the outer test counts recordings.
    let p = profile(HOLDOUT);
    let r = run(&p, &drifting(), 10_000, 0);
    assert!(
        r.feature_settings_scored
            .iter()
            .any(|d| d.0.iter().any(|(k, v)| k == "windows" && v != "none"))
    );
    assert_eq!(r.outer.tested(), 15);
}

#[test]
fn plans_that_cannot_test_are_refused() {
    let one_label = scans(1, 6, |_, _, rng| tone(50.0, 1.0, 1.0, rng));
    let p = profile("method = \"k-fold\"\nfolds = 3");
    let e = tune("t", &p, &one_label, &options(10, 0), &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("single label"), "{e}");

    let one_each = scans(3, 1, |c, _, rng| tone(50.0 + c as f64, 1.0, 1.0, rng));
    let loo = profile("method = \"leave-one-out\"");
    let e = tune("t", &loo, &one_each, &options(10, 0), &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("has only one recording"), "{e}");
    assert!(e.is_bad_input());

    let few = scans(2, 2, |c, _, rng| tone(50.0 + c as f64, 1.0, 1.0, rng));
    let ten = profile("method = \"k-fold\"\nfolds = 10");
    let e = tune("t", &ten, &few, &options(10, 0), &|_, _| {}).unwrap_err();
    assert!(
        e.to_string()
            .contains("10 folds need at least as many recordings, and there are 4"),
        "{e}"
    );
}

/// The tuned profile writes every option searched: one the option list
/// declares values for is written without a line of its own here.
#[test]
fn the_tuned_profile_writes_every_searched_option() {
    let p = profile(HOLDOUT);
    let g = space::grid((&p.analysis, &p.classifier));
    let decided = text::decided(&g[0]);
    for row in space::space() {
        let section = if row.features {
            "analysis"
        } else {
            "classifier"
        };
        let lines = &decided.iter().find(|(s, _)| *s == section).unwrap().1;
        assert!(
            lines.iter().any(|(k, _)| *k == row.option),
            "{section}.{} is searched but not written",
            row.option
        );
    }
}

/// Every setting of the grid, written into a profile, loads and reads
/// back as itself (the cepstra settings' bins aside, which bands replace).
#[test]
fn every_setting_written_reads_back() {
    let original = "name = \"t\"\n[analysis]\nchannel = \"x\"\naxis = \"t_s\"\nwindow = [0.0, 0.999]\n\
         spacing = 0.001\nspectrum = \"log-welch\"\nbins = [1, 64]\n[classifier]\nk = 1\n[evaluation]\n\
         method = \"holdout\"\ntrain_per_class = 5\ntest_per_class = 5\n";
    let p = LoadedProfile::from_str(original, "t.toml", Path::new("."))
        .unwrap()
        .profile;
    let report = run(&p, &drifting(), 48, 0);
    let settings = grid((&p.analysis, &p.classifier));
    assert!(settings.iter().any(|s| s.analysis.bands.is_some()));
    for s in &settings {
        let text = text::tuned_profile(original, s, &report, "test");
        let back = LoadedProfile::from_str(&text, "tuned.toml", Path::new("."))
            .unwrap_or_else(|e| panic!("{e}\n{text}"))
            .profile;
        assert!(
            text::reads_back_as(s, &back.analysis, &back.classifier),
            "{:?}\n{text}",
            s.describe()
        );
    }
}

/// A grid resampled once gives every feature setting on it the features
/// that resampling for each would, bit for bit (one channel over the
/// whole search, and two channels).
#[test]
fn a_shared_grid_gives_the_features_resampling_again_gives() {
    use super::score::{extract_resampled, resample};
    let p = profile(HOLDOUT);
    let scans = drifting();
    let settings = grid((&p.analysis, &p.classifier));
    let mut shared = 0;
    for s in &settings {
        let first = settings
            .iter()
            .find(|o| same_grid(&o.analysis, &s.analysis))
            .unwrap();
        shared += usize::from(first.feature_key() != s.feature_key());
        let kept = resample(&scans, &first.analysis, 2).unwrap();
        assert_eq!(
            extract_resampled(&scans, &kept, &s.analysis, 2).unwrap(),
            extract(&scans, &s.analysis, 2).unwrap(),
            "{:?}",
            s.describe()
        );
    }
    assert!(shared > 0, "no two feature settings share a grid");

    let mut two = p.analysis.clone();
    two.channels = vec!["y".into()];
    two.spectrum = crate::profile::SpectrumKind::LogWelch;
    let mut scans2 = scans.clone();
    for (i, s) in scans2.iter_mut().enumerate() {
        let y: Vec<f64> = s.signals[0].iter().map(|v| v * 0.5 + i as f64).collect();
        s.signals.push(y);
    }
    let kept = resample(&scans2, &two, 1).unwrap();
    assert_eq!(kept[0][0].len(), 2);
    assert_eq!(
        extract_resampled(&scans2, &kept, &two, 1).unwrap(),
        extract(&scans2, &two, 1).unwrap()
    );
}

/// `n` trials of 1 s every `hop` s cut from one long recording per class
/// (as `import --split 1 --split-hop HOP` writes them).
fn cut_trials(classes: usize, n: usize, hop: f64) -> Vec<Entry> {
    let mut s = scans(classes, n, |c, _, rng| {
        tone(40.0 + 25.0 * c as f64, 1.0, 3.0, rng)
    });
    for e in &mut s {
        let t: usize = e.file[1..3].parse().unwrap();
        let c = &e.label;
        e.meta = vec![
            ("source".into(), toml::Value::String(format!("{c}.csv"))),
            ("segment".into(), toml::Value::Integer(t as i64 + 1)),
            ("segment_start_s".into(), toml::Value::Float(t as f64 * hop)),
            ("segment_length_s".into(), toml::Value::Float(1.0)),
        ];
    }
    s
}

#[test]
fn overlapping_trials_are_folded_in_time_and_their_neighbours_left_out() {
    // Half-overlapping: trial t shares signal with t - 1 and t + 1.
    let s = cut_trials(2, 20, 0.5);
    let all: Vec<usize> = (0..s.len()).collect();
    let inner = inner_parts(&s, None, &all, 0, InnerSplit::Shuffled)
        .unwrap()
        .0;
    assert_eq!(inner.len(), 5);
    let span = |i: usize| span_of(&s[i]).unwrap();
    let mut tested = vec![0; s.len()];
    for part in &inner {
        for &t in &part.test {
            tested[t] += 1;
            // No training trial overlaps a test one.
            assert!(part.train.iter().all(|&r| !span(r).overlaps(&span(t))));
        }
        // Each fold tests a block of 4 consecutive trials of each class,
        // and trains on all but those and their 2 neighbours (1 at an end).
        assert_eq!(part.test.len(), 8);
        assert!(
            part.train.len() == 28 || part.train.len() == 30,
            "{}",
            part.train.len()
        );
    }
    assert!(tested.iter().all(|&n| n == 1), "each trial tested once");
    // Trials that only touch (hop = length) keep the shuffled folds.
    let touching = cut_trials(2, 20, 1.0);
    let shuffled = inner_parts(&touching, None, &all, 0, InnerSplit::Shuffled)
        .unwrap()
        .0;
    let plain = inner_parts(
        &scans(2, 20, |_, _, rng| tone(50.0, 1.0, 1.0, rng)),
        None,
        &all,
        0,
        InnerSplit::Shuffled,
    );
    assert_eq!(shuffled, plain.unwrap().0);
    // The report says how the inner folds were made: a shuffled holdout
    // keeps shuffled folds but over overlapping trials.
    let p =
        profile("method = \"holdout\"\ntrain_per_class = 14\ntest_per_class = 3\nshuffle_seed = 3");
    let r = run(&p, &cut_trials(2, 20, 0.5), 48, 0);
    assert_eq!(r.inner_split, InnerSplit::Blocks);
    assert!(r.inner_folds_in_time);
    let r = run(&p, &touching, 48, 0);
    assert_eq!(r.inner_split, InnerSplit::Shuffled);
    assert!(!r.inner_folds_in_time);
}

#[test]
fn one_group_is_told_to_change_group_by_not_folds() {
    let p = profile("method = \"k-fold\"\nfolds = 3\ngroup_by = \"rig\"");
    let mut s = drifting();
    for e in &mut s {
        e.meta.push(("rig".into(), toml::Value::String("a".into())));
    }
    let plan = Plan::new(&p, &Overrides::default());
    let e = check_plan(&s, &plan).unwrap_err().to_string();
    assert!(
        e.contains("give group_by a key with two values") && !e.contains("1 or fewer"),
        "{e}"
    );
}

#[test]
fn under_a_time_split_the_inner_folds_go_forward_in_time() {
    let p = profile(HOLDOUT);
    let s = drifting();
    let plan = Plan::new(&p, &Overrides::default());
    assert_eq!(InnerSplit::of(&plan), InnerSplit::Forward);
    let part = &outer_parts(&p, &s, &plan).unwrap()[0];
    let (inner, made) = inner_parts(&s, None, &part.train, 0, InnerSplit::Forward).unwrap();
    assert_eq!(made, InnerSplit::Forward);
    // 5 training trials of each label: 4 folds, fold j testing trial j.
    assert_eq!(inner.len(), 4);
    let trial = |i: usize| s[i].file[1..3].parse::<usize>().unwrap();
    for (j, f) in inner.iter().enumerate() {
        assert!(f.test.iter().all(|&t| trial(t) == j + 1), "fold {j}");
        assert!(f.train.iter().all(|&r| trial(r) <= j), "fold {j}");
        assert_eq!(f.train.len(), 3 * (j + 1));
    }
    let r = run(&p, &s, 48, 0);
    assert_eq!(r.inner_split, InnerSplit::Forward);
    assert!(r.inner_folds_in_time);
    // A shuffled holdout keeps shuffled inner folds.
    let shuffled = profile(&format!("{HOLDOUT}\nshuffle_seed = 4"));
    let plan = Plan::new(&shuffled, &Overrides::default());
    assert_eq!(InnerSplit::of(&plan), InnerSplit::Shuffled);
    assert_eq!(run(&shuffled, &s, 48, 0).inner_split, InnerSplit::Shuffled);
}

#[test]
fn equal_inner_accuracies_go_to_the_wider_margin_then_the_simplest() {
    let p = profile(HOLDOUT);
    let settings = grid((&p.analysis, &p.classifier));
    let simplest = (0..settings.len())
        .min_by_key(|&i| settings[i].simplicity())
        .unwrap();
    // Another setting of the same family and classifier.
    let other = (0..settings.len())
        .find(|&i| i != simplest && settings[i].family_rank() == settings[simplest].family_rank())
        .unwrap();
    let saturated = InnerScore {
        accuracy: 1.0,
        margin: 0.2,
        true_share: 1.0,
    };
    let mut scores = vec![InnerScore::default(); settings.len()];
    scores[simplest] = saturated;
    scores[other] = InnerScore {
        margin: 0.5,
        true_share: 0.8,
        ..saturated
    };
    assert_eq!(best(&settings, &scores), other, "the wider margin");
    scores[other].margin = 0.2;
    assert_eq!(best(&settings, &scores), simplest, "the larger share");
    scores[other].true_share = 1.0;
    assert_eq!(best(&settings, &scores), simplest, "then the simplest");
    // On data where many settings saturate, the choice has the widest
    // margin of those that tie with it.
    let r = run(&p, &drifting(), 10_000, 0);
    let ties: Vec<&Scored> = r
        .table
        .iter()
        .filter(|t| t.inner_accuracy == r.chosen.inner_accuracy && t.family == r.chosen.family)
        .collect();
    assert!(ties.len() > 1, "the data saturates the inner folds");
    assert!(ties.iter().all(|t| t.inner_margin <= r.chosen.inner_margin));
    // Between families equal accuracies go to the simpler family: their
    // margins are not on one scale.
    for f in &r.families {
        if f.inner_accuracy == r.chosen.inner_accuracy {
            let rank = |family: &str| {
                [
                    "spectrum + knn",
                    "spectrum + ridge",
                    "spectrum + lda",
                    "quantiles + knn",
                    "quantiles + ridge",
                    "quantiles + lda",
                ]
                .iter()
                .position(|x| *x == family)
                .unwrap_or(9)
            };
            assert!(rank(&r.chosen.family) <= rank(&f.family), "{f:?}");
        }
    }
}

/// A sawtooth that rises and the same that falls: one is the other
/// reversed in time, so their magnitude spectra are the same and no
/// spectrum tells them apart; the shape of a rise (kernels) or the
/// quantiles of the first differences do.
fn saws() -> Vec<Entry> {
    scans(2, 20, |c, _, rng| {
        let phase = rng.next() + 0.5;
        (0..1000)
            .map(|i| {
                let x = (i as f64 / 37.0 + phase).fract();
                let saw = if c == 0 { x } else { 1.0 - x };
                saw + 0.05 * rng.next()
            })
            .collect()
    })
}

#[test]
fn a_texture_no_spectrum_tells_apart_goes_to_another_family() {
    let holdout = "method = \"holdout\"\ntrain_per_class = 10\ntest_per_class = 10";
    let r = run(&profile(holdout), &saws(), 10_000, 0);
    let inner = |family: &str| {
        r.families
            .iter()
            .find(|f| f.family == family)
            .unwrap_or_else(|| panic!("{family} not scored: {:?}", r.families))
            .inner_accuracy
    };
    // Every family and classifier was scored (both kinds of kernels with
    // the linear classifiers only).
    assert_eq!(r.families.len(), 10, "{:?}", r.families);
    // The best of a thousand spectrum settings scores above chance by
    // luck in folds of four, but below the family that sees the shape.
    assert!(
        inner("spectrum + knn") < r.chosen.inner_accuracy,
        "{:?}",
        r.families
    );
    assert!(!r.chosen.family.starts_with("spectrum"), "{:?}", r.families);
    assert!(r.chosen.inner_accuracy >= 0.9, "{:?}", r.chosen);
    assert!(r.outer_accuracy >= 0.9, "outer {}", r.outer_accuracy);
    // The tuned profile says the family, and reads back as the setting.
    let setting = r.chosen_setting.as_ref().unwrap();
    assert!(setting.analysis.features != crate::profile::FeatureFamily::Spectrum);
    let text = text::tuned_profile(&profile_text(holdout), setting, &r, "saws");
    assert!(
        text.contains(&format!("# Family chosen: {}", r.chosen.family)),
        "{text}"
    );
    let back = LoadedProfile::from_str(&text, "t.toml", Path::new(".")).unwrap();
    assert!(text::reads_back_as(
        setting,
        &back.profile.analysis,
        &back.profile.classifier
    ));
}

#[test]
fn a_small_budget_still_tries_every_family() {
    let r = run(&profile(HOLDOUT), &saws(), 60, 0);
    assert!(r.configurations <= 60);
    let mut features: Vec<&str> = r
        .families
        .iter()
        .map(|f| f.family.split(' ').next().unwrap())
        .collect();
    features.sort_unstable();
    features.dedup();
    assert_eq!(
        features,
        ["hydra", "kernels", "quantiles", "spectrum"],
        "{:?}",
        r.families
    );
}

#[test]
fn kernels_too_costly_for_the_search_are_left_out_and_named() {
    let mut o = options(10_000, 0);
    // At the default every family is searched on these short windows.
    let all = tune("t", &profile(HOLDOUT), &saws(), &o, &|_, _| {}).unwrap();
    assert!(all.left_out.is_empty(), "{:?}", all.left_out);
    assert!(all.families.iter().any(|f| f.family.starts_with("kernels")));
    // With a hundredth of a second, the random kernels (fitted fold by
    // fold) and the competing kernels (made once per recording, but dear)
    // are left out before any work and said to be; the rest is searched
    // as before.
    o.max_minutes = 1.0 / 6000.0;
    let r = tune("t", &profile(HOLDOUT), &saws(), &o, &|_, _| {}).unwrap();
    assert_eq!(r.left_out.len(), 2, "{:?}", r.left_out);
    for (l, family, work) in [
        (&r.left_out[0], "kernels", "fits"),
        (&r.left_out[1], "hydra", "made once"),
    ] {
        assert_eq!(l.family, family);
        let scored = all
            .feature_settings_scored
            .iter()
            .filter(|f| f.0.iter().any(|(_, v)| v == family))
            .count();
        assert_eq!(l.feature_settings, scored);
        assert!(l.reason.contains("--max-minutes"), "{}", l.reason);
        assert!(l.reason.contains(work), "{}", l.reason);
        assert!(!r.families.iter().any(|f| f.family.starts_with(family)));
    }
    assert_eq!(
        r.grid + r.left_out[0].settings + r.left_out[1].settings,
        all.grid
    );
    assert!(r.families.iter().any(|f| f.family.starts_with("quantiles")));
    // The tuned profile says so too.
    let setting = r.chosen_setting.as_ref().unwrap();
    let text = text::tuned_profile(&profile_text(HOLDOUT), setting, &r, "saws");
    assert!(text.contains("\n# Left out: "), "{text}");
}

#[test]
fn features_evaluate_would_refuse_are_never_searched() {
    let p = profile(HOLDOUT);
    let all = grid((&p.analysis, &p.classifier));
    let work = cost::Work {
        transformed: 10,
        fits: 1,
    };
    // A holdout of `n` recordings in two labels, half of each trained on.
    let holdout = |n: usize| Fits {
        recordings: n,
        fits: 1,
        train: n / 2,
    };
    // Over the limit of feature vectors evaluate and train keep to.
    let (kept, left) = cost::affordable(
        all.clone(),
        holdout(crate::dataset::MAX_VECTORS + 1),
        work,
        10.0,
    );
    assert!(kept.is_empty());
    assert_eq!(left.iter().map(|l| l.settings).sum::<usize>(), all.len());
    assert!(left.iter().all(|l| l.reason.contains("evaluate and train")));
    // Few enough values, but too many to validate: 5000 recordings of
    // hundreds of features compare over 10^10 values.
    let (kept, left) = cost::affordable(all.clone(), holdout(5000), work, 10.0);
    assert!(
        left.iter()
            .any(|l| l.reason.contains("evaluate would refuse to validate")),
        "{left:?}"
    );
    for s in &kept {
        let vectors = 5000
            * s.analysis
                .windows
                .map_or(1, |_| s.analysis.sub_windows().len());
        assert!(
            crate::evaluate::plan::check_validation(
                s.classifier.method,
                vectors,
                s.analysis.fitted_feature_count(),
                holdout(5000)
            )
            .is_ok()
        );
    }
    assert_eq!(
        kept.len() + left.iter().map(|l| l.settings).sum::<usize>(),
        all.len()
    );
    let (kept, left) = cost::affordable(all.clone(), holdout(20), work, 10.0);
    assert_eq!(kept.len(), all.len());
    assert!(left.is_empty());
}

#[test]
fn forward_folds_share_kernels_fitted_on_what_every_fold_trains_on() {
    let holdout = "method = \"holdout\"\ntrain_per_class = 10\ntest_per_class = 10";
    let p = profile(holdout);
    let s = saws();
    let plan = Plan::new(&p, &Overrides::default());
    let part = &outer_parts(&p, &s, &plan).unwrap()[0];
    let (inner, _) = inner_parts(&s, None, &part.train, 0, InnerSplit::Forward).unwrap();
    assert!(inner.len() >= 2);
    let mut analysis = p.analysis.clone();
    analysis.features = FeatureFamily::Kernels;
    analysis.kernel_features = Some(84 * 4);
    let features = extract(&s, &analysis, 1).unwrap();
    let shared = SharedKernels::fit(&analysis, &s, &features, &inner)
        .expect("forward folds all train on the earliest trials");
    // Fitted on the recordings every fold trains on: none an inner test.
    let common: Vec<usize> = part
        .train
        .iter()
        .copied()
        .filter(|r| inner.iter().all(|f| f.train.contains(r)))
        .collect();
    assert!(!common.is_empty() && common.len() < part.train.len());
    assert!(
        inner
            .iter()
            .all(|f| f.test.iter().all(|t| !common.contains(t)))
    );
    let (s, features) = (&s[..], &features);
    let examples = |recordings: &[usize]| examples_of(s, features, recordings);
    let fitted = crate::classify::fit_kernels(&analysis, &examples(&common))
        .unwrap()
        .unwrap();
    assert_eq!(shared.kernels, fitted);
    // Every window of the folds transformed once, as the kernels transform it.
    let mut used: Vec<usize> = inner
        .iter()
        .flat_map(|f| f.train.iter().chain(&f.test))
        .copied()
        .collect();
    used.sort_unstable();
    used.dedup();
    assert_eq!(used, parts::recordings_of(&inner));
    assert_eq!(shared.rows.keys().copied().collect::<Vec<_>>(), used);
    let mut conv = fitted.convolution();
    for (r, rows) in &shared.rows {
        assert_eq!(rows.len(), features[*r].len());
        for (w, row) in features[*r].iter().zip(rows) {
            let mut out = vec![0.0; fitted.feature_count()];
            fitted.transform(w, &mut conv, &mut out);
            assert_eq!(row, &out);
        }
    }
    // A fold's models are trained on its own training windows only, and
    // classify as models trained on raw windows with those kernels do.
    let classifiers = [crate::profile::Classifier {
        method: Method::Ridge,
        ..p.classifier.clone()
    }];
    let fold = &inner[inner.len() - 1];
    let rows: Vec<&[f64]> = fold
        .train
        .iter()
        .flat_map(|r| shared.rows[r].iter().map(Vec::as_slice))
        .collect();
    let model = Model::train_each_transformed(
        "t",
        &analysis,
        &classifiers,
        examples(&fold.train),
        &shared.kernels,
        &rows,
    )
    .unwrap()
    .pop()
    .unwrap()
    .unwrap();
    assert_eq!(model.examples.len(), rows.len());
    for &t in &fold.test {
        assert_eq!(
            model.classify_transformed(&shared.rows[&t]).unwrap(),
            model.classify_windows(&features[t]).unwrap()
        );
    }
    // Shuffled folds test every recording once: nothing to share.
    let (shuffled, _) = inner_parts(s, None, &part.train, 0, InnerSplit::Shuffled).unwrap();
    assert!(SharedKernels::fit(&analysis, s, features, &shuffled).is_none());
}

#[test]
fn what_every_fold_trains_on_is_found_as_by_asking_each_fold() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..200 {
        let recordings = rng.random_range(1..40usize);
        let folds: Vec<Part> = (0..rng.random_range(0..6usize))
            .map(|_| {
                let pick = |rng: &mut rand_chacha::ChaCha8Rng| -> Vec<usize> {
                    (0..rng.random_range(0..recordings + 5))
                        .map(|_| rng.random_range(0..recordings))
                        .collect()
                };
                Part {
                    train: pick(&mut rng),
                    test: pick(&mut rng),
                }
            })
            .collect();
        let want: Vec<usize> = match folds.split_first() {
            Some((first, rest)) if !rest.is_empty() => first
                .train
                .iter()
                .copied()
                .filter(|r| rest.iter().all(|f| f.train.contains(r)))
                .collect(),
            _ => Vec::new(),
        };
        assert_eq!(parts::trained_on_by_all(&folds), want, "{folds:?}");
    }
}
