//! NumPy `.npy` (format 1.0 to 3.0) and `.npz` (a zip of `.npy` files, as
//! `np.savez` and `np.savez_compressed` write them), read by hand: the
//! header is a Python dict literal, the zip is read from its central
//! directory (stored or deflated entries). A 1-D array is one channel; a
//! 2-D array's channels are its columns (samples × channels), or its rows
//! when `--names` counts them, or when there are fewer rows than columns.
//! An `.npz` of several arrays takes each 1-D array as a channel named by
//! it; a scalar (0-d) array becomes metadata; an array named like sample
//! times (`t`, `time`, `time_s`…) is left out, checked against `--rate`.

use super::{ImportError, Imported, Request, bad};
use crate::profile::fitted::significant;
use crate::recording::{Digits, time_decimals};

/// One array read from a `.npy`: its shape, its values in C order, how they
/// are written back (integers as integers).
pub(super) struct Array {
    pub shape: Vec<usize>,
    pub values: Vec<f64>,
    pub digits: Digits,
}

/// Parses the bytes of a `.npy` file.
pub(super) fn parse_npy(b: &[u8], origin: &str) -> Result<Array, ImportError> {
    let err = |m: String| bad(format!("{origin}: not a .npy file this reads: {m}"));
    if b.len() < 10 || &b[..6] != b"\x93NUMPY" {
        return Err(err("no \\x93NUMPY magic".into()));
    }
    let (len, start) = match b[6] {
        1 => (usize::from(u16::from_le_bytes([b[8], b[9]])), 10),
        2 | 3 if b.len() >= 12 => (u32::from_le_bytes([b[8], b[9], b[10], b[11]]) as usize, 12),
        v => return Err(err(format!("format version {v}"))),
    };
    let header = b
        .get(start..start + len)
        .ok_or_else(|| err("the header is cut short".into()))?;
    let header = std::str::from_utf8(header).map_err(|e| {
        err(format!(
            "the header is not text (byte {} of it is 0x{:02x})",
            e.valid_up_to(),
            header[e.valid_up_to()]
        ))
    })?;
    let Header {
        descr,
        fortran,
        shape,
    } = Header::parse(header).map_err(|m| err(format!("its header {m}")))?;
    let descr = descr.as_str();
    let (width, kind) = element(descr).ok_or_else(|| {
        err(format!(
            "dtype {descr:?} (integers, unsigned integers and floats of 1 to 8 bytes only)"
        ))
    })?;
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    let data = &b[start + len..];
    let count = count
        .filter(|c| {
            c.checked_mul(width)
                .is_some_and(|bytes| bytes <= data.len())
        })
        .ok_or_else(|| {
            err(format!(
                "shape {shape:?} needs more data than the file holds"
            ))
        })?;
    let big = descr.starts_with('>');
    let mut values: Vec<f64> = data[..count * width]
        .chunks_exact(width)
        .map(|c| number(c, kind, big))
        .collect();
    // 64-bit integers beyond 2^53 would be rounded: refused, never written wrong.
    if kind != 'f'
        && width == 8
        && let Some(i) = values.iter().position(|v| v.abs() > super::EXACT_INTEGER)
    {
        let c = &data[i * 8..i * 8 + 8];
        let mut raw = [0u8; 8];
        raw.copy_from_slice(c);
        let raw = if big {
            u64::from_be_bytes(raw)
        } else {
            u64::from_le_bytes(raw)
        };
        let text = if kind == 'u' {
            raw.to_string()
        } else {
            (raw as i64).to_string()
        };
        return Err(super::inexact_integer(origin, i + 1, &text));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(err(format!("element {i} is not a finite number")));
    }
    if fortran && shape.len() == 2 {
        values = transpose(&values, shape[1], shape[0]);
    }
    let digits = match (kind, width) {
        ('f', 4) => Digits::ShortestF32,
        ('f', _) => Digits::Shortest,
        _ => Digits::Decimals(0),
    };
    Ok(Array {
        shape,
        values,
        digits,
    })
}

/// A `.npy` header: exactly the dict literal numpy writes, `{'descr':
/// '<f8', 'fortran_order': False, 'shape': (3, 2), }`, parsed as Python
/// would (strings, `True`/`False`, a tuple of integers), with exactly these
/// three keys: a string that merely holds `'shape': (1,)` is a string.
struct Header {
    descr: String,
    fortran: bool,
    shape: Vec<usize>,
}

