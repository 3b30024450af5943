//! The clarabel (interior-point) backend: dense problems through [`ClarabelSolver`], sparse ones through
//! [`ClarabelSparseSolver`].

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use serde::{Deserialize, Serialize};

use crate::dense::DenseQp;
use crate::error::QpError;
use crate::solver::{QpSolver, SolverOutput};
use crate::sparse::{SparseQp, SparseSolution};
use crate::status::QpStatus;

/// Settings of the clarabel backend.
///
/// | field | default | meaning |
/// |---|---|---|
/// | `tolerance` | `1e-10` | clarabel `tol_gap_abs`, `tol_gap_rel` and `tol_feas` |
/// | `max_iterations` | `200` | interior-point iteration limit |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClarabelSettings {
    /// Gap and feasibility tolerance (dimensionless).
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: u32,
}

impl Default for ClarabelSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 200,
        }
    }
}

impl ClarabelSettings {
    /// Clarabel settings; `equilibrate` switches its Ruiz equilibration (on for the first attempt, off for the
    /// retry, see [`ClarabelSolver`]).
    fn build(&self, equilibrate: bool) -> Result<DefaultSettings<f64>, QpError> {
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(QpError::InvalidSetting {
                name: "clarabel.tolerance",
                reason: format!("{} is not in (0, 1)", self.tolerance),
            });
        }
        DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(self.max_iterations)
            .tol_gap_abs(self.tolerance)
            .tol_gap_rel(self.tolerance)
            .tol_feas(self.tolerance)
            .presolve_enable(false)
            .equilibrate_enable(equilibrate)
            .build()
            .map_err(|e| QpError::ClarabelSetup(e.to_string()))
    }
}

/// Whether a failed clarabel solve is worth one retry without equilibration (it stalled or broke down;
/// infeasibility certificates are final).
fn worth_retry(status: QpStatus) -> bool {
    matches!(status, QpStatus::MaxIterations | QpStatus::NumericalError)
}

fn map_status(s: SolverStatus) -> QpStatus {
    match s {
        SolverStatus::Solved => QpStatus::Solved,
        SolverStatus::AlmostSolved => QpStatus::SolvedInaccurate,
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            QpStatus::Infeasible
        }
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => QpStatus::Unbounded,
        SolverStatus::MaxIterations | SolverStatus::MaxTime => QpStatus::MaxIterations,
        _ => QpStatus::NumericalError,
    }
}

/// One row of the clarabel constraint matrix, in terms of the dense problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Row {
    Eq(usize),
    IneqFixed(usize),
    BoundFixed(usize),
    IneqUpper(usize),
    IneqLower(usize),
    BoundUpper(usize),
    BoundLower(usize),
}

/// Dense-problem backend on clarabel (the reference solver).
///
/// Every two-sided row becomes up to two `NonnegativeCone` rows (infinite sides are left out); equality rows
/// and rows with `l = u` go into a `ZeroCone`. The clarabel solver object and its CSC pattern (all entries of
/// the dense blocks, zeros included, so the pattern never changes with the values) are kept between calls and
/// refreshed with `update_P/q/A/b`; they are rebuilt only when the set of finite sides changes. Clarabel cannot
/// warm start and allocates internally: this backend is the accuracy reference, not the 1 kHz path.
///
/// **Retry.** Clarabel's Ruiz equilibration occasionally stalls it on well-posed problems (found by the property
/// tests: about one random problem in 10⁴, e.g. duplicated inequality rows, reaches the iteration limit with
/// it and solves in 10 iterations without it). A solve that ends in `MaxIterations` or `NumericalError` is
/// therefore repeated once with equilibration off; [`ClarabelSolver::retries`] counts these. The next call
/// starts again from the equilibrated solver.
pub struct ClarabelSolver {
    settings: ClarabelSettings,
    solver: Option<DefaultSolver<f64>>,
    /// Whether `solver` was built with equilibration (the first-attempt configuration).
    equilibrated: bool,
    retries: usize,
    layout: Vec<Row>,
    new_layout: Vec<Row>,
    n: usize,
    p_vals: Vec<f64>,
    a_vals: Vec<f64>,
    q: Vec<f64>,
    b: Vec<f64>,
    rebuilds: usize,
}

impl ClarabelSolver {
    /// A backend with the given settings (validated at the first solve).
    pub fn new(settings: ClarabelSettings) -> Self {
        Self {
            settings,
            solver: None,
            equilibrated: true,
            retries: 0,
            layout: Vec::new(),
            new_layout: Vec::new(),
            n: 0,
            p_vals: Vec::new(),
            a_vals: Vec::new(),
            q: Vec::new(),
            b: Vec::new(),
            rebuilds: 0,
        }
    }

    /// How many times the clarabel solver object was (re)built.
    pub fn rebuilds(&self) -> usize {
        self.rebuilds
    }

