//! `hapticlab profile new --from DIR --out P.toml`: an analysis-only
//! profile written for a folder of recordings — the channels, the rate, the
//! axis and spacing, a window that fits the shortest complete recording
//! (but a few aborted trials), the labels with their counts — with the
//! analysis, classifier and evaluation choices as commented option groups,
//! each saying when to use it. The survey of the folder is [`survey()`];
//! the text is [`draft()`]; what would quietly spoil the analysis is said
//! on standard error and in the profile ([`cautions`]).
//!
//! Every option group is written so that putting it in place of the lines
//! it replaces ([`apply_group`]) still gives a valid profile; the tests
//! check that on every group of the profiles they write.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

use crate::profile::LoadedProfile;
use crate::support::{Existing, Failure, bad, check_output, runtime, write_atomically};

pub mod cautions;
pub mod draft;
pub mod survey;

use cautions::rate_text;
pub use draft::{Drafted, apply_group, draft, groups_of};
pub use survey::{Survey, survey};

#[derive(Debug, Args)]
pub struct ProfileArgs {
    #[command(subcommand)]
    pub action: ProfileAction,
}

#[derive(Debug, Subcommand)]
pub enum ProfileAction {
    /// Write a commented analysis-only profile for a folder of recordings.
    #[command(
        after_help = "The profile has only name, [analysis], [classifier] and [evaluation]: it evaluates, trains and classifies recordings, and makes none.\n\nExample:\n  hapticlab profile new --from recordings/rig --out profiles/rig.toml\n  hapticlab check profiles/rig.toml && hapticlab evaluate recordings/rig -p profiles/rig.toml"
    )]
    New(NewArgs),
}

#[derive(Debug, Args)]
pub struct NewArgs {
    /// The folder of recordings (*.csv, *.csv.gz; one subfolder per label, or a `label` in each).
    #[arg(long, value_name = "DIR")]
    pub from: PathBuf,
    /// The profile to write.
    #[arg(long, value_name = "P.toml")]
    pub out: PathBuf,
    /// Replace the file when it exists (by default that is an error).
    #[arg(long)]
    pub overwrite: bool,
}

pub fn run(a: ProfileArgs) -> Result<(), Failure> {
    match a.action {
        ProfileAction::New(n) => new(&n),
    }
}

fn new(a: &NewArgs) -> Result<(), Failure> {
    // Refused before the survey: a file there without --overwrite, and
    // with it a recording or not a regular file.
    let existing = Existing::replace_if(a.overwrite);
    check_output(&a.out, &[], existing)?;
    let s = survey(&a.from)?;
    let name = a
        .out
        .file_stem()
        .map_or("recordings".into(), |n| n.to_string_lossy().into_owned());
    let Drafted {
        text,
        cautions,
        uncovered,
    } = draft(&s, &name, &a.from).map_err(bad)?;
    // What is written must load: a profile that does not is this command's fault.
    let base = a.out.parent().unwrap_or(Path::new("."));
    LoadedProfile::from_str(&text, &a.out.display().to_string(), base)
        .map_err(|e| runtime(format!("the profile drafted is invalid (a bug): {e}")))?;
    write_atomically(&a.out, &[], existing, text.as_bytes())?;
    for c in &cautions {
        crate::errln!("warning: {}: {c}", a.from.display());
    }
    let axis = s.choice().axis;
    // Along time, the rate the analysis resamples at; along a position,
    // the recordings' own.
    let rate = if axis == "t_s" {
        s.slowest_rate()
    } else {
        s.rate_hz
    };
    crate::outln!(
        "wrote {}: analysis only, {} along {} at {}{}, {} label(s) from {} complete recording(s){}",
        a.out.display(),
        s.channels(&axis).join(", "),
        axis,
        rate_text(rate),
        if axis == "t_s" && s.rates.len() > 1 {
            " (the slowest of their rates: see the warning)"
        } else {
            ""
        },
        s.labels.len(),
        s.complete,
        asides(s.incomplete.len(), uncovered)
    );
    crate::outln!(
        "next: hapticlab check {0} && hapticlab evaluate {1} -p {0}",
        a.out.display(),
        a.from.display()
    );
    Ok(())
}

/// What the summary line adds about the recordings: the incomplete ones
/// left out, the complete ones too short for the window.
fn asides(incomplete: usize, uncovered: usize) -> String {
    let mut said = Vec::new();
    if uncovered > 0 {
        said.push(format!(
            "{uncovered} of them too short for the window: see the warning"
        ));
    }
    if incomplete > 0 {
        said.push(format!("{incomplete} incomplete left out"));
    }
    if said.is_empty() {
        String::new()
    } else {
        format!(" ({})", said.join("; "))
    }
}
