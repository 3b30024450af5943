//! A primal–dual interior-point method (Mehrotra predictor–corrector) for convex QPs whose Hessian is
//! banded and whose constraint rows each touch a few neighbouring variables:
//!
//! `min ½ xᵀPx + qᵀx  s.t.  Cx ≤ d`
//!
//! Each Newton system `(P + Cᵀ diag(λ/s) C) Δx = r` stays banded and is solved by a banded Cholesky in
//! `O(n b²)`. All memory is allocated in `new`; `solve` allocates nothing.

// Band algorithms index several arrays with the same loop counter; ranges read like the maths.
#![allow(clippy::needless_range_loop)]

/// A sparse constraint row with at most [`MAX_ROW_ENTRIES`] non-zeros.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SparseRow {
    pub(crate) columns: [usize; MAX_ROW_ENTRIES],
    pub(crate) values: [f64; MAX_ROW_ENTRIES],
    pub(crate) len: usize,
    pub(crate) bound: f64,
}

/// Most non-zeros of a constraint row.
pub(crate) const MAX_ROW_ENTRIES: usize = 4;

impl SparseRow {
    fn dot(&self, x: &[f64]) -> f64 {
        (0..self.len)
            .map(|e| self.values[e] * x[self.columns[e]])
            .sum()
    }
}

/// Outcome of a solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum IpmOutcome {
    /// The unconstrained minimiser was feasible: it is the solution (no iteration).
    Unconstrained,
    /// Converged to the tolerances.
    Converged,
    /// Hit the iteration limit.
    MaxIterations,
    /// A Newton matrix was not positive definite or a value became non-finite.
    NumericalError,
}

/// Half-bandwidth of every band matrix here (the DCM MPC's Newton matrices, x/y interleaved).
pub(crate) const BAND: usize = 5;

/// Banded symmetric matrix (lower band, row-major, fixed half-bandwidth [`BAND`]): row `i` is an array
/// `R_i` with `R_i[c] = A(i, i − BAND + c)`, `c = 0..=BAND` (so `R_i[BAND]` is the diagonal). Entries
/// with a negative column stay zero, which lets the kernels run fixed-length loops.
#[derive(Debug, Clone)]
pub(crate) struct BandMatrix {
    pub(crate) n: usize,
    rows: Vec<[f64; BAND + 1]>,
    /// `1 / L(i,i)` after `cholesky_in_place` (divisions are the slow operation here).
    inverse_diagonal: Vec<f64>,
}

