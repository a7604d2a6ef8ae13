//! Placing an import's recordings: each input's recordings are staged in
//! a hidden folder under `--out` (`.import-<pid>`), then, once every input
//! is good, synced and moved in place, each by one atomic step that never
//! replaces a file unless `--force` says so, and then only a recording this
//! import wrote from the same input ([`Source::wrote`]). All of it runs
//! under the folder's import lock ([`LOCK_FILE`]), so two imports into one
//! folder never interleave their checks, placing and clean-up. Also removes
//! the staging folders of imports that were killed. Never prints.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::provenance::Source;
use super::{ImportError, Request, bad};
use crate::io::{move_no_replace, same_file_as};

/// The hidden file in `--out` whose lock one import at a time holds.
pub const LOCK_FILE: &str = ".hapticlab-import.lock";

/// One input converted into the staging folder, waiting to be moved in place.
pub(super) struct Staged {
    /// The input it was converted from.
    pub input: PathBuf,
    /// Where it goes, and the other name of the same recording (`.csv`
    /// beside `.csv.gz`), replaced with it under `--force`.
    pub path: PathBuf,
    pub other: PathBuf,
    /// With `--split`, on an input's first trial: the seconds at its end
    /// that no whole trial covers (left out); else 0.
    pub left_out_s: f64,
    pub staged: PathBuf,
    /// What the input was: who may be replaced under `--force`.
    pub source: Arc<Source>,
}

/// What an import placed, and what `--force` removed: recordings an
/// earlier import cut another way from the same inputs.
pub(super) struct Settled {
    pub written: Vec<PathBuf>,
    /// Each input with the recordings of its earlier cut removed.
    pub removed: Vec<(PathBuf, Vec<PathBuf>)>,
}

/// Remove the staging folders (`.import-<pid>`) of imports that were killed:
/// those whose process is gone. A running import's folder is left alone.
pub(super) fn remove_abandoned_staging(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(".import-"))
            .and_then(|p| p.parse::<libc::pid_t>().ok())
        else {
            continue;
        };
        // SAFETY: kill with signal 0 sends nothing; it only asks whether
        // the process exists (EPERM: it does, under another user).
        let alive = pid > 0
            && (unsafe { libc::kill(pid, 0) } == 0
                || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM));
        if !alive && entry.path().is_dir() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// The first failure in input order, or every staged recording synced and
/// moved in place; under `--force`, then the earlier cuts of the same
/// inputs removed.
pub(super) fn settle(
    args: &Request,
    staging: &Path,
    results: Vec<Option<Result<Vec<Staged>, ImportError>>>,
) -> Result<Settled, ImportError> {
    let mut staged: Vec<Staged> = Vec::new();
    // Where each recording goes: the index of the staged one going there.
    let mut places = std::collections::HashMap::new();
    for r in results {
        // A job not taken comes after a failure, which is met first.
        for s in r.ok_or_else(|| ImportError::Runtime("an input was skipped".into()))?? {
            if let Some(&first) = places.get(&s.path) {
                return Err(one_place_for_two(&staged[first], &s, args));
            }
            places.insert(s.path.clone(), staged.len());
            staged.push(s);
        }
    }
    if staged.is_empty() {
        return Ok(Settled {
            written: Vec::new(),
            removed: Vec::new(),
        });
    }
    crate::recording::sync_folder(staging).map_err(|e| ImportError::Runtime(e.to_string()))?;
    let written = place(&staged, args.force)?;
    let removed = if args.force {
        remove_other_cuts(&staged, &args.files)
    } else {
        Vec::new()
    };
    Ok(Settled { written, removed })
}

/// Two staged recordings bound for one place: both inputs named, and the
/// way to import them.
fn one_place_for_two(a: &Staged, b: &Staged, args: &Request) -> ImportError {
    let (ia, ib) = (a.input.display(), b.input.display());
    let same = a.input.canonicalize().ok();
    if same.is_some() && same == b.input.canonicalize().ok() {
        return bad(format!(
            "{ia} is given twice (also as {ib}): name each input once"
        ));
    }
    let way = match (super::folder_above(&a.input), super::folder_above(&b.input)) {
        (Some(fa), Some(fb)) if fa != fb && !args.prefix_parent => format!(
            "give --prefix-parent to begin each recording's name with the folder above its \
             input's ({fa}-…, {fb}-…), or import them in two runs into different --out folders"
        ),
        _ => "rename one of them, or import them in two runs into different --out folders"
            .to_string(),
    };
    bad(format!(
        "{ia} and {ib} would both be written to {}: {way}",
        a.path.display()
    ))
}

