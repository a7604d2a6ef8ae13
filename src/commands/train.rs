//! `hapticlab train`: the profile's classifier (k-NN, ridge or LDA)
//! trained on recordings and saved
//! ([`crate::classify::Model`]).

use std::path::{Path, PathBuf};

use clap::Args;

use crate::classify::{Model, plural};
use crate::support::{
    Existing, Failure, ProfileArg, bad, check_output, inputs_of, load_profile,
    load_profile_examples, output_failure,
};

#[derive(Debug, Args)]
pub struct TrainArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    /// Model file to write (JSON).
    #[arg(long, value_name = "MODEL")]
    pub out: PathBuf,
    /// Replace --out when it exists (never a recording or an input).
    #[arg(long)]
    pub overwrite: bool,
}

pub fn run(a: TrainArgs) -> Result<(), Failure> {
    train(
        &a.profile,
        &a.paths,
        &a.out,
        Existing::replace_if(a.overwrite),
    )
}

fn train(
    profile: &ProfileArg,
    paths: &[PathBuf],
    out: &Path,
    existing: Existing,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let inputs = inputs_of(profile, paths)?;
    check_output(out, &inputs, existing)?;
    let examples = load_profile_examples(&lp, paths)?;
    // With sub-windows, a recording gives several examples, consecutive.
    let recordings = examples
        .iter()
        .enumerate()
        .filter(|(i, e)| *i == 0 || examples[i - 1].file != e.file)
        .count();
    let trained_on = if lp.profile.analysis.windows.is_some() {
        format!(
            "{} ({})",
            plural(recordings, "recording", "recordings"),
            plural(examples.len(), "sub-window", "sub-windows")
        )
    } else {
        plural(recordings, "recording", "recordings")
    };
    let model = Model::train_adapting_k(
        &lp.profile.name,
        &lp.profile.analysis,
        &lp.profile.classifier,
        examples,
    )
    .map_err(bad)?;
    if let Some(note) = model.k_notice() {
        crate::errln!("note: {note}");
    }
    model.save(out, &inputs, existing).map_err(output_failure)?;
    crate::outln!(
        "trained {} on {} of {} ({}); model saved to {}",
        model.classifier_name(),
        trained_on,
        plural(model.labels.len(), "class", "classes"),
        model.labels.join(", "),
        out.display()
    );
    Ok(())
}
