//! Every branch of the doctor's verdicts, over made-up facts; and the fact
//! readers that can run anywhere (a temporary folder, /proc text).

use std::io::Read;
use std::path::{Path, PathBuf};

use super::facts::{DatasetFacts, dir_state, effective_caps, rule_names_falcon, vm_size};
use super::*;
use crate::device::falcon::firmware::{self, FirmwareFileError};
use crate::device::falcon::usb::{FalconInfo, UsbError};

const MIB: u64 = 1 << 20;

fn thesis() -> Needs {
    Needs::of(&LoadedProfile::thesis()).unwrap()
}

fn falcon_needs() -> Needs {
    Needs {
        kind: DeviceKind::Falcon,
        firmware: Some(PathBuf::from("profiles/firmware/nvent_firmware.bin")),
        ..thesis()
    }
}

fn rt(priority: u8, lock_memory: bool, cpu: Option<usize>) -> Needs {
    Needs {
        realtime: Some(Realtime {
            priority,
            lock_memory,
            cpu,
        }),
        ..thesis()
    }
}

/// A well set-up lab PC, as an unprivileged user.
fn good_system() -> SystemFacts {
    SystemFacts {
        rtprio: Limit {
            soft: Some(95),
            hard: Some(95),
        },
        memlock: Limit {
            soft: None,
            hard: None,
        },
        cap_sys_nice: false,
        cap_ipc_lock: false,
        allowed_cpus: vec![0, 1, 2, 3],
        vm_bytes: Some(40 * MIB),
        fifo_trial: Some(Ok(())),
        pin_trial: Some(Ok(())),
    }
}

/// A stock desktop: no real-time priority, 8 MiB of lockable memory.
fn stock_system() -> SystemFacts {
    SystemFacts {
        rtprio: Limit {
            soft: Some(0),
            hard: Some(0),
        },
        memlock: Limit {
            soft: Some(8 * MIB),
            hard: Some(8 * MIB),
        },
        fifo_trial: Some(Err("Operation not permitted (os error 1)".into())),
        ..good_system()
    }
}

fn tty(cols: u16, rows: u16) -> TerminalFacts {
    TerminalFacts {
        stdout_is_terminal: true,
        size: Some((cols, rows)),
        term: Some("xterm-256color".into()),
        colorterm: None,
        no_color: false,
    }
}

fn dataset(state: DirState, write: Result<(), String>, free: Option<u64>) -> DatasetFacts {
    DatasetFacts {
        dir: PathBuf::from("recordings/session-2026-11-22"),
        state,
        write,
        free_bytes: free,
        read_only: false,
    }
}

fn falcon(access: Result<(), UsbError>) -> FalconInfo {
    FalconInfo {
        location: "USB bus 1 device 7".into(),
        serial: Some("FTA1B2C3".into()),
        product: Some("FALCON HAPTIC".into()),
        access,
    }
}

fn good_facts() -> Facts {
    Facts {
        root: false,
        usb: Ok(vec![]),
        udev_rule: Some(PathBuf::from("/etc/udev/rules.d/70-novint-falcon.rules")),
        udev_group: true,
        firmware: None,
        system: good_system(),
        terminal: tty(120, 40),
        dataset: dataset(DirState::Exists, Ok(()), Some(50 << 30)),
    }
}

fn find<'a>(checks: &'a [Check], name: &str) -> &'a Check {
    checks
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no check {name} in {checks:#?}"))
}

fn fix(c: &Check) -> &str {
    c.fix
        .as_deref()
        .unwrap_or_else(|| panic!("no fix in {c:#?}"))
}

#[test]
fn a_typical_scan_size_matches_the_thesis_recordings() {
    let n = thesis();
    assert!((n.scan_s - 9.27).abs() < 1e-9, "{}", n.scan_s);
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("recordings/thesis-sim/S1/S1_001.csv.gz");
    let mut text = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(&file).unwrap())
        .read_to_end(&mut text)
        .unwrap();
    let (est, real) = (n.scan_bytes() as f64, text.len() as f64);
    // The estimate counts a sign on every value: a little high, never low.
    assert!(
        est >= real && est < real * 1.08,
        "estimate {est} B, recording {real} B"
    );
}