impl Header {
    fn parse(text: &str) -> Result<Header, String> {
        let mut p = Literal {
            s: text.as_bytes(),
            at: 0,
        };
        p.expect(b'{')?;
        let (mut descr, mut fortran, mut shape) = (None, None, None);
        loop {
            p.space();
            if p.eat(b'}') {
                break;
            }
            let key = p.string()?;
            p.space();
            p.expect(b':')?;
            p.space();
            match key.as_str() {
                "descr" if descr.is_none() => descr = Some(p.string()?),
                "fortran_order" if fortran.is_none() => fortran = Some(p.boolean()?),
                "shape" if shape.is_none() => shape = Some(p.tuple()?),
                "descr" | "fortran_order" | "shape" => return Err(format!("gives {key:?} twice")),
                _ => return Err(format!("has a key {key:?} numpy does not write")),
            }
            p.space();
            if !p.eat(b',') {
                p.space();
                p.expect(b'}')?;
                break;
            }
        }
        if !p.s[p.at..].iter().all(u8::is_ascii_whitespace) {
            return Err("goes on after its dict".into());
        }
        Ok(Header {
            descr: descr.ok_or("has no 'descr'")?,
            fortran: fortran.ok_or("has no 'fortran_order'")?,
            shape: shape.ok_or("has no 'shape'")?,
        })
    }
}

/// A reader of the few Python literals a `.npy` header holds.
struct Literal<'a> {
    s: &'a [u8],
    at: usize,
}

impl Literal<'_> {
    fn space(&mut self) {
        while self.s.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
    }
    fn eat(&mut self, c: u8) -> bool {
        let hit = self.s.get(self.at) == Some(&c);
        self.at += usize::from(hit);
        hit
    }
    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!(
                "is no dict literal: {:?} expected at character {}",
                c as char,
                self.at + 1
            ))
        }
    }
    /// A quoted string without escapes (numpy writes none).
    fn string(&mut self) -> Result<String, String> {
        let quote = match self.s.get(self.at) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => return Err(format!("has no string at character {}", self.at + 1)),
        };
        let from = self.at + 1;
        let len = self.s[from..]
            .iter()
            .position(|&c| c == quote || c == b'\\')
            .ok_or("has a string that is never closed")?;
        if self.s[from + len] == b'\\' {
            return Err("has an escape in a string, which numpy never writes".into());
        }
        self.at = from + len + 1;
        Ok(String::from_utf8_lossy(&self.s[from..from + len]).into_owned())
    }
    fn boolean(&mut self) -> Result<bool, String> {
        for (word, value) in [(&b"True"[..], true), (&b"False"[..], false)] {
            if self.s[self.at..].starts_with(word) {
                self.at += word.len();
                return Ok(value);
            }
        }
        Err("has a 'fortran_order' that is not True or False".into())
    }
    /// `()`, `(n,)` or `(n, m, …)` of non-negative integers.
    fn tuple(&mut self) -> Result<Vec<usize>, String> {
        self.expect(b'(')?;
        let mut dims = Vec::new();
        loop {
            self.space();
            if self.eat(b')') {
                return Ok(dims);
            }
            let from = self.at;
            while self.s.get(self.at).is_some_and(u8::is_ascii_digit) {
                self.at += 1;
            }
            let digits = std::str::from_utf8(&self.s[from..self.at]).unwrap_or("");
            dims.push(digits.parse::<usize>().map_err(|_| {
                format!(
                    "has a 'shape' that is no tuple of sizes (character {})",
                    from + 1
                )
            })?);
            // Python 2's long integers: `(3L,)`.
            self.eat(b'L');
            self.space();
            if !self.eat(b',') {
                self.space();
                self.expect(b')')?;
                // `(3)` is 3, not a tuple; numpy writes `(3,)`.
                if dims.len() == 1 {
                    return Err("has a 'shape' of (n) without a comma, which is no tuple".into());
                }
                return Ok(dims);
            }
        }
    }
}

