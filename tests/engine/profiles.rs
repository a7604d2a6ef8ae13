//! The profile loader over `profiles/invalid/*.toml`: each file says what
//! the message must contain (`# expect:`) and what the line it points at
//! must contain (`# at:`).

use std::path::Path;

use hapticlab::profile::LoadedProfile;
use proptest::prelude::*;

use crate::common::mutation::{mutate, mutation};

// The fuzz targets' entry points (`fuzz/src/lib.rs`): `profile` loads the
// text and checks the promises a loaded profile keeps.
use crate::entries;

#[test]
fn every_invalid_profile_is_refused_with_file_line_key_and_reason() {
    let mut checked = 0;
    let mut entries: Vec<_> = std::fs::read_dir("profiles/invalid")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    entries.sort();
    for path in entries {
        let text = std::fs::read_to_string(&path).unwrap();
        let expect = text
            .lines()
            .find_map(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{} has no `# expect:` line", path.display()));
        let at = text
            .lines()
            .find_map(|l| l.strip_prefix("# at: "))
            .unwrap_or("");
        let err =
            LoadedProfile::load(&path).expect_err(&format!("{} must be refused", path.display()));
        let msg = err.to_string();
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
        assert!(
            msg.contains(expect),
            "{}: message {msg:?} lacks {expect:?}",
            path.display()
        );
        let line = err.line.unwrap_or_else(|| panic!("{msg}: no line"));
        assert!(err.column.is_some(), "{msg}: no column");
        let pointed = text.lines().nth(line - 1).unwrap_or("");
        assert!(
            pointed.contains(at),
            "{msg}: points at line {line} {pointed:?}, expected one containing {at:?}"
        );
        checked += 1;
    }
    assert!(checked >= 12, "only {checked} invalid profiles");
}

#[test]
fn the_shipped_profiles_are_valid() {
    for entry in std::fs::read_dir("profiles").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            LoadedProfile::load(&path).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    // The built-in profile is the file on disk.
    let builtin = LoadedProfile::thesis();
    let disk = LoadedProfile::load(Path::new("profiles/thesis.toml")).unwrap();
    assert_eq!(builtin.profile, disk.profile);
    assert_eq!(builtin.sha256, disk.sha256);
}

/// The profile for a real Falcon asks for the simulated thesis profile's
/// real-time setup: a USB round trip leaves no room for late wake-ups.
#[test]
fn the_falcon_profiles_ask_for_the_thesis_real_time_setup() {
    let thesis = LoadedProfile::load(Path::new("profiles/thesis.toml")).unwrap();
    let falcon = LoadedProfile::load(Path::new("profiles/thesis-falcon.toml")).unwrap();
    let (thesis, falcon) = (thesis.rig().unwrap().device, falcon.rig().unwrap().device);
    assert!(thesis.realtime.is_some());
    assert_eq!(falcon.realtime, thesis.realtime);
    assert_eq!(falcon.spin_us, thesis.spin_us);
}

const SHIPPED: [&str; 3] = [
    include_str!("../../profiles/thesis.toml"),
    include_str!("../../profiles/thesis-emulator.toml"),
    include_str!("../../profiles/thesis-falcon.toml"),
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    /// Any bytes: a profile, or a message naming the file; never a panic.
    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let _ = entries::profile(&bytes);
    }

    #[test]
    fn mutated_profiles_never_panic(
        which in 0..SHIPPED.len(),
        mutations in prop::collection::vec(mutation(b"=[]{}\"'.,#\n-+0123456789e_"), 1..6),
    ) {
        let bytes = mutate(SHIPPED[which].as_bytes().to_vec(), &mutations);
        // Lossy, so that most mutants reach the TOML parser.
        let _ = entries::profile(String::from_utf8_lossy(&bytes).as_bytes());
    }
}

#[test]
fn the_shipped_profiles_pass_the_fuzz_entry_point() {
    for text in SHIPPED {
        assert_eq!(entries::profile(text.as_bytes()), Ok(()));
    }
}
