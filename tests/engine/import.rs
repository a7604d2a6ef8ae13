//! Import round trips: CSV (time column, fixed rate, bursts, label sources,
//! metadata) and WAV (16/24-bit integer, 32-bit float, several channels);
//! a bad input leaves nothing behind.

use std::path::Path;

use hapticlab::import::{Quiet, Request};
use hapticlab::recording;
use hapticlab::support::Failure;
use proptest::prelude::*;

use crate::common::mutation::{mutate, mutation};

// The fuzz targets' entry points (`fuzz/src/lib.rs`): `import_csv` (the
// mapping as options on the first line, then the file) and `import_wav`.
use crate::entries;

/// The import with nothing shown, its error as the command line sees it.
fn run(a: &Request) -> Result<Vec<std::path::PathBuf>, Failure> {
    Ok(hapticlab::import::run(a, &Quiet)?)
}

fn args(files: &[&Path], out: &Path) -> Request {
    Request {
        files: files.iter().map(|p| p.to_path_buf()).collect(),
        out: out.to_path_buf(),
        burst: 1,
        ..Request::default()
    }
}

#[test]
fn csv_with_a_time_column_and_a_label_column() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("scan7.csv");
    std::fs::write(&f, "# from rig B\ntime;fz;acc;texture\n0.0;1.5;-0.25;S3\n0.002;1.25;0.5;S3\n0.004;1.0;0.75;S3\n").unwrap();
    let mut a = args(&[&f], &dir.path().join("out"));
    a.time_column = Some("time".into());
    a.label_column = Some("texture".into());
    a.meta = vec!["session=3".into(), "rig=bench-A".into()];
    let written = run(&a).unwrap();
    assert_eq!(written, [dir.path().join("out/S3/scan7.csv")]);
    let rec = recording::read(&written[0]).unwrap();
    assert!(rec.is_complete());
    assert_eq!(rec.label(), Some("S3"));
    assert_eq!(rec.columns, ["t_s", "fz", "acc"]);
    assert_eq!(rec.column("t_s").unwrap(), [0.0, 0.002, 0.004]);
    assert_eq!(rec.column("acc").unwrap(), [-0.25, 0.5, 0.75]);
    assert_eq!(rec.meta_f64("session"), Some(3.0));
    assert_eq!(rec.meta_str("rig"), Some("bench-A"));
    // Importing again refuses to overwrite.
    assert!(run(&a).unwrap_err().message().contains("--force"));
}

#[test]
fn csv_bursts_are_flattened_in_order_and_timed_by_the_rate() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("S2");
    std::fs::create_dir(&folder).unwrap();
    let f = folder.join("b.csv");
    // Two channels, 3 samples each per row.
    std::fs::write(&f, "a0,a1,a2,b0,b1,b2\n1,2,3,10,20,30\n4,5,6,40,50,60\n").unwrap();
    let mut a = args(&[&f], &dir.path().join("out"));
    a.rate = Some(100.0);
    a.burst = 3;
    a.names = vec!["acc".into(), "force".into()];
    let written = run(&a).unwrap();
    // The label is the folder's name.
    let rec = recording::read(&written[0]).unwrap();
    assert_eq!(rec.label(), Some("S2"));
    assert_eq!(rec.column("acc").unwrap(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(
        rec.column("force").unwrap(),
        [10.0, 20.0, 30.0, 40.0, 50.0, 60.0]
    );
    let t = rec.column("t_s").unwrap();
    assert!((t[5] - 0.05).abs() < 1e-9);
    assert_eq!(rec.meta_f64("rate_hz"), Some(100.0));
}

#[test]
fn a_bad_csv_gives_a_clear_message_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.csv");
    std::fs::write(&good, "t,v\n0,1\n1,2\n").unwrap();
    let badf = dir.path().join("bad.csv");
    std::fs::write(&badf, "t,v\n0,1\n1,oops\n").unwrap();
    let out = dir.path().join("out");
    let mut a = args(&[&good, &badf], &out);
    a.time_column = Some("t".into());
    a.label = Some("S1".into());
    let e = run(&a).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.message()
            .contains("bad.csv:3: column `v`: \"oops\" is not a finite number"),
        "{}",
        e.message()
    );
    assert!(!out.exists(), "nothing written");
    a.time_column = None;
    assert!(
        run(&a)
            .unwrap_err()
            .message()
            .contains("--time-column or --rate")
    );
}

