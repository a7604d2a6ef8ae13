//! The Falcon checks: USB access (through the enumeration `hapticlab
//! devices` uses) and the firmware file (through the driver's own validation).

use std::path::PathBuf;

use super::{Check, Needs, Status, check, with_fix};
use crate::device::falcon::firmware::{FirmwareFileError, KNOWN_IMAGES, WHERE_TO_GET};
use crate::device::falcon::usb::{FalconInfo, UDEV_GROUP, UDEV_HINT, UsbError};
use crate::profile::DeviceKind;

fn falcon_line(f: &FalconInfo) -> String {
    let serial = f
        .serial
        .as_deref()
        .map_or(String::new(), |s| format!(" (serial {s})"));
    format!("{}{serial}", f.location)
}

/// What went wrong opening a Falcon, split into the finding and the fix.
fn usb_problem(e: &UsbError) -> (String, String) {
    match e {
        UsbError::Permission { at } => (
            format!("permission denied opening the Falcon at {at}"),
            UDEV_HINT.to_string(),
        ),
        UsbError::Busy { at, detail } => (
            format!("the Falcon at {at} is in use by another program ({detail})"),
            "close the other program (another hapticlab, a Novint or libnifalcon tool) and try again"
                .into(),
        ),
        UsbError::Other { at, detail } => (
            format!("cannot open the Falcon at {at}: {detail}"),
            "unplug and replug the Falcon (directly, not through a hub, with its power supply on); if it persists, `hapticlab devices` and the kernel log (`sudo dmesg | tail`) say more".into(),
        ),
        UsbError::NotFound(_) => (
            "no Novint Falcon (USB 0403:cb48) is plugged in".into(),
            "plug the Falcon in directly (not through a hub) with its power supply connected, and check with `hapticlab devices`".into(),
        ),
        UsbError::List(why) => (
            format!("cannot list USB devices ({why}): this system shows no USB bus"),
            "run hapticlab on the lab PC itself, or give the container or VM the USB device (passthrough)".into(),
        ),
    }
}

/// USB access to the Falcon: needed (a failure when missing) only when the
/// profile drives a real one.
pub fn usb_check(
    needs: &Needs,
    usb: &Result<Vec<FalconInfo>, UsbError>,
    udev_rule: Option<&PathBuf>,
    root: bool,
) -> Check {
    const NAME: &str = "usb";
    let wanted = needs.kind == DeviceKind::Falcon;
    let not_needed = format!("not needed: the profile's device is {}", needs.kind.name());
    let rule_hint = match udev_rule {
        Some(_) => String::new(),
        None => format!(" (the udev rule is not installed: {UDEV_HINT})"),
    };
    let list = match usb {
        Err(e) => {
            let (finding, fix) = usb_problem(e);
            return if wanted {
                with_fix(check(NAME, Status::Fail, finding), fix)
            } else {
                check(NAME, Status::Note, format!("{finding}; {not_needed}"))
            };
        }
        Ok(list) => list,
    };
    if list.is_empty() {
        let (finding, fix) = usb_problem(&UsbError::NotFound(String::new()));
        return if wanted {
            with_fix(
                check(NAME, Status::Fail, finding),
                format!("{fix}{rule_hint}"),
            )
        } else {
            check(
                NAME,
                Status::Note,
                format!("no Falcon attached; {not_needed}"),
            )
        };
    }
    if !wanted {
        let usable = list.iter().filter(|f| f.access.is_ok()).count();
        let problem = list.iter().find_map(|f| f.access.as_ref().err());
        return match problem {
            None => check(
                NAME,
                Status::Note,
                format!(
                    "{usable} Falcon(s) attached and usable ({}); {not_needed}",
                    list.iter().map(falcon_line).collect::<Vec<_>>().join(", ")
                ),
            ),
            Some(e) => {
                let (finding, fix) = usb_problem(e);
                with_fix(
                    check(
                        NAME,
                        Status::Warn,
                        format!("{finding}; {not_needed}, but a falcon profile would fail"),
                    ),
                    fix,
                )
            }
        };
    }
    let Some(falcon) = list.get(needs.falcon_index) else {
        return with_fix(
            check(
                NAME,
                Status::Fail,
                format!(
                    "the profile wants Falcon index {} but {} attached",
                    needs.falcon_index,
                    list.len()
                ),
            ),
            format!(
                "set `[falcon] index` to 0..{} (it counts from 0), or plug in the other Falcon",
                list.len() - 1
            ),
        );
    };
    match &falcon.access {
        Ok(()) => {
            let mut finding = format!(
                "Falcon [{}] at {} opens",
                needs.falcon_index,
                falcon_line(falcon)
            );
            if root && udev_rule.is_none() {
                finding.push_str(
                    " (as root; other users need the udev rule (`hapticlab doctor --udev-rule`) installed)",
                );
            }
            check(NAME, Status::Ok, finding)
        }
        Err(e) => {
            let (finding, fix) = usb_problem(e);
            with_fix(check(NAME, Status::Fail, finding), fix)
        }
    }
}

