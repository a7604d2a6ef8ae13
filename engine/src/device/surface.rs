//! Texture height profiles and what a spherical probe traces over them.
//!
//! A surface is a height h(x) along the stroke (crests at 0, grooves below).
//! A sphere of radius r cannot follow grooves narrower than itself: its
//! centre rides on the dilated profile H(x) = max over |u| <= r of
//! h(x + u) + sqrt(r² − u²) − r. The dilation is computed once per scan on a
//! fine grid; the physics then looks heights and slopes up by interpolation.

use std::path::{Path, PathBuf};

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::profile::Surface;

/// Grid step of the dilated profile.
const GRID_M: f64 = 0.000_02;

#[derive(Debug, thiserror::Error)]
pub enum SurfaceError {
    #[error("{}: cannot read the surface CSV: {}", path.display(), crate::io::said(source))]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: {reason}")]
    Malformed {
        path: PathBuf,
        line: usize,
        reason: String,
    },
}

/// A raw height function h(x), crest at 0.
enum Raw {
    Flat,
    Trapezoid {
        crest: f64,
        depth: f64,
        trough: f64,
        flank: f64,
    },
    Sine {
        amplitude: f64,
        period: f64,
    },
    Table {
        x: Vec<f64>,
        h: Vec<f64>,
    },
}

impl Raw {
    fn height(&self, u: f64) -> f64 {
        match *self {
            Raw::Flat => 0.0,
            Raw::Trapezoid {
                crest,
                depth,
                trough,
                flank,
            } => {
                let period = crest + trough + 2.0 * flank;
                let u = u.rem_euclid(period);
                if u < crest {
                    0.0
                } else if u < crest + flank {
                    -depth * (u - crest) / flank
                } else if u < crest + flank + trough {
                    -depth
                } else {
                    -depth * (1.0 - (u - crest - flank - trough) / flank)
                }
            }
            Raw::Sine { amplitude, period } => {
                amplitude * ((std::f64::consts::TAU * u / period).cos() - 1.0)
            }
            Raw::Table { ref x, ref h } => interpolate(x, h, u),
        }
    }
}

fn interpolate(x: &[f64], h: &[f64], u: f64) -> f64 {
    if u <= x[0] {
        return h[0];
    }
    let last = x.len() - 1;
    if u >= x[last] {
        return h[last];
    }
    let i = x.partition_point(|&v| v <= u) - 1;
    let f = (u - x[i]) / (x[i + 1] - x[i]);
    h[i] + f * (h[i + 1] - h[i])
}

/// Random micro-roughness: a seeded sum of sinusoids with wavelengths spread
/// around the correlation length, scaled to the requested RMS.
struct Roughness {
    waves: Vec<(f64, f64, f64)>, // amplitude, wavenumber, phase
}

impl Roughness {
    fn new(rms: f64, correlation: f64, rng: &mut ChaCha8Rng) -> Roughness {
        const WAVES: usize = 24;
        if rms <= 0.0 {
            return Roughness { waves: Vec::new() };
        }
        let amplitude = rms * (2.0 / WAVES as f64).sqrt();
        let waves = (0..WAVES)
            .map(|_| {
                // Log-uniform wavelengths from a third to four times the correlation length.
                let lambda =
                    correlation * (rng.random_range((1.0f64 / 3.0).ln()..4.0f64.ln())).exp();
                let phase = rng.random_range(0.0..std::f64::consts::TAU);
                (amplitude, std::f64::consts::TAU / lambda, phase)
            })
            .collect();
        Roughness { waves }
    }
    fn height(&self, x: f64) -> f64 {
        self.waves
            .iter()
            .map(|&(a, k, p)| a * (k * x + p).sin())
            .sum()
    }
}

/// The height the probe's centre rides at, over a range of x.
pub struct ProbeTrace {
    x0: f64,
    heights: Vec<f64>,
    top_y: f64,
}

