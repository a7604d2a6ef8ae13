//! Linear discriminant analysis with a Ledoit–Wolf shrunk covariance, as
//! scikit-learn's `LinearDiscriminantAnalysis(solver = "lsqr", shrinkage =
//! "auto")` makes it: one covariance `Σ` shared by the classes, each
//! class's mean `μ_c` and prior `π_c = n_c / n` (its share of the training
//! examples); a query `x` goes to the class of the largest score
//!
//! ```text
//! δ_c(x) = (x − x̄)ᵀ w_c + b_c,   w_c = Σ⁻¹ (μ_c − x̄),   b_c = −½ (μ_c − x̄)ᵀ w_c + ln π_c
//! ```
//!
//! with `x̄` the mean of all the training examples. Centring on `x̄` adds
//! the same amount to every class's score of a query (`½ x̄ᵀΣ⁻¹x̄ − xᵀΣ⁻¹x̄`),
//! so the answer is the textbook `xᵀΣ⁻¹μ_c − ½ μ_cᵀΣ⁻¹μ_c + ln π_c`'s, with
//! smaller numbers.
//!
//! **The covariance.** scikit-learn shrinks each class's covariance with
//! its own intensity and averages them by prior (its `covariance_` is
//! `Σ_c π_c C_c`), rather than one intensity on the pooled scatter; the
//! tests hold this module to its numbers. Class `c`'s rows are standardised
//! with the class's own mean and standard deviations `D_c` (1 for a feature
//! whose values in the class are all equal), `Z_c = (X_c − 1μ_cᵀ) D_c⁻¹`;
//! their covariance `R_c = Z_cᵀZ_c / n_c` is shrunk toward `m_c I`, `m_c =
//! tr(R_c) / p`, and scaled back:
//!
//! ```text
//! C_c = D_c ((1 − s_c) R_c + s_c m_c I) D_c = (1 − s_c) S_c + s_c m_c D_c²
//! ```
//!
//! (`S_c` the class's covariance, divided by `n_c`), so on the features as
//! measured the target is the diagonal of the class's variances.
//!
//! **The intensity** `s` is Ledoit and Wolf's (2004, "A well-conditioned
//! estimator for large-dimensional covariance matrices", J. Multivariate
//! Analysis 88): with the norm `‖A‖² = tr(AAᵀ)/p` and the rows `z_k` of a
//! centred `Z` (n × p, `R = ZᵀZ/n`), `d² = ‖R − mI‖²`, `b̄² = n⁻² Σ_k
//! ‖z_k z_kᵀ − R‖²`, `b² = min(b̄², d²)` and `s = b²/d²` (0 when `b² =
//! 0`). Expanded so that no `p × p` matrix is needed, with `‖R‖²_F =
//! ‖ZZᵀ‖²_F / n²` (the `n × n` Gram matrix when `p > n`):
//!
//! ```text
//! m = Σ_k ‖z_k‖² / (n p),   d² = (‖R‖²_F − p m²) / p,   b̄² = (Σ_k ‖z_k‖⁴ − n ‖R‖²_F) / (n² p)
//! ```
//!
//! Two examples of a class make `z_1 = −z_2`, so `b̄² = 0`: that class is
//! not shrunk.
//!
//! **Solving `Σ W = M`** (`M`'s columns `μ_c − x̄`). `Σ = UᵀU + Δ`, with
//! `U`'s row for example `k` of class `c` equal to `√((1 − s_c)/n) (x_k −
//! μ_c)` (rank at most n) and `Δ = diag(Σ_c π_c s_c m_c D_c²)`. With no
//! more features than examples, `Σ` is formed (`p × p`) and `W = Σ⁺M` from
//! its eigendecomposition. With more (the kernels' ten thousand against a
//! few hundred windows; `Σ` would be 800 MB) Woodbury's identity needs only
//! `n × n`: with `V = UΔ^{-1/2}` and `VVᵀ = QΛQᵀ`,
//!
//! ```text
//! Σ⁻¹ = Δ^{-1/2} (I − VᵀQ (Λ + I)⁻¹ QᵀV) Δ^{-1/2}
//! ```
//!
//! `Δ` is positive on every feature as soon as one class is shrunk
//! (`D_c > 0`); when none is (two examples a class, or every class's
//! examples alike) `Σ = UᵀU` may be singular and, as least squares gives,
//! `W = Σ⁺M`: from `UUᵀ = QΛQᵀ`, `Σ⁺ = UᵀQΛ⁻²QᵀU`. Both pseudo-inverses
//! drop the eigenvalues below `p ε` times the largest.
//!
//! Refused when every class's examples are alike (one example a class, as
//! a holdout of one training recording per texture gives): `Σ = 0`, and
//! every query would go to the likeliest class a priori.
//!
//! Fitted on the examples it is handed: the caller (the model) hands it
//! training examples only. Pure Rust (faer); never prints.

