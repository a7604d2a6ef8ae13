//! Acquiring scans: datasets in virtual time (`simulate`) and live scans in
//! real time (`scan`), both through the one servo loop.
//!
//! This module builds each scan's metadata and file name, makes the device
//! the profile names, and drives the loop; it prints nothing (callers report
//! progress through a callback).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use crate::clock::VirtualClock;
use crate::device::HapticDevice;
use crate::device::falcon::{self, OpenError};
use crate::device::sim::{SimDevice, SimError};
use crate::profile::{DeviceKind, LoadedProfile, MissingRig, PathSpec, check_label};
use crate::recorder::SavedScan;
use crate::servo::stats::LoopStats;
use crate::servo::{Command, Links, ServoEvent, ServoLoop};
use crate::triggers::{TriggerAction, TriggerEvent};

#[derive(Debug, thiserror::Error)]
pub enum AcquireError {
    #[error("{0}")]
    BadInput(String),
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error("{0}")]
    Runtime(String),
}

impl AcquireError {
    /// Bad input (exit code 2) rather than a runtime failure (1).
    pub fn is_bad_input(&self) -> bool {
        // A texture the profile does not have, or a surface CSV that cannot be used.
        matches!(self, AcquireError::BadInput(_) | AcquireError::Sim(_))
    }
}

/// An analysis-only profile asked to make scans: bad input, naming the
/// missing sections.
impl From<MissingRig> for AcquireError {
    fn from(e: MissingRig) -> Self {
        AcquireError::BadInput(e.to_string())
    }
}

impl From<OpenError> for AcquireError {
    fn from(e: OpenError) -> Self {
        match e {
            OpenError::BadInput(m) => AcquireError::BadInput(m),
            OpenError::Device(m) => AcquireError::Runtime(m),
        }
    }
}

/// The profile's device, ready to run: the simulator, the emulated Falcon
/// (both stroking `texture`, free air when `None`, seeded with `seed`), or
/// the real Falcon on USB. `log` hears the Falcon's start-up steps.
pub fn open_device(
    lp: &LoadedProfile,
    texture: Option<&str>,
    seed: u64,
    log: &mut dyn FnMut(&str),
) -> Result<Box<dyn HapticDevice>, AcquireError> {
    let p = &lp.profile;
    Ok(match lp.rig()?.device.kind {
        DeviceKind::Sim => Box::new(SimDevice::new(p, &lp.base_dir, texture, seed)?),
        DeviceKind::FalconEmulator => Box::new(falcon::open_emulated(lp, texture, seed, log)?),
        DeviceKind::Falcon => Box::new(falcon::open_usb(lp, log)?),
    })
}

/// Scans per texture `simulate` makes unless told (the thesis's 30), and
/// `evaluate --simulate` when the profile's evaluation names no count.
pub const DEFAULT_PER_CLASS: usize = 30;

/// What `scan` tells the user when the Falcon is not homed.
pub const HOMING_HELP: &str = "the Falcon is not homed (its LEDs are red): pull the grip all the way out towards you, then push it all the way back in; the LEDs turn blue when it is homed";

/// The metadata every recording carries.
pub fn scan_metadata(
    lp: &LoadedProfile,
    label: &str,
    device: &str,
    extra: &[(&str, toml::Value)],
) -> Vec<(String, toml::Value)> {
    use toml::Value;
    let p = &lp.profile;
    let arr = |v: [f64; 3]| Value::Array(v.iter().map(|&x| Value::Float(x)).collect());
    // Scans come from a rig; without one (an analysis-only profile) only
    // the keys that do not describe it are written.
    let rig = p.rig().ok();
    let mut meta = vec![
        ("label".to_string(), Value::String(label.into())),
        ("profile".to_string(), Value::String(p.name.clone())),
        (
            "profile_sha256".to_string(),
            Value::String(lp.sha256.clone()),
        ),
        ("device".to_string(), Value::String(device.into())),
    ];
    if let Some(rig) = rig {
        meta.push(("rate_hz".to_string(), Value::Float(rig.device.rate_hz)));
    }
    meta.push((
        "software".to_string(),
        Value::String(crate::version::SOFTWARE.into()),
    ));
    if let Some(rig) = rig {
        let path = rig.path;
        meta.extend([
            (
                "stiffness_n_per_m".to_string(),
                arr(rig.controller.stiffness_n_per_m),
            ),
            (
                "damping_n_s_per_m".to_string(),
                arr(rig.controller.damping_n_s_per_m),
            ),
            (
                "speed_m_per_s".to_string(),
                Value::Float(path.speed_m_per_s),
            ),
            (
                "scan_from_m".to_string(),
                arr(path.waypoints_m[path.scan_leg - 1]),
            ),
            (
                "scan_to_m".to_string(),
                arr(path.waypoints_m[path.scan_leg]),
            ),
        ]);
    }
    for (k, v) in extra {
        meta.push((k.to_string(), v.clone()));
    }
    meta
}