#[test]
fn bytes_read_for_people() {
    assert_eq!(human_bytes(512), "512 B");
    assert_eq!(human_bytes(544 * 1024), "544 KiB");
    assert_eq!(human_bytes(8 * MIB), "8.0 MiB");
    assert_eq!(human_bytes(60 << 30), "60 GiB");
}

#[test]
fn a_well_set_up_pc_for_the_sim_profile_has_nothing_to_fix() {
    let checks = checks(&thesis(), &good_facts());
    assert!(
        checks
            .iter()
            .all(|c| matches!(c.status, Status::Ok | Status::Note) && c.fix.is_none()),
        "{checks:#?}"
    );
    let names: Vec<&str> = checks.iter().map(|c| c.name).collect();
    assert_eq!(
        names,
        [
            "usb",
            "udev",
            "firmware",
            "rt-priority",
            "memory-lock",
            "cpu-pinning",
            "terminal",
            "term",
            "colour",
            "dataset",
            "free-space"
        ]
    );
    assert!(render_json(&checks)["ok"].as_bool().unwrap());
}

#[test]
fn no_falcon_is_a_note_for_sim_and_a_failure_for_falcon() {
    let facts = good_facts();
    let c = usb_check(&thesis(), &facts.usb, None, false);
    assert_eq!(c.status, Status::Note, "{c:?}");
    assert!(
        c.finding.contains("not needed") && c.finding.contains("sim"),
        "{c:?}"
    );
    let c = usb_check(&falcon_needs(), &facts.usb, None, false);
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(c.finding.contains("0403:cb48"), "{c:?}");
    // No udev rule installed either: the fix says to install it.
    assert!(
        fix(&c).contains("not through a hub") && fix(&c).contains("70-novint-falcon.rules"),
        "{c:?}"
    );
    let rule = PathBuf::from("/etc/udev/rules.d/70-novint-falcon.rules");
    let c = usb_check(&falcon_needs(), &facts.usb, Some(&rule), false);
    assert!(!fix(&c).contains("udev"), "{c:?}");
}

#[test]
fn no_usb_bus_says_so_and_fails_only_for_falcon() {
    let usb = Err(UsbError::List("/sys/bus/usb/devices/ not found".into()));
    let c = usb_check(&thesis(), &usb, None, false);
    assert_eq!(c.status, Status::Note, "{c:?}");
    let c = usb_check(&falcon_needs(), &usb, None, false);
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(fix(&c).contains("passthrough"), "{c:?}");
}

#[test]
fn a_missing_udev_group_is_a_warning_for_a_falcon_profile() {
    let c = udev_group_check(&falcon_needs(), false);
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(
        c.finding.contains("`users` does not exist") && fix(&c).contains("log out and in"),
        "{c:?}"
    );
    assert_eq!(udev_group_check(&falcon_needs(), true).status, Status::Ok);
    assert_eq!(udev_group_check(&thesis(), false).status, Status::Note);
}

#[test]
fn a_falcon_without_permission_gets_the_udev_rule() {
    let usb = Ok(vec![falcon(Err(UsbError::Permission {
        at: "USB bus 1 device 7".into(),
    }))]);
    let c = usb_check(&falcon_needs(), &usb, None, false);
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(c.finding.contains("permission denied"), "{c:?}");
    assert!(
        fix(&c).contains("doctor --udev-rule") && fix(&c).contains("log out and in"),
        "{c:?}"
    );
    // Not needed by a sim profile, but worth knowing.
    let c = usb_check(&thesis(), &usb, None, false);
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(fix(&c).contains("70-novint-falcon.rules"), "{c:?}");
}

