//! The headless commands: each turns parsed arguments into engine calls and
//! prints the result for people (or JSON for scripts). Errors come back as
//! [`Failure`], which `main` maps to an exit code.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::acquire::{self, SimulateOptions};
use crate::analysis::FeatureExtractor;
use crate::classify::{Model, TrainingExample, plural};
use crate::cli::{Command, ProfileArg};
use crate::dataset::{self, DatasetError};
use crate::evaluate;
use crate::profile::LoadedProfile;
use crate::recording;

pub mod support;

pub(crate) use support::progress_bar;
pub use support::{Failure, load_profile};
use support::{bad, runtime};

pub fn run(cmd: Command) -> Result<(), Failure> {
    match cmd {
        Command::Console { profile, dataset } => {
            crate::console::run(load_profile(&profile)?, dataset)
        }
        Command::Replay {
            profile,
            path,
            dataset,
        } => crate::console::replay(load_profile(&profile)?, &path, dataset),
        Command::Simulate {
            profile,
            out,
            per_class,
            seed,
            threads,
            gzip,
            overwrite,
            json,
        } => simulate(
            &profile,
            SimulateOptions {
                out,
                per_class,
                seed: seed.unwrap_or(0),
                threads: threads.unwrap_or(0),
                gzip,
                overwrite,
            },
            seed.is_some(),
            json,
        ),
        Command::Scan {
            profile,
            label,
            count,
            out,
            texture,
            seed,
        } => scan(&profile, &label, count, &out, texture.as_deref(), seed),
        Command::Features {
            profile,
            paths,
            out,
        } => features(&profile, &paths, out.as_deref()),
        Command::Train {
            profile,
            paths,
            out,
        } => train(&profile, &paths, &out),
        Command::Classify {
            profile,
            model,
            files,
            json,
        } => classify(&profile, &model, &files, json),
        Command::Evaluate {
            profile,
            paths,
            shuffle_seed,
            json,
            validation,
        } => {
            let method = load_profile(&profile)?.profile.evaluation.method;
            if validation.is_active() || method != crate::profile::SplitMethod::Holdout {
                crate::study::run_evaluate(&profile, &paths, shuffle_seed, json, &validation)
            } else {
                let threads = validation.threads.unwrap_or_else(dataset::cores);
                evaluate_cmd(&profile, &paths, shuffle_seed, json, threads)
            }
        }
        Command::Check { profiles } => check(&profiles),
        Command::Devices { profile } => crate::devices::run(&profile),
        Command::Doctor {
            profile,
            dataset,
            json,
        } => crate::doctor::run(&profile, dataset, json),
        Command::Plot(args) => crate::plot::run(&args),
        Command::Import(args) => {
            let written = crate::import::run(&args)?;
            for p in &written {
                crate::outln!("{}", p.display());
            }
            crate::errln!("imported {} recording(s)", written.len());
            Ok(())
        }
        Command::Inspect {
            profile,
            paths,
            threshold,
            json,
        } => crate::inspect::run(&profile, &paths, threshold, json),
    }
}

