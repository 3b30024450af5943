//! The reference paths: a [`BandedQp`] solved by clarabel, directly or through stride-qp's sparse
//! backend (both allocate on every call; they check the banded interior-point method).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};

use super::ipm::BandedOutcome;
use super::problem::BandedQp;
use super::rows::MAX_ROW_ENTRIES;
use crate::clarabel_backend::ClarabelSparseSolver;
use crate::sparse::SparseQp;
use crate::status::QpStatus;

impl BandedQp {
    /// Solves the QP with clarabel called directly (`tolerance` is its `tol_gap_abs`, `tol_gap_rel`
    /// and `tol_feas`, other settings at clarabel's defaults); on return [`BandedQp::x`],
    /// [`BandedQp::multipliers`] and [`BandedQp::slacks`] hold its solution. Allocates. Returns the
    /// outcome and clarabel's iterations.
    pub fn solve_with_clarabel(
        &mut self,
        tolerance: f64,
        max_iterations: u32,
    ) -> (BandedOutcome, u32) {
        let n = self.x.len();
        let m = self.row_count;
        // P upper triangle, column by column.
        let mut colptr = Vec::with_capacity(n + 1);
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        colptr.push(0);
        for j in 0..n {
            for i in j.saturating_sub(self.hessian.bandwidth())..=j {
                let v = self.hessian.get(j, i);
                if v != 0.0 {
                    rowval.push(i);
                    nzval.push(v);
                }
            }
            colptr.push(rowval.len());
        }
        let p = CscMatrix::new(n, n, colptr, rowval, nzval);
        let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
        for (i, row) in self.sparse_rows().enumerate() {
            for e in 0..row.len {
                triplets.push((row.columns[e], i, row.values[e]));
            }
        }
        triplets.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut colptr = vec![0usize; n + 1];
        for &(col, _, _) in &triplets {
            colptr[col + 1] += 1;
        }
        for j in 0..n {
            colptr[j + 1] += colptr[j];
        }
        let rowval: Vec<usize> = triplets.iter().map(|t| t.1).collect();
        let nzval: Vec<f64> = triplets.iter().map(|t| t.2).collect();
        let a = CscMatrix::new(m, n, colptr, rowval, nzval);
        let b: Vec<f64> = self.sparse_rows().map(|r| r.bound).collect();
        let cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(m)];
        let Ok(settings) = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(max_iterations)
            .tol_gap_abs(tolerance)
            .tol_gap_rel(tolerance)
            .tol_feas(tolerance)
            .build()
        else {
            return (BandedOutcome::NumericalError, 0);
        };
        let Ok(mut solver) = DefaultSolver::new(&p, &self.gradient, &a, &b, &cones, settings)
        else {
            return (BandedOutcome::NumericalError, 0);
        };
        solver.solve();
        let iterations = solver.solution.iterations;
        let outcome = match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => BandedOutcome::Converged,
            SolverStatus::MaxIterations | SolverStatus::MaxTime => BandedOutcome::MaxIterations,
            _ => BandedOutcome::NumericalError,
        };
        self.x.copy_from_slice(&solver.solution.x);
        self.multiplier[..m].copy_from_slice(&solver.solution.z);
        self.slack[..m].copy_from_slice(&solver.solution.s);
        (outcome, iterations)
    }

    /// Solves the QP as a [`SparseQp`] with `solver` (which reuses its clarabel object while the
    /// sparsity pattern repeats); on return [`BandedQp::x`] and [`BandedQp::multipliers`] hold its
    /// solution (the slacks are not written). Allocates. Returns the outcome and the iterations.
    pub fn solve_with_sparse_clarabel(
        &mut self,
        solver: &mut ClarabelSparseSolver,
    ) -> (BandedOutcome, u32) {
        let n = self.x.len();
        let m = self.row_count;
        let mut sparse = SparseQp::new(n, 0);
        for j in 0..n {
            for i in j.saturating_sub(self.hessian.bandwidth())..=j {
                let v = self.hessian.get(j, i);
                if v != 0.0 {
                    sparse.hessian.push((i, j, v));
                }
            }
        }
        sparse.gradient.copy_from_slice(&self.gradient);
        let mut entries = [(0usize, 0.0f64); MAX_ROW_ENTRIES];
        for row in self.sparse_rows() {
            for (slot, (&c, &v)) in entries
                .iter_mut()
                .zip(row.columns.iter().zip(row.values.iter()))
            {
                *slot = (c, v);
            }
            sparse.add_row(&entries[..row.len], f64::NEG_INFINITY, row.bound);
        }
        let Ok(solution) = solver.solve(&sparse) else {
            return (BandedOutcome::NumericalError, 0);
        };
        let iterations = u32::try_from(solution.iterations).unwrap_or(u32::MAX);
        let outcome = match solution.status {
            QpStatus::Solved | QpStatus::SolvedInaccurate => BandedOutcome::Converged,
            QpStatus::MaxIterations => BandedOutcome::MaxIterations,
            _ => BandedOutcome::NumericalError,
        };
        if solution.x.len() != n || solution.multipliers.len() != m {
            return (BandedOutcome::NumericalError, iterations);
        }
        self.x.copy_from_slice(&solution.x);
        self.multiplier[..m].copy_from_slice(&solution.multipliers);
        (outcome, iterations)
    }
}
