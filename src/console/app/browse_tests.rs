//! The replay browser's keys as state transitions: moving through a long
//! list, to a label, to the next wrong prediction, a filter by label, and
//! the curating keys' actions; the message log.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use super::{Action, App, LOG_LIMIT, Source};
use crate::console::curate::Change;
use crate::console::dataset::ReplayEntry;
use crate::console::form::Overlay;
use crate::console::keymap::KeyMap;
use crate::console::replay::Replay;
use crate::profile::LoadedProfile;

fn key(c: char) -> KeyEvent {
    let m = if c.is_ascii_uppercase() {
        KeyModifiers::SHIFT
    } else {
        KeyModifiers::NONE
    };
    KeyEvent::new(KeyCode::Char(c), m)
}
fn code(c: KeyCode) -> KeyEvent {
    KeyEvent::new(c, KeyModifiers::NONE)
}

/// The replay browser on 120 recordings, 30 a texture, S1…S4, every fifth
/// of S3's predicted S4 (the others right).
fn browsing() -> App {
    let mut a = App::new(
        LoadedProfile::thesis(),
        KeyMap::default(),
        Source::ReplayOnly,
        "ds".into(),
    );
    let files = (0..120)
        .map(|i| format!("ds/S{}/S{}_{:03}.csv", i / 30 + 1, i / 30 + 1, i % 30 + 1).into())
        .collect();
    let mut r = Replay::new("ds".into(), files);
    for (i, e) in r.entries.iter_mut().enumerate() {
        let label = format!("S{}", i / 30 + 1);
        e.predicted = Some(if label == "S3" && i % 5 == 0 {
            "S4".into()
        } else {
            label.clone()
        });
        e.label = Some(label);
    }
    a.replay = Some(r);
    a
}

fn selected(a: &App) -> usize {
    a.replay.as_ref().unwrap().selected
}

fn entry(a: &App) -> &ReplayEntry {
    let r = a.replay.as_ref().unwrap();
    &r.entries[r.selected]
}

fn type_text(a: &mut App, text: &str) -> Vec<Action> {
    text.chars().flat_map(|c| a.handle_key(key(c))).collect()
}

#[test]
fn pages_and_ends_move_through_a_long_list() {
    let mut a = browsing();
    assert_eq!(
        a.handle_key(code(KeyCode::PageDown)),
        vec![Action::OpenRecording(10)]
    );
    assert_eq!(
        a.handle_key(code(KeyCode::End)),
        vec![Action::OpenRecording(119)]
    );
    assert_eq!(
        a.handle_key(code(KeyCode::PageUp)),
        vec![Action::OpenRecording(109)]
    );
    assert_eq!(
        a.handle_key(code(KeyCode::Home)),
        vec![Action::OpenRecording(0)]
    );
}

#[test]
fn j_jumps_to_a_label_and_w_to_the_next_wrong_prediction() {
    let mut a = browsing();
    a.handle_key(key('j'));
    assert!(matches!(a.overlay, Some(Overlay::Form(_))));
    // Typed in lower case: the profile spells it S4.
    let actions = type_text(&mut a, "s4");
    assert!(actions.is_empty());
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::OpenRecording(90)]
    );
    assert_eq!(entry(&a).label.as_deref(), Some("S4"));
    a.handle_key(code(KeyCode::Home));
    // S3's wrong ones: 60, 65, …, 85; then round to the first again.
    for want in [60, 65, 70, 75, 80, 85, 60] {
        assert_eq!(a.handle_key(key('W')), vec![Action::OpenRecording(want)]);
        assert!(a.status.text.contains("predicted S4"), "{}", a.status.text);
    }
    a.handle_key(key('j'));
    type_text(&mut a, "S9");
    a.handle_key(code(KeyCode::Enter));
    match &a.overlay {
        Some(Overlay::Form(f)) => assert_eq!(f.error.as_deref(), Some("no recording labelled S9")),
        o => panic!("the form stays open with the error: {o:?}"),
    }
}

#[test]
fn f_filters_by_label_and_moves_stay_inside_the_filter() {
    let mut a = browsing();
    a.handle_key(key('f'));
    type_text(&mut a, "S2");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::OpenRecording(30)]
    );
    assert_eq!(a.replay.as_ref().unwrap().visible().len(), 30);
    assert_eq!(
        a.handle_key(code(KeyCode::End)),
        vec![Action::OpenRecording(59)]
    );
    a.handle_key(code(KeyCode::Down));
    assert_eq!(selected(&a), 59, "the filter's end");
    assert_eq!(a.handle_key(key('W')), vec![], "no wrong S2");
    // An empty filter shows them all again.
    a.handle_key(key('f'));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Backspace));
    a.handle_key(code(KeyCode::Enter));
    assert_eq!(a.replay.as_ref().unwrap().visible().len(), 120);
    assert_eq!(selected(&a), 59);
}

