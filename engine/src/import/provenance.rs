//! Which input a recording was imported from, so `--force` can tell the
//! recordings an import itself wrote from an input from every other file:
//! a notes CSV with a trial's name, a simulator's recording, a symlink, or
//! the import of another file with the same name.
//!
//! Every recording an import writes says in its metadata where it came
//! from: `source` (the path as given), `source_path` (the same file's full
//! path), `source_bytes` and `source_sha256` (what it held). A file is an
//! earlier import of an input when it is a regular file (not a symlink), a
//! recording with `device = "import"`, and either its `source_path` is the
//! input's full path (the same file, perhaps edited since) or its `source`
//! is the input's path as given and its content matches (imports older
//! than these keys: the path as given alone). Never prints.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// What an import knows of one input.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The path as given on the command line.
    pub given: String,
    /// Its full path (`None` when it cannot be resolved).
    pub path: Option<PathBuf>,
    pub bytes: u64,
    /// SHA-256 of its bytes, in hex.
    pub sha256: String,
}

impl Source {
    /// The input at `given`, whose bytes are `bytes`.
    pub fn of(given: &Path, bytes: &[u8]) -> Source {
        Source {
            given: given.display().to_string(),
            path: std::fs::canonicalize(given).ok(),
            bytes: bytes.len() as u64,
            sha256: hex(&Sha256::digest(bytes)),
        }
    }

    /// The metadata every recording made from this input carries.
    pub fn meta(&self) -> Vec<(String, toml::Value)> {
        let mut m = vec![(
            "source".to_string(),
            toml::Value::String(self.given.clone()),
        )];
        if let Some(p) = &self.path {
            m.push((
                "source_path".into(),
                toml::Value::String(p.display().to_string()),
            ));
        }
        m.push((
            "source_bytes".into(),
            // A file above 2^63 bytes is not read: no wrap.
            toml::Value::Integer(i64::try_from(self.bytes).unwrap_or(i64::MAX)),
        ));
        m.push((
            "source_sha256".into(),
            toml::Value::String(self.sha256.clone()),
        ));
        m
    }

    /// `Ok` when `file` is a recording an import wrote from this input;
    /// else why not, in words that finish "… is not an import of INPUT:".
    pub fn wrote(&self, file: &Path) -> Result<(), String> {
        let m = std::fs::symlink_metadata(file).map_err(|e| e.to_string())?;
        if m.file_type().is_symlink() {
            return Err("it is a symlink".into());
        }
        if !m.is_file() {
            return Err(format!("it is a {}", crate::io::kind_of(&m)));
        }
        let Some(meta) = header(file) else {
            return Err("it is no recording".into());
        };
        let text = |k: &str| meta.get(k).and_then(toml::Value::as_str);
        if text("device") != Some("import") {
            return Err(match text("device") {
                Some(d) => format!("it is a recording of device {d:?}, not an import"),
                None => "it is a recording that names no device, not an import".into(),
            });
        }
        let same_place = match (text("source_path"), &self.path) {
            (Some(p), Some(ours)) => Path::new(p) == ours,
            _ => false,
        };
        let same_name = text("source") == Some(self.given.as_str());
        let same_content = match text("source_sha256") {
            Some(h) => h == self.sha256,
            // An import from before these keys: the path as given decides.
            None => text("source_path").is_none(),
        };
        if same_place || (same_name && same_content) {
            return Ok(());
        }
        Err(match text("source") {
            Some(s) if same_name => format!("it was imported from another file also given as {s}"),
            Some(s) => format!("it was imported from {s}"),
            None => "it names no source".into(),
        })
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A recording's header lines (`# key = value`) as a table, read from its
/// first 64 KiB (plain or gzipped), through the one reader; `None` when
/// `path` is not a regular file or not a recording.
fn header(path: &Path) -> Option<toml::Table> {
    let head = crate::io::read_head(path, 64 << 10)?;
    let text = String::from_utf8_lossy(&head);
    let mut lines = text.lines();
    if lines.next()? != crate::io::FORMAT_LINE {
        return None;
    }
    let mut table = toml::Table::new();
    for line in lines {
        let Some(kv) = line.strip_prefix("# ") else {
            break;
        };
        if let Ok(t) = kv.parse::<toml::Table>() {
            table.extend(t);
        }
    }
    Some(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(path: &Path, meta: &[(&str, &str)]) {
        let mut text = format!("{}\n", crate::io::FORMAT_LINE);
        for (k, v) in meta {
            text.push_str(&format!("# {k} = {v:?}\n"));
        }
        text.push_str("t_s,ch1\n0,1\n# end samples = 1\n");
        std::fs::write(path, text).unwrap();
    }

    #[test]
    fn only_an_import_of_the_same_input_is_one_of_ours() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("long.txt");
        std::fs::write(&input, "1\n2\n").unwrap();
        let src = Source::of(&input, b"1\n2\n");
        let given = src.given.clone();
        let full = src.path.clone().unwrap().display().to_string();
        let ours = dir.path().join("ours.csv");
        recording(
            &ours,
            &[
                ("device", "import"),
                ("source", &given),
                ("source_sha256", &src.sha256),
            ],
        );
        assert_eq!(src.wrote(&ours), Ok(()));
        // Edited since: the same file by its full path.
        let edited = dir.path().join("edited.csv");
        recording(
            &edited,
            &[
                ("device", "import"),
                ("source", "elsewhere/long.txt"),
                ("source_path", &full),
                ("source_sha256", "00"),
            ],
        );
        assert_eq!(src.wrote(&edited), Ok(()));
        let other = dir.path().join("other.csv");
        recording(
            &other,
            &[("device", "import"), ("source", "other/S1/long.txt")],
        );
        assert!(src.wrote(&other).unwrap_err().contains("other/S1/long.txt"));
        let sim = dir.path().join("sim.csv");
        recording(&sim, &[("device", "sim")]);
        assert!(src.wrote(&sim).unwrap_err().contains("\"sim\""));
        let notes = dir.path().join("notes.csv");
        std::fs::write(&notes, "what,when\nrecalibrated,monday\n").unwrap();
        assert_eq!(src.wrote(&notes), Err("it is no recording".into()));
        let link = dir.path().join("link.csv");
        std::os::unix::fs::symlink(&ours, &link).unwrap();
        assert_eq!(src.wrote(&link), Err("it is a symlink".into()));
        // Same name as given, other content, no full path: another file.
        let moved = dir.path().join("moved.csv");
        recording(
            &moved,
            &[
                ("device", "import"),
                ("source", &given),
                ("source_sha256", "ff"),
            ],
        );
        assert!(src.wrote(&moved).is_err());
    }
}