#[test]
fn times_that_overflow_are_refused_not_written() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("far.csv");
    // Row intervals of 2e308 s: the median interval shared within a burst is inf.
    std::fs::write(&f, "t,a,b\n-1e308,1,2\n1e308,3,4\n").unwrap();
    let out = dir.path().join("out");
    let mut a = args(&[&f], &out);
    a.time_column = Some("t".into());
    a.burst = 2;
    a.label = Some("S1".into());
    let e = run(&a).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.message().contains(
            "far.csv: the time of sample 1 overflows (it is NaN, from the time column's intervals)"
        ),
        "{}",
        e.message()
    );
    // A positive rate so small that 1/rate is inf: refused before any
    // file is read, whatever its format.
    a.time_column = None;
    a.burst = 1;
    a.rate = Some(1e-310);
    let e = run(&a).unwrap_err();
    assert!(
        e.message().contains("--rate must be from 0.001 Hz") && e.message().contains("got 1e-310"),
        "{}",
        e.message()
    );
    assert!(!out.exists(), "nothing written");
}

/// A WAV file: `format` 1 (PCM) or 3 (float), interleaved frames.
fn wav(format: u16, channels: u16, rate: u32, bits: u16, data: &[u8]) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(b"RIFF");
    b.extend((36 + data.len() as u32).to_le_bytes());
    b.extend(b"WAVEfmt ");
    b.extend(16u32.to_le_bytes());
    b.extend(format.to_le_bytes());
    b.extend(channels.to_le_bytes());
    b.extend(rate.to_le_bytes());
    let block = channels * bits / 8;
    b.extend((rate * u32::from(block)).to_le_bytes());
    b.extend(block.to_le_bytes());
    b.extend(bits.to_le_bytes());
    b.extend(b"data");
    b.extend((data.len() as u32).to_le_bytes());
    b.extend(data);
    b
}

#[test]
fn wav_16_and_24_bit_integer_and_float_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // 16-bit stereo.
    let s16: [i16; 6] = [0, -32768, 32767, 1, -2, 300];
    let d: Vec<u8> = s16.iter().flat_map(|v| v.to_le_bytes()).collect();
    let f16 = dir.path().join("two.wav");
    std::fs::write(&f16, wav(1, 2, 8000, 16, &d)).unwrap();
    // 24-bit mono.
    let s24: [i32; 3] = [-8_388_608, 8_388_607, -5];
    let d: Vec<u8> = s24
        .iter()
        .flat_map(|v| v.to_le_bytes()[..3].to_vec())
        .collect();
    let f24 = dir.path().join("deep.wav");
    std::fs::write(&f24, wav(1, 1, 48000, 24, &d)).unwrap();
    // 32-bit float mono.
    let sf: [f32; 3] = [0.5, -0.25, 0.125];
    let d: Vec<u8> = sf.iter().flat_map(|v| v.to_le_bytes()).collect();
    let ff = dir.path().join("float.wav");
    std::fs::write(&ff, wav(3, 1, 44100, 32, &d)).unwrap();

    let mut a = args(&[&f16, &f24, &ff], &out);
    a.label = Some("S4".into());
    let w = run(&a).unwrap();
    let r = recording::read(&w[0]).unwrap();
    assert_eq!(r.columns, ["t_s", "ch1", "ch2"]);
    assert_eq!(r.column("ch1").unwrap(), [0.0, 32767.0, -2.0]);
    assert_eq!(r.column("ch2").unwrap(), [-32768.0, 1.0, 300.0]);
    assert_eq!(r.meta_f64("full_scale"), Some(32768.0));
    assert_eq!(r.column("t_s").unwrap()[2], 0.00025);
    let r = recording::read(&w[1]).unwrap();
    assert_eq!(r.column("ch1").unwrap(), [-8_388_608.0, 8_388_607.0, -5.0]);
    assert_eq!(r.meta_str("wav_format"), Some("int24"));
    let r = recording::read(&w[2]).unwrap();
    assert_eq!(r.column("ch1").unwrap(), [0.5, -0.25, 0.125]);

    // A truncated WAV is refused by name.
    let cut = dir.path().join("cut.wav");
    let mut bytes = wav(1, 1, 8000, 16, &[0, 0, 1, 0]);
    bytes.truncate(bytes.len() - 2);
    std::fs::write(&cut, bytes).unwrap();
    let mut a = args(&[&cut], &out);
    a.label = Some("S4".into());
    let e = run(&a).unwrap_err();
    assert!(
        e.message()
            .contains("cut.wav: not a WAV file this reads: the data chunk is cut short"),
        "{}",
        e.message()
    );
}

