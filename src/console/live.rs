//! The live device behind the console: the servo loop on its own thread,
//! the simulated Falcon with its mounted texture, and the files scans go to.
//!
//! [`Lab::drain`] is called once per frame: it empties the telemetry and
//! event channels with `try_iter` (never waiting on the servo thread) and
//! hands each finished recording, analysed, to the app. Scans are recorded
//! to `<dataset>/.unsaved/` while they run, so an interrupted scan leaves
//! its samples; [`Lab::store`] moves one to `<dataset>/<label>/`.

use std::path::{Path, PathBuf};

use crate::acquire::{
    AcquireError, next_free_index, open_device, scan_file, scan_metadata, scan_seed,
};
use crate::analysis::FeatureExtractor;
use crate::profile::{DeviceKind, LoadedProfile};
use crate::recorder::{COLUMNS, SavedScan};
use crate::recording::{self, RecordingWriter};
use crate::servo::{self, Command, ServoHandle};

use super::app::{Action, App};
use super::dataset::UNSAVED_DIR;
use super::scan;

/// What the console's loop asks of the lab: the world drained into the app
/// once a frame, commands to the servo, scans, textures. [`Lab`] is the live
/// one (the servo on the profile's device); the loop takes any, so whole
/// sessions run in tests.
pub trait LabPort {
    /// Once per frame: telemetry, events and saved scans into the app (and
    /// the heartbeat that keeps the servo's watchdog quiet); the actions a
    /// saved scan leads to.
    fn drain(&mut self, app: &mut App) -> Vec<Action>;
    fn send(&self, c: Command);
    /// Run the path, recording the scan leg under `label`; the file it goes to.
    fn start_scan(&mut self, label: &str) -> PathBuf;
    /// Put another texture under the probe (a simulated device only).
    fn mount(&mut self, texture: &str, app: &mut App) -> Result<(), String>;
    /// The texture under the probe, when the device is simulated.
    fn texture(&self) -> Option<String>;
    /// Record the next scans into another dataset folder (a session opened).
    fn set_dataset(&mut self, dir: &Path);
}

impl LabPort for Lab {
    fn drain(&mut self, app: &mut App) -> Vec<Action> {
        Lab::drain(self, app)
    }
    fn send(&self, c: Command) {
        Lab::send(self, c);
    }
    fn start_scan(&mut self, label: &str) -> PathBuf {
        Lab::start_scan(self, label)
    }
    fn mount(&mut self, texture: &str, app: &mut App) -> Result<(), String> {
        Lab::mount(self, texture, app)
    }
    fn texture(&self) -> Option<String> {
        self.texture.clone()
    }
    fn set_dataset(&mut self, dir: &Path) {
        self.dataset = dir.to_path_buf();
    }
}

pub struct Lab {
    lp: LoadedProfile,
    handle: Option<ServoHandle>,
    pub dataset: PathBuf,
    /// The simulator's texture (none on a real Falcon: its texture is
    /// whatever the lab put under the probe).
    pub texture: Option<String>,
    mounts: usize,
    extractor: FeatureExtractor,
    /// What opening the device said (firmware, homing), for the message line.
    notes: Vec<String>,
    /// Why the motion last stopped, for when the loop itself ends.
    last_stop: Option<String>,
}

impl Lab {
    /// Start the servo on the profile's device, `texture` under the probe
    /// (simulated devices only).
    pub fn start(
        lp: &LoadedProfile,
        dataset: &Path,
        texture: Option<&str>,
    ) -> Result<Lab, AcquireError> {
        let simulated = lp.rig()?.device.kind != DeviceKind::Falcon;
        let mut lab = Lab {
            lp: lp.clone(),
            handle: None,
            dataset: dataset.to_path_buf(),
            texture: texture.filter(|_| simulated).map(str::to_string),
            mounts: 0,
            extractor: FeatureExtractor::new(&lp.profile.analysis),
            notes: Vec::new(),
            last_stop: None,
        };
        lab.spawn()?;
        Ok(lab)
    }

