//! The lab console: a terminal front end over the engine (ratatui +
//! crossterm), after the thesis's GUI (section 3.1.1): modes Manual, Target
//! and Test, Start Measurement, Store Data, Predict — and training,
//! evaluation and replay.
//!
//! This module runs the session: it starts the servo on the profile's device
//! ([`live::Lab`]), sets up the terminal, and loops at a capped frame rate:
//! drain the servo's channels once (never blocking the servo thread), poll
//! finished jobs, advance a replay, draw (`impl Widget for &App`, a pure
//! function of state), then wait for keys until the next frame is due. Keys
//! become [`app::Action`]s, which [`execute`] carries out. On quit, error,
//! panic, SIGINT/SIGTERM, or a lost terminal (SIGHUP, a hang-up, a failed
//! read or draw) the servo is shut down first (forces off, any scan kept as
//! aborted with the reason), then the terminal is restored, fallibly; a lost
//! terminal exits 1. The servo also watches the loop's heartbeat (one a
//! frame): a loop stuck for a second stops the motion on its own.

pub mod app;
pub mod curate;
pub mod dataset;
pub mod estimate;
pub mod event;
pub mod feed;
#[doc(hidden)]
pub mod fixtures;
pub mod form;
pub mod keymap;
pub mod live;
pub mod panels;
pub mod replay;
pub mod scan;
pub mod session;
#[cfg(test)]
mod session_tests;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use ratatui::Terminal;
use ratatui::backend::Backend;

use crate::analysis::FeatureExtractor;
use crate::profile::LoadedProfile;
use crate::recording;
use crate::servo::Command;
use crate::support::Failure;
use app::{Action, App, Source};
use dataset::Jobs;
use event::{Event, EventSource, Signals};
use keymap::KeyMap;
use live::{Lab, LabPort};

/// Frames per second at most.
pub const FRAME_RATE: u32 = 30;
/// Frames a second while the console sits idle (Manual mode, no scan, no
/// replay, no key for a while): still the 20 a second the panels promise.
pub const IDLE_FRAME_RATE: u32 = 20;
const IDLE_AFTER: Duration = Duration::from_secs(2);

/// What the console opens: the dataset folder, whether it is an earlier
/// session resumed, and the profile as the folder's `session.toml` names it.
pub struct Opening {
    pub dataset: PathBuf,
    pub resumed: Option<session::Session>,
    pub profile: String,
}

fn runtime(m: impl std::fmt::Display) -> Failure {
    Failure::Runtime(m.to_string())
}

/// How a console session ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ending {
    /// The user quit.
    Quit,
    /// SIGINT or SIGTERM asked the session to end.
    Signal,
    /// The terminal has gone (SIGHUP, a hang-up, a read or write that
    /// failed): why.
    TerminalLost(String),
}

impl Ending {
    /// Why a scan still running is stopped (its `# aborted` line).
    pub fn stop_reason(&self) -> String {
        match self {
            Ending::Quit => "the console was quit during the scan".into(),
            Ending::Signal => "interrupted by a signal (SIGINT or SIGTERM)".into(),
            Ending::TerminalLost(why) => format!("terminal lost ({why})"),
        }
    }

    /// The session's result: a lost terminal is a runtime failure (exit 1).
    fn result(&self, stopped: &str) -> Result<(), Failure> {
        match self {
            Ending::TerminalLost(why) => {
                Err(runtime(format!("the terminal was lost ({why}); {stopped}")))
            }
            _ => Ok(()),
        }
    }
}

/// Raw mode and the alternate screen, entered and left fallibly (see
/// [`crate::terminal`]: ratatui's own hooks panic on a terminal that has gone).
fn open_terminal() -> Result<crate::terminal::Screen, Failure> {
    crate::terminal::enter().map_err(|e| runtime(format!("cannot open the terminal: {e}")))
}

