//! The interior-point method on a [`BandedQp`].

// Band algorithms index several arrays with the same loop counter; ranges read like the maths.
#![allow(clippy::needless_range_loop)]

use super::problem::BandedQp;
use crate::status::QpStatus;

/// Outcome of [`BandedQp::solve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandedOutcome {
    /// The unconstrained minimiser was feasible: it is the solution (no iteration).
    Unconstrained,
    /// Converged to the tolerances.
    Converged,
    /// Hit the iteration limit.
    MaxIterations,
    /// A Newton matrix was not positive definite or a value became non-finite.
    NumericalError,
}

impl From<BandedOutcome> for QpStatus {
    /// The backend-independent status: an unconstrained or converged solve is [`QpStatus::Solved`].
    fn from(outcome: BandedOutcome) -> Self {
        match outcome {
            BandedOutcome::Unconstrained | BandedOutcome::Converged => QpStatus::Solved,
            BandedOutcome::MaxIterations => QpStatus::MaxIterations,
            BandedOutcome::NumericalError => QpStatus::NumericalError,
        }
    }
}

/// Settings of the interior-point method.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `tolerance` | – | scaled residuals and complementarity, see [`BandedQp::solve`] |
/// | `max_iterations` | – | interior-point iteration limit |
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandedSettings {
    /// Tolerance on the scaled residuals and on complementarity (dimensionless).
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: u32,
}

/// Smallest slack of a warm start (units of the rows: metres for the DCM MPC's unit-normal polygon
/// rows). Chosen on pushed walks (docs/simplified.md): 1 mm–3 mm floors gave the fewest iterations.
const WARM_SLACK_FLOOR: f64 = 3e-3;

/// Smallest multiplier of a warm start (cost units per row unit; the DCM MPC's multipliers are
/// ~0.1 when active, in units of `Λ_ξ`).
const WARM_MULTIPLIER_FLOOR: f64 = 1e-5;

impl BandedQp {
    /// Residuals `rd = Px + q + Cᵀλ`, `rp = Cx + s − d` at the current iterate, with the quantities
    /// the stopping rules and the step need (one pass over the rows).
    fn compute_residuals(&mut self) -> ResidualSummary {
        let mut summary = ResidualSummary::default();
        self.hessian.mul_vec(&self.x, &mut self.residual_dual);
        self.transpose_product.iter_mut().for_each(|v| *v = 0.0);
        for g in &self.groups[..self.group_count] {
            let z = g.point(&self.x);
            let mut weighted_normals = [0.0; 2];
            for i in g.first_row..g.end_row {
                let row = &self.rows[i];
                let (s, l) = (self.slack[i], self.multiplier[i]);
                let cx = row.dot(z);
                let rp = cx + s - row.bound;
                self.residual_primal[i] = rp;
                weighted_normals[0] += row.normal[0] * l;
                weighted_normals[1] += row.normal[1] * l;
                summary.row_term = summary.row_term.max(cx.abs());
                summary.primal_inf = summary.primal_inf.max(rp.abs());
                let product = s * l;
                summary.product_sum += product;
                summary.largest_product = summary.largest_product.max(product.abs());
                summary.largest_multiplier = summary.largest_multiplier.max(l);
            }
            g.add_transpose(weighted_normals, &mut self.transpose_product);
        }
        for ((r, g), t) in self
            .residual_dual
            .iter_mut()
            .zip(self.gradient.iter())
            .zip(self.transpose_product.iter())
        {
            summary.hessian_term = summary.hessian_term.max(r.abs());
            summary.transpose_term = summary.transpose_term.max(t.abs());
            *r += g + t;
            summary.dual_inf = summary.dual_inf.max(r.abs());
        }
        summary
    }

