//! The calibration: each arm pushed to its stops and the encoders read
//! there, against the model. The encoder offset (`[falcon]
//! encoder_offset_deg`, the arm angle of count 0 after homing) and the
//! stops (about −18.3° pushed in, 73.5° pulled out) both come from the
//! geometry; if the offset is off, every position the driver computes is
//! off with it. So, as a homing routine would, the motors push the grip
//! all the way in and then all the way out with a small torque each
//! (bounded by [`MAX_STOP_TORQUE_NM`]), joint by joint: neither the
//! Jacobian nor the workspace's edge, both taken from the encoders under
//! test, come in. Once the arms are at rest the angles are averaged and
//! compared with the model's stops; the mean difference over both stops
//! (where a stop's give cancels) is how far the encoders read off, and the
//! offset that removes it is suggested.

use std::collections::VecDeque;

use super::motion::mean;
use super::{
    Calibration, FalconTransport, Halt, MAX_STOP_TORQUE_NM, Options, Request, StepContext,
    StopAngles, Verdict,
};
use crate::clock::Clock;
use crate::device::HapticDevice;
use crate::device::falcon::kinematics;

/// The force (N) that `stop_torque_nm` on every motor makes at the grip on
/// the axis at the stops (the larger of the two ends).
pub(super) fn grip_force_n(options: &Options) -> f64 {
    let tau = options.stop_torque_nm.clamp(0.0, MAX_STOP_TORQUE_NM);
    [kinematics::FALCON_MIN_M[2], kinematics::FALCON_MAX_M[2]]
        .into_iter()
        .filter_map(|z| {
            let a = kinematics::inverse([0.0, 0.0, z]).ok()?;
            let j = kinematics::jacobian(&a).ok()?;
            let f = kinematics::force_of_torques(&j, [tau; 3]).ok()?;
            Some(f.iter().map(|v| v * v).sum::<f64>().sqrt())
        })
        .fold(0.0, f64::max)
}

/// Push every arm with `tau_nm` (towards a stop) until the arms are at
/// rest: their mean angles (degrees) over the last rest window, and whether
/// they came to rest within `stop_timeout_s`.
fn push_to_stop<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
    tau_nm: f64,
) -> Result<([f64; 3], bool), Halt> {
    let o = cx.options;
    let window = cx.ticks(o.rest_window_s) as usize;
    let settle = cx.ticks(o.stop_settle_s);
    let mut recent: VecDeque<[f64; 3]> = VecDeque::with_capacity(window + 1);
    for k in 0..cx.ticks(o.stop_timeout_s) {
        cx.tick_torques([tau_nm; 3])?;
        let Some(angles) = cx.dev.0.arm_angles_deg() else {
            recent.clear();
            continue;
        };
        recent.push_back(angles);
        if recent.len() > window {
            recent.pop_front();
        }
        let still = (0..3).all(|i| {
            let (lo, hi) = recent
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| {
                    (l.min(a[i]), h.max(a[i]))
                });
            hi - lo < o.stop_rest_deg
        });
        if k >= settle && recent.len() == window && still {
            return Ok((mean(recent.iter()), true));
        }
    }
    Ok((mean(recent.iter()), false))
}

fn degrees(a: [f64; 3]) -> String {
    format!("{:.2} / {:.2} / {:.2}°", a[0], a[1], a[2])
}