/// Moves every staged recording in place. Without `force` each move is
/// one atomic step that fails when the name is taken ([`move_no_replace`]),
/// so of two imports of the same names at once one gets each name; the one
/// that meets a name taken removes the recordings it placed itself and
/// refuses, naming it: a folder never ends with a mix of two batches.
fn place(staged: &[Staged], force: bool) -> Result<Vec<PathBuf>, ImportError> {
    let mut written = Vec::with_capacity(staged.len());
    for s in staged {
        if let Err(e) = place_one(s, force) {
            // Only ours go: each was placed by this run a moment ago.
            for p in &written {
                let _ = std::fs::remove_file(p);
            }
            return Err(e);
        }
        written.push(s.path.clone());
    }
    Ok(written)
}

fn place_one(s: &Staged, force: bool) -> Result<(), ImportError> {
    let fail = |p: &Path, e: std::io::Error| {
        ImportError::Runtime(format!("{}: {}", p.display(), crate::io::said(&e)))
    };
    if let Some(d) = s.path.parent() {
        std::fs::create_dir_all(d).map_err(|e| fail(d, e))?;
    }
    if force {
        // Checked again at the moment of replacing: only our own go.
        for p in [&s.path, &s.other] {
            if std::fs::symlink_metadata(p).is_ok() {
                s.source
                    .wrote(p)
                    .map_err(|why| not_ours(p, &s.input, &why))?;
            }
        }
        std::fs::rename(&s.staged, &s.path).map_err(|e| fail(&s.path, e))?;
        if std::fs::symlink_metadata(&s.other).is_ok() {
            std::fs::remove_file(&s.other).map_err(|e| fail(&s.other, e))?;
        }
        return Ok(());
    }
    let taken = |p: &Path| {
        bad(format!(
            "{}: already exists (placed by another import running at the same time, or there before); nothing was imported: import into another --out, or use --force to replace it",
            p.display()
        ))
    };
    match move_no_replace(&s.staged, &s.path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(taken(&s.path)),
        Err(e) => return Err(fail(&s.path, e)),
    }
    if std::fs::symlink_metadata(&s.other).is_ok() {
        // The same recording under its other name (.csv beside .csv.gz).
        let _ = std::fs::remove_file(&s.path);
        return Err(taken(&s.other));
    }
    Ok(())
}

/// `--force` met a file it may not replace: named, with why and what to do.
pub(super) fn not_ours(p: &Path, input: &Path, why: &str) -> ImportError {
    bad(format!(
        "{}: --force replaces only recordings imported from {}, and {why}; nothing was imported: move it away, or import into another --out",
        p.display(),
        input.display()
    ))
}

/// The recordings an earlier import made from the same input as `cut` (one
/// input's staged recordings), cut another way, that are not at the names
/// `cut` goes to: beside a whole `long.csv` its trials `long-seg001.csv` …,
/// beside trials the whole `long.csv` or the trials past this cut's count.
/// Only names of the input's stem (`<stem>.csv`, `<stem>-seg<digits>.csv`,
/// or `.csv.gz`) in the folder it goes to are looked at, and of those only
/// the recordings [`Source::wrote`] says import wrote from this input: never
/// a symlink, a file that is no recording, or another input's import.
pub(super) fn earlier_cuts(cut: &[Staged]) -> Vec<PathBuf> {
    use std::collections::HashSet;
    let Some(first) = cut.first() else {
        return Vec::new();
    };
    let (Some(dir), Some(stem)) = (
        first.path.parent(),
        first
            .path
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| trial_of(n).or_else(|| whole_of(n))),
    ) else {
        return Vec::new();
    };
    let ours: HashSet<&PathBuf> = cut.iter().flat_map(|s| [&s.path, &s.other]).collect();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut found: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str());
            !ours.contains(p)
                && name.is_some_and(|n| trial_of(n) == Some(stem) || whole_of(n) == Some(stem))
                && first.source.wrote(p).is_ok()
        })
        .collect();
    found.sort();
    found
}