/// The udev rule's group fallback: the group it names must exist here
/// (sessions without a seat, such as ssh, rely on it).
pub fn udev_group_check(needs: &Needs, group_exists: bool) -> Check {
    const NAME: &str = "udev";
    let status = if needs.kind != DeviceKind::Falcon {
        Status::Note
    } else if group_exists {
        Status::Ok
    } else {
        Status::Warn
    };
    if group_exists {
        return check(
            NAME,
            status,
            format!(
                "the udev rule's group `{UDEV_GROUP}` exists here (members may open the Falcon from any session; the person at the machine may without it)"
            ),
        );
    }
    with_fix(
        check(
            NAME,
            status,
            format!(
                "the udev rule's group `{UDEV_GROUP}` does not exist on this system: only the person logged in at the machine itself can open the Falcon"
            ),
        ),
        format!(
            "`sudo groupadd {UDEV_GROUP} && sudo usermod -aG {UDEV_GROUP} $USER`, then log out and in again, and replug the Falcon"
        ),
    )
}

/// The firmware file named by the profile, checked by the driver's own
/// validation (`firmware::load_image`): `None` when the profile names none.
pub fn firmware_check(needs: &Needs, firmware: Option<&Result<usize, FirmwareFileError>>) -> Check {
    const NAME: &str = "firmware";
    let known = KNOWN_IMAGES
        .iter()
        .map(|(n, s)| format!("{n} {s} B"))
        .collect::<Vec<_>>()
        .join(", ");
    let uploads = matches!(needs.kind, DeviceKind::Falcon | DeviceKind::FalconEmulator);
    match (firmware, needs.firmware.as_ref()) {
        (None, _) | (_, None) => {
            if needs.kind == DeviceKind::Falcon {
                // Profile validation refuses this; kept for completeness.
                with_fix(
                    check(NAME, Status::Fail, "the profile names no firmware file"),
                    WHERE_TO_GET,
                )
            } else {
                check(
                    NAME,
                    Status::Note,
                    format!(
                        "not needed: the profile's device is {} and names no firmware file",
                        needs.kind.name()
                    ),
                )
            }
        }
        (Some(Ok(len)), Some(path)) => {
            let name = KNOWN_IMAGES
                .iter()
                .find(|(_, s)| s == len)
                .map_or("a known image", |(n, _)| n);
            check(
                NAME,
                if uploads { Status::Ok } else { Status::Note },
                format!(
                    "{}: {len} B, the size of {name}{}",
                    path.display(),
                    if uploads {
                        String::new()
                    } else {
                        format!("; not used: the profile's device is {}", needs.kind.name())
                    }
                ),
            )
        }
        (Some(Err(e)), Some(_)) => {
            let status = if uploads { Status::Fail } else { Status::Note };
            let (finding, fix) = match e {
                FirmwareFileError::Missing { path, reason } => (
                    format!("{}: cannot read the firmware: {reason}", path.display()),
                    format!(
                        "{WHERE_TO_GET} (this profile looks for it at {}); if the file is there, make it readable for the lab's user",
                        path.display()
                    ),
                ),
                FirmwareFileError::WrongSize { path, len } => (
                    format!(
                        "{}: {len} B is not a Falcon firmware image (known sizes: {known})",
                        path.display()
                    ),
                    format!("the file is truncated or another file; {WHERE_TO_GET}"),
                ),
            };
            if uploads {
                with_fix(check(NAME, status, finding), fix)
            } else {
                check(
                    NAME,
                    status,
                    format!(
                        "{finding}; not used: the profile's device is {}",
                        needs.kind.name()
                    ),
                )
            }
        }
    }
}
