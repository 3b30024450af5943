//! Problems assembled from named variables and prioritised tasks.

use std::time::{Duration, Instant};

use nalgebra::{DVector, DVectorViewMut};
use serde::{Deserialize, Serialize};

use crate::active_set::{ActiveSetSettings, ActiveSetSolver};
use crate::clarabel_backend::{ClarabelSettings, ClarabelSolver};
use crate::dense::DenseQp;
use crate::error::QpError;
use crate::kkt::{check_kkt, KktReport};
use crate::nullspace::NullSpace;
use crate::solver::{QpSolver, SolverOutput};
use crate::status::QpStatus;
use crate::task::{Task, TaskId, TaskKind, TaskSpec};
use crate::variables::{VarId, VariableSet};

/// Which backend a [`QpProblem`] uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    /// Our dense Goldfarb–Idnani dual active-set solver (warm-started; the default).
    #[default]
    ActiveSet,
    /// Clarabel interior point (the reference).
    Clarabel,
}

impl Backend {
    /// A fresh solver of this kind.
    pub fn make(self, settings: &QpSettings) -> Box<dyn QpSolver> {
        match self {
            Backend::ActiveSet => Box::new(ActiveSetSolver::new(settings.active_set.clone())),
            Backend::Clarabel => Box::new(ClarabelSolver::new(settings.clarabel.clone())),
        }
    }
}

/// Settings of a [`QpProblem`].
///
/// | field | default | meaning |
/// |---|---|---|
/// | `backend` | `active_set` | `active_set` or `clarabel` |
/// | `regularization` | `1e-8` | Tikhonov term `½·ρ‖x‖²` added to the cost (makes `H ≻ 0` with rank-deficient soft tasks); 0 disables it |
/// | `fallback` | `true` | on a failed solve, relax the hard equality tasks into soft ones and solve again |
/// | `relaxation_weight` | `1e4` | weight of every row of a relaxed hard equality task in that fallback solve |
/// | `active_set` | see [`ActiveSetSettings`] | active-set backend settings |
/// | `clarabel` | see [`ClarabelSettings`] | clarabel backend settings |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QpSettings {
    /// Backend.
    pub backend: Backend,
    /// Tikhonov regularisation weight ρ ≥ 0 (cost units per unit of `x`²).
    pub regularization: f64,
    /// Whether to run the relaxed fallback solve.
    pub fallback: bool,
    /// Weight of relaxed hard equality rows (> 0).
    pub relaxation_weight: f64,
    /// Active-set backend settings.
    pub active_set: ActiveSetSettings,
    /// Clarabel backend settings.
    pub clarabel: ClarabelSettings,
}

impl Default for QpSettings {
    fn default() -> Self {
        Self {
            backend: Backend::ActiveSet,
            regularization: 1e-8,
            fallback: true,
            relaxation_weight: 1e4,
            active_set: ActiveSetSettings::default(),
            clarabel: ClarabelSettings::default(),
        }
    }
}

impl QpSettings {
    /// Checks the numeric settings.
    pub fn validate(&self) -> Result<(), QpError> {
        if !(self.regularization >= 0.0 && self.regularization.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "regularization",
                reason: format!("{} must be finite and >= 0", self.regularization),
            });
        }
        if !(self.relaxation_weight > 0.0 && self.relaxation_weight.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "relaxation_weight",
                reason: format!("{} must be finite and > 0", self.relaxation_weight),
            });
        }
        let a = &self.active_set;
        if !(a.feasibility_tolerance > 0.0 && a.feasibility_tolerance < 1.0) {
            return Err(QpError::InvalidSetting {
                name: "active_set.feasibility_tolerance",
                reason: format!("{} is not in (0, 1)", a.feasibility_tolerance),
            });
        }
        if !(a.dependence_tolerance > 0.0 && a.dependence_tolerance < 1.0) {
            return Err(QpError::InvalidSetting {
                name: "active_set.dependence_tolerance",
                reason: format!("{} is not in (0, 1)", a.dependence_tolerance),
            });
        }
        if !(self.clarabel.tolerance > 0.0 && self.clarabel.tolerance < 1.0) {
            return Err(QpError::InvalidSetting {
                name: "clarabel.tolerance",
                reason: format!("{} is not in (0, 1)", self.clarabel.tolerance),
            });
        }
        Ok(())
    }
}

