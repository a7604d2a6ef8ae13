//! Keys in the replay browser: playing a recording, moving through the list
//! (a row, a page, the ends, a label, the next wrong prediction, a filter by
//! label), and curating the dataset (delete, undo, relabel, exclude, store).

use super::super::curate::{self, Change};
use super::super::form::{Form, FormKind, Overlay};
use super::super::keymap::Key;
use super::{Action, App, Source};

/// Rows PgUp/PgDn move in the list.
pub const PAGE_ROWS: usize = 10;

impl App {
    pub(super) fn replay_key(&mut self, k: Key) -> Vec<Action> {
        let standalone = self.source == Source::ReplayOnly;
        match k {
            Key::Quit => return self.quit_key(),
            Key::Abort | Key::Replay => {
                if standalone {
                    let q = self.key_name(Key::Quit);
                    self.info(format!("{q} quits"));
                } else {
                    self.replay = None;
                    self.info("back to the live device");
                }
            }
            Key::Up | Key::Down | Key::Away | Key::Toward | Key::First | Key::Last => {
                return self.list_move(k);
            }
            Key::NextWrong => return self.next_wrong(),
            Key::Jump | Key::Filter => self.label_form(k),
            Key::Delete | Key::Exclude | Key::Relabel | Key::Store => return self.curate_key(k),
            Key::Undo => return vec![Action::UndoCurate],
            Key::Predict => return self.predict_key(),
            Key::Pause
            | Key::Step
            | Key::Right
            | Key::Left
            | Key::Start
            | Key::Faster
            | Key::Slower => {
                self.player_key(k);
            }
            _ => {
                let back = self.key_name(Key::Abort);
                self.info(if standalone {
                    "replay: ↑/↓ PgUp/PgDn Home/End recordings, space pause, +/- speed, . step"
                        .to_string()
                } else {
                    format!("replaying: {back} returns to the live device first")
                });
            }
        }
        vec![]
    }

    fn player_key(&mut self, k: Key) {
        let Some(p) = self.replay.as_mut().and_then(|r| r.player.as_mut()) else {
            return;
        };
        match k {
            Key::Pause if p.finished() => {
                p.restart(&mut self.replay_feed);
                p.paused = false;
            }
            Key::Pause => p.paused = !p.paused,
            Key::Step | Key::Right => p.step(&mut self.replay_feed),
            Key::Left | Key::Start => p.restart(&mut self.replay_feed),
            Key::Faster => p.faster(),
            _ => p.slower(),
        }
    }

    /// ↑/↓ a row, PgUp/PgDn a page, Home/End the ends, among the recordings shown.
    fn list_move(&mut self, k: Key) -> Vec<Action> {
        let Some(r) = self.replay.as_ref() else {
            return vec![];
        };
        let shown = r.visible();
        let Some(last) = shown.len().checked_sub(1) else {
            return vec![];
        };
        let at = shown.iter().position(|&i| i >= r.selected).unwrap_or(last);
        let to = match k {
            Key::Up => at.saturating_sub(1),
            Key::Down => (at + 1).min(last),
            Key::Away => at.saturating_sub(PAGE_ROWS),
            Key::Toward => (at + PAGE_ROWS).min(last),
            Key::First => 0,
            _ => last,
        };
        self.open_entry(shown[to])
    }

    fn open_entry(&mut self, i: usize) -> Vec<Action> {
        let Some(r) = self.replay.as_mut() else {
            return vec![];
        };
        if i != r.selected || r.player.is_none() {
            r.selected = i;
            return vec![Action::OpenRecording(i)];
        }
        vec![]
    }

    /// The next recording shown whose prediction is wrong, after the selected one.
    fn next_wrong(&mut self) -> Vec<Action> {
        let Some(r) = self.replay.as_ref() else {
            return vec![];
        };
        let shown = r.visible();
        let after = shown.iter().filter(|&&i| i > r.selected);
        let before = shown.iter().filter(|&&i| i <= r.selected);
        let wrong = after
            .chain(before)
            .copied()
            .find(|&i| r.entries[i].right() == Some(false));
        match wrong {
            Some(i) => {
                let e = &r.entries[i];
                let text = format!(
                    "{}: recorded as {}, predicted {}",
                    e.path.display(),
                    e.label.as_deref().unwrap_or("?"),
                    e.predicted.as_deref().unwrap_or("?")
                );
                self.info(text);
                self.open_entry(i)
            }
            None if r.listing => {
                self.info("still predicting the recordings: try again in a moment");
                vec![]
            }
            None => {
                self.info("no wrong prediction among the recordings shown");
                vec![]
            }
        }
    }

