//! Values fitted to the data, as a profile writes them: numbers to three
//! significant digits that TOML reads back exactly ([`floor3`], [`ceil3`],
//! [`float`]) and the log bands that fit a spectrum ([`fitting_bands`]).
//! `profile new` writes its first profile with them and `tune` resolves
//! its searched values with them, so the two cannot fit the same data
//! differently.

use super::analysis::{Analysis, BandScale, Bands, check_options};

/// A float as TOML writes it, shortest, read back to the same value
/// (`0.25`, `3.0`).
pub fn float(v: f64) -> String {
    let t = format!("{v}");
    if t.contains('.') || t.contains('e') {
        t
    } else {
        format!("{t}.0")
    }
}

/// `x` rounded down to three significant digits, with its text (`0.0897`,
/// `123.0`): the value is the one TOML reads back from the text, so a
/// written edge or length stays inside what it bounds.
pub fn floor3(x: f64) -> (f64, String) {
    round3(x, f64::floor)
}

/// As [`floor3`], rounded up.
pub fn ceil3(x: f64) -> (f64, String) {
    round3(x, f64::ceil)
}

/// `x` rounded to `digits` significant digits (`999.9999999999998` to 6
/// gives `1000.0`); `x` itself when it is not a positive finite number.
pub fn significant(x: f64, digits: u32) -> f64 {
    rounded(x, digits, f64::round).0
}

/// `x` rounded by `how` to `digits` significant digits, and the power of
/// ten of its last digit.
fn rounded(x: f64, digits: u32, how: fn(f64) -> f64) -> (f64, i32) {
    if !(x.is_finite() && x > 0.0) {
        return (x, 0);
    }
    let e = x.log10().floor() as i32 + 1 - digits.max(1) as i32;
    // Scaled by an exact power of ten (10^-e is exact, 10^e below 1 is
    // not), so a value written with that many digits stays itself.
    let v = if e < 0 {
        how(x * 10f64.powi(-e)) / 10f64.powi(-e)
    } else {
        how(x / 10f64.powi(e)) * 10f64.powi(e)
    };
    (v, e)
}

/// `x` rounded up to `digits` significant digits, with its shortest text
/// (trailing zeros dropped: `1 / 2200` to 6 digits is `0.000454546`, and
/// `1 / 1000` stays `0.001`): a value a person can read that TOML reads
/// back exactly, and never below `x`.
pub fn ceil_significant(x: f64, digits: u32) -> (f64, String) {
    if !(x.is_finite() && x > 0.0) {
        return (x, float(x));
    }
    let (v, e) = rounded(x, digits, f64::ceil);
    let decimals = (-e).max(0) as usize;
    let mut text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.truncate(text.trim_end_matches('0').len());
        if text.ends_with('.') {
            text.push('0');
        }
    } else {
        text.push_str(".0");
    }
    let read: f64 = text.parse().unwrap_or(v);
    // Float noise in the scaling can land a hair below x: one more step up.
    if read < x {
        let step = 10f64.powi(e);
        return ceil_significant(read + step / 2.0, digits);
    }
    (read, text)
}

fn round3(x: f64, how: fn(f64) -> f64) -> (f64, String) {
    if !(x.is_finite() && x > 0.0) {
        return (x, float(x));
    }
    let (v, e) = rounded(x, 3, how);
    let decimals = (-e).max(0) as usize;
    let text = format!("{v:.decimals$}");
    let v: f64 = text.parse().unwrap_or(v);
    let text = if text.contains('.') {
        text
    } else {
        format!("{text}.0")
    };
    (v, text)
}

/// Log-spaced bands from a few bins above DC (2, 4 or 8) up to the
/// Nyquist frequency, each holding a bin of `a`'s spectrum: 32 of them, or
/// fewer when the spectrum is too coarse; the edges to three digits.
/// More bands win over a lower first edge, but never above 8 bins: a
/// coarse texture's fundamental sits in the lowest bins. `None`: no bands
/// fit.
pub fn fitting_bands(a: &Analysis) -> Option<Bands> {
    let bw = a.bin_width();
    let to = floor3(bw * (a.dft_points() / 2) as f64).0;
    for count in [32, 24, 16, 12, 8] {
        for lowest in [2.0, 4.0, 8.0] {
            let from = floor3(bw * lowest).0;
            let b = Bands {
                count,
                from,
                to,
                scale: BandScale::Log,
            };
            // Whether the bands fit does not depend on the cepstra kept
            // of them: those are the caller's (at most `count`).
            let candidate = Analysis {
                band: None,
                bands: Some(b),
                cepstra: None,
                drop_level: false,
                ..a.clone()
            };
            if to > from && check_options(&candidate).is_ok() {
                return Some(b);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_period_is_written_readably_and_never_below_itself() {
        for (rate, text) in [
            (2200.0, "0.000454546"),
            (1000.0, "0.001"),
            (100.0, "0.01"),
            (44100.0, "0.0000226758"),
            (3.0, "0.333334"),
            (0.5, "2.0"),
        ] {
            let (v, t) = ceil_significant(1.0 / rate, 6);
            assert_eq!(t, text, "{rate} Hz");
            assert_eq!(t.parse::<f64>().unwrap(), v);
            assert!(
                v >= 1.0 / rate && v <= 1.0 / rate * (1.0 + 1e-5),
                "{rate} Hz: {v}"
            );
        }
    }

    #[test]
    fn three_digits_read_back_as_written() {
        assert_eq!(floor3(0.08979).1, "0.0897");
        assert_eq!(floor3(4.999).1, "4.99");
        assert_eq!(floor3(123.9).1, "123.0");
        assert_eq!(floor3(12345.0), (12300.0, "12300.0".to_string()));
        assert_eq!(ceil3(0.000101).1, "0.000101");
        assert_eq!(ceil3(0.0001011).1, "0.000102");
        // A value already of three digits stays itself, however its
        // binary form falls.
        for x in [0.745, 1.49, 0.495, 68.7, 1100.0, 0.0003] {
            assert_eq!(floor3(x).0, x, "{x}");
            assert_eq!(ceil3(x).0, x, "{x}");
            assert_eq!(floor3(x).0, floor3(x).1.parse::<f64>().unwrap());
        }
        assert_eq!(floor3(0.0).0, 0.0);
        assert_eq!(float(3.0), "3.0");
        assert_eq!(float(0.25), "0.25");
    }

    fn in_time(rate: f64, seconds: f64, segment: usize) -> Analysis {
        Analysis {
            channel: "vib".into(),
            axis: "t_s".into(),
            window: [0.0, seconds],
            spacing: 1.0 / rate,
            spectrum: crate::profile::SpectrumKind::LogWelch,
            welch_segment: Some(segment),
            ..Analysis::default()
        }
    }

    #[test]
    fn bands_fit_the_spectrum_as_many_as_it_holds() {
        // 256-point segments at 2.2 kHz: 32 bands from 8 bins up.
        let b = fitting_bands(&in_time(2200.0, 5.99, 256)).unwrap();
        assert_eq!((b.count, b.from, b.to), (32, 68.7, 1100.0));
        // 32-point segments at 100 Hz: 8 bands from 2 bins up.
        let b = fitting_bands(&in_time(100.0, 1.98, 32)).unwrap();
        assert_eq!((b.count, b.from, b.to), (8, 6.25, 50.0));
        // 8 bins: no band of 8 holds one each.
        assert_eq!(fitting_bands(&in_time(100.0, 1.98, 16)), None);
    }
}