/// The rows of a written recording (the lines that are not comments, after the header).
fn rows_of(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .collect()
}

#[test]
fn integer_samples_stay_integers() {
    let dir = tempfile::tempdir().unwrap();
    let s16: [i16; 6] = [-228, 0, 32767, -32768, 1, -1];
    let d: Vec<u8> = s16.iter().flat_map(|v| v.to_le_bytes()).collect();
    let f = dir.path().join("tap.wav");
    std::fs::write(&f, wav(1, 1, 44100, 16, &d)).unwrap();
    let mut a = args(&[&f], &dir.path().join("out"));
    a.label = Some("S1".into());
    let w = run(&a).unwrap();
    let text = std::fs::read_to_string(&w[0]).unwrap();
    let samples: Vec<&str> = rows_of(&text)
        .iter()
        .map(|r| r.split_once(',').unwrap().1)
        .collect();
    assert_eq!(
        samples,
        ["-228", "0", "32767", "-32768", "1", "-1"],
        "{text}"
    );
    let rec = recording::read(&w[0]).unwrap();
    let back: Vec<f64> = s16.iter().map(|&v| f64::from(v)).collect();
    assert_eq!(rec.column("ch1").unwrap(), back);
}

/// Every written `t_s` of a WAV at `rate` is within 1 % of a sample period
/// of i / rate, as the text says it and as the reader reads it.
fn check_time_precision(rate: u32, samples: usize) {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("long.wav");
    std::fs::write(&f, wav(1, 1, rate, 16, &vec![0u8; samples * 2])).unwrap();
    let mut a = args(&[&f], &dir.path().join("out"));
    a.label = Some("S1".into());
    let w = run(&a).unwrap();
    let text = std::fs::read_to_string(&w[0]).unwrap();
    let period = 1.0 / f64::from(rate);
    let rows = rows_of(&text);
    assert_eq!(rows.len(), samples);
    for (i, row) in rows.iter().enumerate() {
        let t: f64 = row.split_once(',').unwrap().0.parse().unwrap();
        let err = (t - i as f64 / f64::from(rate)).abs();
        assert!(
            err <= 0.01 * period,
            "{rate} Hz, sample {i}: t_s {t} is off by {:.2} % of a period",
            100.0 * err / period
        );
    }
    let read = recording::read(&w[0]).unwrap();
    for (i, t) in read.column("t_s").unwrap().iter().enumerate() {
        assert!(
            (t - i as f64 / f64::from(rate)).abs() <= 0.01 * period,
            "read back, sample {i}"
        );
    }
}

#[test]
fn t_s_is_within_a_percent_of_a_period_at_44_1_khz() {
    // Six decimals were off by up to 2.2 % here.
    check_time_precision(44_100, 100_000);
}

#[test]
fn t_s_is_within_a_percent_of_a_period_at_200_khz() {
    check_time_precision(200_000, 100_000);
}

#[test]
fn gzip_output_reads_back_identical_samples() {
    let dir = tempfile::tempdir().unwrap();
    // Float samples that need every digit, and CSV values of every kind.
    let sf: Vec<f32> = (0..500).map(|i| ((i as f32) * 0.37).sin() / 3.0).collect();
    let d: Vec<u8> = sf.iter().flat_map(|v| v.to_le_bytes()).collect();
    let ff = dir.path().join("float.wav");
    std::fs::write(&ff, wav(3, 1, 48000, 32, &d)).unwrap();
    let s64: Vec<f64> = (0..300)
        .map(|i| (f64::from(i) * 0.1).exp() * 1e-9)
        .collect();
    let d: Vec<u8> = s64.iter().flat_map(|v| v.to_le_bytes()).collect();
    let fd = dir.path().join("double.wav");
    std::fs::write(&fd, wav(3, 1, 20000, 64, &d)).unwrap();
    let fc = dir.path().join("rig.csv");
    std::fs::write(&fc, "t,acc\n0.0,0.1\n0.001,-3.141592653589793\n0.002,1e-9\n0.0035,123456789012.5\n0.004,-0.000\n").unwrap();
    let out = dir.path().join("out");
    let mut a = args(&[&ff, &fd], &out);
    a.label = Some("S2".into());
    a.gzip = true;
    let w = run(&a).unwrap();
    assert_eq!(
        w,
        [out.join("S2/float.csv.gz"), out.join("S2/double.csv.gz")]
    );
    assert!(!out.join("S2/float.csv").exists());
    let back: Vec<f32> = recording::read(&w[0])
        .unwrap()
        .column("ch1")
        .unwrap()
        .iter()
        .map(|&v| v as f32)
        .collect();
    assert_eq!(back, sf);
    assert_eq!(recording::read(&w[1]).unwrap().column("ch1").unwrap(), s64);
    let mut a = args(&[&fc], &out);
    a.label = Some("S2".into());
    a.time_column = Some("t".into());
    a.gzip = true;
    let w = run(&a).unwrap();
    let rec = recording::read(&w[0]).unwrap();
    assert_eq!(
        rec.column("t_s").unwrap(),
        [0.0, 0.001, 0.002, 0.0035, 0.004]
    );
    assert_eq!(
        rec.column("acc").unwrap(),
        [0.1, -std::f64::consts::PI, 1e-9, 123456789012.5, -0.0]
    );
}

