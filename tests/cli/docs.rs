//! The documentation stays true: every command in README.md and docs/ runs
//! as written, their links to local files resolve, and the profile-key
//! reference is what the one option list renders.
//!
//! Commands are the lines of ```` ```sh ```` blocks. Each file's lines run
//! in order (they may chain) through `sh` in a fresh folder holding the
//! shipped recordings and profiles, with `hapticlab` on the PATH and HOME
//! inside the folder, and must exit 0. Skipped: lines marked as
//! placeholders (`placeholder` in a comment, or a `<…>` to fill in; a
//! comment line `# placeholder…` marks the rest of its block), lines
//! in [`SKIPPED`] or `common::NOT_RUN_IN_TESTS` with the reason, and lines that are not hapticlab's
//! (`cargo`, `python3`, `sudo`, …; a shell loop or `mkdir` that prepares
//! files runs). A block of commands not tagged `sh` fails the test, so none
//! escapes it.

use std::path::{Path, PathBuf};
use std::process::Command;

use hapticlab::profile::options::{REGENERATE, profile_keys_markdown};

use crate::common::{BIN, REPO, not_run_in_tests, shipped_workspace};

/// Commands that cannot run in a test, by a word they contain, and why,
/// beyond `common::NOT_RUN_IN_TESTS`.
const SKIPPED: &[(&str, &str)] = &[
    (
        "-p profiles/thesis-falcon.toml",
        "needs a Novint Falcon on USB",
    ),
    ("sudo ", "needs root"),
    (
        "--self-test -p profiles/thesis-emulator.toml",
        "a self-test, run by the emulator tests (falcon_self_test)",
    ),
];

/// Shell words that prepare files for the commands after them: run.
const PREPARES: &[&str] = &["for", "mkdir"];

