//! Key handling as pure state transitions: `App::handle_key` → actions.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use super::{Action, App, Source};
use crate::console::fixtures;
use crate::console::form::{FormKind, Overlay};
use crate::console::keymap::KeyMap;
use crate::console::replay::{Player, Replay};
use crate::profile::LoadedProfile;
use crate::servo::{Mode, ServoEvent};

fn key(c: char) -> KeyEvent {
    KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE)
}
fn code(c: KeyCode) -> KeyEvent {
    KeyEvent::new(c, KeyModifiers::NONE)
}

/// A fresh live console, the probe resting at the first waypoint.
fn app() -> App {
    let mut a = App::new(
        LoadedProfile::thesis(),
        KeyMap::default(),
        Source::Live {
            backend: "sim".into(),
        },
        "ds".into(),
    );
    a.mounted = Some("S1".into());
    let mut t = fixtures::telemetry(0.0, Mode::Manual);
    t.pos_m = [0.0, 0.0, -0.06];
    a.on_telemetry(&t);
    a
}

fn type_text(a: &mut App, text: &str) -> Vec<Action> {
    let mut out = Vec::new();
    for c in text.chars() {
        out.extend(a.handle_key(key(c)));
    }
    out
}

#[test]
fn m_cycles_manual_target_test() {
    let mut a = app();
    assert_eq!(a.handle_key(key('m')), vec![Action::SetMode(Mode::Target)]);
    assert_eq!(a.target_m, Some([0.0, 0.0, -0.06]));
    let mut t = fixtures::telemetry(0.1, Mode::Target);
    t.pos_m = [0.0, 0.0, -0.06];
    a.on_telemetry(&t);
    assert_eq!(a.handle_key(key('m')), vec![Action::SetMode(Mode::Test)]);
}

#[test]
fn s_starts_once_and_esc_aborts() {
    let mut a = app();
    assert_eq!(a.handle_key(key('s')), vec![Action::StartScan]);
    assert!(a.scan_running);
    assert_eq!(a.handle_key(key('s')), vec![]);
    assert!(a.status.text.contains("a scan is running"));
    assert_eq!(a.handle_key(key('m')), vec![]);
    // Esc asks first; only y aborts.
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert_eq!(a.overlay, Some(Overlay::ConfirmAbort));
    assert_eq!(a.handle_key(key('y')), vec![Action::Abort]);
    assert!(a.overlay.is_none());
    a.on_servo_event(ServoEvent::ScanEnded {
        path: "x".into(),
        samples: 10,
        aborted: Some("aborted by the user".into()),
        stats: Default::default(),
    });
    assert!(!a.scan_running);
}

#[test]
fn the_target_form_is_validated_against_the_workspace() {
    let mut a = app();
    assert_eq!(a.handle_key(key('t')), vec![]);
    let Some(Overlay::Form(f)) = &a.overlay else {
        panic!("no form")
    };
    assert_eq!(f.value(2), "-6.00");
    // x = 9 cm is outside the ±5 cm workspace.
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    type_text(&mut a, "9");
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![]);
    let Some(Overlay::Form(f)) = &a.overlay else {
        panic!("the form closed")
    };
    assert!(f.error.as_ref().unwrap().contains("outside the workspace"));
    a.handle_key(code(KeyCode::Backspace));
    type_text(&mut a, "1.5");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::SetTarget([0.015, 0.0, -0.06])]
    );
    assert!(a.overlay.is_none());
}

#[test]
fn arrows_and_page_keys_nudge_the_target_and_plus_minus_the_speed() {
    let mut a = app();
    let near = |got: &[Action], want: [f64; 3]| match got {
        [Action::SetTarget(p)] => p.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
        _ => false,
    };
    assert!(near(
        &a.handle_key(code(KeyCode::Right)),
        [0.001, 0.0, -0.06]
    ));
    assert!(near(
        &a.handle_key(code(KeyCode::Up)),
        [0.001, 0.001, -0.06]
    ));
    assert!(near(
        &a.handle_key(code(KeyCode::PageDown)),
        [0.001, 0.001, -0.059]
    ));
    assert_eq!(a.handle_key(key('+')), vec![Action::SetSpeed(1.5)]);
    assert_eq!(a.handle_key(key('-')), vec![Action::SetSpeed(1.0)]);
    assert_eq!(a.handle_key(key('-')), vec![Action::SetSpeed(0.75)]);
}