/// Two WAVs and two CSVs of a few thousand samples each.
fn mixed_inputs(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for (k, rate) in [8000u32, 44100].into_iter().enumerate() {
        let d: Vec<u8> = (0..3000)
            .flat_map(|i: i32| ((i * 37 + k as i32 * 11) % 4000 - 2000).to_le_bytes()[..2].to_vec())
            .collect();
        let f = dir.join(format!("clip{k}.wav"));
        std::fs::write(&f, wav(1, 1, rate, 16, &d)).unwrap();
        files.push(f);
    }
    for k in 0..2 {
        let mut text = String::from("a,b\n");
        for i in 0..2000 {
            text.push_str(&format!(
                "{},{}\n",
                f64::from(i) * 0.013 + f64::from(k),
                (f64::from(i) / 7.0).cos()
            ));
        }
        let f = dir.join(format!("trial{k}.csv"));
        std::fs::write(&f, text).unwrap();
        files.push(f);
    }
    files
}

#[test]
fn threads_give_byte_identical_output() {
    let dir = tempfile::tempdir().unwrap();
    let files = mixed_inputs(dir.path());
    let refs: Vec<&Path> = files.iter().map(|f| f.as_path()).collect();
    let mut outputs = Vec::new();
    for (threads, gzip) in [(1, false), (4, false), (1, true), (3, true)] {
        let out = dir.path().join(format!("out-{threads}-{gzip}"));
        let mut a = args(&refs, &out);
        a.label = Some("S3".into());
        a.rate = Some(2500.0);
        a.threads = Some(threads);
        a.gzip = gzip;
        let w = run(&a).unwrap();
        assert_eq!(w.len(), 4);
        let names: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["S3"], "no staging folder left behind");
        outputs.push(
            w.iter()
                .map(|p| std::fs::read(p).unwrap())
                .collect::<Vec<_>>(),
        );
    }
    assert!(
        outputs[0] == outputs[1],
        "--threads 4 differs from --threads 1"
    );
    assert!(
        outputs[2] == outputs[3],
        "--gzip --threads 3 differs from --threads 1"
    );
}

#[test]
fn a_recording_too_large_for_zopfli_gzips_the_same_on_any_thread_count() {
    // 400,000 samples at 44.1 kHz: about 6 MB of text, past Zopfli's limit.
    let dir = tempfile::tempdir().unwrap();
    let samples: Vec<i16> = (0..400_000i64)
        .map(|i| ((i * 7919) % 30000 - 15000) as i16)
        .collect();
    let d: Vec<u8> = samples.iter().flat_map(|v| v.to_le_bytes()).collect();
    let big = dir.path().join("big.wav");
    std::fs::write(&big, wav(1, 1, 44100, 16, &d)).unwrap();
    let small = dir.path().join("small.wav");
    std::fs::write(&small, wav(1, 1, 44100, 16, &d[..2000])).unwrap();
    let mut bytes = Vec::new();
    for threads in [1, 2] {
        let out = dir.path().join(format!("out{threads}"));
        let mut a = args(&[&big, &small], &out);
        a.label = Some("S1".into());
        a.gzip = true;
        a.threads = Some(threads);
        let w = run(&a).unwrap();
        let rec = recording::read(&w[0]).unwrap();
        assert!(rec.is_complete());
        let back: Vec<f64> = samples.iter().map(|&v| f64::from(v)).collect();
        assert_eq!(rec.column("ch1").unwrap(), back);
        bytes.push(std::fs::read(&w[0]).unwrap());
    }
    let mut text = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(&bytes[0][..]), &mut text)
        .unwrap();
    assert!(
        text.len() > 4 << 20,
        "{} bytes of text: under Zopfli's limit",
        text.len()
    );
    assert!(bytes[0] == bytes[1], "--threads 2 differs from --threads 1");
}