/// Which problem produced the returned solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolvePath {
    /// The problem as specified.
    Nominal,
    /// The fallback: hard equality tasks relaxed into soft ones with `relaxation_weight`.
    Relaxed,
    /// The null-space reduced problem (hard equalities eliminated, see
    /// [`QpProblem::enable_null_space`]); its solution is exact for the problem as specified.
    NullSpace,
}

/// Result of [`QpProblem::solve`], overwritten in place every tick.
#[derive(Clone, Debug, PartialEq)]
pub struct QpSolution {
    /// The decision vector (the concatenation of the variables). Zero when the solve failed; never NaN.
    pub x: DVector<f64>,
    /// Status of the path taken (the relaxed solve's status when the fallback ran).
    pub status: QpStatus,
    /// Status of the nominal solve.
    pub nominal_status: QpStatus,
    /// Which problem was finally solved.
    pub path: SolvePath,
    /// Backend iterations, summed over the nominal and the relaxed solve.
    pub iterations: usize,
    /// Wall time of `solve` (assembly + backend(s) + residuals).
    pub solve_time: Duration,
    /// Objective value of the solved problem at `x` (on [`SolvePath::NullSpace`], of the reduced problem:
    /// the soft costs up to a constant, with the regularisation on the null-space coordinates).
    pub objective: f64,
    /// Per task (by [`TaskId`]): `‖A x − b‖₂` for equalities, 2-norm of side violations for inequalities.
    pub task_residuals: Vec<f64>,
    /// Largest violation (∞-norm) of the hard constraints of the *nominal* problem (hard equality tasks,
    /// inequality tasks, variable bounds) at `x`.
    pub hard_violation: f64,
    /// Whether the backend kept its warm start.
    pub warm_started: bool,
}

impl QpSolution {
    /// Whether `x` can be used.
    pub fn is_success(&self) -> bool {
        self.status.is_success()
    }
}

/// A QP assembled from named variables and tasks: built once, then written and solved every tick without
/// allocation.
///
/// Cost: `Σ_soft ½‖W^{1/2}(A x − b)‖² + ½ρ‖x‖²`; constraints: the hard equality tasks, the inequality tasks
/// and the variable bounds.
///
/// ```
/// use stride_qp::{QpProblem, QpSettings, TaskSpec, VariableSet};
/// let mut vars = VariableSet::new();
/// let v = vars.add("v", 2).unwrap();
/// let tasks = vec![
///     TaskSpec::equality("track", &[v], 2).soft(1.0),
///     TaskSpec::equality("sum", &[v], 1),
/// ];
/// let mut qp = QpProblem::new(vars, tasks, QpSettings::default()).unwrap();
/// let track = qp.task_id("track").unwrap();
/// let sum = qp.task_id("sum").unwrap();
/// qp.task_mut(track).a_mut().fill_with_identity();
/// qp.task_mut(track).b_mut().copy_from_slice(&[1.0, 2.0]);
/// qp.task_mut(sum).a_mut().fill(1.0); // x0 + x1 = 1
/// qp.task_mut(sum).b_mut()[0] = 1.0;
/// let sol = qp.solve().unwrap();
/// assert!((sol.x[0] - 0.0).abs() < 1e-6 && (sol.x[1] - 1.0).abs() < 1e-6);
/// ```
pub struct QpProblem {
    vars: VariableSet,
    tasks: Vec<Task>,
    settings: QpSettings,
    lb: DVector<f64>,
    ub: DVector<f64>,
    nominal: DenseQp,
    relaxed: DenseQp,
    solver: Box<dyn QpSolver>,
    relaxed_solver: Box<dyn QpSolver>,
    out: SolverOutput,
    out_relaxed: SolverOutput,
    solution: QpSolution,
    null_space: Option<Box<NullSpace>>,
    used_null_space: bool,
}

