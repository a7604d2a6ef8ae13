//! Resampling onto the window's even grid: bin by nearest grid point, take
//! each bin's centroid, interpolate linearly between centroids (the method is
//! described in the parent module's documentation). Owns only its buffers;
//! never allocates after construction.
//! Samples on a bin's edge go to the bin above only where rounding would
//! leave bins empty (the parent module's step 1), so where rounding fills
//! every bin the result is what it always was, to the bit.

use super::AnalysisError;

/// Grid points at either end of the window that a scan stopping short may
/// leave empty; they are extrapolated from the nearest two bins.
pub const END_SLACK: usize = 2;

/// How close to a bin's edge, in spacings, a sample counts as on it: far
/// above the rounding of `(a − origin − start) / spacing` (about 2e-8
/// spacings an hour into a recording at 44.1 kHz), far below any offset a
/// profile means.
pub const TIE: f64 = 1e-6;

#[derive(Debug, Clone)]
pub(crate) struct Resampler {
    n: usize,
    start: f64,
    spacing: f64,
    /// Per grid point: sample count, sum of positions (in grid units from
    /// the window's start), sum of signal values.
    count: Vec<u32>,
    sum_u: Vec<f64>,
    sum_v: Vec<f64>,
    /// The non-empty bins' centroids, in grid order (increasing position).
    centroid_u: Vec<f64>,
    centroid_v: Vec<f64>,
    /// The other binning's centroids while the two are compared.
    spare_u: Vec<f64>,
    spare_v: Vec<f64>,
    has_run: bool,
}

impl Resampler {
    pub(crate) fn new(n: usize, start: f64, spacing: f64) -> Self {
        Resampler {
            n,
            start,
            spacing,
            count: vec![0; n],
            sum_u: vec![0.0; n],
            sum_v: vec![0.0; n],
            centroid_u: Vec::with_capacity(n),
            centroid_v: Vec::with_capacity(n),
            spare_u: Vec::with_capacity(n),
            spare_v: Vec::with_capacity(n),
            has_run: false,
        }
    }

    /// Move the grid to start at `start` (a sub-window's), keeping its
    /// points and spacing.
    pub(crate) fn set_start(&mut self, start: f64) {
        self.start = start;
    }

    /// Whether a resampling has succeeded since construction.
    pub(crate) fn has_run(&self) -> bool {
        self.has_run
    }

    /// Resample into `out` (length `n`); `out` is untouched on error.
    pub(crate) fn run(
        &mut self,
        axis_name: &str,
        axis: &[f64],
        signal: &[f64],
        out: &mut [f64],
    ) -> Result<(), AnalysisError> {
        self.run_on(axis_name, axis, signal, out, false, true)
    }

    /// [`Self::run`] for samples the caller has checked: every value finite
    /// and the axis never decreasing. Only the samples near the window are
    /// visited (a binary search finds them), with the same result to the
    /// bit: the samples skipped are the ones `run` passes over, and the
    /// extent of an ordered axis is its first and last sample. Sub-windows
    /// of a long recording cost their own length, not the recording's.
    pub(crate) fn run_in_order(
        &mut self,
        axis_name: &str,
        axis: &[f64],
        signal: &[f64],
        out: &mut [f64],
    ) -> Result<(), AnalysisError> {
        self.run_on(axis_name, axis, signal, out, true, true)
    }

    /// The run; `edges_up` off leaves samples on edges where rounding puts
    /// them even if bins are left empty (for tests to measure the rule).
    fn run_on(
        &mut self,
        axis_name: &str,
        axis: &[f64],
        signal: &[f64],
        out: &mut [f64],
        in_order: bool,
        edges_up: bool,
    ) -> Result<(), AnalysisError> {
        debug_assert_eq!(out.len(), self.n);
        if axis.len() != signal.len() {
            return Err(AnalysisError::LengthMismatch {
                axis: axis.len(),
                signal: signal.len(),
            });
        }
        let (Some(&origin), Some(&last)) = (axis.first(), axis.last()) else {
            return Err(AnalysisError::Empty);
        };
        // Distance along the direction of travel (NaN ends are caught below).
        let direction = if last >= origin { 1.0 } else { -1.0 };
        let grid = Grid {
            origin,
            direction,
            start: self.start,
            inv_spacing: 1.0 / self.spacing,
            half: 0.5,
            upper: self.n as f64 - 0.5,
            n: self.n,
        };
        let mut ends = self.centroids(&grid, axis, signal, in_order)?;
        if edges_up && self.centroid_u.len() < self.n {
            // Bins left empty: try the samples on edges one bin up (see
            // the module documentation), keep whichever fills more.
            let rounded = self.centroid_u.len();
            std::mem::swap(&mut self.centroid_u, &mut self.spare_u);
            std::mem::swap(&mut self.centroid_v, &mut self.spare_v);
            let half = 0.5 + TIE;
            let ties_up = Grid {
                half,
                upper: self.n as f64 - half,
                ..grid
            };
            let tied = self.centroids(&ties_up, axis, signal, in_order)?;
            if self.centroid_u.len() > rounded {
                ends = tied;
            } else {
                std::mem::swap(&mut self.centroid_u, &mut self.spare_u);
                std::mem::swap(&mut self.centroid_v, &mut self.spare_v);
            }
        }
        let (first, last_bin) = ends;
        let first_gap = first != Some(0);
        let last_gap = last_bin != self.n - 1;
        // The extent costs a pass over the samples: only when it decides.
        let (lo, hi) = if in_order {
            (0.0, last - origin)
        } else if first_gap || last_gap {
            extent(axis, origin, direction)
        } else {
            (0.0, 0.0)
        };
        self.check_coverage(axis_name, (lo, hi), first_gap, last_gap)?;
        self.interpolate(out);
        self.has_run = true;
        Ok(())
    }