    /// How many solves were repeated without equilibration (see the type's documentation).
    pub fn retries(&self) -> usize {
        self.retries
    }

    fn make_layout(qp: &DenseQp, layout: &mut Vec<Row>) -> usize {
        layout.clear();
        for i in 0..qp.n_eq() {
            layout.push(Row::Eq(i));
        }
        for i in 0..qp.n_ineq() {
            if qp.l[i] == qp.u[i] {
                layout.push(Row::IneqFixed(i));
            }
        }
        for j in 0..qp.n() {
            if qp.lb[j] == qp.ub[j] {
                layout.push(Row::BoundFixed(j));
            }
        }
        let n_zero = layout.len();
        for i in 0..qp.n_ineq() {
            if qp.l[i] != qp.u[i] {
                if qp.u[i].is_finite() {
                    layout.push(Row::IneqUpper(i));
                }
                if qp.l[i].is_finite() {
                    layout.push(Row::IneqLower(i));
                }
            }
        }
        for j in 0..qp.n() {
            if qp.lb[j] != qp.ub[j] {
                if qp.ub[j].is_finite() {
                    layout.push(Row::BoundUpper(j));
                }
                if qp.lb[j].is_finite() {
                    layout.push(Row::BoundLower(j));
                }
            }
        }
        n_zero
    }

    /// Writes the values of P (upper triangle, column-major), A (pattern order), q and b. When `pattern` is
    /// given, also writes colptr/rowval of A.
    fn fill(&mut self, qp: &DenseQp, mut pattern: Option<(&mut Vec<usize>, &mut Vec<usize>)>) {
        let n = qp.n();
        self.p_vals.clear();
        for j in 0..n {
            for i in 0..=j {
                self.p_vals.push(0.5 * (qp.h[(i, j)] + qp.h[(j, i)]));
            }
        }
        self.q.clear();
        self.q.extend(qp.g.iter().copied());
        self.a_vals.clear();
        if let Some((colptr, _)) = pattern.as_mut() {
            colptr.clear();
            colptr.push(0);
        }
        for j in 0..n {
            for (r, row) in self.layout.iter().enumerate() {
                let v = match *row {
                    Row::Eq(i) => Some(qp.e[(i, j)]),
                    Row::IneqFixed(i) | Row::IneqUpper(i) => Some(qp.c[(i, j)]),
                    Row::IneqLower(i) => Some(-qp.c[(i, j)]),
                    Row::BoundFixed(k) | Row::BoundUpper(k) => (k == j).then_some(1.0),
                    Row::BoundLower(k) => (k == j).then_some(-1.0),
                };
                if let Some(v) = v {
                    self.a_vals.push(v);
                    if let Some((_, rowval)) = pattern.as_mut() {
                        rowval.push(r);
                    }
                }
            }
            if let Some((colptr, _)) = pattern.as_mut() {
                colptr.push(self.a_vals.len());
            }
        }
        self.b.clear();
        for row in &self.layout {
            self.b.push(match *row {
                Row::Eq(i) => qp.f[i],
                Row::IneqFixed(i) => qp.l[i],
                Row::BoundFixed(j) => qp.lb[j],
                Row::IneqUpper(i) => qp.u[i],
                Row::IneqLower(i) => -qp.l[i],
                Row::BoundUpper(j) => qp.ub[j],
                Row::BoundLower(j) => -qp.lb[j],
            });
        }
    }

    fn rebuild(&mut self, qp: &DenseQp, n_zero: usize, equilibrate: bool) -> Result<(), QpError> {
        let settings = self.settings.build(equilibrate)?;
        let n = qp.n();
        let mut colptr = Vec::new();
        let mut rowval = Vec::new();
        self.fill(qp, Some((&mut colptr, &mut rowval)));
        let m = self.layout.len();
        let a = CscMatrix::new(m, n, colptr, rowval, self.a_vals.clone());
        let mut pcol = Vec::with_capacity(n + 1);
        let mut prow = Vec::with_capacity(self.p_vals.len());
        pcol.push(0);
        for j in 0..n {
            for i in 0..=j {
                prow.push(i);
            }
            pcol.push(prow.len());
        }
        let p = CscMatrix::new(n, n, pcol, prow, self.p_vals.clone());
        let mut cones = Vec::new();
        if n_zero > 0 {
            cones.push(SupportedConeT::ZeroConeT(n_zero));
        }
        if m > n_zero {
            cones.push(SupportedConeT::NonnegativeConeT(m - n_zero));
        }
        let solver = DefaultSolver::new(&p, &self.q, &a, &self.b, &cones, settings)
            .map_err(|e| QpError::ClarabelSetup(e.to_string()))?;
        self.solver = Some(solver);
        self.equilibrated = equilibrate;
        self.n = n;
        self.rebuilds += 1;
        Ok(())
    }

