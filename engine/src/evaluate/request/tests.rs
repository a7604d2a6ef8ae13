use super::*;
use crate::classify::TrainingExample;

fn examples(per_class: &[(&str, usize)]) -> Vec<TrainingExample> {
    per_class
        .iter()
        .flat_map(|&(l, n)| {
            (0..n).map(move |i| TrainingExample {
                file: format!("{l}/{i}.csv"),
                label: l.to_string(),
                features: vec![i as f64],
            })
        })
        .collect()
}

/// The profile's plan, and the fallback's reason when it fell back.
fn fallen(lp: &LoadedProfile, per_class: &[(&str, usize)]) -> (Plan, Option<String>) {
    let mut plan = Plan::new(&lp.profile, &Overrides::default());
    let why = plan.fall_back(&lp.profile, &examples(per_class));
    (plan, why)
}

#[test]
fn the_fallback_keeps_the_profiles_split_and_falls_back_when_it_cannot_be_met() {
    let mut lp = LoadedProfile::thesis();
    let (plan, note) = fallen(&lp, &[("S1", 30), ("S2", 31)]);
    assert_eq!(plan.method, SplitMethod::Holdout);
    assert_eq!(note, None);
    let (plan, note) = fallen(&lp, &[("S1", 5), ("S2", 6)]);
    assert_eq!((plan.method, plan.folds), (SplitMethod::KFold, 5));
    assert_eq!(
        note.as_deref(),
        Some(
            "the holdout split needs 30 scans per texture (20 to train, 10 to test), S1 has 5: \
             evaluating by stratified 5-fold cross-validation instead"
        )
    );
    let (plan, note) = fallen(&lp, &[("S1", 4), ("S2", 3)]);
    assert_eq!(plan.method, SplitMethod::LeaveOneOut);
    assert!(
        note.unwrap()
            .ends_with("S2 has 3: evaluating by leave-one-out instead")
    );
    // A profile asking for k-fold gets k-fold, with its folds.
    lp.profile.evaluation.method = SplitMethod::KFold;
    lp.profile.evaluation.folds = Some(4);
    let (plan, note) = fallen(&lp, &[("S1", 5), ("S2", 5)]);
    assert_eq!(
        (plan.method, plan.folds, note),
        (SplitMethod::KFold, 4, None)
    );
}

#[test]
fn a_holdout_the_recordings_cannot_meet_says_how_to_go_on() {
    let lp = LoadedProfile::thesis();
    let dir = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
    for label in ["S1", "S2"] {
        std::fs::create_dir_all(dir.path().join(label)).unwrap();
        for i in 1..=5 {
            let name = format!("{label}_00{i}.csv.gz");
            std::fs::copy(
                shipped.join(label).join(&name),
                dir.path().join(label).join(&name),
            )
            .unwrap();
        }
    }
    let mut req = Request::of_recordings(vec![dir.path().to_path_buf()]);
    let e = run(&lp, &req, &Quiet).unwrap_err();
    assert!(e.to_string().contains("--fallback"), "{e}");
    assert!(e.is_bad_input());
    req.fallback = true;
    let ev = run(&lp, &req, &Quiet).unwrap();
    assert_eq!((ev.plan.method, ev.plan.folds), (SplitMethod::KFold, 5));
    assert!(ev.fell_back.unwrap().contains("S1 has 5"));
    assert_eq!(ev.recordings, 10);
    // 4 training scans of a texture per fold: k = 10 gives way.
    assert!(
        ev.outcome.k_used().iter().all(|&k| k < 10),
        "{:?}",
        ev.outcome.k_used()
    );
    assert!(ev.outcome.k_notice().is_some());
    assert_eq!(ev.outcome.report().unwrap().tested(), 10);
}
