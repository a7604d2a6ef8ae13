//! Overlays: the help screen, the quit confirmation, and small forms (the
//! target position, a label, a number of scans). A form edits text fields
//! and says when it is submitted or cancelled; what the text means is
//! checked by the app, which puts any error back on the form.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

#[derive(Debug, Clone, PartialEq)]
pub enum Overlay {
    Help,
    /// Quit although a scan is running or queued, or the last scan is not
    /// stored.
    ConfirmQuit,
    /// Abort the running scan (and the rest of a queue)?
    ConfirmAbort,
    Form(Form),
    /// The message log, newest first, scrolled by this many messages.
    Messages {
        scroll: usize,
    },
    /// Recent sessions to open, most recent first.
    Sessions(Vec<super::session::Session>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FormKind {
    /// x, y, z in cm.
    Target,
    /// The label to store the last scan under.
    Store,
    /// The label for the next scans (and the texture to mount).
    Label,
    /// How many scans to run and store.
    Queue,
    /// The replay browser: store the selected recording under a label
    /// (relabel a stored one, store an unsaved or excluded one).
    StoreAs,
    /// The replay browser: the label to jump to.
    Jump,
    /// The replay browser: show only this label's recordings (empty: all).
    Filter,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: &'static str,
    pub text: String,
    /// Still the prefilled value: the first character typed replaces it.
    pub prefilled: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Form {
    pub kind: FormKind,
    pub fields: Vec<Field>,
    pub focus: usize,
    /// What was wrong with the last submission.
    pub error: Option<String>,
    /// A line of explanation under the fields.
    pub hint: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FormOutcome {
    Editing,
    Cancel,
    Submit,
}

impl Form {
    fn new(kind: FormKind, fields: Vec<Field>, hint: String) -> Form {
        Form {
            kind,
            fields,
            focus: 0,
            error: None,
            hint,
        }
    }

    /// The target form, filled with `cm` (x, y, z).
    pub fn target(cm: [f64; 3], hint: String) -> Form {
        let f = |name, v: f64| Field {
            name,
            text: format!("{v:.2}"),
            prefilled: true,
        };
        Form::new(
            FormKind::Target,
            vec![f("x (cm)", cm[0]), f("y (cm)", cm[1]), f("z (cm)", cm[2])],
            hint,
        )
    }

    pub fn text(kind: FormKind, name: &'static str, value: &str, hint: String) -> Form {
        Form::new(
            kind,
            vec![Field {
                name,
                text: value.to_string(),
                prefilled: true,
            }],
            hint,
        )
    }

    pub fn title(&self) -> &'static str {
        match self.kind {
            FormKind::Target => "Target position",
            FormKind::Store => "Store the last scan",
            FormKind::Label => "Label for the next scans",
            FormKind::Queue => "Automatic scans",
            FormKind::StoreAs => "Store the recording under a label",
            FormKind::Jump => "Jump to a label",
            FormKind::Filter => "Show one label's recordings",
        }
    }

    pub fn value(&self, i: usize) -> &str {
        self.fields.get(i).map_or("", |f| f.text.trim())
    }

    /// Edit with a key: characters, Backspace, Tab/↑/↓ between fields,
    /// Enter submits, Esc cancels. The first character typed into a field
    /// that still holds its prefilled value replaces it; Backspace edits it.
    pub fn key(&mut self, ev: &KeyEvent) -> FormOutcome {
        let n = self.fields.len().max(1);
        match ev.code {
            KeyCode::Esc => return FormOutcome::Cancel,
            KeyCode::Enter => return FormOutcome::Submit,
            KeyCode::Tab | KeyCode::Down => self.focus = (self.focus + 1) % n,
            KeyCode::BackTab | KeyCode::Up => self.focus = (self.focus + n - 1) % n,
            KeyCode::Backspace => {
                if let Some(f) = self.fields.get_mut(self.focus) {
                    f.text.pop();
                    f.prefilled = false;
                }
            }
            KeyCode::Char('u') if ev.modifiers.contains(KeyModifiers::CONTROL) => {
                if let Some(f) = self.fields.get_mut(self.focus) {
                    f.text.clear();
                    f.prefilled = false;
                }
            }
            KeyCode::Char(c) if !ev.modifiers.contains(KeyModifiers::CONTROL) => {
                if let Some(f) = self.fields.get_mut(self.focus) {
                    if f.prefilled {
                        f.text.clear();
                        f.prefilled = false;
                    }
                    if f.text.chars().count() < 64 {
                        f.text.push(c);
                    }
                }
            }
            _ => {}
        }
        FormOutcome::Editing
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(code: KeyCode) -> KeyEvent {
        KeyEvent::new(code, KeyModifiers::NONE)
    }

    #[test]
    fn edits_fields_and_submits() {
        let mut f = Form::target([1.0, 2.0, -3.0], String::new());
        assert_eq!(f.value(2), "-3.00");
        f.key(&k(KeyCode::Tab));
        f.key(&k(KeyCode::Backspace));
        f.key(&k(KeyCode::Char('5')));
        assert_eq!(f.value(1), "2.05");
        assert_eq!(f.key(&k(KeyCode::Enter)), FormOutcome::Submit);
        assert_eq!(f.key(&k(KeyCode::Esc)), FormOutcome::Cancel);
    }

    #[test]
    fn the_first_key_replaces_the_prefilled_value() {
        let mut f = Form::target([1.0, 2.0, -3.0], String::new());
        f.key(&k(KeyCode::Char('4')));
        assert_eq!(f.value(0), "4");
        f.key(&k(KeyCode::Char('.')));
        f.key(&k(KeyCode::Char('5')));
        assert_eq!(f.value(0), "4.5", "only the first key replaces");
        // The next field is still prefilled: its first key replaces it too.
        f.key(&k(KeyCode::Tab));
        f.key(&k(KeyCode::Char('-')));
        f.key(&k(KeyCode::Char('1')));
        assert_eq!(f.value(1), "-1");
        // Backspace edits a prefilled value instead of clearing it.
        f.key(&k(KeyCode::Tab));
        f.key(&k(KeyCode::Backspace));
        f.key(&k(KeyCode::Char('5')));
        assert_eq!(f.value(2), "-3.05");
        let mut q = Form::text(FormKind::Queue, "scans", "5", String::new());
        q.key(&k(KeyCode::Char('3')));
        assert_eq!(q.value(0), "3", "not 53");
    }
}
