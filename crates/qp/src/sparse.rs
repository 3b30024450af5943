//! Sparse QPs given as triplets (for large banded problems such as the DCM MPC).

use std::time::Duration;

use crate::dense::DenseQp;
use crate::error::QpError;
use crate::status::QpStatus;

/// A QP in triplet form:
///
/// ```text
/// minimise    ½ xᵀ P x + qᵀ x
/// subject to  lower ≤ A x ≤ upper      (lower_i = upper_i: equality; ±∞ allowed)
/// ```
///
/// `hessian` holds the **upper triangle** of `P` as `(row, col, value)` with `row ≤ col`; `constraints` holds
/// `A` as `(row, col, value)`. Duplicate entries are summed. Solve it with
/// [`crate::ClarabelSparseSolver`] (no densification) or convert it with [`SparseQp::to_dense`] for the
/// active-set backend when it is small.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseQp {
    /// Number of variables.
    pub n: usize,
    /// Upper-triangle entries of `P` (`row ≤ col`).
    pub hessian: Vec<(usize, usize, f64)>,
    /// Linear cost `q` (length `n`).
    pub gradient: Vec<f64>,
    /// Entries of `A` (`row < lower.len()`, `col < n`).
    pub constraints: Vec<(usize, usize, f64)>,
    /// Row lower sides (−∞ for none).
    pub lower: Vec<f64>,
    /// Row upper sides (+∞ for none).
    pub upper: Vec<f64>,
}

/// Solution of a [`SparseQp`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseSolution {
    /// Primal solution (zeros on failure, never NaN).
    pub x: Vec<f64>,
    /// One multiplier per constraint row: positive when the upper side is active, negative for the lower side
    /// (stationarity `P x + q + Aᵀ multipliers = 0`).
    pub multipliers: Vec<f64>,
    /// Status.
    pub status: QpStatus,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Objective `½ xᵀPx + qᵀx`.
    pub objective: f64,
    /// Wall time of the call (conversion + solve).
    pub solve_time: Duration,
}

impl SparseQp {
    /// An empty problem with `n` variables and `m` unconstrained rows (sides ±∞).
    pub fn new(n: usize, m: usize) -> Self {
        Self {
            n,
            hessian: Vec::new(),
            gradient: vec![0.0; n],
            constraints: Vec::new(),
            lower: vec![f64::NEG_INFINITY; m],
            upper: vec![f64::INFINITY; m],
        }
    }

    /// Adds `value` to `P[i][j]` and `P[j][i]` (stored once in the upper triangle; for `i ≠ j` this adds
    /// the symmetric pair, i.e. the cost term `value · x_i x_j`).
    pub fn add_hessian(&mut self, i: usize, j: usize, value: f64) {
        let (r, c) = if i <= j { (i, j) } else { (j, i) };
        self.hessian.push((r, c, value));
    }

    /// Appends the constraint row `lower ≤ Σ value·x_col ≤ upper` and returns its index.
    pub fn add_row(&mut self, entries: &[(usize, f64)], lower: f64, upper: f64) -> usize {
        let r = self.lower.len();
        for &(c, v) in entries {
            self.constraints.push((r, c, v));
        }
        self.lower.push(lower);
        self.upper.push(upper);
        r
    }

    /// Number of constraint rows.
    pub fn n_rows(&self) -> usize {
        self.lower.len()
    }

    /// Checks sizes, index ranges, finiteness and `lower ≤ upper`.
    pub fn validate(&self) -> Result<(), QpError> {
        if self.gradient.len() != self.n {
            return Err(QpError::Dimension {
                what: "sparse gradient",
                expected: self.n,
                got: self.gradient.len(),
            });
        }
        if self.upper.len() != self.lower.len() {
            return Err(QpError::Dimension {
                what: "sparse upper sides",
                expected: self.lower.len(),
                got: self.upper.len(),
            });
        }
        for &(r, c, v) in &self.hessian {
            if r > c || c >= self.n || !v.is_finite() {
                return Err(QpError::BadTriplet {
                    what: "hessian",
                    row: r,
                    col: c,
                });
            }
        }
        for &(r, c, v) in &self.constraints {
            if r >= self.lower.len() || c >= self.n || !v.is_finite() {
                return Err(QpError::BadTriplet {
                    what: "constraint",
                    row: r,
                    col: c,
                });
            }
        }
        if self.gradient.iter().any(|v| !v.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "gradient",
                reason: "non-finite entry".into(),
            });
        }
        for (i, (&l, &u)) in self.lower.iter().zip(&self.upper).enumerate() {
            if l.is_nan() || u.is_nan() || l > u || l == f64::INFINITY || u == f64::NEG_INFINITY {
                return Err(QpError::InvalidSetting {
                    name: "constraint sides",
                    reason: format!("row {i}: lower {l} / upper {u}"),
                });
            }
        }
        Ok(())
    }

    /// The same problem as a [`DenseQp`] (all rows as two-sided inequalities, no equality block, no bounds).
    pub fn to_dense(&self) -> Result<DenseQp, QpError> {
        self.validate()?;
        let m = self.lower.len();
        let mut d = DenseQp::new(self.n, 0, m);
        for &(r, c, v) in &self.hessian {
            d.h[(r, c)] += v;
            if r != c {
                d.h[(c, r)] += v;
            }
        }
        for (j, &v) in self.gradient.iter().enumerate() {
            d.g[j] = v;
        }
        for &(r, c, v) in &self.constraints {
            d.c[(r, c)] += v;
        }
        for i in 0..m {
            d.l[i] = self.lower[i];
            d.u[i] = self.upper[i];
        }
        Ok(d)
    }
}
