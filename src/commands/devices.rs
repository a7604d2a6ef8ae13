//! `hapticlab devices`: the Falcons and HID triggers attached, whether each
//! can be opened, and what to do when one cannot; with `--self-test`, the
//! profile's Falcon checked step by step (the engine is
//! [`crate::device::falcon::self_test`]; this file asks and prints).

use std::io::BufRead;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;

use crate::clock::RealClock;
use crate::device::falcon;
use crate::device::falcon::emulator::EmulatedFalcon;
use crate::device::falcon::self_test::{self, Operator, Pace, Request};
use crate::device::falcon::usb::{self, UsbError};
use crate::profile::{DeviceKind, LoadedProfile};
use crate::support::{Failure, ProfileArg, bad, load_profile, runtime};
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
    /// Test the profile's Falcon (device.kind "falcon" or "falcon-emulator")
    /// step by step and print a report to paste into an issue.
    #[arg(long)]
    pub self_test: bool,
    /// Apply the self-test's force pulses without asking.
    #[arg(long, requires = "self_test")]
    pub yes: bool,
    /// Print the self-test's report as JSON (progress stays on standard error).
    #[arg(long, requires = "self_test")]
    pub json: bool,
}

pub fn run(a: DevicesArgs) -> Result<(), Failure> {
    let lp = load_profile(&a.profile)?;
    if a.self_test {
        return run_self_test(&lp, a.yes, a.json);
    }
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

/// The person at the Falcon: told on standard error, asked on standard input.
/// For the emulator, its simulated hand does what the person is asked.
struct Terminal<'a> {
    yes: bool,
    /// Raised by a signal: a question waiting for its answer gives up.
    stop: &'a AtomicBool,
}

impl Terminal<'_> {
    fn tell(&self, line: &str) {
        crate::errln!("{line}");
    }

    /// Asked on standard input, read on a helper thread so that a signal
    /// still ends the test (forces zeroed) while the question waits.
    fn ask(&self, question: &str) -> bool {
        crate::errln!("{question} [y/N] (--yes skips this question)");
        let (tx, rx) = crossbeam_channel::bounded(1);
        let reader = std::thread::Builder::new()
            .name("stdin".into())
            .spawn(move || {
                let mut answer = String::new();
                let yes = matches!(std::io::stdin().lock().read_line(&mut answer), Ok(n) if n > 0)
                    && matches!(answer.trim(), "y" | "Y" | "yes" | "Yes" | "YES");
                let _ = tx.send(yes);
            });
        if reader.is_err() {
            return false;
        }
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return false;
            }
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(yes) => return yes,
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return false,
            }
        }
    }
}

/// How long a second signal waits for the test to zero the forces and end
/// before the process exits anyway.
const SECOND_SIGNAL_GRACE: Duration = Duration::from_secs(2);

/// SIGINT, SIGTERM and SIGHUP (a closed terminal) raise `stop`: the test
/// ends at its next exchange with the forces zeroed. A second signal does
/// the same, then exits (130) if the test has not ended within
/// [`SECOND_SIGNAL_GRACE`] (`done` is raised when it has).
fn watch_signals(stop: Arc<AtomicBool>, done: Arc<AtomicBool>) -> Result<(), Failure> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals =
        signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]).map_err(runtime)?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let mut seen = 0;
            for _ in signals.forever() {
                seen += 1;
                stop.store(true, Ordering::Relaxed);
                if seen >= 2 {
                    let until = Instant::now() + SECOND_SIGNAL_GRACE;
                    while !done.load(Ordering::Relaxed) && Instant::now() < until {
                        std::thread::sleep(Duration::from_millis(10));
                    }
                    if !done.load(Ordering::Relaxed) {
                        std::process::exit(130);
                    }
                }
            }
        })
        .map_err(runtime)?;
    Ok(())
}

impl Operator<usb::UsbTransport> for Terminal<'_> {
    fn request(&mut self, request: &Request, _: &mut usb::UsbTransport) {
        self.tell(&format!(">> {}", request.instruction()));
    }
    fn confirm(&mut self, question: &str) -> bool {
        self.yes || self.ask(question)
    }
    fn note(&mut self, line: &str) {
        self.tell(line);
    }
}