impl QpProblem {
    /// Builds the problem structure with the backend named in `settings`. All buffers, including the
    /// active-set backend's workspace, are allocated here: even the first `solve` allocates nothing.
    pub fn new(
        vars: VariableSet,
        tasks: Vec<TaskSpec>,
        settings: QpSettings,
    ) -> Result<Self, QpError> {
        let solver = settings.backend.make(&settings);
        let relaxed_solver = settings.backend.make(&settings);
        Self::with_solvers(vars, tasks, settings, solver, relaxed_solver)
    }

    /// Builds the problem with caller-provided backends (one for the nominal, one for the relaxed problem).
    pub fn with_solvers(
        vars: VariableSet,
        specs: Vec<TaskSpec>,
        settings: QpSettings,
        solver: Box<dyn QpSolver>,
        relaxed_solver: Box<dyn QpSolver>,
    ) -> Result<Self, QpError> {
        settings.validate()?;
        let n = vars.total_size();
        if n == 0 {
            return Err(QpError::Dimension {
                what: "number of variables",
                expected: 1,
                got: 0,
            });
        }
        let mut tasks: Vec<Task> = Vec::with_capacity(specs.len());
        for spec in &specs {
            if tasks.iter().any(|t| t.name == spec.name) {
                return Err(QpError::DuplicateTask {
                    name: spec.name.clone(),
                });
            }
            tasks.push(Task::new(spec, &vars)?);
        }
        let cap_eq: usize = tasks
            .iter()
            .filter(|t| t.kind == TaskKind::Equality)
            .map(|t| t.rows())
            .sum();
        let cap_in: usize = tasks
            .iter()
            .filter(|t| t.kind == TaskKind::Inequality)
            .map(|t| t.rows())
            .sum();
        let mut solver = solver;
        let mut relaxed_solver = relaxed_solver;
        solver.reserve(n, cap_eq, cap_in);
        relaxed_solver.reserve(n, 0, cap_in);
        let nominal = DenseQp::with_capacity(n, cap_eq, cap_in);
        let relaxed = DenseQp::with_capacity(n, 0, cap_in);
        let out = SolverOutput::new(&nominal);
        let out_relaxed = SolverOutput::new(&relaxed);
        let solution = QpSolution {
            x: DVector::zeros(n),
            status: QpStatus::NotSolved,
            nominal_status: QpStatus::NotSolved,
            path: SolvePath::Nominal,
            iterations: 0,
            solve_time: Duration::ZERO,
            objective: 0.0,
            task_residuals: vec![0.0; tasks.len()],
            hard_violation: 0.0,
            warm_started: false,
        };
        Ok(Self {
            vars,
            tasks,
            settings,
            lb: DVector::from_element(n, f64::NEG_INFINITY),
            ub: DVector::from_element(n, f64::INFINITY),
            nominal,
            relaxed,
            solver,
            relaxed_solver,
            out,
            out_relaxed,
            solution,
            null_space: None,
            used_null_space: false,
        })
    }

    /// A problem without tasks over `vars`, with room for `cap_in` inequality rows and no equality row,
    /// whose dense QP the crate writes directly ([`QpProblem::dense_mut`]) and solves as written
    /// ([`QpProblem::solve_dense`]): the null-space path's reduced problem. Its backend is the active-set
    /// solver with the guess-or-cold warm start ([`ActiveSetSolver::guess_or_cold`]; the warm start on
    /// or off with `settings.active_set.warm_start`); its workspace is sized here, so no solve allocates.
    pub(crate) fn raw(
        vars: VariableSet,
        cap_in: usize,
        settings: QpSettings,
    ) -> Result<Self, QpError> {
        let solver = Box::new(ActiveSetSolver::new(settings.active_set.clone()).guess_or_cold());
        let relaxed_solver = settings.backend.make(&settings);
        let mut problem = Self::with_solvers(vars, Vec::new(), settings, solver, relaxed_solver)?;
        let n = problem.n();
        problem.nominal = DenseQp::with_capacity(n, 0, cap_in);
        problem.solver.reserve(n, 0, cap_in);
        problem.out = SolverOutput::new(&problem.nominal);
        Ok(problem)
    }