pub(super) fn calibration<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
) -> Result<(), Halt> {
    let o = cx.options;
    let torque_nm = o.stop_torque_nm.clamp(0.0, MAX_STOP_TORQUE_NM);
    let grip_force_n = grip_force_n(o);
    cx.request(&Request::HandsOffForStops { grip_force_n });
    if !cx.forces_agreed(grip_force_n) {
        cx.report.push(
            "calibration",
            Verdict::Skipped,
            "declined: no force was applied",
        );
        return Ok(());
    }
    let (lo, hi) = kinematics::joint_limits_deg();
    let mut stops = Vec::with_capacity(2);
    for (stop, words, sign, model_deg) in [
        ("pushed_in", "all the way in", -1.0, lo),
        ("pulled_out", "all the way out", 1.0, hi),
    ] {
        cx.operator.note(&format!(
            "  pushing the grip {words}: {torque_nm:.2} N·m on each arm"
        ));
        let (measured_deg, reached) = push_to_stop(cx, sign * torque_nm)?;
        cx.operator.note(&format!(
            "  arms at {} (model {model_deg:.2}°)",
            degrees(measured_deg)
        ));
        stops.push(StopAngles {
            stop,
            model_deg,
            measured_deg,
            difference_deg: measured_deg.map(|m| m - model_deg),
            reached,
        });
    }
    // Forces off; the grip stays where the last push left it.
    cx.dev.0.command([0.0; 3])?;
    let offset = cx.dev.0.encoder_offset_deg();
    let differences: Vec<f64> = stops.iter().flat_map(|s| s.difference_deg).collect();
    let offset_error_deg = differences.iter().sum::<f64>() / differences.len() as f64;
    let suggested = offset - offset_error_deg;
    let tol = o.calibration_tolerance_deg;
    let reached = stops.iter().all(|s| s.reached);
    let travel_deg: [f64; 3] =
        std::array::from_fn(|i| stops[1].measured_deg[i] - stops[0].measured_deg[i]);
    let model_travel_deg = hi - lo;
    let short: Vec<String> = travel_deg
        .iter()
        .enumerate()
        .filter(|(_, t)| (*t - model_travel_deg).abs() > 2.0 * tol)
        .map(|(arm, t)| format!("arm {arm} {t:.1}°"))
        .collect();
    let passed = reached && short.is_empty() && differences.iter().all(|d| d.abs() <= tol);
    let detail = format!(
        "pushed in: arms at {} (model {:.2}°); pulled out: {} (model {:.2}°); the encoders read {offset_error_deg:+.2}° off the model on average (passes with every arm within {tol:.1}° of it); suggested encoder_offset_deg {suggested:.1} (now {offset:.1})",
        degrees(stops[0].measured_deg),
        stops[0].model_deg,
        degrees(stops[1].measured_deg),
        stops[1].model_deg,
    );
    let detail = if passed {
        detail
    } else if !reached {
        let which: Vec<&str> = stops
            .iter()
            .filter(|s| !s.reached)
            .map(|s| s.stop)
            .collect();
        format!(
            "{detail}: the arms did not come to rest at the {} stop within {:.0} s (something holds the grip, or the motors have no power: check the Falcon's power supply)",
            which.join(" and the "),
            o.stop_timeout_s
        )
    } else if !short.is_empty() {
        format!(
            "{detail}: between the stops {} travelled where the model's arms travel {model_travel_deg:.1}°: the grip did not get to both stops (something holds it, or the motors have no power: check the Falcon's power supply); the offset cannot be judged",
            short.join(", ")
        )
    } else if offset_error_deg.abs() > tol {
        format!(
            "{detail}: the encoders read {offset_error_deg:+.1}° off the arms' stops: set `encoder_offset_deg = {suggested:.1}` in the profile's [falcon] section (now {offset:.1}) and run the self-test again"
        )
    } else {
        let off: Vec<String> = stops
            .iter()
            .flat_map(|s| {
                s.difference_deg
                    .iter()
                    .enumerate()
                    .filter(|(_, d)| d.abs() > tol)
                    .map(move |(arm, d)| format!("arm {arm} {d:+.1}° {}", s.stop))
            })
            .collect();
        format!(
            "{detail}: {} off the model, though the arms agree on average (not an offset, which is one for all arms): check nothing blocks those arms; if it persists, this Falcon's stops differ from the model: report it with this output",
            off.join(", ")
        )
    };
    cx.report.calibration = Some(Calibration {
        torque_nm,
        grip_force_n,
        stops,
        travel_deg,
        model_travel_deg,
        encoder_offset_deg: offset,
        offset_error_deg,
        suggested_offset_deg: suggested,
        tolerance_deg: tol,
        passed,
    });
    let verdict = if passed { Verdict::Pass } else { Verdict::Fail };
    cx.report.push("calibration", verdict, detail);
    Ok(())
}