/// `hapticlab` / `hapticlab console`: the live console.
pub fn run(lp: LoadedProfile, opening: Opening) -> Result<(), Failure> {
    // Live mode drives the rig; replay works on an analysis-only profile.
    let rig = lp.rig().map_err(|e| {
        Failure::BadInput(format!(
            "console: {e}; to browse, train on and predict its recordings: hapticlab replay DIR --profile {}",
            lp.origin
        ))
    })?;
    let keys = KeyMap::from_settings(&lp.profile.console).map_err(Failure::BadInput)?;
    let dataset = opening.dataset.clone();
    let signals = Signals::register().map_err(runtime)?;
    let mut app = App::new(
        lp.clone(),
        keys,
        Source::Live {
            backend: rig.device.kind.name().into(),
        },
        dataset.clone(),
    );
    let texture = lp.profile.texture(&app.label).map(|t| t.label.clone());
    // Before anything moves: scans must have somewhere to go (as `scan --out`).
    check_dataset_writable(&dataset)?;
    // A profile's texture or firmware file that cannot be used is bad input
    // (exit 2); a device that cannot be opened is a runtime failure (1).
    let mut lab = Lab::start(&lp, &dataset, texture.as_deref()).map_err(|e| {
        if e.is_bad_input() {
            Failure::BadInput(e.to_string())
        } else {
            runtime(e)
        }
    })?;
    app.mounted = lab.texture.clone();
    refresh_dataset(&mut app);
    // A scan an earlier session left unstored can be stored from here (w).
    let mut ex = FeatureExtractor::new(&lp.profile.analysis);
    if let Some(view) = scan::newest_unsaved(&dataset, &mut ex) {
        app.on_unsaved_found(view);
    }
    dataset::adopt_saved_model(&mut app, &dataset);
    if let Some(s) = &opening.resumed {
        app.on_resumed(s, std::time::SystemTime::now());
    }
    if let Err(why) = session::remember(&dataset, &opening.profile) {
        // Never replaced, never silently passed over.
        app.warn(format!(
            "{why}; this session runs under {}",
            opening.profile
        ));
    }
    let jobs = Jobs::default();
    let mut screen = open_terminal()?;
    let ending = match event::Input::start() {
        Ok(mut input) => run_loop(
            &mut screen,
            &mut app,
            Some(&mut lab),
            &mut input,
            &jobs,
            &signals,
        ),
        Err(e) => Ending::TerminalLost(format!("terminal input: {e}")),
    };
    // The motion first, whatever ended the session: the loop halts, forces
    // zero, any scan is kept as aborted with the reason.
    let saved = lab.shutdown(&ending.stop_reason());
    // Then the terminal, fallibly (it may have gone).
    drop(screen);
    // The session's folder, made by its first scan, names its profile.
    let dataset = app.dataset.dir.clone();
    let _ = session::remember(&dataset, &opening.profile);
    // Every scan cut short this session: those aborted on the way, and the
    // one the shutdown stopped.
    let mut cut = app.interrupted.clone();
    for s in saved.iter().filter(|s| !s.complete) {
        if !cut.contains(&s.path) {
            cut.push(s.path.clone());
        }
    }
    let interrupted = cut.len();
    let (counts, unsaved) = dataset::count(&dataset);
    let stored: usize = counts.iter().map(|(_, n)| n).sum();
    crate::terminal::out(format_args!(
        "hapticlab console closed: {stored} recording(s) in {}{}{}",
        dataset.display(),
        if unsaved > 0 {
            format!(
                ", {unsaved} scan(s) not stored in {}",
                dataset.join(dataset::UNSAVED_DIR).display()
            )
        } else {
            String::new()
        },
        if interrupted > 0 {
            format!(
                "; {} interrupted and kept as incomplete",
                crate::classify::plural(interrupted, "scan", "scans")
            )
        } else {
            String::new()
        }
    ));
    ending.result(&if interrupted > 0 {
        format!(
            "the motion was stopped first (forces off) and the scan kept as incomplete in {}",
            dataset.join(dataset::UNSAVED_DIR).display()
        )
    } else {
        "the motion was stopped first (forces off)".into()
    })
}

