//! `hapticlab doctor`: what the lab PC needs for the profile — USB access to
//! the Falcon, its firmware file, real-time limits, the terminal, the
//! dataset folder — each with a status word and, when not ok, the fix.
//!
//! The system is read once into [`Facts`] (`doctor/facts.rs`); everything
//! here is a pure function from the profile's [`Needs`] and those facts to
//! [`Check`]s, so that tests cover every branch with made-up facts. This
//! module never changes the system: the only writes are the dataset probe's
//! temporary file (removed again) and the real-time trial on a scratch thread.

pub mod facts;
mod falcon;
mod folder;
mod realtime;
mod terminal;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::profile::{DeviceKind, LoadedProfile, MissingRig, Realtime};
use crate::recorder::COLUMNS;
use crate::recording::decimals_for;
use crate::support::{Failure, ProfileArg, bad, load_profile};

pub use facts::{DatasetFacts, DirState, Facts, Limit, SystemFacts, TerminalFacts};
pub use falcon::{firmware_check, udev_group_check, usb_check};
pub use folder::folder_checks;
pub use realtime::{MEMLOCK_ENOUGH_BYTES, realtime_checks};
pub use terminal::terminal_checks;

/// The console's smallest layout.
pub const MIN_TERMINAL: (u16, u16) = (80, 24);
/// Below this much free space the dataset check warns.
pub const LOW_SPACE_BYTES: u64 = 1 << 30;
/// The metadata lines a recording starts with, about (the thesis's: ~650 B).
const HEADER_BYTES: u64 = 1024;

/// The word of a check: never colour alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Ok,
    Warn,
    Fail,
    Note,
}

impl Status {
    pub fn word(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Warn => "warn",
            Status::Fail => "FAIL",
            Status::Note => "note",
        }
    }
}

/// One finding: what was checked, how it stands, what was found, and what to do.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    pub name: &'static str,
    pub status: Status,
    pub finding: String,
    pub fix: Option<String>,
}

fn check(name: &'static str, status: Status, finding: impl Into<String>) -> Check {
    Check {
        name,
        status,
        finding: finding.into(),
        fix: None,
    }
}

fn with_fix(mut c: Check, fix: impl Into<String>) -> Check {
    c.fix = Some(fix.into());
    c
}

/// What the profile asks of the machine.
#[derive(Debug, Clone, PartialEq)]
pub struct Needs {
    pub profile: String,
    pub kind: DeviceKind,
    /// Which Falcon (`[falcon] index`).
    pub falcon_index: usize,
    /// The firmware file, resolved against the profile's folder, when named.
    pub firmware: Option<PathBuf>,
    pub realtime: Option<Realtime>,
    pub rate_hz: f64,
    /// Seconds recorded per scan: the scan leg and the dwell after it.
    pub scan_s: f64,
}

impl Needs {
    /// What `lp`'s rig asks; an analysis-only profile asks nothing of the
    /// machine that doctor checks, and is refused naming its missing sections.
    pub fn of(lp: &LoadedProfile) -> Result<Needs, MissingRig> {
        let p = &lp.profile;
        let rig = lp.rig()?;
        Ok(Needs {
            profile: p.name.clone(),
            kind: rig.device.kind,
            falcon_index: p.falcon.as_ref().map_or(0, |f| f.index),
            firmware: p
                .falcon
                .as_ref()
                .and_then(|f| f.firmware.as_deref())
                .map(|f| lp.resolve(f)),
            realtime: rig.device.realtime.clone(),
            rate_hz: rig.device.rate_hz,
            scan_s: rig.scan_leg_length_m() / rig.path.speed_m_per_s + rig.path.dwell_s,
        })
    }

