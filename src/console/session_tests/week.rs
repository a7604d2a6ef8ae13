//! A lab's second day, in-process on `TestBackend`: the console opens
//! yesterday's session folder without `--dataset`, offers the complete scan
//! an earlier session left unstored (not the newer aborted one), stores it,
//! and in the replay browser deletes and undoes, relabels and excludes
//! recordings (each a file move the loader honours, each flagging the
//! model stale); the message log opens with every message.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;
use std::time::{Duration, SystemTime};

use ratatui::Terminal;
use ratatui::backend::TestBackend;

use super::super::app::{App, Source};
use super::super::curate::{EXCLUDED_DIR, TRASH_DIR};
use super::super::dataset::UNSAVED_DIR;
use super::super::event::Signals;
use super::super::form::Overlay;
use super::super::keymap::KeyMap;
use super::super::live::Lab;
use super::super::panels::Panel;
use super::super::session;
use super::super::{Ending, Jobs, refresh_dataset, run_loop, scan};
use super::{Script, ScriptedKeys, Step, WatchedLab, files_in, keys, panel, screen, stored, until};
use crate::profile::LoadedProfile;
use crate::recorder::COLUMNS;
use crate::recording::RecordingWriter;

/// A scan left in `.unsaved/`: `rows` samples under `label`, complete or
/// aborted, last changed `age` ago.
fn unsaved_scan(ds: &Path, name: &str, label: &str, complete: bool, age: Duration) {
    let path = ds.join(UNSAVED_DIR).join(name);
    let meta = vec![("label".to_string(), toml::Value::String(label.into()))];
    let mut w = RecordingWriter::create(&path, &meta, &COLUMNS).unwrap();
    for i in 0..200 {
        let t = i as f64 * 0.001;
        w.write_row(&[t, t * 0.01, 0.0, -0.06, 0.0, -0.3, 0.0])
            .unwrap();
    }
    if complete {
        w.finish().unwrap();
    } else {
        w.abort("the console was quit during the scan").unwrap();
    }
    let f = std::fs::File::options().write(true).open(&path).unwrap();
    f.set_modified(SystemTime::now() - age).unwrap();
}

