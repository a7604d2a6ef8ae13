//! A whole console session in-process, no pseudo-terminal: [`run_loop`] on
//! ratatui's `TestBackend`, the live [`Lab`] (the servo thread on the
//! simulated Falcon, the fast test profile `tests/data/console-fast.toml`),
//! and keys from a script. Five automatic scans of each texture, stored as
//! they complete; train; predict; the replay browser; quit.
//!
//! The script waits for conditions on the app, never for time: each step's
//! keys are released once the app shows what the step waits for (checked
//! once a frame, when the loop drains the lab), with a generous limit, so a
//! machine busy with other work slows the session down but does not fail
//! it. Snapshots are taken of panels whose content the session decides
//! (counts, the model, the recordings' names and labels); what the timing of
//! a real-time loop can change (distances, votes, each replayed file's
//! prediction) is checked by assertions or redacted.

mod week;

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::layout::Rect;

use super::app::{App, Source};
use super::event::{Event, EventSource, Signals};
use super::keymap::KeyMap;
use super::live::{Lab, LabPort};
use super::panels::{Panel, render_panel};
use super::{Ending, Jobs, refresh_dataset, run_loop};
use crate::profile::LoadedProfile;
use crate::servo::Command;

/// Every wait: generous, for a machine whose two cores are busy elsewhere.
const PATIENCE: Duration = Duration::from_secs(120);
const TEXTURES: [&str; 4] = ["S1", "S2", "S3", "S4"];

type Check = Box<dyn Fn(&App) -> bool>;
type Take = Box<dyn Fn(&App) -> String>;