use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

/// A fitted linear discriminant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LdaFit {
    /// Each class's Ledoit–Wolf shrinkage intensity, 0 to 1.
    pub shrinkage: Vec<f64>,
    /// Each class's share of the training examples.
    pub priors: Vec<f64>,
    /// The training examples' mean, taken from a query first.
    pub centre: Vec<f64>,
    /// One row of weights per class: `Σ⁻¹ (μ_c − x̄)`.
    pub weights: Vec<Vec<f64>>,
    pub intercepts: Vec<f64>,
}

/// The Ledoit–Wolf shrinkage intensity of centred rows `z` (n × p), and
/// the target's scale `m = tr(R)/p`.
pub(crate) fn ledoit_wolf(z: &Mat<f64>) -> (f64, f64) {
    let (n, p) = (z.nrows(), z.ncols());
    if n == 0 || p == 0 {
        return (0.0, 0.0);
    }
    let (nf, pf) = (n as f64, p as f64);
    // ‖ZᵀZ‖_F = ‖ZZᵀ‖_F: the smaller of the two.
    let gram = if p > n {
        z * z.transpose()
    } else {
        z.transpose() * z
    };
    let mut r_f2 = 0.0;
    for j in 0..gram.ncols() {
        for i in 0..gram.nrows() {
            r_f2 += gram[(i, j)] * gram[(i, j)];
        }
    }
    r_f2 /= nf * nf;
    let row_sq: Vec<f64> = (0..n)
        .map(|i| (0..p).map(|j| z[(i, j)] * z[(i, j)]).sum())
        .collect();
    let m = row_sq.iter().sum::<f64>() / (nf * pf);
    let d2 = (r_f2 - pf * m * m) / pf;
    let b2_bar = (row_sq.iter().map(|r| r * r).sum::<f64>() - nf * r_f2) / (nf * nf * pf);
    let b2 = b2_bar.max(0.0).min(d2);
    let s = if b2 > 0.0 && d2 > 0.0 { b2 / d2 } else { 0.0 };
    (s.clamp(0.0, 1.0), m)
}

