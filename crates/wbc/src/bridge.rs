//! From task blocks to stride-qp: every block becomes one [`stride_qp::TaskSpec`] spanning all the
//! controller's variables; each tick copies the numbers in and calls [`QpProblem::solve`], whose relaxed
//! fallback (hard equalities as soft costs with `relaxation_weight`) is used as stride-qp documents it.

use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use stride_qp::{
    Backend, QpProblem, QpSettings, QpStatus, SolvePath, TaskId, TaskSpec, VarId, VariableSet,
};

use crate::error::WbcError;
use crate::io::SolveReport;
use crate::tasks::{RowKind, TaskBlock};

/// Named decision variables of a controller.
#[derive(Debug, Clone)]
pub(crate) struct VariableLayout {
    pub set: VariableSet,
    pub ids: Vec<VarId>,
}

impl VariableLayout {
    pub fn new(vars: &[(&str, usize)]) -> Result<Self, WbcError> {
        let mut set = VariableSet::new();
        let mut ids = Vec::new();
        for (name, size) in vars {
            if *size > 0 {
                ids.push(set.add(name, *size)?);
            }
        }
        Ok(VariableLayout { set, ids })
    }
}

/// Null-space elimination of the hard equality rows (the fast path).
///
/// With `A_e x = b_e` (m rows, full row rank) factor `A_eᵀ = Q R` (Householder), then
/// `x = x_p + N z` with `x_p = Q₁ R⁻ᵀ b_e` and `N = Q₂` (orthonormal, nx × (nx − m)). Soft tasks become
/// `(A N) z = b − A x_p`, inequalities `l − C x_p ≤ (C N) z ≤ u − C x_p`, finite variable bounds rows of
/// `N`. The reduced QP has no equality constraint and `nx − m` variables.
struct Reduced {
    problem: QpProblem,
    /// Block index → reduced task id (None for hard equalities).
    task_of_block: Vec<Option<TaskId>>,
    bounds_task: TaskId,
    m: usize,
    nx: usize,
    /// `A_eᵀ` (nx × m), overwritten by the Householder vectors.
    at: DMatrix<f64>,
    tau: DVector<f64>,
    b_e: DVector<f64>,
    /// Q (nx × nx) and its transpose's columns: `nt` = Nᵀ (nz × nx) so that a row of N is contiguous.
    q: DMatrix<f64>,
    nt: DMatrix<f64>,
    y: DVector<f64>,
    x_p: DVector<f64>,
    z: DVector<f64>,
    /// Per block: `A N` and `A x_p`.
    scratch: Vec<(DMatrix<f64>, DVector<f64>)>,
}

/// Relative pivot threshold below which `A_e` is treated as rank deficient (full path instead).
const RANK_TOLERANCE: f64 = 1e-9;

impl Reduced {
    fn new(
        blocks: &[TaskBlock],
        nx: usize,
        settings: &QpSettings,
    ) -> Result<Option<Self>, WbcError> {
        let m: usize = blocks
            .iter()
            .filter(|b| b.kind == RowKind::Equality && b.hard)
            .map(|b| b.rows())
            .sum();
        if m == 0 || m >= nx {
            return Ok(None);
        }
        let nz = nx - m;
        let mut vars = VariableSet::new();
        let z = vars.add("null_space_coordinates", nz)?;
        let mut specs = Vec::new();
        let mut task_of_block = Vec::new();
        for b in blocks {
            match (b.kind, b.hard) {
                (RowKind::Equality, true) => task_of_block.push(None),
                (RowKind::Equality, false) => {
                    task_of_block.push(Some(TaskId(specs.len())));
                    specs.push(
                        TaskSpec::equality(&b.name, &[z], b.rows())
                            .soft_weights(b.weight.as_slice()),
                    );
                }
                (RowKind::Inequality, _) => {
                    task_of_block.push(Some(TaskId(specs.len())));
                    specs.push(TaskSpec::inequality(&b.name, &[z], b.rows()));
                }
            }
        }
        let bounds_task = TaskId(specs.len());
        specs.push(TaskSpec::inequality("variable_bounds", &[z], nx));
        let mut settings = settings.clone();
        // no hard equality is left to relax: failures go to the full problem
        settings.fallback = false;
        // measured: on these equality-free problems the dual active-set solver's cold start (from the
        // unconstrained minimum) is faster than re-imposing the previous active set (IK 7 µs vs 87 µs,
        // TSID 41 µs vs 68 µs on the bundled model)
        settings.active_set.warm_start = false;
        let mut problem = QpProblem::new(vars, specs, settings)?;
        let _ = problem.solve();
        problem.reset_warm_start();
        Ok(Some(Reduced {
            problem,
            task_of_block,
            bounds_task,
            m,
            nx,
            at: DMatrix::zeros(nx, m),
            tau: DVector::zeros(m),
            b_e: DVector::zeros(m),
            q: DMatrix::zeros(nx, nx),
            nt: DMatrix::zeros(nz, nx),
            y: DVector::zeros(m),
            x_p: DVector::zeros(nx),
            z: DVector::zeros(nz),
            scratch: blocks
                .iter()
                .map(|b| (DMatrix::zeros(nz, b.rows()), DVector::zeros(b.rows())))
                .collect(),
        }))
    }

