//! WAV (RIFF) files: PCM 8/16/24/32-bit integer or 32/64-bit float, any
//! number of channels. Integer samples are kept as integer counts (exact),
//! with `full_scale` in the metadata to normalise them.

use super::{ImportError, Imported, bad};
use crate::recording::{Digits, time_decimals};

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}
fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Parse a WAV file's bytes.
pub fn parse_wav(bytes: &[u8], origin: &str) -> Result<Imported, ImportError> {
    let err = |m: &str| bad(format!("{origin}: not a WAV file this reads: {m}"));
    if bytes.len() < 12 || &bytes[0..4] != b"RIFF" || &bytes[8..12] != b"WAVE" {
        return Err(err("no RIFF/WAVE header"));
    }
    let mut at = 12;
    let mut fmt: Option<(u16, u16, u32, u16)> = None;
    let mut data: Option<&[u8]> = None;
    while at + 8 <= bytes.len() {
        let id = &bytes[at..at + 4];
        let len = u32_at(bytes, at + 4) as usize;
        let body = &bytes[at + 8..(at + 8 + len).min(bytes.len())];
        if id == b"fmt " {
            if fmt.is_some() {
                // Which one a reader takes is a guess: the samples' meaning
                // would hang on it.
                return Err(err("two fmt chunks (a file has one)"));
            }
            if body.len() < 16 {
                return Err(err("the fmt chunk is too short"));
            }
            let mut format = u16_at(body, 0);
            if format == 0xFFFE && body.len() >= 26 {
                format = u16_at(body, 24); // WAVE_FORMAT_EXTENSIBLE: the sub-format's tag
            }
            fmt = Some((format, u16_at(body, 2), u32_at(body, 4), u16_at(body, 14)));
        } else if id == b"data" {
            if body.len() < len {
                return Err(err(&format!(
                    "the data chunk is cut short ({} of {len} bytes)",
                    body.len()
                )));
            }
            data = Some(body);
        }
        at += 8 + len + (len & 1);
    }
    let (format, channels, rate, bits) = fmt.ok_or_else(|| err("no fmt chunk"))?;
    let data = data.ok_or_else(|| err("no data chunk"))?;
    if channels == 0 || rate == 0 {
        return Err(err("zero channels or a zero sample rate"));
    }
    let width = usize::from(bits / 8);
    let (kind, full_scale) = match (format, bits) {
        (1, 8 | 16 | 24 | 32) => ("int", Some(2f64.powi(i32::from(bits) - 1))),
        (3, 32 | 64) => ("float", None),
        _ => {
            return Err(err(&format!(
                "format tag {format} with {bits} bits (PCM 8/16/24/32-bit or float 32/64-bit only)"
            )));
        }
    };
    let frame = width * usize::from(channels);
    let n = data.len() / frame;
    let mut out = vec![Vec::with_capacity(n); usize::from(channels)];
    for f in 0..n {
        for (c, ch) in out.iter_mut().enumerate() {
            let s = &data[f * frame + c * width..f * frame + (c + 1) * width];
            let v = match (kind, width) {
                ("int", 1) => f64::from(s[0]) - 128.0, // 8-bit WAV is unsigned
                ("int", 2) => f64::from(i16::from_le_bytes([s[0], s[1]])),
                ("int", 3) => f64::from(i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8),
                ("int", 4) => f64::from(i32::from_le_bytes([s[0], s[1], s[2], s[3]])),
                ("float", 4) => f64::from(f32::from_le_bytes([s[0], s[1], s[2], s[3]])),
                _ => f64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]]),
            };
            if !v.is_finite() {
                return Err(err(&format!(
                    "sample {f} of channel {} is not finite",
                    c + 1
                )));
            }
            ch.push(v);
        }
    }
    if n == 0 {
        return Err(err("no samples"));
    }
    let rate = f64::from(rate);
    let mut meta = vec![
        ("rate_hz".to_string(), toml::Value::Float(rate)),
        (
            "wav_format".to_string(),
            toml::Value::String(format!("{kind}{bits}")),
        ),
    ];
    if let Some(fs) = full_scale {
        meta.push(("full_scale".to_string(), toml::Value::Float(fs)));
    }
    // Integer counts stay integers; float samples are written exactly.
    let digits = match (kind, bits) {
        ("int", _) => Digits::Decimals(0),
        (_, 32) => Digits::ShortestF32,
        _ => Digits::Shortest,
    };
    Ok(Imported {
        label: None,
        time: (0..n).map(|i| i as f64 / rate).collect(),
        names: (1..=channels).map(|c| format!("ch{c}")).collect(),
        channel_digits: vec![digits; out.len()],
        channels: out,
        meta,
        time_digits: Digits::Decimals(time_decimals(rate)),
    })
}
