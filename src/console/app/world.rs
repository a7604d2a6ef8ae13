//! How the world changes the app: telemetry, servo events, saved and
//! stored scans, finished jobs, and the replay clock. Like the key
//! handlers, these only change state and return actions.

use std::path::PathBuf;

use crate::acquire::HOMING_HELP;
use crate::classify::plural;
use crate::servo::{Mode, ServoEvent, Telemetry};

use super::super::dataset::{Evaluated, JobResult, ModelInfo};
use super::super::estimate::Estimate;
use super::super::keymap::Key;
use super::super::scan::{ScanView, predict_view};
use super::{Action, App};

/// How near the typed target the glide's set-point must be to have
/// arrived, per axis.
const ARRIVED_M: f64 = 0.00001;

impl App {
    /// One telemetry frame from the servo.
    pub fn on_telemetry(&mut self, t: &Telemetry) {
        match (self.live.latest.as_ref().map(|l| l.homed), t.homed) {
            (None, false) => self.warn(HOMING_HELP),
            (Some(false), true) => self.info("homed: the LEDs are blue; forces are on"),
            _ => {}
        }
        self.live.push(t);
        self.gather(t);
        self.speed_scale = t.speed_scale;
        if let Some(g) = self.gliding_to {
            self.follow_glide(g, t);
        }
    }