#[test]
fn w_stores_the_last_scan_under_a_label_defaulting_to_the_last() {
    let mut a = app();
    assert_eq!(a.handle_key(key('w')), vec![]);
    assert!(a.overlay.is_none(), "nothing to store yet");
    a.label = "S2".into();
    assert_eq!(a.on_scan_saved(fixtures::scan_view(false)), vec![]);
    a.handle_key(key('w'));
    assert!(
        matches!(&a.overlay, Some(Overlay::Form(f)) if f.kind == FormKind::Store && f.value(0) == "S2")
    );
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::Store { label: "S2".into() }]
    );
    a.on_stored(Ok("ds/S2/S2_001.csv".into()));
    assert!(!a.unsaved_scan());
    // A bad label is refused on the form.
    a.last_scan.as_mut().unwrap().stored = None;
    a.handle_key(key('w'));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    type_text(&mut a, "../x");
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![]);
    assert!(matches!(&a.overlay, Some(Overlay::Form(f)) if f.error.is_some()));
}

/// The emulated Falcon runs over the simulation, so a label mounts its
/// texture there too (a training session on it is not all one texture);
/// a real Falcon's texture is changed by hand.
#[test]
fn l_mounts_the_texture_on_the_emulated_falcon_but_not_on_a_real_one() {
    for (backend, mounts) in [("falcon-emulator", true), ("falcon", false)] {
        let mut a = app();
        a.source = Source::Live {
            backend: backend.into(),
        };
        a.handle_key(key('l'));
        a.handle_key(code(KeyCode::Backspace));
        a.handle_key(code(KeyCode::Backspace));
        type_text(&mut a, "S3");
        let want = if mounts {
            vec![Action::Mount("S3".into())]
        } else {
            vec![]
        };
        assert_eq!(a.handle_key(code(KeyCode::Enter)), want, "{backend}");
        assert_eq!(a.label, "S3");
    }
}

#[test]
fn l_mounts_a_profile_texture_and_n_runs_a_training_session() {
    let mut a = app();
    a.handle_key(key('l'));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    assert_eq!(type_text(&mut a, "S3"), vec![]);
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::Mount("S3".into())]
    );
    a.mounted = Some("S3".into());
    assert_eq!(a.label, "S3");
    // Three automatic scans: each is stored as it completes, then the next starts.
    a.handle_key(key('n'));
    a.handle_key(code(KeyCode::Backspace));
    type_text(&mut a, "3");
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![Action::StartScan]);
    let store = Action::Store { label: "S3".into() };
    assert_eq!(
        a.on_scan_saved(fixtures::scan_view(false)),
        vec![store.clone(), Action::StartScan]
    );
    a.on_stored(Ok("ds/S3/S3_001.csv".into()));
    assert_eq!(
        a.on_scan_saved(fixtures::scan_view(false)),
        vec![store.clone(), Action::StartScan]
    );
    a.on_stored(Ok("ds/S3/S3_002.csv".into()));
    assert!(a.status.text.contains("1 more to go"), "{}", a.status.text);
    assert_eq!(a.on_scan_saved(fixtures::scan_view(false)), vec![store]);
    assert!(!a.queued_run && a.queue_left == 0);
    // The end of the run is announced when its last scan is stored.
    a.on_stored(Ok("ds/S3/S3_003.csv".into()));
    assert!(
        a.status
            .text
            .contains("automatic scans done: 3 of 3 stored"),
        "{}",
        a.status.text
    );
    a.on_stored(Ok("ds/S3/S3_004.csv".into()));
    assert!(a.status.text.starts_with("stored "), "{}", a.status.text);
    // A label that names no texture keeps the mounted one.
    a.handle_key(key('l'));
    for _ in 0..2 {
        a.handle_key(code(KeyCode::Backspace));
    }
    type_text(&mut a, "wood");
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![]);
    assert!(
        a.status.text.contains("S3 stays mounted"),
        "{}",
        a.status.text
    );
}

#[test]
fn p_trains_first_when_there_is_no_model() {
    let mut a = app();
    assert_eq!(a.handle_key(key('p')), vec![]);
    a.on_scan_saved(fixtures::scan_view(false));
    assert_eq!(
        a.handle_key(key('p')),
        vec![Action::Train { then_predict: true }]
    );
    assert_eq!(a.handle_key(key('T')), vec![], "busy training");
    assert_eq!(a.handle_key(key('e')), vec![Action::Evaluate]);
}