/// `opts.seed` counts only when `seed_given`; `opts.threads` 0 means one per core.
fn simulate(
    profile: &ProfileArg,
    mut opts: SimulateOptions,
    seed_given: bool,
    json: bool,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
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
    let sim_s = samples as f64 / lp.profile.device.rate_hz;
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

fn scan(
    profile: &ProfileArg,
    label: &str,
    count: usize,
    out: &Path,
    texture: Option<&str>,
    seed: Option<u64>,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    if count == 0 {
        return Err(bad("--count must be at least 1"));
    }
    crate::profile::check_label(label).map_err(|e| bad(format!("--label: {e}")))?;
    if lp.profile.device.kind != crate::profile::DeviceKind::Falcon {
        let tex = texture.unwrap_or(label);
        if lp.profile.texture(tex).is_none() {
            let known: Vec<&str> = lp
                .profile
                .textures
                .iter()
                .map(|t| t.label.as_str())
                .collect();
            return Err(bad(format!(
                "the simulator has no texture {tex:?} to put under the probe; {} has {} (use --texture to pick one)",
                lp.origin,
                known.join(", ")
            )));
        }
    }
    // Before anything moves: the recordings must have somewhere to go.
    acquire::check_writable(&out.join(label)).map_err(Failure::from)?;
    // `stop`: end the session (SIGINT, SIGTERM, or the terminal gone);
    // `lost`: the terminal has gone (SIGHUP, a hang-up, a pipe nobody reads,
    // a line that could not be written).
    let stop = Arc::new(AtomicBool::new(false));
    let lost = Arc::new(AtomicBool::new(false));
    for sig in [
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
        signal_hook::consts::SIGHUP,
    ] {
        signal_hook::flag::register(sig, stop.clone()).map_err(runtime)?;
    }
    signal_hook::flag::register(signal_hook::consts::SIGHUP, lost.clone()).map_err(runtime)?;
    let terminal_gone = || {
        lost.store(true, Ordering::Relaxed);
        stop.store(true, Ordering::Relaxed);
    };
    // Nothing may print with println!/eprintln! here: they panic on a
    // terminal that has gone. A line that cannot be written stops the scan.
    let say = |args: std::fmt::Arguments<'_>| {
        if !crate::terminal::out(args) {
            terminal_gone();
        }
    };
    let tell = |args: std::fmt::Arguments<'_>| {
        if !crate::terminal::err(args) {
            terminal_gone();
        }
    };
    tell(format_args!(
        "scanning {label} on the {} device: {count} scan(s) of about {:.0} s each; Ctrl-C stops safely",
        lp.profile.device.kind.name(),
        acquire::path_duration_s(&lp)
    ));
    let mut n = 0;
    let mut failed = None;
    let req = acquire::LiveScans {
        label: label.to_string(),
        texture: texture.map(str::to_string),
        count,
        out: out.to_path_buf(),
        seed: seed.unwrap_or(lp.profile.simulator.seed),
    };
    // Hands-free triggers: used when at least one is plugged in; never fatal.
    let watcher = start_triggers(&lp);
    let triggers = watcher.as_ref().map(|w| w.events.clone());
    let mut on_note = |m: &str| tell(format_args!("{m}"));
    let mut on_scan = |r: &acquire::ScanReport| {
        n += 1;
        let s = &r.saved;
        let state = match (&s.aborted, &s.error) {
            (_, Some(e)) => format!("recording failed: {e}"),
            (Some(reason), None) if s.rows == 0 => {
                format!("aborted before the scan leg began ({reason}); nothing recorded")
            }
            (Some(reason), None) => format!("aborted ({reason}), samples kept, incomplete"),
            (None, None) => "complete".into(),
        };
        say(format_args!(
            "scan {n}: {} — {} samples, {state}",
            s.path.display(),
            s.rows
        ));
        if r.stats.ticks > 0 {
            say(format_args!("  loop: {}", r.stats.summary()));
        }
        if s.aborted.is_some() || s.error.is_some() {
            let kept = if s.rows > 0 {
                format!(
                    "; the {} samples so far are kept in {}, marked incomplete (train, evaluate and features skip it with a warning)",
                    s.rows,
                    s.path.display()
                )
            } else {
                String::new()
            };
            failed = Some(format!("{state}; forces are off{kept}"));
        }
    };
    let hooks = acquire::LiveHooks {
        on_scan: &mut on_scan,
        on_note: &mut on_note,
        triggers,
    };
    let why = || {
        if lost.load(Ordering::Relaxed) {
            "terminal lost".to_string()
        } else {
            "interrupted by a signal".to_string()
        }
    };
    // The terminal is watched while the scan runs: a hang-up or a pipe
    // nobody reads any more stops it within a poll (50 ms).
    let done = AtomicBool::new(false);
    let reports = std::thread::scope(|scope| {
        scope.spawn(|| {
            while !done.load(Ordering::Relaxed) && !stop.load(Ordering::Relaxed) {
                if crate::terminal::lost() {
                    terminal_gone();
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(50));
            }
        });
        let r = acquire::scan_live_stopping(&lp, &req, stop.clone(), &why, hooks);
        done.store(true, Ordering::Relaxed);
        r
    })
    .map_err(Failure::from)?;
    drop(watcher);
    if lost.load(Ordering::Relaxed) {
        return Err(runtime(match failed {
            Some(state) => format!("the terminal was lost: the scan was stopped first: {state}"),
            None => "the terminal was lost: the scans were stopped, forces are off".into(),
        }));
    }
    if let Some(state) = failed {
        return Err(runtime(format!("the scan did not complete: {state}")));
    }
    if reports.len() < count {
        return Err(runtime(format!(
            "only {} of {count} scans ran",
            reports.len()
        )));
    }
    Ok(())
}