/// A seed per scan, from the dataset's seed, the label and the scan's index.
pub fn scan_seed(seed: u64, label: &str, index: usize) -> u64 {
    // FNV-1a over the parts: stable across platforms and versions.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in seed
        .to_le_bytes()
        .iter()
        .chain(label.as_bytes())
        .chain((index as u64).to_le_bytes().iter())
    {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// `DIR/<label>/<label>_<NNN>.csv`.
pub fn scan_file(dir: &Path, label: &str, index: usize) -> PathBuf {
    dir.join(label).join(format!("{label}_{index:03}.csv"))
}

/// The first index from 1 whose file does not exist yet in `DIR/<label>/`.
pub fn next_free_index(dir: &Path, label: &str) -> usize {
    (1..)
        .find(|&i| {
            let p = scan_file(dir, label, i);
            !p.exists() && !p.with_extension("csv.gz").exists()
        })
        .expect("an unbounded range has a free index")
}

pub struct SimulateOptions {
    pub out: PathBuf,
    pub per_class: usize,
    pub seed: u64,
    pub threads: usize,
    /// Compress each finished recording to `.csv.gz`.
    pub gzip: bool,
    /// Replace recordings already at the scans' names (else it is an error).
    pub overwrite: bool,
}

/// One simulated scan in virtual time: the whole path from rest at the first
/// waypoint, the scan leg recorded to `path`. The file is not fsynced: the
/// caller syncs the batch ([`crate::recording::sync_folder`]).
pub fn simulate_one(
    lp: &LoadedProfile,
    label: &str,
    seed: u64,
    path: &Path,
) -> Result<(SavedScan, LoopStats), AcquireError> {
    let p = &lp.profile;
    let rig = lp.rig()?;
    if rig.device.kind == DeviceKind::Falcon {
        return Err(AcquireError::BadInput(format!(
            "{}: simulate runs on the simulator or the emulated Falcon, not a real one (device.kind = \"falcon\"); use `scan` for the real device",
            lp.origin
        )));
    }
    let device = open_device(lp, Some(label), seed, &mut |_| {})?;
    let clock = VirtualClock::new(
        rig.device.rate_hz,
        p.simulator.period_jitter_s,
        p.simulator.period_jitter_fraction,
        seed,
    );
    let meta = scan_metadata(
        lp,
        label,
        device.kind(),
        &[
            ("texture", toml::Value::String(label.into())),
            ("seed", toml::Value::String(seed.to_string())),
            ("clock", toml::Value::String("virtual".into())),
        ],
    );
    let (recorder, sink) = crate::recorder::start_batch();
    let (ev_tx, ev_rx) = crossbeam_channel::bounded(64);
    let links = Links {
        events: Some(ev_tx),
        ..Links::default()
    };
    let mut servo = ServoLoop::new(device, clock, rig, sink, links);
    if rig.device.kind == DeviceKind::FalconEmulator {
        // The emulated hand homes the grip first (forces stay off until then).
        let mut ticks = 0u64;
        while !servo.reading().homed {
            if ticks > (30.0 * rig.device.rate_hz) as u64 {
                return Err(AcquireError::Runtime(
                    "the emulated Falcon did not home within 30 s (is `[falcon.emulator] auto_home` off?)".into(),
                ));
            }
            if let Err(h) = servo.tick() {
                return Err(AcquireError::Runtime(format!(
                    "the emulated Falcon stopped while homing: {h}"
                )));
            }
            ticks += 1;
        }
    }
    servo.apply(Command::StartScan {
        path: path.to_path_buf(),
        meta,
    });
    // The whole path can take at most this long in virtual time.
    let limit = path_duration_s(rig.path) * 3.0 + 10.0;
    let max_ticks = (limit * rig.device.rate_hz) as u64;
    let mut stats = LoopStats::default();
    let mut ticks = 0u64;
    while servo.scan_pending() && ticks < max_ticks {
        if let Err(h) = servo.tick() {
            return Err(AcquireError::Runtime(format!(
                "the simulated scan stopped: {h}"
            )));
        }
        ticks += 1;
    }
    if servo.scan_pending() {
        servo.stop_motion("the scan did not finish in time");
    }
    drop(servo);
    for e in ev_rx.try_iter() {
        if let ServoEvent::ScanEnded { stats: s, .. } = e {
            stats = s;
        }
    }
    let saved = recorder.join().pop().ok_or_else(|| {
        AcquireError::Runtime(format!("{}: the recorder reported nothing", path.display()))
    })?;
    if let Some(e) = &saved.error {
        return Err(AcquireError::Runtime(format!("{}: {e}", path.display())));
    }
    Ok((saved, stats))
}

/// Seconds the path takes at its speeds (from the first waypoint).
pub fn path_duration_s(p: &PathSpec) -> f64 {
    let transit = p.transit_speed_m_per_s.unwrap_or(p.speed_m_per_s);
    p.waypoints_m
        .windows(2)
        .enumerate()
        .map(|(i, w)| {
            let d = crate::profile::dist(w[0], w[1]);
            if i + 1 == p.scan_leg {
                d / p.speed_m_per_s + p.dwell_s
            } else {
                d / transit
            }
        })
        .sum()
}

/// `per_class` scans of every texture in the profile, written under
/// `out/<label>/`, in virtual time on `threads` workers. `progress` is called
/// after each scan with (done, total).
pub fn simulate_dataset(
    lp: &LoadedProfile,
    opts: &SimulateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<SavedScan>, AcquireError> {
    simulate_dataset_until(
        lp,
        opts,
        progress,
        &std::sync::atomic::AtomicBool::new(false),
    )
}

/// [`simulate_dataset`], stopping early when `stop` is raised: no scan is
/// started after it; the scans already running finish (virtual time: a
/// fraction of a second each), and those finished are returned.
pub fn simulate_dataset_until(
    lp: &LoadedProfile,
    opts: &SimulateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Vec<SavedScan>, AcquireError> {
    // An analysis-only profile has nothing to simulate with: say which sections.
    lp.rig()?;
    if lp.profile.textures.is_empty() {
        return Err(AcquireError::BadInput(format!(
            "{}: the profile has no [[textures]] to simulate",
            lp.origin
        )));
    }
    if opts.per_class == 0 {
        return Err(AcquireError::BadInput(
            "--per-class must be at least 1".into(),
        ));
    }
    let jobs: Vec<(String, usize)> = lp
        .profile
        .textures
        .iter()
        .flat_map(|t| (1..=opts.per_class).map(move |i| (t.label.clone(), i)))
        .collect();
    for t in &lp.profile.textures {
        check_label(&t.label).map_err(AcquireError::BadInput)?;
    }
    if !opts.overwrite {
        let taken = jobs.iter().find_map(|(label, i)| {
            let plain = scan_file(&opts.out, label, *i);
            let gz = plain.with_extension("csv.gz");
            [plain, gz].into_iter().find(|p| p.exists())
        });
        if let Some(p) = taken {
            return Err(AcquireError::BadInput(format!(
                "{} already exists: simulate does not overwrite recordings; give an empty --out folder, or --overwrite to replace them",
                p.display()
            )));
        }
    }
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let total = jobs.len();
    let results: Vec<Result<Vec<(usize, SavedScan)>, AcquireError>> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..opts.threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        if stop.load(Ordering::Relaxed) {
                            break;
                        }
                        let j = next.fetch_add(1, Ordering::Relaxed);
                        let Some((label, i)) = jobs.get(j) else { break };
                        let path = scan_file(&opts.out, label, *i);
                        let seed = scan_seed(opts.seed, label, *i);
                        let (mut saved, _) = simulate_one(lp, label, seed, &path)?;
                        if opts.gzip {
                            saved.path = crate::recording::compress(&saved.path)
                                .map_err(|e| AcquireError::Runtime(e.to_string()))?;
                        }
                        mine.push((j, saved));
                        progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                    }
                    Ok(mine)
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| {
                w.join()
                    .unwrap_or_else(|p| Err(AcquireError::Runtime(crate::servo::panic_message(&p))))
            })
            .collect()
    });
    let mut all = Vec::with_capacity(total);
    for r in results {
        all.extend(r?);
    }
    crate::recording::sync_folder(&opts.out).map_err(|e| AcquireError::Runtime(e.to_string()))?;
    all.sort_by_key(|(j, _)| *j);
    Ok(all.into_iter().map(|(_, s)| s).collect())
}