/// Width in bytes and kind (`i`, `u`, `f`) of a dtype such as `<f8`.
fn element(descr: &str) -> Option<(usize, char)> {
    let d = descr.trim_start_matches(['<', '>', '|', '=']);
    let mut chars = d.chars();
    // A character, not a byte: a descr such as 'Đ4' is refused, not split
    // inside its first character.
    let kind = chars.next()?;
    let width: usize = chars.as_str().parse().ok()?;
    let ok = match kind {
        'i' | 'u' => matches!(width, 1 | 2 | 4 | 8),
        'f' => matches!(width, 4 | 8),
        _ => false,
    };
    ok.then_some((width, kind))
}

fn number(c: &[u8], kind: char, big: bool) -> f64 {
    let mut b = [0u8; 8];
    b[..c.len()].copy_from_slice(c);
    if big {
        b[..c.len()].reverse();
    }
    let w = c.len();
    match (kind, w) {
        ('f', 4) => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        ('f', _) => f64::from_le_bytes(b),
        ('u', _) => u64::from_le_bytes(b) as f64,
        // Sign-extend from the element's width.
        (_, _) => ((i64::from_le_bytes(b) << (64 - 8 * w)) >> (64 - 8 * w)) as f64,
    }
}

/// `values` of `rows × cols` in column-major order, as row-major.
fn transpose(values: &[f64], cols: usize, rows: usize) -> Vec<f64> {
    let mut out = vec![0.0; values.len()];
    for r in 0..rows {
        for c in 0..cols {
            out[r * cols + c] = values[c * rows + r];
        }
    }
    out
}

/// The channels of a 1-D or 2-D array (see the module's note), named `name`,
/// `name_1`, `name_2`, … or by `--names`.
pub(super) fn channels_of(
    a: &Array,
    name: &str,
    args: &Request,
    origin: &str,
) -> Result<Vec<(String, Vec<f64>)>, ImportError> {
    match a.shape[..] {
        [n] => Ok(vec![(name.to_string(), a.values[..n].to_vec())]),
        [rows, cols] => {
            let given = args.names.len();
            let by_rows = if given > 0 {
                given == rows && given != cols
            } else {
                rows < cols
            };
            let (count, len) = if by_rows { (rows, cols) } else { (cols, rows) };
            let at = |ch: usize, i: usize| {
                if by_rows {
                    a.values[ch * cols + i]
                } else {
                    a.values[i * cols + ch]
                }
            };
            Ok((0..count)
                .map(|ch| {
                    let v = (0..len).map(|i| at(ch, i)).collect();
                    (format!("{name}_{}", ch + 1), v)
                })
                .collect())
        }
        _ => Err(bad(format!(
            "{origin}: array {name:?} has shape {:?}: import takes 1-D arrays, or 2-D ones of samples × channels",
            a.shape
        ))),
    }
}

/// Names of a scalar that may hold the sample rate (compared without
/// case): named in the message asking for `--rate`, never taken as the
/// rate, since its unit (Hz, kHz) and meaning are a guess.
const RATE_NAMES: [&str; 12] = [
    "fs",
    "fs_hz",
    "sr",
    "srate",
    "rate",
    "rate_hz",
    "samplerate",
    "sample_rate",
    "sample_rate_hz",
    "sampling_rate",
    "sampling_rate_hz",
    "sampling_frequency",
];