/// Start watching the profile's triggers; `None` when none is configured or
/// none is plugged in (each absent one is reported).
fn start_triggers(lp: &LoadedProfile) -> Option<crate::triggers::TriggerWatcher> {
    use crate::triggers::{TriggerEvent, TriggerWatcher, hid::HidBackend};
    if lp.profile.triggers.is_empty() {
        return None;
    }
    let w = match TriggerWatcher::start(lp.profile.triggers.clone(), || Box::new(HidBackend::new()))
    {
        Ok(w) => w,
        Err(e) => {
            crate::terminal::err(format_args!(
                "triggers unavailable ({e}); scans start without them"
            ));
            return None;
        }
    };
    // Each trigger reports in once at start: connected or absent.
    let mut connected = 0;
    for _ in 0..lp.profile.triggers.len() {
        match w.events.recv_timeout(std::time::Duration::from_secs(2)) {
            Ok(TriggerEvent::Connected(s)) => {
                crate::terminal::err(format_args!("trigger {s} connected"));
                connected += 1;
            }
            Ok(TriggerEvent::Absent { source, why }) => {
                crate::terminal::err(format_args!(
                    "trigger {source}: {why}; scans start without it"
                ));
            }
            _ => {}
        }
    }
    (connected > 0).then_some(w)
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
    let files = find_recordings(paths)?;
    let pb = progress_bar(files.len() as u64, "reading");
    let options = dataset::Options {
        threads,
        ..dataset::Options::default()
    };
    let loaded = dataset::load(&files, analysis, options, &|| pb.inc(1));
    pb.finish_and_clear();
    let loaded = loaded?;
    warn_skipped(&loaded.skipped);
    Ok(loaded.into_examples())
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

fn features(profile: &ProfileArg, paths: &[PathBuf], out: Option<&Path>) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let examples = load_examples(paths, &lp.profile.analysis)?;
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
            write_atomically(p, text.as_bytes())?;
            crate::errln!(
                "wrote {} feature rows ({} features each) to {}",
                examples.len(),
                n,
                p.display()
            );
        }
        None => std::io::stdout()
            .write_all(text.as_bytes())
            .map_err(runtime)?,
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

/// Write to a temporary file beside `path`, then rename: never a half-written file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| runtime(format!("{}: {e}", dir.display())))?;
    let tmp = dir.join(format!(
        ".{}.tmp",
        path.file_name()
            .map_or("out".into(), |n| n.to_string_lossy().into_owned())
    ));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        runtime(format!("{}: cannot write: {e}", path.display()))
    })
}

fn train(profile: &ProfileArg, paths: &[PathBuf], out: &Path) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let examples = load_examples(paths, &lp.profile.analysis)?;
    let n = examples.len();
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
    model.save(out).map_err(runtime)?;
    crate::outln!(
        "trained k-NN (k = {}) on {} of {} ({}); model saved to {}",
        model.classifier.k,
        plural(n, "recording", "recordings"),
        plural(model.labels.len(), "class", "classes"),
        model.labels.join(", "),
        out.display()
    );
    Ok(())
}

