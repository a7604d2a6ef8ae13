//! Curating a dataset folder: each change is a file operation a user could
//! do by hand, and each can be undone.
//!
//! - delete: the recording moves to `<dataset>/.trash/` (same relative path);
//! - exclude: it moves to `<dataset>/.excluded/` (same relative path), which
//!   training, evaluation and every command skip as they skip any hidden
//!   folder; excluding an excluded one puts it back;
//! - relabel, and storing a scan from `.unsaved/` or `.excluded/`: it is
//!   stored as `<dataset>/<label>/<label>_NNN.csv` (its `label` rewritten),
//!   the original kept in `.trash/` for the undo.
//!
//! Nothing here prints or knows the screen.

use std::path::{Path, PathBuf};

use super::live;

pub const TRASH_DIR: &str = ".trash";
pub const EXCLUDED_DIR: &str = ".excluded";

/// A change asked for.
#[derive(Debug, Clone, PartialEq)]
pub enum Change {
    Delete(PathBuf),
    /// Exclude from training, or put back when already excluded.
    Exclude(PathBuf),
    /// Store under this label (relabel a stored one, store an unsaved or
    /// excluded one).
    Store {
        file: PathBuf,
        label: String,
    },
}

/// A change made: how to undo it, and what it did in words.
#[derive(Debug, Clone, PartialEq)]
pub struct Done {
    /// Where the recording is now (none once deleted).
    pub now: Option<PathBuf>,
    /// Files to move back (from, to), in order, to undo it.
    pub moves_back: Vec<(PathBuf, PathBuf)>,
    /// A file the change created, removed by the undo.
    pub created: Option<PathBuf>,
    pub what: String,
}

/// A free path: `p`, or `p` with `-2`, `-3`, … before its extension.
fn free(p: PathBuf) -> PathBuf {
    if !p.exists() {
        return p;
    }
    let name = p
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let (stem, ext) = name.split_once('.').unwrap_or((&name, ""));
    (2..)
        .map(|i| p.with_file_name(format!("{stem}-{i}.{ext}")))
        .find(|q| !q.exists())
        .expect("an unbounded range has a free name")
}

fn relative<'a>(file: &'a Path, dataset: &Path) -> Result<&'a Path, String> {
    file.strip_prefix(dataset).map_err(|_| {
        format!(
            "{} is not in the dataset folder {}",
            file.display(),
            dataset.display()
        )
    })
}

