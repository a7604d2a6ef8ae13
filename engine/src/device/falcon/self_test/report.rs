//! The self-test's report: each step's verdict and figures, the pulses, the
//! link's quality, the calibration, in words (`lines`) or as JSON (serde),
//! ready to paste into an issue.

use serde::Serialize;

use crate::device::LinkStats;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Pass,
    Fail,
    /// Not run: the user declined, or an earlier step failed.
    Skipped,
}

impl Verdict {
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
            Verdict::Skipped => "SKIPPED",
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    pub name: String,
    pub verdict: Verdict,
    /// What was measured, in words and numbers.
    pub detail: String,
}

/// One force pulse pair's measurement (for the report and tests).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PulseResponse {
    /// 0 = x, 1 = y, 2 = z (profile frame).
    pub axis: usize,
    /// Half the difference of the motions under the + and the − pulse
    /// (drift and gravity cancel), metres.
    pub motion_m: [f64; 3],
    /// Its component along the pushed axis, metres.
    pub along_m: f64,
    /// The cosine between the motion and the pushed axis.
    pub cosine: f64,
    /// The pulse's force, newtons, and the motion along the pushed axis per
    /// newton of it (how far the lightly held grip gives under a short push
    /// of that length: not a static stiffness).
    pub force_n: f64,
    pub along_mm_per_n: f64,
}

/// The arms' angles measured with each arm pushed to one of its stops.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StopAngles {
    /// `"pushed_in"` or `"pulled_out"`.
    pub stop: &'static str,
    /// Where the model puts the stop (the arm angle on the axis at the
    /// workspace box's end), degrees.
    pub model_deg: f64,
    /// Each arm's angle from its encoder (with the profile's offset),
    /// averaged once the arms came to rest against the stop; and its
    /// difference from the model.
    pub measured_deg: [f64; 3],
    pub difference_deg: [f64; 3],
    /// The arms came to rest against the stop within the step's time.
    pub reached: bool,
}

/// The calibration: the encoders read at the arms' stops against the model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// The torque each motor pushed its arm with, N·m, and the force that
    /// makes at the grip on the axis at the stops, newtons.
    pub torque_nm: f64,
    pub grip_force_n: f64,
    pub stops: Vec<StopAngles>,
    /// Each arm's travel from the pushed-in to the pulled-out stop, and the
    /// model's, degrees: the offset cancels in it, so an arm that did not
    /// get to a stop (no motor power, something in the way) shows here
    /// rather than as an offset.
    pub travel_deg: [f64; 3],
    pub model_travel_deg: f64,
    /// The profile's `[falcon] encoder_offset_deg`, the mean difference
    /// over both stops and all arms (how far the encoders read off the
    /// model: a stop's give cancels between the two), and the offset that
    /// would remove it.
    pub encoder_offset_deg: f64,
    pub offset_error_deg: f64,
    pub suggested_offset_deg: f64,
    /// Every difference must be within this, degrees (a travel within twice it).
    pub tolerance_deg: f64,
    pub passed: bool,
}

/// The link measured over a few seconds with the grip let go.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkQuality {
    /// Packet written to its reply read: the median and the 99th percentile.
    pub round_trip_p50_ms: Option<f64>,
    pub round_trip_p99_ms: Option<f64>,
    pub missed_per_1000: f64,
    /// The limits the step passes within.
    pub limit_p99_ms: f64,
    pub limit_missed_per_1000: f64,
}

/// The link's counters over the whole test, and its measured quality.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkReport {
    #[serde(flatten)]
    pub counts: LinkStats,
    #[serde(flatten)]
    pub quality: Option<LinkQuality>,
}

/// The whole run, for the user to paste into an issue.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    pub hapticlab: String,
    pub platform: String,
    pub profile: String,
    pub device: String,
    /// The firmware loader's and the USB layer's steps, as they were told.
    pub open_log: Vec<String>,
    pub steps: Vec<Step>,
    pub pulses: Vec<PulseResponse>,
    pub link: Option<LinkReport>,
    /// `None` when the calibration did not run.
    pub calibration: Option<Calibration>,
    /// Seconds from the first exchange until the forces were zeroed.
    pub duration_s: f64,
    /// The zero-force packet that ended the test was seen to leave the host.
    pub zero_force_confirmed: bool,
    /// The motor commands the device applies after the test, where that
    /// can be known (the emulator); `None` for a real Falcon.
    pub motors_after: Option<[i16; 3]>,
    pub passed: bool,
}

impl Report {
    pub(super) fn new(profile: &str) -> Report {
        Report {
            hapticlab: crate::version::VERSION.into(),
            platform: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            profile: profile.into(),
            device: String::new(),
            open_log: Vec::new(),
            steps: Vec::new(),
            pulses: Vec::new(),
            link: None,
            calibration: None,
            duration_s: 0.0,
            zero_force_confirmed: false,
            motors_after: None,
            passed: false,
        }
    }

    pub(super) fn push(&mut self, name: &str, verdict: Verdict, detail: impl Into<String>) {
        self.steps.push(Step {
            name: name.into(),
            verdict,
            detail: detail.into(),
        });
        self.passed = self.steps.iter().all(|s| s.verdict == Verdict::Pass);
    }

    /// The steps that did not pass.
    pub fn not_passed(&self) -> Vec<&Step> {
        self.steps
            .iter()
            .filter(|s| s.verdict != Verdict::Pass)
            .collect()
    }

    /// The report as text lines.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![
            "hapticlab Falcon self-test".to_string(),
            format!(
                "hapticlab {} ({}), profile {}, device {}",
                self.hapticlab, self.platform, self.profile, self.device
            ),
        ];
        // The opening's steps, unless the open step's line says it all
        // (one line: "firmware already running").
        let open_detail = self.steps.first().map(|s| s.detail.as_str());
        if !(self.open_log.len() == 1 && open_detail == Some(self.open_log[0].as_str())) {
            for l in &self.open_log {
                out.push(format!("  open: {l}"));
            }
        }
        for s in &self.steps {
            out.push(format!(
                "{:<11} {:<7} {}",
                s.name,
                s.verdict.word(),
                s.detail
            ));
        }
        if let Some(LinkReport { counts: l, .. }) = &self.link {
            out.push(format!(
                "link: {} packets, {} replies, {} missed ({:.2} per 1000 packets), {} bad packets, {} USB errors, {} saturated ticks",
                l.packets,
                l.replies,
                l.missed_replies,
                per_1000(l.missed_replies, l.packets),
                l.bad_packets,
                l.usb_errors,
                l.saturated_ticks
            ));
        }
        out.push(if self.zero_force_confirmed {
            format!(
                "forces zeroed after {:.1} s (the zero-force packet left the host)",
                self.duration_s
            )
        } else {
            format!(
                "forces zeroed after {:.1} s, but the zero-force packet was not seen to leave the host within {} ms: if the grip still pushes, unplug the Falcon's power",
                self.duration_s,
                super::super::SAFE_FLUSH.as_millis()
            )
        });
        let failed = self.not_passed().len();
        out.push(if self.passed {
            format!("result: PASS ({} steps)", self.steps.len())
        } else {
            format!(
                "result: FAIL ({failed} of {} steps did not pass)",
                self.steps.len()
            )
        });
        out
    }
}

pub(super) fn per_1000(n: u64, of: u64) -> f64 {
    if of == 0 {
        0.0
    } else {
        1000.0 * n as f64 / of as f64
    }
}
