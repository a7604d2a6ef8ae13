//! `hapticlab devices`: the Falcons and HID triggers attached, whether each
//! can be opened, and what to do when one cannot.

use clap::Args;

use crate::device::falcon::usb::{self, UsbError};
use crate::support::{Failure, ProfileArg, load_profile};
use crate::triggers::hid;

/// The report as lines, from what was found (pure, for tests).
pub fn report(
    falcons: &Result<Vec<usb::FalconInfo>, UsbError>,
    hid_devices: &Result<Vec<hid::HidInfo>, String>,
    profile_name: &str,
    triggers: &[crate::triggers::TriggerSpec],
) -> Vec<String> {
    let mut out = vec!["Novint Falcons (USB 0403:cb48):".to_string()];
    match falcons {
        Err(e) => out.push(format!("  {e}")),
        Ok(list) if list.is_empty() => out.push(format!(
            "  none found: {}",
            UsbError::NotFound(String::new())
                .to_string()
                .trim_start_matches("no Novint Falcon (USB 0403:cb48) is plugged in; ")
        )),
        Ok(list) => {
            for (i, f) in list.iter().enumerate() {
                let serial = f
                    .serial
                    .as_deref()
                    .map_or(String::new(), |s| format!(", serial {s}"));
                let state = match &f.access {
                    Ok(()) => "ready".to_string(),
                    Err(e) => format!("NOT USABLE: {e}"),
                };
                out.push(format!("  [{i}] {}{serial}: {state}", f.location));
            }
        }
    }
    out.push(format!("HID triggers (profile {profile_name}):"));
    let seen = |vid: u16, pid: u16| {
        hid_devices
            .as_ref()
            .is_ok_and(|l| l.iter().any(|d| d.vendor_id == vid && d.product_id == pid))
    };
    if triggers.is_empty() {
        out.push("  none configured (add [[triggers]] to the profile to use a foot switch or button box)".into());
    }
    for t in triggers {
        let state = if seen(t.vendor_id, t.product_id) {
            "present"
        } else {
            "not plugged in (scans start without it)"
        };
        let map: Vec<String> = t
            .buttons
            .iter()
            .map(|b| format!("button {} = {}", b.button, b.action.name()))
            .collect();
        out.push(format!(
            "  {}: {state}; {}",
            t.display_name(),
            map.join(", ")
        ));
    }
    match hid_devices {
        Err(e) => out.push(format!("  {e}")),
        Ok(list) if list.is_empty() => out.push("  no HID devices visible".into()),
        Ok(list) => {
            out.push("HID devices visible (use their ids in [[triggers]]):".into());
            for d in list {
                let name = [d.manufacturer.as_deref(), d.product.as_deref()]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(" ");
                out.push(format!(
                    "  {:04x}:{:04x} {name} ({})",
                    d.vendor_id, d.product_id, d.path
                ));
            }
        }
    }
    out
}

#[derive(Debug, Args)]
pub struct DevicesArgs {
    #[command(flatten)]
    pub profile: ProfileArg,
}

pub fn run(a: DevicesArgs) -> Result<(), Failure> {
    let lp = load_profile(&a.profile)?;
    let falcons = usb::list_falcons();
    let hid_devices = hid::list();
    for line in report(
        &falcons,
        &hid_devices,
        &lp.profile.name,
        &lp.profile.triggers,
    ) {
        crate::outln!("{line}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn none_present_and_no_permission_say_what_to_do() {
        let lines = report(&Ok(vec![]), &Ok(vec![]), "thesis", &[]).join("\n");
        assert!(
            lines.contains("none found") && lines.contains("not through a hub"),
            "{lines}"
        );
        assert!(lines.contains("none configured"), "{lines}");
        let denied = usb::FalconInfo {
            location: "USB bus 1 device 7".into(),
            serial: Some("FTA1B2C3".into()),
            product: Some("FALCON HAPTIC".into()),
            access: Err(UsbError::Permission {
                at: "USB bus 1 device 7".into(),
            }),
        };
        let lines = report(&Ok(vec![denied]), &Err("no hidraw".into()), "thesis", &[]).join("\n");
        assert!(
            lines
                .contains("[0] USB bus 1 device 7, serial FTA1B2C3: NOT USABLE: permission denied"),
            "{lines}"
        );
        assert!(lines.contains("99-novint-falcon.rules"), "{lines}");
    }
}
