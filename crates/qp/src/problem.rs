//! Problems assembled from named variables and prioritised tasks.

use std::ops::Range;
use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DMatrixViewMut, DVector, DVectorViewMut};
use serde::{Deserialize, Serialize};

use crate::active_set::{ActiveSetSettings, ActiveSetSolver};
use crate::clarabel_backend::{ClarabelSettings, ClarabelSolver};
use crate::dense::DenseQp;
use crate::error::QpError;
use crate::kkt::{check_kkt, KktReport};
use crate::solver::{QpSolver, QpStatus, SolverOutput};
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

/// Equality (`A x = b`) or two-sided inequality (`l ≤ A x ≤ u`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TaskKind {
    /// `A x = b`: a hard constraint or a soft cost `½‖W^{1/2}(A x − b)‖²`.
    Equality,
    /// `l ≤ A x ≤ u` (sides may be ±∞): always a hard constraint.
    Inequality,
}

/// Declaration of a task: its name, kind, the variables it spans (its columns, in this order), its number of
/// rows and its priority.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskSpec {
    /// Unique name (used in errors and logs).
    pub name: String,
    /// Equality or inequality.
    pub kind: TaskKind,
    /// Variables whose columns the task's matrix spans, in order.
    pub variables: Vec<VarId>,
    /// Number of rows.
    pub rows: usize,
    /// Hard constraint (`true`) or weighted cost (`false`).
    pub hard: bool,
    /// Row weights for a soft task: one entry (applied to all rows) or one per row; ≥ 0.
    pub weight: Vec<f64>,
}

impl TaskSpec {
    /// A hard equality task `A x = b` with `rows` rows over `variables`.
    pub fn equality(name: &str, variables: &[VarId], rows: usize) -> Self {
        Self {
            name: name.to_owned(),
            kind: TaskKind::Equality,
            variables: variables.to_vec(),
            rows,
            hard: true,
            weight: vec![1.0],
        }
    }

    /// A (hard) inequality task `l ≤ A x ≤ u` with `rows` rows over `variables`; sides start at ±∞.
    pub fn inequality(name: &str, variables: &[VarId], rows: usize) -> Self {
        Self {
            name: name.to_owned(),
            kind: TaskKind::Inequality,
            variables: variables.to_vec(),
            rows,
            hard: true,
            weight: vec![1.0],
        }
    }

    /// Makes the task soft with the same weight on every row.
    pub fn soft(mut self, weight: f64) -> Self {
        self.hard = false;
        self.weight = vec![weight];
        self
    }

    /// Makes the task soft with one weight per row.
    pub fn soft_weights(mut self, weights: &[f64]) -> Self {
        self.hard = false;
        self.weight = weights.to_vec();
        self
    }

    /// Makes the task hard.
    pub fn hard(mut self) -> Self {
        self.hard = true;
        self
    }
}

/// Handle of a task inside a [`QpProblem`] (index in declaration order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TaskId(pub usize);

/// A task's preallocated data, written every tick through [`QpProblem::task_mut`].
///
/// Its matrix `A` has `rows` rows and one column per scalar of the task's variables, concatenated in the order
/// the spec listed them (use [`Task::var_block_mut`] to address the columns of one variable).
#[derive(Clone, Debug)]
pub struct Task {
    name: String,
    kind: TaskKind,
    vars: Vec<VarId>,
    /// (range in x, offset in the task's columns)
    blocks: Vec<(Range<usize>, usize)>,
    width: usize,
    a: DMatrix<f64>,
    b: DVector<f64>,
    lower: DVector<f64>,
    upper: DVector<f64>,
    hard: bool,
    weight: DVector<f64>,
    aw: DMatrix<f64>,
    bw: DVector<f64>,
    hk: DMatrix<f64>,
    gk: DVector<f64>,
    xk: DVector<f64>,
    ax: DVector<f64>,
    nz: Vec<usize>,
}

