//! `hapticlab evaluate`: one command path for the thesis's holdout split,
//! k-fold, leave-one-out, grouped folds and parameter sweeps, over
//! recordings or datasets simulated on the fly. This file holds the
//! arguments and the printing; the work is the engine's
//! ([`crate::evaluate`]: `split`/`evaluate` for the holdout,
//! `evaluate/plan.rs` for cross-validation, `evaluate/sweep.rs` for sweeps).
//!
//! Without any validation flag, under a profile whose `[evaluation]` asks
//! for a holdout, it prints the thesis's Table 4.1 (`--json`: the
//! [`crate::evaluate::Report`]); otherwise a [`crate::evaluate::cv::CvReport`]
//! or a [`crate::evaluate::sweep::Sweep`].

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::Args;

use crate::classify::Model;
use crate::dataset::{self, Keep, Options, Unusable, meta_text};
use crate::evaluate::plan::{Dataset, Overrides, Plan, validate_with_votes};
use crate::evaluate::sweep::{
    SimPlan, Sweep, Swept, resolve_all, simulated_dataset, sweep_grid, sweep_grid_simulated,
};
use crate::evaluate::{self, EvaluateError, windows};
use crate::profile::SplitMethod;
use crate::support::{
    Failure, ProfileArg, bad, find_recordings, load_examples_on, load_profile, progress_bar,
    runtime, warn_skipped,
};

#[derive(Debug, Args)]
pub struct EvaluateArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// Recordings or folders of recordings (none with --simulate).
    #[arg(
        required_unless_present = "simulate",
        conflicts_with = "simulate",
        value_name = "PATH"
    )]
    pub paths: Vec<PathBuf>,
    /// Shuffle each class with this seed before the split (default: file-name order).
    #[arg(long, value_name = "S")]
    pub shuffle_seed: Option<u64>,
    /// Print JSON for scripts.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub validation: ValidationArgs,
}

/// The options `evaluate` gains for cross-validation and sweeps.
#[derive(Debug, Args, Clone, Default)]
pub struct ValidationArgs {
    /// k-fold cross-validation with N folds, stratified by class (or grouped with --group-by).
    #[arg(long, value_name = "N", conflicts_with = "loo")]
    pub folds: Option<usize>,
    /// Leave-one-out (leave-one-group-out with --group-by).
    #[arg(long)]
    pub loo: bool,
    /// Keep recordings with the same value of this metadata key (session, trial, …) on one side of every split.
    #[arg(long, value_name = "KEY")]
    pub group_by: Option<String>,
    /// Seed of the folds' shuffle (default: the profile's evaluation.shuffle_seed, else 0).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Evaluate once per value of a profile key: `k=1..15`, `k=1..15:2`, `metric=euclidean,cosine`, `spacing=0.0002,0.0003`, `spectrum=magnitude,welch`; with --simulate also `controller.stiffness_n_per_m[1]=90..540:90`, `path.speed_m_per_s=0.005..0.03:0.005`. Repeat for a grid of every combination (two keys print as a matrix). A value the profile refuses is listed as not evaluated, with the reason, and the sweep goes on (exit 2 only when nothing could be evaluated).
    #[arg(long, value_name = "KEY=VALUES")]
    pub sweep: Vec<String>,
    /// Worker threads for the folds and the reading (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Evaluate a dataset simulated from the profile in virtual time (no PATH; a temporary folder, removed after); with --sweep of a [controller], [path], [simulator] or [device] key, one dataset per value.
    #[arg(long)]
    pub simulate: bool,
    /// With --simulate: scans per texture (default: the profile's train_per_class + test_per_class; 30, or the folds, when it names neither).
    #[arg(long, value_name = "N")]
    pub per_class: Option<usize>,
}

impl ValidationArgs {
    /// What these flags set over the profile's `[evaluation]`.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            folds: self.folds,
            loo: self.loo,
            group_by: self.group_by.clone(),
            seed: self.seed,
            threads: self.threads,
        }
    }

    /// Whether anything beyond the thesis's holdout was asked for.
    pub fn is_active(&self) -> bool {
        self.folds.is_some()
            || self.loo
            || self.group_by.is_some()
            || !self.sweep.is_empty()
            || self.simulate
            || self.per_class.is_some()
    }
}