/// After `--force` has placed `staged`: each input's earlier cuts
/// ([`earlier_cuts`]) removed, so the folder holds one cut of each input,
/// never two mixed (their windows would train and test on one signal).
/// Never one of `inputs` (a whole `long.csv` being cut is not an earlier
/// cut of itself). Returns the ones removed, input by input.
fn remove_other_cuts(staged: &[Staged], inputs: &[PathBuf]) -> Vec<(PathBuf, Vec<PathBuf>)> {
    let mut removed = Vec::new();
    for cut in staged.chunk_by(|a, b| a.input == b.input) {
        let gone: Vec<PathBuf> = earlier_cuts(cut)
            .into_iter()
            .filter(|p| {
                let is_input =
                    std::fs::metadata(p).is_ok_and(|m| same_file_as(&m, inputs).is_some());
                !is_input && std::fs::remove_file(p).is_ok()
            })
            .collect();
        if !gone.is_empty() {
            removed.push((cut[0].input.clone(), gone));
        }
    }
    removed
}

/// The stem of a recording's file name: `long.csv` (or `.csv.gz`): `long`.
fn whole_of(name: &str) -> Option<&str> {
    name.strip_suffix(".csv.gz")
        .or_else(|| name.strip_suffix(".csv"))
        .filter(|s| !s.is_empty())
}

/// The input's stem of a trial's file name: `long-seg016.csv` (or
/// `.csv.gz`): `long`.
fn trial_of(name: &str) -> Option<&str> {
    let (stem, number) = whole_of(name)?.rsplit_once(super::split::MARK)?;
    let digits = !number.is_empty() && number.bytes().all(|b| b.is_ascii_digit());
    (!stem.is_empty() && digits).then_some(stem)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A staged file `name` holding `text`, bound for `out/name`.
    fn staged(staging: &Path, out: &Path, name: &str, text: &str) -> Staged {
        std::fs::create_dir_all(staging).unwrap();
        let s = staging.join(name);
        std::fs::write(&s, text).unwrap();
        Staged {
            input: PathBuf::from(name),
            path: out.join(name),
            other: out.join(format!("{name}.gz")),
            left_out_s: 0.0,
            staged: s,
            source: Arc::new(Source::of(Path::new(name), name.as_bytes())),
        }
    }

    #[test]
    fn a_name_taken_while_placing_undoes_only_this_runs_files() {
        let dir = tempfile::tempdir().unwrap();
        let (staging, out) = (dir.path().join(".import-1"), dir.path().join("out"));
        let batch: Vec<Staged> = ["a.csv", "b.csv", "c.csv"]
            .iter()
            .map(|n| staged(&staging, &out, n, "ours"))
            .collect();
        // Another import placed c.csv after this one's check, before its move.
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("c.csv"), "theirs").unwrap();
        let e = place(&batch, false).unwrap_err();
        assert!(e.is_bad_input());
        assert!(
            e.to_string().contains("c.csv: already exists"),
            "{}",
            e.to_string()
        );
        let mut left: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["c.csv"]);
        assert_eq!(
            std::fs::read_to_string(out.join("c.csv")).unwrap(),
            "theirs"
        );
        // The other name of a recording placed is a collision too.
        let one = [staged(&staging, &out, "d.csv", "ours")];
        std::fs::write(out.join("d.csv.gz"), "theirs").unwrap();
        let e = place(&one, false).unwrap_err();
        assert!(
            e.to_string().contains("d.csv.gz: already exists"),
            "{}",
            e.to_string()
        );
        assert!(!out.join("d.csv").exists());
        // --force replaces only a recording import wrote from the same
        // input: "theirs" is no recording, and stays.
        let forced = [staged(&staging, &out, "c.csv", "ours")];
        let e = place(&forced, true).unwrap_err();
        assert!(e.to_string().contains("it is no recording"), "{e}");
        assert_eq!(
            std::fs::read_to_string(out.join("c.csv")).unwrap(),
            "theirs"
        );
    }
}
