//! The dataset folder's checks: there or creatable, writable, with free space.

use super::{
    Check, DatasetFacts, DirState, LOW_SPACE_BYTES, Needs, Status, check, human_bytes, with_fix,
};

/// The dataset folder: there or creatable, writable, and with room.
pub fn folder_checks(needs: &Needs, d: &DatasetFacts, root: bool) -> Vec<Check> {
    let dir = d.dir.display();
    let quoted = shell_word(&d.dir);
    let root_note = if root {
        "; but this ran as root, whom permission bits do not stop: run doctor as the lab's user to be sure"
    } else {
        ""
    };
    let folder = match (&d.state, &d.write) {
        (DirState::NotADirectory { blocker }, _) => with_fix(
            check(
                "dataset",
                Status::Fail,
                format!("{dir} cannot be a folder: {} is a file", blocker.display()),
            ),
            "give `--dataset` a folder path (or move the file away)",
        ),
        (DirState::DanglingLink { link }, _) => with_fix(
            check(
                "dataset",
                Status::Fail,
                format!(
                    "{dir} cannot be a folder: {} is a symlink that leads nowhere",
                    link.display()
                ),
            ),
            "point the symlink at a folder, remove it, or give `--dataset` another path",
        ),
        (DirState::Exists, Ok(())) => check(
            "dataset",
            Status::Ok,
            format!("{dir} exists and a test file was written and removed{root_note}"),
        ),
        (DirState::Missing { ancestor }, Ok(())) => check(
            "dataset",
            Status::Ok,
            format!(
                "{dir} does not exist yet and can be created (a test file was written in {}){root_note}",
                ancestor.display()
            ),
        ),
        (_, Err(e)) if d.read_only => with_fix(
            check(
                "dataset",
                Status::Fail,
                format!("{dir}: its disk is mounted read-only ({e})"),
            ),
            "choose a folder on a writable disk with `--dataset`",
        ),
        (DirState::Exists, Err(e)) => with_fix(
            check("dataset", Status::Fail, format!("{dir}: cannot write: {e}")),
            format!(
                "make it writable for the lab's user (`sudo chown -R \"$USER\" {quoted}`), or choose another folder with `--dataset`"
            ),
        ),
        (DirState::Missing { ancestor }, Err(e)) => with_fix(
            check(
                "dataset",
                Status::Fail,
                format!(
                    "{dir} does not exist and cannot be created: {} is not writable ({e})",
                    ancestor.display()
                ),
            ),
            format!(
                "create it for the lab's user (`sudo mkdir -p {quoted} && sudo chown \"$USER\" {quoted}`), or choose another folder with `--dataset`"
            ),
        ),
    };
    let scan = needs.scan_bytes();
    let typical = format!(
        "a scan is about {}: {:.0} Hz × {:.2} s",
        human_bytes(scan),
        needs.rate_hz,
        needs.scan_s
    );
    let space = match d.free_bytes {
        None => check(
            "free-space",
            Status::Note,
            format!("the free space could not be read; {typical}"),
        ),
        Some(free) => {
            let scans = free / scan.max(1);
            let finding = format!(
                "{} free: room for about {scans} scans; {typical}",
                human_bytes(free)
            );
            if scans == 0 {
                with_fix(
                    check("free-space", Status::Fail, finding),
                    "free space on that disk, or choose a folder on another with `--dataset`",
                )
            } else if free < LOW_SPACE_BYTES {
                with_fix(
                    check(
                        "free-space",
                        Status::Warn,
                        format!("{finding}; under {}", human_bytes(LOW_SPACE_BYTES)),
                    ),
                    "free space on that disk, or choose a folder on another with `--dataset`",
                )
            } else {
                check("free-space", Status::Ok, finding)
            }
        }
    };
    vec![folder, space]
}

/// A path as one shell word, quoted when it needs it.
fn shell_word(p: &std::path::Path) -> String {
    let s = p.display().to_string();
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+:@%,=".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        s
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}