    /// The nominal dense QP, for writing it directly (problems built with [`QpProblem::raw`]).
    pub(crate) fn dense_mut(&mut self) -> &mut DenseQp {
        &mut self.nominal
    }

    /// Solves the nominal dense QP as written, without assembly nor fallback (problems built with
    /// [`QpProblem::raw`]: no task, so the solution has no task residual and `hard_violation` covers the
    /// variable bounds only). `start` is when the caller's solve began (for `solve_time`).
    pub(crate) fn solve_dense(&mut self, start: Instant) -> &QpSolution {
        self.solver.solve(&self.nominal, &mut self.out);
        let sol = &mut self.solution;
        sol.status = self.out.status;
        sol.nominal_status = self.out.status;
        sol.path = SolvePath::Nominal;
        sol.iterations = self.out.iterations;
        sol.warm_started = self.out.warm_started;
        if self.out.status.is_success() {
            sol.x.copy_from(&self.out.x);
            sol.objective = self.out.objective;
        } else {
            sol.x.fill(0.0);
            sol.objective = 0.0;
        }
        self.write_residuals(start);
        &self.solution
    }

    /// Adds the null-space solve path: every [`QpProblem::solve`] first eliminates the hard equality tasks
    /// (`x = x_p + N z`, see the `nullspace` module) and solves the smaller equality-free problem over `z`
    /// with the same backend; the full problem (and its relaxed fallback) is solved only when that is
    /// not possible (rank-deficient hard rows, a task switched between hard and soft since this call) or
    /// fails (e.g. infeasible inequalities). The solution is the full problem's, to the backend's
    /// tolerance.
    ///
    /// Only with the active-set backend (the fast path; clarabel, the reference, always solves the full
    /// problem) and when there is at least one and fewer than `n` hard equality rows. Returns whether the
    /// path was added. Allocates the reduced problem here; solves stay allocation-free.
    pub fn enable_null_space(&mut self) -> Result<bool, QpError> {
        if self.settings.backend != Backend::ActiveSet {
            return Ok(false);
        }
        self.null_space = NullSpace::new(&self.tasks, self.n(), &self.settings)?.map(Box::new);
        Ok(self.null_space.is_some())
    }

    /// The problem the last [`QpProblem::solve`] solved: the null-space reduced one (one variable,
    /// `null_space_coordinates`) when the solution took [`SolvePath::NullSpace`], else `self`. For
    /// inspecting its dense form, solver output and KKT residuals (the reduced problem has no tasks: its
    /// dense QP is written directly from the full problem's tasks).
    pub fn last_solved(&self) -> &QpProblem {
        match (&self.null_space, self.used_null_space) {
            (Some(ns), true) => &ns.problem,
            _ => self,
        }
    }

