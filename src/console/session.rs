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

/// What a session folder's `session.toml` says.
#[derive(Debug, Clone, PartialEq)]
pub enum SessionFile {
    /// There is none.
    Absent,
    /// It names the profile the folder's scans were recorded under.
    Names(PathBuf),
    /// It is there but cannot be read as a session file: why, in words.
    /// It is kept as it is; the console says so on its status line.
    Unreadable(String),
}

/// A session file is a line or two: anything longer is not one.
const SESSION_FILE_MAX: u64 = 64 << 10;

/// Reads `dir`'s `session.toml` through the one reader (a regular file
/// only, never waited on; a FIFO or a folder there is unreadable).
pub fn read(dir: &Path) -> SessionFile {
    let path = dir.join(SESSION_FILE);
    if std::fs::symlink_metadata(&path).is_err() {
        return SessionFile::Absent;
    }
    let unreadable = |why: String| SessionFile::Unreadable(format!("{}: {why}", path.display()));
    let bytes = match crate::io::read_input_at_most(&path, SESSION_FILE_MAX) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return unreadable("a symlink that leads nowhere".into());
        }
        Err(e) => return unreadable(e.to_string()),
    };
    let Ok(text) = String::from_utf8(bytes) else {
        return unreadable("not UTF-8 text".into());
    };
    let table: toml::Table = match text.parse() {
        Ok(t) => t,
        Err(e) => {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].lines().count().max(1));
            return unreadable(match line {
                Some(l) => format!("not TOML (line {l}: {})", e.message()),
                None => format!("not TOML ({})", e.message()),
            });
        }
    };
    match table.get("profile") {
        Some(toml::Value::String(p)) if !p.is_empty() => SessionFile::Names(PathBuf::from(p)),
        Some(_) => unreadable("its `profile` is not the name or path of a profile".into()),
        None => unreadable("it names no `profile`".into()),
    }
}

/// The profile a session's folder was recorded under (`session.toml`'s
/// `profile`), when it names one.
pub fn profile_of(dir: &Path) -> Option<PathBuf> {
    match read(dir) {
        SessionFile::Names(p) => Some(p),
        _ => None,
    }
}

/// Note the profile in the session's folder (once the folder exists: the
/// first scan makes it). A file a user could write by hand. Through the one
/// writer: a new file is created no-clobber; one naming another profile is
/// replaced by a rename (never written through a symlink, never a
/// recording); one that cannot be read is kept as it is.
pub fn remember(dir: &Path, profile: &str) -> Result<(), String> {
    if !dir.is_dir() {
        return Ok(());
    }
    let existing = match read(dir) {
        SessionFile::Absent => crate::io::Existing::Keep,
        SessionFile::Names(p) if p == Path::new(profile) => return Ok(()),
        SessionFile::Names(_) => crate::io::Existing::Replace,
        SessionFile::Unreadable(why) => return Err(format!("{why}; kept as it is")),
    };
    let mut t = toml::Table::new();
    t.insert("profile".into(), toml::Value::String(profile.into()));
    let text = format!(
        "# The profile this session's scans were recorded under: `hapticlab --dataset {}` loads it\n{}",
        dir.display(),
        toml::to_string(&t).unwrap_or_default()
    );
    crate::io::write_output(&dir.join(SESSION_FILE), &[], existing, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())
    })
    .map_err(|e| e.to_string())
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
        // Another profile given: the file is replaced by a rename.
        remember(tmp.path(), "thesis").unwrap();
        assert_eq!(profile_of(tmp.path()), Some(PathBuf::from("thesis")));
    }

    /// A session file that cannot be read is said and kept as it is: a
    /// symlink to a recording elsewhere is never written through, a FIFO
    /// never waited on, a corrupt file never replaced.
    #[test]
    fn a_session_file_that_cannot_be_read_is_named_and_kept() {
        let tmp = tempfile::tempdir().unwrap();
        let elsewhere = tmp.path().join("rec.csv");
        let rec = format!("{}\n# label = \"S1\"\nt_s,z_m\n", crate::io::FORMAT_LINE);
        std::fs::write(&elsewhere, &rec).unwrap();
        let linked = tmp.path().join("linked");
        std::fs::create_dir(&linked).unwrap();
        std::os::unix::fs::symlink(&elsewhere, linked.join(SESSION_FILE)).unwrap();
        let fifo = tmp.path().join("fifo");
        std::fs::create_dir(&fifo).unwrap();
        let c = std::ffi::CString::new(fifo.join(SESSION_FILE).to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let corrupt = tmp.path().join("corrupt");
        std::fs::create_dir(&corrupt).unwrap();
        std::fs::write(corrupt.join(SESSION_FILE), "profile = \"lab\n").unwrap();
        for (dir, said) in [
            (&linked, "not TOML"),
            (&fifo, "FIFO"),
            (&corrupt, "not TOML (line 1"),
        ] {
            let SessionFile::Unreadable(why) = read(dir) else {
                panic!("{dir:?}: {:?}", read(dir));
            };
            assert!(why.contains(said), "{why}");
            let e = remember(dir, "thesis").unwrap_err();
            assert!(e.contains("kept as it is"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&elsewhere).unwrap(), rec);
        assert!(
            std::fs::symlink_metadata(linked.join(SESSION_FILE))
                .unwrap()
                .is_symlink()
        );
        assert_eq!(
            std::fs::read_to_string(corrupt.join(SESSION_FILE)).unwrap(),
            "profile = \"lab\n"
        );
    }
}
