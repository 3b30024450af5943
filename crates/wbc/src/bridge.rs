//! From task blocks to stride-qp: every block becomes one [`stride_qp::TaskSpec`] spanning all the
//! controller's variables; each tick copies the numbers in and calls [`QpProblem::solve`], whose relaxed
//! fallback (hard equalities as soft costs with `relaxation_weight`) is used as stride-qp documents it.

use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use stride_qp::{QpProblem, QpSettings, QpStatus, SolvePath, TaskId, TaskSpec, VarId, VariableSet};

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
}

/// Relative pivot threshold below which `A_e` is treated as rank deficient (full path instead).
const RANK_TOLERANCE: f64 = 1e-9;

impl Reduced {
    fn new(blocks: &[TaskBlock], nx: usize, settings: &QpSettings) -> Result<Option<Self>, WbcError> {
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
                        TaskSpec::equality(&b.name, &[z], b.rows()).soft_weights(b.weight.as_slice()),
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
        }))
    }

    /// Householder QR of `A_eᵀ`; returns false when rank deficient.
    fn factor(&mut self, blocks: &[TaskBlock]) -> bool {
        let (nx, m) = (self.nx, self.m);
        let mut row = 0;
        for b in blocks.iter().filter(|b| b.kind == RowKind::Equality && b.hard) {
            for i in 0..b.rows() {
                for j in 0..nx {
                    self.at[(j, row)] = b.a[(i, j)];
                }
                self.b_e[row] = b.b[i];
                row += 1;
            }
        }
        // Householder: column k, reflect rows k..nx
        let mut max_diag: f64 = 0.0;
        for k in 0..m {
            let mut norm = 0.0;
            for i in k..nx {
                norm += self.at[(i, k)] * self.at[(i, k)];
            }
            let norm = norm.sqrt();
            let alpha = if self.at[(k, k)] > 0.0 { -norm } else { norm };
            if norm == 0.0 {
                return false;
            }
            // v = x − alpha e1, stored in place with v_k = x_k − alpha
            self.at[(k, k)] -= alpha;
            let mut vnorm2 = 0.0;
            for i in k..nx {
                vnorm2 += self.at[(i, k)] * self.at[(i, k)];
            }
            self.tau[k] = if vnorm2 > 0.0 { 2.0 / vnorm2 } else { 0.0 };
            // apply to the remaining columns
            for c in (k + 1)..m {
                let mut dot = 0.0;
                for i in k..nx {
                    dot += self.at[(i, k)] * self.at[(i, c)];
                }
                let f = self.tau[k] * dot;
                for i in k..nx {
                    let v = self.at[(i, k)];
                    self.at[(i, c)] -= f * v;
                }
            }
            // R_kk = alpha; keep it in y temporarily
            self.y[k] = alpha;
            max_diag = max_diag.max(alpha.abs());
        }
        for k in 0..m {
            if self.y[k].abs() <= RANK_TOLERANCE * max_diag {
                return false;
            }
        }
        // Q = H_0 … H_{m−1} applied to the identity
        self.q.fill(0.0);
        for i in 0..nx {
            self.q[(i, i)] = 1.0;
        }
        for k in (0..m).rev() {
            for c in 0..nx {
                let mut dot = 0.0;
                for i in k..nx {
                    dot += self.at[(i, k)] * self.q[(i, c)];
                }
                let f = self.tau[k] * dot;
                if f != 0.0 {
                    for i in k..nx {
                        let v = self.at[(i, k)];
                        self.q[(i, c)] -= f * v;
                    }
                }
            }
        }
        // forward substitution Rᵀ y = b_e (R upper: diag in y, strict upper in at above the diagonal)
        for k in 0..m {
            let mut s = self.b_e[k];
            for j in 0..k {
                s -= self.at[(j, k)] * self.tau_y(j);
            }
            let d = self.y[k];
            // store the solution in b_e (its entry k is no longer needed)
            self.b_e[k] = s / d;
        }
        // x_p = Q₁ y
        for i in 0..nx {
            let mut s = 0.0;
            for k in 0..m {
                s += self.q[(i, k)] * self.b_e[k];
            }
            self.x_p[i] = s;
        }
        // Nᵀ
        let nz = nx - m;
        for r in 0..nz {
            for j in 0..nx {
                self.nt[(r, j)] = self.q[(j, m + r)];
            }
        }
        true
    }

    /// Solution entry `j` of the forward substitution (kept in `b_e`).
    fn tau_y(&self, j: usize) -> f64 {
        self.b_e[j]
    }

    /// `out = A N` (rows × nz) and `rhs = b − A x_p`, skipping zero entries of A.
    fn project(
        a: &DMatrix<f64>,
        nt: &DMatrix<f64>,
        x_p: &DVector<f64>,
        out: &mut DMatrix<f64>,
        shift: &mut [f64],
    ) {
        out.fill(0.0);
        let nz = nt.nrows();
        for i in 0..a.nrows() {
            let mut ax = 0.0;
            for j in 0..a.ncols() {
                let v = a[(i, j)];
                if v != 0.0 {
                    ax += v * x_p[j];
                    for r in 0..nz {
                        out[(i, r)] += v * nt[(r, j)];
                    }
                }
            }
            shift[i] = ax;
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
        for (b, id) in blocks.iter().zip(&self.task_of_block) {
            let Some(id) = *id else { continue };
            let t = self.problem.task_mut(id);
            // reuse the task's b/lower buffer as the shift A x_p
            match b.kind {
                RowKind::Equality => {
                    let (a_out, b_out) = t.a_and_b_mut();
                    Self::project(&b.a, &self.nt, &self.x_p, a_out, b_out.as_mut_slice());
                    for i in 0..b.rows() {
                        b_out[i] = b.b[i] - b_out[i];
                    }
                }
                RowKind::Inequality => {
                    let (a_out, lo, hi) = t.a_lower_upper_mut();
                    Self::project(&b.a, &self.nt, &self.x_p, a_out, lo.as_mut_slice());
                    for i in 0..b.rows() {
                        let shift = lo[i];
                        lo[i] = b.lower[i] - shift;
                        hi[i] = b.upper[i] - shift;
                    }
                }
            }
        }
        {
            let nz = self.nx - self.m;
            let t = self.problem.task_mut(self.bounds_task);
            let (a_out, lo, hi) = t.a_lower_upper_mut();
            for j in 0..self.nx {
                for r in 0..nz {
                    a_out[(j, r)] = self.nt[(r, j)];
                }
                lo[j] = lower[j] - self.x_p[j];
                hi[j] = upper[j] - self.x_p[j];
            }
        }
        let ok = self.problem.solve().is_ok();
        let sol = self.problem.solution();
        if !ok || !sol.x.iter().all(|v| v.is_finite()) {
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
        let reduced = if eliminate {
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