#[test]
fn a_busy_falcon_or_a_missing_index_fails_with_what_to_do() {
    let busy = Ok(vec![falcon(Err(UsbError::Busy {
        at: "USB bus 1 device 7".into(),
        detail: "device or resource busy".into(),
    }))]);
    let c = usb_check(&falcon_needs(), &busy, None, false);
    assert_eq!(c.status, Status::Fail);
    assert!(fix(&c).contains("close the other program"), "{c:?}");
    let one = Ok(vec![falcon(Ok(()))]);
    let second = Needs {
        falcon_index: 1,
        ..falcon_needs()
    };
    let c = usb_check(&second, &one, None, false);
    assert_eq!(c.status, Status::Fail);
    assert!(c.finding.contains("index 1 but 1 attached"), "{c:?}");
    assert!(fix(&c).contains("`[falcon] index` to 0..0"), "{c:?}");
}

#[test]
fn an_accessible_falcon_is_ok_and_root_is_told_about_other_users() {
    let one = Ok(vec![falcon(Ok(()))]);
    let c = usb_check(&falcon_needs(), &one, None, false);
    assert_eq!(c.status, Status::Ok, "{c:?}");
    assert!(
        c.finding.contains("serial FTA1B2C3") && c.fix.is_none(),
        "{c:?}"
    );
    let c = usb_check(&falcon_needs(), &one, None, true);
    assert_eq!(c.status, Status::Ok);
    assert!(c.finding.contains("as root"), "{c:?}");
    let c = usb_check(&thesis(), &one, None, false);
    assert_eq!(c.status, Status::Note);
    assert!(
        c.finding.contains("1 Falcon(s) attached and usable"),
        "{c:?}"
    );
}

#[test]
fn firmware_goes_through_the_drivers_own_validation() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nvent_firmware.bin");
    let needs = Needs {
        firmware: Some(path.clone()),
        ..falcon_needs()
    };
    let read = |p: &Path| firmware::load_image(p).map(|i| i.bytes.len());
    // Missing.
    let c = firmware_check(&needs, Some(&read(&path)));
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(c.finding.contains("cannot read"), "{c:?}");
    assert!(fix(&c).contains("libnifalcon"), "{c:?}");
    assert!(
        fix(&c).contains(&format!("looks for it at {}", path.display())),
        "{c:?}"
    );
    // The wrong size.
    std::fs::write(&path, [0u8; 100]).unwrap();
    let c = firmware_check(&needs, Some(&read(&path)));
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(
        c.finding.contains("100 B") && c.finding.contains("8492"),
        "{c:?}"
    );
    assert!(fix(&c).contains("truncated"), "{c:?}");
    // A known image.
    std::fs::write(&path, vec![7u8; 8492]).unwrap();
    let c = firmware_check(&needs, Some(&read(&path)));
    assert_eq!(c.status, Status::Ok, "{c:?}");
    assert!(
        c.finding.contains("nvent_firmware.bin (recommended)"),
        "{c:?}"
    );
}

#[test]
fn firmware_is_not_needed_by_the_simulator_and_needed_by_the_emulator() {
    let c = firmware_check(&thesis(), None);
    assert_eq!(c.status, Status::Note, "{c:?}");
    assert!(c.finding.contains("not needed"), "{c:?}");
    let bad = Err(FirmwareFileError::WrongSize {
        path: "fw.bin".into(),
        len: 3,
    });
    let emulator = Needs {
        kind: DeviceKind::FalconEmulator,
        ..falcon_needs()
    };
    assert_eq!(firmware_check(&emulator, Some(&bad)).status, Status::Fail);
    let sim_with_file = Needs {
        kind: DeviceKind::Sim,
        ..falcon_needs()
    };
    let c = firmware_check(&sim_with_file, Some(&bad));
    assert_eq!(c.status, Status::Note, "{c:?}");
    assert!(c.finding.contains("not used"), "{c:?}");
}

#[test]
fn without_a_realtime_request_the_limits_are_a_note() {
    let no_rt = Needs {
        realtime: None,
        ..thesis()
    };
    let c = realtime_checks(&no_rt, &stock_system());
    assert_eq!(c.len(), 1);
    assert_eq!(c[0].status, Status::Note);
    assert!(
        c[0].finding.contains("RLIMIT_RTPRIO 0") && c[0].finding.contains("RLIMIT_MEMLOCK 8.0 MiB"),
        "{c:?}"
    );
}