fn classify(
    profile: &ProfileArg,
    model_path: &Path,
    files: &[PathBuf],
    json: bool,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let model = Model::load(model_path).map_err(bad)?;
    // The model's stored features were made under its analysis settings;
    // a model whose settings differ from the profile's is refused.
    model
        .check_settings(&lp.profile.analysis)
        .map_err(|e| bad(format!("{}: {e}", model_path.display())))?;
    // Other classifier settings still classify, but never silently.
    if let Err(e) = model.check_classifier(&lp.profile.classifier) {
        crate::errln!(
            "warning: {}: {e}; classifying with the model's settings",
            model_path.display()
        );
    }
    if let Some(note) = model.k_notice() {
        crate::errln!("note: {}: {note}", model_path.display());
    }
    let mut ex = FeatureExtractor::new(&model.analysis);
    let files = find_recordings(files)?;
    let mut rows = Vec::new();
    for f in &files {
        let rec = recording::read(f).map_err(DatasetError::from)?;
        if !rec.is_complete() {
            let _ = writeln!(
                std::io::stderr(),
                "warning: {}: incomplete scan, classified anyway",
                f.display()
            );
        }
        if model.analysis.windows.is_some() {
            rows.push(classify_by_windows(&model, &rec, f, &mut ex, json)?);
            continue;
        }
        let feats = dataset::features_of(&rec, f, &mut ex)?;
        let p = model.classify(&feats).map_err(bad)?;
        if !json {
            let votes: Vec<String> = p.votes.iter().map(|(l, v)| format!("{l}:{v}")).collect();
            let truth = rec.label().map_or(String::new(), |l| {
                format!(
                    " (recorded as {l}{})",
                    if l == p.label { ", right" } else { ", WRONG" }
                )
            });
            crate::outln!(
                "{}: {}{} — votes {}, nearest {:.3e}",
                f.display(),
                p.label,
                truth,
                votes.join(" "),
                p.neighbours.first().map_or(f64::NAN, |n| n.distance)
            );
        }
        rows.push(serde_json::json!({
            "file": f.display().to_string(),
            "label": rec.label(),
            "predicted": p.label,
            "votes": p.votes,
            "neighbours": p.neighbours,
        }));
    }
    if json {
        crate::outln!("{}", serde_json::Value::Array(rows));
    }
    Ok(())
}

/// `classify` of one recording by its sub-windows' vote: the line (unless
/// `json`) and the JSON row, which adds the tally and each sub-window's vote.
fn classify_by_windows(
    model: &Model,
    rec: &recording::Recording,
    f: &Path,
    ex: &mut FeatureExtractor,
    json: bool,
) -> Result<serde_json::Value, Failure> {
    let windows = dataset::window_features_of(rec, f, ex)?;
    let p = model.classify_windows(&windows).map_err(bad)?;
    let votes: Vec<(String, usize)> = p
        .tally
        .iter()
        .map(|t| (t.label.clone(), t.windows))
        .collect();
    if !json {
        let shown: Vec<String> = votes.iter().map(|(l, v)| format!("{l}:{v}")).collect();
        let truth = rec.label().map_or(String::new(), |l| {
            format!(
                " (recorded as {l}{})",
                if l == p.label { ", right" } else { ", WRONG" }
            )
        });
        crate::outln!(
            "{}: {}{} — {} of {} windows, window votes {}",
            f.display(),
            p.label,
            truth,
            p.tally[0].windows,
            p.windows.len(),
            shown.join(" ")
        );
    }
    Ok(serde_json::json!({
        "file": f.display().to_string(),
        "label": rec.label(),
        "predicted": p.label,
        "votes": votes,
        "tally": p.tally,
        "windows": p.windows,
    }))
}

fn evaluate_cmd(
    profile: &ProfileArg,
    paths: &[PathBuf],
    shuffle_seed: Option<u64>,
    json: bool,
    threads: usize,
) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let examples = load_examples_on(paths, &lp.profile.analysis, threads)?;
    let mut eval = lp.profile.evaluation.clone();
    if shuffle_seed.is_some() {
        eval.shuffle_seed = shuffle_seed;
    }
    let split = evaluate::split(examples, &eval).map_err(|e| match e {
        evaluate::EvaluateError::NotEnough { .. } => {
            bad(format!("{e}; cross-validate instead (--folds 5 or --loo)"))
        }
        e => bad(e),
    })?;
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

fn check(profiles: &[PathBuf]) -> Result<(), Failure> {
    let mut errors = Vec::new();
    for p in profiles {
        match LoadedProfile::load(p) {
            Ok(lp) => crate::outln!(
                "{}: ok — profile {:?}, device {}, {} waypoints, {} textures, {} features, k = {}{}",
                p.display(),
                lp.profile.name,
                lp.profile.device.kind.name(),
                lp.profile.path.waypoints_m.len(),
                lp.profile.textures.len(),
                lp.profile.analysis.feature_count(),
                lp.profile.classifier.k_text(),
                acquire::injected_faults(&lp)
                    .map(|f| format!("; injects faults: {f}"))
                    .unwrap_or_default()
            ),
            Err(e) => errors.push(e.to_string()),
        }
    }
    // One line per invalid profile, each a whole message; the last is the failure.
    match errors.split_last() {
        None => Ok(()),
        Some((last, rest)) => {
            for e in rest {
                crate::errln!("hapticlab: error: {e}");
            }
            Err(bad(last))
        }
    }
}
