//! MATLAB `.mat` level 5 (what `save -v6`/`-v7` and scipy's `savemat`
//! write), read by hand: numeric variables, compressed or not, become
//! channels named by the variable (a matrix's columns `name_1`, `name_2`, …,
//! or its rows when it has fewer rows than columns); a scalar becomes
//! metadata; text, cells, structs and sparse matrices are left out. A v7.3
//! file (HDF5 inside) is refused with how to save it in a form this reads.

use super::npy::{Array, channels_of, signal};
use super::{ImportError, Imported, Request, bad};
use crate::recording::Digits;

const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

/// A data element: its type and bytes (byte order already known).
struct Element<'a> {
    kind: u32,
    data: &'a [u8],
}

/// Reads the element at `at` in `b`: (the element, where the next starts).
fn element(b: &[u8], at: usize, big: bool) -> Option<(Element<'_>, usize)> {
    let word = |i: usize| -> Option<u32> {
        let s: [u8; 4] = b.get(i..i + 4)?.try_into().ok()?;
        Some(if big {
            u32::from_be_bytes(s)
        } else {
            u32::from_le_bytes(s)
        })
    };
    let tag = word(at)?;
    // The small element format: type and size in one word, data in the next four bytes.
    if tag >> 16 != 0 {
        let (kind, len) = (tag & 0xFFFF, (tag >> 16) as usize);
        let data = b.get(at + 4..at + 4 + len.min(4))?;
        return Some((Element { kind, data }, at + 8));
    }
    let len = word(at + 4)? as usize;
    let data = b.get(at + 8..at.checked_add(8)?.checked_add(len)?)?;
    // Elements are padded to 8 bytes; a compressed one is not.
    let padded = if tag == MI_COMPRESSED {
        len
    } else {
        len.div_ceil(8) * 8
    };
    Some((Element { kind: tag, data }, at + 8 + padded))
}

/// The numbers of a numeric element, and whether they are integers.
fn numbers(e: &Element, big: bool) -> Option<(Vec<f64>, bool)> {
    let width = match e.kind {
        1 | 2 => 1,
        3 | 4 => 2,
        5..=7 => 4,
        9 | 12 | 13 => 8,
        _ => return None,
    };
    let values = e
        .data
        .chunks_exact(width)
        .map(|c| {
            let mut s = [0u8; 8];
            s[..width].copy_from_slice(c);
            if big {
                s[..width].reverse();
            }
            let signed = |bits: u32| ((i64::from_le_bytes(s) << (64 - bits)) >> (64 - bits)) as f64;
            match e.kind {
                1 => signed(8),
                3 => signed(16),
                5 => signed(32),
                12 => signed(64),
                7 => f64::from(f32::from_le_bytes([s[0], s[1], s[2], s[3]])),
                9 => f64::from_le_bytes(s),
                _ => u64::from_le_bytes(s) as f64,
            }
        })
        .collect();
    Some((values, !matches!(e.kind, 7 | 9)))
}

/// A numeric matrix variable: its name and array (column-major made
/// row-major); `None` for any other class.
fn variable(m: &[u8], big: bool, origin: &str) -> Result<Option<(String, Array)>, ImportError> {
    let err = |what: &str| bad(format!("{origin}: a damaged MATLAB variable: {what}"));
    let (flags, at) = element(m, 0, big).ok_or_else(|| err("no array flags"))?;
    let class = numbers(&flags, big)
        .and_then(|v| v.0.first().copied())
        .unwrap_or(0.0) as u32
        & 0xFF;
    let complex = flags
        .data
        .get(if big { 2 } else { 1 })
        .is_some_and(|f| f & 0x08 != 0);
    let (dims, at) = element(m, at, big).ok_or_else(|| err("no dimensions"))?;
    let (name, at) = element(m, at, big).ok_or_else(|| err("no name"))?;
    let name = String::from_utf8_lossy(name.data).into_owned();
    // 6–15: double, single, int8 … uint64; the rest (cell, struct, char,
    // sparse, object) carry no samples.
    if !(6..=15).contains(&class) {
        return Ok(None);
    }
    if complex {
        return Err(bad(format!(
            "{origin}: variable {name:?} is complex: save its real part (or abs) instead"
        )));
    }
    let dims: Vec<usize> = numbers(&dims, big)
        .ok_or_else(|| err("dimensions"))?
        .0
        .iter()
        .map(|d| *d as usize)
        .collect();
    let (real, _) = element(m, at, big).ok_or_else(|| err(&format!("{name}: no values")))?;
    // The dimensions are checked against the values the file holds before
    // anything is made of them (their product may overflow).
    let declared = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    let (values, _) = numbers(&real, big).ok_or_else(|| err(&format!("{name}: values")))?;
    if declared != Some(values.len()) {
        return Err(err(&format!(
            "{name}: {} values for dimensions {dims:?}",
            values.len()
        )));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(bad(format!(
            "{origin}: variable {name:?}: element {i} is not a finite number"
        )));
    }
    let digits = match class {
        6 => Digits::Shortest,
        7 => Digits::ShortestF32,
        _ => Digits::Decimals(0),
    };
    // A vector is 1-D whichever way it lies; a matrix is column-major.
    let shape = match dims[..] {
        [1, 1] => Vec::new(),
        [1, n] | [n, 1] => vec![n],
        [r, c] => vec![r, c],
        _ => {
            return Err(bad(format!(
                "{origin}: variable {name:?} has dimensions {dims:?}: import takes vectors and 2-D matrices"
            )));
        }
    };
    let values = if shape.len() == 2 {
        let (r, c) = (shape[0], shape[1]);
        (0..r * c).map(|k| values[(k % c) * r + k / c]).collect()
    } else {
        values
    };
    Ok(Some((
        name,
        Array {
            shape,
            values,
            digits,
        },
    )))
}