    /// Solves the Newton system for the complementarity right-hand side `rc = s∘λ` (predictor,
    /// `centering = None`) or `rc = s∘λ + Δs_aff∘Δλ_aff − σμ` (corrector, `centering = Some(σμ)`),
    /// writing `dx`, `ds`, `dl`; returns the largest step in (0, 1] keeping `s` and `λ` non-negative.
    /// The factorization must be current.
    fn newton_direction(&mut self, centering: Option<f64>) -> f64 {
        // KΔx = −rd + Cᵀ((rc − λ∘rp)/s)
        for (d, r) in self.dx.iter_mut().zip(self.residual_dual.iter()) {
            *d = -r;
        }
        for g in &self.groups[..self.group_count] {
            let mut sum = [0.0; 2];
            for i in g.first_row..g.end_row {
                let mut rc = self.slack[i] * self.multiplier[i];
                if let Some(sigma_mu) = centering {
                    rc += self.ds_aff[i] * self.dl_aff[i] - sigma_mu;
                }
                self.rhs_rows[i] = rc;
                let v = (rc - self.multiplier[i] * self.residual_primal[i]) * self.inverse_slack[i];
                sum[0] += self.rows[i].normal[0] * v;
                sum[1] += self.rows[i].normal[1] * v;
            }
            g.add_transpose(sum, &mut self.dx);
        }
        self.newton.cholesky_solve(&mut self.dx);
        let mut alpha: f64 = 1.0;
        for g in &self.groups[..self.group_count] {
            let dz = g.point(&self.dx);
            for i in g.first_row..g.end_row {
                let c_dx = self.rows[i].dot(dz);
                let ds = -self.residual_primal[i] - c_dx;
                let (s, l) = (self.slack[i], self.multiplier[i]);
                let dl = (-self.rhs_rows[i] - l * ds) * self.inverse_slack[i];
                self.ds[i] = ds;
                self.dl[i] = dl;
                // divide only when this entry limits the step further
                if ds < 0.0 && s < alpha * -ds {
                    alpha = -s / ds;
                }
                if dl < 0.0 && l < alpha * -dl {
                    alpha = -l / dl;
                }
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

    /// Newton matrix `K = P + Cᵀ diag(λ/s) C` into `newton`: per group, `Jᵀ (Σ_rows w n nᵀ) J`.
    fn assemble_newton(&mut self) {
        self.newton.copy_from(&self.hessian);
        for g in &self.groups[..self.group_count] {
            // M = Σ w n nᵀ (symmetric 2×2: xx, yx, yy)
            let mut m = [0.0; 3];
            for i in g.first_row..g.end_row {
                let inverse = 1.0 / self.slack[i];
                self.inverse_slack[i] = inverse;
                let w = self.multiplier[i] * inverse;
                let [nx, ny] = self.rows[i].normal;
                let (wx, wy) = (w * nx, w * ny);
                m[0] += wx * nx;
                m[1] += wy * nx;
                m[2] += wy * ny;
            }
            for t in 0..g.terms {
                let (ct, at) = (g.columns[t], g.coefficients[t]);
                for u in 0..g.terms {
                    let (cu, au) = (g.columns[u], g.coefficients[u]);
                    let f = at * au;
                    if cu < ct {
                        // a full 2×2 block below the diagonal
                        self.newton.add_unchecked(ct, cu, f * m[0]);
                        self.newton.add_unchecked(ct, cu + 1, f * m[1]);
                        self.newton.add_unchecked(ct + 1, cu, f * m[1]);
                        self.newton.add_unchecked(ct + 1, cu + 1, f * m[2]);
                    } else if cu == ct {
                        self.newton.add_diagonal(ct, f * m[0]);
                        self.newton.add_unchecked(ct + 1, ct, f * m[1]);
                        self.newton.add_diagonal(ct + 1, f * m[2]);
                    }
                }
            }
        }
    }

    /// Solves the QP; on return `x`, `slack`, `multiplier` hold the solution. Returns the outcome and
    /// the number of iterations.
    ///
    /// The unconstrained minimiser `−P⁻¹q` (factor of `P` reused while `P` is unchanged) is returned at
    /// once when it satisfies every row; otherwise Mehrotra's predictor–corrector iterates from the
    /// warm start, if armed, or from a shifted infeasible start [Nocedal 2006, §16.6; Mehrotra 1992].
    pub fn solve(&mut self, settings: &BandedSettings) -> (BandedOutcome, u32) {
        let m = self.row_count;
        let Some(min_slack) = self.unconstrained_minimiser() else {
            return (BandedOutcome::NumericalError, 0);
        };
        if m == 0 || min_slack >= 0.0 {
            self.multiplier[..m].iter_mut().for_each(|v| *v = 0.0);
            return (BandedOutcome::Unconstrained, 0);
        }
        self.initial_iterate(min_slack);
        self.iterate(settings)
    }

    /// `x = −P⁻¹q` (factorising `P` only when it changed) and the rows' slacks there; returns the
    /// smallest slack, or `None` when `P` is not positive definite or `x` is not finite.
    fn unconstrained_minimiser(&mut self) -> Option<f64> {
        if !self.hessian_factor_current {
            self.hessian_factor.copy_from(&self.hessian);
            if !self.hessian_factor.cholesky_in_place() {
                return None;
            }
            self.hessian_factor_current = true;
        }
        for (x, g) in self.x.iter_mut().zip(self.gradient.iter()) {
            *x = -g;
        }
        self.hessian_factor.cholesky_solve(&mut self.x);
        if self.x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut min_slack = f64::INFINITY;
        for g in &self.groups[..self.group_count] {
            let z = g.point(&self.x);
            for i in g.first_row..g.end_row {
                let s = self.rows[i].bound - self.rows[i].dot(z);
                self.slack[i] = s;
                min_slack = min_slack.min(s);
            }
        }
        Some(min_slack)
    }

    /// The first iterate of a constrained solve: the armed warm start (consumed here) with slacks and
    /// multipliers pushed into the interior, or the unconstrained minimiser with its slacks shifted by
    /// `1.5 × |min_slack|` and unit multipliers.
    fn initial_iterate(&mut self, min_slack: f64) {
        let m = self.row_count;
        if std::mem::take(&mut self.warm_start) {
            // Warm start: the given point, slacks and multipliers pushed into the interior.
            self.x.copy_from_slice(&self.start_x);
            for g in &self.groups[..self.group_count] {
                let z = g.point(&self.x);
                for i in g.first_row..g.end_row {
                    let s = self.rows[i].bound - self.rows[i].dot(z);
                    self.slack[i] = s.max(WARM_SLACK_FLOOR);
                    self.multiplier[i] = self.start_multiplier[i].max(WARM_MULTIPLIER_FLOOR);
                }
            }
        } else {
            // Infeasible start: positive slacks and multipliers (Mehrotra-style shift).
            let shift = (-1.5 * min_slack).max(0.0);
            let floor = 1e-4;
            for i in 0..m {
                self.slack[i] = (self.slack[i] + shift).max(floor);
                self.multiplier[i] = 1.0;
            }
        }
    }

    /// The predictor–corrector iterations from the current iterate until the stopping rules hold.
    fn iterate(&mut self, settings: &BandedSettings) -> (BandedOutcome, u32) {
        let n = self.n();
        let m = self.row_count;
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
        let mut initial_mu = None;
        loop {
            let r = self.compute_residuals();
            let mu = r.product_sum / m as f64;
            if !(mu.is_finite()
                && r.largest_product.is_finite()
                && r.dual_inf.is_finite()
                && r.primal_inf.is_finite())
            {
                return (BandedOutcome::NumericalError, iterations);
            }
            let initial_mu = *initial_mu.get_or_insert(mu);
            // Scale-invariant stopping rules: residuals relative to the largest term of their
            // equation; complementarity: no product above tol × 1 mm × the largest multiplier, i.e. a
            // row either has a slack below ~tol mm or a multiplier below tol × 1e-3 of the largest.
            let dual_scale = scale_gradient.max(r.hessian_term).max(r.transpose_term);
            let primal_scale = scale_bound.max(r.row_term);
            if r.dual_inf <= tol * dual_scale
                && r.primal_inf <= tol * primal_scale
                && r.largest_product <= tol * 1e-3 * r.largest_multiplier.max(tol * dual_scale)
            {
                return (BandedOutcome::Converged, iterations);
            }
            if iterations >= settings.max_iterations {
                return (BandedOutcome::MaxIterations, iterations);
            }
            iterations += 1;
            self.assemble_newton();
            if !self.factor_newton_regularized() {
                return (BandedOutcome::NumericalError, iterations);
            }
            // Predictor (affine scaling).
            let alpha_aff = self.newton_direction(None);
            let mut mu_aff = 0.0;
            for i in 0..m {
                mu_aff += (self.slack[i] + alpha_aff * self.ds[i])
                    * (self.multiplier[i] + alpha_aff * self.dl[i]);
            }
            mu_aff /= m as f64;
            let sigma = (mu_aff / mu).clamp(0.0, 1.0).powi(3);
            std::mem::swap(&mut self.ds, &mut self.ds_aff);
            std::mem::swap(&mut self.dl, &mut self.dl_aff);
            // Corrector.
            let alpha_max = self.newton_direction(Some(sigma * mu));
            // Fraction to the boundary: 0.99 at the start, tending to 1 as μ falls (the last
            // iterations then take full steps: quadratic-rate endgame instead of ×100 per iteration).
            let eta = 1.0 - 0.01 * (mu / initial_mu).sqrt().min(1.0);
            let alpha = (eta * alpha_max).min(1.0);
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

/// What the stopping rules need from one residual evaluation.
#[derive(Debug, Clone, Copy, Default)]
struct ResidualSummary {
    /// ‖rd‖∞ and ‖rp‖∞.
    dual_inf: f64,
    primal_inf: f64,
    /// Σ sᵢλᵢ, max |sᵢλᵢ|, max λᵢ.
    product_sum: f64,
    largest_product: f64,
    largest_multiplier: f64,
    /// Scales of the terms: ‖Px‖∞, ‖Cᵀλ‖∞, ‖Cx‖∞.
    hessian_term: f64,
    transpose_term: f64,
    row_term: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::banded::rows::{HalfPlaneRow, PointGroup};
    use crate::banded::test_numbers::numbers;
    use nalgebra::{DMatrix, DVector};

    /// Grouped half-plane rows: the Newton matrix, the residuals and the transpose products equal
    /// those of the expanded sparse rows computed densely.
    #[test]
    fn grouped_rows_match_their_dense_expansion() {
        let n = 12;
        let mut next = numbers(7);
        let mut qp = BandedQp::new(n, 6, 30);
        for i in 0..n {
            qp.hessian.add_unchecked(i, i, 3.0 + next().abs());
            if i >= 2 {
                qp.hessian.add_unchecked(i, i - 2, 0.3 * next());
            }
            qp.gradient[i] = next();
            qp.x[i] = next();
        }
        let mut row = 0;
        for k in 0..n / 2 {
            let mut g = PointGroup {
                first_row: row,
                ..PointGroup::default()
            };
            if k > 0 {
                g.columns[0] = 2 * (k - 1);
                g.coefficients[0] = next();
                g.terms = 1;
            }
            g.columns[g.terms] = 2 * k;
            g.coefficients[g.terms] = 2.0 + next();
            g.terms += 1;
            for _ in 0..(3 + k % 3) {
                let angle = 3.0 * next();
                qp.rows[row] = HalfPlaneRow {
                    normal: [angle.cos(), angle.sin()],
                    bound: next(),
                };
                qp.slack[row] = 0.5 + next().abs();
                qp.multiplier[row] = 0.1 + next().abs();
                row += 1;
            }
            g.end_row = row;
            qp.groups[k] = g;
        }
        qp.group_count = n / 2;
        qp.row_count = row;
        let mut dense_c = DMatrix::<f64>::zeros(row, n);
        let mut bounds = DVector::<f64>::zeros(row);
        for (i, r) in qp.sparse_rows().enumerate() {
            for e in 0..r.len {
                dense_c[(i, r.columns[e])] += r.values[e];
            }
            bounds[i] = r.bound;
        }
        let dense_p = DMatrix::<f64>::from_fn(n, n, |i, j| qp.hessian.get(i, j));
        let s = DVector::from_column_slice(&qp.slack[..row]);
        let l = DVector::from_column_slice(&qp.multiplier[..row]);
        let x = DVector::from_column_slice(&qp.x);
        let w = DMatrix::from_diagonal(&l.component_div(&s));
        let newton: DMatrix<f64> = &dense_p + dense_c.transpose() * w * &dense_c;
        qp.assemble_newton();
        for i in 0..n {
            for j in 0..n {
                assert!(
                    (qp.newton.get(i, j) - newton[(i, j)]).abs() < 1e-12,
                    "({i}, {j})"
                );
            }
        }
        let summary = qp.compute_residuals();
        let dual =
            &dense_p * &x + DVector::from_column_slice(&qp.gradient) + dense_c.transpose() * &l;
        let primal = &dense_c * &x + &s - &bounds;
        assert!((DVector::from_column_slice(&qp.residual_dual) - &dual).amax() < 1e-12);
        assert!((DVector::from_column_slice(&qp.residual_primal[..row]) - &primal).amax() < 1e-12);
        assert!((summary.dual_inf - dual.amax()).abs() < 1e-12);
        assert!((summary.primal_inf - primal.amax()).abs() < 1e-12);
        assert!((summary.product_sum - s.dot(&l)).abs() < 1e-12);
    }
}