/// The recording of named channels sampled at `--rate`, renamed by
/// `--names`; every channel the same length. `meta` holds the file's
/// scalars; those a `--meta` key could be are kept as metadata.
pub(super) fn signal(
    mut channels: Vec<(String, Vec<f64>)>,
    mut digits: Vec<Digits>,
    mut meta: Vec<(String, toml::Value)>,
    args: &Request,
    origin: &str,
    what: &str,
) -> Result<Imported, ImportError> {
    let Some(rate) = args.rate else {
        let like_rate = meta
            .iter()
            .find(|(k, _)| RATE_NAMES.iter().any(|r| k.eq_ignore_ascii_case(r)));
        return Err(bad(match like_rate {
            Some((k, v)) => {
                let v = v.as_float().map_or_else(|| v.to_string(), super::plain);
                format!(
                    "{origin}: {what} carries no sample rate import can be sure of; its scalar \
                     `{k}` = {v} looks like one: give --rate {v} if that is in Hz"
                )
            }
            None => match times_rate(&channels) {
                Some((name, hz)) => format!(
                    "{origin}: {what} carries no sample rate import can be sure of; its array \
                     `{name}` looks like sample times, a sample every {} s: give --rate {} if \
                     they are in seconds",
                    super::plain(significant(1.0 / hz, 6)),
                    super::plain(significant(hz, 6))
                ),
                None => format!("{origin}: {what} carries no sample rate: give --rate HZ"),
            },
        }));
    };
    check_stated_rate(&meta, rate, origin, what)?;
    meta.retain(|(k, _)| scalar_key(k));
    leave_out_times(&mut channels, &mut digits, rate, origin, what)?;
    let n = channels.first().map_or(0, |c| c.1.len());
    if n == 0 {
        return Err(bad(format!("{origin}: no samples")));
    }
    if let Some((name, v)) = channels.iter().find(|c| c.1.len() != n) {
        return Err(bad(format!(
            "{origin}: {name:?} has {} samples but {:?} has {n}: one recording's channels share their samples",
            v.len(),
            channels[0].0
        )));
    }
    let mut names: Vec<String> = channels.iter().map(|c| c.0.clone()).collect();
    if !args.names.is_empty() {
        if args.names.len() != names.len() {
            return Err(bad(format!(
                "--names gives {} name(s) but {origin} has {} channel(s) ({})",
                args.names.len(),
                names.len(),
                names.join(", ")
            )));
        }
        names = args.names.clone();
    }
    let mut all_meta = vec![("rate_hz".to_string(), toml::Value::Float(rate))];
    all_meta.extend(meta);
    Ok(Imported {
        label: None,
        time: (0..n).map(|i| i as f64 / rate).collect(),
        names,
        channels: channels.into_iter().map(|c| c.1).collect(),
        meta: all_meta,
        time_digits: Digits::Decimals(time_decimals(rate)),
        channel_digits: digits,
    })
}

/// A scalar named like a rate (`fs` = 2000) that `--rate` contradicts by
/// more than 0.5 % (as a time array is checked), in Hz or in kHz: refused,
/// never imported at the wrong rate without a word.
fn check_stated_rate(
    meta: &[(String, toml::Value)],
    rate: f64,
    origin: &str,
    what: &str,
) -> Result<(), ImportError> {
    for (k, v) in meta {
        let Some(stated) = v.as_float().or_else(|| v.as_integer().map(|i| i as f64)) else {
            continue;
        };
        let named_like_a_rate = RATE_NAMES.iter().any(|r| k.eq_ignore_ascii_case(r));
        if !(named_like_a_rate && stated.is_finite() && stated > 0.0) {
            continue;
        }
        let near = |hz: f64| (hz - rate).abs() <= 0.005 * rate;
        if !near(stated) && !near(stated * 1000.0) {
            let v = super::plain(stated);
            return Err(bad(format!(
                "{origin}: {what} states its rate as `{k}` = {v}, but --rate is {}: give --rate \
                 {v} if `{k}` is in Hz (or rename `{k}` if it is no sample rate)",
                super::plain(rate)
            )));
        }
    }
    Ok(())
}

/// The array named like sample times and the rate its mean spacing gives,
/// when it is steady (ascending, finite).
fn times_rate(channels: &[(String, Vec<f64>)]) -> Option<(&str, f64)> {
    let (name, t) = channels
        .iter()
        .find(|(name, _)| super::csv::is_time_name(name))?;
    Some((name.as_str(), 1.0 / mean_period(t)?))
}

/// The mean spacing of sample times, when there are two or more and it is
/// finite and positive.
fn mean_period(t: &[f64]) -> Option<f64> {
    let (first, last) = (t.first()?, t.last()?);
    let period = (last - first) / (t.len().checked_sub(1)? as f64);
    (period.is_finite() && period > 0.0).then_some(period)
}