#[test]
fn q_asks_before_losing_an_unsaved_scan_and_ctrl_c_quits_now() {
    let mut a = app();
    a.on_scan_saved(fixtures::scan_view(false));
    assert_eq!(a.handle_key(key('q')), vec![]);
    assert_eq!(a.overlay, Some(Overlay::ConfirmQuit));
    assert_eq!(a.handle_key(key('n')), vec![]);
    assert!(!a.quit);
    a.handle_key(key('q'));
    assert_eq!(a.handle_key(key('y')), vec![Action::Quit]);
    assert!(a.quit);
    let mut b = app();
    assert_eq!(b.handle_key(key('q')), vec![Action::Quit]);
    // Between the end of a scan's motion and its saved file, q asks too.
    let mut d = app();
    d.handle_key(key('s'));
    d.on_servo_event(ServoEvent::ScanEnded {
        path: "x".into(),
        samples: 10,
        aborted: None,
        stats: Default::default(),
    });
    assert!(!d.scan_busy());
    assert_eq!(d.handle_key(key('q')), vec![]);
    assert_eq!(d.overlay, Some(Overlay::ConfirmQuit));
    d.handle_key(key('n'));
    d.on_scan_saved(fixtures::scan_view(false));
    d.on_stored(Ok("ds/S1/S1_001.csv".into()));
    assert_eq!(d.handle_key(key('q')), vec![Action::Quit], "all stored");
    let mut c = app();
    c.on_scan_saved(fixtures::scan_view(false));
    let ctrl_c = KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL);
    assert_eq!(c.handle_key(ctrl_c), vec![Action::Quit]);
}

#[test]
fn help_and_pages() {
    let mut a = app();
    a.resize(80, 24);
    a.handle_key(key('?'));
    assert_eq!(a.overlay, Some(Overlay::Help));
    assert_eq!(a.handle_key(key('s')), vec![], "any key closes the help");
    assert!(a.overlay.is_none());
    a.handle_key(code(KeyCode::Tab));
    assert_eq!(a.page, 1);
    a.handle_key(key('4'));
    assert_eq!(a.page, 3);
    a.handle_key(code(KeyCode::Tab));
    assert_eq!(a.page, 0);
    a.resize(200, 60);
    assert_eq!(a.page_count(), 1);
}

#[test]
fn replay_keys_drive_the_player() {
    let mut a = app();
    let view = fixtures::scan_view(false);
    let rec = crate::recording::Recording {
        path: None,
        meta: vec![],
        columns: vec!["t_s".into(), "x_m".into()],
        data: vec![
            (0..1000).map(|i| i as f64 * 0.001).collect(),
            vec![0.0; 1000],
        ],
        trailer_samples: Some(1000),
        torn_last_row: false,
    };
    let mut r = Replay::new("ds".into(), vec!["ds/a.csv".into(), "ds/b.csv".into()]);
    r.player = Some(Player::new(&rec));
    r.scan = Some(view);
    a.replay = Some(r);
    a.advance(0.1);
    assert_eq!(a.replay_feed.frames, 101);
    a.handle_key(key(' '));
    a.advance(0.1);
    assert_eq!(a.replay_feed.frames, 101, "paused");
    a.handle_key(key('.'));
    assert_eq!(a.replay_feed.frames, 151, "a single step");
    a.handle_key(key('+'));
    assert_eq!(a.replay.as_ref().unwrap().player.as_ref().unwrap().speed, 4);
    assert_eq!(
        a.handle_key(code(KeyCode::Down)),
        vec![Action::OpenRecording(1)]
    );
    assert_eq!(a.handle_key(code(KeyCode::Down)), vec![]);
    assert_eq!(a.handle_key(key('s')), vec![], "no scans while replaying");
    a.handle_key(code(KeyCode::Esc));
    assert!(a.replay.is_none(), "Esc returns to the live device");
}

