//! `hapticlab import` through the binary: `--gzip` and `--threads`, quiet
//! when piped, and a bad option refused with exit code 2; inputs of one
//! name in two session folders, named, and `--prefix-parent`.

use hapticlab::recording;

use crate::common::{p, run};

/// A 16-bit PCM mono WAV of `samples`.
fn wav16(rate: u32, samples: &[i16]) -> Vec<u8> {
    let data: Vec<u8> = samples.iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut b = Vec::new();
    b.extend(b"RIFF");
    b.extend((36 + data.len() as u32).to_le_bytes());
    b.extend(b"WAVEfmt ");
    b.extend(16u32.to_le_bytes());
    b.extend(1u16.to_le_bytes());
    b.extend(1u16.to_le_bytes());
    b.extend(rate.to_le_bytes());
    b.extend((rate * 2).to_le_bytes());
    b.extend(2u16.to_le_bytes());
    b.extend(16u16.to_le_bytes());
    b.extend(b"data");
    b.extend((data.len() as u32).to_le_bytes());
    b.extend(data);
    b
}

#[test]
fn import_gzip_on_two_threads_writes_exact_compressed_recordings_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let samples: Vec<i16> = (0..5000)
        .map(|i| ((i * 131) % 20000 - 10000) as i16)
        .collect();
    let mut inputs = Vec::new();
    for name in ["a", "b", "c"] {
        let f = dir.path().join(format!("{name}.wav"));
        std::fs::write(&f, wav16(44100, &samples)).unwrap();
        inputs.push(f);
    }
    let out = dir.path().join("out");
    let mut args = vec![
        "import",
        "--gzip",
        "--threads",
        "2",
        "--label",
        "S2",
        "--out",
        p(&out),
    ];
    args.extend(inputs.iter().map(|f| p(f)));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    let listed: Vec<&str> = r.stdout.lines().collect();
    let expected: Vec<String> = ["a", "b", "c"]
        .iter()
        .map(|n| out.join(format!("S2/{n}.csv.gz")).display().to_string())
        .collect();
    assert_eq!(listed, expected, "{r:?}");
    // Piped: the summary only, no progress bar.
    assert_eq!(r.stderr, "imported 3 recording(s)\n");
    let rec = recording::read(&out.join("S2/b.csv.gz")).unwrap();
    let back: Vec<f64> = samples.iter().map(|&v| f64::from(v)).collect();
    assert_eq!(rec.column("ch1").unwrap(), back);
    assert!(rec.is_complete());

    let bad = run(&[
        "import",
        "--threads",
        "many",
        "--label",
        "S2",
        "--out",
        p(&out),
        p(&inputs[0]),
    ]);
    assert_eq!(bad.code, Some(2), "{bad:?}");
    assert!(bad.stderr.contains("--threads"), "{bad:?}");
}

/// `days/day1/felt/trial1.txt` and `days/day2/felt/trial1.txt` would both
/// be `OUT/felt/trial1.csv`: refused naming both inputs and the ways out,
/// nothing written; `--prefix-parent` names them `day1-trial1.csv` and
/// `day2-trial1.csv`. One input named twice is told as such.
#[test]
fn inputs_of_one_name_in_two_session_folders_are_named_and_prefixed_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let mut inputs = Vec::new();
    for day in ["day1", "day2"] {
        let folder = dir.path().join("days").join(day).join("felt");
        std::fs::create_dir_all(&folder).unwrap();
        let f = folder.join("trial1.txt");
        std::fs::write(&f, "1\n2\n3\n").unwrap();
        inputs.push(p(&f).to_string());
    }
    let out = dir.path().join("out");
    let mut args = vec!["import", "--rate", "100", "--out", p(&out)];
    args.extend(inputs.iter().map(String::as_str));
    let r = run(&args);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert_eq!(r.stderr.lines().count(), 1, "{r:?}");
    for s in [
        inputs[0].as_str(),
        inputs[1].as_str(),
        "would both be written to",
        "--prefix-parent",
        "two runs into different --out folders",
    ] {
        assert!(r.stderr.contains(s), "{s:?} missing: {r:?}");
    }
    assert!(!r.stderr.contains(".import-"), "{r:?}");
    assert!(!out.exists(), "nothing written: {r:?}");

    args.push("--prefix-parent");
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{r:?}");
    for day in ["day1", "day2"] {
        let rec = recording::read(&out.join(format!("felt/{day}-trial1.csv"))).unwrap();
        assert_eq!(rec.label(), Some("felt"));
        assert_eq!(rec.column("ch1").unwrap(), [1.0, 2.0, 3.0]);
    }

    let again = dir.path().join("again");
    let r = run(&[
        "import",
        "--rate",
        "100",
        "--out",
        p(&again),
        &inputs[0],
        &inputs[0],
    ]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("is given twice"), "{r:?}");
}