    /// Target mode: say when the glide to the typed target is over, and
    /// where the probe is. Frames sent before the servo took the target
    /// (still in the old mode) do not end the glide.
    fn follow_glide(&mut self, g: [f64; 3], t: &Telemetry) {
        if t.mode == Mode::Target {
            self.glide_seen = true;
        } else {
            if self.glide_seen {
                self.gliding_to = None;
            }
            return;
        }
        if !(0..3).all(|a| (t.setpoint_m[a] - g[a]).abs() < ARRIVED_M) {
            return;
        }
        // The glide is over; the probe may rest a little off the
        // target (its weight, a texture under it): say how far.
        self.gliding_to = None;
        let off = (0..3)
            .map(|a| (t.pos_m[a] - g[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        let p = t.pos_m.map(|v| v * 100.0);
        self.info(format!(
            "the probe is at ({:.2}, {:.2}, {:.2}) cm: holding at the target ({:.2}, {:.2}, {:.2}) cm, {:.1} mm from it",
            p[0],
            p[1],
            p[2],
            g[0] * 100.0,
            g[1] * 100.0,
            g[2] * 100.0,
            off * 1000.0
        ));
    }

    /// A scan's sample for the live estimate: the first of a scan starts
    /// one when the model votes over sub-windows; the first frame after
    /// the scan ends it.
    fn gather(&mut self, t: &Telemetry) {
        let running = self.estimate.as_ref().is_some_and(|e| e.running);
        match (t.scanning, running) {
            (true, true) => {
                if let Some(e) = self.estimate.as_mut() {
                    e.push(t);
                }
            }
            (true, false) => {
                self.estimate = self
                    .model
                    .as_ref()
                    .filter(|m| m.analysis.windows.is_some())
                    .map(|m| Estimate::start(m, t));
            }
            (false, true) => {
                if let Some(e) = self.estimate.as_mut() {
                    e.running = false;
                }
            }
            (false, false) => {}
        }
    }

    /// Once a frame, after the telemetry: the live estimate classifies the
    /// sub-windows completed since the last frame.
    pub fn update_estimate(&mut self) {
        if let Some(e) = self.estimate.as_mut() {
            e.update();
        }
    }

    pub fn on_servo_event(&mut self, e: ServoEvent) {
        match e {
            ServoEvent::ScanStarted { path } => {
                self.info(format!(
                    "on the texture: recording the stroke to {}",
                    path.display()
                ));
            }
            ServoEvent::ScanEnded {
                aborted,
                samples,
                path,
                ..
            } => {
                if aborted.is_some() && samples > 0 && !self.interrupted.contains(&path) {
                    self.interrupted.push(path);
                }
                self.scan_running = false;
                // The recorder reports the file next (none without samples).
                self.scan_saving = samples > 0;
                if samples == 0 {
                    self.estimate = None;
                }
                match aborted {
                    None => self.info(format!("scan complete: {samples} samples; analysing")),
                    Some(r) => {
                        self.queue_left = 0;
                        self.queued_run = false;
                        let queue = self.end_queue();
                        self.warn(format!(
                            "scan aborted ({r}): {samples} samples kept, incomplete{queue}"
                        ));
                    }
                }
            }
            ServoEvent::MotionStopped { reason } => {
                self.scan_running = false;
                self.queue_left = 0;
                self.queued_run = false;
                let queue = self.end_queue();
                self.warn(format!("motion stopped: {reason}{queue}"));
            }
            ServoEvent::Notice { message } => self.warn(message),
        }
    }

    /// A scan an earlier session left unstored in `.unsaved/` (already
    /// counted there): shown as the last scan, so `w` stores it.
    pub fn on_unsaved_found(&mut self, view: ScanView) {
        if self.last_scan.is_some() {
            return;
        }
        self.info(format!(
            "an earlier session left a scan unstored: {} stores it ({})",
            self.key_name(Key::Store),
            view.path.display()
        ));
        self.last_scan = Some(view);
        self.last_scan_earlier = true;
    }

    /// A scan the recorder finished writing, analysed.
    pub fn on_scan_saved(&mut self, mut view: ScanView) -> Vec<Action> {
        self.scan_running = false;
        self.scan_saving = false;
        self.last_scan_earlier = false;
        self.dataset.unsaved += 1;
        let complete = view.complete;
        let mut analysed = match &view.features {
            Ok(_) => String::new(),
            Err(e) => format!(" — no features: {e}"),
        };
        // A scan followed live ends with the stored recording's prediction,
        // made as `p` (and `classify`) make it, not with the live vote.
        if self.estimate.take().is_some()
            && complete
            && let Some(m) = &self.model
            && let Some(p) = predict_view(m, &view)
        {
            analysed = match &p {
                Ok(pv) => match &pv.windows {
                    Some(w) => format!(
                        ", predicted {} ({} of {} windows)",
                        w.label,
                        w.tally.first().map_or(0, |t| t.windows),
                        w.windows.len()
                    ),
                    None => format!(", predicted {}", pv.prediction.label),
                },
                Err(e) => format!(" — no prediction: {e}"),
            };
            view.prediction = Some(p);
        }
        let predicted = view.prediction.is_some();
        self.last_scan = Some(view);
        if !complete {
            self.queue_left = 0;
            self.queued_run = false;
            self.queue_total = 0;
            self.queue_stored = 0;
            return vec![];
        }
        if !self.queued_run {
            let predicts = if predicted {
                String::new()
            } else {
                format!("{} predicts, ", self.key_name(Key::Predict))
            };
            self.info(format!(
                "scan complete{analysed}: {predicts}{} stores it",
                self.key_name(Key::Store)
            ));
            return vec![];
        }
        let mut actions = vec![Action::Store {
            label: self.label.clone(),
        }];
        if self.queue_left > 0 {
            self.queue_left -= 1;
            self.scan_running = true;
            actions.push(Action::StartScan);
        } else {
            self.queued_run = false;
        }
        actions
    }

    /// The last scan was stored (or could not be).
    pub fn on_stored(&mut self, result: Result<PathBuf, String>) {
        if std::mem::take(&mut self.quit_after_store) && result.is_ok() {
            self.quit = true;
        }
        match result {
            Ok(path) => {
                let left = if self.queued_run || self.queue_left > 0 {
                    format!("; {} more to go", self.queue_left + 1)
                } else {
                    String::new()
                };
                let complete = self.last_scan.as_ref().is_none_or(|s| s.complete);
                if let Some(s) = self.last_scan.as_mut() {
                    s.path = path.clone();
                    s.stored = Some(path.clone());
                }
                self.dataset.unsaved = self.dataset.unsaved.saturating_sub(1);
                let note = if complete {
                    ""
                } else {
                    " (incomplete: training skips it)"
                };
                if self.queue_total > 0 {
                    self.queue_stored += 1;
                }
                if self.queued_run && self.scan_running {
                    self.info(format!("stored {}{note}{left}", path.display()));
                } else if self.queue_total > 0 {
                    // The last scan of an automatic run.
                    let (n, total) = (self.queue_stored, self.queue_total);
                    self.queue_total = 0;
                    self.queue_stored = 0;
                    self.info(format!(
                        "automatic scans done: {n} of {total} stored (the last as {}){note}",
                        path.display()
                    ));
                } else {
                    self.info(format!("stored {}{note}", path.display()));
                }
            }
            Err(e) => {
                self.queue_left = 0;
                self.queued_run = false;
                let queue = self.end_queue();
                self.error(format!("could not store the scan: {e}{queue}"));
            }
        }
    }

    /// Ends an automatic run cut short; what to add to the message.
    fn end_queue(&mut self) -> String {
        if self.queue_total == 0 {
            return String::new();
        }
        let (n, total) = (self.queue_stored, self.queue_total);
        self.queue_total = 0;
        self.queue_stored = 0;
        format!("; automatic scans stopped: {n} of {total} stored")
    }

    /// A finished job; may ask for more (a prediction after training).
    pub fn on_job(&mut self, r: JobResult) -> Vec<Action> {
        self.dataset.busy = None;
        match r {
            JobResult::Trained {
                model,
                skipped,
                saved,
                then_predict,
            } => {
                let file = saved.as_ref().ok().cloned();
                let mut info = ModelInfo::of(&model, file);
                info.skipped = skipped;
                self.dataset.model = Some(info);
                self.dataset.model_note = None;
                self.dataset.edits = 0;
                let skipped = if skipped > 0 {
                    format!(", {skipped} incomplete skipped")
                } else {
                    String::new()
                };
                let text = format!(
                    "trained {} on {} of {}{skipped}",
                    model.classifier_name(),
                    plural(model.examples.len(), "recording", "recordings"),
                    model.labels.join(", ")
                );
                // Why k is not the profile's comes first: it must be seen.
                match (saved, model.k_notice()) {
                    (Ok(p), None) => self.info(format!("{text}; saved {}", p.display())),
                    (Ok(p), Some(n)) => self.warn(format!("{n}; {text}; saved {}", p.display())),
                    (Err(e), n) => self.warn(format!(
                        "{}{text}; not saved: {e}",
                        n.map_or(String::new(), |n| format!("{n}; "))
                    )),
                }
                self.model = Some(*model);
                if then_predict {
                    return vec![Action::Predict];
                }
                vec![]
            }
            JobResult::Evaluated(e) => {
                let Evaluated {
                    report,
                    method,
                    note,
                    saved,
                } = *e;
                // The result first: a narrow status line cuts the end.
                let mut text = format!(
                    "evaluated: {}/{} right ({:.1} %) by {method}",
                    report.correct(),
                    report.tested(),
                    report.accuracy * 100.0
                );
                if !note.is_empty() {
                    text.push_str(&format!("; {note}"));
                }
                match &saved {
                    Ok(file) => text.push_str(&format!("; report in {}", file.display())),
                    Err(e) => text.push_str(&format!("; report not saved: {e}")),
                }
                if note.is_empty() && saved.is_ok() {
                    self.info(text);
                } else {
                    self.warn(text);
                }
                self.dataset.report = Some(report);
                self.dataset.report_method = Some(method);
                self.dataset.report_file = saved.ok();
                vec![]
            }
            JobResult::Listed {
                entries,
                model,
                skipped,
            } => {
                if let Some(m) = model
                    && self.model.is_none()
                {
                    let mut info = ModelInfo::of(&m, None);
                    info.skipped = skipped;
                    self.dataset.model = Some(info);
                    // The recording already open was analysed before there was a model.
                    if let Some(s) = self.replay.as_mut().and_then(|r| r.scan.as_mut())
                        && s.prediction.is_none()
                    {
                        s.prediction = predict_view(&m, s);
                    }
                    self.model = Some(*m);
                }
                if let Some(r) = self.replay.as_mut() {
                    for e in entries {
                        if let Some(slot) = r.entries.iter_mut().find(|s| s.path == e.path) {
                            *slot = e;
                        }
                    }
                    r.listing = false;
                    let (right, n) = r.score();
                    if n > 0 {
                        let text = format!(
                            "replay: {right} of {} predicted right",
                            plural(n, "recording", "recordings")
                        );
                        match self.model.as_ref().and_then(|m| m.k_notice()) {
                            Some(note) => self.warn(format!("{note}; {text}")),
                            None => self.info(text),
                        }
                    }
                }
                vec![]
            }
            JobResult::Failed { what, error } => {
                // A new session has nothing stored to train on yet.
                let hint = if what == "train" && error.starts_with("no recordings") {
                    format!(
                        ": store scans of each texture first ({} stores a scan under the label, {} changes the label)",
                        self.key_name(Key::Store),
                        self.key_name(Key::Label)
                    )
                } else {
                    String::new()
                };
                self.error(format!("could not {what}: {error}{hint}"));
                vec![]
            }
        }
    }

    /// Advance the replay by a frame's wall time.
    pub fn advance(&mut self, wall_s: f64) {
        if let Some(p) = self.replay.as_mut().and_then(|r| r.player.as_mut()) {
            p.advance(wall_s, &mut self.replay_feed);
        }
    }
}
