//! `hapticlab evaluate`: the arguments and the printing of the engine's one
//! evaluation ([`crate::evaluate::request::run`]): the thesis's holdout
//! split, k-fold, leave-one-out, grouped folds and parameter sweeps, over
//! recordings or datasets simulated on the fly, and with `--fallback` the
//! small-data fallback the console's `e` uses.
//!
//! Without any validation flag, under a profile whose `[evaluation]` asks
//! for a holdout, it prints the thesis's Table 4.1 (`--json`: the
//! [`crate::evaluate::Report`]); otherwise a [`crate::evaluate::cv::CvReport`]
//! or a [`crate::evaluate::sweep::Sweep`]. The header always names the
//! method and the k actually used.

use std::path::PathBuf;
use std::sync::Mutex;

use clap::Args;
use indicatif::ProgressBar;

use crate::evaluate::plan::Overrides;
use crate::evaluate::request::{self, Evaluation, Outcome, Progress, Request, Source};
use crate::evaluate::sweep::{Sweep, Swept};
use crate::support::evaluation_text::{header, source_text, table};
use crate::support::{
    Failure, IMPORT_HINT, ProfileArg, bad, load_profile, progress_bar, runtime, their_profile,
    warn_skipped,
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
    /// When the recordings cannot meet the profile's split (too few scans of a texture for its holdout, fewer recordings than folds), evaluate by stratified 5-fold cross-validation, or leave-one-out below 5 scans of a texture, and say so in the header: what the console's `e` does. Not with --sweep.
    #[arg(long, conflicts_with = "sweep")]
    pub fallback: bool,
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
}

/// The engine's progress as a bar on standard error (hidden when it is not
/// a terminal), one per phase.
#[derive(Default)]
struct Bar(Mutex<Option<ProgressBar>>);

impl Progress for Bar {
    fn begin(&self, what: &str, total: usize) {
        if let Ok(mut b) = self.0.lock() {
            *b = Some(progress_bar(total as u64, what));
        }
    }
    fn set(&self, done: usize) {
        if let Ok(b) = self.0.lock()
            && let Some(b) = b.as_ref()
        {
            b.set_position(done as u64);
        }
    }
    fn message(&self, text: &str) {
        if let Ok(b) = self.0.lock()
            && let Some(b) = b.as_ref()
        {
            b.set_message(text.to_string());
        }
    }
    fn end(&self) {
        if let Ok(mut b) = self.0.lock()
            && let Some(b) = b.take()
        {
            b.finish_and_clear();
        }
    }
    /// Removed on Ctrl-C too, which ends the run (status 130).
    fn scratch(&self) -> Result<Box<dyn crate::evaluate::sweep::Scratch + '_>, String> {
        crate::scratch::make()
    }
}

/// `hapticlab evaluate`: parse, run the engine's evaluation, print.
pub fn run(a: EvaluateArgs) -> Result<(), Failure> {
    let lp = load_profile(&a.profile)?;
    let v = &a.validation;
    if v.simulate && !a.paths.is_empty() {
        return Err(bad(
            "--simulate evaluates datasets simulated from the profile: give no PATH",
        ));
    }
    if v.per_class.is_some() && !v.simulate {
        return Err(bad(
            "--per-class sets how many scans --simulate makes per texture; add --simulate (and no PATH)",
        ));
    }
    let req = Request {
        source: if v.simulate {
            Source::Simulated {
                per_class: v.per_class,
            }
        } else {
            Source::Recordings(a.paths.clone())
        },
        overrides: v.overrides(),
        shuffle_seed: a.shuffle_seed,
        sweep: v.sweep.clone(),
        fallback: v.fallback,
    };
    let bar = Bar::default();
    let ev = request::run(&lp, &req, &bar);
    bar.end();
    let ev = ev.map_err(|e| with_next_step(e, &lp, &a.paths))?;
    warn_skipped(&ev.skipped);
    if let Some(note) = ev.outcome.k_notice() {
        crate::errln!("note: {note}");
    }
    if let Outcome::Sweep(s) = &ev.outcome {
        return print_sweep(
            &lp.profile.name,
            &req.sweep,
            s,
            &source_text(&ev),
            &ev,
            a.json,
        );
    }
    if a.json {
        crate::outln!("{}", serde_json::to_string(&ev.outcome).map_err(runtime)?);
    } else {
        crate::outln!("{}", header(&lp, &ev));
        crate::outp!("{}", table(&ev.outcome));
    }
    Ok(())
}

/// An evaluation's error, with what to do where its message leaves the
/// user guessing: a recording that does not cover the window (a trial cut
/// short, which `profile new` names) is refused rather than analysed as
/// far as it goes; recordings without the built-in profile's columns need
/// their own profile; a file that is no recording needs importing.
fn with_next_step(
    e: crate::evaluate::EvaluateError,
    lp: &crate::profile::LoadedProfile,
    paths: &[PathBuf],
) -> Failure {
    use crate::analysis::AnalysisError;
    use crate::dataset::DatasetError;
    use crate::evaluate::EvaluateError;
    let EvaluateError::Dataset(d) = &e else {
        return e.into();
    };
    if let Some(m) = their_profile(lp, paths, d) {
        return bad(m);
    }
    match d {
        DatasetError::Analysis {
            source: AnalysisError::WindowNotCovered { .. },
            ..
        } => bad(format!(
            "{e}: remove the recording from the folder, or narrow the profile's window to what it covers"
        )),
        DatasetError::Recording(r) if r.is_not_a_recording() => bad(format!("{e}; {IMPORT_HINT}")),
        _ => e.into(),
    }
}

/// A sweep's table (or JSON), then the verdict on the exit code: 0 when at
/// least one point was evaluated, 2 (bad input) when none could be.
fn print_sweep(
    profile: &str,
    specs: &[String],
    s: &Sweep,
    source: &str,
    ev: &Evaluation,
    json: bool,
) -> Result<(), Failure> {
    if json {
        crate::outln!("{}", serde_json::to_string(s).map_err(bad)?);
    } else {
        let over = match s.keys.len() {
            1 => crate::classify::plural(s.points.len(), "value", "values"),
            _ => {
                let sizes: Vec<String> = specs
                    .iter()
                    .map(|spec| Swept::parse(spec).map_or(0, |w| w.values.len()).to_string())
                    .collect();
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
            ev.plan.describe(),
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
