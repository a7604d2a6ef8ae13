//! The console's key map: which key does what.
//!
//! The defaults and the key syntax live in the profile module
//! ([`crate::profile::CONSOLE_ACTIONS`], [`crate::profile::parse_key`]) so a
//! profile's `[console] keys` table is validated with the rest of the
//! profile; this module turns those bindings into a lookup from terminal key
//! events to [`Key`] actions, and names the key of an action for the footer
//! and the help overlay. It never changes state and never does I/O.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use crate::profile::{ConsoleSettings, KeySpec};

/// What a key asks for; the app decides what it means in the current view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Key {
    Help,
    Quit,
    Mode,
    Target,
    Start,
    Abort,
    Store,
    Label,
    Queue,
    Predict,
    Train,
    Evaluate,
    Replay,
    Faster,
    Slower,
    Left,
    Right,
    Up,
    Down,
    Away,
    Toward,
    NextPage,
    PrevPage,
    Page(u8),
    Pause,
    Step,
    /// The recent sessions, to open one or start today's.
    Sessions,
    /// The message log.
    Messages,
    /// Curating, in the replay browser: the selected recording.
    Delete,
    Undo,
    Relabel,
    Exclude,
    /// Replay browser: to a label, to the next wrong prediction, a filter,
    /// the first and last recordings.
    Jump,
    NextWrong,
    Filter,
    First,
    Last,
}

impl Key {
    /// The action's name in `[console] keys`.
    pub fn from_name(name: &str) -> Option<Key> {
        Some(match name {
            "help" => Key::Help,
            "quit" => Key::Quit,
            "mode" => Key::Mode,
            "target" => Key::Target,
            "start" => Key::Start,
            "abort" => Key::Abort,
            "store" => Key::Store,
            "label" => Key::Label,
            "queue" => Key::Queue,
            "predict" => Key::Predict,
            "train" => Key::Train,
            "evaluate" => Key::Evaluate,
            "replay" => Key::Replay,
            "faster" => Key::Faster,
            "slower" => Key::Slower,
            "left" => Key::Left,
            "right" => Key::Right,
            "up" => Key::Up,
            "down" => Key::Down,
            "away" => Key::Away,
            "toward" => Key::Toward,
            "next_page" => Key::NextPage,
            "prev_page" => Key::PrevPage,
            "page_1" => Key::Page(1),
            "page_2" => Key::Page(2),
            "page_3" => Key::Page(3),
            "page_4" => Key::Page(4),
            "pause" => Key::Pause,
            "step" => Key::Step,
            "sessions" => Key::Sessions,
            "messages" => Key::Messages,
            "delete" => Key::Delete,
            "undo" => Key::Undo,
            "relabel" => Key::Relabel,
            "exclude" => Key::Exclude,
            "jump" => Key::Jump,
            "next_wrong" => Key::NextWrong,
            "filter" => Key::Filter,
            "first" => Key::First,
            "last" => Key::Last,
            _ => return None,
        })
    }
}

#[derive(Debug, Clone)]
pub struct KeyMap {
    bindings: Vec<(KeySpec, Key)>,
}

impl Default for KeyMap {
    fn default() -> Self {
        KeyMap::from_settings(&ConsoleSettings::default()).expect("the default keys are valid")
    }
}

impl KeyMap {
    /// The bindings of a (validated) profile's `[console]` section.
    pub fn from_settings(s: &ConsoleSettings) -> Result<KeyMap, String> {
        let pairs = s
            .bindings()
            .map_err(|e| format!("{}: {}", e.key, e.reason))?;
        let bindings = pairs
            .into_iter()
            .filter_map(|(name, spec)| Key::from_name(name).map(|k| (spec, k)))
            .collect();
        Ok(KeyMap { bindings })
    }

    /// The action bound to a key press, if any.
    pub fn lookup(&self, ev: &KeyEvent) -> Option<Key> {
        if ev.kind == KeyEventKind::Release {
            return None;
        }
        let spec = spec_of(ev)?;
        self.bindings
            .iter()
            .find(|(s, _)| *s == spec)
            .map(|(_, k)| *k)
    }

