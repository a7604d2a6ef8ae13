//! Drafts of every kind load, and so does each of their option groups in place.

use std::collections::BTreeMap;

use super::*;
use crate::commands::profile::survey::Segment;
use crate::profile::LoadedProfile;

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
    let text = draft(&s, "sound", Path::new("rec")).unwrap().text;
    assert!(text.contains("spectrum = \"log-welch\""), "{text}");
    assert!(text.contains("welch_segment = 4096   # 0.0928 s"), "{text}");
    assert!(text.contains("taper = \"hann\"   # "), "{text}");
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
    let text = draft(&s, "stroke", Path::new("rec")).unwrap().text;
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
    let text = draft(&s, "vib", Path::new("rec")).unwrap().text;
    assert!(text.contains("channels = [\"ay\", \"az\"]"), "{text}");
    assert!(every_group_loads(&text) >= 8);
}

#[test]
fn a_recording_too_short_is_refused_naming_it() {
    let s = survey_of(&["t_s", "mic"], &[("a", 2)], 1000.0, 0.003);
    let Err(e) = draft(&s, "short", Path::new("rec")) else {
        panic!("a recording too short to analyse was drafted");
    };
    assert!(e.contains("a/a_001.csv") && e.contains("too short"), "{e}");
}

#[test]
fn recordings_of_widely_varying_length_fit_the_window_to_the_shortest_and_say_so() {
    let mut s = survey_of(&["t_s", "mic"], &[("a", 4), ("b", 4)], 1000.0, 1.0);
    let files: Vec<String> = (0..8).map(|i| format!("x/{i}.csv")).collect();
    // Half the trials last 1 s, half 3 s: lengths that vary, not a few aborted trials.
    let travels = (0..8).map(|i| (if i < 4 { 1.0 } else { 3.0 }, &files[i]));
    s.reach
        .insert("t_s".into(), super::super::survey::reach(travels));
    let d = draft(&s, "varied", Path::new("rec")).unwrap();
    assert!(d.text.contains("window = [0.0, 1.00]"), "{}", d.text);
    assert_eq!(d.uncovered, 0);
    assert_eq!(d.cautions.len(), 1, "{:?}", d.cautions);
    assert!(
        d.cautions[0].starts_with(
            "4 of 8 recordings are under half the median length along t_s (3.0 s), e.g. x/0.csv (1.0 s): the window fits the shortest"
        ),
        "{:?}",
        d.cautions
    );
}

/// `per` segments of `length` s every `hop` s of one source per label.
fn segments(per: usize, length: f64, hop: f64) -> BTreeMap<String, Vec<Option<Segment>>> {
    ["a", "b"]
        .iter()
        .map(|l| {
            let list = (0..per)
                .map(|i| {
                    Some(Segment {
                        source: format!("{l}.csv"),
                        start: i as f64 * hop,
                        length,
                    })
                })
                .collect();
            (l.to_string(), list)
        })
        .collect()
}

#[test]
fn the_time_split_leaves_out_the_segments_that_overlap_its_training_ones() {
    let split = |per, length, hop| time_split(&segments(per, length, hop), per, true);
    // No overlap: 70 / 30, nothing left out.
    let s = split(30, 2.0, 2.0);
    assert_eq!((s.train, s.gap, s.test, s.overlapping), (21, 0, 9, false));
    // 2 s every 0.5 s: the three after the training ones share signal.
    let s = split(40, 2.0, 0.5);
    assert_eq!((s.train, s.gap, s.test, s.shared), (26, 3, 11, 0));
    // Two segments a label: no room for a gap; both test ones overlap.
    let s = split(2, 2.0, 1.0);
    assert_eq!((s.train, s.gap, s.test, s.shared), (1, 0, 1, 2));
    let d = draft(&segmented_survey(2), "few", Path::new("rec")).unwrap();
    assert!(
        d.cautions[0].starts_with("2 test segment(s) of the time split share signal"),
        "{:?}",
        d.cautions
    );
    assert!(
        d.text.contains("# Caution: 2 test segment(s)"),
        "{}",
        d.text
    );
}

/// A survey of `per` overlapping segments (2 s every 1 s) per label.
fn segmented_survey(per: usize) -> Survey {
    let mut s = survey_of(&["t_s", "acc"], &[("a", per), ("b", per)], 100.0, 2.0);
    s.varying_meta = vec!["segment".into(), "segment_start_s".into()];
    s.segments = segments(per, 2.0, 1.0);
    s
}
