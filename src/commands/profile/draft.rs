//! The text of an analysis-only profile for a [`Survey`]: the settings
//! chosen, the labels found, and the other choices as commented option
//! groups ([`groups_of`], [`apply_group`]), each with a line saying when to
//! use it.

use std::fmt::Write as _;
use std::path::Path;

use super::survey::Survey;
#[cfg(test)]
use crate::profile::LoadedProfile;
use crate::profile::{Analysis, Bands, SpectrumKind, check_options};

/// Round down to three significant digits, as text TOML reads back exactly.
fn floor3(x: f64) -> (f64, String) {
    round3(x, f64::floor)
}

fn ceil3(x: f64) -> (f64, String) {
    round3(x, f64::ceil)
}

fn round3(x: f64, how: fn(f64) -> f64) -> (f64, String) {
    let e = x.abs().log10().floor() as i32 - 2;
    let decimals = (-e).max(0) as usize;
    let v = how(x / 10f64.powi(e)) * 10f64.powi(e);
    let text = format!("{v:.decimals$}");
    let v: f64 = text.parse().unwrap_or(v);
    (
        v,
        if text.contains('.') {
            text
        } else {
            format!("{text}.0")
        },
    )
}

/// A float as TOML, read back to the same value.
fn float(v: f64) -> String {
    let t = format!("{v}");
    if t.contains('.') || t.contains('e') {
        t
    } else {
        format!("{t}.0")
    }
}

