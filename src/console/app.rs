//! The console's state, and how keys and the world change it.
//!
//! [`App`] owns everything the screen shows. Keys go through
//! [`App::handle_key`], which changes UI state (pages, forms, the replay
//! player) and returns [`Action`]s for the runtime to carry out (commands to
//! the servo, files to move, work to start); what comes back from the world
//! (telemetry, servo events, saved scans, finished jobs) arrives through the
//! `on_*` methods. Nothing here does I/O, talks to the servo or draws:
//! every transition can be tested as a plain function, and rendering
//! (`impl Widget for &App` in [`super::panels`]) only reads.

#[cfg(test)]
mod browse_tests;
mod live_keys;
mod replay_keys;
mod sessions;
#[cfg(test)]
mod tests;
mod world;

use std::path::PathBuf;

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use crate::acquire::HOMING_HELP;
use crate::classify::Model;
use crate::profile::{DeviceKind, LoadedProfile, WORKSPACE_MAX_M, WORKSPACE_MIN_M, check_label};
use crate::servo::Mode;

use super::dataset::DatasetView;
use super::estimate::Estimate;
use super::feed::Feed;
use super::form::{Form, FormKind, FormOutcome, Overlay};
use super::keymap::{Key, KeyMap};
use super::replay::Replay;
use super::scan::ScanView;

/// Target nudges, metres.
pub const NUDGE_M: f64 = 0.001;
/// The path speed factors `+`/`-` step through.
pub const SPEED_STEPS: [f64; 8] = [0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0];

/// What the runtime is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    Quit,
    SetMode(Mode),
    /// Glide to this position, metres (Target mode).
    SetTarget([f64; 3]),
    SetSpeed(f64),
    /// Run the waypoint path and record the scan leg under the current label.
    StartScan,
    Abort,
    /// Move the last scan into the dataset as `<label>/<label>_NNN.csv`.
    Store {
        label: String,
    },
    /// Restart the simulator with this texture under the probe.
    Mount(String),
    /// Classify the scan on screen (the last scan, or the replayed one).
    Predict,
    Train {
        then_predict: bool,
    },
    Evaluate,
    /// Open the replay browser on the dataset folder.
    OpenReplay,
    /// Open recording `i` of the replay list.
    OpenRecording(usize),
    /// Make this folder the session's dataset (a recent session, or a new one).
    OpenDataset(PathBuf),
    /// A change to the dataset's files (curating), carried out by the runtime.
    Curate(super::curate::Change),
    /// Put back the last change undone (the trash, the exclusion, the label).
    UndoCurate,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Info,
    Warn,
    Error,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Status {
    pub text: String,
    pub level: Level,
}

/// Which source the simulator is, or whether this is a replay-only console.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A live device: its backend name.
    Live { backend: String },
    /// `hapticlab replay`: no device at all.
    ReplayOnly,
}

pub struct App {
    pub profile: LoadedProfile,
    pub keys: KeyMap,
    pub source: Source,
    /// The simulator's texture, when the device is simulated.
    pub mounted: Option<String>,
    pub live: Feed,
    /// The goal of Target mode, metres.
    pub target_m: Option<[f64; 3]>,
    pub speed_scale: f64,
    /// The label of the next scans.
    pub label: String,
    /// Automatic scans still to start after the running one.
    pub queue_left: usize,
    /// The running scan belongs to an automatic run (stored when it completes).
    pub queued_run: bool,
    /// Scans asked for in the automatic run under way (0: none), and how
    /// many of them are stored so far: the run's end is announced.
    pub queue_total: usize,
    pub queue_stored: usize,
    /// A target typed in the form, until the probe gets there.
    pub gliding_to: Option<[f64; 3]>,
    /// The servo has been seen in Target mode since the glide was asked for.
    pub glide_seen: bool,
    /// A scan was requested and has not ended yet.
    pub scan_running: bool,
    /// A scan's motion ended and its file is not reported saved yet:
    /// quitting now asks too.
    pub scan_saving: bool,
    pub last_scan: Option<ScanView>,
    /// The live estimate of the scan running (or just ended, until its
    /// file comes back), when the model votes over sub-windows.
    pub estimate: Option<Estimate>,
    /// The last scan was left unstored by an earlier session: `w` stores
    /// it, but quitting does not ask about it again.
    pub last_scan_earlier: bool,
    pub dataset: DatasetView,
    pub model: Option<Model>,
    pub replay: Option<Replay>,
    pub replay_feed: Feed,
    pub overlay: Option<Overlay>,
    pub page: usize,
    /// The terminal's size, for the page count (set on resize).
    pub size: (u16, u16),
    pub status: Status,
    /// Every message the status line showed, oldest first (the log shows
    /// the newest first), up to [`LOG_LIMIT`].
    pub log: Vec<Status>,
    pub quit: bool,
    /// The quit dialog's `w`: quit once the scan is stored.
    pub quit_after_store: bool,
    /// Scans cut short this session (kept as incomplete), for the exit summary.
    pub interrupted: Vec<PathBuf>,
    /// Curating changes made, the last undone first.
    pub curated: Vec<super::curate::Done>,
}