/// `Σ W = M` for `Σ = UᵀU + diag(Δ)`: directly (`p × p`) or by Woodbury
/// (`n × n`).
fn solve(u: &Mat<f64>, delta: &[f64], m: &Mat<f64>, woodbury: bool) -> Result<Mat<f64>, String> {
    let (n, p, k) = (u.nrows(), u.ncols(), m.ncols());
    let eigen = |a: Mat<f64>| {
        let e = a
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| format!("the LDA's eigendecomposition failed: {e:?}"))?;
        let values: Vec<f64> = (0..a.nrows()).map(|i| e.S()[i]).collect();
        Ok::<_, String>((e.U().to_owned(), values))
    };
    // The pseudo-inverse's cut: eigenvalues below p ε of the largest.
    let cut =
        |values: &[f64]| values.iter().fold(0.0f64, |a, &v| a.max(v)) * p as f64 * f64::EPSILON;
    if !woodbury {
        let mut sigma = u.transpose() * u;
        for (j, d) in delta.iter().enumerate() {
            sigma[(j, j)] += d;
        }
        let (q, l) = eigen(sigma)?;
        let small = cut(&l);
        let projected = q.transpose() * m;
        let scaled = Mat::<f64>::from_fn(p, k, |i, c| {
            if l[i] > small {
                projected[(i, c)] / l[i]
            } else {
                0.0
            }
        });
        return Ok(&q * &scaled);
    }
    if delta.iter().all(|&d| d > 0.0) {
        let root: Vec<f64> = delta.iter().map(|d| d.sqrt()).collect();
        let v = Mat::<f64>::from_fn(n, p, |i, j| u[(i, j)] / root[j]);
        let y = Mat::<f64>::from_fn(p, k, |j, c| m[(j, c)] / root[j]);
        let (q, l) = eigen(&v * v.transpose())?;
        let t = q.transpose() * (&v * &y);
        let t = Mat::<f64>::from_fn(n, k, |i, c| t[(i, c)] / (l[i].max(0.0) + 1.0));
        let correction = v.transpose() * (&q * &t);
        Ok(Mat::<f64>::from_fn(p, k, |j, c| {
            (y[(j, c)] - correction[(j, c)]) / root[j]
        }))
    } else {
        // No class shrunk: Σ = UᵀU, its pseudo-inverse UᵀQΛ⁻²QᵀU.
        let (q, l) = eigen(u * u.transpose())?;
        let small = cut(&l);
        let t = q.transpose() * (u * m);
        let t = Mat::<f64>::from_fn(n, k, |i, c| {
            if l[i] > small {
                t[(i, c)] / (l[i] * l[i])
            } else {
                0.0
            }
        });
        Ok(u.transpose() * (&q * &t))
    }
}

impl LdaFit {
    /// Fits on `rows` (each the same length, finite) of classes `classes`
    /// (indices below `n_classes`, every one of them present).
    pub fn fit(rows: &[&[f64]], classes: &[usize], n_classes: usize) -> Result<LdaFit, String> {
        let p = rows.first().map_or(0, |r| r.len());
        LdaFit::fit_by(rows, classes, n_classes, p > rows.len())
    }

