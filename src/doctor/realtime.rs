//! The real-time checks: RLIMIT_RTPRIO, RLIMIT_MEMLOCK, capabilities and
//! cores against what `device.realtime` asks for.

use super::{Check, Limit, Needs, Status, SystemFacts, check, human_bytes, with_fix};
use crate::profile::Realtime;

/// A finite RLIMIT_MEMLOCK of at least this much is taken as enough for
/// mlockall: it locks every mapping of the process (code, heap, each
/// thread's stack): `scan` on the simulator maps about 150 MiB, the console more.
pub const MEMLOCK_ENOUGH_BYTES: u64 = 1 << 30;
/// The limits.d file the fixes suggest; the lab's users are in `users`
/// already for the Falcon's udev rule.
const LIMITS_FILE: &str = "/etc/security/limits.d/95-hapticlab.conf";
const LAB_GROUP: &str = "@users";

/// A limit for people: a number, or "unlimited".
fn limit_text(v: Option<u64>, bytes: bool) -> String {
    match v {
        None => "unlimited".into(),
        Some(n) if bytes => human_bytes(n),
        Some(n) => n.to_string(),
    }
}

fn limits_text(name: &str, l: &Limit, bytes: bool) -> String {
    format!(
        "{name} {} (hard {})",
        limit_text(l.soft, bytes),
        limit_text(l.hard, bytes)
    )
}

/// `a >= b` where `None` is unlimited.
fn at_least(limit: Option<u64>, want: u64) -> bool {
    limit.is_none_or(|l| l >= want)
}

/// Real-time limits against what `device.realtime` asks for.
pub fn realtime_checks(needs: &Needs, sys: &SystemFacts) -> Vec<Check> {
    let Some(rt) = &needs.realtime else {
        return vec![check(
            "realtime",
            Status::Note,
            format!(
                "the profile asks for no real-time scheduling (`device.realtime` unset): the servo thread runs at normal priority; here {}, {}",
                limits_text("RLIMIT_RTPRIO", &sys.rtprio, false),
                limits_text("RLIMIT_MEMLOCK", &sys.memlock, true)
            ),
        )];
    };
    vec![
        rtprio_check(rt, sys),
        memlock_check(rt, sys),
        cpu_check(rt, sys),
    ]
}

fn rtprio_check(rt: &Realtime, sys: &SystemFacts) -> Check {
    const NAME: &str = "rt-priority";
    let p = u64::from(rt.priority);
    let limits = limits_text("RLIMIT_RTPRIO", &sys.rtprio, false);
    let allowed = sys.cap_sys_nice || at_least(sys.rtprio.soft, p);
    let why = if sys.cap_sys_nice {
        "CAP_SYS_NICE".to_string()
    } else {
        limits.clone()
    };
    match (&sys.fifo_trial, allowed) {
        (Some(Ok(())), _) | (None, true) => check(
            NAME,
            Status::Ok,
            format!(
                "SCHED_FIFO {} {} ({why})",
                rt.priority,
                if sys.fifo_trial.is_some() {
                    "granted to a scratch thread"
                } else {
                    "allowed"
                }
            ),
        ),
        (Some(Err(e)), true) => with_fix(
            check(
                NAME,
                Status::Warn,
                format!(
                    "SCHED_FIFO {} is allowed by {why} but the kernel refused a scratch thread ({e})",
                    rt.priority
                ),
            ),
            "the limits are not the obstacle: a container or a cgroup without a real-time budget is (run on the lab PC itself, or give the container `--cap-add SYS_NICE --ulimit rtprio=99` and a real-time budget); the servo runs at normal priority until then",
        ),
        (trial, false) => {
            let refused = match trial {
                Some(Err(e)) => format!("; a scratch thread was refused ({e})"),
                _ => String::new(),
            };
            let fix = if at_least(sys.rtprio.hard, p) {
                format!(
                    "raise the soft limit in the shell that starts hapticlab: `ulimit -r {p}` (the hard limit allows it)"
                )
            } else {
                format!(
                    "add `{LAB_GROUP} - rtprio {p}` to {LIMITS_FILE} and log in again (or grant the binary CAP_SYS_NICE: `sudo setcap cap_sys_nice+ep \"$(command -v hapticlab)\"`)"
                )
            };
            with_fix(
                check(
                    NAME,
                    Status::Warn,
                    format!(
                        "SCHED_FIFO {} asked, but {limits} and no CAP_SYS_NICE{refused}: the servo will run at normal priority",
                        rt.priority
                    ),
                ),
                fix,
            )
        }
    }
}