impl ProbeTrace {
    /// Build the dilated profile of `surface` for a sphere of `radius`, with
    /// the texture's origin at `origin_x` and its crests (as touched by the
    /// sphere's centre) at `top_y`, covering `x_range`.
    pub fn new(
        surface: &Surface,
        radius: f64,
        origin_x: f64,
        top_y: f64,
        x_range: (f64, f64),
        base_dir: &Path,
        rng: &mut ChaCha8Rng,
    ) -> Result<ProbeTrace, SurfaceError> {
        let (raw, roughness) = match surface {
            Surface::Flat {
                roughness_rms_m,
                correlation_length_m,
            } => (
                Raw::Flat,
                Roughness::new(*roughness_rms_m, *correlation_length_m, rng),
            ),
            Surface::Trapezoid {
                crest_m,
                depth_m,
                trough_m,
                flank_m,
                roughness_rms_m,
            } => (
                Raw::Trapezoid {
                    crest: *crest_m,
                    depth: *depth_m,
                    trough: *trough_m,
                    // A zero-width flank is a vertical wall; keep it a grid step wide.
                    flank: flank_m.max(GRID_M),
                },
                Roughness::new(*roughness_rms_m, 0.001, rng),
            ),
            Surface::Sine {
                amplitude_m,
                period_m,
            } => (
                Raw::Sine {
                    amplitude: *amplitude_m,
                    period: *period_m,
                },
                Roughness { waves: Vec::new() },
            ),
            Surface::Csv { path } => {
                let full = if path.is_absolute() {
                    path.clone()
                } else {
                    base_dir.join(path)
                };
                let (x, h) = read_surface_csv(&full)?;
                (Raw::Table { x, h }, Roughness { waves: Vec::new() })
            }
        };
        let lo = x_range.0 - radius - GRID_M;
        let hi = x_range.1 + radius + GRID_M;
        let n = ((hi - lo) / GRID_M).ceil() as usize + 1;
        let raw_h: Vec<f64> = (0..n)
            .map(|i| {
                let x = lo + i as f64 * GRID_M;
                raw.height(x - origin_x) + roughness.height(x)
            })
            .collect();
        let reach = (radius / GRID_M).floor() as usize;
        let cap: Vec<f64> = (0..=reach)
            .map(|j| {
                let u = j as f64 * GRID_M;
                (radius * radius - u * u).max(0.0).sqrt() - radius
            })
            .collect();
        let mut heights = vec![f64::NEG_INFINITY; n];
        for (i, out) in heights.iter_mut().enumerate() {
            let mut best = raw_h[i];
            for (j, c) in cap.iter().enumerate().skip(1) {
                if i >= j {
                    best = best.max(raw_h[i - j] + c);
                }
                if i + j < n {
                    best = best.max(raw_h[i + j] + c);
                }
            }
            *out = best;
        }
        // Crests at top_y: shift so the highest point the centre rides is 0.
        let max = heights.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        for h in &mut heights {
            *h -= max;
        }
        Ok(ProbeTrace {
            x0: lo,
            heights,
            top_y,
        })
    }

    /// Height of the sphere's centre when touching at `x`, and the slope dH/dx.
    pub fn at(&self, x: f64) -> (f64, f64) {
        let f = (x - self.x0) / GRID_M;
        let last = self.heights.len() - 1;
        if f <= 0.0 {
            return (self.top_y + self.heights[0], 0.0);
        }
        if f >= last as f64 {
            return (self.top_y + self.heights[last], 0.0);
        }
        let i = f as usize;
        let frac = f - i as f64;
        let (a, b) = (self.heights[i], self.heights[i + 1]);
        (self.top_y + a + frac * (b - a), (b - a) / GRID_M)
    }
}