impl BandMatrix {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            rows: vec![[0.0; BAND + 1]; n],
            inverse_diagonal: vec![0.0; n],
        }
    }

    /// Half-bandwidth.
    pub(crate) fn bandwidth(&self) -> usize {
        BAND
    }

    /// Adds `v` to the symmetric entry `(i, j)`, `|i − j| ≤ BAND` (stored once, in the lower band).
    #[inline]
    pub(crate) fn add(&mut self, i: usize, j: usize, v: f64) {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        debug_assert!(r - c <= BAND);
        self.rows[r][BAND + c - r] += v;
    }

    /// Entry `(i, j)` of the symmetric matrix (zero outside the band).
    #[inline]
    pub(crate) fn get(&self, i: usize, j: usize) -> f64 {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if r - c > BAND {
            0.0
        } else {
            self.rows[r][BAND + c - r]
        }
    }

    /// Diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn diagonal(&self, i: usize) -> f64 {
        self.rows[i][BAND]
    }

    /// Adds `v` to the diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn add_diagonal(&mut self, i: usize, v: f64) {
        self.rows[i][BAND] += v;
    }

    pub(crate) fn fill_zero(&mut self) {
        self.rows.iter_mut().for_each(|r| *r = [0.0; BAND + 1]);
    }

    pub(crate) fn copy_from(&mut self, other: &BandMatrix) {
        self.rows.copy_from_slice(&other.rows);
    }

    /// `y = A x` for the symmetric matrix.
    pub(crate) fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..self.n {
            let row = &self.rows[i];
            let lo = i.saturating_sub(BAND);
            for j in lo..i {
                let a = row[BAND + j - i];
                y[i] += a * x[j];
                y[j] += a * x[i];
            }
            y[i] += row[BAND] * x[i];
        }
    }

    /// In-place Cholesky `A = L Lᵀ` (L kept in the band). Returns false if not positive definite.
    pub(crate) fn cholesky_in_place(&mut self) -> bool {
        for i in 0..self.n {
            let lo = i.saturating_sub(BAND);
            for j in lo..=i {
                let d = i - j;
                // Σ_{k=i−BAND}^{j−1} L(i,k) L(j,k) = Σ_{c=0}^{BAND−d−1} R_i[c] R_j[c+d] (zero padding)
                let row_i = &self.rows[i];
                let row_j = &self.rows[j];
                let mut dot = 0.0;
                for c in 0..BAND - d {
                    dot += row_i[c] * row_j[c + d];
                }
                let sum = row_i[BAND - d] - dot;
                if d == 0 {
                    if !(sum > 0.0 && sum.is_finite()) {
                        return false;
                    }
                    let root = sum.sqrt();
                    self.rows[i][BAND] = root;
                    self.inverse_diagonal[i] = 1.0 / root;
                } else {
                    self.rows[i][BAND - d] = sum * self.inverse_diagonal[j];
                }
            }
        }
        true
    }

    /// Solves `L Lᵀ x = b` in place (after `cholesky_in_place`).
    pub(crate) fn cholesky_solve(&self, b: &mut [f64]) {
        let n = self.n;
        // L y = b, row-oriented.
        for i in 0..n {
            let row = &self.rows[i];
            let first = BAND.saturating_sub(i);
            let mut dot = 0.0;
            for c in first..BAND {
                dot += row[c] * b[i + c - BAND];
            }
            b[i] = (b[i] - dot) * self.inverse_diagonal[i];
        }
        // Lᵀ x = y, column-oriented (row i of L is column i of Lᵀ).
        for i in (0..n).rev() {
            let xi = b[i] * self.inverse_diagonal[i];
            b[i] = xi;
            let row = &self.rows[i];
            let first = BAND.saturating_sub(i);
            for c in first..BAND {
                b[i + c - BAND] -= row[c] * xi;
            }
        }
    }
}

/// Settings of the interior-point method.
#[derive(Debug, Clone, Copy)]
pub(crate) struct IpmSettings {
    pub(crate) tolerance: f64,
    pub(crate) max_iterations: u32,
}

/// Workspace and problem data of the banded QP.
#[derive(Debug, Clone)]
pub(crate) struct BandedQp {
    pub(crate) hessian: BandMatrix,
    pub(crate) gradient: Vec<f64>,
    pub(crate) rows: Vec<SparseRow>,
    pub(crate) row_count: usize,
    // iterates
    pub(crate) x: Vec<f64>,
    pub(crate) slack: Vec<f64>,
    pub(crate) multiplier: Vec<f64>,
    // scratch
    newton: BandMatrix,
    residual_dual: Vec<f64>,
    residual_primal: Vec<f64>,
    dx: Vec<f64>,
    ds: Vec<f64>,
    dl: Vec<f64>,
    ds_aff: Vec<f64>,
    dl_aff: Vec<f64>,
    rhs_rows: Vec<f64>,
    transpose_product: Vec<f64>,
    inverse_slack: Vec<f64>,
    /// Scales of the terms of the last residuals: ‖Px‖∞, ‖Cᵀλ‖∞, ‖Cx‖∞.
    term_scales: [f64; 3],
}

