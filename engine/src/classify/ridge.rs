//! The ridge classifier, as scikit-learn's `RidgeClassifierCV` makes it:
//! every feature standardised with the training examples' mean and
//! standard deviation; one column of targets per class, +1 for its
//! examples and −1 for the others; a least-squares fit with an intercept
//! (not penalised) and the penalty `α‖w‖²`, `α` chosen among [`ALPHAS`]
//! (`10^-3 … 10^3`, ten on a log scale) by the smallest mean squared
//! leave-one-out error over all the columns (the first, so the smallest α,
//! on a tie); a query goes to the class of the largest score.
//!
//! The leave-one-out errors come from one eigendecomposition, not n fits:
//! with `X` the centred training matrix and `H` the hat matrix
//! (`ŷ = H y`), the error of example `i` left out is `(y_i − ŷ_i) / (1 −
//! H_ii)`. When there are more features than examples (the kernels' ten
//! thousand against a few hundred windows) the `n × n` Gram matrix `XXᵀ =
//! QΛQᵀ` gives `H = 11ᵀ/n + Q Λ(Λ+α)⁻¹ Qᵀ`; otherwise the `p × p`
//! `XᵀX = VΛVᵀ` gives `H = 11ᵀ/n + R(Λ+α)⁻¹Rᵀ` with `R = XV`. Either way
//! every α costs only a pass over the decomposition.
//!
//! Fitted on the examples it is handed: the caller (the model) hands it
//! training examples only. Pure Rust (faer); never prints.

use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

use super::Scaling;

/// The penalties tried: `logspace(-3, 3, 10)`.
pub fn alphas() -> [f64; 10] {
    std::array::from_fn(|i| 10f64.powf(-3.0 + 6.0 * i as f64 / 9.0))
}

/// A fitted ridge classifier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RidgeFit {
    /// The penalty chosen.
    pub alpha: f64,
    /// Each penalty tried with its mean squared leave-one-out error.
    pub loo: Vec<(f64, f64)>,
    /// The standardisation fitted on the training examples.
    pub scaling: Scaling,
    /// One row of weights per class (on the standardised features).
    pub weights: Vec<Vec<f64>>,
    pub intercepts: Vec<f64>,
}

/// The training examples as a standardised matrix and centred targets.
struct Problem {
    x: Mat<f64>,
    /// `n × classes`, each column less its mean.
    y: Mat<f64>,
    y_mean: Vec<f64>,
}

fn problem(rows: &[&[f64]], classes: &[usize], n_classes: usize, scaling: &Scaling) -> Problem {
    let n = rows.len();
    let p = scaling.mean.len();
    let mut scaled = vec![0.0; p];
    let mut x = Mat::<f64>::zeros(n, p);
    for (i, r) in rows.iter().enumerate() {
        scaling.apply(r, &mut scaled);
        for (j, v) in scaled.iter().enumerate() {
            x[(i, j)] = *v;
        }
    }
    // Standardised, so already centred; centred again against rounding.
    for j in 0..p {
        let m = (0..n).map(|i| x[(i, j)]).sum::<f64>() / n as f64;
        for i in 0..n {
            x[(i, j)] -= m;
        }
    }
    let mut y = Mat::<f64>::from_fn(
        n,
        n_classes,
        |i, c| if classes[i] == c { 1.0 } else { -1.0 },
    );
    let mut y_mean = vec![0.0; n_classes];
    for (c, mean) in y_mean.iter_mut().enumerate() {
        *mean = (0..n).map(|i| y[(i, c)]).sum::<f64>() / n as f64;
        for i in 0..n {
            y[(i, c)] -= *mean;
        }
    }
    Problem { x, y, y_mean }
}

/// The decomposition every α reuses: `basis` (n × r) and `values` (r)
/// such that `H = 11ᵀ/n + basis (Λ+α)⁻¹-weighted basisᵀ`, and how the
/// weights come back from it.
struct Decomposition {
    /// `Q` (Gram) or `R = XV` (covariance).
    basis: Mat<f64>,
    values: Vec<f64>,
    /// `basisᵀ y`.
    projected: Mat<f64>,
    /// Whether `basis` is `Q` (then `H`'s part is `Q Λ(Λ+α)⁻¹ Qᵀ`) or `R`
    /// (then `R (Λ+α)⁻¹ Rᵀ`).
    gram: bool,
    /// `V` (covariance only).
    v: Option<Mat<f64>>,
}

