//! The calling thread's CPU time, for the examples that time one core's
//! work (`examples/kernel_window_cpu.rs`, `examples/hydra_window_cpu.rs`),
//! and their whole-number arguments.

/// This thread's CPU time, in seconds.
pub fn thread_cpu() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// Argument `i` as a whole number, `default` when it is not given; exit 2
/// with one line naming `program` and its `usage` when it is not one.
pub fn number_arg(args: &[String], i: usize, default: usize, program: &str, usage: &str) -> usize {
    match args.get(i) {
        None => default,
        Some(a) => a.parse().unwrap_or_else(|_| {
            eprintln!("{program}: {a:?} is not a whole number ({usage})");
            std::process::exit(2)
        }),
    }
}
