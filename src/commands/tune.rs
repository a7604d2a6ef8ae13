//! `hapticlab tune DIR -p P.toml --out TUNED.toml`: the front end of
//! [`crate::tune`]. Reads the recordings once (their samples, so each
//! feature setting is made from them), runs the nested search with a
//! progress bar on a terminal, writes the profile with the chosen lines
//! and prints the outer estimate (or the report as JSON).

use std::path::{Path, PathBuf};

use clap::Args;

use crate::dataset::{self, Keep, Options, Unusable};
use crate::evaluate::plan::Recordings;
use crate::profile::{LoadedProfile, THESIS_PROFILE};
use crate::support::{
    Existing, Failure, ProfileArg, bad, check_output, find_recordings, inputs_of, load_profile,
    progress_bar, runtime, warn_skipped, write_atomically,
};
use crate::tune::{self, TuneError, TuneReport};

#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Folders (or files) of recordings.
    #[arg(value_name = "DIR", required = true)]
    pub paths: Vec<PathBuf>,
    #[command(flatten)]
    pub profile: ProfileArg,
    /// The tuned profile to write (never the input profile or a recording).
    #[arg(long, value_name = "TUNED.toml")]
    pub out: PathBuf,
    /// Settings scored at most; a larger grid is sampled (whole feature
    /// settings, each with every classifier setting, the families in turn)
    /// with the seed.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u64).range(1..))]
    pub budget: u64,
    /// Seeds the sampling and the inner folds (the outer split is the profile's).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// CPU minutes (estimated from the recordings and the plan, the same on
    /// any machine) a costly feature setting (random kernels, refitted in
    /// every fold; competing kernels) may take over the whole search:
    /// costlier ones (random kernels on long windows under leave-one-out
    /// can take hours) are left out and named.
    #[arg(long, value_name = "MINUTES", default_value_t = tune::MAX_MINUTES, value_parser = minutes)]
    pub max_minutes: f64,
    /// Replace --out when it exists (never a recording or the input profile).
    #[arg(long)]
    pub overwrite: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

impl From<TuneError> for Failure {
    fn from(e: TuneError) -> Failure {
        if e.is_bad_input() { bad(e) } else { runtime(e) }
    }
}

/// `--max-minutes`: a number of minutes above zero.
fn minutes(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(m) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(format!("{text} is not a number of minutes above 0")),
    }
}

/// `--out` may be neither an input nor a recording nor anything but a
/// regular file (the shared guard); an existing profile only with
/// `--overwrite`.
fn check_out(a: &TuneArgs, inputs: &[PathBuf]) -> Result<(), Failure> {
    check_output(&a.out, inputs, Existing::replace_if(a.overwrite))
}

/// The profile's own text, to write the tuned one from.
fn profile_text(arg: &ProfileArg) -> Result<String, Failure> {
    let p = &arg.profile;
    if p.as_os_str() == "thesis" && !p.exists() {
        return Ok(THESIS_PROFILE.to_string());
    }
    crate::io::read_input_to_string(p).map_err(|e| {
        bad(format!(
            "{}: cannot read: {}",
            p.display(),
            crate::io::said(&e)
        ))
    })
}