fn decompose(pr: &Problem) -> Result<Decomposition, String> {
    let (n, p) = (pr.x.nrows(), pr.x.ncols());
    let gram = p > n;
    let (basis, values, v) = if gram {
        let k = &pr.x * pr.x.transpose();
        let e = k
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| format!("the ridge's eigendecomposition failed: {e:?}"))?;
        let values = (0..n).map(|i| e.S()[i].max(0.0)).collect();
        (e.U().to_owned(), values, None)
    } else {
        let c = pr.x.transpose() * &pr.x;
        let e = c
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| format!("the ridge's eigendecomposition failed: {e:?}"))?;
        let values = (0..p).map(|i| e.S()[i].max(0.0)).collect();
        let v = e.U().to_owned();
        (&pr.x * &v, values, Some(v))
    };
    let projected = basis.transpose() * &pr.y;
    Ok(Decomposition {
        basis,
        values,
        projected,
        gram,
        v,
    })
}

impl Decomposition {
    /// The factor on component `j` in `H`: `λ/(λ+α)` on `Q`, `1/(λ+α)` on `R`.
    fn shrink(&self, j: usize, alpha: f64) -> f64 {
        let l = self.values[j];
        if self.gram {
            l / (l + alpha)
        } else {
            1.0 / (l + alpha)
        }
    }

    /// The mean squared leave-one-out error under `alpha`, and its
    /// residuals (n × classes).
    fn loo(&self, y: &Mat<f64>, alpha: f64) -> (f64, Mat<f64>) {
        let (n, r, k) = (self.basis.nrows(), self.basis.ncols(), y.ncols());
        let shrink: Vec<f64> = (0..r).map(|j| self.shrink(j, alpha)).collect();
        let mut residuals = Mat::<f64>::zeros(n, k);
        let mut total = 0.0;
        for i in 0..n {
            let mut leverage = 1.0 / n as f64;
            for (j, s) in shrink.iter().enumerate() {
                let b = self.basis[(i, j)];
                leverage += b * b * s;
            }
            for c in 0..k {
                let mut fitted = 0.0;
                for (j, s) in shrink.iter().enumerate() {
                    fitted += self.basis[(i, j)] * s * self.projected[(j, c)];
                }
                let e = (y[(i, c)] - fitted) / (1.0 - leverage);
                residuals[(i, c)] = e;
                total += e * e;
            }
        }
        (total / (n * k) as f64, residuals)
    }

    /// The weights (p × classes) under `alpha`.
    fn weights(&self, x: &Mat<f64>, alpha: f64) -> Mat<f64> {
        let (r, k) = (self.basis.ncols(), self.projected.ncols());
        // Coefficients on the basis: (Λ+α)⁻¹ basisᵀ y.
        let coef = Mat::<f64>::from_fn(r, k, |j, c| {
            self.projected[(j, c)] / (self.values[j] + alpha)
        });
        match &self.v {
            // w = Xᵀ Q (Λ+α)⁻¹ Qᵀ y.
            None => x.transpose() * (&self.basis * &coef),
            // w = V (Λ+α)⁻¹ Rᵀ y.
            Some(v) => v * &coef,
        }
    }
}

impl RidgeFit {
    /// Fits on `rows` (each the same length, finite) of classes `classes`
    /// (indices below `n_classes`, at least two of them present).
    pub fn fit(rows: &[&[f64]], classes: &[usize], n_classes: usize) -> Result<RidgeFit, String> {
        if rows.len() < 2 || rows.len() != classes.len() {
            return Err("the ridge needs at least two training examples".into());
        }
        let scaling = Scaling::fit(rows);
        let pr = problem(rows, classes, n_classes, &scaling);
        let dec = decompose(&pr)?;
        let mut loo = Vec::new();
        let mut best: Option<(f64, f64)> = None;
        for alpha in alphas() {
            let (error, _) = dec.loo(&pr.y, alpha);
            loo.push((alpha, error));
            if best.is_none_or(|(_, e)| error < e) {
                best = Some((alpha, error));
            }
        }
        let Some((alpha, _)) = best.filter(|(_, e)| e.is_finite()) else {
            return Err("the ridge's leave-one-out errors are not finite numbers".into());
        };
        let w = dec.weights(&pr.x, alpha);
        let p = pr.x.ncols();
        let weights = (0..n_classes)
            .map(|c| (0..p).map(|j| w[(j, c)]).collect())
            .collect();
        Ok(RidgeFit {
            alpha,
            loo,
            scaling,
            weights,
            intercepts: pr.y_mean,
        })
    }