/// Scans are recorded under `<dataset>/.unsaved/`: check a file can be
/// created there, as `scan` checks `--out`, without leaving folders behind
/// that were not there before.
fn check_dataset_writable(dataset: &Path) -> Result<(), Failure> {
    let unsaved = dataset.join(dataset::UNSAVED_DIR);
    // The folders the check creates, deepest first, to remove again.
    let created: Vec<PathBuf> = unsaved
        .ancestors()
        .take_while(|p| !p.as_os_str().is_empty() && !p.exists())
        .map(Path::to_path_buf)
        .collect();
    let checked = crate::acquire::check_writable_for(&unsaved, "--dataset");
    for dir in &created {
        let _ = std::fs::remove_dir(dir);
    }
    checked.map_err(Failure::from)
}

/// `hapticlab replay FILE|DIR`: recordings through the same dashboard.
pub fn replay(lp: LoadedProfile, path: &Path, dataset: Option<PathBuf>) -> Result<(), Failure> {
    let keys = KeyMap::from_settings(&lp.profile.console).map_err(Failure::BadInput)?;
    let files = recording::collect_files(&[path.to_path_buf()])
        .map_err(|e| Failure::BadInput(e.to_string()))?;
    if files.is_empty() {
        return Err(Failure::BadInput(format!(
            "{}: no recordings (*.csv, *.csv.gz) to replay",
            path.display()
        )));
    }
    // The training set: --dataset, the folder given, or the folder above a file's label folder.
    let train_dir = dataset.clone().or_else(|| {
        if path.is_dir() {
            Some(path.to_path_buf())
        } else {
            path.parent().and_then(Path::parent).map(Path::to_path_buf)
        }
    });
    let signals = Signals::register().map_err(runtime)?;
    let mut app = App::new(
        lp.clone(),
        keys,
        Source::ReplayOnly,
        train_dir.clone().unwrap_or_else(|| path.to_path_buf()),
    );
    if let Some(d) = &train_dir {
        refresh_dataset(&mut app);
        dataset::adopt_saved_model(&mut app, d);
    }
    let jobs = Jobs::default();
    open_replay(&mut app, &jobs, path.to_path_buf(), files, train_dir);
    let mut screen = open_terminal()?;
    let ending = match event::Input::start() {
        Ok(mut input) => run_loop(&mut screen, &mut app, None, &mut input, &jobs, &signals),
        Err(e) => Ending::TerminalLost(format!("terminal input: {e}")),
    };
    drop(screen);
    ending.result("the replay was closed")
}

fn refresh_dataset(app: &mut App) {
    let (counts, unsaved) = dataset::count(&app.dataset.dir);
    app.dataset.counts = counts;
    app.dataset.unsaved = unsaved;
}

fn open_replay(
    app: &mut App,
    jobs: &Jobs,
    source: PathBuf,
    files: Vec<PathBuf>,
    train_dir: Option<PathBuf>,
) {
    let mut r = replay::Replay::new(source, files.clone());
    r.listing = true;
    app.replay = Some(r);
    app.replay_feed.clear();
    jobs.list(&app.profile, files, app.model.clone(), train_dir);
    open_recording(app, 0);
}

/// Open recording `i` of the replay list: play it from the start.
fn open_recording(app: &mut App, i: usize) {
    let model = app.model.clone();
    let lp = app.profile.clone();
    let Some(r) = app.replay.as_mut() else {
        return;
    };
    let Some(path) = r.entries.get(i).map(|e| e.path.clone()) else {
        return;
    };
    r.selected = i;
    app.replay_feed.clear();
    match recording::read(&path) {
        Ok(rec) => {
            let mut ex = FeatureExtractor::new(&lp.profile.analysis);
            let mut view = scan::analyse(&rec, &path, &mut ex);
            if let Some(m) = &model {
                view.prediction = scan::predict_view(m, &view);
            }
            r.player = Some(replay::Player::new(&rec));
            r.scan = Some(view);
            r.error = None;
        }
        Err(e) => {
            r.player = None;
            r.scan = None;
            r.error = Some(e.to_string());
        }
    }
}