    /// Householder QR of `A_eᵀ`; returns false when rank deficient. Column-slice loops (contiguous).
    fn factor(&mut self, blocks: &[TaskBlock]) -> bool {
        let (nx, m) = (self.nx, self.m);
        let mut row = 0;
        for b in blocks
            .iter()
            .filter(|b| b.kind == RowKind::Equality && b.hard)
        {
            for i in 0..b.rows() {
                for j in 0..nx {
                    self.at[(j, row)] = b.a[(i, j)];
                }
                self.b_e[row] = b.b[i];
                row += 1;
            }
        }
        let at = self.at.as_mut_slice();
        let mut max_diag: f64 = 0.0;
        for k in 0..m {
            let (done, rest) = at.split_at_mut((k + 1) * nx);
            let vk = &mut done[k * nx + k..(k + 1) * nx];
            let norm = vk.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 {
                return false;
            }
            let alpha = if vk[0] > 0.0 { -norm } else { norm };
            vk[0] -= alpha;
            let vnorm2: f64 = vk.iter().map(|v| v * v).sum();
            let tau = if vnorm2 > 0.0 { 2.0 / vnorm2 } else { 0.0 };
            self.tau[k] = tau;
            for c in 0..(m - k - 1) {
                let col = &mut rest[c * nx + k..(c + 1) * nx];
                let dot: f64 = vk.iter().zip(col.iter()).map(|(a, b)| a * b).sum();
                let f = tau * dot;
                for (x, v) in col.iter_mut().zip(vk.iter()) {
                    *x -= f * v;
                }
            }
            self.y[k] = alpha;
            max_diag = max_diag.max(alpha.abs());
        }
        for k in 0..m {
            if self.y[k].abs() <= RANK_TOLERANCE * max_diag {
                return false;
            }
        }
        // Q = H_0 … H_{m−1} I
        let q = self.q.as_mut_slice();
        q.fill(0.0);
        for i in 0..nx {
            q[i * nx + i] = 1.0;
        }
        for k in (0..m).rev() {
            let vk = &at[k * nx + k..(k + 1) * nx];
            let tau = self.tau[k];
            // columns c < k of H_{k+1}…I are unit vectors e_c with zero rows ≥ k+1… only rows ≥ k matter
            for c in k..nx {
                let col = &mut q[c * nx + k..(c + 1) * nx];
                let dot: f64 = vk.iter().zip(col.iter()).map(|(a, b)| a * b).sum();
                if dot != 0.0 {
                    let f = tau * dot;
                    for (x, v) in col.iter_mut().zip(vk.iter()) {
                        *x -= f * v;
                    }
                }
            }
        }
        // forward substitution Rᵀ y = b_e (R: diagonal in y, strict upper part in at); y overwrites b_e
        for k in 0..m {
            let mut s = self.b_e[k];
            for j in 0..k {
                s -= at[k * nx + j] * self.b_e[j];
            }
            self.b_e[k] = s / self.y[k];
        }
        // x_p = Q₁ y
        self.x_p.fill(0.0);
        for k in 0..m {
            let yk = self.b_e[k];
            let col = &q[k * nx..(k + 1) * nx];
            for (x, c) in self.x_p.as_mut_slice().iter_mut().zip(col.iter()) {
                *x += yk * c;
            }
        }
        // Nᵀ (nz × nx): entry (r, j) = Q[j, m + r]
        let nz = nx - m;
        let nt = self.nt.as_mut_slice();
        for j in 0..nx {
            for r in 0..nz {
                nt[j * nz + r] = q[(m + r) * nx + j];
            }
        }
        true
    }