    /// A typical recording's size (uncompressed, as the console and `scan`
    /// write it): the header, then a row per sample on the scan leg, each
    /// value with a sign, one integer digit and the writer's decimals.
    pub fn scan_bytes(&self) -> u64 {
        let rows = (self.rate_hz * self.scan_s).ceil() as u64;
        let time_digits = (self.scan_s.max(1.0).log10().floor() as usize) + 1;
        let row: usize = COLUMNS
            .iter()
            .map(|c| {
                let int_part = if *c == "t_s" { time_digits } else { 2 };
                int_part + 1 + decimals_for(c) + 1
            })
            .sum();
        HEADER_BYTES + rows * row as u64
    }
}

/// Bytes for people: B, KiB, MiB, GiB, TiB.
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} B")
    } else if v < 10.0 {
        format!("{v:.1} {}", UNITS[unit])
    } else {
        format!("{v:.0} {}", UNITS[unit])
    }
}

/// Every check, in the order printed.
pub fn checks(needs: &Needs, facts: &Facts) -> Vec<Check> {
    let mut out = vec![
        usb_check(needs, &facts.usb, facts.udev_rule.as_ref(), facts.root),
        udev_group_check(needs, facts.udev_group),
        firmware_check(needs, facts.firmware.as_ref()),
    ];
    out.extend(realtime_checks(needs, &facts.system));
    out.extend(terminal_checks(&facts.terminal));
    out.extend(folder_checks(needs, &facts.dataset, facts.root));
    out
}

/// Counts per status word, for the summary line.
fn summary(checks: &[Check]) -> String {
    let count = |s| checks.iter().filter(|c| c.status == s).count();
    let verdict = if checks.iter().any(|c| c.status == Status::Fail) {
        "not ready"
    } else {
        "ready"
    };
    format!(
        "{} checks: {} ok, {} warn, {} FAIL, {} note — {verdict}",
        checks.len(),
        count(Status::Ok),
        count(Status::Warn),
        count(Status::Fail),
        count(Status::Note)
    )
}

/// The report for people: a line per check (status word, name, finding),
/// the fix indented below when not ok, then the summary.
pub fn render_text(checks: &[Check]) -> String {
    let width = checks.iter().map(|c| c.name.len()).max().unwrap_or(0);
    let mut out = String::new();
    for c in checks {
        out.push_str(&format!(
            "{:<4}  {:<width$}  {}\n",
            c.status.word(),
            c.name,
            c.finding
        ));
        if let Some(fix) = &c.fix {
            out.push_str(&format!("{:<4}  {:<width$}  fix: {fix}\n", "", ""));
        }
    }
    out.push_str(&summary(checks));
    out.push('\n');
    out
}

/// The report for scripts: `{checks: [{name, status, finding, fix}], ok}`.
pub fn render_json(checks: &[Check]) -> serde_json::Value {
    serde_json::json!({
        "checks": checks,
        "ok": !checks.iter().any(|c| c.status == Status::Fail),
    })
}

/// `hapticlab doctor`.
pub fn run(profile: &ProfileArg, dataset: Option<PathBuf>, json: bool) -> Result<(), Failure> {
    let lp = load_profile(profile)?;
    let needs = Needs::of(&lp).map_err(|e| bad(format!("doctor: {e}")))?;
    // The folder the console would open.
    let dataset = dataset.unwrap_or_else(|| {
        crate::console::session::choose(
            Path::new(crate::console::session::SESSIONS_ROOT),
            std::time::SystemTime::now(),
        )
        .0
    });
    let facts = Facts::gather(&needs, &dataset);
    let checks = checks(&needs, &facts);
    if json {
        crate::outln!("{}", render_json(&checks));
    } else {
        crate::outln!(
            "hapticlab doctor: profile {} (device {}), dataset {}",
            needs.profile,
            needs.kind.name(),
            dataset.display()
        );
        crate::outp!("{}", render_text(&checks));
    }
    let failed: Vec<&str> = checks
        .iter()
        .filter(|c| c.status == Status::Fail)
        .map(|c| c.name)
        .collect();
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Failure::Runtime(format!(
            "this machine is not ready for profile {}: {} failed",
            needs.profile,
            failed.join(", ")
        )))
    }
}
