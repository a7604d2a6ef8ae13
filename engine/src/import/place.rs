//! Placing an import's recordings: each input's recordings are staged in
//! a hidden folder under `--out` (`.import-<pid>`), then, once every input
//! is good, synced and moved in place, each by one atomic step that never
//! replaces a recording unless `--force` says so. Also removes the staging
//! folders of imports that were killed. Never prints.

use std::path::{Path, PathBuf};

use super::{ImportError, Request, bad};
use crate::recording::files::{move_no_replace, same_file_as};

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
/// moved in place.
pub(super) fn settle(
    args: &Request,
    staging: &Path,
    results: Vec<Option<Result<Vec<Staged>, ImportError>>>,
) -> Result<Vec<PathBuf>, ImportError> {
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
        return Ok(Vec::new());
    }
    crate::recording::sync_folder(staging).map_err(|e| ImportError::Runtime(e.to_string()))?;
    place(&staged, args.force)
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
    let fail = |p: &Path, e: std::io::Error| ImportError::Runtime(format!("{}: {e}", p.display()));
    if let Some(d) = s.path.parent() {
        std::fs::create_dir_all(d).map_err(|e| fail(d, e))?;
    }
    if force {
        std::fs::rename(&s.staged, &s.path).map_err(|e| fail(&s.path, e))?;
        if s.other.exists() {
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
    if s.other.exists() {
        // The same recording under its other name (.csv beside .csv.gz).
        let _ = std::fs::remove_file(&s.path);
        return Err(taken(&s.other));
    }
    Ok(())
}

/// After `--force`: the recordings an earlier import made from inputs of
/// the same names, cut another way, that this one did not write again:
/// beside a whole `long.csv` its trials `long-seg001.csv` …, beside trials
/// the whole `long.csv` or the trials past this cut's count (an earlier,
/// shorter `--split` left `long-seg016` … `long-seg030` where this one
/// wrote 15). Removed so the folder holds one cut of each input, never two
/// mixed (their windows would train and test on one signal). Only
/// `<stem>.csv`, `<stem>-seg<digits>.csv` (or `.csv.gz`) beside a
/// recording this run placed are touched, and never one of `inputs` (a
/// whole `long.csv` being cut is not an earlier cut of itself). Returns
/// the ones removed.
pub(super) fn remove_other_cuts(
    placed: &[PathBuf],
    split: bool,
    inputs: &[PathBuf],
) -> Vec<PathBuf> {
    use std::collections::{BTreeMap, BTreeSet, HashSet};
    let ours: HashSet<&PathBuf> = placed.iter().collect();
    // The input stems of the recordings placed, by folder: each folder is
    // read once.
    let mut cuts: BTreeMap<&Path, BTreeSet<&str>> = BTreeMap::new();
    for p in placed {
        let name = p.file_name().and_then(|n| n.to_str());
        let stem = if split {
            name.and_then(trial_of)
        } else {
            name.and_then(whole_of)
        };
        if let (Some(dir), Some(stem)) = (p.parent(), stem) {
            cuts.entry(dir).or_default().insert(stem);
        }
    }
    let mut removed = Vec::new();
    for (dir, stems) in cuts {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut other: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                let name = p.file_name().and_then(|n| n.to_str());
                !ours.contains(p)
                    && std::fs::metadata(p)
                        .is_ok_and(|m| m.is_file() && same_file_as(&m, inputs).is_none())
                    && name.is_some_and(|n| {
                        trial_of(n).is_some_and(|s| stems.contains(s))
                            || whole_of(n).is_some_and(|s| stems.contains(s))
                    })
            })
            .collect();
        other.sort();
        for p in other {
            if std::fs::remove_file(&p).is_ok() {
                removed.push(p);
            }
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
        // With --force the batch replaces.
        let forced = [staged(&staging, &out, "c.csv", "ours")];
        assert_eq!(place(&forced, true).unwrap(), [out.join("c.csv")]);
        assert_eq!(std::fs::read_to_string(out.join("c.csv")).unwrap(), "ours");
    }
}
