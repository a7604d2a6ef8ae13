//! `hapticlab features`: the feature vector (spectrum bins) of each
//! recording, as `file,label,f1,…,fN` rows ([`crate::dataset`] computes them).

use std::path::{Path, PathBuf};

use clap::Args;

use crate::dataset;
use crate::support::{
    Existing, Failure, ProfileArg, check_output, inputs_of, load_profile, load_profile_examples,
    write_atomically,
};

#[derive(Debug, Args)]
pub struct FeaturesArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// Recordings or folders of recordings.
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    /// Write `file,label,f1,…,fN` rows here instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Replace --out when it exists (never a recording or an input).
    #[arg(long, requires = "out")]
    pub overwrite: bool,
}

pub fn run(a: FeaturesArgs) -> Result<(), Failure> {
    features(
        &a.profile,
        &a.paths,
        a.out.as_deref(),
        Existing::replace_if(a.overwrite),
    )
}

fn features(
    profile: &ProfileArg,
    paths: &[PathBuf],
    out: Option<&Path>,
    existing: Existing,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let inputs = match out {
        Some(p) => {
            let inputs = inputs_of(profile, paths)?;
            check_output(p, &inputs, existing)?;
            inputs
        }
        None => Vec::new(),
    };
    let examples = load_profile_examples(&lp, paths)?;
    let n = lp.profile.analysis.feature_count();
    // One row per sub-window, with its index, when `windows` is set.
    let windows = lp
        .profile
        .analysis
        .windows
        .is_some()
        .then(|| dataset::window_indices(&examples));
    let mut text = String::from(if windows.is_some() {
        "file,label,window"
    } else {
        "file,label"
    });
    for i in 1..=n {
        text.push_str(&format!(",f{i}"));
    }
    text.push('\n');
    for (row, e) in examples.iter().enumerate() {
        text.push_str(&csv_field(&e.file));
        text.push(',');
        text.push_str(&csv_field(&e.label));
        if let Some(w) = &windows {
            text.push_str(&format!(",{}", w[row]));
        }
        for v in &e.features {
            text.push_str(&format!(",{v:.9e}"));
        }
        text.push('\n');
    }
    match out {
        Some(p) => {
            write_atomically(p, &inputs, existing, text.as_bytes())?;
            crate::errln!(
                "wrote {} feature rows ({} features each) to {}",
                examples.len(),
                n,
                p.display()
            );
        }
        // A write failure is noted for the exit code; a closed pipe is quiet.
        None => crate::outp!("{text}"),
    }
    Ok(())
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
