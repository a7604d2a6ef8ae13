//! Headerless text: one number per line (the LMT haptic texture database's
//! layout), or several separated by whitespace (or commas) per line, one
//! column per channel, sampled at `--rate`. Lines starting with `#` or `%`
//! are comments. A file is headerless when its first line is all numbers.

use super::{ImportError, Imported, Request, bad};
use crate::recording::Digits;

/// The lines of `text`, ended by `\n`, `\r\n` or a lone `\r` (a classic
/// Mac export), numbered from 1.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = text;
    let mut n = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        n += 1;
        let end = rest.find(['\n', '\r']).unwrap_or(rest.len());
        let line = &rest[..end];
        let skip = match rest.as_bytes().get(end) {
            Some(b'\r') if rest.as_bytes().get(end + 1) == Some(&b'\n') => 2,
            Some(_) => 1,
            None => 0,
        };
        rest = &rest[end + skip..];
        Some((n, line))
    })
}

/// The lines of `text` that hold data, numbered from 1.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    lines(text)
        .map(|(i, l)| (i, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#') && !l.starts_with('%'))
}

/// The values of a line: separated by whitespace, or by `,` or `;` (spaces
/// around them allowed). `None` for a value left empty between two
/// separators (`1,,-1`): the columns after it would shift.
fn fields(line: &str) -> Vec<Option<&str>> {
    let parts: Vec<&str> = line.split([',', ';']).collect();
    let last = parts.len() - 1;
    parts
        .iter()
        .enumerate()
        .flat_map(|(i, part)| {
            let words: Vec<Option<&str>> = part.split_whitespace().map(Some).collect();
            // One trailing separator ("1,2,") is an exporter's habit, not a value.
            if words.is_empty() && !(i == last && last > 0) {
                vec![None]
            } else {
                words
            }
        })
        .collect()
}

/// Whether `line` writes its decimals with a comma: `0,099;-0,099` (a
/// `;` beside commas), or a value after a comma with a leading zero that no
/// integer column has (`0,099`).
fn decimal_comma(line: &str) -> bool {
    let leading_zero = |f: &str| {
        let f = f.trim().trim_start_matches(['-', '+']);
        f.len() > 1 && f.starts_with('0') && f.as_bytes()[1].is_ascii_digit()
    };
    line.contains(',') && (line.contains(';') || line.split(',').skip(1).any(leading_zero))
}

/// Whether `text` holds anything but blank lines and comments.
pub fn has_lines(text: &str) -> bool {
    data_lines(text).next().is_some()
}

/// Whether `text` starts with a line of numbers only (no header).
pub fn is_headerless(text: &str) -> bool {
    data_lines(text).next().is_some_and(|(_, l)| {
        let f = fields(l);
        !f.is_empty()
            && f.iter()
                .all(|x| x.is_some_and(|x| x.parse::<f64>().is_ok()))
    })
}

/// Parses headerless text: channels `ch1`, `ch2`, … (or `--names`) at `--rate`.
pub fn parse(text: &str, origin: &str, args: &Request) -> Result<Imported, ImportError> {
    if args.time_column.is_some() || args.label_column.is_some() {
        return Err(bad(format!(
            "{origin}: a file without a header has no column names for --time-column or --label-column: give --rate and --label (or the folder's name)"
        )));
    }
    let mut channels: Vec<Vec<f64>> = Vec::new();
    let mut integers = true;
    for (ln, line) in data_lines(text) {
        if decimal_comma(line) {
            return Err(bad(format!(
                "{origin}:{ln}: {line:?} looks like numbers written with a decimal comma, which \
                 would be read as two columns: write decimal points (and separate the values by \
                 commas, tabs or spaces)"
            )));
        }
        let values = fields(line);
        if let Some(c) = values.iter().position(Option::is_none) {
            return Err(bad(format!(
                "{origin}:{ln}: value {} is empty ({line:?}): every column needs a value on every \
                 line, or the columns after it would shift",
                c + 1
            )));
        }
        let values: Vec<&str> = values.into_iter().flatten().collect();
        if channels.is_empty() {
            channels = vec![Vec::new(); values.len()];
        }
        if values.len() != channels.len() {
            return Err(bad(format!(
                "{origin}:{ln}: {} values but the first line has {}",
                values.len(),
                channels.len()
            )));
        }
        for (c, v) in values.iter().enumerate() {
            let x = v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "{origin}:{ln}: value {} ({v:?}) is not a finite number",
                        c + 1
                    ))
                })?;
            let integer = !v.contains(['.', 'e', 'E']);
            // Exactly the integer written? (f64 rounds 2^53 + 1 to 2^53.)
            let exact = || match v.trim_start_matches('+').parse::<i128>() {
                Ok(n) => x as i128 == n,
                Err(_) => x.abs() < super::EXACT_INTEGER,
            };
            if integer && x.abs() >= super::EXACT_INTEGER && !exact() {
                return Err(super::inexact_integer(&format!("{origin}:{ln}"), c + 1, v));
            }
            integers &= integer;
            channels[c].push(x);
        }
    }
    let named: Vec<(String, Vec<f64>)> = channels
        .into_iter()
        .enumerate()
        .map(|(c, v)| (format!("ch{}", c + 1), v))
        .collect();
    // Integer counts stay integers; other values are written exactly.
    let digits = if integers {
        Digits::Decimals(0)
    } else {
        Digits::Shortest
    };
    let digits = vec![digits; named.len()];
    super::npy::signal(
        named,
        digits,
        Vec::new(),
        args,
        origin,
        "a file without a header",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_column_and_whitespace_columns_read_at_the_rate() {
        let args = Request {
            rate: Some(10_000.0),
            ..Request::default()
        };
        assert!(is_headerless("% LMT\n0.012\n-0.03\n"));
        assert!(!is_headerless("acc\n1\n"));
        let one = parse("0.012\n-0.03\n0.5\n", "a.txt", &args).unwrap();
        assert_eq!(one.names, ["ch1"]);
        assert_eq!(one.channels, [vec![0.012, -0.03, 0.5]]);
        assert_eq!(one.time[2], 0.0002);
        // Lines ended by a lone CR (a classic Mac export) are lines.
        let cr = parse("0.5\r0.25\r-1\r", "cr.txt", &args).unwrap();
        assert_eq!(cr.channels, [vec![0.5, 0.25, -1.0]]);
        let crlf = parse("1,2\r\n3, 4,\r\n", "crlf.txt", &args).unwrap();
        assert_eq!(crlf.channels, [vec![1.0, 3.0], vec![2.0, 4.0]]);
        let two = parse("1  2\n3\t4\n", "b.txt", &args).unwrap();
        assert_eq!(two.channels, [vec![1.0, 3.0], vec![2.0, 4.0]]);
        assert_eq!(two.channel_digits[0], Digits::Decimals(0));
    }

    #[test]
    fn a_ragged_line_a_word_and_no_rate_are_refused_naming_the_line() {
        let args = Request {
            rate: Some(100.0),
            ..Request::default()
        };
        let m = |r: Result<Imported, ImportError>| match r.unwrap_err() {
            ImportError::BadInput(m) | ImportError::Runtime(m) => m,
        };
        assert!(m(parse("1 2\n3\n", "r.txt", &args)).contains("r.txt:2: 1 values"));
        assert!(m(parse("1\nnan\n", "n.txt", &args)).contains("n.txt:2: value 1"));
        // A value left empty between separators would shift the columns.
        assert!(m(parse("1,2,3\n1,,-1\n", "e.txt", &args)).contains("e.txt:2: value 2 is empty"));
        // Decimal commas are not read as two columns.
        for text in ["0,099\n0,1\n", "0,099;-0,099\n"] {
            assert!(
                m(parse(text, "c.txt", &args)).contains("decimal comma"),
                "{text:?}"
            );
        }
        // An integer a 64-bit float cannot hold exactly.
        let e = m(parse("1\n9007199254740993\n", "i.txt", &args));
        assert!(e.contains("i.txt:2") && e.contains("2^53"), "{e}");
        let e = m(parse("1\n2\n", "x.txt", &Request::default()));
        assert!(e.contains("x.txt") && e.contains("--rate"), "{e}");
    }
}