fn memlock_check(rt: &Realtime, sys: &SystemFacts) -> Check {
    const NAME: &str = "memory-lock";
    let limits = limits_text("RLIMIT_MEMLOCK", &sys.memlock, true);
    if !rt.lock_memory {
        return check(
            NAME,
            Status::Note,
            format!("not asked (`device.realtime.lock_memory` false); here {limits}"),
        );
    }
    if sys.cap_ipc_lock {
        return check(
            NAME,
            Status::Ok,
            format!("mlockall allowed by CAP_IPC_LOCK ({limits})"),
        );
    }
    if at_least(sys.memlock.soft, MEMLOCK_ENOUGH_BYTES) {
        return check(NAME, Status::Ok, format!("mlockall allowed: {limits}"));
    }
    let mapped = sys.vm_bytes.map_or(String::new(), |b| {
        format!(
            " (this doctor alone maps {}; a scan maps more)",
            human_bytes(b)
        )
    });
    let fix = if at_least(sys.memlock.hard, MEMLOCK_ENOUGH_BYTES) {
        "raise the soft limit in the shell that starts hapticlab: `ulimit -l unlimited` (the hard limit allows it)".to_string()
    } else {
        format!(
            "add `{LAB_GROUP} - memlock unlimited` to {LIMITS_FILE} and log in again (or grant the binary CAP_IPC_LOCK: `sudo setcap cap_ipc_lock+ep \"$(command -v hapticlab)\"`)"
        )
    };
    with_fix(
        check(
            NAME,
            Status::Warn,
            format!(
                "memory locking asked, but {limits} and no CAP_IPC_LOCK: mlockall locks every mapping of the process{mapped}, so it will be refused and the servo runs unlocked"
            ),
        ),
        fix,
    )
}

/// Cores as ranges: `0-3, 6`.
fn cpu_list(cpus: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < cpus.len() {
        let mut j = i;
        while j + 1 < cpus.len() && cpus[j + 1] == cpus[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            cpus[i].to_string()
        } else {
            format!("{}-{}", cpus[i], cpus[j])
        });
        i = j + 1;
    }
    out.join(", ")
}

fn cpu_check(rt: &Realtime, sys: &SystemFacts) -> Check {
    const NAME: &str = "cpu-pinning";
    let n = sys.allowed_cpus.len();
    let have = format!(
        "hapticlab may run on {n} core(s): {}",
        cpu_list(&sys.allowed_cpus)
    );
    let Some(cpu) = rt.cpu else {
        return check(
            NAME,
            Status::Note,
            format!("not asked (`device.realtime.cpu` unset); {have}"),
        );
    };
    let suggest = sys
        .allowed_cpus
        .iter()
        .rev()
        .find(|&&c| c != 0)
        .or(sys.allowed_cpus.first())
        .map_or("another".to_string(), |c| c.to_string());
    if !sys.allowed_cpus.contains(&cpu) {
        return with_fix(
            check(
                NAME,
                Status::Warn,
                format!("core {cpu} asked, but {have}: pinning will be refused"),
            ),
            format!(
                "set `device.realtime.cpu` to one of {} (e.g. {suggest}; core 0 takes most interrupts)",
                cpu_list(&sys.allowed_cpus)
            ),
        );
    }
    if let Some(Err(e)) = &sys.pin_trial {
        return with_fix(
            check(
                NAME,
                Status::Warn,
                format!(
                    "core {cpu} is listed, but pinning a scratch thread to it was refused ({e})"
                ),
            ),
            "check the cgroup's cpuset (`cat /sys/fs/cgroup/cpuset.cpus.effective`) or leave `device.realtime.cpu` unset",
        );
    }
    if n == 1 {
        return with_fix(
            check(
                NAME,
                Status::Warn,
                format!(
                    "core {cpu} is the only one: the servo thread shares it with the console, the writer and everything else"
                ),
            ),
            "use a machine with at least two cores for live scans, or leave `device.realtime.cpu` unset",
        );
    }
    check(
        NAME,
        Status::Ok,
        format!("core {cpu} can be pinned; {have}"),
    )
}