#[test]
fn no_measurement_until_the_falcon_is_homed_and_the_user_is_told_how() {
    let mut a = App::new(
        LoadedProfile::thesis(),
        KeyMap::default(),
        Source::Live {
            backend: "falcon-emulator".into(),
        },
        "ds".into(),
    );
    let mut t = fixtures::telemetry(0.0, Mode::Manual);
    t.homed = false;
    a.on_telemetry(&t);
    assert!(a.status.text.contains("pull the grip"), "{}", a.status.text);
    assert_eq!(a.handle_key(key('s')), vec![]);
    assert!(!a.scan_running);
    assert!(a.status.text.contains("not homed"), "{}", a.status.text);
    // Queued scans are refused the same way.
    a.handle_key(key('n'));
    assert_eq!(type_text(&mut a, "3"), vec![]);
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![]);
    assert!(!a.scan_running);
    let mut t = fixtures::telemetry(0.5, Mode::Manual);
    t.homed = true;
    a.on_telemetry(&t);
    assert!(a.status.text.contains("homed"), "{}", a.status.text);
    a.overlay = None;
    assert_eq!(a.handle_key(key('s')), vec![Action::StartScan]);
}

/// A console three scans into an automatic run of five (queued after an
/// earlier scan that is not stored).
fn queue_running() -> App {
    let mut a = app();
    a.on_scan_saved(fixtures::scan_view(false));
    a.handle_key(key('n'));
    assert_eq!(type_text(&mut a, "5"), vec![]);
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![Action::StartScan]);
    assert!(a.scan_running && a.queue_left == 4);
    a
}

#[test]
fn q_during_a_scan_or_a_queue_asks_before_quitting() {
    let mut a = app();
    a.handle_key(key('s'));
    assert_eq!(a.handle_key(key('q')), vec![], "q must not quit mid-scan");
    assert_eq!(a.overlay, Some(Overlay::ConfirmQuit));
    assert!(!a.quit);
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert!(a.overlay.is_none() && !a.quit && a.scan_running);
    assert!(
        a.status.text.contains("the scan goes on"),
        "{}",
        a.status.text
    );
    // During a queue too, and y quits.
    let mut b = queue_running();
    assert_eq!(b.handle_key(key('q')), vec![]);
    assert_eq!(b.overlay, Some(Overlay::ConfirmQuit));
    assert_eq!(b.handle_key(key('y')), vec![Action::Quit]);
    assert!(b.quit);
}

#[test]
fn esc_closes_a_form_or_the_help_without_touching_the_queue() {
    let mut a = queue_running();
    // The store form (the earlier scan is unsaved): a reflex Esc closes it.
    a.handle_key(key('w'));
    assert!(matches!(&a.overlay, Some(Overlay::Form(f)) if f.kind == FormKind::Store));
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert!(a.overlay.is_none());
    a.handle_key(key('?'));
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert!(a.overlay.is_none());
    assert!(a.scan_running && a.queued_run && a.queue_left == 4);
    // A second reflex Esc only asks; a third closes the question.
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert_eq!(a.overlay, Some(Overlay::ConfirmAbort));
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert!(a.overlay.is_none());
    assert!(a.scan_running && a.queued_run && a.queue_left == 4);
    // The footer says what Esc does now.
    let hints = crate::console::panels::footer::hints(&a);
    assert!(
        hints
            .iter()
            .any(|(k, what)| k == "Esc" && what.contains("abort scan + queue")),
        "{hints:?}"
    );
}

#[test]
fn the_abort_confirmation_aborts_the_scan_and_cancels_the_queue() {
    let mut a = queue_running();
    a.handle_key(code(KeyCode::Esc));
    a.handle_key(key('?'));
    assert!(a.overlay.is_none(), "any other key keeps scanning");
    assert!(a.queue_left == 4);
    a.handle_key(code(KeyCode::Esc));
    assert_eq!(a.handle_key(key('y')), vec![Action::Abort]);
    assert!(a.queue_left == 0 && !a.queued_run);
    assert!(
        a.status.text.contains("4 queued scan(s) cancelled"),
        "{}",
        a.status.text
    );
    a.on_servo_event(ServoEvent::ScanEnded {
        path: "x".into(),
        samples: 10,
        aborted: Some("aborted by the user".into()),
        stats: Default::default(),
    });
    assert!(
        a.status
            .text
            .contains("automatic scans stopped: 0 of 5 stored"),
        "{}",
        a.status.text
    );
    // With nothing running, Esc in Manual mode has nothing to abort.
    assert!(!a.scan_busy());
    assert_eq!(a.handle_key(code(KeyCode::Esc)), vec![]);
    assert!(a.overlay.is_none());
}