#[test]
fn priority_limits_too_low_say_which_line_to_add() {
    let c = realtime_checks(&rt(80, false, None), &stock_system());
    let p = find(&c, "rt-priority");
    assert_eq!(p.status, Status::Warn, "{p:?}");
    assert!(
        p.finding.contains("RLIMIT_RTPRIO 0 (hard 0)") && p.finding.contains("refused"),
        "{p:?}"
    );
    assert!(
        fix(p).contains("@users - rtprio 80") && fix(p).contains("/etc/security/limits.d/"),
        "{p:?}"
    );
    assert!(fix(p).contains("cap_sys_nice"), "{p:?}");
    // A hard limit that allows it: raising the soft one is enough.
    let sys = SystemFacts {
        rtprio: Limit {
            soft: Some(0),
            hard: Some(99),
        },
        ..stock_system()
    };
    let c = realtime_checks(&rt(80, false, None), &sys);
    assert_eq!(
        fix(find(&c, "rt-priority")),
        "raise the soft limit in the shell that starts hapticlab: `ulimit -r 80` (the hard limit allows it)"
    );
}

#[test]
fn priority_granted_by_limit_or_capability_is_ok() {
    let c = realtime_checks(&rt(80, false, None), &good_system());
    let p = find(&c, "rt-priority");
    assert_eq!(p.status, Status::Ok, "{p:?}");
    assert!(p.finding.contains("granted to a scratch thread"), "{p:?}");
    let sys = SystemFacts {
        cap_sys_nice: true,
        fifo_trial: None,
        ..stock_system()
    };
    let p = realtime_checks(&rt(80, false, None), &sys).remove(0);
    assert_eq!(p.status, Status::Ok, "{p:?}");
    assert!(p.finding.contains("CAP_SYS_NICE"), "{p:?}");
    // Above the limit, no trial: not allowed.
    let sys = SystemFacts {
        fifo_trial: None,
        ..good_system()
    };
    assert_eq!(
        realtime_checks(&rt(99, false, None), &sys)[0].status,
        Status::Warn
    );
}

#[test]
fn a_refusal_despite_the_limits_points_at_the_container() {
    let sys = SystemFacts {
        fifo_trial: Some(Err("Operation not permitted (os error 1)".into())),
        ..good_system()
    };
    let p = realtime_checks(&rt(80, false, None), &sys).remove(0);
    assert_eq!(p.status, Status::Warn, "{p:?}");
    assert!(p.finding.contains("allowed by RLIMIT_RTPRIO 95"), "{p:?}");
    assert!(fix(&p).contains("container"), "{p:?}");
}

#[test]
fn memory_locking_needs_an_unlimited_memlock_or_the_capability() {
    let c = realtime_checks(&rt(80, true, None), &stock_system());
    let m = find(&c, "memory-lock");
    assert_eq!(m.status, Status::Warn, "{m:?}");
    assert!(
        m.finding.contains("8.0 MiB") && m.finding.contains("maps 40 MiB"),
        "{m:?}"
    );
    assert!(fix(m).contains("@users - memlock unlimited"), "{m:?}");
    let sys = SystemFacts {
        memlock: Limit {
            soft: Some(64 * 1024),
            hard: None,
        },
        ..stock_system()
    };
    let m = realtime_checks(&rt(80, true, None), &sys).remove(1);
    assert!(fix(&m).contains("ulimit -l unlimited"), "{m:?}");
    let sys = SystemFacts {
        cap_ipc_lock: true,
        ..stock_system()
    };
    assert_eq!(
        realtime_checks(&rt(80, true, None), &sys)[1].status,
        Status::Ok
    );
    assert_eq!(
        realtime_checks(&rt(80, true, None), &good_system())[1].status,
        Status::Ok
    );
    let m = realtime_checks(&rt(80, false, None), &stock_system()).remove(1);
    assert_eq!(m.status, Status::Note, "{m:?}");
    assert!(m.finding.contains("not asked"), "{m:?}");
}