/// What `scan` reports per scan.
#[derive(Debug, Clone)]
pub struct ScanReport {
    pub saved: SavedScan,
    pub stats: LoopStats,
}

/// What `scan` asks for.
pub struct LiveScans {
    pub label: String,
    /// Simulator only: the texture under the probe (default: the label).
    pub texture: Option<String>,
    pub count: usize,
    pub out: PathBuf,
    pub seed: u64,
}

/// What a live session reports besides scans, and its optional triggers.
pub struct LiveHooks<'a> {
    pub on_scan: &'a mut dyn FnMut(&ScanReport),
    /// The device's start-up steps, homing instructions, trigger news.
    pub on_note: &'a mut dyn FnMut(&str),
    /// Hands-free triggers: when given, each scan waits for a start press,
    /// and an abort press stops the running scan.
    pub triggers: Option<crossbeam_channel::Receiver<TriggerEvent>>,
}

/// Wait until the device is homed, telling the user how once. `Ok(false)`
/// when the loop ended or a signal came first.
fn wait_for_homing(
    lp: &LoadedProfile,
    handle: &crate::servo::ServoHandle,
    stop: &std::sync::atomic::AtomicBool,
    on_note: &mut dyn FnMut(&str),
) -> Result<bool, AcquireError> {
    let limit = lp
        .profile
        .falcon
        .as_ref()
        .map_or(120.0, |f| f.homing_timeout_s);
    let started = Instant::now();
    let mut told = false;
    loop {
        if stop.load(Ordering::Relaxed) {
            handle.stop.store(true, Ordering::Relaxed);
            return Ok(false);
        }
        match handle.telemetry.recv_timeout(Duration::from_millis(50)) {
            Ok(t) if t.homed => {
                if told {
                    on_note("homed: the LEDs are blue; forces are on");
                }
                return Ok(true);
            }
            Ok(_) => {
                if !told {
                    on_note(&format!("{HOMING_HELP} (waiting up to {limit:.0} s)"));
                    told = true;
                }
            }
            Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return Ok(false),
        }
        if handle.is_finished() {
            return Ok(false);
        }
        if started.elapsed().as_secs_f64() > limit {
            return Err(AcquireError::Runtime(format!(
                "the Falcon was not homed within {limit:.0} s: pull the grip fully out and push it fully in; if the LEDs stay red, check the Falcon's wall power (homing needs the motors)"
            )));
        }
    }
}