#[test]
fn the_second_day_resumes_stores_the_good_unsaved_scan_and_curates() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("recordings");
    let ds = root.join("session-2020-01-01");
    let lp = LoadedProfile::load(Path::new("tests/data/console-fast.toml")).unwrap();
    let opts = crate::acquire::SimulateOptions {
        out: ds.clone(),
        per_class: 3,
        seed: 7,
        threads: 2,
        gzip: false,
        overwrite: false,
    };
    crate::acquire::simulate_dataset(&lp, &opts, &|_, _| {}).unwrap();
    let hour = Duration::from_secs(3600);
    // Yesterday: a complete scan left unstored, then one cut short by a quit.
    unsaved_scan(&ds, "scan-001.csv", "S3", true, hour * 26);
    unsaved_scan(&ds, "scan-002.csv", "S3", false, hour * 25);
    for d in ["S1", "S2", "S3", "S4", UNSAVED_DIR, ""] {
        let f = std::fs::File::open(ds.join(d)).unwrap();
        f.set_modified(SystemTime::now() - hour * 25).unwrap();
    }

    // No --dataset: yesterday's folder is opened, and the console says so.
    let now = SystemTime::now();
    let (dir, resumed) = session::choose(&root, now);
    assert_eq!(dir, ds);
    let resumed = resumed.expect("yesterday's session resumed");
    let mut app = App::new(
        lp.clone(),
        KeyMap::from_settings(&lp.profile.console).unwrap(),
        Source::Live {
            backend: "sim".into(),
        },
        ds.clone(),
    );
    let lab = Lab::start(&lp, &ds, Some("S1")).unwrap();
    app.mounted = lab.texture.clone();
    refresh_dataset(&mut app);
    let mut ex = crate::analysis::FeatureExtractor::new(&lp.profile.analysis);
    let offered = scan::newest_unsaved(&ds, &mut ex).expect("a complete unsaved scan");
    assert!(
        offered.path.ends_with("scan-001.csv"),
        "the aborted scan-002 is not offered: {}",
        offered.path.display()
    );
    app.on_unsaved_found(offered);
    app.on_resumed(&resumed, now);
    assert!(
        app.status
            .text
            .starts_with(&format!("resumed {}", ds.display())),
        "{}",
        app.status.text
    );
    session::remember(&ds, "thesis").unwrap();
    assert_eq!(
        session::profile_of(&ds),
        Some(std::path::PathBuf::from("thesis"))
    );

    let selected_label = |a: &App| {
        a.replay
            .as_ref()
            .and_then(|r| r.entries.get(r.selected))
            .map(|e| e.label_or_folder())
    };
    let ds2 = ds.clone();
    let ds3 = ds.clone();
    let steps = vec![
        until("the device homed", |a: &App| {
            a.live.latest.is_some_and(|t| t.homed)
        }),
        // The older, complete unsaved scan is stored under its label.
        keys("w\r"),
        until("the unsaved scan stored", |a: &App| stored(a, "S3") == 4),
        // The browser lists the stored ones, then the aborted scan, labelled.
        keys("r"),
        until("the replay browser listed", |a: &App| {
            a.replay.as_ref().is_some_and(|r| !r.listing)
        }),
        until(
            "the aborted scan listed as incomplete, unsaved",
            move |a: &App| {
                a.replay.as_ref().is_some_and(|r| {
                    r.entries.iter().any(|e| {
                        e.unsaved(&ds2)
                            && e.complete == Some(false)
                            && e.path.ends_with("scan-002.csv")
                    })
                })
            },
        ),
        Step::Snapshot(
            "browser",
            Box::new(|a: &App| panel(Panel::Dataset, a, 100, 30)),
        ),
        // Jump to S2, delete its first scan, undo.
        keys("jS2\r"),
        until("S2 selected", move |a: &App| {
            selected_label(a).as_deref() == Some("S2")
        }),
        keys("d"),
        until("an S2 scan in the trash", |a: &App| {
            stored(a, "S2") == 2 && a.dataset.edits == 1
        }),
        keys("u"),
        until("the S2 scan back", |a: &App| stored(a, "S2") == 3),
        // Relabel it S1, then exclude it from training.
        keys("jS2\rRS1\r"),
        until("relabelled S1", |a: &App| {
            stored(a, "S1") == 4 && stored(a, "S2") == 2
        }),
        keys("x"),
        until("excluded", move |a: &App| {
            stored(a, "S1") == 3 && files_in(&ds3.join(EXCLUDED_DIR).join("S1")) == 1
        }),
        keys("M"),
        until("the message log open", |a: &App| {
            matches!(a.overlay, Some(Overlay::Messages { .. }))
        }),
        Step::Snapshot("log", Box::new(screen)),
        keys("\x1b\x1bq"),
    ];
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
    let ending = run_loop(
        &mut terminal,
        &mut app,
        Some(&mut lab),
        &mut events,
        &Jobs::default(),
        &Signals::unraised(),
    );
    lab.lab.shutdown(&ending.stop_reason());
    assert_eq!(ending, Ending::Quit);
    assert!(
        script.borrow().steps.is_empty(),
        "the script ran to its end"
    );

    // On disk: the stored scan, the relabelled one, the excluded one, the
    // trash holding the relabelled original; the aborted scan untouched.
    assert!(!ds.join(UNSAVED_DIR).join("scan-001.csv").exists());
    assert!(ds.join(UNSAVED_DIR).join("scan-002.csv").exists());
    assert_eq!(files_in(&ds.join("S3")), 4);
    assert_eq!(files_in(&ds.join("S2")), 2);
    assert_eq!(files_in(&ds.join("S1")), 3);
    assert!(files_in(&ds.join(TRASH_DIR).join("S2")) >= 1);
    let training = crate::recording::collect_files(std::slice::from_ref(&ds)).unwrap();
    assert_eq!(
        training.len(),
        12,
        "3 + 2 + 4 + 3: the hidden folders skipped"
    );
    assert!(app.dataset.edits >= 4, "every change flags the model stale");

    let frames = &script.borrow().snapshots;
    let find = |name: &str| frames.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    let browser = find("browser");
    assert!(browser.contains("scan-002.csv"), "{browser}");
    assert!(browser.contains("incomplete"), "{browser}");
    let log = find("log");
    assert!(log.contains("Messages:"), "{log}");
    assert!(log.contains("excluded from training"), "{log}");
    assert!(log.contains("undone: deleted"), "{log}");
}
