//! The text of an analysis-only profile for a [`Survey`]: the settings
//! chosen, the labels found, and the other choices as commented option
//! groups ([`groups_of`], [`apply_group`]), each with a line saying when to
//! use it.

use std::fmt::Write as _;
use std::path::Path;

use super::cautions::{self, per_label};
use super::survey::{self, Survey};
use crate::profile::families::DEFAULT_KERNEL_FEATURES;
use crate::profile::fitted::{ceil_significant, fitting_bands};
use crate::profile::options::Group;
use crate::profile::{Analysis, Classifier, Metric, SpectrumKind, Taper, check_options};

mod evaluation;
#[cfg(test)]
mod tests;
mod writer;

use evaluation::{TimeSplit, evaluation_table, shared_caution, time_split};
pub use writer::shown;
use writer::{Alternatives, Doc, Line, OptionGroup, advised, ceil3, float, floor3, line, wrap};
pub use writer::{apply_group, groups_of};

/// A drafted profile's text, and the cautions its comments hold, for the
/// command to say on standard error too.
pub struct Drafted {
    pub text: String,
    pub cautions: Vec<String>,
    /// Recordings too short for the window (named in the cautions).
    pub uncovered: usize,
}

/// What the survey decides before any text: the axis, rate, spacing,
/// window and spectrum sizes every section derives from.
struct Plan<'a> {
    s: &'a Survey,
    from: &'a Path,
    signal: String,
    more: Vec<String>,
    time: bool,
    unit: &'static str,
    spacing_text: String,
    spacing_why: String,
    extent: f64,
    shortest_file: String,
    end_text: String,
    /// Points in the window, and the window's analysis (log-Welch).
    n: usize,
    analysis: Analysis,
    /// The Welch segment, and whether Welch is the first choice.
    segment: usize,
    welch_active: bool,
    magnitude_bins: usize,
    min_count: usize,
    /// The recordings are consecutive segments of longer ones (`import --split`).
    segments: bool,
    /// The split in time offered (or chosen, for segments).
    split: TimeSplit,
    /// What would quietly spoil the analysis ([`cautions`]).
    cautions: Vec<String>,
    /// The recordings much shorter than the rest, which the window was not
    /// fitted to and which do not cover it.
    uncovered: usize,
}

/// The spacing along the axis: one sample period of the slowest rate in
/// time (so every point holds a sample of every recording), the thesis's
/// 0.3 mm or ten steps along a position axis. (value, text, why).
fn spacing_of(s: &Survey, axis: &str, time: bool) -> (f64, String, String) {
    if time {
        let slowest = s.slowest_rate();
        let why = if s.rates.len() > 1 {
            format!(
                "one sample period of the slowest rate, 1 / {} Hz: the recordings' rates differ (see above), and every point must hold a sample of each",
                shown(slowest)
            )
        } else {
            format!("one sample period, 1 / {} Hz", shown(slowest))
        };
        // Six digits, rounded up (`0.000454546` for 2.2 kHz, not the
        // float noise of `0.00045454545454545455`): a hair coarser than
        // the samples, never finer.
        let (spacing, text) = ceil_significant(1.0 / slowest, 6);
        let why = if spacing == 1.0 / slowest {
            why
        } else {
            format!("{why}, rounded up to six digits")
        };
        return (spacing, text, why);
    }
    let step = s.step.get(axis).copied().unwrap_or(0.0);
    if step * 10.0 <= 0.0003 {
        let why = format!(
            "0.3 mm, the thesis's: about {:.0} samples per point at the recordings' {:.4} mm per sample",
            0.0003 / step.max(1e-12),
            step * 1000.0
        );
        return (0.0003, "0.0003".into(), why);
    }
    let (v, t) = ceil3(step * 10.0);
    (
        v,
        t,
        "ten of the recordings' steps along the axis, so every point holds samples".into(),
    )
}

/// The Welch segment in points: on a time axis about a tenth of a second
/// (10 Hz bins: textures' spectra are broad, and many segments average),
/// at least 64 points (32 bins); elsewhere an eighth of the window; never
/// more than a quarter of the window, so at least seven half-overlapping
/// segments average. A power of two (a fast DFT).
fn welch_segment(n: usize, time: bool, rate: f64) -> usize {
    let target = if time {
        (rate * 0.1).max(64.0)
    } else {
        n as f64 / 8.0
    };
    let nearest = 2f64.powf(target.max(1.0).log2().round()) as usize;
    let cap = (n / 4).max(1);
    nearest.min(1usize << (usize::BITS - 1 - cap.leading_zeros()))
}