/// Draw, drain, and handle keys until the app quits, a signal arrives or
/// the terminal goes. Returns at once (within a frame) on a lost terminal:
/// the caller stops the motion before it touches the terminal again.
///
/// Everything outside the app comes in as a parameter — the terminal (any
/// ratatui backend), its events, the lab (none for a replay), the signals —
/// so a whole session runs in a test against `TestBackend` with scripted
/// keys (see `console::session_tests`).
pub fn run_loop<B: Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
    mut lab: Option<&mut dyn LabPort>,
    input: &mut dyn EventSource,
    jobs: &Jobs,
    signals: &Signals,
) -> Ending
where
    B::Error: std::fmt::Display,
{
    let mut last_key = Instant::now();
    if let Ok(size) = terminal.size() {
        app.resize(size.width, size.height);
    }
    let mut last = Instant::now();
    while !app.quit {
        if signals.hung_up() {
            return Ending::TerminalLost("SIGHUP".into());
        }
        if input.hung_up() {
            return Ending::TerminalLost("hang-up".into());
        }
        if signals.raised() {
            return Ending::Signal;
        }
        let started = Instant::now();
        // The world, once per frame.
        let mut actions = match reborrow(&mut lab) {
            Some(l) => l.drain(app),
            None => vec![],
        };
        for r in jobs.poll() {
            actions.extend(app.on_job(r));
        }
        run_actions(actions, app, reborrow(&mut lab), jobs);
        app.advance(started.duration_since(last).as_secs_f64());
        last = started;
        if let Err(e) = terminal.draw(|f| f.render_widget(&*app, f.area())) {
            return Ending::TerminalLost(format!("cannot draw: {e}"));
        }
        // Keys until the next frame is due: 30 fps while anything moves or
        // the user types, 20 (the panels' minimum) when the console sits idle.
        let idle = app.mode() == crate::servo::Mode::Manual
            && !app.scan_running
            && app.replay.is_none()
            && last_key.elapsed() > IDLE_AFTER;
        let frame = Duration::from_secs(1) / if idle { IDLE_FRAME_RATE } else { FRAME_RATE };
        loop {
            let left = frame.saturating_sub(started.elapsed());
            if left.is_zero() || app.quit {
                break;
            }
            match input.next(left) {
                Ok(Some(Event::Key(k))) => {
                    last_key = Instant::now();
                    let actions = app.handle_key(k);
                    run_actions(actions, app, reborrow(&mut lab), jobs);
                }
                Ok(Some(Event::Resize(w, h))) => app.resize(w, h),
                Ok(None) => {}
                Err(e) => return Ending::TerminalLost(format!("terminal input: {e}")),
            }
        }
    }
    Ending::Quit
}

fn run_actions(
    mut actions: Vec<Action>,
    app: &mut App,
    mut lab: Option<&mut dyn LabPort>,
    jobs: &Jobs,
) {
    // Actions may lead to more (a store after a queued scan, a prediction after training).
    while !actions.is_empty() {
        let mut next = Vec::new();
        for a in actions {
            next.extend(execute(a, app, reborrow(&mut lab), jobs));
        }
        actions = next;
    }
}

