//! hapticlab's entry point: parse the command line, dispatch, map errors to
//! exit codes (0 ok, 1 runtime failure, 2 bad input).

use clap::Parser;

fn main() {
    let cli = match hapticlab::cli::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // Help and version are not errors; bad arguments are bad input.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    // Past a file size limit (`ulimit -f`) a write should fail with EFBIG,
    // which the recorder reports and survives, rather than kill the process.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to "ignore" has no preconditions.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    // The console on the built-in thesis profile is the default.
    let command = cli.command();
    if let Err(f) = hapticlab::commands::run(command) {
        // Fallibly: the terminal may be the reason for the failure.
        hapticlab::terminal::err(format_args!("hapticlab: error: {}", f.message()));
        std::process::exit(f.exit_code());
    }
    // Output lost to a full disk or an I/O error is a runtime failure, never
    // a success (a closed pipe stays quiet).
    if let Some(why) = hapticlab::terminal::stdout_failure() {
        hapticlab::terminal::err(format_args!(
            "hapticlab: error: standard output could not be written ({why}): what was printed is lost"
        ));
        std::process::exit(1);
    }
}