    /// `out_t = (A N)ᵀ` (nz × rows) and `shift = A x_p`, skipping zero entries of A.
    fn project(
        a: &DMatrix<f64>,
        nt: &DMatrix<f64>,
        x_p: &DVector<f64>,
        out_t: &mut DMatrix<f64>,
        shift: &mut [f64],
    ) {
        let nz = nt.nrows();
        let rows = a.nrows();
        let nt = nt.as_slice();
        let out = out_t.as_mut_slice();
        out.fill(0.0);
        shift.fill(0.0);
        let a_s = a.as_slice();
        for j in 0..a.ncols() {
            let ncol = &nt[j * nz..(j + 1) * nz];
            let acol = &a_s[j * rows..(j + 1) * rows];
            for (i, &v) in acol.iter().enumerate() {
                if v != 0.0 {
                    shift[i] += v * x_p[j];
                    for (o, n) in out[i * nz..(i + 1) * nz].iter_mut().zip(ncol.iter()) {
                        *o += v * n;
                    }
                }
            }
        }
    }

    /// Fills and solves the reduced problem; on success writes `x` and returns the solution status.
    fn solve(
        &mut self,
        blocks: &[TaskBlock],
        lower: &DVector<f64>,
        upper: &DVector<f64>,
        x: &mut DVector<f64>,
    ) -> Option<(QpStatus, usize)> {
        if !self.factor(blocks) {
            return None;
        }
        for (k, (b, id)) in blocks.iter().zip(&self.task_of_block).enumerate() {
            let Some(id) = *id else { continue };
            let (a_red, shift) = &mut self.scratch[k];
            Self::project(&b.a, &self.nt, &self.x_p, a_red, shift.as_mut_slice());
            let t = self.problem.task_mut(id);
            t.a_mut().tr_copy_from(a_red);
            match b.kind {
                RowKind::Equality => {
                    let rhs = t.b_mut();
                    for i in 0..b.rows() {
                        rhs[i] = b.b[i] - shift[i];
                    }
                }
                RowKind::Inequality => {
                    for i in 0..b.rows() {
                        t.lower_mut()[i] = b.lower[i] - shift[i];
                        t.upper_mut()[i] = b.upper[i] - shift[i];
                    }
                }
            }
        }
        {
            let nz = self.nx - self.m;
            let t = self.problem.task_mut(self.bounds_task);
            let _ = nz;
            t.a_mut().tr_copy_from(&self.nt);
            for j in 0..self.nx {
                t.lower_mut()[j] = lower[j] - self.x_p[j];
                t.upper_mut()[j] = upper[j] - self.x_p[j];
            }
        }
        let ok = self.problem.solve().is_ok();
        let sol = self.problem.solution();
        // anything short of an exact solve goes to the full problem
        if !ok || sol.status != QpStatus::Solved || !sol.x.iter().all(|v| v.is_finite()) {
            return None;
        }
        self.z.copy_from(&sol.x);
        // x = x_p + N z
        for j in 0..self.nx {
            let mut s = self.x_p[j];
            for r in 0..self.z.len() {
                s += self.nt[(r, j)] * self.z[r];
            }
            x[j] = s;
        }
        Some((sol.status, sol.iterations))
    }
}

/// One QP of fixed structure (the blocks given at construction): the reduced (null-space) problem as
/// the fast path, the full stride-qp problem (with its relaxed fallback) when the reduction is not
/// possible (rank-deficient hard rows) or fails (e.g. infeasible inequalities).
pub(crate) struct QpBridge {
    problem: QpProblem,
    tasks: Vec<TaskId>,
    ids: Vec<VarId>,
    reduced: Option<Reduced>,
    used_reduced: bool,
}