    /// The bins' centroids on `grid`, in order or not (see
    /// [`Self::run_in_order`]). The first and last bins filled.
    fn centroids(
        &mut self,
        grid: &Grid,
        axis: &[f64],
        signal: &[f64],
        in_order: bool,
    ) -> Result<(Option<usize>, usize), AnalysisError> {
        self.centroid_u.clear();
        self.centroid_v.clear();
        if in_order {
            Ok(self.centroids_in_order(grid, axis, signal))
        } else {
            self.centroids_any_order(grid, axis, signal)
        }
    }

    /// The bins' centroids of samples whose axis never decreases: only the
    /// samples near the window are visited. The first and last bins filled.
    fn centroids_in_order(
        &mut self,
        grid: &Grid,
        axis: &[f64],
        signal: &[f64],
    ) -> (Option<usize>, usize) {
        debug_assert!(axis.windows(2).all(|w| w[0] <= w[1]));
        let (mut first, mut last_bin) = (None, 0);
        // A grid point's bin reaches half a spacing out; one spacing of
        // margin keeps rounding on the safe side (`bin` still decides
        // each sample).
        let lo = grid.origin + self.start - self.spacing;
        let hi = grid.origin + self.start + (self.n as f64 + 0.5) * self.spacing;
        let from = axis.partition_point(|&a| a < lo);
        let to = axis.partition_point(|&a| a <= hi).max(from);
        // In order, each bin's samples are one run: its centroid is
        // pushed when the run ends, with the sums the bin arrays would
        // hold (0 + x is x), so the result is the same to the bit.
        let (mut run_bin, mut run_n, mut run_u, mut run_v) = (usize::MAX, 0u32, 0.0, 0.0);
        let mut push = |bin: usize, n: u32, su: f64, sv: f64| {
            if n == 0 {
                return;
            }
            first.get_or_insert(bin);
            last_bin = bin;
            let (cu, cv) = centroid(n, su, sv);
            self.centroid_u.push(cu);
            self.centroid_v.push(cv);
        };
        for (&a, &v) in axis[from..to].iter().zip(&signal[from..to]) {
            let Some((i, u)) = grid.bin(a) else { continue };
            if i != run_bin {
                push(run_bin, run_n, run_u, run_v);
                (run_bin, run_n, run_u, run_v) = (i, 0, 0.0, 0.0);
            }
            run_n += 1;
            run_u += u;
            run_v += v;
        }
        push(run_bin, run_n, run_u, run_v);
        (first, last_bin)
    }

    /// The bins' centroids of samples in any order (every value checked
    /// finite). The first and last bins filled.
    fn centroids_any_order(
        &mut self,
        grid: &Grid,
        axis: &[f64],
        signal: &[f64],
    ) -> Result<(Option<usize>, usize), AnalysisError> {
        self.count.fill(0);
        self.sum_u.fill(0.0);
        self.sum_v.fill(0.0);
        // Scans arrive mostly in order, so consecutive samples share a
        // bin: summing a run in registers and storing it once avoids a
        // chain of store-to-load round trips through the bin arrays.
        let mut run_bin = 0;
        let (mut run_n, mut run_u, mut run_v) = (0u32, 0.0, 0.0);
        let mut finite = true;
        for (&a, &v) in axis.iter().zip(signal) {
            // One flag for the whole loop keeps it branch-light; the
            // rare failure is located afterwards.
            finite &= a.is_finite() & v.is_finite();
            let Some((i, u)) = grid.bin(a) else { continue };
            if i != run_bin {
                self.count[run_bin] += run_n;
                self.sum_u[run_bin] += run_u;
                self.sum_v[run_bin] += run_v;
                (run_bin, run_n, run_u, run_v) = (i, 0, 0.0, 0.0);
            }
            run_n += 1;
            run_u += u;
            run_v += v;
        }
        self.count[run_bin] += run_n;
        self.sum_u[run_bin] += run_u;
        self.sum_v[run_bin] += run_v;
        if !finite {
            return Err(first_non_finite(axis, signal));
        }
        let (mut first, mut last_bin) = (None, 0);
        for i in 0..self.n {
            let c = self.count[i];
            if c > 0 {
                first.get_or_insert(i);
                last_bin = i;
                let (cu, cv) = centroid(c, self.sum_u[i], self.sum_v[i]);
                self.centroid_u.push(cu);
                self.centroid_v.push(cv);
            }
        }
        Ok((first, last_bin))
    }