    /// The variables.
    pub fn variables(&self) -> &VariableSet {
        &self.vars
    }
    /// Number of scalar decision variables.
    pub fn n(&self) -> usize {
        self.vars.total_size()
    }
    /// Settings.
    pub fn settings(&self) -> &QpSettings {
        &self.settings
    }
    /// Sets the Tikhonov regularisation ρ (≥ 0).
    pub fn set_regularization(&mut self, rho: f64) -> Result<(), QpError> {
        if !(rho >= 0.0 && rho.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "regularization",
                reason: format!("{rho} must be >= 0"),
            });
        }
        self.settings.regularization = rho;
        if let Some(ns) = &mut self.null_space {
            ns.problem.set_regularization(rho)?;
        }
        Ok(())
    }
    /// Name of the nominal backend.
    pub fn backend_name(&self) -> &'static str {
        self.solver.name()
    }
    /// The id of the task called `name`.
    pub fn task_id(&self, name: &str) -> Option<TaskId> {
        self.tasks.iter().position(|t| t.name == name).map(TaskId)
    }
    /// Number of tasks.
    pub fn n_tasks(&self) -> usize {
        self.tasks.len()
    }
    /// A task.
    ///
    /// # Panics
    /// If `id` did not come from this problem.
    pub fn task(&self, id: TaskId) -> &Task {
        &self.tasks[id.0]
    }
    /// A task, for writing its numbers (see [`QpProblem::task`] for panics).
    pub fn task_mut(&mut self, id: TaskId) -> &mut Task {
        &mut self.tasks[id.0]
    }
    /// All tasks in declaration order.
    pub fn tasks(&self) -> &[Task] {
        &self.tasks
    }
    /// Lower bounds of variable `var` (−∞ = none).
    pub fn lower_bounds_mut(&mut self, var: VarId) -> DVectorViewMut<'_, f64> {
        let r = self.vars.range(var);
        self.lb.rows_mut(r.start, r.len())
    }
    /// Upper bounds of variable `var` (+∞ = none).
    pub fn upper_bounds_mut(&mut self, var: VarId) -> DVectorViewMut<'_, f64> {
        let r = self.vars.range(var);
        self.ub.rows_mut(r.start, r.len())
    }
    /// All lower bounds (length n).
    pub fn lower_bounds(&self) -> &DVector<f64> {
        &self.lb
    }
    /// All upper bounds (length n).
    pub fn upper_bounds(&self) -> &DVector<f64> {
        &self.ub
    }
    /// Removes every variable bound.
    pub fn clear_bounds(&mut self) {
        self.lb.fill(f64::NEG_INFINITY);
        self.ub.fill(f64::INFINITY);
    }
    /// The last solution.
    pub fn solution(&self) -> &QpSolution {
        &self.solution
    }
    /// The dense QP solved last (the relaxed one when the fallback path was taken, the reduced one's
    /// on the null-space path).
    pub fn dense_qp(&self) -> &DenseQp {
        match self.solution.path {
            SolvePath::Nominal => &self.nominal,
            SolvePath::Relaxed => &self.relaxed,
            SolvePath::NullSpace => self.last_solved().dense_qp(),
        }
    }
    /// The raw backend output (with multipliers) of the last solve, matching [`QpProblem::dense_qp`].
    pub fn solver_output(&self) -> &SolverOutput {
        match self.solution.path {
            SolvePath::Nominal => &self.out,
            SolvePath::Relaxed => &self.out_relaxed,
            SolvePath::NullSpace => self.last_solved().solver_output(),
        }
    }
    /// KKT residuals of the last solve (see [`KktReport`]).
    pub fn check_kkt(&self) -> KktReport {
        check_kkt(self.dense_qp(), self.solver_output())
    }
    /// Forgets the backends' warm starts.
    pub fn reset_warm_start(&mut self) {
        self.solver.reset();
        self.relaxed_solver.reset();
        if let Some(ns) = &mut self.null_space {
            ns.problem.reset_warm_start();
        }
    }

    /// Writes the dense QP from the tasks (nominal, or with hard equality tasks relaxed).
    fn assemble(&mut self, relaxed: bool) {
        let rho = self.settings.regularization;
        let relax_w = self.settings.relaxation_weight;
        let qp = if relaxed {
            &mut self.relaxed
        } else {
            &mut self.nominal
        };
        let n = qp.n();
        qp.h.fill(0.0);
        for i in 0..n {
            qp.h[(i, i)] = rho;
        }
        qp.g.fill(0.0);
        let mut row_e = 0;
        let mut row_c = 0;
        for task in &mut self.tasks {
            match task.kind {
                TaskKind::Equality => {
                    if task.hard && !relaxed {
                        task.write_rows(&mut qp.e, row_e);
                        for i in 0..task.rows() {
                            qp.f[row_e + i] = task.b[i];
                        }
                        row_e += task.rows();
                    } else {
                        let w = if task.hard { Some(relax_w) } else { None };
                        task.add_cost(&mut qp.h, &mut qp.g, w);
                    }
                }
                TaskKind::Inequality => {
                    task.write_rows(&mut qp.c, row_c);
                    for i in 0..task.rows() {
                        qp.l[row_c + i] = task.lower[i];
                        qp.u[row_c + i] = task.upper[i];
                    }
                    row_c += task.rows();
                }
            }
        }
        // capacities were sized from the task list, so these cannot fail
        let _ = qp.set_n_eq(row_e);
        let _ = qp.set_n_ineq(row_c);
        qp.lb.copy_from(&self.lb);
        qp.ub.copy_from(&self.ub);
    }

    /// Assembles and solves. On success returns the solution; on failure (after the fallback, if enabled)
    /// returns [`QpError::SolveFailed`] and [`QpProblem::solution`] still holds the statuses and residuals
    /// (with `x = 0`). Allocation-free after the first call.
    pub fn solve(&mut self) -> Result<&QpSolution, QpError> {
        let start = Instant::now();
        self.used_null_space = false;
        if let Some(ns) = self.null_space.as_deref_mut() {
            if let Some((status, iterations)) =
                ns.solve(&self.tasks, &self.lb, &self.ub, &mut self.solution.x)
            {
                self.used_null_space = true;
                let reduced = ns.problem.solution();
                let sol = &mut self.solution;
                sol.status = status;
                sol.nominal_status = status;
                sol.path = SolvePath::NullSpace;
                sol.iterations = iterations;
                sol.warm_started = reduced.warm_started;
                sol.objective = reduced.objective;
                self.write_residuals(start);
                return Ok(&self.solution);
            }
        }
        self.assemble(false);
        self.solver.solve(&self.nominal, &mut self.out);
        let nominal_status = self.out.status;
        let mut path = SolvePath::Nominal;
        let mut status = nominal_status;
        let mut iterations = self.out.iterations;
        let has_hard_eq = self
            .tasks
            .iter()
            .any(|t| t.kind == TaskKind::Equality && t.hard);
        let retry = matches!(
            nominal_status,
            QpStatus::Infeasible
                | QpStatus::MaxIterations
                | QpStatus::NumericalError
                | QpStatus::HessianNotPositiveDefinite
        );
        let mut relaxed_status = None;
        if !nominal_status.is_success() && retry && self.settings.fallback && has_hard_eq {
            self.assemble(true);
            self.relaxed_solver
                .solve(&self.relaxed, &mut self.out_relaxed);
            status = self.out_relaxed.status;
            relaxed_status = Some(status);
            iterations += self.out_relaxed.iterations;
            path = SolvePath::Relaxed;
        }
        let (x_src, objective, warm) = match path {
            SolvePath::Nominal => (&self.out.x, self.out.objective, self.out.warm_started),
            SolvePath::Relaxed | SolvePath::NullSpace => (
                &self.out_relaxed.x,
                self.out_relaxed.objective,
                self.out_relaxed.warm_started,
            ),
        };
        let sol = &mut self.solution;
        if status.is_success() {
            sol.x.copy_from(x_src);
            sol.objective = objective;
        } else {
            sol.x.fill(0.0);
            sol.objective = 0.0;
        }
        sol.status = status;
        sol.nominal_status = nominal_status;
        sol.path = path;
        sol.iterations = iterations;
        sol.warm_started = warm;
        self.write_residuals(start);
        if status.is_success() {
            Ok(&self.solution)
        } else {
            Err(QpError::SolveFailed {
                nominal: nominal_status,
                relaxed: relaxed_status,
            })
        }
    }

    /// Task residuals, hard-constraint violation and solve time of the solution.
    fn write_residuals(&mut self, start: Instant) {
        let sol = &mut self.solution;
        let mut hard_violation: f64 = 0.0;
        for (k, task) in self.tasks.iter_mut().enumerate() {
            let (r2, rinf) = task.residual(&sol.x);
            sol.task_residuals[k] = r2;
            if task.hard {
                hard_violation = hard_violation.max(rinf);
            }
        }
        for j in 0..sol.x.len() {
            hard_violation = hard_violation
                .max(self.lb[j] - sol.x[j])
                .max(sol.x[j] - self.ub[j]);
        }
        sol.hard_violation = hard_violation;
        sol.solve_time = start.elapsed();
    }
}
