//! The distances the neighbour search ranks by, one pair at a time
//! ([`rank_value`]) and a table of many pairs at once ([`rank_table`]),
//! the same numbers to the bit.
//!
//! A pair's sum runs in four lanes (feature `j` into lane `j % 4`, each
//! lane in feature order), the lanes added as `(l0 + l1) + (l2 + l3)`,
//! then the features past the last multiple of four. The table keeps each
//! pair's four lanes through passes over [`CHUNK`] features of a few rows
//! at a time, so every lane adds the same terms in the same order while
//! the rows it reads stay in cache and four pairs' sums run side by side.

use crate::profile::Metric;

/// Features per pass of the table: a multiple of four, so a chunk ends
/// where a lane's turn does.
const CHUNK: usize = 256;

/// Rows of each side of a tile: their chunks (2 KiB each) stay in cache
/// while every pair of the tile is summed over them.
const TILE: usize = 16;

/// The value the neighbour search ranks by (squared for Euclidean), and how
/// it turns into the reported distance.
pub(crate) fn rank_value(
    metric: Metric,
    q: &[f64],
    q_norm: f64,
    row: &[f64],
    row_norm: f64,
) -> f64 {
    match metric {
        Metric::Euclidean => squared_distance(q, row),
        Metric::Manhattan => manhattan(q, row),
        Metric::Cosine => cosine(dot(q, row), q_norm, row_norm),
    }
}

pub(crate) fn to_distance(metric: Metric, r: f64) -> f64 {
    if metric == Metric::Euclidean {
        r.sqrt()
    } else {
        r
    }
}

fn cosine(dot: f64, q_norm: f64, row_norm: f64) -> f64 {
    if q_norm == 0.0 || row_norm == 0.0 {
        1.0
    } else {
        (1.0 - dot / (q_norm * row_norm)).max(0.0)
    }
}

/// One term of a metric's sum.
trait Term {
    fn term(a: f64, b: f64) -> f64;
}
struct Squared;
struct Absolute;
struct Product;
impl Term for Squared {
    #[inline(always)]
    fn term(a: f64, b: f64) -> f64 {
        let d = a - b;
        d * d
    }
}
impl Term for Absolute {
    #[inline(always)]
    fn term(a: f64, b: f64) -> f64 {
        (a - b).abs()
    }
}
impl Term for Product {
    #[inline(always)]
    fn term(a: f64, b: f64) -> f64 {
        a * b
    }
}

/// Adds the terms of `a` and `b` (lengths a multiple of four) into lanes.
#[inline(always)]
fn lanes<T: Term>(a: &[f64], b: &[f64], acc: &mut [f64; 4]) {
    for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for l in 0..4 {
            acc[l] += T::term(x[l], y[l]);
        }
    }
}

/// The lanes added, then the terms of the features past them in order.
#[inline(always)]
fn finish<T: Term>(acc: &[f64; 4], a_tail: &[f64], b_tail: &[f64]) -> f64 {
    let mut tail = -0.0;
    for (x, y) in a_tail.iter().zip(b_tail) {
        tail += T::term(*x, *y);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

#[inline(always)]
fn sum<T: Term>(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let full = a.len().min(b.len()) / 4 * 4;
    lanes::<T>(&a[..full], &b[..full], &mut acc);
    finish::<T>(&acc, &a[full..], &b[full..])
}

/// Squared Euclidean distance.
pub(crate) fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    sum::<Squared>(a, b)
}

pub(crate) fn manhattan(a: &[f64], b: &[f64]) -> f64 {
    sum::<Absolute>(a, b)
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    sum::<Product>(a, b)
}

/// `out[i * b.len() + j]` = [`rank_value`] of `a[i]` and `b[j]` (all rows
/// of one length; norms as [`rank_value`] takes them, read for cosine
/// only), the same to the bit, tile by tile.
pub(crate) fn rank_table(
    metric: Metric,
    a: &[&[f64]],
    a_norms: &[f64],
    b: &[&[f64]],
    b_norms: &[f64],
    out: &mut [f64],
) {
    assert_eq!(out.len(), a.len() * b.len());
    match metric {
        Metric::Euclidean => table::<Squared>(a, b, out),
        Metric::Manhattan => table::<Absolute>(a, b, out),
        Metric::Cosine => {
            table::<Product>(a, b, out);
            for (i, row) in out.chunks_exact_mut(b.len().max(1)).enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = cosine(*v, a_norms[i], b_norms[j]);
                }
            }
        }
    }
}

/// The sums of every pair into `out`, on the processor's widest vectors.
fn table<T: Term>(a: &[&[f64]], b: &[&[f64]], out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, just checked.
            unsafe { table_avx2::<T>(a, b, out) };
            return;
        }
    }
    table_portable::<T>(a, b, out);
}

/// The same operations in the same order, with 256-bit vectors.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn table_avx2<T: Term>(a: &[&[f64]], b: &[&[f64]], out: &mut [f64]) {
    table_portable::<T>(a, b, out);
}

