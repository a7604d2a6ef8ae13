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
mod tests;
mod world;

use std::path::PathBuf;

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use crate::acquire::HOMING_HELP;
use crate::classify::Model;
use crate::profile::{LoadedProfile, WORKSPACE_MAX_M, WORKSPACE_MIN_M, check_label};
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
    pub quit: bool,
}

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
            quit: false,
        }
    }

    /// Whether the device is homed (as far as the telemetry has told).
    pub fn homed(&self) -> bool {
        self.live.latest.as_ref().is_none_or(|t| t.homed)
    }

    pub fn info(&mut self, text: impl Into<String>) {
        self.status = Status {
            text: text.into(),
            level: Level::Info,
        };
    }
    pub fn warn(&mut self, text: impl Into<String>) {
        self.status = Status {
            text: text.into(),
            level: Level::Warn,
        };
    }
    pub fn error(&mut self, text: impl Into<String>) {
        self.status = Status {
            text: text.into(),
            level: Level::Error,
        };
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

    /// The texture the label names, when the simulator can mount it.
    fn texture_for(&self, label: &str) -> Option<String> {
        let sim = matches!(&self.source, Source::Live { backend } if backend == "sim");
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
            "training k-NN on the recordings in {}",
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

    fn live_key(&mut self, k: Key) -> Vec<Action> {
        let busy_scan = |app: &mut App| {
            let abort = app.key_name(Key::Abort);
            app.warn(format!(
                "a scan is running: wait for it, or {abort} then y aborts it"
            ));
            vec![]
        };
        match k {
            Key::Quit => self.quit_key(),
            Key::Mode => {
                if self.scan_running {
                    return busy_scan(self);
                }
                let next = match self.mode() {
                    Mode::Manual => Mode::Target,
                    Mode::Target => Mode::Test,
                    Mode::Test => Mode::Manual,
                };
                if next == Mode::Target {
                    self.target_m = self.live.latest.map(|t| t.pos_m);
                }
                self.info(match next {
                    Mode::Manual => "Manual mode: no forces, the probe moves by hand".to_string(),
                    Mode::Target => format!(
                        "Target mode: holding here; {} types a target, arrows and PgUp/PgDn nudge it",
                        self.key_name(Key::Target)
                    ),
                    Mode::Test => format!(
                        "Test mode: {} starts a measurement along the waypoint path",
                        self.key_name(Key::Start)
                    ),
                });
                vec![Action::SetMode(next)]
            }
            Key::Target => {
                if self.scan_running {
                    return busy_scan(self);
                }
                let m = self
                    .target_m
                    .or(self.live.latest.map(|t| t.pos_m))
                    .unwrap_or_else(|| self.home_m());
                let hint = format!(
                    "workspace x {:.0}…{:.0}, y {:.0}…{:.0}, z {:.0}…{:.0} cm; Tab next field, Enter go, Esc cancel",
                    WORKSPACE_MIN_M[0] * 100.0,
                    WORKSPACE_MAX_M[0] * 100.0,
                    WORKSPACE_MIN_M[1] * 100.0,
                    WORKSPACE_MAX_M[1] * 100.0,
                    WORKSPACE_MIN_M[2] * 100.0,
                    WORKSPACE_MAX_M[2] * 100.0
                );
                self.overlay = Some(Overlay::Form(Form::target(
                    [m[0] * 100.0, m[1] * 100.0, m[2] * 100.0],
                    hint,
                )));
                vec![]
            }
            Key::Start => {
                if self.scan_running {
                    return busy_scan(self);
                }
                if !self.homed() {
                    self.warn(HOMING_HELP);
                    return vec![];
                }
                self.scan_running = true;
                self.info(format!(
                    "measurement started: label {}{} — {} aborts",
                    self.label,
                    self.mounted
                        .as_ref()
                        .map_or(String::new(), |t| format!(", texture {t} mounted")),
                    self.key_name(Key::Abort)
                ));
                vec![Action::StartScan]
            }
            Key::Abort => {
                if self.scan_busy() {
                    // A reflex Esc must not cost a scan: ask first.
                    self.overlay = Some(Overlay::ConfirmAbort);
                    vec![]
                } else if self.mode() != Mode::Manual {
                    self.info("motion stopped: Manual mode, forces off");
                    vec![Action::Abort]
                } else {
                    self.info("nothing to abort");
                    vec![]
                }
            }
            Key::Store => {
                match &self.last_scan {
                    None => self.info("no scan yet to store"),
                    Some(s) if s.stored.is_some() => {
                        let p = s.path.display().to_string();
                        self.info(format!("the last scan is already stored as {p}"));
                    }
                    Some(scan) => {
                        let hint = format!(
                            "saved as {}/<label>/<label>_NNN.csv; Enter store, Esc cancel",
                            self.dataset.dir.display()
                        );
                        // The label it was recorded under (an earlier
                        // session's may differ from the current one).
                        let label = scan.label.clone().unwrap_or_else(|| self.label.clone());
                        self.overlay = Some(Overlay::Form(Form::text(
                            FormKind::Store,
                            "label",
                            &label,
                            hint,
                        )));
                    }
                }
                vec![]
            }
            Key::Label | Key::Queue => {
                if self.scan_running {
                    return busy_scan(self);
                }
                let form = if k == Key::Label {
                    let names: Vec<&str> = self
                        .profile
                        .profile
                        .textures
                        .iter()
                        .map(|t| t.label.as_str())
                        .collect();
                    let hint = if matches!(&self.source, Source::Live { backend } if backend == "sim")
                    {
                        format!(
                            "a texture's label ({}) also mounts it in the simulator",
                            names.join(", ")
                        )
                    } else {
                        "any name without / or \\, not starting with .".into()
                    };
                    Form::text(FormKind::Label, "label", &self.label, hint)
                } else {
                    let hint = format!(
                        "each scan of {} is stored as it completes; {} then y stops them",
                        self.label,
                        self.key_name(Key::Abort)
                    );
                    Form::text(FormKind::Queue, "scans", "5", hint)
                };
                self.overlay = Some(Overlay::Form(form));
                vec![]
            }
            Key::Predict => self.predict_key(),
            Key::Replay => {
                if self.scan_running {
                    return busy_scan(self);
                }
                vec![Action::OpenReplay]
            }
            Key::Faster | Key::Slower => {
                let i = SPEED_STEPS
                    .iter()
                    .position(|s| (*s - self.speed_scale).abs() < 1e-9)
                    .unwrap_or(3);
                let j = if k == Key::Faster {
                    (i + 1).min(SPEED_STEPS.len() - 1)
                } else {
                    i.saturating_sub(1)
                };
                self.speed_scale = SPEED_STEPS[j];
                self.info(format!("path speed ×{:.2}", self.speed_scale));
                vec![Action::SetSpeed(self.speed_scale)]
            }
            Key::Left | Key::Right | Key::Up | Key::Down | Key::Away | Key::Toward => {
                if self.scan_running {
                    return busy_scan(self);
                }
                let (axis, sign) = match k {
                    Key::Left => (0, -1.0),
                    Key::Right => (0, 1.0),
                    Key::Up => (1, 1.0),
                    Key::Down => (1, -1.0),
                    Key::Away => (2, -1.0),
                    _ => (2, 1.0),
                };
                let mut t = self
                    .target_m
                    .or(self.live.latest.map(|t| t.pos_m))
                    .unwrap_or_else(|| self.home_m());
                t[axis] =
                    (t[axis] + sign * NUDGE_M).clamp(WORKSPACE_MIN_M[axis], WORKSPACE_MAX_M[axis]);
                self.target_m = Some(t);
                self.info(format!(
                    "target ({:.2}, {:.2}, {:.2}) cm",
                    t[0] * 100.0,
                    t[1] * 100.0,
                    t[2] * 100.0
                ));
                vec![Action::SetTarget(t)]
            }
            Key::Pause | Key::Step => {
                self.info(format!(
                    "space and . control a replay; {} opens the replay browser",
                    self.key_name(Key::Replay)
                ));
                vec![]
            }
            _ => vec![],
        }
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

    fn replay_key(&mut self, k: Key) -> Vec<Action> {
        let standalone = self.source == Source::ReplayOnly;
        let Some(r) = self.replay.as_mut() else {
            return vec![];
        };
        match k {
            Key::Quit => return self.quit_key(),
            Key::Abort | Key::Replay => {
                if standalone {
                    let q = self.key_name(Key::Quit);
                    self.info(format!("{q} quits"));
                } else {
                    self.replay = None;
                    self.info("back to the live device");
                }
            }
            Key::Up | Key::Down => {
                let n = r.entries.len();
                if n == 0 {
                    return vec![];
                }
                let i = if k == Key::Up {
                    r.selected.saturating_sub(1)
                } else {
                    (r.selected + 1).min(n - 1)
                };
                if i != r.selected || r.player.is_none() {
                    r.selected = i;
                    return vec![Action::OpenRecording(i)];
                }
            }
            Key::Pause => {
                if let Some(p) = r.player.as_mut() {
                    if p.finished() {
                        p.restart(&mut self.replay_feed);
                        p.paused = false;
                    } else {
                        p.paused = !p.paused;
                    }
                }
            }
            Key::Step | Key::Right => {
                if let Some(p) = r.player.as_mut() {
                    p.step(&mut self.replay_feed);
                }
            }
            Key::Left | Key::Start => {
                if let Some(p) = r.player.as_mut() {
                    p.restart(&mut self.replay_feed);
                }
            }
            Key::Faster => {
                if let Some(p) = r.player.as_mut() {
                    p.faster();
                }
            }
            Key::Slower => {
                if let Some(p) = r.player.as_mut() {
                    p.slower();
                }
            }
            Key::Predict => return self.predict_key(),
            _ => {
                let back = self.key_name(Key::Abort);
                self.info(if standalone {
                    "replay: ↑/↓ recordings, space pause, +/- speed, . step".to_string()
                } else {
                    format!("replaying: {back} returns to the live device first")
                });
            }
        }
        vec![]
    }

    fn overlay_key(&mut self, overlay: Overlay, ev: &KeyEvent) -> Vec<Action> {
        match overlay {
            Overlay::Help => vec![],
            Overlay::ConfirmQuit => match ev.code {
                KeyCode::Char('y') | KeyCode::Char('Y') => {
                    self.quit = true;
                    vec![Action::Quit]
                }
                KeyCode::Char('w') if self.unsaved_scan() => {
                    self.overlay = None;
                    self.live_key(Key::Store)
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
                self.info(format!(
                    "Target mode: gliding to ({}, {}, {}) cm",
                    form.value(0),
                    form.value(1),
                    form.value(2)
                ));
                Ok(vec![Action::SetTarget(m)])
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