/// Messages the log keeps.
pub const LOG_LIMIT: usize = 500;

impl App {
    /// Where the probe rests: the path's first waypoint (the workspace's
    /// centre for a profile without a path, which has no live mode).
    fn home_m(&self) -> [f64; 3] {
        self.profile
            .profile
            .path
            .as_ref()
            .map_or([0.0; 3], |p| p.waypoints_m[0])
    }

    pub fn new(profile: LoadedProfile, keys: KeyMap, source: Source, dataset: PathBuf) -> App {
        let label = profile
            .profile
            .textures
            .first()
            .map_or_else(|| "scan".to_string(), |t| t.label.clone());
        let status = Status {
            text: format!("dataset folder: {} — press ? for help", dataset.display()),
            level: Level::Info,
        };
        let log = vec![status.clone()];
        App {
            profile,
            keys,
            source,
            mounted: None,
            live: Feed::default(),
            target_m: None,
            speed_scale: 1.0,
            label,
            queue_left: 0,
            queued_run: false,
            queue_total: 0,
            queue_stored: 0,
            gliding_to: None,
            glide_seen: false,
            scan_running: false,
            scan_saving: false,
            last_scan: None,
            estimate: None,
            last_scan_earlier: false,
            dataset: DatasetView {
                dir: dataset,
                ..DatasetView::default()
            },
            model: None,
            replay: None,
            replay_feed: Feed::default(),
            overlay: None,
            page: 0,
            size: (80, 24),
            status,
            log,
            quit: false,
            quit_after_store: false,
            curated: Vec::new(),
            interrupted: Vec::new(),
        }
    }

    /// Whether the device is homed (as far as the telemetry has told).
    pub fn homed(&self) -> bool {
        self.live.latest.as_ref().is_none_or(|t| t.homed)
    }

    /// A message on the status line, kept in the log (once when repeated).
    fn say(&mut self, text: String, level: Level) {
        self.status = Status { text, level };
        if self.log.last() != Some(&self.status) {
            if self.log.len() >= LOG_LIMIT {
                self.log.remove(0);
            }
            self.log.push(self.status.clone());
        }
    }
    pub fn info(&mut self, text: impl Into<String>) {
        self.say(text.into(), Level::Info);
    }
    pub fn warn(&mut self, text: impl Into<String>) {
        self.say(text.into(), Level::Warn);
    }
    pub fn error(&mut self, text: impl Into<String>) {
        self.say(text.into(), Level::Error);
    }

    /// The feed the panels show: the replay's while one plays.
    pub fn feed(&self) -> &Feed {
        if self.replay.is_some() {
            &self.replay_feed
        } else {
            &self.live
        }
    }

    /// The live estimate the Prediction panel shows instead of the last
    /// scan's prediction (none while a replay is open).
    pub fn live_estimate(&self) -> Option<&Estimate> {
        self.estimate.as_ref().filter(|_| self.replay.is_none())
    }

    /// The scan the analysis panels show.
    pub fn scan(&self) -> Option<&ScanView> {
        match &self.replay {
            Some(r) => r.scan.as_ref(),
            None => self.last_scan.as_ref(),
        }
    }

    pub fn mode(&self) -> Mode {
        self.live.latest.map_or(Mode::Manual, |t| t.mode)
    }

