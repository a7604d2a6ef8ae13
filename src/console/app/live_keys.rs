//! Keys on the live device, one handler per kind of work: moving the probe
//! (modes, the target, nudges, speed, stopping), measuring (start, store,
//! label, queue), and the rest (sessions, replay, predict).

use crate::acquire::HOMING_HELP;
use crate::profile::{WORKSPACE_MAX_M, WORKSPACE_MIN_M};
use crate::servo::Mode;

use super::super::form::{Form, FormKind, Overlay};
use super::super::keymap::Key;
use super::{Action, App, NUDGE_M, SPEED_STEPS, Source};

impl App {
    /// "a scan is running": keys that would disturb it say so instead.
    fn busy_scan(&mut self) -> Vec<Action> {
        let abort = self.key_name(Key::Abort);
        self.warn(format!(
            "a scan is running: wait for it, or {abort} then y aborts it"
        ));
        vec![]
    }

    pub(super) fn live_key(&mut self, k: Key) -> Vec<Action> {
        match k {
            Key::Quit => self.quit_key(),
            Key::Mode
            | Key::Target
            | Key::Abort
            | Key::Faster
            | Key::Slower
            | Key::Left
            | Key::Right
            | Key::Up
            | Key::Down
            | Key::Away
            | Key::Toward => self.motion_key(k),
            Key::Start | Key::Store | Key::Label | Key::Queue => self.measure_key(k),
            Key::Predict => self.predict_key(),
            Key::Replay if self.scan_running => self.busy_scan(),
            Key::Replay => vec![Action::OpenReplay],
            Key::Sessions if self.scan_busy() || self.scan_saving => self.busy_scan(),
            Key::Sessions => self.sessions_key(),
            Key::Pause | Key::Step => {
                self.info(format!(
                    "space and . control a replay; {} opens the replay browser",
                    self.key_name(Key::Replay)
                ));
                vec![]
            }
            Key::Delete | Key::Relabel | Key::Exclude | Key::Undo => {
                self.info(format!(
                    "curating is in the replay browser: {} opens it on the dataset",
                    self.key_name(Key::Replay)
                ));
                vec![]
            }
            _ => vec![],
        }
    }

    /// Moving the probe: the mode, the target, nudges, the path's speed, stop.
    fn motion_key(&mut self, k: Key) -> Vec<Action> {
        match k {
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
            _ if self.scan_running => self.busy_scan(),
            Key::Mode => self.mode_key(),
            Key::Target => {
                let m = self
                    .target_m
                    .or(self.live.latest.map(|t| t.pos_m))
                    .unwrap_or_else(|| self.home_m());
                let (lo, hi) = (
                    WORKSPACE_MIN_M.map(|v| v * 100.0),
                    WORKSPACE_MAX_M.map(|v| v * 100.0),
                );
                let hint = format!(
                    "workspace x {:.0}…{:.0}, y {:.0}…{:.0}, z {:.0}…{:.0} cm; Tab next field, Enter go, Esc cancel",
                    lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
                );
                self.overlay = Some(Overlay::Form(Form::target(
                    [m[0] * 100.0, m[1] * 100.0, m[2] * 100.0],
                    hint,
                )));
                vec![]
            }
            _ => self.nudge(k),
        }
    }

    fn mode_key(&mut self) -> Vec<Action> {
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

    /// Arrows and PgUp/PgDn: the target 1 mm along an axis.
    fn nudge(&mut self, k: Key) -> Vec<Action> {
        let (axis, sign) = match k {
            Key::Left => (0, -1.0),
            Key::Right => (0, 1.0),
            Key::Up => (1, 1.0),
            Key::Down => (1, -1.0),
            Key::Away => (2, -1.0),
            Key::Toward => (2, 1.0),
            _ => return vec![],
        };
        let mut t = self
            .target_m
            .or(self.live.latest.map(|t| t.pos_m))
            .unwrap_or_else(|| self.home_m());
        t[axis] = (t[axis] + sign * NUDGE_M).clamp(WORKSPACE_MIN_M[axis], WORKSPACE_MAX_M[axis]);
        self.target_m = Some(t);
        self.info(format!(
            "target ({:.2}, {:.2}, {:.2}) cm",
            t[0] * 100.0,
            t[1] * 100.0,
            t[2] * 100.0
        ));
        vec![Action::SetTarget(t)]
    }

    /// Measuring: start a scan, store one, the label, a queue of scans.
    fn measure_key(&mut self, k: Key) -> Vec<Action> {
        match k {
            Key::Store => self.store_key(),
            _ if self.scan_running => self.busy_scan(),
            Key::Start => {
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
            Key::Label => {
                let names: Vec<&str> = self
                    .profile
                    .profile
                    .textures
                    .iter()
                    .map(|t| t.label.as_str())
                    .collect();
                let hint = if matches!(&self.source, Source::Live { backend } if backend == "sim") {
                    format!(
                        "a texture's label ({}) also mounts it in the simulator",
                        names.join(", ")
                    )
                } else {
                    "any name without / or \\, not starting with .".into()
                };
                let form = Form::text(FormKind::Label, "label", &self.label, hint);
                self.overlay = Some(Overlay::Form(form));
                vec![]
            }
            _ => {
                let hint = format!(
                    "each scan of {} is stored as it completes; {} then y stops them",
                    self.label,
                    self.key_name(Key::Abort)
                );
                let form = Form::text(FormKind::Queue, "scans", "5", hint);
                self.overlay = Some(Overlay::Form(form));
                vec![]
            }
        }
    }

    /// `w`: the last scan into the dataset, under a label the form asks for.
    pub(super) fn store_key(&mut self) -> Vec<Action> {
        match &self.last_scan {
            None => self.info("no scan yet to store"),
            Some(s) if s.stored.is_some() => {
                let p = s.path.display().to_string();
                self.info(format!("the last scan is already stored as {p}"));
            }
            Some(scan) => {
                // An aborted scan is stored only when asked for, and says so.
                let hint = format!(
                    "{}saved as {}/<label>/<label>_NNN.csv; Enter store, Esc cancel",
                    if scan.complete {
                        ""
                    } else {
                        "INCOMPLETE (training skips it): "
                    },
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
}