fn plan<'a>(s: &'a Survey, from: &'a Path) -> Result<Plan<'a>, String> {
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
    let (spacing, spacing_text, spacing_why) = spacing_of(s, axis, time);
    let ((extent, shortest_file), uncovered) = s.window_reach(axis);
    let too_short = || {
        format!(
            "{shortest_file}: the shortest complete recording spans only {} along {axis}: too short to analyse (at least 8 points of {spacing_text})",
            shown(extent)
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
    let segment = welch_segment(n, time, 1.0 / spacing);
    let min_count = s.labels.values().copied().min().unwrap_or(0);
    let segments = s.varying_meta.iter().any(|k| k == "segment");
    let split = time_split(&s.segments, min_count, segments);
    let cautions = cautions::of_rates(s, time.then_some(spacing_text.as_str()))
        .into_iter()
        .chain(cautions::of_lengths(s, axis, &end_text, spacing))
        .chain(cautions::of_names(s))
        .chain((split.shared > 0).then(|| shared_caution(split.shared)))
        .collect();
    // Log-Welch for other rigs' signals in time (vibration, sound) and for
    // long windows; the thesis's |DFT| for a short stroke resampled by position.
    let welch_active = (time || n > 4096) && segment >= 16;
    analysis.spectrum = SpectrumKind::LogWelch;
    analysis.welch_segment = Some(segment);
    analysis.taper = Taper::Hann;
    Ok(Plan {
        s,
        from,
        signal: signal.clone(),
        more: more.to_vec(),
        time,
        unit: if time { "s" } else { "m" },
        spacing_why,
        extent,
        shortest_file,
        end_text,
        n,
        analysis,
        segment,
        welch_active,
        magnitude_bins: (n / 2).min(128),
        min_count,
        segments,
        split,
        cautions,
        uncovered: uncovered.len(),
        spacing_text,
    })
}

/// The profile's text for the survey `s` of `from`.
pub fn draft(s: &Survey, name: &str, from: &Path) -> Result<Drafted, String> {
    let p = plan(s, from)?;
    let mut doc = Doc::default();
    header(&mut doc, &p);
    let _ = writeln!(doc.0, "name = {name:?}");
    let description = format!(
        "Recordings of {} texture(s) from {}",
        s.labels.len(),
        from.display()
    );
    let _ = writeln!(doc.0, "description = {description:?}");
    doc.blank();
    analysis_table(&mut doc, &p);
    classifier_table(&mut doc, &p);
    evaluation_table(&mut doc, &p);
    Ok(Drafted {
        text: doc.0,
        cautions: p.cautions,
        uncovered: p.uncovered,
    })
}

/// What was found, and how to use the option groups.
fn header(doc: &mut Doc, p: &Plan) {
    let s = p.s;
    let from = p.from.display();
    doc.comment(&format!(
        "An analysis-only profile for the recordings in {from}, written by `hapticlab profile new`.\n\
         It has no [device], [controller] or [path]: it evaluates, trains and classifies\n\
         recordings (`hapticlab evaluate {from} -p THIS.toml`) and makes none.\n"
    ));
    let left_out = match s.incomplete.first() {
        None => String::new(),
        Some(f) => format!(" ({} incomplete left out, e.g. {f})", s.incomplete.len()),
    };
    doc.comment(&format!(
        "Found: {} complete recording(s){left_out}; columns {}; about {} samples a second.",
        s.complete,
        s.columns.join(", "),
        shown(s.rate_hz)
    ));
    if s.rates.len() > 1 {
        doc.comment("The recordings' rates differ (rate: recordings (per label), e.g.):");
        for r in &s.rates {
            doc.comment(&format!(
                "  {} Hz: {} ({}), e.g. {}",
                shown(r.hz),
                r.count,
                per_label(&r.labels),
                r.file
            ));
        }
    }
    for caution in &p.cautions {
        doc.comment(&format!("Caution: {}.", wrap(caution, 90)));
    }
    doc.comment("Labels and recordings per label:");
    for (label, count) in &s.labels {
        doc.comment(&format!("  {label}: {count}"));
    }
    if !s.varying_meta.is_empty() {
        doc.comment(&format!(
            "Metadata that varies between recordings (for group_by below): {}",
            s.varying_meta.join(", ")
        ));
    }
    doc.comment(
        "\nAn option group below is a few `key = value` lines after a line saying when\n\
         to use it: uncomment the group's lines in place of the same keys above it\n\
         (a spectrum group replaces every spectrum line), then `hapticlab check`.",
    );
    doc.blank();
}

/// `[analysis]`, written from the option list: the lines chosen, each
/// with its reason (or its option's advice), and after the spectrum and
/// sub-window groups their alternatives.
fn analysis_table(doc: &mut Doc, p: &Plan) {
    let s = p.s;
    let choice = s.choice();
    let axis = p.analysis.axis.as_str();
    let others: Vec<&str> = s
        .columns
        .iter()
        .filter(|c| *c != axis && *c != "t_s" && !choice.signals.contains(c))
        .map(String::as_str)
        .collect();
    let mut channel = advised("channel", format!("{:?}", p.signal));
    if !others.is_empty() {
        channel = channel.below(format!(
            "Other columns (name one as channel, or add it to channels = [...]): {}",
            others.join(", ")
        ));
    }
    let mut lines = vec![
        channel,
        advised("axis", format!("{axis:?}")),
        advised("window", format!("[0.0, {}]", p.end_text)).below(format!(
            "The whole of the shortest complete recording ({}: {} {} along {axis}), {} points{}.",
            p.shortest_file,
            shown(p.extent),
            p.unit,
            p.n,
            if p.uncovered > 0 {
                "; the much shorter ones named in the Caution above do not cover it"
            } else {
                ""
            },
        )),
        line("spacing", p.spacing_text.clone(), p.spacing_why.clone()),
        advised("detrend", "\"mean\""),
    ];
    if !p.more.is_empty() {
        let names: Vec<String> = p.more.iter().map(|c| format!("{c:?}")).collect();
        lines.push(line(
            "channels",
            format!("[{}]", names.join(", ")),
            "analysed like `channel`, features concatenated",
        ));
    }
    lines.extend(first_spectrum(p));
    let alternatives = vec![
        (
            Group::Spectrum,
            Alternatives {
                intro: Some(
                    "Other spectra and features (one group replaces the spectrum lines above):",
                ),
                groups: Ok(spectrum_groups(p)),
            },
        ),
        (
            Group::Windows,
            Alternatives {
                intro: None,
                groups: windows_group(p).map(|g| vec![g]),
            },
        ),
    ];
    doc.analysis(&format!("{}.", choice.why), lines, alternatives);
}

/// The spectrum lines of the first choice, each with its reason.
fn first_spectrum(p: &Plan) -> Vec<Line> {
    if !p.welch_active {
        return vec![
            line(
                "spectrum",
                "\"magnitude\"",
                "|DFT| of the whole window, the thesis's: a short stroke resampled by position",
            ),
            line(
                "bins",
                format!("[1, {}]", p.magnitude_bins),
                "DC dropped; the first bins hold a stroke's texture periods",
            ),
        ];
    }
    let m = p.segment;
    let seconds = m as f64 * p.analysis.spacing;
    vec![
        line(
            "spectrum",
            "\"log-welch\"",
            "log10 of Welch's averaged spectrum: noisy, broadband signals whose level drifts between trials",
        ),
        line(
            "taper",
            "\"hann\"",
            "each segment tapered, as scipy's welch: without it leakage smears the log spectrum",
        ),
        line(
            "welch_segment",
            m.to_string(),
            format!(
                "{} {}, {} {}-wide bins; {} segments half-overlapping in the window",
                floor3(seconds).1,
                p.unit,
                floor3(p.analysis.bin_width()).1,
                p.analysis.frequency_unit(),
                2 * p.n / m - 1
            ),
        ),
        line(
            "bins",
            format!("[1, {}]", m / 2),
            "every bin but DC, up to the Nyquist frequency",
        ),
    ]
}

fn hann() -> (&'static str, String) {
    ("taper", "\"hann\"".into())
}

fn magnitude_keys(p: &Plan, kind: &str) -> Vec<(&'static str, String)> {
    let mut k = vec![("spectrum", format!("{kind:?}"))];
    if kind != "magnitude" {
        k.push(hann());
    }
    k.push(("bins", format!("[1, {}]", p.magnitude_bins)));
    k
}

fn welch_keys(p: &Plan, kind: &str) -> Vec<(&'static str, String)> {
    vec![
        ("spectrum", format!("{kind:?}")),
        hann(),
        ("welch_segment", p.segment.to_string()),
        ("bins", format!("[1, {}]", p.segment / 2)),
    ]
}

/// Every other spectrum that fits the window, with when to use it.
fn spectrum_groups(p: &Plan) -> Vec<OptionGroup> {
    let top = p.magnitude_bins as f64
        / (p.n as f64 * p.analysis.spacing)
        / if p.time { 1.0 } else { 1000.0 };
    let fu = p.analysis.frequency_unit();
    let mut groups = vec![
        OptionGroup {
            when: format!(
                "|DFT| of the whole window (the thesis), no taper: a few strong periodic peaks, a short window; bins 1–{} reach {} {fu}",
                p.magnitude_bins,
                floor3(top).1
            ),
            keys: magnitude_keys(p, "magnitude"),
        },
        OptionGroup {
            when: "the power (|X|² / n) of each bin, Hann-tapered: as magnitude, with energy rather than amplitude".into(),
            keys: magnitude_keys(p, "power"),
        },
        OptionGroup {
            when: "log10 of the power, Hann-tapered: textures that differ over a wide range of levels, or a gain that drifts between trials".into(),
            keys: magnitude_keys(p, "log-power"),
        },
    ];
    if p.segment < 16 {
        return groups;
    }
    groups.push(OptionGroup {
        when: format!(
            "Welch's average over {}-point Hann-tapered segments: noisy, broadband textures (vibration, sound); smoother than one DFT",
            p.segment
        ),
        keys: welch_keys(p, "welch"),
    });
    groups.push(OptionGroup {
        when: "log10 of the Welch spectrum: other rigs' signals whose level drifts between trials (accelerometers, microphones)".into(),
        keys: welch_keys(p, "log-welch"),
    });
    groups.extend(band_groups(p));
    groups.extend(family_groups());
    groups
}

/// The feature families beside the spectrum (`tune` searches them too).
fn family_groups() -> Vec<OptionGroup> {
    vec![
        OptionGroup {
            when: "interval quantiles of the signal, its differences and its spectrum (QUANT): textures told apart by the shape of the signal more than by its spectrum (a rising and a falling sawtooth have one spectrum); with k-NN or the LDA below".into(),
            keys: vec![("features", "\"quantiles\"".into())],
        },
        OptionGroup {
            when: "random convolutional kernels (MiniRocket), their biases fitted on the training windows: with method = \"ridge\" or \"lda\" below, their pairing".into(),
            keys: vec![
                ("features", "\"kernels\"".into()),
                ("kernel_features", DEFAULT_KERNEL_FEATURES.to_string()),
            ],
        },
        OptionGroup {
            when: "competing random kernels (Hydra), how often each kernel of a group matches the signal and its difference best and worst: motion or vibration sampled slowly (an IMU), short windows; with method = \"ridge\" or \"lda\" below".into(),
            keys: vec![("features", "\"hydra\"".into())],
        },
    ]
}

/// Band energies and their cepstra, when log-spaced bands fit the spectrum.
fn band_groups(p: &Plan) -> Vec<OptionGroup> {
    let Some(b) = fitting_bands(&p.analysis) else {
        return Vec::new();
    };
    let fu = p.analysis.frequency_unit();
    let bands = format!(
        "{{ count = {}, from = {}, to = {}, scale = \"log\" }}",
        b.count,
        float(b.from),
        float(b.to)
    );
    let mut k = welch_keys(p, "log-welch");
    k.retain(|(key, _)| *key != "bins");
    k.push(("bands", bands));
    let c = b.count.min(13);
    let mut cepstra = k.clone();
    cepstra.push(("cepstra", c.to_string()));
    cepstra.push(("drop_level", "true".into()));
    vec![
        OptionGroup {
            when: format!(
                "{} log-spaced band energies ({}–{} {fu}) of the log-Welch spectrum: fewer, steadier features over a wide band (sound, vibration)",
                b.count,
                float(b.from),
                float(b.to)
            ),
            keys: k,
        },
        OptionGroup {
            when: format!(
                "{c} cepstra of those bands without c0 (as MFCCs, the tool-mediated texture literature's features): drop_level when the gain drifts between trials"
            ),
            keys: cepstra,
        },
    ]
}

/// Sub-windows, half-overlapping, each a vote: about a tenth of the window
/// (the generated stylus-sound set of contrib/rig-sets.py, 5 s clips, gave
/// 98 % at 0.5 s and 93 % at 1.24 s), but at least two Welch segments (or
/// 16 points of one DFT) so each still averages, and at most half the
/// window so at least three fit. `Err`: why none fits.
fn windows_group(p: &Plan) -> Result<OptionGroup, String> {
    let least = if p.welch_active { 2 * p.segment } else { 16 };
    let points = (p.n / 10).max(least);
    if points > p.n / 2 {
        return Err(format!(
            "the window's {} points hold no three sub-windows of {least} points",
            p.n
        ));
    }
    let spacing = p.analysis.spacing;
    // Rounded up, so the sub-window keeps its points; the hop down, but
    // never below the spacing.
    let (length, length_text) = ceil3(points as f64 * spacing);
    let (hop, hop_text) = floor3(length / 2.0);
    let (hop, hop_text) = if hop < spacing {
        (spacing, p.spacing_text.clone())
    } else {
        (hop, hop_text)
    };
    let w = crate::profile::Windows { length, hop };
    let sub = Analysis {
        windows: Some(w),
        spectrum: if p.welch_active {
            SpectrumKind::LogWelch
        } else {
            SpectrumKind::Magnitude
        },
        welch_segment: p.welch_active.then_some(p.segment),
        ..p.analysis.clone()
    };
    let mut keys = vec![(
        "windows",
        format!("{{ length = {length_text}, hop = {hop_text} }}"),
    )];
    if !p.welch_active {
        let bins = (sub.points() / 2).min(p.magnitude_bins);
        keys.push(("bins", format!("[1, {bins}]")));
    }
    crate::profile::check_windows(&sub, w)?;
    check_options(&sub).map_err(|(k, why)| format!("{k} {why}"))?;
    let unit = p.unit;
    Ok(OptionGroup {
        when: format!(
            "cut the window into {length_text} {unit} windows every {hop_text} {unit}: more examples from few recordings, each recording classified by its windows' vote"
        ),
        keys,
    })
}

fn classifier_table(doc: &mut Doc, p: &Plan) {
    // 1-NN whatever the count: on the generated sets with 30 and 50
    // recordings per label (the long IMU set cut into trials, the
    // fingertip set at 50 trials), 5-NN scored below 1-NN at every seed
    // it differed (contrib/rig-sets.py; the README's table), as on the
    // real 1000-trial set; tune tries 3, 5 and 9.
    let why = "the nearest recording decides (as the 1-NN script a researcher writes; more neighbours lost to it on every generated set): `tune` tries 3, 5 and 9";
    let c = Classifier {
        k: 1,
        metric: Metric::Euclidean,
        ..Classifier::default()
    };
    let mut groups = vec![OptionGroup {
        when: "z-score every feature over the training set: features of very different sizes (several channels, log and linear)".into(),
        keys: vec![("standardize", "true".into())],
    }];
    if p.min_count >= 3 {
        groups.push(OptionGroup {
            when: "k chosen by cross-validation inside the training set: when unsure which k"
                .into(),
            keys: vec![("k", "\"auto\"".into())],
        });
    }
    groups.push(OptionGroup {
        when: "the angle between spectra, not their size: recordings whose overall level differs"
            .into(),
        keys: vec![("metric", "\"cosine\"".into())],
    });
    groups.push(OptionGroup {
        when: "a ridge classifier, its penalty chosen by leave-one-out inside the training set: many features against few recordings (the random kernels)".into(),
        keys: vec![("method", "\"ridge\"".into())],
    });
    groups.push(OptionGroup {
        when: "linear discriminant analysis with a shrunk covariance (Ledoit-Wolf): log spectra, quantiles or kernels whose classes differ by a shift".into(),
        keys: vec![("method", "\"lda\"".into())],
    });
    doc.classifier(
        &c,
        &[("k", why), ("metric", "the distance between spectra")],
        groups,
    );
}
