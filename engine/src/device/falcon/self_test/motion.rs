//! The force pulses: the lightly held grip pushed with a small force each
//! way along each axis; the motion must follow the push (a motor wired
//! backwards, without power or with a wrong gain shows here), and its size
//! per newton is reported.

use std::collections::VecDeque;

use super::{FalconTransport, Halt, MAX_PULSE_N, PulseResponse, Request, StepContext, Verdict, mm};
use crate::clock::Clock;
use crate::device::HapticDevice;

/// Wait (at most `rest_timeout_s`) until the grip is at rest; its position then.
fn come_to_rest<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
) -> Result<[f64; 3], Halt> {
    let window = cx.ticks(cx.options.rest_window_s) as usize;
    let mut recent: VecDeque<[f64; 3]> = VecDeque::with_capacity(window + 1);
    for _ in 0..cx.ticks(cx.options.rest_timeout_s) {
        let p = cx.tick([0.0; 3])?.pos_m;
        recent.push_back(p);
        if recent.len() > window {
            recent.pop_front();
            let first = recent[0];
            if recent
                .iter()
                .all(|q| distance(*q, first) < cx.options.rest_m)
            {
                break;
            }
        }
    }
    Ok(mean(recent.iter().rev().take(20)))
}

/// One pulse of `force` for `pulse_s`: the motion from rest to its end.
fn pulse<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
    force: [f64; 3],
) -> Result<[f64; 3], Halt> {
    let rest = come_to_rest(cx)?;
    let mut last = VecDeque::with_capacity(6);
    for _ in 0..cx.ticks(cx.options.pulse_s) {
        last.push_back(cx.tick(force)?.pos_m);
        if last.len() > 5 {
            last.pop_front();
        }
    }
    // Forces off at once; the next tick carries zero.
    cx.dev.0.command([0.0; 3])?;
    let end = mean(last.iter());
    Ok(std::array::from_fn(|a| end[a] - rest[a]))
}

pub(super) fn pulses<T: FalconTransport, C: Clock>(
    cx: &mut StepContext<'_, '_, '_, T, C>,
) -> Result<(), Halt> {
    let f = cx.options.pulse_n.clamp(0.0, MAX_PULSE_N);
    let ms = cx.options.pulse_s * 1000.0;
    cx.request(&Request::HoldLightly);
    if !cx.forces_agreed(super::calibration::grip_force_n(cx.options)) {
        for axis in ["x", "y", "z"] {
            cx.report.push(
                &format!("pulse {axis}"),
                Verdict::Skipped,
                "declined: no force was applied",
            );
        }
        return Ok(());
    }
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        cx.operator
            .note(&format!("  pulse along {name}: +{f:.1} N, then -{f:.1} N"));
        let mut push = [0.0; 3];
        push[axis] = f;
        let plus = pulse(cx, push)?;
        push[axis] = -f;
        let minus = pulse(cx, push)?;
        let motion_m: [f64; 3] = std::array::from_fn(|a| (plus[a] - minus[a]) / 2.0);
        let along_m = motion_m[axis];
        let size = distance(motion_m, [0.0; 3]);
        let cosine = if size > 0.0 { along_m / size } else { 0.0 };
        let along_mm_per_n = if f > 0.0 { along_m * 1000.0 / f } else { 0.0 };
        cx.report.pulses.push(PulseResponse {
            axis,
            motion_m,
            along_m,
            cosine,
            force_n: f,
            along_mm_per_n,
        });
        let o = cx.options;
        let detail = format!(
            "±{f:.1} N for {ms:.0} ms: moved {:+.2} mm along {name}, {along_mm_per_n:+.1} mm/N (motion {}; cosine {cosine:.2}, at least {:.2} and {:.1} mm needed)",
            along_m * 1000.0,
            mm(motion_m),
            o.min_cosine,
            o.min_motion_m * 1000.0
        );
        let ok = along_m >= o.min_motion_m && cosine >= o.min_cosine;
        let (verdict, detail) = if ok {
            (Verdict::Pass, detail)
        } else if along_m <= -o.min_motion_m {
            (
                Verdict::Fail,
                format!(
                    "{detail}: the grip moved against the push (a motor wired backwards, or the wrong frame?)"
                ),
            )
        } else {
            (
                Verdict::Fail,
                format!(
                    "{detail}: the motion does not follow the push (a motor wired backwards or without power, or a wrong gain?)"
                ),
            )
        };
        cx.report.push(&format!("pulse {name}"), verdict, detail);
    }
    Ok(())
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// The mean of some points (zero for none).
pub(super) fn mean<'a>(ps: impl Iterator<Item = &'a [f64; 3]>) -> [f64; 3] {
    let (mut sum, mut n) = ([0.0; 3], 0.0);
    for p in ps {
        for a in 0..3 {
            sum[a] += p[a];
        }
        n += 1.0;
    }
    if n == 0.0 {
        return sum;
    }
    sum.map(|s| s / n)
}