    /// [`LdaFit::fit`], solving by Woodbury's identity or directly.
    fn fit_by(
        rows: &[&[f64]],
        classes: &[usize],
        n_classes: usize,
        woodbury: bool,
    ) -> Result<LdaFit, String> {
        let n = rows.len();
        if n < 2 || n != classes.len() {
            return Err("the LDA needs at least two training examples".into());
        }
        let p = rows[0].len();
        let mut members = vec![Vec::new(); n_classes];
        for (i, &c) in classes.iter().enumerate() {
            members
                .get_mut(c)
                .ok_or("the LDA was handed an example of no class")?
                .push(i);
        }
        if members.iter().any(Vec::is_empty) {
            return Err("the LDA needs a training example of every class".into());
        }
        let nf = n as f64;
        let mut centre = vec![0.0; p];
        for r in rows {
            for (c, v) in centre.iter_mut().zip(*r) {
                *c += v / nf;
            }
        }
        let mut u = Mat::<f64>::zeros(n, p);
        let mut delta = vec![0.0; p];
        let mut means = Mat::<f64>::zeros(p, n_classes);
        let mut shrinkage = Vec::with_capacity(n_classes);
        let mut priors = Vec::with_capacity(n_classes);
        let mut scatter = false;
        for (c, of) in members.iter().enumerate() {
            let nc = of.len() as f64;
            let prior = nc / nf;
            let mut mean = vec![0.0; p];
            for &i in of {
                for (m, v) in mean.iter_mut().zip(rows[i]) {
                    *m += v / nc;
                }
            }
            // A feature whose values in the class are all equal is
            // centred to exactly 0 and keeps a scale of 1.
            let constant: Vec<bool> = (0..p)
                .map(|j| of.iter().all(|&i| rows[i][j] == rows[of[0]][j]))
                .collect();
            scatter |= constant.contains(&false);
            let scale: Vec<f64> = (0..p)
                .map(|j| {
                    let var = of
                        .iter()
                        .map(|&i| (rows[i][j] - mean[j]).powi(2))
                        .sum::<f64>()
                        / nc;
                    if constant[j] || var <= 0.0 {
                        1.0
                    } else {
                        var.sqrt()
                    }
                })
                .collect();
            let centred = |i: usize, j: usize| {
                if constant[j] {
                    0.0
                } else {
                    rows[i][j] - mean[j]
                }
            };
            let z = Mat::<f64>::from_fn(of.len(), p, |a, j| centred(of[a], j) / scale[j]);
            let (s, m) = ledoit_wolf(&z);
            let weight = ((1.0 - s) / nf).sqrt();
            for &i in of {
                for j in 0..p {
                    u[(i, j)] = weight * centred(i, j);
                }
            }
            for (d, sc) in delta.iter_mut().zip(&scale) {
                *d += prior * s * m * sc * sc;
            }
            for j in 0..p {
                means[(j, c)] = mean[j] - centre[j];
            }
            shrinkage.push(s);
            priors.push(prior);
        }
        if !scatter {
            // Σ = 0: every score would be the prior's alone.
            return Err(
                "the LDA has no covariance to estimate: every texture's training \
                        examples are alike (or one each); it needs two different examples of a \
                        texture at least"
                    .into(),
            );
        }
        let w = solve(&u, &delta, &means, woodbury)?;
        let weights: Vec<Vec<f64>> = (0..n_classes)
            .map(|c| (0..p).map(|j| w[(j, c)]).collect())
            .collect();
        let intercepts: Vec<f64> = (0..n_classes)
            .map(|c| {
                let quad: f64 = (0..p).map(|j| means[(j, c)] * w[(j, c)]).sum();
                -0.5 * quad + priors[c].ln()
            })
            .collect();
        let fit = LdaFit {
            shrinkage,
            priors,
            centre,
            weights,
            intercepts,
        };
        if !fit.finite() {
            return Err("the LDA's weights are not finite numbers".into());
        }
        Ok(fit)
    }

    fn finite(&self) -> bool {
        use super::linear::finite;
        self.weights.iter().all(|w| finite(w)) && finite(&self.intercepts) && finite(&self.centre)
    }

    /// Each class's score for `x`, with `centred` a buffer of its length.
    pub fn scores(&self, x: &[f64], centred: &mut [f64]) -> Vec<f64> {
        for ((o, v), c) in centred.iter_mut().zip(x).zip(&self.centre) {
            *o = v - c;
        }
        super::linear::scores(&self.weights, &self.intercepts, centred)
    }

    /// Checks a fit read from a file against `features` and `classes`.
    pub fn check(&self, features: usize, classes: usize) -> Result<(), String> {
        if !super::linear::weights_fit(&self.weights, &self.intercepts, features, classes)
            || self.centre.len() != features
            || !super::linear::finite(&self.centre)
        {
            return Err(format!(
                "its LDA must have {classes} rows of {features} finite weights, {classes} \
                 intercepts and a centre of {features} finite numbers"
            ));
        }
        if self.shrinkage.len() != classes
            || self.priors.len() != classes
            || self.shrinkage.iter().any(|s| !(0.0..=1.0).contains(s))
            || self.priors.iter().any(|p| !(*p > 0.0 && *p <= 1.0))
        {
            return Err(format!(
                "its LDA must have {classes} shrinkage intensities from 0 to 1 and {classes} \
                 priors above 0 and at most 1"
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