    /// Whether quitting now would leave the last scan unstored.
    pub fn unsaved_scan(&self) -> bool {
        !self.last_scan_earlier
            && self
                .last_scan
                .as_ref()
                .is_some_and(|s| s.stored.is_none() && s.samples > 0)
    }

    /// Pages at the current size (see [`super::panels::pages`]).
    pub fn page_count(&self) -> usize {
        super::panels::pages(self.size.0, self.size.1).len()
    }

    pub fn resize(&mut self, w: u16, h: u16) {
        self.size = (w, h);
        self.page %= self.page_count();
    }

    fn key_name(&self, k: Key) -> String {
        self.keys.name(k)
    }

    /// The texture the label names, when the device is simulated (the
    /// simulator, or the emulated Falcon over its simulation) and can
    /// mount it; on a real Falcon the lab changes the texture by hand.
    fn texture_for(&self, label: &str) -> Option<String> {
        let sim = matches!(&self.source, Source::Live { backend }
            if backend == DeviceKind::Sim.name() || backend == DeviceKind::FalconEmulator.name());
        (sim && self.profile.profile.texture(label).is_some()).then(|| label.to_string())
    }

    /// A typed label as the profile spells it: `s2` is texture `S2`.
    fn profile_spelling(&self, label: &str) -> String {
        let textures = &self.profile.profile.textures;
        if textures.iter().any(|t| t.label == label) {
            return label.to_string();
        }
        textures
            .iter()
            .find(|t| t.label.eq_ignore_ascii_case(label))
            .map_or_else(|| label.to_string(), |t| t.label.clone())
    }

    /// A profile texture the label may have meant (one letter off, or a
    /// prefix), to suggest when it names none.
    fn suggest_texture(&self, label: &str) -> Option<&str> {
        let l = label.to_lowercase();
        self.profile
            .profile
            .textures
            .iter()
            .map(|t| t.label.as_str())
            .find(|t| {
                let t = t.to_lowercase();
                t.starts_with(&l) || l.starts_with(&t) || one_edit_apart(&t, &l)
            })
    }

    /// A key press: state changes here, effects returned as actions.
    pub fn handle_key(&mut self, ev: KeyEvent) -> Vec<Action> {
        if ev.modifiers.contains(KeyModifiers::CONTROL) && ev.code == KeyCode::Char('c') {
            self.quit = true;
            return vec![Action::Quit];
        }
        if let Some(overlay) = self.overlay.take() {
            return self.overlay_key(overlay, &ev);
        }
        let Some(k) = self.keys.lookup(&ev) else {
            return vec![];
        };
        match k {
            Key::Help => {
                self.overlay = Some(Overlay::Help);
                return vec![];
            }
            Key::Messages => {
                self.overlay = Some(Overlay::Messages { scroll: 0 });
                return vec![];
            }
            Key::NextPage => {
                self.page = (self.page + 1) % self.page_count();
                return vec![];
            }
            Key::PrevPage => {
                let n = self.page_count();
                self.page = (self.page + n - 1) % n;
                return vec![];
            }
            Key::Page(p) => {
                let n = self.page_count();
                if usize::from(p) <= n {
                    self.page = usize::from(p) - 1;
                } else {
                    self.info(format!("the terminal is large enough for {n} page(s)"));
                }
                return vec![];
            }
            Key::Train => return self.train(false),
            Key::Evaluate => {
                self.dataset.busy = Some("evaluating…".into());
                self.info(format!(
                    "evaluating {} by {} (the profile's [evaluation])",
                    self.dataset.dir.display(),
                    crate::evaluate::plan::Plan::new(&self.profile.profile, &Default::default())
                        .describe()
                ));
                return vec![Action::Evaluate];
            }
            _ => {}
        }
        if self.replay.is_some() {
            return self.replay_key(k);
        }
        self.live_key(k)
    }

    fn train(&mut self, then_predict: bool) -> Vec<Action> {
        if self.dataset.busy.is_some() {
            self.warn("busy: wait for the work in progress to finish");
            return vec![];
        }
        self.dataset.busy = Some("training…".into());
        self.info(format!(
            "training {} on the recordings in {}",
            self.profile.profile.classifier.method.name(),
            self.dataset.dir.display()
        ));
        vec![Action::Train { then_predict }]
    }