impl QpBridge {
    pub fn new(
        layout: VariableLayout,
        blocks: &[TaskBlock],
        settings: &QpSettings,
        eliminate: bool,
    ) -> Result<Self, WbcError> {
        let nx = layout.set.total_size();
        let mut specs = Vec::with_capacity(blocks.len());
        for b in blocks {
            if b.a.ncols() != nx {
                return Err(WbcError::InvalidConfig {
                    task: b.name.clone(),
                    key: "type",
                    reason: format!("block has {} columns, the QP {nx}", b.a.ncols()),
                });
            }
            let spec = match b.kind {
                RowKind::Equality => {
                    let s = TaskSpec::equality(&b.name, &layout.ids, b.rows());
                    if b.hard {
                        s
                    } else {
                        s.soft_weights(b.weight.as_slice())
                    }
                }
                RowKind::Inequality => TaskSpec::inequality(&b.name, &layout.ids, b.rows()),
            };
            specs.push(spec);
        }
        let mut problem = QpProblem::new(layout.set.clone(), specs, settings.clone())?;
        let tasks: Vec<TaskId> = (0..blocks.len()).map(TaskId).collect();
        // Prime the backends: their workspaces are sized at the first solve, so solve once here, with an
        // inconsistent hard row `0 = 1` so that the relaxed (fallback) backend is sized too; then forget
        // everything. After this no tick allocates, whichever path it takes.
        if let Some(k) = blocks
            .iter()
            .position(|b| b.kind == RowKind::Equality && b.hard)
        {
            problem.task_mut(tasks[k]).b_mut()[0] = 1.0;
            let _ = problem.solve();
            problem.task_mut(tasks[k]).b_mut()[0] = 0.0;
        }
        let _ = problem.solve();
        problem.reset_warm_start();
        // the reduction is the active-set fast path; clarabel (the reference) solves the full problem
        let reduced = if eliminate && settings.backend == Backend::ActiveSet {
            Reduced::new(blocks, nx, settings)?
        } else {
            None
        };
        Ok(QpBridge {
            problem,
            tasks,
            ids: layout.ids,
            reduced,
            used_reduced: false,
        })
    }

    /// The stride-qp problem solved last: the reduced one (variable `null_space_coordinates`) or the
    /// full one (data, solution, KKT check).
    pub fn problem(&self) -> &QpProblem {
        match (&self.reduced, self.used_reduced) {
            (Some(r), true) => &r.problem,
            _ => &self.problem,
        }
    }

    /// Sets the weights of soft block `k` (one value or one per row) in both problems.
    pub fn set_weights(&mut self, k: usize, weights: &[f64]) -> Result<(), WbcError> {
        self.problem.task_mut(self.tasks[k]).set_weights(weights)?;
        if let Some(r) = &mut self.reduced {
            if let Some(id) = r.task_of_block[k] {
                r.problem.task_mut(id).set_weights(weights)?;
            }
        }
        Ok(())
    }

    pub fn reset(&mut self) {
        self.problem.reset_warm_start();
        if let Some(r) = &mut self.reduced {
            r.problem.reset_warm_start();
        }
    }

    /// Solves (reduced path first); on success writes `x`. When the full problem's nominal and relaxed
    /// solves both fail `x` is left untouched and `held` is set.
    pub fn solve(
        &mut self,
        blocks: &[TaskBlock],
        lower: &DVector<f64>,
        upper: &DVector<f64>,
        x: &mut DVector<f64>,
    ) -> SolveReport {
        let start = Instant::now();
        if let Some(r) = &mut self.reduced {
            if let Some((status, iterations)) = r.solve(blocks, lower, upper, x) {
                self.used_reduced = true;
                return SolveReport {
                    status,
                    relaxed_status: None,
                    iterations,
                    solve_time: start.elapsed().as_secs_f64(),
                    tick_time: 0.0,
                    fallback: false,
                    held: false,
                };
            }
        }
        self.used_reduced = false;
        for (b, &id) in blocks.iter().zip(&self.tasks) {
            let t = self.problem.task_mut(id);
            t.a_mut().copy_from(&b.a);
            match b.kind {
                RowKind::Equality => t.b_mut().copy_from(&b.b),
                RowKind::Inequality => {
                    t.lower_mut().copy_from(&b.lower);
                    t.upper_mut().copy_from(&b.upper);
                }
            }
        }
        let mut offset = 0;
        for k in 0..self.ids.len() {
            let id = self.ids[k];
            let mut lb = self.problem.lower_bounds_mut(id);
            let len = lb.len();
            lb.copy_from(&lower.rows(offset, len));
            self.problem
                .upper_bounds_mut(id)
                .copy_from(&upper.rows(offset, len));
            offset += len;
        }
        let ok = self.problem.solve().is_ok();
        let sol = self.problem.solution();
        let mut report = SolveReport {
            status: sol.nominal_status,
            relaxed_status: None,
            iterations: sol.iterations,
            solve_time: start.elapsed().as_secs_f64(),
            tick_time: 0.0,
            fallback: false,
            held: false,
        };
        if sol.path == SolvePath::Relaxed {
            report.relaxed_status = Some(sol.status);
        }
        if ok && sol.x.iter().all(|v| v.is_finite()) {
            x.copy_from(&sol.x);
            report.fallback = sol.path == SolvePath::Relaxed;
        } else {
            report.held = true;
        }
        report
    }
}