/// One commented option group: what it is for, and its `key = value` lines.
struct Group {
    when: String,
    keys: Vec<(&'static str, String)>,
}

/// The keys a spectrum group replaces (the group sets the spectrum anew).
pub const SPECTRUM_KEYS: [&str; 8] = [
    "spectrum",
    "bins",
    "band",
    "bands",
    "welch_segment",
    "welch_overlap",
    "cepstra",
    "drop_level",
];

/// The profile's text for the survey `s` of `from`.
pub fn draft(s: &Survey, name: &str, from: &Path) -> Result<String, String> {
    let choice = s.choice();
    let axis = choice.axis.as_str();
    let Some((signal, more)) = choice.signals.split_first() else {
        if let Some([(a, a_cols), (b, b_cols)]) = &s.differing {
            return Err(format!(
                "the recordings share no channel to analyse (in common only: {}): {a} has {} but \
                 {b} has {}; survey recordings of one kind together",
                if s.columns.is_empty() {
                    "nothing".to_string()
                } else {
                    s.columns.join(", ")
                },
                a_cols.join(", "),
                b_cols.join(", ")
            ));
        }
        return Err(format!(
            "{}: no column varies besides the axis ({}): nothing to analyse",
            from.display(),
            s.columns.join(", ")
        ));
    };
    let time = axis == "t_s";
    let (spacing, spacing_text, spacing_why) = if time {
        let sp = 1.0 / s.rate_hz;
        (
            sp,
            float(sp),
            format!("one sample period, 1 / {} Hz", s.rate_hz),
        )
    } else {
        let step = s.step.get(axis).copied().unwrap_or(0.0);
        if step * 10.0 <= 0.0003 {
            (
                0.0003,
                "0.0003".to_string(),
                format!(
                    "0.3 mm, the thesis's: about {:.0} samples per point at the recordings' {:.4} mm per sample",
                    0.0003 / step.max(1e-12),
                    step * 1000.0
                ),
            )
        } else {
            let (v, t) = ceil3(step * 10.0);
            (
                v,
                t,
                "ten of the recordings' steps along the axis, so every point holds samples".into(),
            )
        }
    };
    let (extent, shortest_file) = s.shortest.get(axis).cloned().unwrap_or_default();
    let too_short = || {
        format!(
            "{shortest_file}: the shortest complete recording spans only {extent} along {axis}: too short to analyse (at least 8 points of {spacing_text})"
        )
    };
    if !(extent.is_finite() && extent >= 8.0 * spacing) {
        return Err(too_short());
    }
    let (end, end_text) = floor3(extent);
    let mut analysis = Analysis {
        channel: signal.clone(),
        channels: more.to_vec(),
        axis: axis.to_string(),
        window: [0.0, end],
        spacing,
        ..Analysis::default()
    };
    let n = analysis.points();
    if n < 8 {
        return Err(too_short());
    }
    let unit = if time { "s" } else { "m" };
    let fu = analysis.frequency_unit();
    // The DFT length of a Welch segment: a power of two, at most 2048 and a
    // quarter of the window, so several segments average.
    let segment = (n / 4).clamp(1, 2048);
    let segment = 1usize << (usize::BITS - 1 - segment.leading_zeros());
    let welch_ok = segment >= 16;
    // Log-Welch for other rigs' signals in time (vibration, sound: the
    // issue's reference reached its best with it) and for long windows;
    // the thesis's |DFT| for a short stroke resampled by position.
    let welch_active = (time || n > 4096) && welch_ok;
    let magnitude_bins = (n / 2).min(128);
    let mut groups: Vec<Group> = Vec::new();
    let mag = |kind: &str| {
        vec![
            ("spectrum", format!("{kind:?}")),
            ("bins", format!("[1, {magnitude_bins}]")),
        ]
    };
    let welch = |kind: &str| {
        vec![
            ("spectrum", format!("{kind:?}")),
            ("welch_segment", segment.to_string()),
            ("bins", format!("[1, {}]", segment / 2)),
        ]
    };
    let active = if welch_active {
        welch("log-welch")
    } else {
        mag("magnitude")
    };
    let top = |bins: usize, m: usize| {
        bins as f64 / (m as f64 * spacing) / if time { 1.0 } else { 1000.0 }
    };
    groups.push(Group {
        when: format!(
            "|DFT| of the whole window (the thesis): a few strong periodic peaks, a short window; bins 1–{magnitude_bins} reach {} {fu}",
            floor3(top(magnitude_bins, n)).1
        ),
        keys: mag("magnitude"),
    });
    groups.push(Group {
        when: "the power (|X|² / n) of each bin: as magnitude, with energy rather than amplitude"
            .into(),
        keys: mag("power"),
    });
    groups.push(Group {
        when: "log10 of the power: textures that differ over a wide range of levels, or a gain that drifts between trials".into(),
        keys: mag("log-power"),
    });
    if welch_ok {
        groups.push(Group {
            when: format!(
                "Welch's average over {segment}-point segments: noisy, broadband textures (vibration, sound); smoother than one DFT"
            ),
            keys: welch("welch"),
        });
        groups.push(Group {
            when: "log10 of the Welch spectrum: other rigs' signals whose level drifts between trials (accelerometers, microphones)".into(),
            keys: welch("log-welch"),
        });
        analysis.spectrum = SpectrumKind::LogWelch;
        analysis.welch_segment = Some(segment);
        if let Some(b) = fitting_bands(&analysis) {
            let bands = format!(
                "{{ count = {}, from = {}, to = {}, scale = \"log\" }}",
                b.count,
                float(b.from),
                float(b.to)
            );
            let mut k = welch("log-welch");
            k.retain(|(key, _)| *key != "bins");
            k.push(("bands", bands));
            groups.push(Group {
                when: format!(
                    "{} log-spaced band energies ({}–{} {fu}) of the log-Welch spectrum: fewer, steadier features over a wide band (sound, vibration)",
                    b.count,
                    float(b.from),
                    float(b.to)
                ),
                keys: k.clone(),
            });
            let c = b.count.min(13);
            k.push(("cepstra", c.to_string()));
            k.push(("drop_level", "true".into()));
            groups.push(Group {
                when: format!(
                    "{c} cepstra of those bands without c0 (as MFCCs, the tool-mediated texture literature's features): drop_level when the gain drifts between trials"
                ),
                keys: k,
            });
        }
    }
    let min_count = s.labels.values().copied().min().unwrap_or(0);
    let mut text = String::new();
    let w = &mut text;
    let _ = writeln!(
        w,
        "# An analysis-only profile for the recordings in {}, written by `hapticlab profile new`.",
        from.display()
    );
    let _ = writeln!(
        w,
        "# It has no [device], [controller] or [path]: it evaluates, trains and classifies\n\
         # recordings (`hapticlab evaluate {} -p THIS.toml`) and makes none.",
        from.display()
    );
    let _ = writeln!(w, "#");
    let _ = writeln!(
        w,
        "# Found: {} complete recording(s){}; columns {}; about {} samples a second.",
        s.complete,
        if s.incomplete.is_empty() {
            String::new()
        } else {
            format!(
                " ({} incomplete left out, e.g. {})",
                s.incomplete.len(),
                s.incomplete[0]
            )
        },
        s.columns.join(", "),
        float(s.rate_hz)
    );
    let _ = writeln!(w, "# Labels and recordings per label:");
    for (label, count) in &s.labels {
        let _ = writeln!(w, "#   {label}: {count}");
    }
    if !s.varying_meta.is_empty() {
        let _ = writeln!(
            w,
            "# Metadata that varies between recordings (for group_by below): {}",
            s.varying_meta.join(", ")
        );
    }
    let _ = writeln!(w, "#");
    let _ = writeln!(
        w,
        "# An option group below is a few `key = value` lines after a line saying when\n\
         # to use it: uncomment the group's lines in place of the same keys above it\n\
         # (a spectrum group replaces every spectrum line), then `hapticlab check`."
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "name = {name:?}");
    let _ = writeln!(
        w,
        "description = {:?}",
        format!(
            "Recordings of {} texture(s) from {}",
            s.labels.len(),
            from.display()
        )
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "[analysis]");
    let _ = writeln!(w, "# {}.", choice.why);
    let others: Vec<&String> = s
        .columns
        .iter()
        .filter(|c| *c != axis && *c != "t_s" && !choice.signals.contains(c))
        .collect();
    let _ = writeln!(w, "channel = {signal:?}");
    if !more.is_empty() {
        let _ = writeln!(
            w,
            "channels = [{}]   # analysed like `channel`, features concatenated",
            more.iter()
                .map(|c| format!("{c:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !others.is_empty() {
        let _ = writeln!(
            w,
            "# Other columns (name one as channel, or add it to channels = [...]): {}",
            others
                .iter()
                .map(|c| c.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(w, "axis = {axis:?}");
    let _ = writeln!(
        w,
        "# The whole of the shortest complete recording ({shortest_file}: {} {unit} along {axis}), {n} points.",
        float(extent)
    );
    let _ = writeln!(w, "window = [0.0, {end_text}]");
    let _ = writeln!(w, "spacing = {spacing_text}   # {spacing_why}");
    let _ = writeln!(w, "detrend = \"mean\"");
    for (k, v) in &active {
        let _ = writeln!(w, "{k} = {v}");
    }
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "# Other spectra and features (one group replaces the spectrum lines above):"
    );
    write_groups(w, &groups);
    // Sub-windows, half-overlapping, each a vote: about a tenth of the
    // window (the generated stylus-sound set of contrib/rig-sets.py, 5 s
    // clips, gave 98 % at 0.5 s and 93 % at 1.24 s), but at least two Welch
    // segments, so each sub-window still averages, and at most half the
    // window.
    let least = if welch_active {
        2.0 * segment as f64 * spacing
    } else {
        0.0
    };
    let (length, length_text) = floor3((end / 10.0).max(least).min(end / 2.0));
    let (_, hop_text) = floor3(length / 2.0);
    let sub = Analysis {
        windows: Some(crate::profile::Windows {
            length,
            hop: length / 2.0,
        }),
        ..analysis.clone()
    };
    let mut windows = vec![(
        "windows",
        format!("{{ length = {length_text}, hop = {hop_text} }}"),
    )];
    if !welch_active {
        windows.push((
            "bins",
            format!("[1, {}]", (sub.points() / 2).min(magnitude_bins)),
        ));
    }
    let _ = writeln!(w, "# Sub-windows that vote:");
    write_groups(
        w,
        &[Group {
            when: format!(
                "cut the window into {length_text} {unit} windows every {hop_text} {unit}: more examples from few recordings, each recording classified by its windows' vote"
            ),
            keys: windows,
        }],
    );
    let few = min_count < 5;
    let k = if min_count <= 10 { 1 } else { 5 };
    let _ = writeln!(w, "[classifier]");
    let _ = writeln!(
        w,
        "k = {k}   # {}",
        if k == 1 {
            "the nearest recording decides: few recordings per label"
        } else {
            "five neighbours vote: enough recordings per label to outvote a stray one"
        }
    );
    let _ = writeln!(w, "metric = \"euclidean\"");
    let _ = writeln!(w);
    write_groups(
        w,
        &[
            Group {
                when: "z-score every feature over the training set: features of very different sizes (several channels, log and linear)".into(),
                keys: vec![("standardize", "true".into())],
            },
            Group {
                when: "k chosen by cross-validation inside the training set: when unsure which k".into(),
                keys: vec![("k", "\"auto\"".into())],
            },
            Group {
                when: "the angle between spectra, not their size: recordings whose overall level differs".into(),
                keys: vec![("metric", "\"cosine\"".into())],
            },
        ],
    );
    let _ = writeln!(w, "[evaluation]");
    let folds = min_count.clamp(2, 10);
    if few {
        let _ = writeln!(
            w,
            "# Fewer than 5 recordings of some label ({min_count}): each is tested against all the others."
        );
        let _ = writeln!(w, "method = \"leave-one-out\"");
    } else {
        let _ = writeln!(
            w,
            "# {min_count} or more recordings per label: stratified {folds}-fold cross-validation."
        );
        let _ = writeln!(w, "method = \"k-fold\"");
        let _ = writeln!(w, "folds = {folds}");
    }
    let _ = writeln!(w);
    let mut eval_groups = vec![if few {
        Group {
            when: format!(
                "{folds}-fold cross-validation: once there are more recordings per label"
            ),
            keys: vec![
                ("method", "\"k-fold\"".into()),
                ("folds", folds.to_string()),
            ],
        }
    } else {
        Group {
            when: "each recording tested against all the others: few recordings per label".into(),
            keys: vec![("method", "\"leave-one-out\"".into())],
        }
    }];
    if min_count >= 2 {
        // Half and half: the time split of recordings made over days (the
        // thesis's own split was 20 + 10 of 30).
        let train = min_count.div_ceil(2);
        eval_groups.push(Group {
            when: format!(
                "a fixed split in time: per label the first {train} recordings (file-name order) train and the next {} test; for recordings made in order over days, the later ones drifting",
                min_count - train
            ),
            keys: vec![
                ("method", "\"holdout\"".into()),
                ("train_per_class", train.to_string()),
                ("test_per_class", (min_count - train).to_string()),
            ],
        });
    }
    if let Some(key) = s.varying_meta.first() {
        let mut keys = vec![("method", "\"leave-one-out\"".into())];
        keys.push(("group_by", format!("{key:?}")));
        eval_groups.push(Group {
            when: format!(
                "recordings sharing a {key} stay on one side of every split: trials or sessions that resemble each other"
            ),
            keys,
        });
    }
    write_groups(w, &eval_groups);
    Ok(text)
}

fn write_groups(w: &mut String, groups: &[Group]) {
    for g in groups {
        let _ = writeln!(w, "# -- {}", g.when);
        for (k, v) in &g.keys {
            let _ = writeln!(w, "# {k} = {v}");
        }
        let _ = writeln!(w);
    }
}

/// Log-spaced bands from a few bins up to Nyquist that each hold a bin:
/// as many as 32, fewer when the spectrum is too coarse.
fn fitting_bands(a: &Analysis) -> Option<Bands> {
    let bw = a.bin_width();
    let nyquist = bw * (a.dft_points() / 2) as f64;
    for count in [32, 24, 16, 12, 8] {
        for lowest in [2.0, 4.0, 8.0, 16.0] {
            let from = floor3(bw * lowest).0;
            let to = floor3(nyquist).0;
            if !(from > 0.0 && to > from) {
                continue;
            }
            let b = Bands {
                count,
                from,
                to,
                scale: crate::profile::BandScale::Log,
            };
            let candidate = Analysis {
                bands: Some(b),
                ..a.clone()
            };
            if check_options(&candidate).is_ok() {
                return Some(b);
            }
        }
    }
    None
}

/// The option groups of a drafted profile: (table, key lines).
pub fn groups_of(text: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut out = Vec::new();
    let mut table = String::new();
    let mut current: Option<Vec<(String, String)>> = None;
    for line in text.lines() {
        if let Some(t) = line.strip_prefix('[') {
            table = t.trim_end_matches(']').to_string();
        }
        if line.starts_with("# -- ") {
            if let Some(g) = current.take() {
                out.push((table.clone(), g));
            }
            current = Some(Vec::new());
            continue;
        }
        match (
            line.strip_prefix("# ").and_then(|l| l.split_once(" = ")),
            &mut current,
        ) {
            (Some((k, v)), Some(g)) if !k.contains(' ') => g.push((k.to_string(), v.to_string())),
            (_, Some(_)) => {
                if let Some(g) = current.take() {
                    out.push((table.clone(), g));
                }
            }
            _ => {}
        }
    }
    if let Some(g) = current {
        out.push((table, g));
    }
    out
}

/// The profile `text` with an option group in place: its keys set in
/// `table`; a spectrum group first removes every spectrum key, an
/// evaluation group with a `method` the whole `[evaluation]`.
pub fn apply_group(text: &str, table: &str, keys: &[(String, String)]) -> Result<String, String> {
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
    let t = doc
        .get_mut(table)
        .and_then(|v| v.as_table_mut())
        .ok_or_else(|| format!("no [{table}]"))?;
    if keys.iter().any(|(k, _)| k == "spectrum") {
        t.retain(|k, _| SPECTRUM_KEYS.iter().all(|s| *s != k));
    }
    if table == "evaluation" && keys.iter().any(|(k, _)| k == "method") {
        t.clear();
    }
    for (k, v) in keys {
        let parsed: toml::Table =
            toml::from_str(&format!("v = {v}")).map_err(|e| format!("{k} = {v}: {e}"))?;
        t.insert(k.clone(), parsed["v"].clone());
    }
    toml::to_string(&doc).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn survey_of(columns: &[&str], labels: &[(&str, usize)], rate: f64, extent: f64) -> Survey {
        let mut s = Survey {
            complete: labels.iter().map(|l| l.1).sum(),
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rate_hz: rate,
            labels: labels.iter().map(|(l, n)| (l.to_string(), *n)).collect(),
            varying_meta: vec!["trial".into()],
            ..Survey::default()
        };
        for c in columns {
            let moves = *c == "t_s" || *c == "x_m";
            s.shortest.insert(
                c.to_string(),
                (if moves { extent } else { 0.0001 }, "a/a_001.csv".into()),
            );
            s.step
                .insert(c.to_string(), if *c == "x_m" { 1e-5 } else { 1.0 / rate });
            s.spread.insert(c.to_string(), 1.0);
        }
        s
    }

    /// Every option group, put in place, gives a profile that loads.
    fn every_group_loads(text: &str) -> usize {
        LoadedProfile::from_str(text, "drafted", Path::new(".")).unwrap();
        let groups = groups_of(text);
        for (table, keys) in &groups {
            let t = apply_group(text, table, keys).unwrap();
            if let Err(e) = LoadedProfile::from_str(&t, "drafted", Path::new(".")) {
                panic!("[{table}] {keys:?}: {e}\n{t}");
            }
        }
        groups.len()
    }

    #[test]
    fn a_sound_set_gets_log_welch_leave_one_out_and_valid_options() {
        let s = survey_of(&["t_s", "mic"], &[("glass", 4), ("wood", 4)], 44100.0, 4.9);
        let text = draft(&s, "sound", Path::new("rec")).unwrap();
        assert!(text.contains("spectrum = \"log-welch\""), "{text}");
        assert!(text.contains("welch_segment = 2048"), "{text}");
        assert!(text.contains("window = [0.0, 4.90]"), "{text}");
        assert!(text.contains("method = \"leave-one-out\""), "{text}");
        assert!(text.contains("#   glass: 4"), "{text}");
        assert!(text.contains("# cepstra = "), "{text}");
        assert!(every_group_loads(&text) >= 10);
    }

    #[test]
    fn a_stroke_gets_the_height_along_the_travel_and_valid_options() {
        let cols = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n"];
        let s = survey_of(&cols, &[("S1", 30), ("S2", 30)], 1000.0, 0.08975);
        let c = s.choice();
        assert_eq!(
            (c.axis.as_str(), c.signals.clone()),
            ("x_m", vec!["y_m".to_string()])
        );
        let text = draft(&s, "stroke", Path::new("rec")).unwrap();
        assert!(text.contains("window = [0.0, 0.0897]"), "{text}");
        assert!(text.contains("spacing = 0.0003"), "{text}");
        assert!(text.contains("spectrum = \"magnitude\""), "{text}");
        assert!(text.contains("folds = 10"), "{text}");
        assert!(
            text.contains("fy_n"),
            "the other columns are listed: {text}"
        );
        assert!(every_group_loads(&text) >= 8);
    }

    #[test]
    fn a_multichannel_vibration_set_analyses_each_varying_channel() {
        let s = survey_of(
            &["t_s", "ax", "ay", "az"],
            &[("a", 10), ("b", 10)],
            2200.0,
            2.0,
        );
        let c = s.choice();
        assert_eq!(c.axis, "t_s");
        assert_eq!(c.signals, ["ax", "ay", "az"]);
        let text = draft(&s, "vib", Path::new("rec")).unwrap();
        assert!(text.contains("channels = [\"ay\", \"az\"]"), "{text}");
        assert!(every_group_loads(&text) >= 8);
    }

    #[test]
    fn a_recording_too_short_is_refused_naming_it() {
        let s = survey_of(&["t_s", "mic"], &[("a", 2)], 1000.0, 0.003);
        let e = draft(&s, "short", Path::new("rec")).unwrap_err();
        assert!(e.contains("a/a_001.csv") && e.contains("too short"), "{e}");
    }

    #[test]
    fn three_significant_digits_round_the_right_way() {
        assert_eq!(floor3(0.08979).1, "0.0897");
        assert_eq!(floor3(4.999).1, "4.99");
        assert_eq!(floor3(123.9).1, "123.0");
        assert_eq!(ceil3(0.000101).1, "0.000101");
        assert_eq!(ceil3(0.0001011).1, "0.000102");
    }
}