#[test]
fn pinning_checks_the_core_against_the_machine() {
    let two = SystemFacts {
        allowed_cpus: vec![0, 1],
        ..good_system()
    };
    let c = realtime_checks(&rt(80, false, Some(5)), &two).remove(2);
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(
        c.finding.contains("core 5 asked") && c.finding.contains("2 core(s): 0-1"),
        "{c:?}"
    );
    assert!(fix(&c).contains("one of 0-1 (e.g. 1"), "{c:?}");
    let c = realtime_checks(&rt(80, false, Some(1)), &two).remove(2);
    assert_eq!(c.status, Status::Ok, "{c:?}");
    let one = SystemFacts {
        allowed_cpus: vec![0],
        ..good_system()
    };
    let c = realtime_checks(&rt(80, false, Some(0)), &one).remove(2);
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(c.finding.contains("the only one"), "{c:?}");
    let refused = SystemFacts {
        allowed_cpus: vec![0, 1, 2, 3, 6, 7],
        pin_trial: Some(Err("Invalid argument (os error 22)".into())),
        ..good_system()
    };
    let c = realtime_checks(&rt(80, false, Some(6)), &refused).remove(2);
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(fix(&c).contains("cpuset"), "{c:?}");
    let c = realtime_checks(&rt(80, false, None), &refused).remove(2);
    assert_eq!(c.status, Status::Note);
    assert!(c.finding.contains("0-3, 6-7"), "{c:?}");
}

#[test]
fn a_tiny_terminal_warns_with_the_size_needed() {
    let c = terminal_checks(&tty(60, 20));
    assert_eq!(c[0].status, Status::Warn, "{c:?}");
    assert!(
        c[0].finding.contains("60×20") && c[0].finding.contains("80×24"),
        "{c:?}"
    );
    assert!(fix(&c[0]).contains("80 columns by 24 rows"), "{c:?}");
    assert_eq!(terminal_checks(&tty(80, 24))[0].status, Status::Ok);
    assert_eq!(terminal_checks(&tty(200, 23))[0].status, Status::Warn);
    let unknown = TerminalFacts {
        size: None,
        ..tty(80, 24)
    };
    assert_eq!(terminal_checks(&unknown)[0].status, Status::Warn);
}

#[test]
fn not_a_terminal_is_a_note() {
    let piped = TerminalFacts {
        stdout_is_terminal: false,
        size: None,
        term: None,
        ..tty(0, 0)
    };
    let c = terminal_checks(&piped);
    assert!(
        c.iter()
            .all(|c| c.status == Status::Note && c.fix.is_none()),
        "{c:#?}"
    );
    assert!(c[0].finding.contains("not a terminal"), "{c:?}");
}

#[test]
fn an_unset_or_dumb_term_warns_on_a_terminal() {
    for term in [None, Some("dumb".to_string()), Some(String::new())] {
        let t = TerminalFacts {
            term: term.clone(),
            ..tty(100, 30)
        };
        let c = terminal_checks(&t);
        assert_eq!(c[1].status, Status::Warn, "{term:?}: {c:?}");
        assert!(fix(&c[1]).contains("TERM=xterm-256color"), "{c:?}");
        assert_eq!(c[2].status, Status::Note, "{c:?}");
    }
}

#[test]
fn colour_support_is_read_from_term_colorterm_and_no_color() {
    let c = terminal_checks(&tty(100, 30));
    assert_eq!(c[2].status, Status::Ok);
    assert!(c[2].finding.starts_with("256 colours"), "{c:?}");
    let truecolor = TerminalFacts {
        colorterm: Some("truecolor".into()),
        ..tty(100, 30)
    };
    assert!(
        terminal_checks(&truecolor)[2]
            .finding
            .starts_with("24-bit colour")
    );
    let plain = TerminalFacts {
        term: Some("xterm".into()),
        ..tty(100, 30)
    };
    assert!(
        terminal_checks(&plain)[2]
            .finding
            .starts_with("basic colours")
    );
    let no_color = TerminalFacts {
        no_color: true,
        ..tty(100, 30)
    };
    let c = terminal_checks(&no_color);
    assert_eq!(c[2].status, Status::Note);
    assert!(c[2].finding.contains("NO_COLOR"), "{c:?}");
}