    /// Whether a scan is running or queued: quitting or aborting now would
    /// cut it short.
    pub fn scan_busy(&self) -> bool {
        self.scan_running || self.queue_left > 0
    }

    fn quit_key(&mut self) -> Vec<Action> {
        let unsaved = self.unsaved_scan()
            && self
                .replay
                .as_ref()
                .is_none_or(|_| self.source != Source::ReplayOnly);
        if unsaved || self.scan_busy() || self.scan_saving {
            self.overlay = Some(Overlay::ConfirmQuit);
            return vec![];
        }
        self.quit = true;
        vec![Action::Quit]
    }

    /// Abort the running scan and the rest of its queue, now.
    fn abort_scan(&mut self) -> Vec<Action> {
        let queued = self.queue_left;
        self.queue_left = 0;
        self.queued_run = false;
        self.warn(if queued > 0 {
            format!(
                "aborting: forces off, the samples so far are kept (incomplete); {queued} queued scan(s) cancelled"
            )
        } else {
            "aborting: forces off, the samples so far are kept (incomplete)".to_string()
        });
        vec![Action::Abort]
    }

    fn predict_key(&mut self) -> Vec<Action> {
        let Some(scan) = self.scan() else {
            self.info(format!(
                "no scan to predict yet: {} starts a measurement",
                self.key_name(Key::Start)
            ));
            return vec![];
        };
        if let Err(e) = &scan.features {
            let e = e.clone();
            self.warn(format!("this scan has no features: {e}"));
            return vec![];
        }
        if self.model.is_none() {
            return self.train(true);
        }
        vec![Action::Predict]
    }

    fn overlay_key(&mut self, overlay: Overlay, ev: &KeyEvent) -> Vec<Action> {
        match overlay {
            Overlay::Help => vec![],
            Overlay::Messages { scroll } => {
                let last = self.log.len().saturating_sub(1);
                let scroll = match ev.code {
                    KeyCode::Down | KeyCode::Char('j') => (scroll + 1).min(last),
                    KeyCode::Up | KeyCode::Char('k') => scroll.saturating_sub(1),
                    KeyCode::PageDown => (scroll + 10).min(last),
                    KeyCode::PageUp => scroll.saturating_sub(10),
                    KeyCode::Home => 0,
                    KeyCode::End => last,
                    _ => return vec![],
                };
                self.overlay = Some(Overlay::Messages { scroll });
                vec![]
            }
            Overlay::Sessions(list) => self.sessions_pick(list, ev),
            Overlay::ConfirmQuit => match ev.code {
                KeyCode::Char('y') | KeyCode::Char('Y') => {
                    self.quit = true;
                    vec![Action::Quit]
                }
                KeyCode::Char('w') if self.unsaved_scan() => {
                    // Stores, then quits (see `on_stored`).
                    self.quit_after_store = true;
                    self.store_key()
                }
                _ => {
                    self.info(if self.scan_busy() {
                        "not quitting: the scan goes on"
                    } else {
                        "not quitting"
                    });
                    vec![]
                }
            },
            Overlay::ConfirmAbort => match ev.code {
                KeyCode::Char('y') | KeyCode::Char('Y') if self.scan_busy() => self.abort_scan(),
                KeyCode::Char('y') | KeyCode::Char('Y') => {
                    self.info("the scan had already ended: nothing to abort");
                    vec![]
                }
                _ => {
                    self.info("not aborted: the scan goes on");
                    vec![]
                }
            },
            Overlay::Form(mut form) => match form.key(ev) {
                FormOutcome::Editing => {
                    self.overlay = Some(Overlay::Form(form));
                    vec![]
                }
                FormOutcome::Cancel => {
                    self.quit_after_store = false;
                    self.info("cancelled");
                    vec![]
                }
                FormOutcome::Submit => match self.submit(&form) {
                    Ok(actions) => actions,
                    Err(e) => {
                        form.error = Some(e);
                        self.overlay = Some(Overlay::Form(form));
                        vec![]
                    }
                },
            },
        }
    }