enum Step {
    /// Type these keys.
    Keys(Vec<KeyEvent>),
    /// Wait until the app shows this (named for the failure message).
    Until(String, Check),
    /// Keep this text of the app's screen as a snapshot named so.
    Snapshot(&'static str, Take),
}

/// The session's script, shared by the keys and the lab.
#[derive(Default)]
struct Script {
    steps: VecDeque<Step>,
    keys: VecDeque<KeyEvent>,
    since: Option<Instant>,
    snapshots: Vec<(&'static str, String)>,
    /// When the last step was done (the session should end soon after).
    finished_at: Option<Instant>,
}

impl Script {
    /// Once a frame, with the app as the loop has it: run the steps whose
    /// conditions hold.
    fn observe(&mut self, app: &App) {
        while self.keys.is_empty() {
            let Some(step) = self.steps.front() else {
                self.finished_at.get_or_insert_with(Instant::now);
                return;
            };
            match step {
                Step::Keys(k) => self.keys.extend(k.iter().copied()),
                Step::Until(what, check) => {
                    if !check(app) {
                        let since = *self.since.get_or_insert_with(Instant::now);
                        assert!(
                            since.elapsed() < PATIENCE,
                            "waited {PATIENCE:?} for {what}; the status: {:?}; the screen:\n{}",
                            app.status.text,
                            screen(app)
                        );
                        return;
                    }
                }
                Step::Snapshot(name, take) => self.snapshots.push((name, take(app))),
            }
            self.since = None;
            self.steps.pop_front();
        }
    }
}

/// Keys from the script, one at a time, as the terminal would give them.
struct ScriptedKeys(Rc<RefCell<Script>>);

impl EventSource for ScriptedKeys {
    fn next(&mut self, timeout: Duration) -> io::Result<Option<Event>> {
        let mut s = self.0.borrow_mut();
        if let Some(k) = s.keys.pop_front() {
            return Ok(Some(Event::Key(k)));
        }
        if s.finished_at.is_some_and(|t| t.elapsed() > PATIENCE) {
            return Err(io::Error::other(
                "the script ended but the console did not quit",
            ));
        }
        drop(s);
        // No key before the frame is due, as a quiet terminal.
        std::thread::sleep(timeout);
        Ok(None)
    }
}

/// The live lab, with the script looking on once a frame.
struct WatchedLab {
    lab: Lab,
    script: Rc<RefCell<Script>>,
}

impl LabPort for WatchedLab {
    fn drain(&mut self, app: &mut App) -> Vec<super::app::Action> {
        let actions = self.lab.drain(app);
        self.script.borrow_mut().observe(app);
        actions
    }
    fn send(&self, c: Command) {
        self.lab.send(c);
    }
    fn start_scan(&mut self, label: &str) -> PathBuf {
        self.lab.start_scan(label)
    }
    fn mount(&mut self, texture: &str, app: &mut App) -> Result<(), String> {
        self.lab.mount(texture, app)
    }
    fn texture(&self) -> Option<String> {
        self.lab.texture.clone()
    }
    fn set_dataset(&mut self, dir: &Path) {
        self.lab.set_dataset(dir);
    }
}

fn key(c: char) -> KeyEvent {
    let (code, mods) = match c {
        '\r' => (KeyCode::Enter, KeyModifiers::NONE),
        '\x1b' => (KeyCode::Esc, KeyModifiers::NONE),
        '\x7f' => (KeyCode::Backspace, KeyModifiers::NONE),
        c if c.is_ascii_uppercase() => (KeyCode::Char(c), KeyModifiers::SHIFT),
        c => (KeyCode::Char(c), KeyModifiers::NONE),
    };
    KeyEvent::new(code, mods)
}

fn keys(s: &str) -> Step {
    Step::Keys(s.chars().map(key).collect())
}

fn until(what: impl Into<String>, check: impl Fn(&App) -> bool + 'static) -> Step {
    Step::Until(what.into(), Box::new(check))
}

fn text(buf: &Buffer) -> String {
    let a = buf.area;
    let mut out = String::new();
    for y in a.y..a.bottom() {
        let line: String = (a.x..a.right()).map(|x| buf[(x, y)].symbol()).collect();
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// The frame the loop draws of this app, 120 × 40, as text.
fn screen(app: &App) -> String {
    let mut t = Terminal::new(TestBackend::new(120, 40)).unwrap();
    t.draw(|f| f.render_widget(app, f.area())).unwrap();
    text(t.backend().buffer())
}

/// One panel as the frame shows it, the dataset folder (a temporary one)
/// written as `<dataset>`.
fn panel(p: Panel, app: &App, w: u16, h: u16) -> String {
    let area = Rect::new(0, 0, w, h);
    let mut buf = Buffer::empty(area);
    render_panel(p, app, area, &mut buf);
    let dir = app.dataset.dir.display().to_string();
    redact(&text(&buf), w, |l| {
        l.contains(&dir).then(|| {
            l.replace(&dir, "<dataset>")
                .trim_end_matches('│')
                .to_string()
        })
    })
}

/// Lines `f` rewrites, padded back to the panel's width and closed with its
/// border (the top one too); the others as they are.
fn redact(panel: &str, width: u16, f: impl Fn(&str) -> Option<String>) -> String {
    let inner = usize::from(width) - 1;
    panel
        .lines()
        .map(|l| match f(l) {
            Some(r) => {
                let r = r.trim_end();
                let (fill, end) = if r.starts_with('┌') {
                    ("─", '┐')
                } else {
                    (" ", '│')
                };
                let pad = inner.saturating_sub(r.chars().count());
                format!("{r}{}{end}\n", fill.repeat(pad))
            }
            None => format!("{l}\n"),
        })
        .collect()
}

/// The Recordings panel with each prediction, and the score, redacted:
/// which texture a real-time scan is taken for may change from run to run
/// (the test checks each is one of the profile's).
fn recordings(app: &App) -> String {
    redact(&panel(Panel::Dataset, app, 64, 24), 64, |l| {
        if l.starts_with('│') {
            l.find('→').map(|i| format!("{}→ <predicted>", &l[..i]))
        } else {
            match (l.find(", "), l.find(" predicted right")) {
                (Some(a), Some(b)) => Some(format!(
                    "{}, <score>{}",
                    &l[..a],
                    l[b..].trim_end_matches(['┐', '─'])
                )),
                _ => None,
            }
        }
    })
}

fn stored(app: &App, label: &str) -> usize {
    app.dataset
        .counts
        .iter()
        .find(|(l, _)| l == label)
        .map_or(0, |(_, n)| *n)
}

fn files_in(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |d| d.count())
}

/// Queue 5 scans per texture, store, train, predict, replay, quit: the whole
/// console in one process, against the real servo on the simulator.
#[test]
fn a_whole_session_queue_train_predict_replay_quit() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let lp = LoadedProfile::load(Path::new("tests/data/console-fast.toml")).unwrap();
    let keymap = KeyMap::from_settings(&lp.profile.console).unwrap();
    let mut app = App::new(
        lp.clone(),
        keymap,
        Source::Live {
            backend: "sim".into(),
        },
        ds.clone(),
    );
    assert_eq!(app.label, "S1", "the first texture is the first label");
    let lab = Lab::start(&lp, &ds, Some("S1")).unwrap();
    app.mounted = lab.texture.clone();
    refresh_dataset(&mut app);

    let mut steps = vec![until("the device homed", |a: &App| {
        a.live.latest.is_some_and(|t| t.homed)
    })];
    for (i, t) in TEXTURES.into_iter().enumerate() {
        if i > 0 {
            // The label names a texture: the simulator mounts it.
            steps.push(keys(&format!("l{t}\r")));
            steps.push(until(format!("texture {t} mounted"), move |a: &App| {
                a.mounted.as_deref() == Some(t) && a.label == t
            }));
        }
        // Five automatic scans (the form's default), each stored as it completes.
        steps.push(keys("n\r"));
        steps.push(until(format!("5 scans of {t} stored"), move |a: &App| {
            stored(a, t) == 5 && !a.scan_busy() && a.status.text.contains("automatic scans done")
        }));
    }
    steps.push(Step::Snapshot(
        "dataset_after_the_queues",
        Box::new(|a| panel(Panel::Dataset, a, 80, 8)),
    ));
    steps.push(keys("T"));
    steps.push(until("the model trained", |a: &App| {
        a.model.is_some() && a.dataset.busy.is_none()
    }));
    steps.push(Step::Snapshot(
        "dataset_after_training",
        Box::new(|a| panel(Panel::Dataset, a, 80, 8)),
    ));
    steps.push(keys("p"));
    steps.push(until("the last scan predicted", |a: &App| {
        a.last_scan.as_ref().is_some_and(|s| s.prediction.is_some())
    }));
    steps.push(Step::Snapshot("prediction_screen", Box::new(screen)));
    steps.push(keys("r"));
    steps.push(until(
        "the replay browser listed and predicted",
        |a: &App| {
            a.replay
                .as_ref()
                .is_some_and(|r| !r.listing && r.entries.iter().all(|e| e.predicted.is_some()))
        },
    ));
    steps.push(until(
        "every recording predicted as a profile texture",
        |a: &App| {
            a.replay.as_ref().is_some_and(|r| {
                r.score().1 == 20
                    && r.entries
                        .iter()
                        .all(|e| TEXTURES.contains(&e.predicted.as_deref().unwrap_or_default()))
            })
        },
    ));
    steps.push(Step::Snapshot("replay_browser", Box::new(recordings)));
    steps.push(keys("\x1b"));
    steps.push(until("back to the live device", |a: &App| {
        a.replay.is_none()
    }));
    steps.push(keys("q"));

    let script = Rc::new(RefCell::new(Script {
        steps: steps.into(),
        ..Script::default()
    }));
    let mut lab = WatchedLab {
        lab,
        script: script.clone(),
    };
    let mut events = ScriptedKeys(script.clone());
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let jobs = Jobs::default();
    let ending = run_loop(
        &mut terminal,
        &mut app,
        Some(&mut lab),
        &mut events,
        &jobs,
        &Signals::unraised(),
    );
    let saved = lab.lab.shutdown(&ending.stop_reason());
    assert_eq!(ending, Ending::Quit);
    assert!(
        script.borrow().steps.is_empty(),
        "the script ran to its end"
    );
    assert!(saved.iter().all(|s| s.complete), "no scan cut short");

    // On disk: five complete recordings per texture, nothing left unstored,
    // the model saved.
    for t in TEXTURES {
        let dir = ds.join(t);
        assert_eq!(files_in(&dir), 5, "{}", dir.display());
        for i in 1..=5 {
            let rec = crate::recording::read(&dir.join(format!("{t}_{i:03}.csv"))).unwrap();
            assert!(rec.is_complete());
            assert_eq!(rec.label(), Some(t));
            assert_eq!(rec.meta_str("texture"), Some(t), "scanned on its texture");
        }
    }
    assert_eq!(files_in(&ds.join(super::dataset::UNSAVED_DIR)), 0);
    assert!(ds.join("model.json").exists(), "T saved the model");

    // The prediction: the last scan (S4's fifth), as the frame shows it.
    let frames = &script.borrow().snapshots;
    let find = |name: &str| {
        frames
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, s)| s.clone())
            .unwrap()
    };
    let predicted = find("prediction_screen");
    assert!(predicted.contains("Predicted "), "{predicted}");
    assert!(
        predicted.contains("recorded as S4"),
        "the last scan was S4's: {predicted}"
    );
    // The last frame the session drew: back on the live device.
    let last = text(terminal.backend().buffer());
    assert!(last.contains("Device"), "{last}");