    pub fn backend(&self) -> &'static str {
        self.lp
            .profile
            .device
            .as_ref()
            .map_or("none", |d| d.kind.name())
    }

    fn spawn(&mut self) -> Result<(), AcquireError> {
        let p = &self.lp.profile;
        let rig = self.lp.rig()?;
        let seed = scan_seed(
            p.simulator.seed,
            self.texture.as_deref().unwrap_or(""),
            self.mounts,
        );
        let notes = &mut self.notes;
        let device = open_device(&self.lp, self.texture.as_deref(), seed, &mut |m| {
            notes.push(m.to_string())
        })?;
        self.mounts += 1;
        self.last_stop = None;
        let handle = servo::spawn(rig, move || device)
            .map_err(|e| AcquireError::Runtime(format!("cannot start the servo thread: {e}")))?;
        self.handle = Some(handle);
        Ok(())
    }

    /// Restart the simulator with another texture (only while idle): the
    /// old loop is shut down, its device made safe.
    pub fn mount(&mut self, texture: &str, app: &mut App) -> Result<(), String> {
        if self.lp.profile.device.as_ref().map(|d| d.kind) == Some(DeviceKind::Falcon) {
            // The lab changes a real texture by hand; the Falcon stays homed.
            return Ok(());
        }
        if let Some(h) = self.handle.take() {
            let (_, saved) = h.shutdown();
            for s in saved {
                self.deliver(s, app);
            }
        }
        self.texture = Some(texture.to_string());
        self.spawn().map_err(|e| e.to_string())
    }

    pub fn send(&self, c: Command) {
        if let Some(h) = &self.handle {
            h.send(c);
        }
    }

    /// Run the path, recording to the next free `.unsaved/scan-NNN.csv`.
    pub fn start_scan(&mut self, label: &str) -> PathBuf {
        let dir = self.dataset.join(UNSAVED_DIR);
        let path = unsaved_path(&dir);
        let mut extra = vec![
            ("clock", toml::Value::String("real".into())),
            (
                "session",
                toml::Value::String(self.dataset.display().to_string()),
            ),
        ];
        if let Some(t) = &self.texture {
            extra.push(("texture", toml::Value::String(t.clone())));
        }
        let meta = scan_metadata(&self.lp, label, self.backend(), &extra);
        self.send(Command::StartScan {
            path: path.clone(),
            meta,
        });
        path
    }

    /// Once per frame: telemetry, events and saved scans into the app.
    pub fn drain(&mut self, app: &mut App) -> Vec<Action> {
        for n in self.notes.drain(..) {
            app.info(n);
        }
        let Some(h) = &self.handle else {
            return vec![];
        };
        // The console is alive: without this the servo's watchdog stops the
        // motion after servo::WATCHDOG_S (a loop stuck on a dead terminal).
        h.heartbeat();
        // Whether the loop had ended before its last events are drained, so
        // none sent before the end is missed.
        let finished = h.is_finished();
        for t in h.telemetry.try_iter() {
            app.on_telemetry(&t);
        }
        // The live estimate: only the sub-windows completed this frame.
        app.update_estimate();
        for e in h.events.try_iter() {
            if let servo::ServoEvent::MotionStopped { reason } = &e {
                self.last_stop = Some(reason.clone());
            }
            app.on_servo_event(e);
        }
        let saved = h.saved();
        let mut actions = Vec::new();
        for s in saved {
            actions.extend(self.deliver(s, app));
        }
        if finished {
            // Wait for the recorder to finish the last scan, and show it.
            if let Some(h) = self.handle.take() {
                for s in h.shutdown().1 {
                    actions.extend(self.deliver(s, app));
                }
            }
            // The reason stays on screen: a device fault ends the loop.
            let why = self
                .last_stop
                .as_deref()
                .map(|r| format!(" ({r})"))
                .unwrap_or_default();
            app.error(format!(
                "the servo loop stopped{why}; the device is safe (forces off), any scan kept as incomplete. Quit with q"
            ));
        }
        actions
    }

    fn deliver(&mut self, s: SavedScan, app: &mut App) -> Vec<Action> {
        if let Some(e) = &s.error {
            app.error(format!("{}: {e}", s.path.display()));
            return vec![];
        }
        match recording::read(&s.path) {
            Ok(rec) => {
                let view = scan::analyse(&rec, &s.path, &mut self.extractor);
                app.on_scan_saved(view)
            }
            Err(e) => {
                app.error(format!("cannot read the scan back: {e}"));
                vec![]
            }
        }
    }

    /// Stop the loop: forces zero, any scan kept as aborted for `reason`;
    /// the scans still being written.
    pub fn shutdown(mut self, reason: &str) -> Vec<SavedScan> {
        self.handle
            .take()
            .map(|h| {
                h.send(Command::Stop(reason.to_string()));
                h.shutdown().1
            })
            .unwrap_or_default()
    }
}

/// The first `scan-NNN.csv` free in `dir`.
fn unsaved_path(dir: &Path) -> PathBuf {
    (1..)
        .map(|i| dir.join(format!("scan-{i:03}.csv")))
        .find(|p| !p.exists())
        .expect("an unbounded range has a free name")
}