/// The pages whose commands and links are checked.
fn pages() -> Vec<PathBuf> {
    let repo = Path::new(REPO);
    let mut out = vec![repo.join("README.md")];
    for dir in ["docs", "docs/reference"] {
        let mut md: Vec<PathBuf> = std::fs::read_dir(repo.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect();
        md.sort();
        out.extend(md);
    }
    out
}

/// The fenced blocks of a markdown text: (info string, lines).
fn blocks(text: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    let mut open: Option<(String, Vec<String>)> = None;
    for l in text.lines() {
        let t = l.trim_start();
        if let Some(info) = t.strip_prefix("```") {
            match open.take() {
                Some(b) => out.push(b),
                None => open = Some((info.trim().to_string(), Vec::new())),
            }
        } else if let Some((_, lines)) = open.as_mut() {
            lines.push(l.to_string());
        }
    }
    out
}

/// Whether a line stands for the reader's own files: `placeholder` in a
/// comment, or a `<name>` to fill in (`<DIR>`, `<date>`).
fn placeholder(line: &str) -> bool {
    let comment = line.split_once(" #").map_or("", |(_, c)| c);
    if comment.contains("placeholder") || line.contains("(placeholder") {
        return true;
    }
    let b = line.as_bytes();
    b.iter().enumerate().any(|(i, &c)| {
        c == b'<'
            && b.get(i + 1).is_some_and(|n| n.is_ascii_alphabetic())
            && line[i + 1..]
                .split_once('>')
                .is_some_and(|(inside, _)| !inside.contains(' '))
    })
}

/// A fresh folder with the shipped recordings and profiles, and a HOME.
fn workspace() -> tempfile::TempDir {
    let dir = shipped_workspace();
    std::fs::create_dir(dir.path().join("home")).unwrap();
    dir
}

#[test]
fn every_command_in_the_readme_and_docs_runs_as_written() {
    let bin_dir = Path::new(BIN).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let (mut ran, mut skipped) = (0, 0);
    for page in pages() {
        let name = page.strip_prefix(REPO).unwrap().display().to_string();
        let text = std::fs::read_to_string(&page).unwrap();
        let dir = workspace();
        for (info, lines) in blocks(&text) {
            if info != "sh" {
                let untagged = lines.iter().find(|l| l.starts_with("hapticlab "));
                assert!(
                    info == "text" || untagged.is_none(),
                    "{name}: a block of commands not tagged sh (tag it ```sh, or ```text if it is output): {}",
                    untagged.unwrap()
                );
                continue;
            }
            let mut rest_placeholder = false;
            for line in lines.iter().map(|l| l.trim()) {
                if line.starts_with("# placeholder") {
                    rest_placeholder = true;
                }
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                if rest_placeholder || placeholder(line) {
                    eprintln!("{name}: placeholder: {line}");
                    skipped += 1;
                    continue;
                }
                if let Some(why) = not_run_in_tests(line, SKIPPED) {
                    eprintln!("{name}: skipped ({why}): {line}");
                    skipped += 1;
                    continue;
                }
                let first = line.split_whitespace().next().unwrap_or("");
                if first != "hapticlab" && !PREPARES.contains(&first) {
                    eprintln!("{name}: not hapticlab's: {line}");
                    continue;
                }
                let started = std::time::Instant::now();
                let out = Command::new("sh")
                    .arg("-c")
                    .arg(line)
                    .current_dir(dir.path())
                    .env("PATH", &path)
                    .env("HOME", dir.path().join("home"))
                    .output()
                    .unwrap();
                assert_eq!(
                    out.status.code(),
                    Some(0),
                    "{name}: a command failed as written: {line}\n{}",
                    String::from_utf8_lossy(&out.stderr)
                );
                eprintln!("{name}: ran in {:.1?}: {line}", started.elapsed());
                ran += 1;
            }
        }
    }
    eprintln!("{ran} commands ran, {skipped} skipped");
    assert!(ran >= 30, "only {ran} commands ran");
}

/// The anchors a page's headings get on GitHub (lower case, punctuation
/// but `-` and `_` dropped, spaces to `-`), and its `<a id="…">`s.
fn anchors(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for l in text.lines() {
        if l.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && l.starts_with('#') {
            let title = l.trim_start_matches('#').trim().to_lowercase();
            out.push(
                title
                    .chars()
                    .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
                    .map(|c| if c == ' ' { '-' } else { c })
                    .collect(),
            );
        }
        for (i, _) in l.match_indices("<a id=\"") {
            out.extend(l[i + 7..].split('"').next().map(str::to_string));
        }
    }
    out
}

#[test]
fn every_link_to_a_local_file_and_heading_resolves() {
    let mut pages = pages();
    for top in [
        "BENCHMARKS.md",
        "CONTRIBUTING.md",
        "ARCHITECTURE.md",
        "CHANGELOG.md",
    ] {
        pages.push(Path::new(REPO).join(top));
    }
    for page in pages {
        let text = std::fs::read_to_string(&page).unwrap();
        for (i, _) in text.match_indices("](") {
            let target = text[i + 2..].split(')').next().unwrap_or("");
            if target.contains("://") {
                continue;
            }
            let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
            let resolved = if file.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(file)
            };
            assert!(
                resolved.exists(),
                "{}: the link to {target} names no file",
                page.display()
            );
            if !anchor.is_empty() {
                let there = std::fs::read_to_string(&resolved).unwrap();
                assert!(
                    anchors(&there).iter().any(|a| a == anchor),
                    "{}: the link to {target} names no heading there",
                    page.display()
                );
            }
        }
    }
}

/// `docs/reference/profile-keys.md` is what the option list renders; with
/// HAPTICLAB_BLESS=1 this test writes it.
#[test]
fn profile_keys_reference_is_current() {
    let page = Path::new(REPO).join("docs/reference/profile-keys.md");
    let rendered = profile_keys_markdown();
    if std::env::var_os("HAPTICLAB_BLESS").is_some() {
        std::fs::write(&page, &rendered).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&page).unwrap_or_default();
    if committed != rendered {
        let line = committed
            .lines()
            .zip(rendered.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(committed.lines().count().min(rendered.lines().count()));
        panic!(
            "docs/reference/profile-keys.md is not what the option list \
             (engine/src/profile/options.rs) renders; it first differs at line {}.\n\
             Write it again with: {REGENERATE}",
            line + 1
        );
    }
}