    fn try_update(&mut self, qp: &DenseQp) -> bool {
        self.fill(qp, None);
        let Some(solver) = self.solver.as_mut() else {
            return false;
        };
        solver.update_P(&self.p_vals).is_ok()
            && solver.update_A(&self.a_vals).is_ok()
            && solver.update_q(&self.q).is_ok()
            && solver.update_b(&self.b).is_ok()
    }
}

impl QpSolver for ClarabelSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn solve(&mut self, qp: &DenseQp, out: &mut SolverOutput) {
        out.prepare(qp);
        if !qp.is_valid() {
            out.status = QpStatus::InvalidData;
            return;
        }
        let mut new_layout = std::mem::take(&mut self.new_layout);
        let n_zero = Self::make_layout(qp, &mut new_layout);
        let same = self.solver.is_some()
            && self.equilibrated
            && self.n == qp.n()
            && new_layout == self.layout;
        std::mem::swap(&mut self.layout, &mut new_layout);
        self.new_layout = new_layout;
        let ready = if same && self.try_update(qp) {
            true
        } else {
            self.rebuild(qp, n_zero, true).is_ok()
        };
        let Some(solver) = self.solver.as_mut().filter(|_| ready) else {
            self.solver = None;
            out.status = QpStatus::NumericalError;
            return;
        };
        solver.solve();
        if worth_retry(map_status(solver.solution.status)) {
            self.retries += 1;
            let rebuilt = self.rebuild(qp, n_zero, false).is_ok();
            match self.solver.as_mut().filter(|_| rebuilt) {
                Some(retry) => retry.solve(),
                None => {
                    self.solver = None;
                    out.status = QpStatus::NumericalError;
                    return;
                }
            }
        }
        let Some(solver) = self.solver.as_ref() else {
            out.status = QpStatus::NumericalError;
            return;
        };
        let sol = &solver.solution;
        out.status = map_status(sol.status);
        out.iterations = sol.iterations as usize;
        if out.status.is_success() {
            for j in 0..qp.n() {
                out.x[j] = sol.x[j];
            }
            for (r, row) in self.layout.iter().enumerate() {
                let zr = sol.z[r];
                match *row {
                    Row::Eq(i) => out.y[i] = zr,
                    Row::IneqFixed(i) | Row::IneqUpper(i) => out.z[i] += zr,
                    Row::IneqLower(i) => out.z[i] -= zr,
                    Row::BoundFixed(j) | Row::BoundUpper(j) => out.bound_multipliers[j] += zr,
                    Row::BoundLower(j) => out.bound_multipliers[j] -= zr,
                }
            }
            out.objective = qp.objective_noalloc(&out.x);
        }
        out.sanitize();
    }

    fn reset(&mut self) {
        self.solver = None;
    }
}

/// Builds a CSC matrix from triplets, summing duplicates.
fn csc_from_triplets(m: usize, n: usize, trips: &mut [(usize, usize, f64)]) -> CscMatrix<f64> {
    trips.sort_by_key(|a| (a.1, a.0));
    let mut colptr = vec![0usize; n + 1];
    let mut rowval: Vec<usize> = Vec::with_capacity(trips.len());
    let mut nzval: Vec<f64> = Vec::with_capacity(trips.len());
    let mut last: Option<(usize, usize)> = None;
    for &(r, c, v) in trips.iter() {
        if last == Some((r, c)) {
            if let Some(x) = nzval.last_mut() {
                *x += v;
            }
            continue;
        }
        last = Some((r, c));
        rowval.push(r);
        nzval.push(v);
        colptr[c + 1] += 1;
    }
    for j in 0..n {
        colptr[j + 1] += colptr[j];
    }
    CscMatrix::new(m, n, colptr, rowval, nzval)
}

/// Sparse-problem backend on clarabel, for large banded problems (e.g. the DCM MPC, 400–800 variables) that
/// must not be densified.
///
/// Each call converts the [`SparseQp`] triplets into CSC form (duplicates summed); if the resulting
/// sparsity pattern and the set of finite sides are the same as in the previous call, the existing clarabel
/// object is refreshed with `update_*`, otherwise it is rebuilt. This path allocates (triplet conversion and
/// clarabel internals).
///
/// Failed solves are retried once without equilibration, as in [`ClarabelSolver`].
pub struct ClarabelSparseSolver {
    settings: ClarabelSettings,
    solver: Option<DefaultSolver<f64>>,
    /// Whether `solver` was built with equilibration (the first-attempt configuration).
    equilibrated: bool,
    key: (usize, Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>, usize),
    solution: SparseSolution,
}

impl ClarabelSparseSolver {
    /// A sparse backend with the given settings.
    pub fn new(settings: ClarabelSettings) -> Self {
        Self {
            settings,
            solver: None,
            equilibrated: true,
            key: (0, Vec::new(), Vec::new(), Vec::new(), Vec::new(), 0),
            solution: SparseSolution::default(),
        }
    }