impl Task {
    fn new(spec: &TaskSpec, vars: &VariableSet) -> Result<Self, QpError> {
        if spec.rows == 0 || spec.variables.is_empty() {
            return Err(QpError::EmptyTask {
                task: spec.name.clone(),
            });
        }
        let mut blocks = Vec::new();
        let mut width = 0;
        for (k, &v) in spec.variables.iter().enumerate() {
            if !vars.contains(v) {
                return Err(QpError::UnknownVariable {
                    task: spec.name.clone(),
                    id: v.index(),
                });
            }
            if spec.variables[..k].contains(&v) {
                return Err(QpError::RepeatedVariable {
                    task: spec.name.clone(),
                    variable: vars.name(v).to_owned(),
                });
            }
            blocks.push((vars.range(v), width));
            width += vars.size(v);
        }
        if spec.kind == TaskKind::Inequality && !spec.hard {
            return Err(QpError::SoftInequality {
                task: spec.name.clone(),
            });
        }
        let rows = spec.rows;
        let mut task = Self {
            name: spec.name.clone(),
            kind: spec.kind,
            vars: spec.variables.clone(),
            blocks,
            width,
            a: DMatrix::zeros(rows, width),
            b: DVector::zeros(rows),
            lower: DVector::from_element(rows, f64::NEG_INFINITY),
            upper: DVector::from_element(rows, f64::INFINITY),
            hard: spec.hard,
            weight: DVector::from_element(rows, 1.0),
            aw: DMatrix::zeros(rows, width),
            bw: DVector::zeros(rows),
            hk: DMatrix::zeros(width, width),
            gk: DVector::zeros(width),
            xk: DVector::zeros(width),
            ax: DVector::zeros(rows),
            nz: Vec::with_capacity(width),
        };
        task.set_weights(&spec.weight)?;
        Ok(task)
    }