impl Operator<EmulatedFalcon> for Terminal<'_> {
    fn request(&mut self, request: &Request, transport: &mut EmulatedFalcon) {
        self.tell(&format!(">> {}", request.instruction()));
        if let Some(task) = request.hand_task() {
            if *request != Request::WatchLeds {
                self.tell("   (the emulator's simulated hand does it)");
            }
            transport.ask_hand(task);
        }
    }
    fn confirm(&mut self, question: &str) -> bool {
        self.yes || self.ask(question)
    }
    fn note(&mut self, line: &str) {
        self.tell(line);
    }
}

/// What the self-test takes from the profile, read in one place.
fn self_test_options(lp: &LoadedProfile, yes: bool) -> Result<self_test::Options, Failure> {
    let p = &lp.profile;
    let device = lp
        .rig()
        .map_err(|e| bad(format!("devices --self-test: {e}")))?
        .device;
    if !matches!(device.kind, DeviceKind::Falcon | DeviceKind::FalconEmulator) {
        return Err(bad(format!(
            "{}: devices --self-test needs a Falcon profile (device.kind = \"falcon\", or \"falcon-emulator\" to try it on the emulator), not \"{}\"; e.g. -p profiles/thesis-falcon.toml",
            lp.origin,
            device.kind.name()
        )));
    }
    Ok(self_test::Options {
        rate_hz: device.rate_hz,
        homing_timeout_s: p.falcon.as_ref().map_or(120.0, |f| f.homing_timeout_s),
        assume_yes: yes,
        ..self_test::Options::default()
    })
}

fn run_self_test(lp: &LoadedProfile, yes: bool, json: bool) -> Result<(), Failure> {
    let options = self_test_options(lp, yes)?;
    let stop = Arc::new(AtomicBool::new(false));
    let done = Arc::new(AtomicBool::new(false));
    watch_signals(stop.clone(), done.clone())?;
    // Raised once the device is closed (its forces zeroed), however this ends.
    let _closed = RaiseOnDrop(done);
    let mut terminal = Terminal { yes, stop: &stop };
    let mut clock = RealClock::start();
    let name = &lp.profile.name;
    // (`self_test_options` has checked the profile has a Falcon device.)
    let real = lp
        .profile
        .device
        .as_ref()
        .is_some_and(|d| d.kind == DeviceKind::Falcon);
    let (report, opened) = if real {
        let pace = Pace {
            clock: &mut clock,
            stop: &stop,
        };
        let open = |log: &mut dyn FnMut(&str)| falcon::open_usb(lp, log);
        let (report, device) = self_test::run(name, open, pace, &mut terminal, &options);
        (report, device.err())
    } else {
        let pace = Pace {
            clock: &mut clock,
            stop: &stop,
        };
        let seed = lp.profile.simulator.seed;
        let open = |log: &mut dyn FnMut(&str)| falcon::open_emulated(lp, None, seed, log);
        let (report, device) = self_test::run(name, open, pace, &mut terminal, &options);
        (report, device.err())
    };
    if let Some(falcon::OpenError::BadInput(m)) = opened {
        // A firmware file that is missing or the wrong size, found before any USB traffic.
        return Err(bad(m));
    }
    if json {
        let text = serde_json::to_string_pretty(&report).map_err(runtime)?;
        crate::outln!("{text}");
    } else {
        for line in report.lines() {
            crate::outln!("{line}");
        }
    }
    if report.passed {
        return Ok(());
    }
    let names: Vec<String> = report
        .not_passed()
        .iter()
        .map(|s| format!("{} {}", s.name, s.verdict.word()))
        .collect();
    Err(runtime(format!(
        "the Falcon self-test did not pass: {}",
        names.join(", ")
    )))
}

/// Raises its flag when dropped.
struct RaiseOnDrop(Arc<AtomicBool>);

impl Drop for RaiseOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
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
        assert!(lines.contains("70-novint-falcon.rules"), "{lines}");
    }
}