/// The named arrays without one that holds the sample times (named `t`,
/// `time`, `time_s`… as a CSV's time column): kept, it would be analysed
/// as a signal. Its spacing must agree with `--rate` within 0.5 %, or
/// the import is refused naming both.
fn leave_out_times(
    channels: &mut Vec<(String, Vec<f64>)>,
    digits: &mut Vec<Digits>,
    rate: f64,
    origin: &str,
    what: &str,
) -> Result<(), ImportError> {
    let Some(i) = channels
        .iter()
        .position(|(name, _)| super::csv::is_time_name(name))
    else {
        return Ok(());
    };
    let (name, times) = channels.remove(i);
    digits.remove(i);
    if channels.is_empty() {
        return Err(bad(format!(
            "{origin}: {what} holds only `{name}`, which looks like sample times: \
             save the signal beside it"
        )));
    }
    if times.len() > 1 {
        let period = mean_period(&times);
        if !period.is_some_and(|p| (p * rate - 1.0).abs() <= 0.005) {
            let said = period.map_or("no steady sample period".to_string(), |p| {
                format!(
                    "a sample every {} s, {} Hz",
                    super::plain(significant(p, 6)),
                    super::plain(significant(1.0 / p, 6))
                )
            });
            return Err(bad(format!(
                "{origin}: `{name}` looks like sample times ({said}) but --rate says {} Hz: \
                 give the rate the times were taken at (the array is left out either way), \
                 or rename it if it is a signal",
                super::plain(rate)
            )));
        }
    }
    Ok(())
}

/// A `.npy` file's recording.
pub fn parse_npy_file(bytes: &[u8], origin: &str, args: &Request) -> Result<Imported, ImportError> {
    let a = parse_npy(bytes, origin)?;
    let chans = channels_of(&a, "ch", args, origin)?;
    let names: Vec<(String, Vec<f64>)> = if chans.len() == 1 {
        vec![(
            "ch1".into(),
            chans.into_iter().next().map(|c| c.1).unwrap_or_default(),
        )]
    } else {
        chans
            .into_iter()
            .map(|(n, v)| (n.replace("ch_", "ch"), v))
            .collect()
    };
    let digits = vec![a.digits; names.len()];
    signal(names, digits, Vec::new(), args, origin, "a .npy file")
}

/// A `.npz` file's recording: its arrays by name (see the module's note).
pub fn parse_npz_file(bytes: &[u8], origin: &str, args: &Request) -> Result<Imported, ImportError> {
    let entries = unzip(bytes, origin)?;
    let mut channels = Vec::new();
    let mut digits = Vec::new();
    let mut meta = Vec::new();
    let several = entries.len() > 1;
    for (file, data) in &entries {
        let name = file.strip_suffix(".npy").unwrap_or(file);
        let a = parse_npy(data, &format!("{origin}: {file}"))?;
        if a.shape.is_empty() && several {
            meta.push((name.to_string(), toml::Value::Float(a.values[0])));
            continue;
        }
        if several && a.shape.len() != 1 {
            return Err(bad(format!(
                "{origin}: array {name:?} has shape {:?}: an .npz of several arrays takes 1-D ones, one per channel",
                a.shape
            )));
        }
        for (n, v) in channels_of(&a, name, args, origin)? {
            channels.push((n, v));
            digits.push(a.digits);
        }
    }
    signal(channels, digits, meta, args, origin, "an .npz file")
}

/// Whether a scalar array or variable named `k` can be metadata: a key
/// `--meta` would take, and none the import sets itself.
fn scalar_key(k: &str) -> bool {
    const SET: [&str; 5] = ["source", "device", "wav_format", "full_scale", "software"];
    super::parse_meta(&format!("{k}=0")).is_ok()
        && !SET.contains(&k)
        && !super::split::KEYS.contains(&k)
}

