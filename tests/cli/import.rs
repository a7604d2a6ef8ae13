//! `hapticlab import` through the binary: `--gzip` and `--threads`, quiet
//! when piped, and a bad option refused with exit code 2.

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