/// Carry out one action.
pub fn execute(
    a: Action,
    app: &mut App,
    lab: Option<&mut dyn LabPort>,
    jobs: &Jobs,
) -> Vec<Action> {
    let dir = app.dataset.dir.clone();
    match a {
        Action::Quit => {}
        Action::SetMode(m) => send(lab, Command::SetMode(m)),
        Action::SetTarget(p) => send(lab, Command::SetTarget(p)),
        Action::SetSpeed(s) => send(lab, Command::SetSpeedScale(s)),
        Action::Abort => send(lab, Command::Abort),
        Action::StartScan => {
            if let Some(l) = lab {
                let label = app.label.clone();
                l.start_scan(&label);
            } else {
                app.scan_running = false;
            }
        }
        Action::Store { label } => {
            let Some(from) = app.last_scan.as_ref().map(|s| s.path.clone()) else {
                return vec![];
            };
            let r = live::store(&from, &dir, &label);
            app.on_stored(r);
            refresh_dataset(app);
        }
        Action::Mount(t) => {
            if let Some(l) = lab {
                match l.mount(&t, app) {
                    Ok(()) => {
                        app.mounted = l.texture();
                        app.live.clear();
                    }
                    Err(e) => app.error(format!("cannot mount {t}: {e}")),
                }
            }
        }
        Action::Predict => {
            let model = app.model.clone();
            let target = match app.replay.as_mut() {
                Some(r) => r.scan.as_mut(),
                None => app.last_scan.as_mut(),
            };
            if let (Some(m), Some(s)) = (model, target)
                && let Some(p) = scan::predict_view(&m, s)
            {
                let text = match &p {
                    Ok(pv) => format!("predicted {}", pv.prediction.label),
                    Err(e) => format!("no prediction: {e}"),
                };
                s.prediction = Some(p);
                app.info(text);
            }
        }
        Action::Train { then_predict } => jobs.train(&app.profile, &dir, then_predict),
        Action::Evaluate => jobs.evaluate(&app.profile, &dir),
        Action::OpenReplay => match recording::collect_files(std::slice::from_ref(&dir)) {
            Ok(mut files) if !files.is_empty() || curate::hidden_scans(&dir).next().is_some() => {
                let stored = files.len();
                // Scans not stored and excluded ones, listed after, to curate.
                files.extend(curate::hidden_scans(&dir));
                let hidden = files.len() - stored;
                open_replay(app, jobs, dir.clone(), files, Some(dir));
                let also = if hidden > 0 {
                    format!(" and {hidden} not stored or excluded")
                } else {
                    String::new()
                };
                app.info(format!(
                    "replaying {stored} stored recordings{also}; Esc returns to the live device"
                ));
            }
            Ok(_) => app.info(format!(
                "no stored recordings in {} to replay",
                dir.display()
            )),
            Err(e) => app.error(e.to_string()),
        },
        Action::OpenRecording(i) => open_recording(app, i),
        Action::OpenDataset(to) => {
            if let Some(l) = lab {
                l.set_dataset(&to);
            }
            app.on_dataset_opened(to.clone());
            refresh_dataset(app);
            dataset::adopt_saved_model(app, &to);
            let mut ex = FeatureExtractor::new(&app.profile.profile.analysis);
            if let Some(view) = scan::newest_unsaved(&to, &mut ex) {
                app.on_unsaved_found(view);
            }
        }
        Action::Curate(change) => {
            let (from, label) = match &change {
                curate::Change::Delete(f) | curate::Change::Exclude(f) => (f.clone(), None),
                curate::Change::Store { file, label } => (file.clone(), Some(label.clone())),
            };
            let r = curate::apply(&change, &dir).map(|done| {
                let out = (done.now.clone(), done.what.clone());
                app.curated.push(done);
                out
            });
            app.on_curated(&from, label.as_deref(), r);
            refresh_dataset(app);
            return follow_selection(app);
        }
        Action::UndoCurate => {
            match app.curated.pop() {
                None => app.info("nothing to undo"),
                Some(done) => match curate::undo(&done) {
                    Ok(what) => {
                        let back = done.moves_back.last().map(|(_, to)| to.clone());
                        app.dataset.edits += 1;
                        // The file put back carries its own label again.
                        let label = back
                            .as_deref()
                            .and_then(|b| crate::recording::read_columns(b, &[]).ok())
                            .and_then(|rec| rec.label().map(str::to_string));
                        if let Some(r) = app.replay.as_mut() {
                            r.moved(done.now.as_deref(), back.as_deref(), label.as_deref());
                        }
                        app.info(what);
                    }
                    Err(e) => app.error(format!("cannot undo: {e}")),
                },
            }
            refresh_dataset(app);
            return follow_selection(app);
        }
    }
    vec![]
}

/// After a change to the list, open the recording now selected.
fn follow_selection(app: &App) -> Vec<Action> {
    app.replay
        .as_ref()
        .filter(|r| !r.entries.is_empty())
        .map_or_else(Vec::new, |r| vec![Action::OpenRecording(r.selected)])
}

/// The lab for one call (`as_deref_mut` cannot shorten the trait object's lifetime).
fn reborrow<'a>(lab: &'a mut Option<&mut dyn LabPort>) -> Option<&'a mut dyn LabPort> {
    match lab {
        Some(l) => Some(&mut **l),
        None => None,
    }
}

fn send(lab: Option<&mut dyn LabPort>, c: Command) {
    if let Some(l) = lab {
        l.send(c);
    }
}