    /// Each class's score for `x`, with `scaled` a buffer of its length.
    pub fn scores(&self, x: &[f64], scaled: &mut [f64]) -> Vec<f64> {
        self.scaling.apply(x, scaled);
        super::linear::scores(&self.weights, &self.intercepts, scaled)
    }

    /// Checks a fit read from a file against `features` and `classes`.
    pub fn check(&self, features: usize, classes: usize) -> Result<(), String> {
        use super::linear::{finite, weights_fit};
        if !weights_fit(&self.weights, &self.intercepts, features, classes) {
            return Err(format!(
                "its ridge must have {classes} rows of {features} finite weights and {classes} intercepts"
            ));
        }
        if self.scaling.mean.len() != features
            || self.scaling.scale.len() != features
            || !finite(&self.scaling.mean)
            || self
                .scaling
                .scale
                .iter()
                .any(|s| !(s.is_finite() && *s > 0.0))
        {
            return Err(format!(
                "its ridge's scaling must have {features} finite means and positive scales"
            ));
        }
        if !(self.alpha.is_finite() && self.alpha > 0.0) {
            return Err("its ridge's alpha must be a positive number".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solves `a x = b` by Gaussian elimination with partial pivoting.
    fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for col in 0..n {
            let pivot = (col..n)
                .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
                .unwrap();
            a.swap(col, pivot);
            b.swap(col, pivot);
            let pivot_row = a[col].clone();
            for row in col + 1..n {
                let f = a[row][col] / pivot_row[col];
                for (v, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                    *v -= f * p;
                }
                b[row] -= f * b[col];
            }
        }
        let mut x = vec![0.0; n];
        for row in (0..n).rev() {
            let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
            x[row] = (b[row] - s) / a[row][row];
        }
        x
    }

    /// Ridge with an unpenalised intercept on `x` (rows) and targets `y`,
    /// by the normal equations: the prediction at `q`.
    fn ridge_predict(x: &[Vec<f64>], y: &[f64], alpha: f64, q: &[f64]) -> f64 {
        let (n, p) = (x.len(), x[0].len());
        let xm: Vec<f64> = (0..p)
            .map(|j| x.iter().map(|r| r[j]).sum::<f64>() / n as f64)
            .collect();
        let ym = y.iter().sum::<f64>() / n as f64;
        let mut a = vec![vec![0.0; p]; p];
        let mut b = vec![0.0; p];
        for (r, &t) in x.iter().zip(y) {
            for i in 0..p {
                b[i] += (r[i] - xm[i]) * (t - ym);
                for j in 0..p {
                    a[i][j] += (r[i] - xm[i]) * (r[j] - xm[j]);
                }
            }
        }
        for (i, row) in a.iter_mut().enumerate() {
            row[i] += alpha;
        }
        let w = solve(a, b);
        ym + (0..p).map(|j| (q[j] - xm[j]) * w[j]).sum::<f64>()
    }

    fn data(n: usize, p: usize, classes: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<usize>) {
        crate::classify::linear::separable(n, p, classes, seed, |_| 0.0)
    }

    /// The efficient leave-one-out errors are those of n fits, each
    /// without one example, on the standardised features: with more
    /// features than examples (the Gram form) and fewer (the covariance).
    #[test]
    fn efficient_leave_one_out_matches_refitting_without_each_example() {
        for (n, p, classes) in [(12, 30, 3), (25, 4, 2)] {
            let (rows, labels) = data(n, p, classes, n as u64);
            let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            let scaling = Scaling::fit(&refs);
            let pr = problem(&refs, &labels, classes, &scaling);
            let dec = decompose(&pr).unwrap();
            assert_eq!(dec.gram, p > n);
            let x: Vec<Vec<f64>> = (0..n)
                .map(|i| (0..p).map(|j| pr.x[(i, j)]).collect())
                .collect();
            for alpha in [1e-3, 0.1, 10.0] {
                let (error, residuals) = dec.loo(&pr.y, alpha);
                let mut total = 0.0;
                for c in 0..classes {
                    let y: Vec<f64> = (0..n)
                        .map(|i| if labels[i] == c { 1.0 } else { -1.0 })
                        .collect();
                    for i in 0..n {
                        let (xs, ys): (Vec<Vec<f64>>, Vec<f64>) = (0..n)
                            .filter(|&k| k != i)
                            .map(|k| (x[k].clone(), y[k]))
                            .unzip();
                        let e = y[i] - ridge_predict(&xs, &ys, alpha, &x[i]);
                        assert!(
                            (e - residuals[(i, c)]).abs() < 1e-6 * (1.0 + e.abs()),
                            "n {n} p {p} alpha {alpha} example {i} class {c}: {e} vs {}",
                            residuals[(i, c)]
                        );
                        total += e * e;
                    }
                }
                let brute = total / (n * classes) as f64;
                assert!((error - brute).abs() < 1e-6 * brute, "{error} {brute}");
            }
        }
    }

    #[test]
    fn weights_are_the_normal_equations_solution_and_alpha_the_best_loo() {
        let (rows, labels) = data(20, 50, 2, 3);
        let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
        let fit = RidgeFit::fit(&refs, &labels, 2).unwrap();
        let best = fit.loo.iter().fold(f64::INFINITY, |b, &(_, e)| b.min(e));
        assert_eq!(
            fit.loo.iter().find(|(_, e)| *e == best).unwrap().0,
            fit.alpha
        );
        assert_eq!(fit.loo.len(), 10);
        assert!((fit.loo[0].0 - 1e-3).abs() < 1e-15 && (fit.loo[9].0 - 1e3).abs() < 1e-9);
        // The score of a training row is the direct ridge's prediction.
        let scaled: Vec<Vec<f64>> = rows
            .iter()
            .map(|r| {
                let mut s = vec![0.0; r.len()];
                fit.scaling.apply(r, &mut s);
                s
            })
            .collect();
        let y: Vec<f64> = labels
            .iter()
            .map(|&c| if c == 0 { 1.0 } else { -1.0 })
            .collect();
        let mut buf = vec![0.0; 50];
        for q in [0, 7] {
            let want = ridge_predict(&scaled, &y, fit.alpha, &scaled[q]);
            let got = fit.scores(&rows[q], &mut buf)[0];
            assert!((want - got).abs() < 1e-8, "{want} {got}");
        }
    }

    #[test]
    fn separable_classes_are_told_apart() {
        let (rows, labels) = data(60, 20, 3, 5);
        let refs: Vec<&[f64]> = rows[..45].iter().map(Vec::as_slice).collect();
        let fit = RidgeFit::fit(&refs, &labels[..45], 3).unwrap();
        let mut buf = vec![0.0; 20];
        let right = rows[45..]
            .iter()
            .zip(&labels[45..])
            .filter(|(r, c)| {
                let s = fit.scores(r, &mut buf);
                let best = (0..3).max_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap();
                best == **c
            })
            .count();
        assert_eq!(right, 15);
        assert!(fit.check(20, 3).is_ok());
        assert!(fit.check(21, 3).is_err());
        // Labels permuted in training: every held-out row goes to the
        // permuted class, so the fit follows the labels it was given.
        let shuffled: Vec<usize> = labels.iter().map(|c| (c * 7 + 1) % 3).collect();
        let fit = RidgeFit::fit(&refs, &shuffled[..45], 3).unwrap();
        let right = rows[45..]
            .iter()
            .zip(&labels[45..])
            .filter(|(r, c)| {
                let s = fit.scores(r, &mut buf);
                (0..3).max_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap() == **c
            })
            .count();
        assert_eq!(right, 0);
    }
}