/// `hapticlab evaluate`: the holdout of the thesis when nothing else is
/// asked for, else cross-validation, a sweep, or simulated data.
pub fn run(a: EvaluateArgs) -> Result<(), Failure> {
    let method = load_profile(&a.profile)?.profile.evaluation.method;
    if a.validation.is_active() || method != SplitMethod::Holdout {
        validated(&a.profile, &a.paths, a.shuffle_seed, a.json, &a.validation)
    } else {
        let threads = a.validation.threads.unwrap_or_else(dataset::cores);
        holdout(&a.profile, &a.paths, a.shuffle_seed, a.json, threads)
    }
}

fn holdout(
    profile: &ProfileArg,
    paths: &[PathBuf],
    shuffle_seed: Option<u64>,
    json: bool,
    threads: usize,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let examples = load_examples_on(paths, &lp.profile.analysis, threads)?;
    evaluate::check_two_labels(&examples).map_err(bad)?;
    let mut eval = lp.profile.evaluation.clone();
    if shuffle_seed.is_some() {
        eval.shuffle_seed = shuffle_seed;
    }
    let not_enough = |e: EvaluateError| match e {
        EvaluateError::NotEnough { .. } => {
            bad(format!("{e}; cross-validate instead (--folds 5 or --loo)"))
        }
        e => bad(e),
    };
    if lp.profile.analysis.windows.is_some() {
        return holdout_windows(&lp.profile, examples, &eval, json, not_enough);
    }
    let split = evaluate::split(examples, &eval).map_err(not_enough)?;
    let model = Model::train_adapting_k(
        &lp.profile.name,
        &lp.profile.analysis,
        &lp.profile.classifier,
        split.train,
    )
    .map_err(bad)?;
    if let Some(note) = model.k_notice() {
        crate::errln!("note: {note}");
    }
    let report = evaluate::evaluate(&model, &split.test).map_err(bad)?;
    if json {
        crate::outln!("{}", serde_json::to_string(&report).map_err(runtime)?);
    } else {
        crate::outln!(
            "profile {}: k-NN k = {}, {} training and {} test recordings per class{}",
            lp.profile.name,
            lp.profile.classifier.k_text(),
            eval.train_per_class,
            eval.test_per_class,
            eval.shuffle_seed
                .map_or(" (file-name order)".into(), |s| format!(
                    " (shuffled, seed {s})"
                ))
        );
        crate::outp!("{}", report.table());
    }
    Ok(())
}

/// The holdout with `[analysis] windows`: whole recordings on each side
/// (the ones the split picks without windows), the model trained on every
/// sub-window of the training recordings, each test recording classified
/// by its sub-windows' vote; `--json` adds each one's votes (`windows`).
fn holdout_windows(
    profile: &crate::profile::Profile,
    examples: Vec<crate::classify::TrainingExample>,
    eval: &crate::profile::Evaluation,
    json: bool,
    not_enough: impl Fn(EvaluateError) -> Failure,
) -> Result<(), Failure> {
    let recs = windows::recordings_of(examples, None).map_err(bad)?;
    let (train, test) = windows::split_recordings(&recs, eval).map_err(not_enough)?;
    let model = Model::train_adapting_k(
        &profile.name,
        &profile.analysis,
        &profile.classifier,
        windows::window_examples(&train),
    )
    .map_err(bad)?;
    if let Some(note) = model.k_notice() {
        crate::errln!("note: {note}");
    }
    let report = windows::evaluate_recordings(&model, &test).map_err(bad)?;
    if json {
        crate::outln!("{}", serde_json::to_string(&report).map_err(runtime)?);
    } else {
        let used = train.iter().chain(&test);
        crate::outln!(
            "profile {}: k-NN k = {}, {} training and {} test recordings per class{}; {}, classified by the vote of their windows",
            profile.name,
            profile.classifier.k_text(),
            eval.train_per_class,
            eval.test_per_class,
            eval.shuffle_seed
                .map_or(" (file-name order)".into(), |s| format!(
                    " (shuffled, seed {s})"
                )),
            recordings_and_windows(
                train.len() + test.len(),
                used.map(|r| r.windows.len()).sum()
            )
        );
        crate::outp!("{}", report.report.table());
    }
    Ok(())
}

/// "40 recordings, 120 windows".
fn recordings_and_windows(recordings: usize, windows: usize) -> String {
    format!(
        "{}, {}",
        crate::classify::plural(recordings, "recording", "recordings"),
        crate::classify::plural(windows, "window", "windows")
    )
}