    /// The last solution.
    pub fn solution(&self) -> &SparseSolution {
        &self.solution
    }

    /// Solves `qp`. Returns the solution (whose `status` may be a failure) or a data error.
    pub fn solve(&mut self, qp: &SparseQp) -> Result<&SparseSolution, QpError> {
        let start = Instant::now();
        qp.validate()?;
        let n = qp.n;
        let m_rows = qp.lower.len();
        // Row layout: zero-cone rows (l == u), then upper sides, then lower sides.
        let mut row_map: Vec<(usize, f64, f64)> = Vec::new(); // (original row, sign, rhs)
        for i in 0..m_rows {
            if qp.lower[i] == qp.upper[i] {
                row_map.push((i, 1.0, qp.lower[i]));
            }
        }
        let n_zero = row_map.len();
        for i in 0..m_rows {
            if qp.lower[i] != qp.upper[i] {
                if qp.upper[i].is_finite() {
                    row_map.push((i, 1.0, qp.upper[i]));
                }
                if qp.lower[i].is_finite() {
                    row_map.push((i, -1.0, -qp.lower[i]));
                }
            }
        }
        let m = row_map.len();
        // expanded rows of each original row
        let mut expansions: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m_rows];
        for (r, &(i, s, _)) in row_map.iter().enumerate() {
            expansions[i].push((r, s));
        }
        let mut a_trips = Vec::with_capacity(qp.constraints.len() * 2);
        for &(i, j, v) in &qp.constraints {
            for &(r, s) in &expansions[i] {
                a_trips.push((r, j, s * v));
            }
        }
        let a = csc_from_triplets(m, n, &mut a_trips);
        let mut p_trips = qp.hessian.clone();
        let p = csc_from_triplets(n, n, &mut p_trips);
        let b: Vec<f64> = row_map.iter().map(|&(_, _, rhs)| rhs).collect();
        let key = (
            n,
            p.colptr.clone(),
            p.rowval.clone(),
            a.colptr.clone(),
            a.rowval.clone(),
            n_zero,
        );
        let reuse = self.solver.is_some() && self.equilibrated && key == self.key;
        let mut updated = false;
        if reuse {
            if let Some(s) = self.solver.as_mut() {
                updated = s.update_P(&p.nzval).is_ok()
                    && s.update_A(&a.nzval).is_ok()
                    && s.update_q(&qp.gradient).is_ok()
                    && s.update_b(&b).is_ok();
            }
        }
        let mut cones = Vec::new();
        if n_zero > 0 {
            cones.push(SupportedConeT::ZeroConeT(n_zero));
        }
        if m > n_zero {
            cones.push(SupportedConeT::NonnegativeConeT(m - n_zero));
        }
        if !updated {
            let settings = self.settings.build(true)?;
            let solver = DefaultSolver::new(&p, &qp.gradient, &a, &b, &cones, settings)
                .map_err(|e| QpError::ClarabelSetup(e.to_string()))?;
            self.solver = Some(solver);
            self.equilibrated = true;
            self.key = key;
        }
        let sol_out = &mut self.solution;
        sol_out.x.clear();
        sol_out.x.resize(n, 0.0);
        sol_out.multipliers.clear();
        sol_out.multipliers.resize(m_rows, 0.0);
        let Some(solver) = self.solver.as_mut() else {
            sol_out.status = QpStatus::NumericalError;
            return Ok(&self.solution);
        };
        solver.solve();
        if worth_retry(map_status(solver.solution.status)) {
            let settings = self.settings.build(false)?;
            let mut retry = DefaultSolver::new(&p, &qp.gradient, &a, &b, &cones, settings)
                .map_err(|e| QpError::ClarabelSetup(e.to_string()))?;
            retry.solve();
            self.equilibrated = false;
            *solver = retry;
        }
        let sol = &solver.solution;
        sol_out.status = map_status(sol.status);
        sol_out.iterations = sol.iterations as usize;
        if sol_out.status.is_success() {
            sol_out.x.copy_from_slice(&sol.x[..n]);
            for (r, &(i, s, _)) in row_map.iter().enumerate() {
                sol_out.multipliers[i] += s * sol.z[r];
            }
            sol_out.objective = sol.obj_val;
        }
        if !(sol_out.x.iter().all(|v| v.is_finite())
            && sol_out.multipliers.iter().all(|v| v.is_finite()))
        {
            sol_out.x.iter_mut().for_each(|v| *v = 0.0);
            sol_out.multipliers.iter_mut().for_each(|v| *v = 0.0);
            sol_out.status = QpStatus::NumericalError;
        }
        sol_out.solve_time = start.elapsed();
        Ok(&self.solution)
    }
}
