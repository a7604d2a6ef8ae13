//! Names the commit hapticlab is built from, for `--version` and the
//! `software` written into every recording, model and tuned profile:
//! `HAPTICLAB_COMMIT` is `commit 67c70ce`, `commit 67c70ce, modified` (tracked
//! files differ from the commit, as `git describe --dirty` counts them, or
//! a Rust source under `src/` or `engine/src/` is not tracked yet), or
//! `unknown commit` when there is no git or no repository (a tarball): a
//! build never fails for want of git.
//!
//! Reruns only when the commit or the index can have changed (HEAD, the ref
//! it points to, the index) or the engine's own files did, not on every
//! build: a path that does not exist is never named, as cargo would rerun
//! for it every time. So an edit to the front end (`src/`) that was neither
//! staged nor committed since the engine was last built is not yet counted
//! as "modified"; building the engine again for any other reason, `git add`
//! or a commit brings the mark up to date.

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    // The engine's own files, as cargo watches them when a build script
    // names none: naming any turns that off.
    for own in ["src", "Cargo.toml", "build.rs"] {
        println!("cargo:rerun-if-changed={own}");
    }
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    // The repository is the workspace's (engine/..), never one that merely
    // holds an unpacked tarball further up.
    let root = manifest.parent().unwrap_or(&manifest).to_path_buf();
    let commit = if is_toplevel(&root) {
        watch_git(&root);
        describe(&root)
    } else {
        None
    };
    println!(
        "cargo:rustc-env=HAPTICLAB_COMMIT={}",
        commit.unwrap_or_else(|| "unknown commit".into())
    );
}

/// `git ARGS` in `root`, its output trimmed; `None` when git is missing or fails.
fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(root)
        .args(args)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

/// `root` holds a `.git` (a folder, or a file in a linked worktree) that git
/// takes as the repository whose top is `root`: not a stray `.git` in a
/// tarball that git would skip for a repository further up.
fn is_toplevel(root: &Path) -> bool {
    root.join(".git").exists()
        && git(root, &["rev-parse", "--show-toplevel"])
            .is_some_and(|top| Path::new(&top).canonicalize().ok() == root.canonicalize().ok())
}

/// `commit abc1234` or `commit abc1234, modified`.
fn describe(root: &Path) -> Option<String> {
    let hash = git(root, &["rev-parse", "--short=7", "HEAD"])?;
    if hash.is_empty() || !hash.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    // Tracked files only, as `git describe --dirty`; no optional locks, so
    // the build never rewrites the index (which would rerun this script).
    let status = git(
        root,
        &[
            "--no-optional-locks",
            "status",
            "--porcelain",
            "--untracked-files=no",
        ],
    )?;
    // And Rust sources git does not track yet that a build compiles in
    // (a new module not yet added): the commit alone would not rebuild it.
    let untracked = git(
        root,
        &[
            "--no-optional-locks",
            "status",
            "--porcelain",
            "--untracked-files=all",
            "--",
            "src",
            "engine/src",
        ],
    )?;
    let new_source = untracked
        .lines()
        .any(|l| l.starts_with("?? ") && l.ends_with(".rs"));
    Some(if status.is_empty() && !new_source {
        format!("commit {hash}")
    } else {
        format!("commit {hash}, modified")
    })
}

/// Reruns this script when HEAD moves (a checkout), its branch moves (a
/// commit) or the index changes (`git add`, a checkout). Works in a linked
/// worktree too, where `.git` is a file and the refs live in the common
/// folder: git says where each is.
fn watch_git(root: &Path) {
    let path_of = |name: &str| -> Option<PathBuf> {
        let p = PathBuf::from(git(root, &["rev-parse", "--git-path", name])?);
        let p = if p.is_absolute() { p } else { root.join(p) };
        p.exists().then_some(p)
    };
    let mut watched: Vec<PathBuf> = ["HEAD", "index"]
        .iter()
        .filter_map(|n| path_of(n))
        .collect();
    if let Some(branch) = git(root, &["symbolic-ref", "-q", "HEAD"]) {
        // A loose ref, or else the packed one.
        watched.extend(path_of(&branch).or_else(|| path_of("packed-refs")));
    }
    for p in watched {
        println!("cargo:rerun-if-changed={}", p.display());
    }
}
