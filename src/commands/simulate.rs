//! `hapticlab simulate`: a dataset simulated in virtual time, N scans of
//! every texture in the profile ([`crate::acquire::simulate_dataset_until`]).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::Args;

use crate::acquire::{self, SimulateOptions};
use crate::support::{Failure, ProfileArg, bad, load_profile, progress_bar, runtime};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// Output folder; scans go to OUT/<label>/<label>_NNN.csv.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Scans per texture.
    #[arg(long, default_value_t = acquire::DEFAULT_PER_CLASS, value_name = "N")]
    pub per_class: usize,
    /// Dataset seed (default: the profile's simulator.seed).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Worker threads (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Compress each recording (Zopfli gzip, about a second per recording) to OUT/<label>/<label>_NNN.csv.gz.
    #[arg(long)]
    pub gzip: bool,
    /// Replace recordings already in OUT under the same names (by default that is an error).
    #[arg(long)]
    pub overwrite: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: SimulateArgs) -> Result<(), Failure> {
    simulate(
        &a.profile,
        SimulateOptions {
            out: a.out,
            per_class: a.per_class,
            seed: a.seed.unwrap_or(0),
            threads: a.threads.unwrap_or(0),
            gzip: a.gzip,
            overwrite: a.overwrite,
        },
        a.seed.is_some(),
        a.json,
    )
}

/// `opts.seed` counts only when `seed_given`; `opts.threads` 0 means one per core.
fn simulate(
    profile: &ProfileArg,
    mut opts: SimulateOptions,
    seed_given: bool,
    json: bool,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let rate_hz = lp
        .rig()
        .map_err(|e| bad(format!("simulate: {e}")))?
        .device
        .rate_hz;
    let (out, per_class) = (opts.out.clone(), opts.per_class);
    let total = per_class * lp.profile.textures.len();
    let pb = progress_bar(total as u64, "simulating");
    if !seed_given {
        opts.seed = lp.profile.simulator.seed;
    }
    if opts.threads == 0 {
        opts.threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    }
    // A lost terminal (SIGHUP, a hang-up, a pipe nobody reads) stops the
    // batch after the scans already running; nothing here prints with
    // println!, which would panic on it.
    let lost = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGHUP, lost.clone()).map_err(runtime)?;
    let finished = AtomicBool::new(false);
    let started = std::time::Instant::now();
    let saved = std::thread::scope(|scope| {
        scope.spawn(|| {
            while !finished.load(Ordering::Relaxed) && !lost.load(Ordering::Relaxed) {
                if crate::terminal::lost() {
                    lost.store(true, Ordering::Relaxed);
                }
                std::thread::sleep(std::time::Duration::from_millis(50));
            }
        });
        let r = acquire::simulate_dataset_until(
            &lp,
            &opts,
            &|done, _| pb.set_position(done as u64),
            &lost,
        );
        finished.store(true, Ordering::Relaxed);
        r
    });
    pb.finish_and_clear();
    // A lost terminal is the reason, whatever else failed after it.
    if lost.load(Ordering::Relaxed) {
        let done = saved.as_ref().map_or(0, Vec::len);
        return Err(runtime(format!(
            "the terminal was lost: simulate stopped after {done} of {total} scans (in {})",
            out.display()
        )));
    }
    let saved = saved.map_err(Failure::from)?;
    let secs = started.elapsed().as_secs_f64();
    let samples: usize = saved.iter().map(|s| s.rows).sum();
    let sim_s = samples as f64 / rate_hz;
    let printed = if json {
        let files: Vec<String> = saved.iter().map(|s| s.path.display().to_string()).collect();
        let v = serde_json::json!({
            "profile": lp.profile.name, "seed": opts.seed, "out": out.display().to_string(),
            "scans": saved.len(), "samples": samples, "wall_s": secs, "files": files,
        });
        crate::terminal::out(format_args!("{v}"))
    } else {
        crate::terminal::out(format_args!(
            "simulated {} scans ({} per texture, {} samples) into {} in {:.2} s (seed {})",
            saved.len(),
            per_class,
            samples,
            out.display(),
            secs,
            opts.seed
        )) && crate::terminal::out(format_args!(
            "recorded scan time {:.0} s: {:.0}x real time",
            sim_s,
            sim_s / secs.max(1e-9)
        ))
    };
    if !printed {
        return Err(runtime(format!(
            "the terminal was lost: {} scans were simulated into {}, but the summary could not be printed",
            saved.len(),
            out.display()
        )));
    }
    Ok(())
}