/// The profile's injected faults for its device, named, if it has any.
pub fn injected_faults(lp: &LoadedProfile) -> Option<String> {
    let p = &lp.profile;
    let named = |keys: &[(&str, Option<f64>)]| -> Vec<String> {
        keys.iter()
            .filter_map(|(k, v)| v.map(|t| format!("{k} = {t}")))
            .collect()
    };
    let (section, faults) = match p.device.as_ref()?.kind {
        DeviceKind::Sim => {
            let f = &p.simulator.faults;
            (
                "[simulator.faults]",
                named(&[
                    ("read_error_after_s", f.read_error_after_s),
                    ("stall_after_s", f.stall_after_s),
                    ("nan_after_s", f.nan_after_s),
                    ("vanish_after_s", f.vanish_after_s),
                ]),
            )
        }
        DeviceKind::FalconEmulator => {
            let e = p.falcon.clone().unwrap_or_default().emulator;
            (
                "[falcon.emulator]",
                named(&[
                    ("read_error_after_s", e.read_error_after_s),
                    ("stall_after_s", e.stall_after_s),
                    ("unplug_after_s", e.unplug_after_s),
                    ("reversed_motor", e.reversed_motor.map(f64::from)),
                    ("motor_power_lost_after_s", e.motor_power_lost_after_s),
                    (
                        "slow_link_ms",
                        (e.slow_link_ms > 0.0).then_some(e.slow_link_ms),
                    ),
                ]),
            )
        }
        DeviceKind::Falcon => return None,
    };
    (!faults.is_empty()).then(|| format!("{section} {}", faults.join(", ")))
}

