//! Sessions in the app: saying a session was resumed, the list of recent
//! sessions (`S`), and picking one or starting today's.

use std::time::SystemTime;

use ratatui::crossterm::event::{KeyCode, KeyEvent};

use super::super::form::Overlay;
use super::super::keymap::Key;
use super::super::session::{self, Session};
use super::{Action, App};

/// Sessions the list shows (picked with 1-9).
pub const LISTED: usize = 9;

impl App {
    /// The folder sessions are made in: the current dataset's.
    pub fn sessions_root(&self) -> std::path::PathBuf {
        self.dataset
            .dir
            .parent()
            .map_or_else(|| ".".into(), std::path::Path::to_path_buf)
    }

    /// The console opened an earlier session's folder (no `--dataset`).
    pub fn on_resumed(&mut self, s: &Session, now: SystemTime) {
        self.info(format!(
            "resumed {} (last used {}, {} stored): {} lists sessions, or starts today's",
            s.dir.display(),
            s.age(now),
            s.recordings,
            self.key_name(Key::Sessions)
        ));
    }

    pub(super) fn sessions_key(&mut self) -> Vec<Action> {
        let mut list = session::recent(&self.sessions_root());
        list.truncate(LISTED);
        self.overlay = Some(Overlay::Sessions(list));
        vec![]
    }

    /// A key in the sessions list: 1-9 opens that session, n today's new one.
    pub(super) fn sessions_pick(&mut self, list: Vec<Session>, ev: &KeyEvent) -> Vec<Action> {
        let dir = match ev.code {
            KeyCode::Char('n') => session::today(&self.sessions_root(), SystemTime::now()),
            KeyCode::Char(c @ '1'..='9') => match list.get(c as usize - '1' as usize) {
                Some(s) => s.dir.clone(),
                None => {
                    self.overlay = Some(Overlay::Sessions(list));
                    return vec![];
                }
            },
            _ => {
                self.info(format!("staying in {}", self.dataset.dir.display()));
                return vec![];
            }
        };
        if dir == self.dataset.dir {
            self.info(format!("already in {}", dir.display()));
            return vec![];
        }
        vec![Action::OpenDataset(dir)]
    }

    /// The runtime switched the dataset folder: forget the old one's state.
    pub fn on_dataset_opened(&mut self, dir: std::path::PathBuf) {
        self.dataset = super::super::dataset::DatasetView {
            dir,
            ..Default::default()
        };
        self.model = None;
        self.last_scan = None;
        self.last_scan_earlier = false;
        self.replay = None;
        // The built-in profile is `thesis` in session.toml; a file, its full path.
        let origin = std::path::Path::new(&self.profile.origin);
        let same = |p: &std::path::Path| {
            (p.as_os_str() == "thesis" && self.profile.origin.starts_with("<built-in"))
                || std::fs::canonicalize(p).ok() == std::fs::canonicalize(origin).ok() && p.exists()
        };
        let profile = session::profile_of(&self.dataset.dir)
            .filter(|p| !same(p))
            .map(|p| {
                format!(
                    " (recorded under profile {}: `hapticlab --dataset DIR` loads it)",
                    p.display()
                )
            })
            .unwrap_or_default();
        let new = if self.dataset.dir.is_dir() {
            ""
        } else {
            "new "
        };
        self.info(format!(
            "{new}session {}{profile}",
            self.dataset.dir.display()
        ));
    }
}