    /// Whether the centroids cover the window well enough to interpolate:
    /// the scan reaches both ends (within the slack), few bins are empty,
    /// no empty end bin was passed over, and at least two are filled.
    fn check_coverage(
        &self,
        axis_name: &str,
        (lo, hi): (f64, f64),
        first_gap: bool,
        last_gap: bool,
    ) -> Result<(), AnalysisError> {
        let filled = self.centroid_u.len();
        let end = self.start + (self.n - 1) as f64 * self.spacing;
        let half = 0.5 * self.spacing;
        let slack = END_SLACK as f64 * self.spacing;
        // The scan stops short of the window by more than the slack.
        if (first_gap && lo > self.start + slack) || (last_gap && hi < end - slack) {
            return Err(AnalysisError::WindowNotCovered {
                axis: axis_name.to_string(),
                covered: (lo, hi),
                window: [self.start, end],
            });
        }
        let empty = self.n - filled;
        if empty * 4 > self.n {
            return Err(AnalysisError::TooSparse {
                axis: axis_name.to_string(),
                empty,
                points: self.n,
                spacing: self.spacing,
            });
        }
        // An empty end bin the scan passed over: nothing to anchor the end.
        let (first_gap, last_gap) = (
            first_gap && lo < self.start - half,
            last_gap && hi > end + half,
        );
        if first_gap || last_gap {
            return Err(AnalysisError::EdgeGap {
                axis: axis_name.to_string(),
                edge: if first_gap { "start" } else { "end" },
                at: if first_gap { self.start } else { end },
                spacing: self.spacing,
            });
        }
        if filled < 2 {
            return Err(AnalysisError::TooFewPoints {
                axis: axis_name.to_string(),
                filled,
            });
        }
        Ok(())
    }

    /// Walk the grid and the centroids together; segment m runs from
    /// centroid m to m + 1, and the first and last segments extend
    /// outwards to extrapolate.
    fn interpolate(&self, out: &mut [f64]) {
        let (cu, cv) = (&self.centroid_u, &self.centroid_v);
        let filled = cu.len();
        let mut m = 0;
        for (i, slot) in out.iter_mut().enumerate() {
            let g = i as f64;
            while m + 2 < filled && cu[m + 1] < g {
                m += 1;
            }
            let du = cu[m + 1] - cu[m];
            *slot = if du > 0.0 {
                cv[m] + (g - cu[m]) * (cv[m + 1] - cv[m]) / du
            } else {
                0.5 * (cv[m] + cv[m + 1])
            };
        }
    }
}

/// The resampling grid as one run sees it.
struct Grid {
    origin: f64,
    direction: f64,
    start: f64,
    inv_spacing: f64,
    /// Where a bin starts below its grid point: ½, or ½ + [`TIE`] for
    /// samples on an edge to go up.
    half: f64,
    /// Exclusive upper end of a grid coordinate, n − `half`.
    upper: f64,
    n: usize,
}

impl Grid {
    /// Nearest grid point: bin i holds u in [i − `half`, i + 1 − `half`).
    /// The cast truncates, which is the floor here since u + `half` ≥ 0;
    /// `upper` is exclusive, but rounding in `u + half` can still reach n.
    #[inline]
    fn bin(&self, a: f64) -> Option<(usize, f64)> {
        let u = (self.direction * (a - self.origin) - self.start) * self.inv_spacing;
        let i = (u + self.half) as usize;
        ((-self.half..self.upper).contains(&u) && i < self.n).then_some((i, u))
    }
}

/// A bin's centroid from its count and sums; one sample is its own (x / 1
/// is x: no division).
fn centroid(count: u32, sum_u: f64, sum_v: f64) -> (f64, f64) {
    if count == 1 {
        (sum_u, sum_v)
    } else {
        let c = f64::from(count);
        (sum_u / c, sum_v / c)
    }
}

