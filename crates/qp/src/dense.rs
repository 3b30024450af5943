//! The dense standard form every backend solves.

use nalgebra::{DMatrix, DMatrixView, DMatrixViewMut, DVector, DVectorView, DVectorViewMut};

use crate::error::QpError;
use crate::finite::all_finite;

/// A dense convex QP in the standard form shared by all backends:
///
/// ```text
/// minimise    ½ xᵀ H x + gᵀ x
/// subject to  E x = f                 (n_eq rows)
///             l ≤ C x ≤ u             (n_ineq rows, l_i may be −∞, u_i may be +∞, l_i = u_i allowed)
///             lb ≤ x ≤ ub             (simple bounds, ±∞ allowed)
/// ```
///
/// `H` must be symmetric (only the full matrix is read; keep both triangles equal). The active-set backend
/// needs `H` positive definite; clarabel accepts positive semi-definite `H`.
///
/// The equality and inequality blocks are stored with a *capacity* so that the number of active rows can
/// change (e.g. when a task switches between hard and soft) without reallocating; the accessors return
/// views of the rows in use.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseQp {
    n: usize,
    pub(crate) h: DMatrix<f64>,
    pub(crate) g: DVector<f64>,
    pub(crate) e: DMatrix<f64>,
    pub(crate) f: DVector<f64>,
    n_eq: usize,
    pub(crate) c: DMatrix<f64>,
    pub(crate) l: DVector<f64>,
    pub(crate) u: DVector<f64>,
    n_ineq: usize,
    pub(crate) lb: DVector<f64>,
    pub(crate) ub: DVector<f64>,
}

impl DenseQp {
    /// A problem with `n` variables, `n_eq` equality rows and `n_ineq` inequality rows, all data zero,
    /// inequality sides and bounds at ±∞ (i.e. inactive).
    pub fn new(n: usize, n_eq: usize, n_ineq: usize) -> Self {
        Self::with_capacity(n, n_eq, n_ineq)
    }

    /// Like [`DenseQp::new`], with `cap_eq`/`cap_ineq` rows allocated and all of them in use.
    pub fn with_capacity(n: usize, cap_eq: usize, cap_ineq: usize) -> Self {
        Self {
            n,
            h: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            e: DMatrix::zeros(cap_eq, n),
            f: DVector::zeros(cap_eq),
            n_eq: cap_eq,
            c: DMatrix::zeros(cap_ineq, n),
            l: DVector::from_element(cap_ineq, f64::NEG_INFINITY),
            u: DVector::from_element(cap_ineq, f64::INFINITY),
            n_ineq: cap_ineq,
            lb: DVector::from_element(n, f64::NEG_INFINITY),
            ub: DVector::from_element(n, f64::INFINITY),
        }
    }

    /// Number of variables.
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of equality rows in use.
    pub fn n_eq(&self) -> usize {
        self.n_eq
    }
    /// Number of inequality rows in use.
    pub fn n_ineq(&self) -> usize {
        self.n_ineq
    }
    /// Allocated equality rows.
    pub fn eq_capacity(&self) -> usize {
        self.e.nrows()
    }
    /// Allocated inequality rows.
    pub fn ineq_capacity(&self) -> usize {
        self.c.nrows()
    }

    /// Sets how many equality rows are in use (≤ capacity).
    pub fn set_n_eq(&mut self, n_eq: usize) -> Result<(), QpError> {
        if n_eq > self.e.nrows() {
            return Err(QpError::Dimension {
                what: "equality rows",
                expected: self.e.nrows(),
                got: n_eq,
            });
        }
        self.n_eq = n_eq;
        Ok(())
    }
    /// Sets how many inequality rows are in use (≤ capacity).
    pub fn set_n_ineq(&mut self, n_ineq: usize) -> Result<(), QpError> {
        if n_ineq > self.c.nrows() {
            return Err(QpError::Dimension {
                what: "inequality rows",
                expected: self.c.nrows(),
                got: n_ineq,
            });
        }
        self.n_ineq = n_ineq;
        Ok(())
    }