    /// A submitted form: its actions, or what is wrong with it.
    fn submit(&mut self, form: &Form) -> Result<Vec<Action>, String> {
        match form.kind {
            FormKind::Target => {
                let mut m = [0.0; 3];
                for (a, v) in m.iter_mut().enumerate() {
                    let name = ["x", "y", "z"][a];
                    let cm: f64 = form
                        .value(a)
                        .parse()
                        .map_err(|_| format!("{name}: {:?} is not a number", form.value(a)))?;
                    let (lo, hi) = (WORKSPACE_MIN_M[a] * 100.0, WORKSPACE_MAX_M[a] * 100.0);
                    if !(cm.is_finite() && (lo..=hi).contains(&cm)) {
                        return Err(format!(
                            "{name} = {cm} cm is outside the workspace: {lo:.0} to {hi:.0} cm"
                        ));
                    }
                    *v = cm / 100.0;
                }
                self.target_m = Some(m);
                self.gliding_to = Some(m);
                self.glide_seen = false;
                self.info(format!(
                    "Target mode: gliding to ({}, {}, {}) cm",
                    form.value(0),
                    form.value(1),
                    form.value(2)
                ));
                Ok(vec![Action::SetTarget(m)])
            }
            FormKind::Jump | FormKind::Filter => self.jump_or_filter(form.kind, form.value(0)),
            FormKind::StoreAs => {
                let label = self.profile_spelling(form.value(0));
                check_label(&label)?;
                let Some(file) = self
                    .replay
                    .as_ref()
                    .and_then(|r| r.selected_path().cloned())
                else {
                    return Ok(vec![]);
                };
                Ok(vec![Action::Curate(super::curate::Change::Store {
                    file,
                    label,
                })])
            }
            FormKind::Store => {
                let label = self.profile_spelling(form.value(0));
                check_label(&label)?;
                self.label = label.clone();
                Ok(vec![Action::Store { label }])
            }
            FormKind::Label => {
                let typed = form.value(0);
                let label = self.profile_spelling(typed);
                check_label(&label)?;
                let spelt = if label == typed {
                    String::new()
                } else {
                    format!(" (as the profile spells {typed})")
                };
                self.label = label.clone();
                match self.texture_for(&label) {
                    Some(t) if self.mounted.as_deref() != Some(t.as_str()) => {
                        self.info(format!(
                            "label {label}{spelt}: mounting texture {t} in the simulator"
                        ));
                        Ok(vec![Action::Mount(t)])
                    }
                    Some(_) => {
                        self.info(format!(
                            "label {label}{spelt}: its texture is already mounted"
                        ));
                        Ok(vec![])
                    }
                    None => {
                        let known = self.profile.profile.texture(&label).is_some();
                        let hint = match self.suggest_texture(&label) {
                            Some(t) if !known => format!("; did you mean {t}?"),
                            _ => String::new(),
                        };
                        let why = match &self.mounted {
                            Some(m) if !known => {
                                format!(" (not a profile texture: {m} stays mounted{hint})")
                            }
                            _ if !known && !hint.is_empty() => {
                                format!(" (not a profile texture{hint})")
                            }
                            _ => spelt,
                        };
                        self.info(format!("label {label}{why}"));
                        Ok(vec![])
                    }
                }
            }
            FormKind::Queue => {
                let n: usize = form
                    .value(0)
                    .parse()
                    .ok()
                    .filter(|n| (1..=500).contains(n))
                    .ok_or_else(|| "give a number of scans from 1 to 500".to_string())?;
                if !self.homed() {
                    return Err(HOMING_HELP.to_string());
                }
                self.queue_left = n - 1;
                self.queued_run = true;
                self.queue_total = n;
                self.queue_stored = 0;
                self.scan_running = true;
                self.info(format!(
                    "{n} automatic scans of {}: each is stored as it completes",
                    self.label
                ));
                Ok(vec![Action::StartScan])
            }
        }
    }
}

/// Whether two words differ by one letter changed, added or removed.
fn one_edit_apart(a: &str, b: &str) -> bool {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let (short, long) = if a.len() <= b.len() {
        (&a, &b)
    } else {
        (&b, &a)
    };
    if short.len() < 2 {
        // "S5" is not a typo of "S1".
        return false;
    }
    match long.len() - short.len() {
        0 => short.len() > 2 && a.iter().zip(&b).filter(|(x, y)| x != y).count() == 1,
        1 => (0..long.len()).any(|i| long[..i] == short[..i] && long[i + 1..] == short[i..]),
        _ => false,
    }
}
