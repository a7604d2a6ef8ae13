//! Sessions: which dataset folder the console opens without `--dataset`,
//! and what a session's folder remembers.
//!
//! A session is a folder `recordings/session-<date>`. Without `--dataset`
//! the console opens today's folder when it exists, or else the most
//! recently used session folder of the last [`RESUME_DAYS`] days (and says
//! so: `S` lists the recent sessions, with today's new one to pick); a lab
//! on its second day carries on where it stopped. A session's folder holds
//! `session.toml` ([`SESSION_FILE`]), naming the profile it was recorded
//! under, beside `model.json`; reading files only, this module never
//! prints.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// The file that names a session's profile, inside its folder.
pub const SESSION_FILE: &str = "session.toml";
/// A session folder used within these many days is resumed.
pub const RESUME_DAYS: u64 = 7;
/// Where session folders are made.
pub const SESSIONS_ROOT: &str = "recordings";
const PREFIX: &str = "session-";

/// A session folder, and when it was last used.
#[derive(Debug, Clone, PartialEq)]
pub struct Session {
    pub dir: PathBuf,
    pub last_used: SystemTime,
    /// Recordings stored in it.
    pub recordings: usize,
}

impl Session {
    /// "3 h ago", "2 days ago".
    pub fn age(&self, now: SystemTime) -> String {
        ago(self.last_used, now)
    }
}

/// How long before `now` `then` was: "just now", "3 h ago", "2 days ago".
pub fn ago(then: SystemTime, now: SystemTime) -> String {
    let s = now.duration_since(then).unwrap_or_default().as_secs();
    match s {
        0..120 => "just now".into(),
        120..7200 => format!("{} min ago", s / 60),
        7200..172_800 => format!("{} h ago", s / 3600),
        _ => format!("{} days ago", s / 86_400),
    }
}

/// Today's session folder under `root`: `session-<date>`.
pub fn today(root: &Path, now: SystemTime) -> PathBuf {
    let stamp = humantime::format_rfc3339(now).to_string();
    root.join(format!("{PREFIX}{}", &stamp[..10]))
}

/// When a folder was last used: the newest change to it, its label folders,
/// its `.unsaved/` or its files one level down (a scan stored, a model saved).
fn last_used(dir: &Path) -> Option<SystemTime> {
    let mtime = |p: &Path| std::fs::metadata(p).ok()?.modified().ok();
    let mut newest = mtime(dir)?;
    for e in std::fs::read_dir(dir).ok()?.filter_map(Result::ok) {
        if let Some(t) = mtime(&e.path()) {
            newest = newest.max(t);
        }
    }
    Some(newest)
}

/// The session folders under `root`, most recently used first.
pub fn recent(root: &Path) -> Vec<Session> {
    let Ok(rd) = std::fs::read_dir(root) else {
        return vec![];
    };
    let mut out: Vec<Session> = rd
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(PREFIX))
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .filter_map(|dir| {
            let last_used = last_used(&dir)?;
            let recordings = super::dataset::count(&dir).0.iter().map(|(_, n)| n).sum();
            Some(Session {
                dir,
                last_used,
                recordings,
            })
        })
        .collect();
    out.sort_by(|a, b| b.last_used.cmp(&a.last_used).then(b.dir.cmp(&a.dir)));
    out
}

/// The folder to open without `--dataset`: today's when it exists, else
/// the most recent session used in the last [`RESUME_DAYS`] days (`Some`
/// session: say so), else today's new one.
pub fn choose(root: &Path, now: SystemTime) -> (PathBuf, Option<Session>) {
    let today = today(root, now);
    if today.is_dir() {
        return (today, None);
    }
    let window = Duration::from_secs(RESUME_DAYS * 86_400);
    match recent(root).into_iter().next() {
        Some(s) if now.duration_since(s.last_used).unwrap_or_default() <= window => {
            (s.dir.clone(), Some(s))
        }
        _ => (today, None),
    }
}

/// The profile a session's folder was recorded under (`session.toml`'s
/// `profile`), when it names one.
pub fn profile_of(dir: &Path) -> Option<PathBuf> {
    let text = std::fs::read_to_string(dir.join(SESSION_FILE)).ok()?;
    let v: toml::Table = text.parse().ok()?;
    v.get("profile")?.as_str().map(PathBuf::from)
}

/// Note the profile in the session's folder (once the folder exists: the
/// first scan makes it). A file a user could write by hand.
pub fn remember(dir: &Path, profile: &str) -> std::io::Result<()> {
    if !dir.is_dir() || profile_of(dir).as_deref() == Some(Path::new(profile)) {
        return Ok(());
    }
    let mut t = toml::Table::new();
    t.insert("profile".into(), toml::Value::String(profile.into()));
    let text = format!(
        "# The profile this session's scans were recorded under: `hapticlab --dataset {}` loads it\n{}",
        dir.display(),
        toml::to_string(&t).unwrap_or_default()
    );
    std::fs::write(dir.join(SESSION_FILE), text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch_session(root: &Path, name: &str, age: Duration) -> PathBuf {
        let dir = root.join(name);
        std::fs::create_dir_all(dir.join("S1")).unwrap();
        let t = SystemTime::now() - age;
        for p in [dir.join("S1"), dir.clone()] {
            std::fs::File::open(&p).unwrap().set_modified(t).unwrap();
        }
        dir
    }

    #[test]
    fn yesterdays_session_is_resumed_and_an_old_one_is_not() {
        let tmp = tempfile::tempdir().unwrap();
        let now = SystemTime::now();
        let day = Duration::from_secs(86_400);
        let old = touch_session(tmp.path(), "session-2020-01-01", day * 30);
        let (dir, resumed) = choose(tmp.path(), now);
        assert_eq!(
            dir,
            today(tmp.path(), now),
            "a month-old session is not resumed"
        );
        assert!(resumed.is_none());
        let yesterday = touch_session(tmp.path(), "session-2020-01-02", day + day / 16);
        // 25.5 h ago, less the moments since `now`.
        let (dir, resumed) = choose(tmp.path(), now);
        assert_eq!(dir, yesterday);
        assert_eq!(resumed.unwrap().age(now), "25 h ago");
        assert_eq!(
            recent(tmp.path())
                .iter()
                .map(|s| s.dir.clone())
                .collect::<Vec<_>>(),
            vec![yesterday, old]
        );
        std::fs::create_dir_all(today(tmp.path(), now)).unwrap();
        assert_eq!(choose(tmp.path(), now), (today(tmp.path(), now), None));
    }

    #[test]
    fn a_session_remembers_its_profile() {
        let tmp = tempfile::tempdir().unwrap();
        assert_eq!(profile_of(tmp.path()), None);
        remember(tmp.path(), "profiles/thesis.toml").unwrap();
        assert_eq!(
            profile_of(tmp.path()),
            Some(PathBuf::from("profiles/thesis.toml"))
        );
        remember(&tmp.path().join("missing"), "x").unwrap();
        assert!(!tmp.path().join("missing").exists());
    }
}
