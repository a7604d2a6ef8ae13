//! `profile new` on folders of different character (short, long, sound-rate,
//! low-rate, mixed rates, segments of long recordings): every line it writes,
//! commented or not, passes `check` once put in place, as a person would
//! put it (the group's lines uncommented, the lines they replace removed).

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use crate::common::{p, run};

/// The keys a spectrum group replaces: every spectrum line above it.
const SPECTRUM_KEYS: [&str; 9] = [
    "spectrum",
    "taper",
    "bins",
    "band",
    "bands",
    "welch_segment",
    "welch_overlap",
    "cepstra",
    "drop_level",
];

/// A recording v1 of `n` samples at `rate` Hz: a tone that differs by
/// label, with noise, and the metadata `meta` (TOML lines).
fn recording(label: &str, tone: f64, n: usize, rate: f64, meta: &str, seed: u64) -> String {
    let mut s = format!(
        "# hapticlab recording v1\n# label = \"{label}\"\n# device = \"test\"\n# rate_hz = {rate:.1}\n{meta}t_s,acc\n"
    );
    let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(7);
    for i in 0..n {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let noise = ((x >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
        let t = i as f64 / rate;
        let v = (std::f64::consts::TAU * tone * rate * t).sin() + 0.5 * noise;
        let _ = writeln!(s, "{t:.7},{v:.5}");
    }
    let _ = writeln!(s, "# end samples = {n}");
    s
}

/// Recording `i`'s samples, rate and metadata lines.
type Shape = Box<dyn Fn(usize) -> (usize, f64, String)>;

/// Two labels × `per` recordings, each (samples, rate) from `shape(i)`.
fn folder(dir: &Path, per: usize, shape: impl Fn(usize) -> (usize, f64, String)) {
    for (l, label) in ["a", "b"].iter().enumerate() {
        fs::create_dir_all(dir.join(label)).unwrap();
        for i in 0..per {
            let (n, rate, meta) = shape(i);
            let tone = [0.05, 0.17][l];
            let text = recording(label, tone, n, rate, &meta, (l * 100 + i) as u64);
            fs::write(dir.join(label).join(format!("{label}-{i:03}.csv")), text).unwrap();
        }
    }
}

/// `text` with option group `g` (its `# -- ` line's index) in place.
fn with_group(text: &str, g: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let keys: Vec<(&str, &str)> = lines[g + 1..]
        .iter()
        .map_while(|l| l.strip_prefix("# ")?.split_once(" = "))
        .collect();
    let table = lines[..g]
        .iter()
        .rev()
        .find(|l| l.starts_with('['))
        .unwrap()
        .trim_matches(['[', ']']);
    let replaces = |key: &str| {
        keys.iter().any(|(k, _)| *k == key)
            || (keys
                .iter()
                .any(|(k, _)| *k == "spectrum" || *k == "features")
                && SPECTRUM_KEYS.contains(&key))
            || (table == "evaluation" && keys.iter().any(|(k, _)| *k == "method"))
    };
    let mut out = String::new();
    let mut current = "";
    for (i, l) in lines.iter().enumerate() {
        if l.starts_with('[') {
            current = l.trim_matches(['[', ']']);
        }
        let key = l.split_once(" = ").map(|(k, _)| k.trim());
        if current == table && !l.starts_with('#') && key.is_some_and(replaces) {
            continue;
        }
        if i > g && i <= g + keys.len() {
            out.push_str(&l[2..]);
        } else {
            out.push_str(l);
        }
        out.push('\n');
    }
    out
}

/// `profile new` on `rec`, then `check` of the profile and of each of its
/// option groups in place; the number of groups.
fn every_line_checks(rec: &Path, dir: &Path) -> (String, usize) {
    let out = dir.join(format!(
        "{}.toml",
        rec.file_name().unwrap().to_string_lossy()
    ));
    let r = run(&["profile", "new", "--from", p(rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    let r = run(&["check", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}\n{text}");
    let starts: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.starts_with("# -- "))
        .map(|(i, _)| i)
        .collect();
    for &g in &starts {
        let t = with_group(&text, g);
        let f = dir.join("group.toml");
        fs::write(&f, &t).unwrap();
        let r = run(&["check", p(&f)]);
        assert_eq!(
            r.code,
            Some(0),
            "{}\n{r:?}\n{t}",
            text.lines().nth(g).unwrap()
        );
    }
    (text, starts.len())
}

#[test]
fn every_line_profile_new_writes_passes_check_on_folders_of_every_kind() {
    let dir = tempfile::tempdir().unwrap();
    let plain = |n: usize, rate: f64| move |i: usize| (n, rate, format!("# trial = {i}\n"));
    let kinds: Vec<(&str, usize, Shape)> = vec![
        ("short", 3, Box::new(plain(20, 1000.0))),
        ("long", 2, Box::new(plain(200_000, 1000.0))),
        ("sound", 3, Box::new(plain(22_050, 44_100.0))),
        ("low-rate", 6, Box::new(plain(200, 100.0))),
        (
            "mixed",
            4,
            Box::new(|i: usize| (3000, [1000.0, 2000.0][i % 2], String::new())),
        ),
        (
            "segments",
            12,
            Box::new(|i: usize| {
                let meta = format!(
                    "# source = \"s{}.csv\"\n# segment = {i}\n# segment_start_s = {}\n",
                    i / 6,
                    i % 6
                );
                (400, 200.0, meta)
            }),
        ),
    ];
    for (name, per, shape) in kinds {
        let rec = dir.path().join(name);
        folder(&rec, per, shape);
        let (text, groups) = every_line_checks(&rec, dir.path());
        assert!(groups >= 4, "{name}: {groups} groups\n{text}");
        match name {
            "short" => assert!(text.contains("(none offered: "), "{text}"),
            "long" | "sound" => {
                assert!(!text.contains("source after another"), "{text}");
                assert!(text.contains("taper = \"hann\""), "{text}");
                assert!(text.contains("# windows = "), "{text}");
            }
            "mixed" => {
                assert!(text.contains("#   1000.0 Hz: 4"), "{text}");
                assert!(text.contains("spacing = 0.001 "), "{text}");
            }
            "segments" => {
                assert!(text.contains("method = \"holdout\"\n"), "{text}");
                assert!(text.contains("# group_by = \"source\""), "{text}");
                assert!(text.contains("one\n# source after another"), "{text}");
            }
            _ => {}
        }
    }
    // The mixed rates' profile evaluates (every point holds samples).
    let r = run(&[
        "evaluate",
        p(&dir.path().join("mixed")),
        "-p",
        p(&dir.path().join("mixed.toml")),
    ]);
    assert_eq!(r.code, Some(0), "{r:?}");
}

/// `hapticlab import` of CSVs with a time column (`time`: seconds since the
/// logger started, with three decimals, as a logger writes them): two
/// labels × `per` files of `n` samples at 1 kHz, into `dir/rec`. Their
/// differences carry float noise: (12.000 s - 10.001 s) / 1999 is not 0.001.
fn imported_with_times(dir: &Path, per: usize, n: usize) -> std::path::PathBuf {
    let raw = dir.join("raw");
    let mut files = Vec::new();
    for (l, label) in ["a", "b"].iter().enumerate() {
        fs::create_dir_all(raw.join(label)).unwrap();
        for i in 0..per {
            let mut text = String::from("time,acc\n");
            for j in 1..=n {
                let v = ((j * (3 + l) + i) % 17) as f64 / 17.0 - 0.5;
                let _ = writeln!(text, "{:.3},{v:.4}", 10.0 + j as f64 * 0.001);
            }
            let f = raw.join(label).join(format!("{label}-{i:02}.csv"));
            fs::write(&f, text).unwrap();
            files.push(f);
        }
    }
    let rec = dir.join("rec");
    let mut args: Vec<&str> = vec!["import", "--time-column", "time", "--out", p(&rec)];
    args.extend(files.iter().map(|f| p(f)));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    rec
}

#[test]
fn a_rate_measured_from_sample_times_is_written_without_float_noise() {
    let dir = tempfile::tempdir().unwrap();
    let rec = imported_with_times(dir.path(), 3, 2000);
    let out = dir.path().join("times.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    assert!(r.stdout.contains("along t_s at 1 kHz"), "{r:?}");
    assert!(text.contains("about 1000.0 samples a second"), "{text}");
    assert!(text.contains("spacing = 0.001   #"), "{text}");
    assert!(text.contains(": 1.999 s along t_s), 1991 points"), "{text}");
    // No 999.9999999999998, 0.001000000000000001 or 1.9989999999999988.
    for noise in ["99999", "00000"] {
        assert!(!text.contains(noise), "{noise} in\n{text}");
        assert!(!r.stdout.contains(noise), "{noise} in {r:?}");
    }
}

#[test]
fn mixed_rates_are_reported_as_analysed_and_a_rate_of_one_label_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rates");
    // Label a at 1 kHz; label b "imported with --rate 100 by mistake".
    for (label, rate, n) in [("a", 1000.0, 3000), ("b", 100.0, 300)] {
        fs::create_dir_all(rec.join(label)).unwrap();
        for i in 0..4 {
            let text = recording(label, 0.05, n, rate, "", i);
            fs::write(rec.join(label).join(format!("{label}-{i}.csv")), text).unwrap();
        }
    }
    let out = dir.path().join("rates.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("spacing = 0.01 "), "{text}");
    // The summary names the rate analysed, not the typical one.
    assert!(
        r.stdout
            .contains("acc along t_s at 100 Hz (the slowest of their rates: see the warning)"),
        "{r:?}"
    );
    let warning = r
        .stderr
        .lines()
        .find(|l| l.starts_with("warning: ") && l.contains("rates differ"))
        .unwrap_or_else(|| panic!("no warning of the rates: {r:?}"));
    for said in [
        "100 Hz: 4 recordings (b: 4); 1 kHz: 4 recordings (a: 4)",
        "analysed at 100 Hz, the slowest (spacing = 0.01)",
        "100 Hz goes with label b alone, 1 kHz goes with label a alone: the classifier would tell the labels apart by their rate, not their texture",
        "--rate",
    ] {
        assert!(warning.contains(said), "{said:?} not in {warning}");
    }
    assert_eq!(r.stderr.lines().count(), 1, "{r:?}");
    assert!(
        text.contains("# Caution: the recordings' rates differ"),
        "{text}"
    );
    assert!(text.contains("#   100.0 Hz: 4 (b: 4), e.g. "), "{text}");
}

#[test]
fn an_aborted_trial_is_named_and_the_window_fits_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("aborted");
    // Nine trials of 2-3 s per label at 1 kHz, and one of b stopped after
    // 40 samples.
    folder(&rec, 9, |i| (2000 + 111 * i, 1000.0, String::new()));
    let short = rec.join("b").join("b-009.csv");
    fs::write(&short, recording("b", 0.17, 40, 1000.0, "", 9)).unwrap();
    let out = dir.path().join("aborted.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    // Fitted to the shortest trial that is not aborted (2 s), not to 40 ms.
    assert!(text.contains("window = [0.0, 1.99]"), "{text}");
    let warning = r
        .stderr
        .lines()
        .find(|l| l.starts_with("warning: "))
        .unwrap_or_else(|| panic!("no warning: {r:?}"));
    for said in [
        "1 recording is under half the median length along t_s (2.443 s): ",
        "b-009.csv (0.039 s)",
        "The window was fitted to the others (window = [0.0, 1.99]), so it does not cover it and evaluate refuses it until it is removed from the folder",
        "; or, to keep it, set window = [0.0, 0.039] by hand",
    ] {
        assert!(warning.contains(said), "{said:?} not in {warning}");
    }
    assert!(
        r.stdout.contains(
            "from 19 complete recording(s) (1 of them too short for the window: see the warning)"
        ),
        "{r:?}"
    );
    assert!(
        text.contains("# Caution: 1 recording is under half"),
        "{text}"
    );
    // evaluate refuses the trial rather than analyse 40 ms of every other.
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("b-009.csv: the scan covers"), "{r:?}");
    assert!(
        r.stderr.contains(
            "1.990 s: remove the recording from the folder, or narrow the profile's window"
        ),
        "{r:?}"
    );
    fs::remove_file(&short).unwrap();
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
}

#[test]
fn overlapping_segments_are_left_out_between_training_and_test() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("raw");
    let mut files = Vec::new();
    for (l, label) in ["a", "b"].iter().enumerate() {
        fs::create_dir_all(raw.join(label)).unwrap();
        let mut text = String::new();
        for j in 0..6000 {
            let v = (j as f64 * [0.4, 1.1][l]).sin() + ((j * 7919) % 13) as f64 / 26.0;
            let _ = writeln!(text, "{v:.4}");
        }
        let f = raw.join(label).join("long.txt");
        fs::write(&f, text).unwrap();
        files.push(f);
    }
    let rec = dir.path().join("rec");
    let mut args = vec![
        "import",
        "--rate",
        "100",
        "--split",
        "2",
        "--split-hop",
        "1",
    ];
    args.extend(["--out", p(&rec)]);
    args.extend(files.iter().map(|f| p(f)));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    let out = dir.path().join("overlap.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    // 59 segments of 2 s every 1 s: the one after the training ones shares
    // its first second with the last of them.
    for line in [
        "method = \"holdout\"\ntrain_per_class = 41\ntest_per_class = 17\ngap_per_class = 1\n",
        "so gap_per_class = 1 leaves them out of both sides",
        "neighbours sharing signal fall on both sides: this flatters",
    ] {
        assert!(text.contains(line), "{line:?} not in\n{text}");
    }
    let r = run(&["check", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let r = run(&["evaluate", p(&rec), "-p", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stdout
            .contains("41 training and 17 test recordings per class, 1 left out between them"),
        "{r:?}"
    );
    let json = crate::common::json_of(&["evaluate", p(&rec), "-p", p(&out), "--json"]);
    let names = |part: &str| -> Vec<String> {
        json[part]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_str().unwrap().to_string())
            .collect()
    };
    let (train, test) = (names("train"), names("test"));
    assert!(
        train.iter().any(|f| f.ends_with("a/long-seg041.csv")),
        "{train:?}"
    );
    assert!(
        !train
            .iter()
            .chain(&test)
            .any(|f| f.ends_with("-seg042.csv"))
    );
    assert!(
        test.iter().any(|f| f.ends_with("a/long-seg043.csv")),
        "{test:?}"
    );
}

#[test]
fn trials_numbered_without_leading_zeros_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("bare");
    for (l, label) in ["a", "b"].iter().enumerate() {
        fs::create_dir_all(rec.join(label)).unwrap();
        for i in 1..=12 {
            let text = recording(label, [0.05, 0.17][l], 2000, 1000.0, "", i);
            fs::write(rec.join(label).join(format!("trial{i}.csv")), text).unwrap();
        }
    }
    let out = dir.path().join("bare.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    assert!(
        r.stderr.contains(
            "file names are numbered without leading zeros: file-name order, which a holdout and the time split take, puts trial12.csv before trial2.csv"
        ),
        "{r:?}"
    );
    let text = fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("# Caution: file names are numbered without leading zeros"),
        "{text}"
    );
}

#[test]
fn many_recordings_per_label_still_start_at_1_nn_and_2_2_khz_reads_as_written() {
    // 12 recordings a label at 2.2 kHz: 5-NN lost to 1-NN on every
    // generated set with many trials (the README), so the first choice
    // stays 1-NN; the spacing is one period to six digits, rounded up.
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    folder(&rec, 12, |_| (2200, 2200.0, String::new()));
    let out = dir.path().join("p.toml");
    let r = run(&["profile", "new", "--from", p(&rec), "--out", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("\nk = 1 "), "{text}");
    assert!(text.contains("the nearest recording decides"), "{text}");
    assert!(text.contains("\nspacing = 0.000454546 "), "{text}");
    assert!(text.contains("rounded up to six digits"), "{text}");
    assert!(!text.contains("4545454545"), "{text}");
    let r = run(&["check", p(&out)]);
    assert_eq!(r.code, Some(0), "{r:?}");
}