#[test]
fn curating_keys_ask_for_file_changes() {
    let mut a = browsing();
    a.handle_key(code(KeyCode::End));
    let file = entry(&a).path.clone();
    assert_eq!(
        a.handle_key(key('d')),
        vec![Action::Curate(Change::Delete(file.clone()))]
    );
    assert_eq!(
        a.handle_key(key('x')),
        vec![Action::Curate(Change::Exclude(file.clone()))]
    );
    assert_eq!(a.handle_key(key('u')), vec![Action::UndoCurate]);
    a.handle_key(key('R'));
    type_text(&mut a, "S1");
    assert_eq!(
        a.handle_key(code(KeyCode::Enter)),
        vec![Action::Curate(Change::Store {
            file,
            label: "S1".into()
        })]
    );
}

/// A relabelled recording shows its new label beside the prediction it
/// had (the same samples), takes its place in file-name order, and stays
/// selected; a deleted one leaves the list.
#[test]
fn a_relabelled_recording_shows_its_new_label_in_file_order() {
    let mut a = browsing();
    a.handle_key(code(KeyCode::Home));
    let from = entry(&a).path.clone();
    let to: std::path::PathBuf = "ds/S3/S3_031.csv".into();
    a.on_curated(
        &from,
        Some("S3"),
        Ok((Some(to.clone()), "relabelled".into())),
    );
    let r = a.replay.as_ref().unwrap();
    assert_eq!(r.entries.len(), 120);
    assert!(r.entries.windows(2).all(|w| w[0].path < w[1].path));
    let e = entry(&a);
    assert_eq!(e.path, to);
    assert_eq!(e.label.as_deref(), Some("S3"));
    assert_eq!(
        e.predicted.as_deref(),
        Some("S1"),
        "the model's verdict on it"
    );
    assert_eq!(e.right(), Some(false));
    assert_eq!(selected(&a), 89, "after S3_030, before S4_001");
    // Excluding keeps the label; deleting removes the entry.
    let to2: std::path::PathBuf = "ds/.excluded/S3/S3_031.csv".into();
    a.on_curated(&to, None, Ok((Some(to2.clone()), "excluded".into())));
    assert_eq!(entry(&a).path, to2);
    assert_eq!(entry(&a).label.as_deref(), Some("S3"));
    a.on_curated(&to2, None, Ok((None, "deleted".into())));
    assert_eq!(a.replay.as_ref().unwrap().entries.len(), 119);
}

#[test]
fn the_log_keeps_every_message_newest_last_and_the_status_line_the_newest() {
    let mut a = browsing();
    for i in 0..LOG_LIMIT + 10 {
        a.info(format!("message {i}"));
    }
    a.info(format!("message {}", LOG_LIMIT + 9));
    assert_eq!(
        a.log.len(),
        LOG_LIMIT,
        "kept up to the limit, a repeat once"
    );
    assert_eq!(
        a.log.last().unwrap().text,
        format!("message {}", LOG_LIMIT + 9)
    );
    assert_eq!(a.status.text, format!("message {}", LOG_LIMIT + 9));
    a.handle_key(key('M'));
    assert_eq!(a.overlay, Some(Overlay::Messages { scroll: 0 }));
    a.handle_key(code(KeyCode::Down));
    assert_eq!(a.overlay, Some(Overlay::Messages { scroll: 1 }));
    a.handle_key(key('q'));
    assert_eq!(a.overlay, None, "any other key closes the log");
    assert!(!a.quit);
}

#[test]
fn the_quit_dialogs_w_stores_the_scan_then_quits() {
    let mut a = App::new(
        LoadedProfile::thesis(),
        KeyMap::default(),
        Source::Live {
            backend: "sim".into(),
        },
        "ds".into(),
    );
    a.last_scan = Some(crate::console::fixtures::scan_view(false));
    assert!(a.unsaved_scan());
    a.handle_key(key('q'));
    assert_eq!(a.overlay, Some(Overlay::ConfirmQuit));
    a.handle_key(key('w'));
    assert!(
        matches!(a.overlay, Some(Overlay::Form(_))),
        "the label is asked"
    );
    let actions = a.handle_key(code(KeyCode::Enter));
    assert!(
        matches!(actions.as_slice(), [Action::Store { .. }]),
        "{actions:?}"
    );
    assert!(!a.quit, "not before the scan is stored");
    a.on_stored(Ok("ds/S1/S1_001.csv".into()));
    assert!(a.quit, "stored, then quit");
}