/// Make `dir` and check a file can be created in it (then remove it).
pub fn check_writable(dir: &Path) -> Result<(), AcquireError> {
    check_writable_for(dir, "--out")
}

/// [`check_writable`], the message naming the command-line `option` that
/// chose the folder.
pub fn check_writable_for(dir: &Path, option: &str) -> Result<(), AcquireError> {
    let probe = dir.join(format!(".hapticlab-write-check-{}", std::process::id()));
    let result = std::fs::create_dir_all(dir).and_then(|()| {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&probe)
            .map(drop)
    });
    let _ = std::fs::remove_file(&probe);
    result.map_err(|e| {
        AcquireError::Runtime(format!(
            "cannot record into {}: {e}; nothing was scanned: choose a writable folder with {option} (or fix this one's permissions)",
            dir.display()
        ))
    })
}

fn trigger_note(e: &TriggerEvent) -> Option<String> {
    match e {
        TriggerEvent::Action { .. } => None,
        TriggerEvent::Connected(s) => Some(format!("trigger {s} connected")),
        TriggerEvent::Absent { source, why } => {
            Some(format!("trigger {source}: {why}; scans start without it"))
        }
        TriggerEvent::Unplugged { source, why } => Some(format!(
            "trigger {source} was unplugged ({why}); scans go on without it"
        )),
    }
}

/// Live scans in real time on the profile's device: `count` runs of the path,
/// each recorded to the next free `out/<label>/<label>_NNN.csv`. `texture`
/// picks the simulated texture (default: the label). Stops early, keeping
/// what was recorded, when `stop` is raised (signals). `hooks` reports each
/// scan and the device's notes, and carries hands-free triggers.
pub fn scan_live_with(
    lp: &LoadedProfile,
    req: &LiveScans,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    hooks: LiveHooks<'_>,
) -> Result<Vec<ScanReport>, AcquireError> {
    scan_live_stopping(lp, req, stop, &|| "interrupted by a signal".into(), hooks)
}