    fn label_form(&mut self, k: Key) {
        let (kind, value, hint) = if k == Key::Jump {
            (
                FormKind::Jump,
                String::new(),
                "a label; Enter jumps to its first recording",
            )
        } else {
            let current = self
                .replay
                .as_ref()
                .and_then(|r| r.filter.clone())
                .unwrap_or_default();
            (
                FormKind::Filter,
                current,
                "a label; empty shows every recording",
            )
        };
        self.overlay = Some(Overlay::Form(Form::text(
            kind,
            "label",
            &value,
            hint.into(),
        )));
    }

    /// A submitted jump or filter form.
    pub(super) fn jump_or_filter(
        &mut self,
        kind: FormKind,
        label: &str,
    ) -> Result<Vec<Action>, String> {
        let label = self.profile_spelling(label);
        let Some(r) = self.replay.as_mut() else {
            return Ok(vec![]);
        };
        if kind == FormKind::Filter {
            r.filter = (!label.is_empty()).then(|| label.clone());
            let n = r.visible().len();
            if label.is_empty() {
                self.info(format!("showing all {n} recordings"));
                return Ok(vec![]);
            }
            if n == 0 {
                r.filter = None;
                return Err(format!("no recording labelled {label}"));
            }
            self.info(format!("showing the {n} recordings of {label}"));
        }
        let Some(r) = self.replay.as_ref() else {
            return Ok(vec![]);
        };
        let first = r
            .visible()
            .into_iter()
            .find(|&i| r.entries[i].label_or_folder() == label);
        match first {
            Some(i) => Ok(self.open_entry(i)),
            None => Err(format!("no recording labelled {label}")),
        }
    }

    /// Curating the selected recording: the change, or the form it needs.
    fn curate_key(&mut self, k: Key) -> Vec<Action> {
        let dataset = self.dataset.dir.clone();
        let Some(e) = self.replay.as_ref().and_then(|r| r.entries.get(r.selected)) else {
            self.info("no recording selected");
            return vec![];
        };
        if e.path.strip_prefix(&dataset).is_err() {
            self.warn(format!(
                "{} is not in the dataset folder {}: curate it by hand",
                e.path.display(),
                dataset.display()
            ));
            return vec![];
        }
        let (file, label) = (e.path.clone(), e.label_or_folder());
        let unsaved = e.unsaved(&dataset);
        match k {
            Key::Delete => vec![Action::Curate(Change::Delete(file))],
            Key::Exclude if unsaved => {
                self.info(format!(
                    "{} is not stored, so not trained on: {} stores it",
                    file.display(),
                    self.key_name(Key::Store)
                ));
                vec![]
            }
            Key::Exclude => vec![Action::Curate(Change::Exclude(file))],
            _ => {
                let what = if unsaved || curate::is_excluded(&file, &dataset) {
                    "stored"
                } else {
                    "moved"
                };
                let hint = format!(
                    "{what} as {}/<label>/<label>_NNN.csv; Enter ok, Esc cancel",
                    dataset.display()
                );
                self.overlay = Some(Overlay::Form(Form::text(
                    FormKind::StoreAs,
                    "label",
                    &label,
                    hint,
                )));
                vec![]
            }
        }
    }

    /// A curating change was made (or failed): the list follows the file
    /// (with `label`, the label it was stored under), and the model no
    /// longer matches the dataset.
    pub fn on_curated(
        &mut self,
        from: &std::path::Path,
        label: Option<&str>,
        result: Result<(Option<std::path::PathBuf>, String), String>,
    ) {
        match result {
            Ok((now, what)) => {
                self.dataset.edits += 1;
                if let Some(r) = self.replay.as_mut() {
                    r.moved(Some(from), now.as_deref(), label);
                }
                let undo = self.key_name(Key::Undo);
                self.info(format!("{what}; {undo} undoes it"));
            }
            Err(e) => self.error(e),
        }
    }
}