#[test]
fn a_dataset_path_under_a_file_or_unwritable_fails() {
    let blocked = dataset(
        DirState::NotADirectory {
            blocker: "recordings".into(),
        },
        Err("recordings is a file".into()),
        Some(50 << 30),
    );
    let c = folder_checks(&thesis(), &blocked, false);
    assert_eq!(c[0].status, Status::Fail, "{c:?}");
    assert!(c[0].finding.contains("recordings is a file"), "{c:?}");
    let denied = || Err("Permission denied (os error 13)".to_string());
    let c = folder_checks(
        &thesis(),
        &dataset(DirState::Exists, denied(), Some(50 << 30)),
        false,
    );
    assert_eq!(c[0].status, Status::Fail, "{c:?}");
    assert!(
        fix(&c[0]).contains("chown") && fix(&c[0]).contains("--dataset"),
        "{c:?}"
    );
    let missing = DirState::Missing {
        ancestor: "/srv".into(),
    };
    let c = folder_checks(
        &thesis(),
        &dataset(missing, denied(), Some(50 << 30)),
        false,
    );
    assert_eq!(c[0].status, Status::Fail, "{c:?}");
    assert!(c[0].finding.contains("/srv is not writable"), "{c:?}");
    assert!(
        fix(&c[0]).contains("sudo mkdir -p recordings/session-2026-11-22"),
        "{c:?}"
    );
}

#[test]
fn a_read_only_disk_is_named_as_such() {
    let ro = DatasetFacts {
        read_only: true,
        ..dataset(
            DirState::Exists,
            Err("Read-only file system (os error 30)".into()),
            Some(50 << 30),
        )
    };
    let c = folder_checks(&thesis(), &ro, false);
    assert_eq!(c[0].status, Status::Fail, "{c:?}");
    assert!(c[0].finding.contains("mounted read-only"), "{c:?}");
    assert!(!fix(&c[0]).contains("chown"), "{c:?}");
}

#[test]
fn a_writable_dataset_is_ok_and_root_is_warned_of_its_privilege() {
    let c = folder_checks(
        &thesis(),
        &dataset(DirState::Exists, Ok(()), Some(50 << 30)),
        false,
    );
    assert_eq!(c[0].status, Status::Ok, "{c:?}");
    assert!(!c[0].finding.contains("root"), "{c:?}");
    let c = folder_checks(
        &thesis(),
        &dataset(DirState::Exists, Ok(()), Some(50 << 30)),
        true,
    );
    assert!(c[0].finding.contains("ran as root"), "{c:?}");
    let missing = DirState::Missing {
        ancestor: "recordings".into(),
    };
    let c = folder_checks(&thesis(), &dataset(missing, Ok(()), Some(50 << 30)), false);
    assert_eq!(c[0].status, Status::Ok, "{c:?}");
    assert!(c[0].finding.contains("can be created"), "{c:?}");
}

#[test]
fn free_space_counts_scans_and_warns_under_a_gibibyte() {
    let n = thesis();
    let scan = n.scan_bytes();
    let space = |free| folder_checks(&n, &dataset(DirState::Exists, Ok(()), free), false).remove(1);
    let c = space(Some(100 * MIB));
    assert_eq!(c.status, Status::Warn, "{c:?}");
    assert!(
        c.finding
            .contains(&format!("room for about {} scans", 100 * MIB / scan)),
        "{c:?}"
    );
    assert!(c.finding.contains("1000 Hz × 9.27 s"), "{c:?}");
    let c = space(Some(scan - 1));
    assert_eq!(c.status, Status::Fail, "{c:?}");
    assert!(c.finding.contains("room for about 0 scans"), "{c:?}");
    assert_eq!(space(Some(2 << 30)).status, Status::Ok);
    assert_eq!(space(None).status, Status::Note);
}