/// `hapticlab evaluate` with cross-validation, a sweep, or simulated data.
fn validated(
    profile: &ProfileArg,
    paths: &[PathBuf],
    shuffle_seed: Option<u64>,
    json: bool,
    args: &ValidationArgs,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let mut args = args.clone();
    if args.seed.is_none() {
        args.seed = shuffle_seed;
    }
    let plan = Plan::new(&lp.profile, &args.overrides());
    let swept = args
        .sweep
        .iter()
        .map(|spec| Swept::parse(spec))
        .collect::<Result<Vec<_>, _>>()?;
    let keys = if swept.is_empty() {
        Vec::new()
    } else {
        resolve_all(&lp.profile, &swept)?
    };
    match (args.simulate, paths.is_empty()) {
        (true, false) => {
            return Err(bad(
                "--simulate evaluates datasets simulated from the profile: give no PATH",
            ));
        }
        (false, true) => {
            return Err(bad(
                "no recordings: give a PATH, or --simulate to evaluate a simulated dataset",
            ));
        }
        _ => {}
    }
    if let Some((spec, k)) = args
        .sweep
        .iter()
        .zip(&keys)
        .find(|(_, k)| k.needs_simulation())
        && !args.simulate
    {
        return Err(bad(format!(
            "--sweep {}: this key changes the recordings themselves, so it cannot be swept over \
             recordings on disk; simulate a dataset per value instead: \
             hapticlab evaluate --profile {} --simulate --folds 5 --sweep {spec}",
            k.name(),
            profile.profile.display()
        )));
    }
    if args.simulate {
        lp.rig()
            .map_err(|e| bad(format!("evaluate --simulate: {e}")))?;
    }
    // The holdout's own counts; cross-validation names none, so as many
    // scans as `simulate` makes by default (more when the folds need it).
    let held_out = lp.profile.evaluation.train_per_class + lp.profile.evaluation.test_per_class;
    let sim = SimPlan {
        per_class: args.per_class.unwrap_or(if held_out > 0 {
            held_out
        } else {
            crate::acquire::DEFAULT_PER_CLASS.max(plan.folds)
        }),
        threads: plan.threads,
        scratch: &crate::scratch::make,
    };
    if args.per_class.is_some() && !args.simulate {
        return Err(bad(
            "--per-class sets how many scans --simulate makes per texture; add --simulate (and no PATH)",
        ));
    }
    if args.simulate && sim.per_class == 0 {
        return Err(bad("--per-class must be at least 1"));
    }
    let e = &lp.profile.evaluation;
    if args.simulate
        && plan.method == SplitMethod::Holdout
        && sim.per_class < e.train_per_class + e.test_per_class
    {
        return Err(bad(format!(
            "--per-class {}: the profile's holdout split needs {} scans per texture ({} to train, {} to test); \
             simulate at least that many, or cross-validate (--folds N)",
            sim.per_class,
            e.train_per_class + e.test_per_class,
            e.train_per_class,
            e.test_per_class
        )));
    }
    let n_textures = lp.profile.textures.len();
    if keys.iter().any(|k| k.needs_simulation()) {
        let combos = crate::evaluate::sweep::combinations(&swept);
        let points = combos.len();
        // `path.speed_m_per_s = 0.4, k = 1 (3/4)`.
        let naming = |i: usize| {
            let set: Vec<String> = keys
                .iter()
                .zip(&swept)
                .zip(&combos[i])
                .map(|((k, w), &j)| format!("{} = {}", k.name(), meta_text(&w.values[j])))
                .collect();
            format!("{} ({}/{points})", set.join(", "), i + 1)
        };
        let per_value = sim.per_class * n_textures;
        // One dataset per combination of the recording keys' values.
        let datasets: usize = keys
            .iter()
            .zip(&swept)
            .filter(|(k, _)| k.needs_simulation())
            .map(|(_, w)| w.values.len())
            .product();
        let pb = progress_bar((per_value * datasets) as u64, "simulating");
        // The point whose dataset is being simulated (+1), and how many
        // datasets were started.
        let (current, started) = (AtomicUsize::new(0), AtomicUsize::new(0));
        let s = sweep_grid_simulated(&lp, &swept, &plan, sim, &|i, done, _| {
            if current.swap(i + 1, Ordering::Relaxed) != i + 1 {
                started.fetch_add(1, Ordering::Relaxed);
                pb.set_message(naming(i));
            }
            let before = started.load(Ordering::Relaxed).saturating_sub(1);
            pb.set_position((before * per_value + done) as u64);
        })?;
        pb.finish_and_clear();
        let source = format!(
            "each on {} simulated scans per texture (seed {})",
            sim.per_class, lp.profile.simulator.seed
        );
        return print_sweep(&lp.profile.name, &swept, &s, &source, &plan, json);
    }
    // Samples are kept only when a sweep extracts features again per value;
    // otherwise memory holds one feature vector per recording.
    let keep = if keys.iter().any(|k| k.table == "analysis") {
        Keep::Samples
    } else {
        Keep::Features
    };
    let options = Options {
        keep,
        unusable: Unusable::Fail,
        threads: plan.threads,
    };
    let data = if args.simulate {
        let pb = progress_bar((sim.per_class * n_textures) as u64, "simulating");
        let d = simulated_dataset(&lp, sim, &lp.profile.analysis, options, &|done, _| {
            pb.set_position(done as u64)
        });
        pb.finish_and_clear();
        d?
    } else {
        let files = find_recordings(paths)?;
        let pb = progress_bar(files.len() as u64, "reading");
        let d = Dataset::load_files(&files, &lp.profile.analysis, options, &|| pb.inc(1));
        pb.finish_and_clear();
        d?
    };
    warn_skipped(&data.skipped);
    // With sub-windows kept as features, the scans are windows.
    let (n_recordings, n_scans) = data.counts();
    let windows_held = if lp.profile.analysis.windows.is_some() && keep == Keep::Features {
        format!(
            ", {}",
            crate::classify::plural(n_scans, "window", "windows")
        )
    } else {
        String::new()
    };
    let source = if args.simulate {
        format!(
            "{n_recordings} simulated recordings{windows_held} (seed {})",
            lp.profile.simulator.seed
        )
    } else {
        format!(
            "{}{windows_held}",
            crate::classify::plural(n_recordings, "recording", "recordings")
        )
    };
    if !swept.is_empty() {
        let s = sweep_grid(&lp.profile, &data, &swept, &plan, &|_| {})?;
        return print_sweep(&lp.profile.name, &swept, &s, &source, &plan, json);
    }
    let groups = match &plan.group_by {
        Some(g) => Some(data.groups(g)?),
        None => None,
    };
    let examples = data.examples(&lp.profile.analysis)?;
    let validated = validate_with_votes(&lp.profile, examples, groups.as_deref(), &plan)?;
    let report = &validated.report;
    let notice = report.k_notice();
    if let Some(n) = &notice {
        crate::errln!("note: {n}");
    }
    if json {
        crate::outln!("{}", serde_json::to_string(&validated).map_err(bad)?);
    } else {
        crate::outln!(
            "profile {}: k-NN k = {}{} ({:?}, {:?} votes{}), {}, {source}{}",
            lp.profile.name,
            lp.profile.classifier.k_text(),
            if notice.is_some() {
                ", chosen by CV in folds with too few scans of a texture (see the note)"
            } else {
                ""
            },
            lp.profile.classifier.metric,
            lp.profile.classifier.weights,
            if lp.profile.classifier.standardize {
                ", standardised"
            } else {
                ""
            },
            plan.describe(),
            if validated.windows.is_some() {
                ", each recording classified by the vote of its windows"
            } else {
                ""
            },
        );
        crate::outp!("{}", report.table());
    }
    Ok(())
}

