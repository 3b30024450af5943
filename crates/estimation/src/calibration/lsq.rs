//! Least squares over many samples without storing them: the rows are folded into the triangular factor of
//! a QR decomposition batch by batch, and the solution is the minimum-norm one on the numerically
//! identifiable subspace (SVD of the factor), with that subspace reported so callers can check that what
//! they need is determined.

use nalgebra::{DMatrix, DVector};

/// Rows folded per QR update.
const BATCH_ROWS: usize = 384;

/// Default relative rank tolerance: singular values below `tol · σ_max` are treated as zero.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// `min ‖A x − b‖` accumulated row by row. Memory is `O(n²)` for `n` unknowns, whatever the row count.
#[derive(Clone, Debug)]
pub struct StackedLeastSquares {
    unknowns: usize,
    /// Upper-triangular factor of `[A b]` so far, `(n + 1) × (n + 1)`.
    r: DMatrix<f64>,
    /// Rows waiting to be folded into `r`, `[A b]`.
    pending: DMatrix<f64>,
    filled: usize,
    rows: usize,
}

/// The solution of a [`StackedLeastSquares`].
#[derive(Clone, Debug)]
pub struct LeastSquaresSolution {
    /// Minimum-norm solution on the identifiable subspace.
    pub x: DVector<f64>,
    /// Numerical rank of `A`.
    pub rank: usize,
    /// Singular values of `A`, decreasing.
    pub singular_values: DVector<f64>,
    /// Orthonormal basis of the numerical null space of `A` (`n × (n − rank)`).
    pub null_space: DMatrix<f64>,
    /// `(AᵀA)⁺` on the identifiable subspace: the covariance of `x` for unit-variance row noise.
    pub covariance: DMatrix<f64>,
    /// `‖A x − b‖²`.
    pub residual_squared: f64,
    /// Number of rows.
    pub rows: usize,
}

impl StackedLeastSquares {
    /// An empty problem with `unknowns` columns.
    pub fn new(unknowns: usize) -> Self {
        Self {
            unknowns,
            r: DMatrix::zeros(unknowns + 1, unknowns + 1),
            pending: DMatrix::zeros(BATCH_ROWS, unknowns + 1),
            filled: 0,
            rows: 0,
        }
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }

    /// Number of rows added.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Adds the row `a · x = b` (`a.len()` must be the number of unknowns).
    pub fn add_row(&mut self, a: &[f64], b: f64) {
        debug_assert_eq!(a.len(), self.unknowns);
        if self.filled == BATCH_ROWS {
            self.fold();
        }
        let k = self.filled;
        for (j, v) in a.iter().enumerate() {
            self.pending[(k, j)] = *v;
        }
        self.pending[(k, self.unknowns)] = b;
        self.filled += 1;
        self.rows += 1;
    }

    /// Folds the pending rows into the triangular factor.
    fn fold(&mut self) {
        if self.filled == 0 {
            return;
        }
        let n = self.unknowns + 1;
        let mut stacked = DMatrix::zeros(n + self.filled, n);
        stacked.view_mut((0, 0), (n, n)).copy_from(&self.r);
        stacked
            .view_mut((n, 0), (self.filled, n))
            .copy_from(&self.pending.rows(0, self.filled));
        let r = stacked.qr().r();
        self.r.fill(0.0);
        let k = r.nrows().min(n);
        self.r.view_mut((0, 0), (k, n)).copy_from(&r.rows(0, k));
        self.filled = 0;
    }

    /// The triangular factor of the rows so far: `(R, Qᵀb, ρ)` with `‖A x − b‖² = ‖R x − Qᵀb‖² + ρ²` for
    /// every `x` (`R` upper-triangular, `n × n`).
    pub fn triangular_factor(&self) -> (DMatrix<f64>, DVector<f64>, f64) {
        let mut this = self.clone();
        this.fold();
        let n = this.unknowns;
        let ra = this.r.view((0, 0), (n, n)).into_owned();
        let qb = this.r.column(n).rows(0, n).into_owned();
        (ra, qb, this.r[(n, n)])
    }

    /// Solves with the relative rank tolerance `tolerance` (see [`RANK_TOLERANCE`]).
    pub fn solve(&self, tolerance: f64) -> LeastSquaresSolution {
        let (ra, qb, rho) = self.triangular_factor();
        let n = self.unknowns;
        let svd = ra.svd(true, true);
        let (u, v_t) = match (svd.u, svd.v_t) {
            (Some(u), Some(v_t)) => (u, v_t),
            _ => unreachable!("the SVD was asked for U and Vᵀ"),
        };
        let s = svd.singular_values;
        let s_max = s.iter().cloned().fold(0.0, f64::max);
        let rank = s
            .iter()
            .filter(|&&x| x > tolerance * s_max && x > 0.0)
            .count();
        let mut x = DVector::zeros(n);
        let mut covariance = DMatrix::zeros(n, n);
        let mut residual_squared = rho * rho;
        for i in 0..n {
            let c = u.column(i).dot(&qb);
            if i < rank {
                let vi = v_t.row(i).transpose();
                x += &vi * (c / s[i]);
                covariance += &vi * vi.transpose() / (s[i] * s[i]);
            } else {
                residual_squared += c * c;
            }
        }
        let null_space = v_t.rows(rank, n - rank).transpose();
        LeastSquaresSolution {
            x,
            rank,
            singular_values: s,
            null_space,
            covariance,
            residual_squared,
            rows: self.rows,
        }
    }
}

impl LeastSquaresSolution {
    /// Largest component of the null space along the unknowns `range` (0: they are all determined).
    pub fn null_component(&self, range: std::ops::Range<usize>) -> f64 {
        let n = self.null_space.ncols();
        if n == 0 {
            return 0.0;
        }
        self.null_space
            .rows(range.start, range.len())
            .column_iter()
            .map(|c| c.norm())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Folding in batches gives the normal-equation solution of a well-posed problem, the residual and the
    /// null space of a rank-deficient one.
    #[test]
    fn batches_give_the_direct_solution() {
        let n = 5;
        let rows = 1000;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut ls = StackedLeastSquares::new(n);
        let a = DMatrix::from_fn(rows, n, |_, _| rng.random::<f64>() - 0.5);
        let b = DVector::from_fn(rows, |_, _| rng.random::<f64>() - 0.5);
        for i in 0..rows {
            ls.add_row(a.row(i).transpose().as_slice(), b[i]);
        }
        let sol = ls.solve(RANK_TOLERANCE);
        let direct = (a.transpose() * &a)
            .lu()
            .solve(&(a.transpose() * &b))
            .expect("full rank");
        assert!((&sol.x - &direct).norm() < 1e-10);
        assert_eq!(sol.rank, n);
        let res = (&a * &direct - &b).norm_squared();
        assert!((sol.residual_squared - res).abs() < 1e-9 * res);

        // Duplicate column 0 into column 5: rank 5 of 6, null space (1, 0, 0, 0, 0, −1)/√2.
        let mut ls = StackedLeastSquares::new(n + 1);
        for i in 0..rows {
            let mut row: Vec<f64> = a.row(i).iter().cloned().collect();
            row.push(a[(i, 0)]);
            ls.add_row(&row, b[i]);
        }
        let sol = ls.solve(RANK_TOLERANCE);
        assert_eq!(sol.rank, n);
        assert!((sol.null_component(0..1) - 0.5f64.sqrt()).abs() < 1e-9);
        assert!(sol.null_component(1..5) < 1e-9);
        assert!(
            (sol.x[0] - sol.x[5]).abs() < 1e-9,
            "minimum norm splits evenly"
        );
    }
}
