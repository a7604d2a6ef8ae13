//! The front ends' shared floor, below every front end (`commands/`,
//! `console/`, `doctor/`, `plot`, `import`) and above the engine:
//! [`Failure`] (bad input, exit code 2, or a runtime failure, exit code 1)
//! and the engine errors it maps, `--profile` ([`ProfileArg`]) and loading
//! it, progress bars on standard error, finding recordings and warning
//! about the ones left out, loading feature vectors through
//! [`crate::dataset`], and writing a file atomically.
//!
//! It must never import a front end (`commands`, `cli`, `console`, …):
//! they all stand on it.

pub mod evaluation_text;

pub use crate::io::Existing;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::acquire;
use crate::classify::TrainingExample;
use crate::dataset;
use crate::profile::LoadedProfile;

#[derive(Debug, Args, Clone)]
pub struct ProfileArg {
    /// Experiment profile (TOML); `thesis` names the built-in thesis profile.
    #[arg(long, short = 'p', default_value = "thesis", value_name = "PROFILE")]
    pub profile: PathBuf,
}

impl Default for ProfileArg {
    /// The built-in thesis profile, as `--profile` defaults to.
    fn default() -> ProfileArg {
        ProfileArg {
            profile: "thesis".into(),
        }
    }
}

/// A command that failed: bad input (exit 2) or a runtime failure (exit 1).
#[derive(Debug)]
pub enum Failure {
    BadInput(String),
    Runtime(String),
}

impl Failure {
    pub fn exit_code(&self) -> i32 {
        match self {
            Failure::BadInput(_) => 2,
            Failure::Runtime(_) => 1,
        }
    }
    pub fn message(&self) -> &str {
        match self {
            Failure::BadInput(m) | Failure::Runtime(m) => m,
        }
    }
}