#[inline(always)]
fn table_portable<T: Term>(a: &[&[f64]], b: &[&[f64]], out: &mut [f64]) {
    let d = a.first().or(b.first()).map_or(0, |r| r.len());
    assert!(a.iter().chain(b).all(|r| r.len() == d));
    let full = d / 4 * 4;
    let nb = b.len();
    let mut acc = vec![[0.0f64; 4]; TILE * TILE];
    for (ti, a_tile) in a.chunks(TILE).enumerate() {
        for (tj, b_tile) in b.chunks(TILE).enumerate() {
            let acc = &mut acc[..a_tile.len() * b_tile.len()];
            acc.iter_mut().for_each(|l| *l = [0.0; 4]);
            let mut start = 0;
            while start < full {
                let end = (start + CHUNK).min(full);
                for (i, x) in a_tile.iter().enumerate() {
                    let x = &x[start..end];
                    let row = &mut acc[i * b_tile.len()..(i + 1) * b_tile.len()];
                    let mut quads = b_tile.chunks_exact(4);
                    let mut at = 0;
                    for q in quads.by_ref() {
                        let [s0, s1, s2, s3] = &mut row[at..at + 4] else {
                            unreachable!()
                        };
                        lanes4::<T>(
                            x,
                            [
                                &q[0][start..end],
                                &q[1][start..end],
                                &q[2][start..end],
                                &q[3][start..end],
                            ],
                            [s0, s1, s2, s3],
                        );
                        at += 4;
                    }
                    for (y, s) in quads.remainder().iter().zip(&mut row[at..]) {
                        lanes::<T>(x, &y[start..end], s);
                    }
                }
                start = end;
            }
            for (i, x) in a_tile.iter().enumerate() {
                for (j, y) in b_tile.iter().enumerate() {
                    out[(ti * TILE + i) * nb + tj * TILE + j] =
                        finish::<T>(&acc[i * b_tile.len() + j], &x[full..], &y[full..]);
                }
            }
        }
    }
}

/// [`lanes`] of one row against four: four pairs' sums side by side.
#[inline(always)]
fn lanes4<T: Term>(x: &[f64], ys: [&[f64]; 4], acc: [&mut [f64; 4]; 4]) {
    let [a0, a1, a2, a3] = acc;
    let (mut s0, mut s1, mut s2, mut s3) = (*a0, *a1, *a2, *a3);
    let n = x.len() / 4;
    for c in 0..n {
        let xs = &x[4 * c..4 * c + 4];
        let (y0, y1, y2, y3) = (
            &ys[0][4 * c..4 * c + 4],
            &ys[1][4 * c..4 * c + 4],
            &ys[2][4 * c..4 * c + 4],
            &ys[3][4 * c..4 * c + 4],
        );
        for l in 0..4 {
            s0[l] += T::term(xs[l], y0[l]);
            s1[l] += T::term(xs[l], y1[l]);
            s2[l] += T::term(xs[l], y2[l]);
            s3[l] += T::term(xs[l], y3[l]);
        }
    }
    (*a0, *a1, *a2, *a3) = (s0, s1, s2, s3);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every metric, lengths around the lanes and the chunk, tiles full
    /// and partial, zero rows and norms: the table is `rank_value` to the
    /// bit.
    #[test]
    fn the_table_is_rank_value_to_the_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for d in [0, 1, 3, 4, 5, 255, 256, 257, 513, 1030] {
            for (na, nb) in [(1, 1), (3, 5), (17, 21), (16, 4)] {
                let row = |rng: &mut ChaCha8Rng, i: usize| -> Vec<f64> {
                    let scale = 10f64.powi(rng.random_range(-3..4));
                    (0..d)
                        .map(|_| {
                            if i % 7 == 3 {
                                0.0
                            } else {
                                scale * rng.random_range(-1.0..1.0)
                            }
                        })
                        .collect()
                };
                let a: Vec<Vec<f64>> = (0..na).map(|i| row(&mut rng, i)).collect();
                let b: Vec<Vec<f64>> = (0..nb).map(|i| row(&mut rng, i + 1)).collect();
                let a: Vec<&[f64]> = a.iter().map(Vec::as_slice).collect();
                let b: Vec<&[f64]> = b.iter().map(Vec::as_slice).collect();
                let an: Vec<f64> = a.iter().map(|r| dot(r, r).sqrt()).collect();
                let bn: Vec<f64> = b.iter().map(|r| dot(r, r).sqrt()).collect();
                for metric in [Metric::Euclidean, Metric::Manhattan, Metric::Cosine] {
                    let mut out = vec![f64::NAN; na * nb];
                    rank_table(metric, &a, &an, &b, &bn, &mut out);
                    for i in 0..na {
                        for j in 0..nb {
                            let want = rank_value(metric, a[i], an[i], b[j], bn[j]);
                            assert_eq!(
                                out[i * nb + j].to_bits(),
                                want.to_bits(),
                                "{metric:?} d {d} {na}x{nb} ({i}, {j})"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The sums are the plain ones, as a reader would write them, to
    /// rounding.
    #[test]
    fn the_sums_are_the_metrics() {
        let a = [1.0, -2.0, 3.0, 0.5, 7.0];
        let b = [0.0, 2.0, 1.0, 0.5, -1.0];
        assert_eq!(squared_distance(&a, &b), 1.0 + 16.0 + 4.0 + 0.0 + 64.0);
        assert_eq!(manhattan(&a, &b), 1.0 + 4.0 + 2.0 + 0.0 + 8.0);
        assert_eq!(dot(&a, &b), -4.0 + 3.0 + 0.25 - 7.0);
        assert_eq!(rank_value(Metric::Cosine, &a, 0.0, &b, 1.0), 1.0);
    }
}