    /// Task name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Equality or inequality.
    pub fn kind(&self) -> TaskKind {
        self.kind
    }
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.a.nrows()
    }
    /// Number of columns (sum of the sizes of the task's variables).
    pub fn width(&self) -> usize {
        self.width
    }
    /// Variables spanned by the task, in column order.
    pub fn variables(&self) -> &[VarId] {
        &self.vars
    }
    /// Whether the task is a hard constraint.
    pub fn is_hard(&self) -> bool {
        self.hard
    }
    /// Task matrix `A` (rows × width).
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }
    /// Mutable task matrix `A`.
    pub fn a_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.a
    }
    /// The columns of `A` that multiply variable `var`, or `None` if the task does not span it.
    pub fn var_block_mut(&mut self, var: VarId) -> Option<DMatrixViewMut<'_, f64>> {
        let k = self.vars.iter().position(|&v| v == var)?;
        let (range, offset) = &self.blocks[k];
        let len = range.len();
        let offset = *offset;
        Some(self.a.columns_mut(offset, len))
    }
    /// Target `b` of an equality task.
    pub fn b(&self) -> &DVector<f64> {
        &self.b
    }
    /// Mutable target `b` (equality tasks; ignored for inequalities).
    pub fn b_mut(&mut self) -> &mut DVector<f64> {
        &mut self.b
    }
    /// Lower sides `l` of an inequality task (−∞ = none).
    pub fn lower(&self) -> &DVector<f64> {
        &self.lower
    }
    /// Mutable lower sides (inequality tasks; ignored for equalities).
    pub fn lower_mut(&mut self) -> &mut DVector<f64> {
        &mut self.lower
    }
    /// Upper sides `u` of an inequality task (+∞ = none).
    pub fn upper(&self) -> &DVector<f64> {
        &self.upper
    }
    /// Mutable upper sides (inequality tasks; ignored for equalities).
    pub fn upper_mut(&mut self) -> &mut DVector<f64> {
        &mut self.upper
    }
    /// Row weights (used when the task is soft).
    pub fn weights(&self) -> &DVector<f64> {
        &self.weight
    }
    /// Sets the same weight on every row (finite, ≥ 0).
    pub fn set_weight(&mut self, weight: f64) -> Result<(), QpError> {
        if !(weight >= 0.0 && weight.is_finite()) {
            return Err(QpError::InvalidWeight {
                task: self.name.clone(),
                row: 0,
                value: weight,
            });
        }
        self.weight.fill(weight);
        Ok(())
    }
    /// Sets the row weights: one entry for all rows, or one per row (finite, ≥ 0).
    pub fn set_weights(&mut self, weights: &[f64]) -> Result<(), QpError> {
        let rows = self.rows();
        if weights.len() != 1 && weights.len() != rows {
            return Err(QpError::WeightSize {
                task: self.name.clone(),
                expected: rows,
                got: weights.len(),
            });
        }
        for (row, &w) in weights.iter().enumerate() {
            if !(w >= 0.0 && w.is_finite()) {
                return Err(QpError::InvalidWeight {
                    task: self.name.clone(),
                    row,
                    value: w,
                });
            }
        }
        if weights.len() == 1 {
            self.weight.fill(weights[0]);
        } else {
            self.weight.copy_from_slice(weights);
        }
        Ok(())
    }
    /// Switches an equality task between hard and soft at run time (allocation-free). Inequalities must stay
    /// hard.
    pub fn set_hard(&mut self, hard: bool) -> Result<(), QpError> {
        if self.kind == TaskKind::Inequality && !hard {
            return Err(QpError::SoftInequality {
                task: self.name.clone(),
            });
        }
        self.hard = hard;
        Ok(())
    }

    fn gather(&mut self, x: &DVector<f64>) {
        for (range, offset) in &self.blocks {
            for (k, i) in range.clone().enumerate() {
                self.xk[offset + k] = x[i];
            }
        }
    }

    /// Residual at `x`: `‖A x − b‖₂` for equalities, the 2-norm of the side violations for inequalities;
    /// also returns the ∞-norm.
    fn residual(&mut self, x: &DVector<f64>) -> (f64, f64) {
        self.gather(x);
        self.ax.gemv(1.0, &self.a, &self.xk, 0.0);
        let mut sq = 0.0;
        let mut inf: f64 = 0.0;
        for i in 0..self.rows() {
            let r = match self.kind {
                TaskKind::Equality => (self.ax[i] - self.b[i]).abs(),
                TaskKind::Inequality => (self.lower[i] - self.ax[i])
                    .max(self.ax[i] - self.upper[i])
                    .max(0.0),
            };
            sq += r * r;
            inf = inf.max(r);
        }
        (sq.sqrt(), inf)
    }

    /// Adds `½‖W^{1/2}(A x − b)‖²` (with `weight_override` on every row if given) to `H`, `g`.
    fn add_cost(
        &mut self,
        h: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
        weight_override: Option<f64>,
    ) {
        for i in 0..self.rows() {
            let w = weight_override.unwrap_or(self.weight[i]).sqrt();
            for c in 0..self.width {
                self.aw[(i, c)] = w * self.a[(i, c)];
            }
            self.bw[i] = w * self.b[i];
        }
        // AᵀWA: dense product, or a row-by-row sum over the nonzeros when A is sparse (selection matrices,
        // identities, contact blocks), which is much cheaper for posture / regularisation tasks.
        let nnz = self.aw.iter().filter(|v| **v != 0.0).count();
        if 4 * nnz >= self.aw.len() {
            self.hk.gemm_tr(1.0, &self.aw, &self.aw, 0.0);
        } else {
            self.hk.fill(0.0);
            for i in 0..self.rows() {
                self.nz.clear();
                for c in 0..self.width {
                    if self.aw[(i, c)] != 0.0 {
                        self.nz.push(c);
                    }
                }
                for (k, &c1) in self.nz.iter().enumerate() {
                    let v1 = self.aw[(i, c1)];
                    for &c2 in &self.nz[k..] {
                        let v = v1 * self.aw[(i, c2)];
                        self.hk[(c1, c2)] += v;
                        if c1 != c2 {
                            self.hk[(c2, c1)] += v;
                        }
                    }
                }
            }
        }
        self.gk.gemv_tr(-1.0, &self.aw, &self.bw, 0.0);
        for (ra, oa) in &self.blocks {
            for (rb, ob) in &self.blocks {
                for (cb, jb) in rb.clone().enumerate() {
                    for (ca, ia) in ra.clone().enumerate() {
                        h[(ia, jb)] += self.hk[(oa + ca, ob + cb)];
                    }
                }
            }
            for (ca, ia) in ra.clone().enumerate() {
                g[ia] += self.gk[oa + ca];
            }
        }
    }

    /// Writes the task rows into `m` (rows `row0..`), zero outside the task's columns.
    fn write_rows(&self, m: &mut DMatrix<f64>, row0: usize) {
        for i in 0..self.rows() {
            for c in 0..m.ncols() {
                m[(row0 + i, c)] = 0.0;
            }
        }
        for (range, offset) in &self.blocks {
            for (k, col) in range.clone().enumerate() {
                for i in 0..self.rows() {
                    m[(row0 + i, col)] = self.a[(i, offset + k)];
                }
            }
        }
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
    /// Objective value of the solved problem at `x`.
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
        })
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
    /// The dense QP solved last (the relaxed one when the fallback path was taken).
    pub fn dense_qp(&self) -> &DenseQp {
        match self.solution.path {
            SolvePath::Nominal => &self.nominal,
            SolvePath::Relaxed => &self.relaxed,
        }
    }
    /// The raw backend output (with multipliers) of the last solve, matching [`QpProblem::dense_qp`].
    pub fn solver_output(&self) -> &SolverOutput {
        match self.solution.path {
            SolvePath::Nominal => &self.out,
            SolvePath::Relaxed => &self.out_relaxed,
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
            SolvePath::Relaxed => (
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
        if status.is_success() {
            Ok(&self.solution)
        } else {
            Err(QpError::SolveFailed {
                nominal: nominal_status,
                relaxed: relaxed_status,
            })
        }
    }
}