/// [`scan_live_with`], where `why` says why `stop` was raised: a scan it
/// stops is kept with that reason in its `# aborted` line.
pub fn scan_live_stopping(
    lp: &LoadedProfile,
    req: &LiveScans,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    why: &dyn Fn() -> String,
    hooks: LiveHooks<'_>,
) -> Result<Vec<ScanReport>, AcquireError> {
    let LiveHooks {
        on_scan,
        on_note,
        triggers,
    } = hooks;
    let label = req.label.as_str();
    let texture = req.texture.as_deref().unwrap_or(label);
    check_label(label).map_err(AcquireError::BadInput)?;
    // Before the device moves: the recordings must have somewhere to go.
    check_writable(&req.out.join(label))?;
    let rig = lp.rig()?;
    if let Some(faults) = injected_faults(lp) {
        on_note(&format!(
            "note: {} injects device faults ({faults}), to rehearse failures",
            lp.origin
        ));
    }
    let device = open_device(lp, Some(texture), req.seed, on_note)?;
    let kind = device.kind();
    let handle = crate::servo::spawn(rig, move || device)
        .map_err(|e| AcquireError::Runtime(format!("cannot start the servo thread: {e}")))?;
    let mut reports = Vec::new();
    let live = Live {
        handle: &handle,
        stop: &stop,
        triggers: triggers.as_ref(),
        per_scan_limit: Duration::from_secs_f64(path_duration_s(rig.path) * 2.0 + 30.0),
    };
    let scanned = wait_for_homing(lp, &handle, &stop, on_note).and_then(|homed| {
        if homed {
            live.scans(lp, req, kind, why, on_note, &mut |r| {
                on_scan(&r);
                reports.push(r);
            })
        } else {
            Ok(())
        }
    });
    // Whatever happened, the loop is shut down (forces zero) before the
    // error, if any, is told.
    let (result, saved) = handle.shutdown();
    scanned?;
    for s in saved {
        let r = ScanReport {
            saved: s,
            stats: LoopStats::default(),
        };
        on_scan(&r);
        reports.push(r);
    }
    match result {
        // The device failed before any scan could run: that is the error.
        Ok((crate::servo::Halt::DeviceError(reason), _)) if reports.is_empty() => Err(
            AcquireError::Runtime(format!("the {kind} device stopped: {reason}")),
        ),
        Ok(_) => Ok(reports),
        Err(panic) => Err(AcquireError::Runtime(format!(
            "the servo thread failed: {panic}"
        ))),
    }
}

/// A running servo loop making live scans, and what stops them.
struct Live<'a> {
    handle: &'a crate::servo::ServoHandle,
    /// Raised by signals (or the caller): the running scan is kept with
    /// the reason, and no other starts.
    stop: &'a std::sync::atomic::AtomicBool,
    triggers: Option<&'a crossbeam_channel::Receiver<TriggerEvent>>,
    /// A scan running longer than this is aborted.
    per_scan_limit: Duration,
}

/// How a scan's motion ended, as the servo loop reported it.
struct Ended {
    stats: LoopStats,
    recorded: bool,
    aborted: Option<String>,
}