pub fn run(a: TuneArgs) -> Result<(), Failure> {
    let inputs = inputs_of(&a.profile, &a.paths)?;
    check_out(&a, &inputs)?;
    let loaded = load_profile(&a.profile)?;
    let original = profile_text(&a.profile)?;
    let files = find_recordings(&a.paths)?;
    let threads = dataset::cores();
    let pb = progress_bar(files.len() as u64, "reading");
    let options = Options {
        keep: Keep::Samples,
        unusable: Unusable::Fail,
        threads,
    };
    let data = Recordings::load_files(&files, &loaded.profile.analysis, options, &|| pb.inc(1));
    pb.finish_and_clear();
    let data = data?;
    warn_skipped(&data.skipped);
    if data.scans.is_empty() {
        return Err(bad(format!(
            "none of the {} recording(s) found can be used (each is named above)",
            files.len()
        )));
    }
    let pb = progress_bar(0, "scoring settings");
    let progress = |done: usize, total: usize| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let options = tune::Options {
        budget: usize::try_from(a.budget).unwrap_or(usize::MAX),
        seed: a.seed,
        threads,
        max_minutes: a.max_minutes,
    };
    let name = &loaded.profile.name;
    let report = tune::tune(name, &loaded.profile, &data.scans, &options, &progress);
    pb.finish_and_clear();
    let report = report?;
    let setting = report
        .chosen_setting
        .as_ref()
        .ok_or_else(|| runtime("the search chose nothing (a bug)"))?;
    let about = format!(
        "{}, seed {}",
        a.paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        a.seed
    );
    let text = tune::text::tuned_profile(&original, setting, &report, &about);
    // What is written must load with the setting chosen: else it is a bug.
    let base = a.out.parent().unwrap_or(Path::new("."));
    let written = LoadedProfile::from_str(&text, &a.out.display().to_string(), base)
        .map_err(|e| runtime(format!("the tuned profile is invalid (a bug): {e}")))?;
    if !tune::text::reads_back_as(
        setting,
        &written.profile.analysis,
        &written.profile.classifier,
    ) {
        return Err(runtime(
            "the tuned profile does not read back as the setting chosen (a bug)",
        ));
    }
    write_atomically(
        &a.out,
        &inputs,
        Existing::replace_if(a.overwrite),
        text.as_bytes(),
    )?;
    if a.json {
        crate::outln!("{}", serde_json::to_string(&report).map_err(runtime)?);
    } else {
        print_report(&report, &a);
    }
    Ok(())
}

fn print_report(r: &TuneReport, a: &TuneArgs) {
    let pct = |x: f64| format!("{:.1} %", 100.0 * x);
    crate::outln!(
        "{} of {} settings ({} feature settings) scored by {} inner folds ({}) inside each training part; outer validation: {}",
        r.configurations,
        r.grid,
        r.feature_settings,
        r.inner_folds,
        r.inner_split.describe(),
        r.method
    );
    for l in &r.left_out {
        crate::outln!(
            "left out: {} {} feature setting(s) ({} settings): {}",
            l.feature_settings,
            l.family,
            l.settings,
            l.reason
        );
    }
    let chosen: Vec<String> = r
        .chosen
        .options
        .0
        .iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    crate::outln!(
        "chosen (inner {}): {}",
        pct(r.chosen.inner_accuracy),
        chosen.join(", ")
    );
    let families: Vec<String> = r
        .families
        .iter()
        .map(|f| format!("{} {}", f.family, pct(f.inner_accuracy)))
        .collect();
    crate::outln!(
        "family: {} (the best inner score of each: {})",
        r.chosen.family,
        families.join(", ")
    );
    // Each outer fold on a line; under leave-one-out, one line for them all.
    if r.outer_folds.len() <= 20 {
        for f in &r.outer_folds {
            crate::outln!(
                "  outer fold: {}/{} right ({}), chosen at inner {}",
                (f.accuracy * f.tested as f64).round(),
                f.tested,
                pct(f.accuracy),
                pct(f.chosen.inner_accuracy)
            );
        }
    } else {
        let inner = |pick: fn(f64, f64) -> f64| {
            r.outer_folds
                .iter()
                .map(|f| f.chosen.inner_accuracy)
                .fold(f64::NAN, pick)
        };
        let wrong = r.outer_folds.iter().filter(|f| f.accuracy < 1.0).count();
        crate::outln!(
            "  {} outer folds, {} with a test recording wrong, each chosen at inner {} to {} (every fold: --json)",
            r.outer_folds.len(),
            wrong,
            pct(inner(f64::min)),
            pct(inner(f64::max))
        );
    }
    crate::outln!(
        "outer estimate: {} ({}/{} test recordings never seen by the search that chose)",
        pct(r.outer_accuracy),
        r.outer.correct(),
        r.outer.tested()
    );
    crate::outln!(
        "wrote {} (the chosen lines marked `# tune`, the top settings in a comment)",
        a.out.display()
    );
    let dirs = a
        .paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" ");
    if r.tuned_on.holdout {
        crate::outln!(
            "quote the outer estimate; next: hapticlab evaluate {dirs} -p {} (the same held-out part: the same figure)",
            a.out.display()
        );
    } else {
        crate::outln!(
            "quote the outer estimate ({}): the lines written were chosen on every one of these recordings, so `evaluate` of {} on them flatters; next, on recordings the search never saw: hapticlab evaluate NEW_DIR -p {}",
            pct(r.outer_accuracy),
            a.out.display(),
            a.out.display()
        );
    }
}