#[test]
fn the_text_report_has_words_fixes_and_a_summary() {
    let mut facts = good_facts();
    facts.terminal = tty(60, 20);
    facts.dataset = dataset(
        DirState::Exists,
        Err("Read-only file system (os error 30)".into()),
        Some(0),
    );
    let checks = checks(&falcon_needs(), &facts);
    let text = render_text(&checks);
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("FAIL  usb"), "{text}");
    assert!(
        lines[1].trim_start().starts_with("fix: plug the Falcon in"),
        "{text}"
    );
    assert!(text.contains("warn  terminal"), "{text}");
    assert!(text.contains("FAIL  free-space"), "{text}");
    assert!(
        lines.last().unwrap().contains("FAIL") && lines.last().unwrap().ends_with("not ready"),
        "{text}"
    );
    let fails = checks.iter().filter(|c| c.status == Status::Fail).count();
    assert!(
        lines.last().unwrap().contains(&format!("{fails} FAIL")),
        "{text}"
    );
    let json = render_json(&checks);
    assert_eq!(json["ok"], false);
    assert_eq!(json["checks"][0]["status"], "fail");
    assert_eq!(json["checks"][0]["name"], "usb");
    assert!(json["checks"][0]["fix"].is_string());
    assert_eq!(json["checks"].as_array().unwrap().len(), checks.len());
}

#[test]
fn the_dataset_state_and_write_probe_on_a_real_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    assert_eq!(dir_state(root), DirState::Exists);
    let deep = root.join("a/b/c");
    assert_eq!(
        dir_state(&deep),
        DirState::Missing {
            ancestor: root.to_path_buf()
        }
    );
    let file = root.join("plain");
    std::fs::write(&file, "x").unwrap();
    let under = file.join("session");
    assert_eq!(
        dir_state(&under),
        DirState::NotADirectory {
            blocker: file.clone()
        }
    );
    let f = DatasetFacts::gather(&under);
    assert!(f.write.is_err() && f.free_bytes.is_some(), "{f:?}");
    let f = DatasetFacts::gather(&deep);
    assert_eq!(f.write, Ok(()), "{f:?}");
    assert!(
        !deep.exists() && !root.join("a").exists(),
        "the probe created folders"
    );
    let f = DatasetFacts::gather(root);
    assert_eq!(f.write, Ok(()));
    assert_eq!(
        std::fs::read_dir(root).unwrap().count(),
        1,
        "the probe left its file"
    );
}

#[test]
fn a_relative_missing_folder_is_created_in_the_current_one() {
    let rel = Path::new("no-such-folder-for-doctor-tests/x");
    assert_eq!(
        dir_state(rel),
        DirState::Missing {
            ancestor: PathBuf::from(".")
        }
    );
}

#[test]
fn the_shipped_udev_rule_is_recognised() {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("contrib/70-novint-falcon.rules"),
    )
    .unwrap();
    assert!(rule_names_falcon(&shipped));
    assert!(!rule_names_falcon(
        "# ATTRS{idVendor}==\"0403\", ATTRS{idProduct}==\"cb48\"\n"
    ));
    assert!(!rule_names_falcon(
        "SUBSYSTEM==\"usb\", ATTRS{idVendor}==\"0403\", ATTRS{idProduct}==\"6001\"\n"
    ));
}

#[test]
fn capabilities_and_mapped_memory_come_from_proc_status() {
    let status = "Name:\thapticlab\nVmSize:\t   33280 kB\nCapEff:\t000001fffeffffff\n";
    let caps = effective_caps(status);
    assert!(caps & (1 << 23) != 0 && caps & (1 << 14) != 0 && caps & (1 << 24) == 0);
    assert_eq!(vm_size(status), Some(33280 * 1024));
    assert_eq!(effective_caps("CapEff:\t0000000000000000\n"), 0);
    assert_eq!(effective_caps(""), 0);
    assert_eq!(vm_size(""), None);
}