/// Move a recording to `<dataset>/<label>/<label>_NNN.csv`: renamed when its
/// metadata already names `label`, else rewritten with the new label (the
/// samples, and an abort reason if any, unchanged).
pub fn store(from: &Path, dataset: &Path, label: &str) -> Result<PathBuf, String> {
    let to = scan_file(dataset, label, next_free_index(dataset, label));
    let rec = recording::read(from).map_err(|e| e.to_string())?;
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    if rec.label() == Some(label) {
        std::fs::rename(from, &to).map_err(|e| format!("{}: {e}", to.display()))?;
        return Ok(to);
    }
    let mut meta: Vec<(String, toml::Value)> = rec
        .meta
        .iter()
        .filter(|(k, _)| k != recording::ABORTED_KEY)
        .cloned()
        .collect();
    match meta.iter_mut().find(|(k, _)| k == "label") {
        Some((_, v)) => *v = toml::Value::String(label.into()),
        None => meta.insert(0, ("label".into(), toml::Value::String(label.into()))),
    }
    let columns: Vec<&str> = rec.columns.iter().map(String::as_str).collect();
    let columns = if columns.is_empty() {
        COLUMNS.to_vec()
    } else {
        columns
    };
    let mut w = RecordingWriter::create_new(&to, &meta, &columns).map_err(|e| e.to_string())?;
    let mut row = vec![0.0; rec.data.len()];
    for i in 0..rec.len() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = rec.data[c][i];
        }
        w.write_row(&row).map_err(|e| e.to_string())?;
    }
    let done = match (rec.is_complete(), rec.aborted()) {
        (true, _) => w.finish(),
        (false, reason) => w.abort(reason.unwrap_or("incomplete")),
    };
    done.map_err(|e| e.to_string())?;
    std::fs::remove_file(from).map_err(|e| format!("{}: {e}", from.display()))?;
    Ok(to)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::console::app::{Level, Source};
    use crate::console::keymap::KeyMap;
    use std::time::{Duration, Instant};

    /// The console hears a device fault through the servo's events: the
    /// reason stays in the status line once the loop has ended, and the scan
    /// is on disk, incomplete, with the reason.
    #[test]
    fn a_device_that_vanishes_mid_scan_is_reported_with_its_reason() {
        let d = tempfile::tempdir().unwrap();
        let mut lp = LoadedProfile::load(Path::new("tests/data/profiles/quick-scan.toml")).unwrap();
        // The quick path's stroke runs from about 0.1 s to 0.95 s of loop time.
        lp.profile.simulator.faults.vanish_after_s = Some(0.5);
        let mut app = App::new(
            lp.clone(),
            KeyMap::default(),
            Source::Live {
                backend: "sim".into(),
            },
            d.path().to_path_buf(),
        );
        let mut lab = Lab::start(&lp, d.path(), Some("S2")).unwrap();
        let path = lab.start_scan("S2");
        let give_up = Instant::now() + Duration::from_secs(30);
        while lab.handle.is_some() {
            lab.drain(&mut app);
            assert!(Instant::now() < give_up, "the loop did not stop");
            std::thread::sleep(Duration::from_millis(20));
        }
        assert_eq!(app.status.level, Level::Error, "{:?}", app.status.text);
        assert!(
            app.status.text.contains("vanished at 0.5")
                && app.status.text.contains("forces off")
                && app.status.text.contains("check its cable and power"),
            "{}",
            app.status.text
        );
        // The scan was read back and shown (the recorder was waited for).
        let shown = app.last_scan.as_ref().expect("the aborted scan is shown");
        assert!(!shown.complete);
        let rec = recording::read(&path).unwrap();
        assert!(!rec.is_complete());
        assert!(
            rec.aborted().unwrap().contains("vanished"),
            "{:?}",
            rec.meta
        );
        assert!(rec.len() > 100, "{} samples kept", rec.len());
    }

    #[test]
    fn storing_renames_or_rewrites_with_the_label() {
        let d = tempfile::tempdir().unwrap();
        let unsaved = d.path().join(UNSAVED_DIR).join("scan-001.csv");
        let meta = vec![("label".to_string(), toml::Value::String("S1".into()))];
        let mut w = RecordingWriter::create(&unsaved, &meta, &COLUMNS).unwrap();
        w.write_row(&[0.0, 0.01, -0.004, -0.02, 0.0, -0.3, 0.0])
            .unwrap();
        w.finish().unwrap();
        let to = store(&unsaved, d.path(), "S1").unwrap();
        assert_eq!(to, d.path().join("S1/S1_001.csv"));
        assert!(!unsaved.exists());
        // Under another label: rewritten, label changed, still complete.
        let to2 = store(&to, d.path(), "S3").unwrap();
        assert_eq!(to2, d.path().join("S3/S3_001.csv"));
        let rec = recording::read(&to2).unwrap();
        assert_eq!(rec.label(), Some("S3"));
        assert!(rec.is_complete());
        assert_eq!(rec.len(), 1);
        assert!(!to.exists());
    }
}