impl BandedQp {
    /// Workspace for `n` variables (half-bandwidth [`BAND`]) and at most `max_rows` constraint rows.
    pub(crate) fn new(n: usize, max_rows: usize) -> Self {
        Self {
            hessian: BandMatrix::new(n),
            gradient: vec![0.0; n],
            rows: vec![SparseRow::default(); max_rows],
            row_count: 0,
            x: vec![0.0; n],
            slack: vec![0.0; max_rows],
            multiplier: vec![0.0; max_rows],
            newton: BandMatrix::new(n),
            residual_dual: vec![0.0; n],
            residual_primal: vec![0.0; max_rows],
            dx: vec![0.0; n],
            ds: vec![0.0; max_rows],
            dl: vec![0.0; max_rows],
            ds_aff: vec![0.0; max_rows],
            dl_aff: vec![0.0; max_rows],
            rhs_rows: vec![0.0; max_rows],
            transpose_product: vec![0.0; n],
            inverse_slack: vec![0.0; max_rows],
            term_scales: [0.0; 3],
        }
    }

    fn n(&self) -> usize {
        self.hessian.n
    }

    /// `out = Cᵀ v` over the active rows.
    fn add_transpose_product(rows: &[SparseRow], v: &[f64], out: &mut [f64]) {
        for (row, &vi) in rows.iter().zip(v.iter()) {
            for e in 0..row.len {
                out[row.columns[e]] += row.values[e] * vi;
            }
        }
    }

    fn compute_residuals(&mut self) {
        let m = self.row_count;
        let inf_norm = |v: &[f64]| v.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        self.hessian.mul_vec(&self.x, &mut self.residual_dual);
        let hessian_term = inf_norm(&self.residual_dual);
        self.transpose_product.iter_mut().for_each(|v| *v = 0.0);
        Self::add_transpose_product(
            &self.rows[..m],
            &self.multiplier[..m],
            &mut self.transpose_product,
        );
        let transpose_term = inf_norm(&self.transpose_product);
        for ((r, g), t) in self
            .residual_dual
            .iter_mut()
            .zip(self.gradient.iter())
            .zip(self.transpose_product.iter())
        {
            *r += g + t;
        }
        let mut row_term: f64 = 0.0;
        for i in 0..m {
            let row = &self.rows[i];
            let cx = row.dot(&self.x);
            row_term = row_term.max(cx.abs());
            self.residual_primal[i] = cx + self.slack[i] - row.bound;
        }
        self.term_scales = [hessian_term, transpose_term, row_term];
    }

    /// Solves the Newton system for right-hand side `rc` (complementarity residual, in `rhs_rows`),
    /// writing `dx`, `ds`, `dl`. The factorization must be current.
    fn newton_direction(&mut self) {
        let m = self.row_count;
        // KΔx = −rd + Cᵀ((rc − λ∘rp)/s)
        for i in 0..m {
            self.ds[i] = (self.rhs_rows[i] - self.multiplier[i] * self.residual_primal[i])
                * self.inverse_slack[i];
        }
        for (d, r) in self.dx.iter_mut().zip(self.residual_dual.iter()) {
            *d = -r;
        }
        Self::add_transpose_product(&self.rows[..m], &self.ds[..m], &mut self.dx);
        self.newton.cholesky_solve(&mut self.dx);
        for i in 0..m {
            let c_dx = self.rows[i].dot(&self.dx);
            self.ds[i] = -self.residual_primal[i] - c_dx;
            self.dl[i] =
                (-self.rhs_rows[i] - self.multiplier[i] * self.ds[i]) * self.inverse_slack[i];
        }
    }

    fn max_step(values: &[f64], steps: &[f64]) -> f64 {
        let mut alpha: f64 = 1.0;
        for (&v, &d) in values.iter().zip(steps.iter()) {
            // divide only when this entry limits the step further
            if d < 0.0 && v < alpha * -d {
                alpha = -v / d;
            }
        }
        alpha
    }

    /// Factorises the Newton matrix assembled in `newton`; when round-off makes it numerically
    /// indefinite (multipliers/slacks ratios near 1e16 at the end of a degenerate solve), retries with a
    /// growing diagonal shift relative to its largest diagonal entry (a primal regularisation that only
    /// damps the step). Returns false when even the largest shift fails.
    fn factor_newton_regularized(&mut self) -> bool {
        let n = self.n();
        let largest = (0..n).fold(0.0_f64, |a, i| a.max(self.newton.diagonal(i).abs()));
        for shift in [0.0, 1e-14, 1e-12, 1e-10, 1e-8] {
            if shift > 0.0 {
                // the failed factorization overwrote the band: reassemble, then shift the diagonal
                self.assemble_newton();
                for i in 0..n {
                    self.newton.add_diagonal(i, shift * largest);
                }
            }
            if self.newton.cholesky_in_place() {
                return true;
            }
        }
        false
    }