impl Live<'_> {
    /// `req.count` scans, each reported to `report` as it ends; stops after
    /// an aborted one, when the loop ends, or at an abort press.
    fn scans(
        &self,
        lp: &LoadedProfile,
        req: &LiveScans,
        kind: &str,
        why: &dyn Fn() -> String,
        on_note: &mut dyn FnMut(&str),
        report: &mut dyn FnMut(ScanReport),
    ) -> Result<(), AcquireError> {
        let (label, out) = (req.label.as_str(), req.out.as_path());
        for k in 0..req.count {
            if !self.wait_for_start(k, req.count, on_note) {
                break;
            }
            let path = scan_file(out, label, next_free_index(out, label));
            let meta = scan_metadata(
                lp,
                label,
                kind,
                &[
                    (
                        "texture",
                        toml::Value::String(req.texture.as_deref().unwrap_or(label).into()),
                    ),
                    ("seed", toml::Value::String(req.seed.to_string())),
                    ("clock", toml::Value::String("real".into())),
                ],
            );
            self.handle.send(Command::StartScan {
                path: path.clone(),
                meta,
            });
            let Some(ended) = self.until_ended(why, on_note) else {
                break;
            };
            let saved = self.saved_file(&path, ended.recorded, ended.aborted)?;
            let aborted = saved.aborted.is_some() || saved.error.is_some();
            report(ScanReport {
                saved,
                stats: ended.stats,
            });
            if aborted {
                break;
            }
        }
        Ok(())
    }

    /// Waits for a start press on the triggers (at once `true` without
    /// them); `false` when the session ends instead (a signal, the loop
    /// gone, an abort press).
    fn wait_for_start(&self, k: usize, count: usize, on_note: &mut dyn FnMut(&str)) -> bool {
        let Some(rx) = self.triggers else {
            return true;
        };
        on_note(&format!(
            "press start on the trigger to begin scan {} of {count} (abort ends the session)",
            k + 1
        ));
        loop {
            if self.stop.load(Ordering::Relaxed) || self.handle.is_finished() {
                self.handle.stop.store(true, Ordering::Relaxed);
                return false;
            }
            let _ = self.handle.telemetry.try_iter().count();
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(TriggerEvent::Action { action, .. }) => match action {
                    TriggerAction::Start => return true,
                    TriggerAction::Abort => {
                        on_note("abort pressed: no more scans");
                        return false;
                    }
                    TriggerAction::Store => {
                        on_note("store pressed: scans are stored as they finish")
                    }
                },
                Ok(e) => {
                    if let Some(m) = trigger_note(&e) {
                        on_note(&m);
                    }
                }
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
                    on_note("the triggers stopped; scanning without them");
                    return true;
                }
            }
        }
    }

    /// Follows the running scan until the loop says it ended (`None`: the
    /// loop itself ended first). A raised stop flag stops it with `why`;
    /// an abort press or the time limit aborts it.
    fn until_ended(
        &self,
        why: &dyn Fn() -> String,
        on_note: &mut dyn FnMut(&str),
    ) -> Option<Ended> {
        let started = Instant::now();
        let mut stopping = false;
        loop {
            if self.stop.load(Ordering::Relaxed) && !stopping {
                // The scan stops, kept with the reason; the loop halts after.
                self.handle.send(Command::Stop(why()));
                stopping = true;
            }
            // Nobody displays telemetry here: drain it so none counts as dropped.
            let _ = self.handle.telemetry.try_iter().count();
            for e in self.triggers.into_iter().flat_map(|rx| rx.try_iter()) {
                match e {
                    TriggerEvent::Action {
                        action: TriggerAction::Abort,
                        ..
                    } => self.handle.send(Command::Abort),
                    TriggerEvent::Action { .. } => {}
                    other => {
                        if let Some(m) = trigger_note(&other) {
                            on_note(&m);
                        }
                    }
                }
            }
            match self.handle.events.recv_timeout(Duration::from_millis(50)) {
                Ok(ServoEvent::ScanEnded {
                    stats,
                    samples,
                    aborted,
                    ..
                }) => {
                    return Some(Ended {
                        stats,
                        recorded: samples > 0,
                        aborted,
                    });
                }
                Ok(ServoEvent::Notice { message }) => on_note(&format!("note: {message}")),
                Ok(_) => {}
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {
                    if started.elapsed() > self.per_scan_limit {
                        self.handle.send(Command::Abort);
                    }
                    if self.handle.is_finished() {
                        return None;
                    }
                }
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return None,
            }
        }
    }

    /// The file the recorder finished for the scan at `path`, just after
    /// its motion ended; a scan stopped before its leg began has no file.
    fn saved_file(
        &self,
        path: &Path,
        recorded: bool,
        aborted: Option<String>,
    ) -> Result<SavedScan, AcquireError> {
        if !recorded {
            return Ok(SavedScan {
                path: path.to_path_buf(),
                rows: 0,
                complete: false,
                aborted,
                error: None,
            });
        }
        let waited = Instant::now();
        loop {
            if let Some(s) = self.handle.saved().pop() {
                return Ok(s);
            }
            if waited.elapsed() > Duration::from_secs(60) {
                return Err(AcquireError::Runtime(format!(
                    "{}: the recorder did not finish the file within a minute",
                    path.display()
                )));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_and_file_names_are_stable() {
        assert_eq!(scan_seed(1, "S2", 3), scan_seed(1, "S2", 3));
        assert_ne!(scan_seed(1, "S2", 3), scan_seed(1, "S2", 4));
        assert_ne!(scan_seed(1, "S2", 3), scan_seed(2, "S2", 3));
        assert_eq!(
            scan_file(Path::new("d"), "S2", 7),
            PathBuf::from("d/S2/S2_007.csv")
        );
    }

    #[test]
    fn the_thesis_path_takes_about_thirteen_seconds() {
        let d = path_duration_s(LoadedProfile::thesis().rig().unwrap().path);
        assert!((d - (0.1009 / 0.03 + 8.97 + 0.3)).abs() < 0.01, "{d}");
    }
}