fn rename(from: &Path, to: &Path) -> Result<(), String> {
    if let Some(d) = to.parent() {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    std::fs::rename(from, to)
        .map_err(|e| format!("cannot move {} to {}: {e}", from.display(), to.display()))
}

/// The scans in `.unsaved/` and `.excluded/` (which the loader skips), to
/// list for curating: complete scans first, the incomplete ones last.
pub fn hidden_scans(dataset: &Path) -> impl Iterator<Item = PathBuf> {
    let dirs = [
        dataset.join(super::dataset::UNSAVED_DIR),
        dataset.join(EXCLUDED_DIR),
    ];
    let mut files: Vec<PathBuf> = dirs
        .iter()
        .filter(|d| d.is_dir())
        .flat_map(|d| {
            // The folder itself is hidden: list what is inside it.
            std::fs::read_dir(d)
                .into_iter()
                .flatten()
                .filter_map(Result::ok)
                .map(|e| e.path())
                .collect::<Vec<_>>()
        })
        .flat_map(|p| crate::recording::collect_files(&[p]).unwrap_or_default())
        .collect();
    files.sort_by_key(|f| (!complete(f), f.clone()));
    files.into_iter()
}

/// Whether a recording ended complete (its trailer), read cheaply.
pub fn complete(file: &Path) -> bool {
    crate::recording::read(file).is_ok_and(|r| r.is_complete())
}

/// Whether `file` is excluded (under `<dataset>/.excluded/`).
pub fn is_excluded(file: &Path, dataset: &Path) -> bool {
    file.strip_prefix(dataset.join(EXCLUDED_DIR)).is_ok()
}

/// Carry out a change in `dataset`.
pub fn apply(change: &Change, dataset: &Path) -> Result<Done, String> {
    match change {
        Change::Delete(file) => {
            let to = free(dataset.join(TRASH_DIR).join(relative(file, dataset)?));
            rename(file, &to)?;
            Ok(Done {
                now: None,
                what: format!("deleted {} (kept in {})", file.display(), to.display()),
                moves_back: vec![(to, file.clone())],
                created: None,
            })
        }
        Change::Exclude(file) => {
            let rel = relative(file, dataset)?;
            let (to, what) = match rel.strip_prefix(EXCLUDED_DIR) {
                Ok(back) => (free(dataset.join(back)), "put back for training"),
                Err(_) => (
                    free(dataset.join(EXCLUDED_DIR).join(rel)),
                    "excluded from training",
                ),
            };
            rename(file, &to)?;
            Ok(Done {
                what: format!("{} {what}: now {}", file.display(), to.display()),
                now: Some(to.clone()),
                moves_back: vec![(to, file.clone())],
                created: None,
            })
        }
        Change::Store { file, label } => {
            // The original to the trash first: the undo puts it back as it was.
            let kept = free(dataset.join(TRASH_DIR).join(relative(file, dataset)?));
            if let Some(d) = kept.parent() {
                std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
            }
            std::fs::copy(file, &kept).map_err(|e| {
                format!("cannot keep {} in {}: {e}", file.display(), kept.display())
            })?;
            let to = match live::store(file, dataset, label) {
                Ok(to) => to,
                Err(e) => {
                    let _ = std::fs::remove_file(&kept);
                    return Err(e);
                }
            };
            Ok(Done {
                what: format!("stored {} as {}", file.display(), to.display()),
                now: Some(to.clone()),
                moves_back: vec![(kept, file.clone())],
                created: Some(to),
            })
        }
    }
}

/// Undo a change; what was undone, in words.
pub fn undo(done: &Done) -> Result<String, String> {
    if let Some(c) = &done.created {
        std::fs::remove_file(c).map_err(|e| format!("cannot remove {}: {e}", c.display()))?;
    }
    for (from, to) in &done.moves_back {
        if to.exists() {
            return Err(format!("{} exists again: not overwritten", to.display()));
        }
        rename(from, to)?;
    }
    Ok(format!("undone: {}", done.what))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recorder::COLUMNS;
    use crate::recording::RecordingWriter;

    fn scan(path: &Path, label: &str) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let meta = vec![("label".to_string(), toml::Value::String(label.into()))];
        let mut w = RecordingWriter::create(path, &meta, &COLUMNS).unwrap();
        w.write_row(&vec![0.0; COLUMNS.len()]).unwrap();
        w.finish().unwrap();
    }

    fn training_files(ds: &Path) -> Vec<PathBuf> {
        crate::recording::collect_files(&[ds.to_path_buf()]).unwrap()
    }

    #[test]
    fn delete_exclude_and_relabel_are_moves_the_loader_honours_and_each_undoes() {
        let d = tempfile::tempdir().unwrap();
        let ds = d.path();
        let a = ds.join("S1/S1_001.csv");
        scan(&a, "S1");
        assert_eq!(training_files(ds), vec![a.clone()]);

        let done = apply(&Change::Delete(a.clone()), ds).unwrap();
        assert!(!a.exists() && ds.join(".trash/S1/S1_001.csv").exists());
        assert!(training_files(ds).is_empty(), "the trash is skipped");
        undo(&done).unwrap();
        assert_eq!(training_files(ds), vec![a.clone()]);

        let done = apply(&Change::Exclude(a.clone()), ds).unwrap();
        let excluded = ds.join(".excluded/S1/S1_001.csv");
        assert_eq!(done.now.as_ref(), Some(&excluded));
        assert!(training_files(ds).is_empty(), "the excluded are skipped");
        assert!(is_excluded(&excluded, ds));
        let back = apply(&Change::Exclude(excluded.clone()), ds).unwrap();
        assert_eq!(back.now, Some(a.clone()));
        undo(&back).unwrap();
        undo(&done).unwrap();
        assert_eq!(training_files(ds), vec![a.clone()]);

        let done = apply(
            &Change::Store {
                file: a.clone(),
                label: "S2".into(),
            },
            ds,
        )
        .unwrap();
        let b = ds.join("S2/S2_001.csv");
        assert_eq!(done.now.as_ref(), Some(&b));
        assert_eq!(crate::recording::read(&b).unwrap().label(), Some("S2"));
        assert_eq!(training_files(ds), vec![b.clone()]);
        undo(&done).unwrap();
        assert_eq!(training_files(ds), vec![a.clone()]);
        assert_eq!(crate::recording::read(&a).unwrap().label(), Some("S1"));
    }
}