    for name in [
        "dataset_after_the_queues",
        "dataset_after_training",
        "replay_browser",
    ] {
        insta::assert_snapshot!(name, find(name));
    }
}

/// The live lab, recording after each frame how many sub-windows the live
/// estimate had classified while its scan ran.
struct FollowedLab {
    watched: WatchedLab,
    followed: Rc<RefCell<Vec<usize>>>,
}

impl LabPort for FollowedLab {
    fn drain(&mut self, app: &mut App) -> Vec<super::app::Action> {
        let actions = self.watched.drain(app);
        if let Some(e) = app.estimate.as_ref().filter(|e| e.running) {
            self.followed.borrow_mut().push(e.completed());
        }
        actions
    }
    fn send(&self, c: Command) {
        self.watched.send(c);
    }
    fn start_scan(&mut self, label: &str) -> PathBuf {
        self.watched.start_scan(label)
    }
    fn mount(&mut self, texture: &str, app: &mut App) -> Result<(), String> {
        self.watched.mount(texture, app)
    }
    fn texture(&self) -> Option<String> {
        self.watched.texture()
    }
    fn set_dataset(&mut self, dir: &Path) {
        self.watched.set_dataset(dir);
    }
}

/// With `[analysis] windows` and a trained model, a scan is followed live
/// (the servo's telemetry, drained once a frame, feeding the vote) and ends
/// predicted without a key: the stored recording's vote, as `classify`
/// makes it.
#[test]
fn a_scan_under_sub_windows_is_followed_live_and_ends_predicted_as_classify_says() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let mut lp = LoadedProfile::load(Path::new("tests/data/console-fast.toml")).unwrap();
    // Three 7.5 mm sub-windows every 3.6 mm of the 14.7 mm window.
    lp.profile.analysis.bins = [1, 12];
    lp.profile.analysis.windows = Some(crate::profile::Windows {
        length: 0.0075,
        hop: 0.0036,
    });
    assert_eq!(lp.profile.analysis.sub_windows().len(), 3);
    // Scans to train on, simulated in virtual time.
    let opts = crate::acquire::SimulateOptions {
        out: ds.clone(),
        per_class: 4,
        seed: 7,
        threads: 2,
        gzip: false,
        overwrite: false,
    };
    crate::acquire::simulate_dataset(&lp, &opts, &|_, _| {}).unwrap();
    let keymap = KeyMap::from_settings(&lp.profile.console).unwrap();
    let mut app = App::new(
        lp.clone(),
        keymap,
        Source::Live {
            backend: "sim".into(),
        },
        ds.clone(),
    );
    let lab = Lab::start(&lp, &ds, Some("S1")).unwrap();
    app.mounted = lab.texture.clone();
    refresh_dataset(&mut app);
    assert_eq!(stored(&app, "S1"), 4);

    let steps = vec![
        until("the device homed", |a: &App| {
            a.live.latest.is_some_and(|t| t.homed)
        }),
        keys("T"),
        until("the model trained", |a: &App| {
            a.model.is_some() && a.dataset.busy.is_none()
        }),
        keys("s"),
        until("the scan ended and predicted from its file", |a: &App| {
            !a.scan_busy()
                && !a.scan_saving
                && a.last_scan.as_ref().is_some_and(|s| s.prediction.is_some())
        }),
        // Store it under its label (the form's default).
        keys("w\r"),
        until("the scan stored", |a: &App| stored(a, "S1") == 5),
        keys("q"),
    ];
    let script = Rc::new(RefCell::new(Script {
        steps: steps.into(),
        ..Script::default()
    }));
    let followed = Rc::new(RefCell::new(Vec::new()));
    let mut lab = FollowedLab {
        watched: WatchedLab {
            lab,
            script: script.clone(),
        },
        followed: followed.clone(),
    };
    let mut events = ScriptedKeys(script.clone());
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let jobs = Jobs::default();
    let ending = run_loop(
        &mut terminal,
        &mut app,
        Some(&mut lab),
        &mut events,
        &jobs,
        &Signals::unraised(),
    );
    lab.watched.lab.shutdown(&ending.stop_reason());
    assert_eq!(ending, Ending::Quit);
    assert!(
        script.borrow().steps.is_empty(),
        "the script ran to its end"
    );

    // Followed while it ran: frames saw the vote grow, never shrink.
    let followed = followed.borrow();
    assert!(!followed.is_empty(), "no frame saw the scan running");
    assert!(followed.windows(2).all(|w| w[0] <= w[1]), "{followed:?}");
    assert!(followed.iter().all(|&n| n <= 3), "{followed:?}");

    // The prediction shown is `classify`'s for the stored file.
    let model = app.model.as_ref().unwrap();
    assert!(model.analysis.windows.is_some());
    let s = app.last_scan.as_ref().unwrap();
    let file = s.stored.clone().expect("stored");
    let rec = crate::recording::read(&file).unwrap();
    assert!(rec.is_complete());
    let mut ex = crate::analysis::FeatureExtractor::new(&model.analysis);
    let classify = model
        .classify_windows(&crate::dataset::window_features_of(&rec, &file, &mut ex).unwrap())
        .unwrap();
    let shown = s.prediction.clone().unwrap().unwrap();
    assert_eq!(shown.windows, Some(classify));
    assert!(!shown.left_out);
}