#[test]
fn a_label_in_another_case_is_the_profile_texture() {
    let mut a = app();
    a.handle_key(key('l'));
    type_text(&mut a, "s3");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::Mount("S3".into())]
    );
    assert_eq!(a.label, "S3");
    assert!(
        a.status.text.contains("as the profile spells s3"),
        "{}",
        a.status.text
    );
    // A near miss is suggested, not mounted.
    a.mounted = Some("S3".into());
    a.handle_key(key('l'));
    type_text(&mut a, "S33");
    assert_eq!(a.handle_key(code(KeyCode::Enter)), vec![]);
    assert_eq!(a.label, "S33");
    assert!(
        a.status.text.contains("did you mean S3?"),
        "{}",
        a.status.text
    );
}

#[test]
fn the_status_line_says_when_the_probe_reaches_the_target() {
    let mut a = app();
    a.handle_key(key('t'));
    type_text(&mut a, "1");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::SetTarget([0.01, 0.0, -0.06])]
    );
    assert!(a.status.text.contains("gliding"), "{}", a.status.text);
    // A frame sent before the servo took the target: still Manual.
    a.on_telemetry(&fixtures::telemetry(0.05, Mode::Manual));
    assert!(a.gliding_to.is_some(), "the glide goes on");
    let mut t = fixtures::telemetry(0.1, Mode::Target);
    t.pos_m = [0.004, 0.0, -0.06];
    t.setpoint_m = [0.005, 0.0, -0.06];
    a.on_telemetry(&t);
    assert!(a.status.text.contains("gliding"), "{}", a.status.text);
    // The set-point arrives; the probe rests 0.8 mm below it.
    t.pos_m = [0.01, -0.0008, -0.06];
    t.setpoint_m = [0.01, 0.0, -0.06];
    a.on_telemetry(&t);
    assert!(
        a.status
            .text
            .contains("the probe is at (1.00, -0.08, -6.00) cm")
            && a.status
                .text
                .contains("the target (1.00, 0.00, -6.00) cm, 0.8 mm from it"),
        "{}",
        a.status.text
    );
}

#[test]
fn an_unsaved_scan_from_an_earlier_session_can_be_stored() {
    let mut a = app();
    a.dataset.unsaved = 1;
    a.on_unsaved_found(fixtures::scan_view(false));
    assert!(
        a.status.text.contains("earlier session"),
        "{}",
        a.status.text
    );
    assert_eq!(a.dataset.unsaved, 1, "counted once");
    // Quitting does not ask about it again…
    assert!(!a.unsaved_scan());
    // …but w stores it, offering the label it was recorded under (S2,
    // not the session's S1); a label typed in another case is the profile's.
    assert_eq!(a.label, "S1");
    a.handle_key(key('w'));
    assert!(
        matches!(&a.overlay, Some(Overlay::Form(f)) if f.kind == FormKind::Store && f.value(0) == "S2")
    );
    type_text(&mut a, "s2");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::Store { label: "S2".into() }],
        "typed s2, stored as the profile's S2"
    );
    // A new scan of this session replaces it and is asked about again.
    a.on_scan_saved(fixtures::scan_view(false));
    assert!(a.unsaved_scan());
    a.on_unsaved_found(fixtures::scan_view(true));
    assert!(a.last_scan.as_ref().unwrap().prediction.is_none(), "kept");
}

/// Predict in a new session trains on a folder with nothing stored yet:
/// the error says what to do, with the keys in use.
#[test]
fn training_on_nothing_stored_says_to_store_scans_first() {
    let mut a = app();
    a.on_job(crate::console::dataset::JobResult::Failed {
        what: "train",
        error: "no recordings (*.csv, *.csv.gz) found in ds".into(),
    });
    assert!(
        a.status
            .text
            .contains("store scans of each texture first (w stores"),
        "{}",
        a.status.text
    );
    a.on_job(crate::console::dataset::JobResult::Failed {
        what: "evaluate",
        error: "no recordings (*.csv, *.csv.gz) found in ds".into(),
    });
    assert!(!a.status.text.contains("store scans"), "{}", a.status.text);
}