/// A sweep's table (or JSON), then the verdict on the exit code: 0 when at
/// least one point was evaluated, 2 (bad input) when none could be.
fn print_sweep(
    profile: &str,
    swept: &[Swept],
    s: &Sweep,
    source: &str,
    plan: &Plan,
    json: bool,
) -> Result<(), Failure> {
    if json {
        crate::outln!("{}", serde_json::to_string(s).map_err(bad)?);
    } else {
        let over = match s.keys.len() {
            1 => crate::classify::plural(s.points.len(), "value", "values"),
            _ => {
                let sizes: Vec<String> = swept.iter().map(|w| w.values.len().to_string()).collect();
                format!(
                    "{} ({})",
                    crate::classify::plural(s.points.len(), "combination", "combinations"),
                    sizes.join(" × ")
                )
            }
        };
        crate::outln!(
            "profile {profile}: sweeping {} over {over}, {}, {source}",
            s.key,
            plan.describe(),
        );
        crate::outp!("{}", s.table());
    }
    if s.evaluated() == 0 {
        return Err(bad(format!(
            "--sweep {}: no {} could be evaluated (the reasons are listed above)",
            s.key,
            if s.keys.len() == 1 {
                "value"
            } else {
                "combination"
            }
        )));
    }
    Ok(())
}