    /// How the key of `action` is written, for the footer and help.
    pub fn name(&self, action: Key) -> String {
        self.bindings
            .iter()
            .find(|(_, k)| *k == action)
            .map_or_else(|| "(none)".into(), |(s, _)| short(s))
    }
}

/// Short names for the footer: arrows as symbols, `PageUp` as `PgUp`.
fn short(s: &KeySpec) -> String {
    match s {
        KeySpec::Named("Up") => "↑".into(),
        KeySpec::Named("Down") => "↓".into(),
        KeySpec::Named("Left") => "←".into(),
        KeySpec::Named("Right") => "→".into(),
        KeySpec::Named("PageUp") => "PgUp".into(),
        KeySpec::Named("PageDown") => "PgDn".into(),
        KeySpec::Named("BackTab") => "S-Tab".into(),
        other => other.to_string(),
    }
}

/// The profile-syntax key of a terminal key event.
pub fn spec_of(ev: &KeyEvent) -> Option<KeySpec> {
    let named = |n: &'static str| Some(KeySpec::Named(n));
    match ev.code {
        KeyCode::Char(' ') => named("Space"),
        KeyCode::Char(c) if ev.modifiers.contains(KeyModifiers::CONTROL) => {
            Some(KeySpec::Ctrl(c.to_ascii_lowercase()))
        }
        KeyCode::Char(c) => Some(KeySpec::Char(c)),
        KeyCode::Esc => named("Esc"),
        KeyCode::Enter => named("Enter"),
        KeyCode::Tab => named("Tab"),
        KeyCode::BackTab => named("BackTab"),
        KeyCode::Backspace => named("Backspace"),
        KeyCode::Delete => named("Delete"),
        KeyCode::Insert => named("Insert"),
        KeyCode::Home => named("Home"),
        KeyCode::End => named("End"),
        KeyCode::Up => named("Up"),
        KeyCode::Down => named("Down"),
        KeyCode::Left => named("Left"),
        KeyCode::Right => named("Right"),
        KeyCode::PageUp => named("PageUp"),
        KeyCode::PageDown => named("PageDown"),
        KeyCode::F(n) => crate::profile::NAMED_KEYS
            .iter()
            .find(|k| **k == format!("F{n}"))
            .map(|k| KeySpec::Named(k)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn press(code: KeyCode, m: KeyModifiers) -> KeyEvent {
        KeyEvent::new(code, m)
    }

    #[test]
    fn defaults_follow_the_thesis_buttons() {
        let k = KeyMap::default();
        let none = KeyModifiers::NONE;
        assert_eq!(k.lookup(&press(KeyCode::Char('s'), none)), Some(Key::Start));
        assert_eq!(
            k.lookup(&press(KeyCode::Char('T'), KeyModifiers::SHIFT)),
            Some(Key::Train)
        );
        assert_eq!(k.lookup(&press(KeyCode::Esc, none)), Some(Key::Abort));
        assert_eq!(k.lookup(&press(KeyCode::Char(' '), none)), Some(Key::Pause));
        assert_eq!(k.lookup(&press(KeyCode::PageUp, none)), Some(Key::Away));
        assert_eq!(k.lookup(&press(KeyCode::Char('z'), none)), None);
        assert_eq!(k.name(Key::Up), "↑");
    }

    #[test]
    fn a_profile_can_rebind_keys() {
        let mut s = ConsoleSettings::default();
        s.keys.insert("start".into(), "F5".into());
        s.keys.insert("store".into(), "Ctrl-s".into());
        let k = KeyMap::from_settings(&s).unwrap();
        let none = KeyModifiers::NONE;
        assert_eq!(k.lookup(&press(KeyCode::F(5), none)), Some(Key::Start));
        assert_eq!(k.lookup(&press(KeyCode::Char('s'), none)), None);
        assert_eq!(
            k.lookup(&press(KeyCode::Char('s'), KeyModifiers::CONTROL)),
            Some(Key::Store)
        );
        assert_eq!(k.name(Key::Store), "Ctrl-s");
        s.keys.insert("quit".into(), "F5".into());
        assert!(
            KeyMap::from_settings(&s)
                .unwrap_err()
                .contains("bound to both")
        );
    }
}
