//! The import's checks of what its flags and inputs would write, made
//! before anything is written so a fault is blamed on the input and the
//! flag, never on the staging folder.

use std::path::{Path, PathBuf};

use super::{ImportError, Imported, Request, bad, split};

/// The flags a WAV file does not take, which carries its own rate and
/// channels: refused when every input is a WAV (nothing takes them), else a
/// warning to print (they apply to the other files alone), so the user
/// never believes they reached a WAV. `--rate` is for every format without
/// a rate of its own; the others are for CSV files only.
pub(super) fn flags_a_wav_ignores(args: &Request) -> Result<Option<String>, ImportError> {
    let is_wav = |f: &PathBuf| {
        f.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("wav") || e.eq_ignore_ascii_case("wave"))
    };
    let Some(wav) = args.files.iter().find(|f| is_wav(f)) else {
        return Ok(None);
    };
    let csv_only: Vec<&str> = csv_only(args)
        .iter()
        .filter(|(_, on)| *on)
        .map(|(f, _)| *f)
        .collect();
    let mut said = Vec::new();
    if args.rate.is_some() {
        said.push(
            "--rate applies to files without a rate of their own (CSV, text, .npy, .npz, .mat)"
                .to_string(),
        );
    }
    let verb = match (said.is_empty(), csv_only.len()) {
        (false, _) => "",
        (true, 1) => " applies",
        (true, _) => " apply",
    };
    if !csv_only.is_empty() {
        said.push(format!("{}{verb} to CSV files only", csv_only.join(", ")));
    }
    if said.is_empty() {
        return Ok(None);
    }
    let one = usize::from(args.rate.is_some()) + csv_only.len() == 1;
    let said = said.join(", ");
    if args.files.iter().all(is_wav) {
        return Err(bad(format!(
            "{}: {said}; a WAV file carries its own rate and channels: leave {} out",
            wav.display(),
            if one { "it" } else { "them" }
        )));
    }
    Ok(Some(format!(
        "warning: {said}; {} and any other WAV file keep their own rate and channels",
        wav.display()
    )))
}

/// The flags only a CSV file with a header takes (its columns by name,
/// bursts of one channel, its separator), as (flag, given).
fn csv_only(args: &Request) -> [(&'static str, bool); 5] {
    [
        ("--time-column", args.time_column.is_some()),
        ("--channels", !args.channels.is_empty()),
        ("--label-column", args.label_column.is_some()),
        ("--burst", args.burst != 1),
        ("--delimiter", args.delimiter.is_some()),
    ]
}

/// Refuses the flags only a CSV file with a header takes on `origin`, a
/// file of another kind (`what`), naming them: never ignored without a word.
pub(super) fn csv_only_flags(args: &Request, origin: &str, what: &str) -> Result<(), ImportError> {
    let given: Vec<&str> = csv_only(args)
        .iter()
        .filter(|(_, on)| *on)
        .map(|(f, _)| *f)
        .collect();
    if given.is_empty() {
        return Ok(());
    }
    Err(bad(format!(
        "{origin}: {} {} to CSV files with a header only, and this is {what}: leave {} out \
         (its channels are {}; name them with --names)",
        given.join(", "),
        if given.len() == 1 { "applies" } else { "apply" },
        if given.len() == 1 { "it" } else { "them" },
        match what {
            "a .npz file" | "a .mat file" => "its arrays",
            _ => "its columns or rows, all of them",
        }
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
    // Each trial's own keys are added after this check, when it is cut.
    if args.split.is_some()
        && let Some((k, _)) = extra
            .iter()
            .find(|(k, _)| split::KEYS.contains(&k.as_str()))
    {
        return Err(bad(format!(
            "{origin}: --meta {k}: with --split the import writes `{k}` itself, for each \
             trial; choose another key"
        )));
    }
    Ok(())
}

/// A warning when two or more inputs all sit in one folder and take their
/// label from it: every recording gets that one label (`import
/// raw/long/*.txt` labels all of them "long"), which is right only when
/// they are all one texture.
pub(super) fn one_folder_for_every_label(args: &Request) -> Option<String> {
    if args.label.is_some() || args.label_column.is_some() || args.files.len() < 2 {
        return None;
    }
    let folder = |f: &PathBuf| f.canonicalize().ok()?.parent().map(Path::to_path_buf);
    let first = folder(&args.files[0])?;
    if !args.files[1..]
        .iter()
        .all(|f| folder(f).as_ref() == Some(&first))
    {
        return None;
    }
    let label = first.file_name()?.to_string_lossy().into_owned();
    let shown = match args.files[0].parent() {
        Some(p) if !p.as_os_str().is_empty() => p.display().to_string(),
        _ => first.display().to_string(),
    };
    Some(format!(
        "warning: all {} inputs are in one folder, {shown}, so every recording is labelled \
         {label:?} (the label is each file's folder): if they are not all one texture, give \
         each texture's files a folder of its own (DIR/<label>/FILE), or import each with --label",
        args.files.len()
    ))
}
