//! Headerless text: one number per line (the LMT haptic texture database's
//! layout), or several separated by whitespace (or commas) per line, one
//! column per channel, sampled at `--rate`. Lines starting with `#` or `%`
//! are comments. A file is headerless when its first line is all numbers.

use super::{ImportError, Imported, Request, bad};
use crate::recording::Digits;

/// The lines of `text` that hold data, numbered from 1.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#') && !l.starts_with('%'))
}

fn fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|f| !f.is_empty())
}

/// Whether `text` holds anything but blank lines and comments.
pub fn has_lines(text: &str) -> bool {
    data_lines(text).next().is_some()
}

/// Whether `text` starts with a line of numbers only (no header).
pub fn is_headerless(text: &str) -> bool {
    data_lines(text).next().is_some_and(|(_, l)| {
        let mut f = fields(l).peekable();
        f.peek().is_some() && f.all(|x| x.parse::<f64>().is_ok())
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
        let values: Vec<&str> = fields(line).collect();
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
            integers &= !v.contains(['.', 'e', 'E']);
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
        let e = m(parse("1\n2\n", "x.txt", &Request::default()));
        assert!(e.contains("x.txt") && e.contains("--rate"), "{e}");
    }
}