/// A `.mat` file's recording.
pub fn parse_mat_file(b: &[u8], origin: &str, args: &Request) -> Result<Imported, ImportError> {
    let v73 = b.get(512..520) == Some(b"\x89HDF\r\n\x1a\n")
        || b.starts_with(b"MATLAB 7.3")
        || b.get(124..126) == Some(&[0, 2]);
    if v73 {
        return Err(bad(format!(
            "{origin}: a MATLAB v7.3 file (HDF5 inside), which import does not read: in MATLAB save it as v7 \
             (`save('file.mat', 'x', '-v7')`) or as text (`writematrix(x, 'file.csv')`)"
        )));
    }
    let big = match b.get(126..128) {
        Some(b"IM") => false,
        Some(b"MI") => true,
        _ => {
            return Err(bad(format!(
                "{origin}: not a MATLAB level 5 .mat file (no header): save it with `save -v7` or as CSV"
            )));
        }
    };
    // The header's byte order must be the data's: a first element that is
    // a matrix only when read the other way says the file is damaged.
    let kind = |big: bool| {
        b.get(128..132).map(|w| {
            let w: [u8; 4] = w.try_into().unwrap_or_default();
            if big {
                u32::from_be_bytes(w)
            } else {
                u32::from_le_bytes(w)
            }
        })
    };
    if let (Some(ours), Some(other)) = (kind(big), kind(!big))
        && ![MI_MATRIX, MI_COMPRESSED].contains(&ours)
        && [MI_MATRIX, MI_COMPRESSED].contains(&other)
    {
        return Err(bad(format!(
            "{origin}: its header says the data is {} but the data reads as {}: a damaged \
             .mat file (save it again, or as CSV)",
            if big {
                "big-endian ('MI')"
            } else {
                "little-endian ('IM')"
            },
            if big { "little-endian" } else { "big-endian" }
        )));
    }
    let mut channels = Vec::new();
    let mut digits = Vec::new();
    let mut meta = Vec::new();
    let mut at = 128;
    // What all compressed variables together may unpack to: a bomb is
    // refused having unpacked at most this ([`crate::io::inflate_limit`]).
    let mut budget = crate::io::inflate_limit(b.len() as u64);
    while at + 8 <= b.len() {
        let (e, next) =
            element(b, at, big).ok_or_else(|| bad(format!("{origin}: cut short at byte {at}")))?;
        at = next;
        let inflated;
        let matrix = match e.kind {
            MI_MATRIX => e.data,
            MI_COMPRESSED => {
                inflated = crate::io::inflate_at_most(e.data, crate::io::Packing::Zlib, budget)
                    .map_err(|x| bad(format!("{origin}: a compressed variable: {x}")))?;
                budget -= inflated.len() as u64;
                match element(&inflated, 0, big) {
                    Some((inner, _)) if inner.kind == MI_MATRIX => inner.data,
                    _ => continue,
                }
            }
            _ => continue,
        };
        let Some((name, a)) = variable(matrix, big, origin)? else {
            continue;
        };
        if a.shape.is_empty() {
            meta.push((name, toml::Value::Float(a.values[0])));
            continue;
        }
        for (n, v) in channels_of(&a, &name, args, origin)? {
            channels.push((n, v));
            digits.push(a.digits);
        }
    }
    if channels.is_empty() {
        return Err(bad(format!(
            "{origin}: no numeric vector or matrix among its variables"
        )));
    }
    signal(channels, digits, meta, args, origin, "a .mat file")
}