    /// Newton matrix `K = P + Cᵀ diag(λ/s) C` into `newton`.
    fn assemble_newton(&mut self) {
        let m = self.row_count;
        self.newton.copy_from(&self.hessian);
        for i in 0..m {
            self.inverse_slack[i] = 1.0 / self.slack[i];
            let w = self.multiplier[i] * self.inverse_slack[i];
            let row = self.rows[i];
            for a in 0..row.len {
                for b in 0..=a {
                    self.newton.add(
                        row.columns[a],
                        row.columns[b],
                        w * row.values[a] * row.values[b],
                    );
                }
            }
        }
    }

    /// Solves the QP; on return `x`, `slack`, `multiplier` hold the solution. Returns the outcome and
    /// the number of iterations.
    pub(crate) fn solve(&mut self, settings: &IpmSettings) -> (IpmOutcome, u32) {
        let n = self.n();
        let m = self.row_count;
        // Unconstrained minimiser.
        self.newton.copy_from(&self.hessian);
        if !self.newton.cholesky_in_place() {
            return (IpmOutcome::NumericalError, 0);
        }
        for (x, g) in self.x.iter_mut().zip(self.gradient.iter()) {
            *x = -g;
        }
        self.newton.cholesky_solve(&mut self.x);
        if self.x.iter().any(|v| !v.is_finite()) {
            return (IpmOutcome::NumericalError, 0);
        }
        let mut min_slack = f64::INFINITY;
        for i in 0..m {
            let s = self.rows[i].bound - self.rows[i].dot(&self.x);
            self.slack[i] = s;
            min_slack = min_slack.min(s);
        }
        if m == 0 || min_slack >= 0.0 {
            self.multiplier[..m].iter_mut().for_each(|v| *v = 0.0);
            return (IpmOutcome::Unconstrained, 0);
        }
        // Infeasible start: positive slacks and multipliers (Mehrotra-style shift).
        let shift = (-1.5 * min_slack).max(0.0);
        let floor = 1e-4;
        for i in 0..m {
            self.slack[i] = (self.slack[i] + shift).max(floor);
            self.multiplier[i] = 1.0;
        }
        let scale_gradient = self
            .gradient
            .iter()
            .fold(0.0_f64, |a, v| a.max(v.abs()))
            .max(1.0);
        let scale_bound = self.rows[..m]
            .iter()
            .fold(0.0_f64, |a, r| a.max(r.bound.abs()))
            .max(1.0);
        let tol = settings.tolerance;
        let mut iterations = 0u32;
        loop {
            self.compute_residuals();
            let mu = self.slack[..m]
                .iter()
                .zip(self.multiplier[..m].iter())
                .map(|(s, l)| s * l)
                .sum::<f64>()
                / m as f64;
            let largest_product = self.slack[..m]
                .iter()
                .zip(self.multiplier[..m].iter())
                .fold(0.0_f64, |a, (s, l)| a.max((s * l).abs()));
            let largest_multiplier = self.multiplier[..m].iter().fold(0.0_f64, |a, l| a.max(*l));
            let dual_inf = self
                .residual_dual
                .iter()
                .fold(0.0_f64, |a, v| a.max(v.abs()));
            let primal_inf = self.residual_primal[..m]
                .iter()
                .fold(0.0_f64, |a, v| a.max(v.abs()));
            if !(mu.is_finite()
                && largest_product.is_finite()
                && dual_inf.is_finite()
                && primal_inf.is_finite())
            {
                return (IpmOutcome::NumericalError, iterations);
            }
            // Scale-invariant stopping rules: residuals relative to the largest term of their
            // equation; complementarity: no product above tol × 1 mm × the largest multiplier, i.e. a
            // row either has a slack below ~tol mm or a multiplier below tol × 1e-3 of the largest.
            let [hessian_term, transpose_term, row_term] = self.term_scales;
            let dual_scale = scale_gradient.max(hessian_term).max(transpose_term);
            let primal_scale = scale_bound.max(row_term);
            if dual_inf <= tol * dual_scale
                && primal_inf <= tol * primal_scale
                && largest_product <= tol * 1e-3 * largest_multiplier.max(tol * dual_scale)
            {
                return (IpmOutcome::Converged, iterations);
            }
            if iterations >= settings.max_iterations {
                return (IpmOutcome::MaxIterations, iterations);
            }
            iterations += 1;
            self.assemble_newton();
            if !self.factor_newton_regularized() {
                return (IpmOutcome::NumericalError, iterations);
            }
            // Predictor (affine scaling).
            for i in 0..m {
                self.rhs_rows[i] = self.slack[i] * self.multiplier[i];
            }
            self.newton_direction();
            let alpha_aff = Self::max_step(&self.slack[..m], &self.ds[..m])
                .min(Self::max_step(&self.multiplier[..m], &self.dl[..m]));
            let mut mu_aff = 0.0;
            for i in 0..m {
                mu_aff += (self.slack[i] + alpha_aff * self.ds[i])
                    * (self.multiplier[i] + alpha_aff * self.dl[i]);
            }
            mu_aff /= m as f64;
            let sigma = (mu_aff / mu).clamp(0.0, 1.0).powi(3);
            self.ds_aff[..m].copy_from_slice(&self.ds[..m]);
            self.dl_aff[..m].copy_from_slice(&self.dl[..m]);
            // Corrector.
            for i in 0..m {
                self.rhs_rows[i] = self.slack[i] * self.multiplier[i]
                    + self.ds_aff[i] * self.dl_aff[i]
                    - sigma * mu;
            }
            self.newton_direction();
            let alpha_max = Self::max_step(&self.slack[..m], &self.ds[..m])
                .min(Self::max_step(&self.multiplier[..m], &self.dl[..m]));
            let alpha = (0.99 * alpha_max).min(1.0);
            for j in 0..n {
                self.x[j] += alpha * self.dx[j];
            }
            for i in 0..m {
                self.slack[i] += alpha * self.ds[i];
                self.multiplier[i] += alpha * self.dl[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Deterministic pseudo-random numbers in [−1, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    #[test]
    fn band_kernels_match_dense_linear_algebra() {
        for n in [1, 3, 6, 7, 40] {
            let mut next = numbers(n as u64);
            let mut band = BandMatrix::new(n);
            let mut dense = DMatrix::zeros(n, n);
            for i in 0..n {
                for j in i.saturating_sub(BAND)..=i {
                    let v = if i == j { 10.0 + next().abs() } else { next() };
                    band.add(i, j, v);
                    dense[(i, j)] = v;
                    dense[(j, i)] = v;
                }
            }
            let x = DVector::from_fn(n, |_, _| next());
            let mut y = vec![0.0; n];
            band.mul_vec(x.as_slice(), &mut y);
            assert!((DVector::from_vec(y) - &dense * &x).amax() < 1e-12);
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(band.get(i, j), dense[(i, j)]);
                }
            }
            let b = DVector::from_fn(n, |_, _| next());
            assert!(band.cholesky_in_place());
            let mut solution = b.as_slice().to_vec();
            band.cholesky_solve(&mut solution);
            let expected = dense.cholesky().unwrap().solve(&b);
            assert!(
                (DVector::from_vec(solution) - expected).amax() < 1e-12,
                "n {n}"
            );
        }
        let mut indefinite = BandMatrix::new(3);
        indefinite.add(0, 0, 1.0);
        indefinite.add(1, 1, -1.0);
        indefinite.add(2, 2, 1.0);
        assert!(!indefinite.cholesky_in_place());
    }
}
