//! Tune's mark in a tuned profile: which recordings the search chose its
//! lines on (a fingerprint of their labels and file names), under which
//! validation, and the outer estimate to quote. Written as one comment
//! line (`# tuned_on = { … }`), so the profile stays the same TOML, and
//! read back when the profile is loaded, so `evaluate` of the profile on
//! those same recordings can say which figure to quote.

use serde::{Deserialize, Serialize};

use super::sha256_hex;

/// The comment line's start.
const MARK: &str = "# tuned_on = ";

/// What `tune` searched, as its tuned profile records it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TunedOn {
    /// Recordings searched.
    pub recordings: usize,
    /// [`fingerprint`] of them.
    pub fingerprint: String,
    /// The outer validation, as `evaluate` describes its plan.
    pub validation: String,
    /// Whether the outer split was a holdout: `evaluate` with the same
    /// plan tests the same part, never seen by the search.
    pub holdout: bool,
    /// The outer estimate (0..1): the figure to quote.
    pub outer_estimate: f64,
}

impl TunedOn {
    /// The comment line that records it.
    pub fn line(&self) -> String {
        let table = toml::to_string(self).unwrap_or_default();
        format!("{MARK}{}", inline_table(&table))
    }

    /// The mark in a profile's text, when it has one that reads.
    pub fn find(text: &str) -> Option<TunedOn> {
        let line = text.lines().find(|l| l.starts_with(MARK))?;
        let doc: toml::Table = toml::from_str(&format!("t = {}", &line[MARK.len()..])).ok()?;
        doc.get("t")?.clone().try_into().ok()
    }
}

/// A TOML table's text on one line (`{ a = 1, b = "x" }`).
fn inline_table(text: &str) -> String {
    let pairs: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    format!("{{ {} }}", pairs.join(", "))
}

/// A set of recordings' fingerprint: the first 16 hex digits of the
/// SHA-256 of their distinct `label<TAB>file name` lines, sorted (the
/// folder they sit in does not count, so a copied or moved set keeps it;
/// a recording's sub-windows count once).
pub fn fingerprint<'a>(recordings: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    let mut lines: Vec<String> = recordings
        .into_iter()
        .map(|(label, file)| {
            let name = std::path::Path::new(file)
                .file_name()
                .map_or(file.to_string(), |n| n.to_string_lossy().into_owned());
            format!("{label}\t{name}\n")
        })
        .collect();
    lines.sort_unstable();
    lines.dedup();
    let hex = sha256_hex(lines.concat().as_bytes());
    hex[..16.min(hex.len())].to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mark_reads_back_from_a_profile() {
        let mark = TunedOn {
            recordings: 45,
            fingerprint: fingerprint([("a", "x/a-1.csv"), ("b", "b-1.csv")]),
            validation: "5-fold cross-validation (seed 0)".into(),
            holdout: false,
            outer_estimate: 0.9556,
        };
        let line = mark.line();
        assert!(
            line.starts_with("# tuned_on = { ") && !line.contains('\n'),
            "{line}"
        );
        let text = format!("name = \"t\"\n\n# --- hapticlab tune ---\n{line}\n# more\n");
        assert_eq!(TunedOn::find(&text), Some(mark));
        assert_eq!(TunedOn::find("name = \"t\"\n# tuned_on = { what }\n"), None);
        assert_eq!(TunedOn::find("name = \"t\"\n"), None);
    }

    #[test]
    fn a_fingerprint_is_of_labels_and_names_not_folders_or_order() {
        let a = fingerprint([("a", "/x/a-1.csv"), ("b", "/x/b-1.csv")]);
        assert_eq!(a, fingerprint([("b", "b-1.csv"), ("a", "y/a-1.csv")]));
        assert_ne!(a, fingerprint([("a", "a-1.csv")]));
        let windows = [("a", "a-1.csv"), ("a", "a-1.csv"), ("b", "b-1.csv")];
        assert_eq!(a, fingerprint(windows));
        assert_ne!(a, fingerprint([("b", "a-1.csv"), ("a", "b-1.csv")]));
        assert_eq!(a.len(), 16);
    }
}
