//! `hapticlab scan`: live scans in real time on the profile's device
//! ([`crate::acquire::scan_live_stopping`]), hands-free triggers if any are
//! plugged in, loop statistics per scan; Ctrl-C, a hang-up or a lost
//! terminal stop it with forces off.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::Args;

use crate::acquire;
use crate::profile::LoadedProfile;
use crate::support::{Failure, ProfileArg, bad, load_profile, runtime};

#[derive(Debug, Args)]
pub struct ScanArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
    /// The texture's label; scans go to OUT/<label>/.
    #[arg(long, value_name = "LABEL")]
    pub label: String,
    /// Number of scans.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub count: usize,
    #[arg(long, default_value = "recordings", value_name = "DIR")]
    pub out: PathBuf,
    /// Simulator only: the texture under the probe (default: the label).
    #[arg(long, value_name = "LABEL")]
    pub texture: Option<String>,
    /// Simulator only: the seed.
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
}

pub fn run(a: ScanArgs) -> Result<(), Failure> {
    scan(
        &a.profile,
        &a.label,
        a.count,
        &a.out,
        a.texture.as_deref(),
        a.seed,
    )
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
    let rig = check_request(&lp, label, count, texture)?;
    // Before anything moves: the recordings must have somewhere to go.
    acquire::check_writable(&out.join(label)).map_err(Failure::from)?;
    let stops = Stops::install()?;
    // Nothing may print with println!/eprintln! here: they panic on a
    // terminal that has gone. A line that cannot be written stops the scan.
    let say = |args: std::fmt::Arguments<'_>| {
        if !crate::terminal::out(args) {
            stops.terminal_gone();
        }
    };
    let tell = |args: std::fmt::Arguments<'_>| {
        if !crate::terminal::err(args) {
            stops.terminal_gone();
        }
    };
    tell(format_args!(
        "scanning {label} on the {} device: {count} scan(s) of about {:.0} s each; Ctrl-C stops safely",
        rig.device.kind.name(),
        acquire::path_duration_s(rig.path)
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
        if let Some(f) = report_scan(n, r, &say) {
            failed = Some(f);
        }
    };
    let hooks = acquire::LiveHooks {
        on_scan: &mut on_scan,
        on_note: &mut on_note,
        triggers,
    };
    let reports = stops.run_watching_the_terminal(|stop, why| {
        acquire::scan_live_stopping(&lp, &req, stop, why, hooks)
    })?;
    drop(watcher);
    if stops.lost.load(Ordering::Relaxed) {
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

/// The rig, once the request fits it: at least one scan, a valid label,
/// and on the simulator a texture it knows.
fn check_request<'a>(
    lp: &'a LoadedProfile,
    label: &str,
    count: usize,
    texture: Option<&str>,
) -> Result<crate::profile::Rig<'a>, Failure> {
    let rig = lp.rig().map_err(|e| bad(format!("scan: {e}")))?;
    if count == 0 {
        return Err(bad("--count must be at least 1"));
    }
    crate::profile::check_label(label).map_err(|e| bad(format!("--label: {e}")))?;
    if rig.device.kind != crate::profile::DeviceKind::Falcon {
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
    Ok(rig)
}

/// One scan's lines (where it went, how many samples, the loop's
/// statistics); for a scan that did not complete, what to say of it.
fn report_scan(
    n: usize,
    r: &acquire::ScanReport,
    say: &dyn Fn(std::fmt::Arguments<'_>),
) -> Option<String> {
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
    if s.aborted.is_none() && s.error.is_none() {
        return None;
    }
    let kept = if s.rows > 0 {
        format!(
            "; the {} samples so far are kept in {}, marked incomplete (train, evaluate and features skip it with a warning)",
            s.rows,
            s.path.display()
        )
    } else {
        String::new()
    };
    Some(format!("{state}; forces are off{kept}"))
}

/// What stops the session. `stop`: end it (SIGINT, SIGTERM, or the
/// terminal gone); `lost`: the terminal has gone (SIGHUP, a hang-up, a
/// pipe nobody reads, a line that could not be written).
struct Stops {
    stop: Arc<AtomicBool>,
    lost: Arc<AtomicBool>,
}

impl Stops {
    fn install() -> Result<Stops, Failure> {
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
        Ok(Stops { stop, lost })
    }

    fn terminal_gone(&self) {
        self.lost.store(true, Ordering::Relaxed);
        self.stop.store(true, Ordering::Relaxed);
    }

    /// `scan(stop, why)` run while the terminal is watched: a hang-up or a
    /// pipe nobody reads any more stops it within a poll (50 ms).
    fn run_watching_the_terminal<T, E>(
        &self,
        scan: impl FnOnce(Arc<AtomicBool>, &dyn Fn() -> String) -> Result<T, E>,
    ) -> Result<T, Failure>
    where
        Failure: From<E>,
    {
        let why = || {
            if self.lost.load(Ordering::Relaxed) {
                "terminal lost".to_string()
            } else {
                "interrupted by a signal".to_string()
            }
        };
        let done = AtomicBool::new(false);
        std::thread::scope(|scope| {
            scope.spawn(|| {
                while !done.load(Ordering::Relaxed) && !self.stop.load(Ordering::Relaxed) {
                    if crate::terminal::lost() {
                        self.terminal_gone();
                        break;
                    }
                    std::thread::sleep(std::time::Duration::from_millis(50));
                }
            });
            let r = scan(self.stop.clone(), &why);
            done.store(true, Ordering::Relaxed);
            r
        })
        .map_err(Failure::from)
    }
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
