//! The import's checks of what its flags and inputs would write, made
//! before anything is written so a fault is blamed on the input and the
//! flag, never on the staging folder.

use std::path::PathBuf;

use super::{ImportError, Imported, Request, bad};

/// The flags that mean something for a CSV only, given for WAV inputs,
/// which carry their own rate and channels: refused when every input is a
/// WAV (nothing takes them), else a warning to print (they apply to the CSV
/// files alone), so the user never believes they reached a WAV.
pub(super) fn csv_only_flags_for_wav(args: &Request) -> Result<Option<String>, ImportError> {
    let is_wav = |f: &PathBuf| {
        f.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("wav") || e.eq_ignore_ascii_case("wave"))
    };
    let Some(wav) = args.files.iter().find(|f| is_wav(f)) else {
        return Ok(None);
    };
    let given = [
        ("--rate", args.rate.is_some()),
        ("--time-column", args.time_column.is_some()),
        ("--channels", !args.channels.is_empty()),
        ("--label-column", args.label_column.is_some()),
        ("--burst", args.burst != 1),
        ("--delimiter", args.delimiter.is_some()),
    ];
    let flags: Vec<&str> = given
        .iter()
        .filter(|(_, on)| *on)
        .map(|(f, _)| *f)
        .collect();
    if flags.is_empty() {
        return Ok(None);
    }
    let flags = flags.join(", ");
    if args.files.iter().all(is_wav) {
        return Err(bad(format!(
            "{}: {flags} applies to CSV files only (a WAV file carries its own rate and \
             channels): leave it out",
            wav.display()
        )));
    }
    Ok(Some(format!(
        "warning: {flags} applies to the CSV files only; {} and any other WAV file keep \
         their own rate and channels",
        wav.display()
    )))
}

/// Checks what the recording's head will hold (the channel names, the
/// metadata keys) before it is written, so a fault is blamed on the input
/// and the flag it came from, not on the staging file.
pub(super) fn check_written_names(
    imp: &Imported,
    extra: &[(String, toml::Value)],
    origin: &str,
    args: &Request,
) -> Result<(), ImportError> {
    let mut columns = vec!["t_s"];
    columns.extend(imp.names.iter().map(String::as_str));
    let from = if !args.names.is_empty() {
        "--names"
    } else if !args.channels.is_empty() {
        "--channels"
    } else {
        "the header"
    };
    // A channel named `t_s` would meet the recording's own time column.
    if imp.names.iter().any(|n| n == "t_s") {
        let way = if from == "--names" {
            "choose another name"
        } else {
            "take the times from it with --time-column t_s, or rename the channel with --names A,B,…"
        };
        return Err(bad(format!(
            "{origin}: a channel named `t_s` ({from}) would be a second time column: {way}"
        )));
    }
    if let Err(e) = crate::recording::check_columns(&columns) {
        return Err(bad(format!(
            "{origin}: the channel names ({from}): {e}; give others with --names A,B,…"
        )));
    }
    if let Some((k, _)) = extra
        .iter()
        .find(|(k, _)| k == "device" || imp.meta.iter().any(|(m, _)| m == k))
    {
        return Err(bad(format!(
            "{origin}: --meta {k}: the import writes `{k}` itself; choose another key"
        )));
    }
    Ok(())
}