/// The entries of a zip archive (name, bytes), stored or deflated, in the
/// central directory's order.
fn unzip(b: &[u8], origin: &str) -> Result<Vec<(String, Vec<u8>)>, ImportError> {
    let err = |m: &str| bad(format!("{origin}: not an .npz (zip) file this reads: {m}"));
    let u16_at = |i: usize| {
        b.get(i..i + 2)
            .map(|s| u16::from_le_bytes([s[0], s[1]]) as usize)
    };
    let u32_at = |i: usize| {
        b.get(i..i + 4)
            .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize)
    };
    // The end of central directory record: within the last 64 KiB + 22 bytes.
    let eocd = (0..b.len().saturating_sub(21))
        .rev()
        .take(65_557)
        .find(|&i| b[i..].starts_with(b"PK\x05\x06"))
        .ok_or_else(|| err("no end of central directory"))?;
    let count = u16_at(eocd + 10).ok_or_else(|| err("cut short"))?;
    let mut at = u32_at(eocd + 16).ok_or_else(|| err("cut short"))?;
    let mut out = Vec::new();
    // What all entries together may unpack to ([`crate::io::inflate_limit`]).
    let mut budget = crate::io::inflate_limit(b.len() as u64);
    for _ in 0..count {
        if !b.get(at..).is_some_and(|s| s.starts_with(b"PK\x01\x02")) {
            return Err(err("a central directory entry is damaged"));
        }
        let field = |o: usize| u16_at(at + o).ok_or_else(|| err("cut short"));
        let (method, name_len, extra, comment) = (field(10)?, field(28)?, field(30)?, field(32)?);
        let size = u32_at(at + 20).ok_or_else(|| err("cut short"))?;
        let full = u32_at(at + 24).ok_or_else(|| err("cut short"))?;
        let local = u32_at(at + 42).ok_or_else(|| err("cut short"))?;
        if size == 0xFFFF_FFFF || local == 0xFFFF_FFFF {
            return Err(err("a zip64 entry over 4 GiB"));
        }
        let name =
            String::from_utf8_lossy(b.get(at + 46..at + 46 + name_len).unwrap_or(&[])).into_owned();
        let data_at =
            local + 30 + u16_at(local + 26).unwrap_or(0) + u16_at(local + 28).unwrap_or(0);
        let raw = b
            .get(data_at..data_at + size)
            .ok_or_else(|| err(&format!("entry {name:?} is cut short")))?;
        let data = match method {
            0 => raw.to_vec(),
            8 => {
                // The size the entry claims is checked against what the
                // file may unpack to before anything is allocated, and the
                // inflation stops past it.
                if full as u64 > budget {
                    return Err(bad(format!(
                        "{origin}: entry {name:?} claims {full} bytes unpacked, more than the {budget} \
                         an .npz of {} bytes is read as: refused as a decompression bomb",
                        b.len()
                    )));
                }
                let v = crate::io::inflate_at_most(raw, crate::io::Packing::Deflate, full as u64)
                    .map_err(|e| match e {
                    crate::io::InflateError::TooLarge { .. } => err(&format!(
                        "entry {name:?} unpacks to more than the {full} bytes it claims"
                    )),
                    e => err(&format!("entry {name:?}: {e}")),
                })?;
                if v.len() != full {
                    return Err(err(&format!(
                        "entry {name:?} unpacks to {} bytes, not the {full} it claims",
                        v.len()
                    )));
                }
                budget -= full as u64;
                v
            }
            m => return Err(err(&format!("entry {name:?} uses compression method {m}"))),
        };
        out.push((name, data));
        at += 46 + name_len + extra + comment;
    }
    if out.is_empty() {
        return Err(err("no arrays"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signal_of(arrays: &[(&str, Vec<f64>)], rate: f64) -> Result<Imported, ImportError> {
        let channels: Vec<(String, Vec<f64>)> = arrays
            .iter()
            .map(|(n, v)| (n.to_string(), v.clone()))
            .collect();
        let digits = vec![Digits::Shortest; channels.len()];
        let args = Request {
            rate: Some(rate),
            ..Request::default()
        };
        signal(channels, digits, Vec::new(), &args, "x.npz", "an .npz file")
    }

    #[test]
    fn an_array_of_sample_times_is_left_out_and_checked_against_the_rate() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.001).collect();
        let acc: Vec<f64> = (0..100).map(|i| (i % 7) as f64).collect();
        let r = signal_of(&[("t", t.clone()), ("acc", acc.clone())], 1000.0).unwrap();
        assert_eq!(
            (r.names, r.channels),
            (vec!["acc".to_string()], vec![acc.clone()])
        );
        let e = signal_of(&[("Time", t.clone()), ("acc", acc)], 500.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`Time` looks like sample times (a sample every 0.001 s, 1000 Hz)")
                && e.contains("--rate says 500 Hz"),
            "{e}"
        );
        let e = signal_of(&[("t", t.clone())], 1000.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds only `t`"), "{e}");
        // Without --rate, the times' rate is offered (times as np.arange(n) / 3
        // gives them, float noise and all).
        let t: Vec<f64> = (0..100).map(|i| i as f64 / 3.0).collect();
        let channels = vec![("t".to_string(), t), ("acc".to_string(), vec![0.0; 100])];
        let digits = vec![Digits::Shortest; 2];
        let e = signal(
            channels,
            digits,
            Vec::new(),
            &Request::default(),
            "x.npz",
            "an .npz file",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`t` looks like sample times, a sample every 0.333333 s: give --rate 3 "),
            "{e}"
        );
    }
}