/// The least and greatest distance travelled from the first sample.
fn extent(axis: &[f64], origin: f64, direction: f64) -> (f64, f64) {
    axis.iter()
        .map(|&a| direction * (a - origin))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        })
}

/// The first sample that is not a finite number (one is known to exist).
fn first_non_finite(axis: &[f64], signal: &[f64]) -> AnalysisError {
    for (index, (&a, &v)) in axis.iter().zip(signal).enumerate() {
        if !a.is_finite() {
            return AnalysisError::NonFinite {
                what: "axis",
                index,
                value: a,
            };
        }
        if !v.is_finite() {
            return AnalysisError::NonFinite {
                what: "signal",
                index,
                value: v,
            };
        }
    }
    unreachable!("called only when a sample is not finite")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid half a sample period off evenly spaced samples puts every
    /// sample on a bin's edge, and rounding alone leaves bins empty: each
    /// bin still gets one sample, and a straight line resamples exactly, in
    /// order or not. Times as a CSV's decimals parse (k / rate, correctly
    /// rounded); starts as a profile writes them and as sub-windows reach
    /// them (the window's start plus a multiple of the hop).
    #[test]
    fn a_grid_half_a_period_off_even_samples_fills_every_bin() {
        let n = 100;
        for rate in [100.0, 2200.0, 44_100.0] {
            let t: Vec<f64> = (0..3 * n).map(|k| k as f64 / rate).collect();
            let y: Vec<f64> = t.iter().map(|t| 3.0 * t - 1.0).collect();
            let hop = 49.5 / rate;
            let starts = (0..n).map(|k| (k as f64 + 0.5) / rate);
            for start in starts.chain((1..4).map(|j| j as f64 * hop)) {
                for in_order in [false, true] {
                    let mut r = Resampler::new(n, start, 1.0 / rate);
                    let mut out = vec![0.0; n];
                    let at = format!("{rate} Hz, start {start}, in order {in_order}");
                    r.run_on("t_s", &t, &y, &mut out, in_order, true)
                        .unwrap_or_else(|e| panic!("{at}: {e}"));
                    assert_eq!(r.centroid_u.len(), n, "{at}: a bin is empty");
                    for (i, v) in out.iter().enumerate() {
                        let want = 3.0 * (start + i as f64 / rate) - 1.0;
                        assert!((v - want).abs() < 1e-9, "{at}, point {i}: {v} vs {want}");
                    }
                }
            }
        }
    }

    /// The rule changes no resampled value of the thesis recordings, to
    /// the bit, and accepts or refuses the same windows: their positions on
    /// a µm grid sit on the 0.3 mm grid's edges, but rounding fills every
    /// bin there. Over the thesis window, the sub-windows the CLI tests
    /// use, the whole leg, and the leg along time at 1 and 2 ms.
    #[test]
    fn samples_on_edges_of_the_thesis_recordings_stay_where_rounding_puts_them() {
        use crate::profile::{Analysis, LoadedProfile, Windows};
        let thesis = LoadedProfile::thesis().profile.analysis;
        let leg = |axis: &str, window_end: f64, spacing: f64| Analysis {
            axis: axis.into(),
            window: [0.0, window_end],
            spacing,
            ..thesis.clone()
        };
        let settings = [
            thesis.clone(),
            Analysis {
                windows: Some(Windows {
                    length: 0.0147,
                    hop: 0.0075,
                }),
                ..thesis.clone()
            },
            leg("x_m", 0.0897, 0.0003),
            leg("t_s", 9.27, 0.001),
            leg("t_s", 9.27, 0.002),
        ];
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recordings/thesis-sim");
        let files = crate::recording::collect_files(&[dir]).unwrap();
        assert_eq!(files.len(), 120);
        let (mut windows, mut refused) = (0, 0);
        for f in &files {
            let rec = crate::recording::read(f).unwrap();
            for a in &settings {
                let axis = rec.column(&a.axis).unwrap();
                let y = rec.column("y_m").unwrap();
                let n = a.points();
                for [start, _] in a.sub_windows() {
                    let mut got = Vec::new();
                    for edges_up in [true, false] {
                        let mut r = Resampler::new(n, start, a.spacing);
                        let mut out = vec![0.0; n];
                        let done = r.run_on(&a.axis, axis, y, &mut out, false, edges_up);
                        let bits: Vec<u64> = out.iter().map(|v| v.to_bits()).collect();
                        got.push((done, bits));
                    }
                    let at = format!("{} at {start} along {}", f.display(), a.axis);
                    assert_eq!(got[0], got[1], "{at}");
                    windows += 1;
                    refused += usize::from(got[0].0.is_err());
                }
            }
        }
        assert_eq!((windows, refused), (120 * 7, 0));
    }
}
