//! The numbers of a recording's rows: a fast exact path for plain decimals
//! (what the writer writes), the general `str::parse` for anything else.
//! Pure functions over bytes; never panics, never allocates.

/// Powers of ten that an f64 holds exactly.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses a plain decimal (`-0.045000`) at the start of `b`: the value and the
/// bytes it spans, or `None` when the text needs the general parser.
///
/// Exact: with at most 2^53 as the integer of digits and at most 22 decimals,
/// both operands of the one division are exact f64s, and IEEE division
/// rounds correctly (Clinger's fast path), so this agrees with `str::parse`.
#[inline]
fn parse_plain_decimal(b: &[u8]) -> Option<(f64, usize)> {
    let (negative, sign) = match b.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let mut mantissa: u64 = 0;
    let mut i = accumulate_digits(b, sign, &mut mantissa);
    let mut digits = i - sign;
    let mut decimals = 0;
    if b.get(i) == Some(&b'.') {
        let first_decimal = i + 1;
        i = accumulate_digits(b, first_decimal, &mut mantissa);
        decimals = i - first_decimal;
        digits += decimals;
    }
    if digits == 0 || digits > 19 || mantissa > (1 << 53) || decimals >= POW10.len() {
        return None;
    }
    let magnitude = mantissa as f64 / POW10[decimals];
    Some((if negative { -magnitude } else { magnitude }, i))
}

/// Appends the digits from `b[i..]` to `mantissa`; the position after them.
/// (One byte at a time: reading eight at once, as fast_float does, measured
/// slower here, where a value's runs of digits are one to six long.)
#[inline(always)]
fn accumulate_digits(b: &[u8], mut i: usize, mantissa: &mut u64) -> usize {
    while let Some(d) = b.get(i).map(|c| c.wrapping_sub(b'0')).filter(|&d| d <= 9) {
        // Wrapping: overflow past 19 digits is caught by the caller's check.
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    i
}

/// The position after the digits from `b[i..]`.
#[inline(always)]
fn skip_digits(b: &[u8], mut i: usize) -> usize {
    while b.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    i
}

/// Parses one whole value: plain decimals quickly, anything else `str::parse`
/// accepts (exponents, `nan`, `inf`) the general way.
pub(super) fn parse_value(text: &str) -> Option<f64> {
    match parse_plain_decimal(text.as_bytes()) {
        Some((v, used)) if used == text.len() => Some(v),
        _ => text.parse().ok(),
    }
}

/// Checks that a plain decimal (`-0.045000`, any number of digits) starts `b`
/// without converting it: the bytes it spans, or `None` when the text needs
/// the general parser. Every text this accepts, `str::parse` reads as a
/// number, so a column skipped this way is refused exactly when reading it
/// would be.
#[inline]
fn skip_plain_decimal(b: &[u8]) -> Option<usize> {
    let sign = usize::from(matches!(b.first(), Some(b'-' | b'+')));
    let mut i = skip_digits(b, sign);
    let mut digits = i - sign;
    if b.get(i) == Some(&b'.') {
        let first_decimal = i + 1;
        i = skip_digits(b, first_decimal);
        digits += i - first_decimal;
    }
    (digits > 0).then_some(i)
}

/// Parses a row of plain decimals starting at `start` into `row`; the
/// position after its line end, or `None` when the row needs the careful path
/// (other number syntax, spaces, the wrong count, …). Columns whose `read`
/// is false are checked but not converted (their slot is left as it was).
#[inline]
pub(super) fn parse_row_fast(
    bytes: &[u8],
    start: usize,
    row: &mut [f64],
    read: &[bool],
) -> Option<usize> {
    let mut pos = start;
    let last = row.len().checked_sub(1)?;
    for (c, (slot, &convert)) in row.iter_mut().zip(read).enumerate() {
        let rest = bytes.get(pos..)?;
        if convert {
            let (value, used) = parse_plain_decimal(rest)?;
            *slot = value;
            pos += used;
        } else {
            pos += skip_plain_decimal(rest)?;
        }
        match bytes.get(pos) {
            Some(b',') if c < last => pos += 1,
            Some(b'\n') if c == last => return Some(pos + 1),
            Some(b'\r') if c == last && bytes.get(pos + 1) == Some(&b'\n') => return Some(pos + 2),
            None if c == last => return Some(pos),
            _ => return None,
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_fast_decimal_path_handles_edges() {
        assert_eq!(parse_plain_decimal(b"1."), Some((1.0, 2)));
        assert_eq!(parse_plain_decimal(b".5,"), Some((0.5, 2)));
        assert_eq!(parse_plain_decimal(b"+3"), Some((3.0, 2)));
        assert_eq!(parse_plain_decimal(b"1e5"), Some((1.0, 1)));
        for refused in [
            &b""[..],
            b"-",
            b".",
            b"-.",
            b"nan",
            b"12345678901234567890",
            b"9007199254740993",
        ] {
            assert_eq!(parse_plain_decimal(refused), None, "{refused:?}");
        }
        assert_eq!(parse_value("9007199254740993"), Some(9007199254740992.0));
        assert_eq!(parse_value("1e5"), Some(1e5));
        assert_eq!(parse_value("1.5 "), None);
    }

    proptest! {
        #[test]
        fn the_fast_decimal_path_agrees_with_std(v in -1e9f64..1e9, decimals in 0usize..12) {
            let text = format!("{v:.decimals$}");
            let expected: f64 = text.parse().unwrap();
            // Up to 15 digits always fit the exact fast path; longer may fall back.
            match parse_plain_decimal(text.as_bytes()) {
                Some((fast, used)) => {
                    prop_assert_eq!(used, text.len());
                    prop_assert_eq!(fast.to_bits(), expected.to_bits(), "{}", text);
                }
                None => prop_assert!(text.bytes().filter(u8::is_ascii_digit).count() > 15, "{}", text),
            }
            prop_assert_eq!(parse_value(&text).map(f64::to_bits), Some(expected.to_bits()));
        }

        #[test]
        fn any_digit_string_agrees_with_std(text in "[-+]?[0-9]{0,20}(\\.[0-9]{0,25})?") {
            prop_assert_eq!(parse_value(&text).map(f64::to_bits), text.parse::<f64>().ok().map(f64::to_bits));
        }
    }
}
