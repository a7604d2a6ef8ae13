//! Which hapticlab made a file: the package version and the commit it was
//! built from (named by `build.rs`). [`SOFTWARE`] is what `--version`
//! prints and what every recording's `software` key, every model's
//! `software_version` and every tuned profile's comment block say, so a
//! result can be traced to the code that produced it.
//!
//! Ground layer: imports nothing of the crate.

/// `0.1.0 (commit 67c70ce)`, `0.1.0 (commit 67c70ce, modified)` or
/// `0.1.0 (unknown commit)` (built without git or outside a repository).
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("HAPTICLAB_COMMIT"),
    ")"
);

/// `hapticlab 0.1.0 (commit 67c70ce)`: `hapticlab --version`'s line, and the
/// `software` key of the recordings it writes. Files from before the commit
/// was recorded say `hapticlab 0.1.0` and read as well: the key is only told.
pub const SOFTWARE: &str = concat!(
    "hapticlab ",
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("HAPTICLAB_COMMIT"),
    ")"
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn software_is_the_name_and_the_version_naming_a_commit_or_none() {
        assert_eq!(SOFTWARE, format!("hapticlab {VERSION}"));
        let inner = VERSION
            .strip_prefix(concat!(env!("CARGO_PKG_VERSION"), " ("))
            .and_then(|v| v.strip_suffix(')'))
            .unwrap();
        let known = inner.strip_prefix("commit ").is_some_and(|c| {
            let hash = c.strip_suffix(", modified").unwrap_or(c);
            hash.len() >= 7 && hash.bytes().all(|b| b.is_ascii_hexdigit())
        });
        assert!(known || inner == "unknown commit", "{VERSION}");
    }
}