impl From<acquire::AcquireError> for Failure {
    fn from(e: acquire::AcquireError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

impl From<crate::import::ImportError> for Failure {
    fn from(e: crate::import::ImportError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

impl From<crate::evaluate::EvaluateError> for Failure {
    fn from(e: crate::evaluate::EvaluateError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

impl From<crate::dataset::DatasetError> for Failure {
    fn from(e: crate::dataset::DatasetError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

pub fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

pub fn runtime(m: impl std::fmt::Display) -> Failure {
    Failure::Runtime(m.to_string())
}

pub fn load_profile(arg: &ProfileArg) -> Result<LoadedProfile, Failure> {
    LoadedProfile::load(&arg.profile).map_err(bad)
}

/// When the built-in thesis profile (no `-p`) meets recordings that lack
/// its columns, they are another rig's: the message names the columns they
/// have and how to give their profile or make one from `paths`. `None`
/// for any other profile or error.
pub fn their_profile(
    lp: &LoadedProfile,
    paths: &[PathBuf],
    e: &dataset::DatasetError,
) -> Option<String> {
    let dataset::DatasetError::MissingColumn { file, column, has } = e else {
        return None;
    };
    if !lp.is_built_in() {
        return None;
    }
    let a = &lp.profile.analysis;
    Some(format!(
        "{file}: no column `{column}`: the recordings have columns {has}, and the built-in thesis profile \
         (used when no -p is given) analyses {} along {} of the thesis's Falcon scans; give their profile \
         with -p P.toml, or make one: hapticlab profile new --from {} --out P.toml",
        a.channel,
        a.axis,
        folder_of(paths)
    ))
}

/// The folder to name in a suggested command: the one path given, else DIR.
pub fn folder_of(paths: &[PathBuf]) -> String {
    match paths {
        [one] => one.display().to_string(),
        _ => "DIR".into(),
    }
}

/// How other rigs' files become recordings, for a message about a file
/// that is not one.
pub const IMPORT_HINT: &str = "convert other rigs' files first: hapticlab import FILE... --out DIR \
     (CSV, headerless text, WAV, NumPy .npy/.npz, MATLAB .mat v5; each labelled by its folder, or --label)";

/// A progress bar on a terminal; nothing when standard error is piped.
pub fn progress_bar(total: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    }
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed}, ETA {eta})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// Recordings under `paths`, read on every core and turned into feature
/// vectors under `analysis` ([`crate::dataset::load`]). Each recording left
/// out (incomplete) is named in one warning on standard error; a malformed
/// one is an error.
pub fn load_examples(
    paths: &[PathBuf],
    analysis: &crate::profile::Analysis,
) -> Result<Vec<TrainingExample>, Failure> {
    load_examples_on(paths, analysis, dataset::cores())
}

/// [`load_examples`] on `threads` reader threads.
pub fn load_examples_on(
    paths: &[PathBuf],
    analysis: &crate::profile::Analysis,
    threads: usize,
) -> Result<Vec<TrainingExample>, Failure> {
    read_examples(paths, analysis, threads, &|_| None)
}

/// [`load_examples`] under `lp`'s analysis, where recordings without the
/// built-in profile's columns say whose profile to give ([`their_profile`]).
pub fn load_profile_examples(
    lp: &LoadedProfile,
    paths: &[PathBuf],
) -> Result<Vec<TrainingExample>, Failure> {
    read_examples(paths, &lp.profile.analysis, dataset::cores(), &|e| {
        their_profile(lp, paths, e)
    })
}

/// [`load_examples_on`], a failure's message replaced by `explain`'s when
/// it has one.
fn read_examples(
    paths: &[PathBuf],
    analysis: &crate::profile::Analysis,
    threads: usize,
    explain: &dyn Fn(&dataset::DatasetError) -> Option<String>,
) -> Result<Vec<TrainingExample>, Failure> {
    let files = find_recordings(paths)?;
    let pb = progress_bar(files.len() as u64, "reading");
    let options = dataset::Options {
        threads,
        ..dataset::Options::default()
    };
    let loaded = dataset::load(&files, analysis, options, &|| pb.inc(1));
    pb.finish_and_clear();
    let loaded = loaded.map_err(|e| match explain(&e) {
        Some(m) => bad(m),
        None => e.into(),
    })?;
    warn_skipped(&loaded.skipped);
    let examples = loaded.into_examples();
    if examples.is_empty() {
        // Every one was left out (each named above): nothing to go on.
        return Err(bad(format!(
            "none of the {} recording(s) found can be used (each is named above)",
            files.len()
        )));
    }
    Ok(examples)
}

/// The recordings under `paths` ([`dataset::find`]); a path that cannot be
/// walked, or none found, is the user's to fix (exit code 2).
pub fn find_recordings(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Failure> {
    dataset::find(paths).map_err(bad)
}

/// One warning line on standard error per recording left out; never panics
/// on a terminal that has gone.
pub fn warn_skipped(skipped: &[dataset::Skipped]) {
    for s in skipped {
        let _ = writeln!(std::io::stderr(), "warning: {s}");
    }
}

/// Write `bytes` to `path` through a temporary file beside it, put in
/// place in one step: never a half-written file. Refused (exit code 2) when
/// `path` is one of `inputs`, a recording or not a regular file, and when
/// it exists unless `existing` is [`Existing::Replace`] (`--overwrite`)
/// ([`crate::io::write_output`]).
pub fn write_atomically(
    path: &Path,
    inputs: &[PathBuf],
    existing: Existing,
    bytes: &[u8],
) -> Result<(), Failure> {
    crate::io::write_output(path, inputs, existing, |w| w.write_all(bytes)).map_err(output_failure)
}

/// The files a command reads besides a model: the recordings under
/// `paths` and the profile (a built-in name is no file and matches none).
/// For [`crate::io::check_output`] before any work, so a refused output
/// costs nothing.
pub fn inputs_of(profile: &ProfileArg, paths: &[PathBuf]) -> Result<Vec<PathBuf>, Failure> {
    let mut inputs = find_recordings(paths)?;
    inputs.push(profile.profile.clone());
    Ok(inputs)
}

/// [`crate::io::check_output`] as a [`Failure`].
pub fn check_output(out: &Path, inputs: &[PathBuf], existing: Existing) -> Result<(), Failure> {
    crate::io::check_output(out, inputs, existing).map_err(output_failure)
}

/// An output refused is bad input; one that could not be written, a runtime failure.
pub fn output_failure(e: crate::io::OutputError) -> Failure {
    if e.is_bad_input() { bad(e) } else { runtime(e) }
}
