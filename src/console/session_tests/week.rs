//! A lab's second day, in-process on `TestBackend`: the console opens
//! yesterday's session folder without `--dataset`, offers the complete scan
//! an earlier session left unstored (not the newer aborted one), stores it,
//! trains, and `e` keeps its report beside the model (the numbers
//! `hapticlab evaluate DIR --fallback` gives for the folder). In the replay
//! browser the keys move through the list (PgUp/PgDn, Home/End, a label,
//! the next wrong prediction, a filter), delete and undo, relabel and
//! exclude recordings (each a file move the loader honours, each flagging
//! the model stale, which the Dataset panel says), and `p` on a texture's
//! only scan says it has no other scans; the message log opens with every
//! message.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;
use std::time::{Duration, SystemTime};

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::layout::Rect;

use super::super::app::{App, Source};
use super::super::curate::{EXCLUDED_DIR, TRASH_DIR};
use super::super::dataset::{REPORT_FILE, REPORT_JSON, UNSAVED_DIR};
use super::super::event::Signals;
use super::super::form::Overlay;
use super::super::keymap::KeyMap;
use super::super::live::Lab;
use super::super::panels::{Panel, dataset as dataset_panel};
use super::super::session;
use super::super::{Ending, Jobs, refresh_dataset, run_loop, scan};
use super::{
    Script, ScriptedKeys, Step, WatchedLab, files_in, keys, panel, screen, stored, text, until,
};
use crate::profile::LoadedProfile;
use crate::recorder::COLUMNS;
use crate::recording::RecordingWriter;
use crate::support::evaluation_text::{header, table};

/// A scan left in `.unsaved/` under `label`, complete or
/// aborted, last changed `age` ago.
fn unsaved_scan(ds: &Path, name: &str, label: &str, complete: bool, age: Duration) {
    let path = ds.join(UNSAVED_DIR).join(name);
    let meta = vec![("label".to_string(), toml::Value::String(label.into()))];
    let mut w = RecordingWriter::create(&path, &meta, &COLUMNS).unwrap();
    // 3.2 cm along x in 2 s, over a 4 mm ripple: it covers the analysis
    // window (1.5 to 2.97 cm), so training can use it once stored.
    for i in 0..2000 {
        let t = i as f64 * 0.001;
        let x = t * 0.016;
        let y = 0.0002 * (x * std::f64::consts::TAU / 0.004).sin();
        w.write_row(&[t, x, y, -0.02, 0.0, -0.3, 0.0]).unwrap();
    }
    if complete {
        w.finish().unwrap();
    } else {
        w.abort("the console was quit during the scan").unwrap();
    }
    let f = std::fs::File::options().write(true).open(&path).unwrap();
    f.set_modified(SystemTime::now() - age).unwrap();
}

/// A named key (an arrow, PgUp, Home…) as a step.
fn press(code: KeyCode) -> Step {
    Step::Keys(vec![KeyEvent::new(code, KeyModifiers::NONE)])
}

/// The replay browser's selection: its index and the recording's path.
fn selected(a: &App) -> Option<(usize, std::path::PathBuf)> {
    let r = a.replay.as_ref()?;
    Some((r.selected, r.entries.get(r.selected)?.path.clone()))
}

/// The Dataset panel itself (the frame shows the Recordings in its place
/// while the browser is open), 100 × 12.
fn dataset_panel_text(a: &App) -> String {
    let area = Rect::new(0, 0, 100, 12);
    let mut buf = Buffer::empty(area);
    dataset_panel::render(a, area, &mut buf);
    text(&buf)
}

