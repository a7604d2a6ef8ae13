//! `hapticlab completions SHELL` and `hapticlab man`: generated from the
//! clap definitions, so every command the top help lists is completed and
//! has a page; a page already there is not replaced without --overwrite;
//! a reader that goes away early is no failure.

use std::fs;
use std::process::{Command, Stdio};

use crate::common::{hapticlab, p, run};

/// The commands `hapticlab --help` lists (the source the generated text
/// must follow), `help` left out.
fn commands() -> Vec<String> {
    let r = run(&["--help"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let names: Vec<String> = r
        .stdout
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect();
    assert!(names.len() >= 16, "{names:?}");
    assert!(names.iter().any(|n| n == "completions") && names.iter().any(|n| n == "man"));
    names
}

fn completions(shell: &str) -> String {
    let r = run(&["completions", shell]);
    assert_eq!(r.code, Some(0), "{shell}: {r:?}");
    assert!(r.stderr.is_empty(), "{shell}: {r:?}");
    r.stdout
}

#[test]
fn every_shell_completes_every_command() {
    let names = commands();
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let script = completions(shell);
        for n in &names {
            assert!(
                script.contains(n.as_str()),
                "the {shell} completions never mention {n}"
            );
        }
    }
    // Bash's list of words after `hapticlab` holds each command as a word.
    let bash = completions("bash");
    let top = bash
        .lines()
        .find(|l| l.trim_start().starts_with("opts=\"-p "))
        .expect("the top-level opts line");
    let words: Vec<&str> = top
        .trim()
        .trim_start_matches("opts=\"")
        .trim_end_matches('"')
        .split(' ')
        .collect();
    for n in &names {
        assert!(words.contains(&n.as_str()), "{n} not in {top}");
    }
}

/// The bash script, sourced by bash, completes as a user would see it.
#[test]
fn bash_completes_a_command_and_its_values() {
    let script = completions("bash");
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("hapticlab.bash");
    fs::write(&f, script).unwrap();
    let complete = |words: &str| -> String {
        // `_hapticlab` reads COMP_WORDS/COMP_CWORD and its arguments
        // (command, current word, previous word), as `complete -F` calls it.
        let prog = format!(
            "source {}; COMP_WORDS=({words}); COMP_CWORD=$((${{#COMP_WORDS[@]}} - 1)); \
             _hapticlab hapticlab \"${{COMP_WORDS[COMP_CWORD]}}\" \"${{COMP_WORDS[COMP_CWORD-1]}}\"; \
             echo \"${{COMPREPLY[*]}}\"",
            f.display()
        );
        let o = Command::new("bash").arg("-c").arg(prog).output().unwrap();
        assert!(o.status.success(), "{o:?}");
        String::from_utf8(o.stdout).unwrap().trim().to_string()
    };
    assert_eq!(complete("hapticlab eva"), "evaluate");
    assert_eq!(complete("hapticlab plot tr"), "trace");
    let shells = complete("hapticlab completions ''");
    for shell in ["bash", "elvish", "fish", "powershell", "zsh"] {
        assert!(shells.split(' ').any(|w| w == shell), "{shells}");
    }
    assert_eq!(complete("hapticlab completions po"), "powershell");
}

#[test]
fn an_unknown_shell_is_bad_input() {
    let r = run(&["completions", "nushell"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("invalid value 'nushell'"), "{r:?}");
    assert!(r.stdout.is_empty(), "{r:?}");
    let r = run(&["completions"]);
    assert_eq!(r.code, Some(2), "{r:?}");
}

#[test]
fn the_manual_page_names_every_command() {
    let r = run(&["man"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(r.stdout.contains(".TH hapticlab 1"), "{}", r.stdout);
    for n in commands() {
        // roff writes a hyphen in a name as `\-`.
        assert!(
            r.stdout.contains(&format!("hapticlab\\-{n}(1)")),
            "hapticlab(1) does not name {n}"
        );
    }
}

#[test]
fn man_out_writes_one_page_per_command_and_replaces_none() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man1");
    let r = run(&["man", "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let mut expected = vec!["hapticlab.1".to_string()];
    expected.extend(commands().iter().map(|n| format!("hapticlab-{n}.1")));
    // Nested commands have pages of their own.
    expected.push("hapticlab-profile-new.1".into());
    expected.push("hapticlab-plot-trace.1".into());
    for f in &expected {
        let text = fs::read_to_string(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        let name = f.trim_end_matches(".1");
        assert!(text.starts_with(".ie") || text.starts_with(".TH"), "{f}");
        assert!(text.contains(&format!(".TH {name} 1")), "{f}:\n{text}");
    }
    let evaluate = fs::read_to_string(out.join("hapticlab-evaluate.1")).unwrap();
    assert!(evaluate.contains("\\-\\-folds"), "{evaluate}");

    // Again: a page is there, so nothing is written (or replaced).
    fs::write(out.join("hapticlab-tune.1"), "mine").unwrap();
    fs::remove_file(out.join("hapticlab-man.1")).unwrap();
    let r = run(&["man", "--out", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("already exists"), "{r:?}");
    assert_eq!(
        fs::read_to_string(out.join("hapticlab-tune.1")).unwrap(),
        "mine"
    );
    assert!(!out.join("hapticlab-man.1").exists());
    // With --overwrite every page is written anew.
    let r = run(&["man", "--out", p(&out), "--overwrite"]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        fs::read_to_string(out.join("hapticlab-tune.1"))
            .unwrap()
            .contains(".TH")
    );
    assert!(out.join("hapticlab-man.1").exists());

    // --out on a file is bad input, said once.
    let file = dir.path().join("file");
    fs::write(&file, "x").unwrap();
    let r = run(&["man", "--out", p(&file)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("not a folder"), "{r:?}");
    assert_eq!(r.stderr.lines().count(), 1, "{r:?}");
}

/// A reader that goes away (`| head -1`) gets no error and no panic; a full
/// disk is a failure.
#[test]
fn a_pipe_closed_early_stays_quiet_and_a_full_disk_does_not() {
    for args in [["completions", "bash"], ["completions", "zsh"], ["man", ""]] {
        let args: Vec<&str> = args.into_iter().filter(|a| !a.is_empty()).collect();
        let mut c = hapticlab()
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(c.stdout.take());
        let o = c.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{args:?}: {o:?}");
        assert!(o.stderr.is_empty(), "{args:?}: {o:?}");
        if std::path::Path::new("/dev/full").exists() {
            let full = fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap();
            let o = hapticlab().args(&args).stdout(full).output().unwrap();
            assert_eq!(o.status.code(), Some(1), "{args:?}: {o:?}");
            assert!(
                String::from_utf8_lossy(&o.stderr).contains("standard output could not be written"),
                "{args:?}: {o:?}"
            );
        }
    }
}