#[test]
fn a_bad_input_among_many_on_several_threads_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = mixed_inputs(dir.path());
    let broken = dir.path().join("broken.wav");
    std::fs::write(&broken, b"RIFF....WAVE").unwrap();
    files.insert(2, broken);
    let refs: Vec<&Path> = files.iter().map(|f| f.as_path()).collect();
    let out = dir.path().join("out");
    let mut a = args(&refs, &out);
    a.label = Some("S3".into());
    a.rate = Some(2500.0);
    a.threads = Some(3);
    let e = run(&a).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.message().contains("broken.wav: not a WAV file"),
        "{}",
        e.message()
    );
    assert!(!out.exists(), "nothing written");
    // Into a folder that was there: it is left as it was.
    std::fs::create_dir(&out).unwrap();
    run(&a).unwrap_err();
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
    // An --out that names a file is a bad argument, said before anything.
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    let mut a = args(&refs[..1], &file);
    a.label = Some("S3".into());
    let e = run(&a).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{}", e.message());
    assert!(e.message().contains("a-file"), "{}", e.message());
}

const CSV_MAPPINGS: [&str; 4] = [
    "--time-column t --label-column texture",
    "--rate 1000 --label S1",
    "--time-column t --burst 2 --channels a1,a2 --label S1",
    "--rate 3000 --burst 2 --label S1 --delimiter ;",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    /// Any bytes as a CSV or a WAV file: an import, or a message; never a panic.
    #[test]
    fn arbitrary_bytes_never_panic(
        mapping in 0..CSV_MAPPINGS.len(),
        bytes in prop::collection::vec(any::<u8>(), 0..400),
    ) {
        let _ = entries::import_wav(&bytes);
        let mut csv = format!("{}\n", CSV_MAPPINGS[mapping]).into_bytes();
        csv.extend(&bytes);
        let _ = entries::import_csv(&csv);
    }

    #[test]
    fn mutated_csv_files_never_panic(
        mapping in 0..CSV_MAPPINGS.len(),
        mutations in prop::collection::vec(mutation(b",;\t\n\r\"-.e0123456789"), 1..6),
    ) {
        let file = "t,a1,a2,texture\n0,1,2,S1\n0.5,3,4,S1\n1,5,6,S1\n";
        let _ = entries::import_csv(&mutate(format!("{}\n{file}", CSV_MAPPINGS[mapping]).into_bytes(), &mutations));
    }

    #[test]
    fn mutated_wav_files_never_panic(
        format in prop::sample::select(vec![(1u16, 8u16), (1, 16), (1, 24), (1, 32), (3, 32), (3, 64)]),
        channels in 1u16..4,
        mutations in prop::collection::vec(mutation(&[0, 1, 0xff, 0x7f, 0x80, 0xfe]), 1..6),
    ) {
        let data: Vec<u8> = (0..48).collect();
        let bytes = wav(format.0, channels, 8000, format.1, &data);
        let _ = entries::import_wav(&mutate(bytes, &mutations));
    }
}

/// A killed import leaves its hidden staging folder; the next import into
/// the same folder removes it, and leaves a running import's alone.
#[test]
fn an_abandoned_staging_folder_is_removed_by_the_next_import() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // A process that has exited: its pid names the abandoned folder.
    let mut child = std::process::Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let abandoned = out.join(format!(".import-{dead}"));
    std::fs::create_dir_all(abandoned.join("S1")).unwrap();
    std::fs::write(abandoned.join("S1/half.csv"), "# hapticlab recording v1\n").unwrap();
    // A process that is running (this test's parent).
    let running = out.join(format!(".import-{}", std::os::unix::process::parent_id()));
    std::fs::create_dir_all(&running).unwrap();
    let f = dir.path().join("a.csv");
    std::fs::write(&f, "t;v\n0.0;1\n0.001;2\n").unwrap();
    let mut a = args(&[&f], &out);
    a.time_column = Some("t".into());
    a.label = Some("S1".into());
    run(&a).unwrap();
    assert!(
        !abandoned.exists(),
        "the killed import's folder is still there"
    );
    assert!(running.exists(), "a running import's folder was removed");
}