/// What `hapticlab evaluate DIR --fallback` makes of the folder now: its
/// `--json` (the outcome) and its text (header and table), as the command
/// prints them.
fn command_evaluation(lp: &LoadedProfile, ds: &Path) -> (serde_json::Value, String) {
    use crate::evaluate::request::{self, Request};
    let mut req = Request::of_recordings(vec![ds.to_path_buf()]);
    req.fallback = true;
    let ev = request::run(lp, &req, &request::Quiet).unwrap();
    let json = serde_json::to_value(&ev.outcome).unwrap();
    (json, format!("{}\n{}", header(lp, &ev), table(&ev.outcome)))
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
    // A mislabelled scan: S1's first, stored again as S2. Predicted with
    // itself left out, its twin in S1 is at distance 0: a WRONG prediction
    // for the browser's `W` to find.
    let twin = ds.join("S2").join("S2_004.csv");
    let s1 = std::fs::read_to_string(ds.join("S1").join("S1_001.csv")).unwrap();
    assert!(s1.contains("# label = \"S1\"\n"));
    std::fs::write(
        &twin,
        s1.replace("# label = \"S1\"\n", "# label = \"S2\"\n"),
    )
    .unwrap();
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
    let at = |i: usize| move |a: &App| selected(a).is_some_and(|(s, _)| s == i);
    let last = |a: &App| {
        a.replay
            .as_ref()
            .is_some_and(|r| r.selected + 1 == r.entries.len() && r.entries.len() > 10)
    };
    let (ds2, ds3, twin2) = (ds.clone(), ds.clone(), twin.clone());
    let (lp2, ds4) = (lp.clone(), ds.clone());
    let steps = vec![
        until("the device homed", |a: &App| {
            a.live.latest.is_some_and(|t| t.homed)
        }),
        // The older, complete unsaved scan is stored under its label.
        keys("w\r"),
        until("the unsaved scan stored", |a: &App| stored(a, "S3") == 4),
        // Train, then evaluate: the report is kept beside the model.
        keys("T"),
        until("the model trained", |a: &App| {
            a.model.is_some() && a.dataset.busy.is_none()
        }),
        Step::Snapshot("trained", Box::new(dataset_panel_text)),
        keys("e"),
        until("the evaluation kept", |a: &App| {
            a.dataset.report_file.is_some() && a.dataset.busy.is_none()
        }),
        Step::Snapshot("evaluated", Box::new(dataset_panel_text)),
        // The files `e` wrote, and the command's evaluation of the folder
        // as it is now (the curating below changes it).
        Step::Snapshot(
            "evaluation_files",
            Box::new(move |_: &App| {
                let kept_json = std::fs::read_to_string(ds4.join(REPORT_JSON)).unwrap();
                let kept_text = std::fs::read_to_string(ds4.join(REPORT_FILE)).unwrap();
                let (cli_json, cli_text) = command_evaluation(&lp2, &ds4);
                serde_json::json!({
                    "kept_json": serde_json::from_str::<serde_json::Value>(&kept_json).unwrap(),
                    "kept_text": kept_text,
                    "cli_json": cli_json,
                    "cli_text": cli_text,
                })
                .to_string()
            }),
        ),
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
        // Through the list: a page down and up, the last and the first.
        press(KeyCode::PageDown),
        until("PgDn: ten rows down", at(10)),
        press(KeyCode::PageUp),
        until("PgUp: ten rows up", at(0)),
        press(KeyCode::End),
        until("End: the last recording", last),
        press(KeyCode::Home),
        until("Home: the first recording", at(0)),
        // To a label; then only S2's, and the next wrong one among them.
        keys("jS2\r"),
        until("S2 selected", move |a: &App| {
            selected_label(a).as_deref() == Some("S2")
        }),
        keys("fS2\r"),
        until("only S2's recordings shown", |a: &App| {
            a.replay.as_ref().is_some_and(|r| {
                r.filter.as_deref() == Some("S2")
                    && r.visible().len() == 4
                    && r.visible().contains(&r.selected)
            })
        }),
        keys("W"),
        until("W: the mislabelled scan", move |a: &App| {
            selected(a).is_some_and(|(_, p)| p == twin2)
                && a.status.text.contains("recorded as S2, predicted S1")
        }),
        // The filter emptied (Backspace edits the value shown): all again.
        keys("f\x7f\x7f\r"),
        until("every recording shown again", |a: &App| {
            a.replay
                .as_ref()
                .is_some_and(|r| r.filter.is_none() && r.visible().len() == r.entries.len())
        }),
        // Jump to S2, delete its first scan, undo.
        keys("jS2\r"),
        until("S2 selected", move |a: &App| {
            selected_label(a).as_deref() == Some("S2")
        }),
        keys("d"),
        until("an S2 scan in the trash", |a: &App| {
            stored(a, "S2") == 3 && a.dataset.edits == 1
        }),
        keys("u"),
        until("the S2 scan back", |a: &App| stored(a, "S2") == 4),
        // Relabel it S1, then exclude it from training.
        keys("jS2\rRS1\r"),
        until("relabelled S1", |a: &App| {
            stored(a, "S1") == 4 && stored(a, "S2") == 3
        }),
        keys("x"),
        until("excluded", move |a: &App| {
            stored(a, "S1") == 3 && files_in(&ds3.join(EXCLUDED_DIR).join("S1")) == 1
        }),
        Step::Snapshot("stale", Box::new(dataset_panel_text)),
        // S4 down to one scan, trained again: `p` on it has no answer.
        keys("jS4\rdd"),
        until("one S4 scan left", |a: &App| stored(a, "S4") == 1),
        keys("T"),
        until("trained again", |a: &App| {
            a.dataset.busy.is_none() && a.dataset.edits == 0
        }),
        keys("jS4\r"),
        until("the S4 scan selected", move |a: &App| {
            selected_label(a).as_deref() == Some("S4")
        }),
        keys("p"),
        until("p answered", |a: &App| {
            a.scan().is_some_and(|s| s.prediction.is_some())
        }),
        Step::Snapshot("only_scan", Box::new(screen)),
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
    // trash holding the relabelled original and two S4 scans; the aborted
    // scan untouched.
    assert!(!ds.join(UNSAVED_DIR).join("scan-001.csv").exists());
    assert!(ds.join(UNSAVED_DIR).join("scan-002.csv").exists());
    assert_eq!(files_in(&ds.join("S3")), 4);
    assert_eq!(files_in(&ds.join("S2")), 3);
    assert_eq!(files_in(&ds.join("S1")), 3);
    assert_eq!(files_in(&ds.join("S4")), 1);
    assert_eq!(files_in(&ds.join(TRASH_DIR).join("S2")), 1);
    assert_eq!(files_in(&ds.join(TRASH_DIR).join("S4")), 2);
    let training = crate::recording::collect_files(std::slice::from_ref(&ds)).unwrap();
    assert_eq!(
        training.len(),
        11,
        "3 + 3 + 4 + 1: the hidden folders skipped"
    );

    let frames = &script.borrow().snapshots;
    let find = |name: &str| frames.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    let trained = find("trained");
    assert!(
        trained.contains("model: k-NN k = 3 on 14 recordings of S1, S2, S3, S4"),
        "{trained}"
    );

    // `e`: the report beside the model, in the Dataset panel, and the
    // command's numbers for the same folder.
    let evaluated = find("evaluated");
    assert!(evaluated.contains("by leave-one-out"), "{evaluated}");
    assert!(evaluated.contains(", in evaluation.txt"), "{evaluated}");
    let files: serde_json::Value = serde_json::from_str(&find("evaluation_files")).unwrap();
    let (kept, cli) = (&files["kept_json"], &files["cli_json"]);
    let compared = [
        "labels",
        "confusion",
        "accuracy",
        "per_class",
        "predictions",
        "method",
        "folds",
        "macro_f1",
    ];
    for key in compared {
        assert!(!cli[key].is_null(), "the command's --json has {key}: {cli}");
        assert_eq!(kept[key], cli[key], "{key}");
    }
    // The k each fold used, as the command's folds give them.
    let mut k_folds: Vec<u64> = cli["folds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["k"].as_u64().unwrap())
        .collect();
    k_folds.sort_unstable();
    k_folds.dedup();
    assert_eq!(kept["k_used"], serde_json::json!(k_folds), "{kept}");
    assert_eq!(kept["dataset"]["recordings"], 14, "{kept}");
    assert_eq!(
        kept["dataset"]["model"],
        ds.join("model.json").display().to_string()
    );
    let (kept_text, cli_text) = (
        files["kept_text"].as_str().unwrap(),
        files["cli_text"].as_str().unwrap(),
    );
    assert!(kept_text.starts_with(cli_text), "{kept_text}\n{cli_text}");
    let accuracy = cli["accuracy"].as_f64().unwrap() * 100.0;
    assert!(
        evaluated.contains(&format!("right ({accuracy:.1} %)")),
        "{evaluated}"
    );

    // Curating flagged the model stale, and the Dataset panel says so.
    let stale = find("stale");
    assert!(
        stale.contains(
            "model stale: T trains again (k = 3, trained before 4 changes to the dataset)"
        ),
        "{stale}"
    );

    let browser = find("browser");
    assert!(browser.contains("scan-002.csv"), "{browser}");
    assert!(browser.contains("incomplete"), "{browser}");
    let only = find("only_scan");
    assert!(only.contains("S4 has no other scans"), "{only}");
    assert!(!only.contains("WRONG"), "{only}");
    let log = find("log");
    assert!(log.contains("Messages:"), "{log}");
    assert!(log.contains("excluded from training"), "{log}");
    assert!(log.contains("undone: deleted"), "{log}");
    assert!(log.contains("S4 has no other scans"), "{log}");
}
