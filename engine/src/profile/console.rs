//! `[console]`: the lab console's key bindings — the actions, their default
//! keys, and how a key is written. Schema and checks only; the console
//! (`crate::console`) reads its bindings from here.

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use super::{Invalid, bad};

/// The lab console's settings: `[console]` in a profile.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ConsoleSettings {
    /// Key bindings that replace the defaults, action name → key, e.g.
    /// `keys = { start = "F5", store = "Ctrl-s" }`. Actions are listed in
    /// [`CONSOLE_ACTIONS`]; keys are written as [`parse_key`] reads them.
    #[serde(default)]
    pub keys: BTreeMap<String, String>,
}

/// The console's actions and their default keys.
pub const CONSOLE_ACTIONS: &[(&str, &str)] = &[
    ("help", "?"),
    ("quit", "q"),
    ("mode", "m"),
    ("target", "t"),
    ("start", "s"),
    ("abort", "Esc"),
    ("store", "w"),
    ("label", "l"),
    ("queue", "n"),
    ("predict", "p"),
    ("train", "T"),
    ("evaluate", "e"),
    ("replay", "r"),
    ("faster", "+"),
    ("slower", "-"),
    ("left", "Left"),
    ("right", "Right"),
    ("up", "Up"),
    ("down", "Down"),
    ("away", "PageUp"),
    ("toward", "PageDown"),
    ("next_page", "Tab"),
    ("prev_page", "BackTab"),
    ("page_1", "1"),
    ("page_2", "2"),
    ("page_3", "3"),
    ("page_4", "4"),
    ("pause", "Space"),
    ("step", "."),
    ("sessions", "S"),
    ("messages", "M"),
    ("delete", "d"),
    ("undo", "u"),
    ("relabel", "R"),
    ("exclude", "x"),
    ("jump", "j"),
    ("next_wrong", "W"),
    ("filter", "f"),
    ("first", "Home"),
    ("last", "End"),
];

/// The named (non-character) keys a binding may use.
pub const NAMED_KEYS: &[&str] = &[
    "Esc",
    "Enter",
    "Tab",
    "BackTab",
    "Space",
    "Backspace",
    "Delete",
    "Insert",
    "Home",
    "End",
    "Up",
    "Down",
    "Left",
    "Right",
    "PageUp",
    "PageDown",
    "F1",
    "F2",
    "F3",
    "F4",
    "F5",
    "F6",
    "F7",
    "F8",
    "F9",
    "F10",
    "F11",
    "F12",
];

/// One key as a profile writes it: a character (`s`, `T`, `+`), a named
/// key (`Esc`, `PageUp`, `F5`), or `Ctrl-` and a letter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KeySpec {
    Char(char),
    Named(&'static str),
    Ctrl(char),
}

impl fmt::Display for KeySpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeySpec::Char(c) => write!(f, "{c}"),
            KeySpec::Named(n) => write!(f, "{n}"),
            KeySpec::Ctrl(c) => write!(f, "Ctrl-{c}"),
        }
    }
}

/// Read a key as written in `[console] keys`. Ctrl-C is reserved (it always quits).
pub fn parse_key(text: &str) -> Result<KeySpec, String> {
    let mut chars = text.chars();
    if let (Some(c), None) = (chars.next(), chars.next()) {
        if c.is_control() || c == ' ' {
            return Err(format!(
                "{text:?} is a control character; write \"Space\" or a named key"
            ));
        }
        return Ok(KeySpec::Char(c));
    }
    if let Some(rest) = text
        .strip_prefix("Ctrl-")
        .or_else(|| text.strip_prefix("ctrl-"))
    {
        let mut cs = rest.chars();
        return match (cs.next(), cs.next()) {
            (Some(c), None) if c.is_ascii_alphabetic() => {
                let c = c.to_ascii_lowercase();
                if c == 'c' {
                    Err("Ctrl-C is reserved: it always quits".into())
                } else {
                    Ok(KeySpec::Ctrl(c))
                }
            }
            _ => Err(format!(
                "{text:?}: Ctrl- takes one letter, as in \"Ctrl-s\""
            )),
        };
    }
    NAMED_KEYS
        .iter()
        .find(|n| n.eq_ignore_ascii_case(text))
        .map(|n| KeySpec::Named(n))
        .ok_or_else(|| {
            format!(
                "{text:?} is not a key: write one character, Ctrl-<letter>, or one of {}",
                NAMED_KEYS.join(", ")
            )
        })
}

impl ConsoleSettings {
    /// Every action with its key: the defaults, overridden by `keys`.
    pub fn bindings(&self) -> Result<Vec<(&'static str, KeySpec)>, Invalid> {
        for name in self.keys.keys() {
            if !CONSOLE_ACTIONS.iter().any(|(a, _)| a == name) {
                return bad(
                    format!("console.keys.{name}"),
                    format!(
                        "no such console action; the actions are {}",
                        CONSOLE_ACTIONS
                            .iter()
                            .map(|(a, _)| *a)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
                .map(|()| Vec::new());
            }
        }
        let mut out: Vec<(&'static str, KeySpec)> = Vec::with_capacity(CONSOLE_ACTIONS.len());
        // Where a binding was written: its own entry, or the defaults.
        let entry = |action: &str| {
            if self.keys.contains_key(action) {
                format!("console.keys.{action}")
            } else {
                "console.keys".to_string()
            }
        };
        for (action, default) in CONSOLE_ACTIONS {
            let text = self.keys.get(*action).map_or(*default, String::as_str);
            let spec = parse_key(text).map_err(|reason| Invalid {
                key: entry(action),
                reason,
            })?;
            if let Some((other, _)) = out.iter().find(|(_, s)| *s == spec) {
                // A remapped key may land on another action's default
                // (the defaults grow): name the entry the user wrote, and
                // say which binding is a default.
                let how = |a: &str| {
                    if self.keys.contains_key(a) {
                        format!("console.keys.{a}")
                    } else {
                        format!("{a}'s default key")
                    }
                };
                let written = if self.keys.contains_key(*action) {
                    action
                } else {
                    other
                };
                return Err(Invalid {
                    key: entry(written),
                    reason: format!(
                        "key {spec} is bound to both {other:?} ({}) and {action:?} ({}); give one of them another key",
                        how(other),
                        how(action)
                    ),
                });
            }
            out.push((action, spec));
        }
        Ok(out)
    }
}