    /// Hessian `H` (n × n).
    pub fn hessian(&self) -> &DMatrix<f64> {
        &self.h
    }
    /// Mutable Hessian.
    pub fn hessian_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.h
    }
    /// Linear cost `g`.
    pub fn gradient(&self) -> &DVector<f64> {
        &self.g
    }
    /// Mutable linear cost.
    pub fn gradient_mut(&mut self) -> &mut DVector<f64> {
        &mut self.g
    }
    /// Equality matrix `E` (rows in use).
    pub fn eq_matrix(&self) -> DMatrixView<'_, f64> {
        self.e.rows(0, self.n_eq)
    }
    /// Mutable equality matrix.
    pub fn eq_matrix_mut(&mut self) -> DMatrixViewMut<'_, f64> {
        self.e.rows_mut(0, self.n_eq)
    }
    /// Equality right-hand side `f`.
    pub fn eq_rhs(&self) -> DVectorView<'_, f64> {
        self.f.rows(0, self.n_eq)
    }
    /// Mutable equality right-hand side.
    pub fn eq_rhs_mut(&mut self) -> DVectorViewMut<'_, f64> {
        self.f.rows_mut(0, self.n_eq)
    }
    /// Inequality matrix `C` (rows in use).
    pub fn ineq_matrix(&self) -> DMatrixView<'_, f64> {
        self.c.rows(0, self.n_ineq)
    }
    /// Mutable inequality matrix.
    pub fn ineq_matrix_mut(&mut self) -> DMatrixViewMut<'_, f64> {
        self.c.rows_mut(0, self.n_ineq)
    }
    /// Inequality lower sides `l` (−∞ for none).
    pub fn ineq_lower(&self) -> DVectorView<'_, f64> {
        self.l.rows(0, self.n_ineq)
    }
    /// Mutable inequality lower sides.
    pub fn ineq_lower_mut(&mut self) -> DVectorViewMut<'_, f64> {
        self.l.rows_mut(0, self.n_ineq)
    }
    /// Inequality upper sides `u` (+∞ for none).
    pub fn ineq_upper(&self) -> DVectorView<'_, f64> {
        self.u.rows(0, self.n_ineq)
    }
    /// Mutable inequality upper sides.
    pub fn ineq_upper_mut(&mut self) -> DVectorViewMut<'_, f64> {
        self.u.rows_mut(0, self.n_ineq)
    }
    /// Variable lower bounds `lb`.
    pub fn lower_bounds(&self) -> &DVector<f64> {
        &self.lb
    }
    /// Mutable variable lower bounds.
    pub fn lower_bounds_mut(&mut self) -> &mut DVector<f64> {
        &mut self.lb
    }
    /// Variable upper bounds `ub`.
    pub fn upper_bounds(&self) -> &DVector<f64> {
        &self.ub
    }
    /// Mutable variable upper bounds.
    pub fn upper_bounds_mut(&mut self) -> &mut DVector<f64> {
        &mut self.ub
    }

    /// Cost `½ xᵀHx + gᵀx` at `x`.
    pub fn objective(&self, x: &DVector<f64>) -> f64 {
        self.objective_noalloc(x)
    }

    /// Objective without allocating: `½ xᵀHx + gᵀx`.
    pub(crate) fn objective_noalloc(&self, x: &DVector<f64>) -> f64 {
        let n = self.n;
        let mut quad = 0.0;
        for j in 0..n {
            let col = self.h.column(j);
            let mut s = 0.0;
            for i in 0..n {
                s += col[i] * x[i];
            }
            quad += s * x[j];
        }
        0.5 * quad + self.g.dot(x)
    }

    /// Checks the data: finite `H`, `g`, `E`, `f`, `C`; no NaN in `l`, `u`, `lb`, `ub`; `l ≤ u`, `lb ≤ ub`;
    /// no `+∞` lower side nor `−∞` upper side. Returns `false` on any violation.
    pub fn is_valid(&self) -> bool {
        // the rows in use of a column-major matrix: the first `used` entries of each column
        fn finite_rows(m: &DMatrix<f64>, used: usize) -> bool {
            let rows = m.nrows();
            if used == rows {
                return all_finite(m.as_slice());
            }
            (0..m.ncols()).all(|c| all_finite(&m.as_slice()[c * rows..c * rows + used]))
        }
        if !all_finite(self.h.as_slice()) || !all_finite(self.g.as_slice()) {
            return false;
        }
        if !finite_rows(&self.e, self.n_eq) || !all_finite(&self.f.as_slice()[..self.n_eq]) {
            return false;
        }
        if !finite_rows(&self.c, self.n_ineq) {
            return false;
        }
        let sides_ok = |lo: f64, hi: f64| {
            !lo.is_nan() && !hi.is_nan() && lo <= hi && lo < f64::INFINITY && hi > f64::NEG_INFINITY
        };
        for i in 0..self.n_ineq {
            if !sides_ok(self.l[i], self.u[i]) {
                return false;
            }
        }
        for j in 0..self.n {
            if !sides_ok(self.lb[j], self.ub[j]) {
                return false;
            }
        }
        true
    }
}