/// Read `x_m,height_m` rows (a header line first; `#` comments allowed).
pub fn read_surface_csv(path: &Path) -> Result<(Vec<f64>, Vec<f64>), SurfaceError> {
    let text = crate::io::read_input_to_string(path).map_err(|source| SurfaceError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |line: usize, reason: String| SurfaceError::Malformed {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut header_seen = false;
    let mut xs = Vec::new();
    let mut hs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if !header_seen {
            let cols: Vec<&str> = line.split(',').map(str::trim).collect();
            if cols != ["x_m", "height_m"] {
                return Err(bad(
                    ln,
                    format!("the header must be `x_m,height_m`, got `{line}`"),
                ));
            }
            header_seen = true;
            continue;
        }
        let mut parts = line.split(',');
        let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(bad(ln, "a row needs two values: x_m,height_m".into()));
        };
        let parse = |s: &str| -> Result<f64, SurfaceError> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(ln, format!("`{}` is not a number", s.trim())))
        };
        let x = parse(a)?;
        let h = parse(b)?;
        if let Some(&prev) = xs.last()
            && x <= prev
        {
            return Err(bad(ln, format!("x_m must increase: {x} after {prev}")));
        }
        xs.push(x);
        hs.push(h);
    }
    if xs.len() < 2 {
        return Err(bad(
            text.lines().count().max(1),
            "needs at least two rows".into(),
        ));
    }
    Ok((xs, hs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn trace(surface: Surface, radius: f64) -> ProbeTrace {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        ProbeTrace::new(
            &surface,
            radius,
            0.0,
            0.0,
            (0.0, 0.03),
            Path::new("."),
            &mut rng,
        )
        .unwrap()
    }

    #[test]
    fn a_sphere_cannot_reach_the_bottom_of_a_narrow_groove() {
        // A 0.4 mm wide, 0.9 mm deep groove: a 2 mm sphere stops short of the bottom.
        let groove = || Surface::Trapezoid {
            crest_m: 0.002,
            depth_m: 0.0009,
            trough_m: 0.0002,
            flank_m: 0.0001,
            roughness_rms_m: 0.0,
        };
        let t = trace(groove(), 0.001);
        let mid_trough = 0.002 + 0.0001 + 0.0001 + 0.0024;
        let (h, _) = t.at(mid_trough);
        // The sphere spans the 0.4 mm opening: sqrt(1 - 0.2^2) - 1 = -0.0202 mm deep.
        assert!((h + 0.0000202).abs() < 0.000005, "dilated groove depth {h}");
        // A point probe would reach the full depth.
        let p = trace(groove(), GRID_M / 2.0);
        assert!((p.at(mid_trough).0 + 0.0009).abs() < 1e-5);
    }

    #[test]
    fn wide_grooves_are_traced_to_the_bottom() {
        let s = Surface::Trapezoid {
            crest_m: 0.002,
            depth_m: 0.001,
            trough_m: 0.006,
            flank_m: 0.001,
            roughness_rms_m: 0.0,
        };
        let t = trace(s, 0.001);
        let (h, slope) = t.at(0.002 + 0.001 + 0.003 + 0.01);
        assert!((h + 0.001).abs() < 1e-6, "{h}");
        assert!(slope.abs() < 1e-6);
    }

    #[test]
    fn sine_and_flat_surfaces() {
        let t = trace(
            Surface::Sine {
                amplitude_m: 0.0001,
                period_m: 0.01,
            },
            0.0005,
        );
        assert!(t.at(0.01).0.abs() < 1e-6);
        assert!((t.at(0.015).0 + 0.0002).abs() < 1e-5);
        let f = trace(
            Surface::Flat {
                roughness_rms_m: 0.0,
                correlation_length_m: 0.001,
            },
            0.001,
        );
        assert_eq!(f.at(0.012), (0.0, 0.0));
    }

    #[test]
    fn roughness_has_the_requested_rms() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let r = Roughness::new(0.00002, 0.001, &mut rng);
        let n = 20000;
        let ms: f64 = (0..n)
            .map(|i| r.height(i as f64 * 1e-5).powi(2))
            .sum::<f64>()
            / n as f64;
        let rms = ms.sqrt();
        assert!((rms - 0.00002).abs() < 0.000006, "rms {rms}");
    }

    #[test]
    fn csv_surfaces_are_read_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("s.csv");
        std::fs::write(&good, "x_m,height_m\n0,0\n0.01,-0.001\n0.02,0\n").unwrap();
        let (x, h) = read_surface_csv(&good).unwrap();
        assert_eq!(x.len(), 3);
        assert_eq!(interpolate(&x, &h, 0.005), -0.0005);
        let bad = dir.path().join("b.csv");
        std::fs::write(&bad, "x_m,height_m\n0,0\n0.01,zz\n").unwrap();
        let e = read_surface_csv(&bad).unwrap_err().to_string();
        assert!(
            e.contains("b.csv:3") && e.contains("`zz` is not a number"),
            "{e}"
        );
    }
}
