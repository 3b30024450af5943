//! From the controllers' tasks to stride-qp: one [`QpProblem`] whose tasks all span the controller's
//! whole decision vector (so a task's row `i`, column `j` is `x_j`'s coefficient); the task library
//! writes its rows straight into the problem's task storage ([`QpBridge::task`]) and
//! [`QpBridge::solve`] turns the solution into a [`SolveReport`]. Null-space elimination of the hard
//! equalities and the relaxed fallback are stride-qp's solve paths.

use std::time::Instant;

use nalgebra::DVector;
use stride_qp::{
    QpProblem, QpSettings, SolvePath, Task, TaskDataMut, TaskId, TaskKind, TaskSpec, VarId,
    VariableSet, Weight,
};

use crate::config::Priority;
use crate::error::WbcError;
use crate::io::SolveReport;

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

    /// A hard equality task over every variable.
    pub fn hard(&self, name: &str, rows: usize) -> TaskSpec {
        TaskSpec::equality(name, &self.ids, rows)
    }

    /// A soft equality task over every variable.
    pub fn soft(&self, name: &str, rows: usize, weight: Weight) -> TaskSpec {
        TaskSpec::equality(name, &self.ids, rows).soft_weight(weight)
    }

    /// An equality task of the configured priority over every variable; a weight on a hard task and a
    /// weight of the wrong length or value are configuration errors naming the task.
    pub fn equality(
        &self,
        name: &str,
        rows: usize,
        priority: Priority,
        weight: &Option<Weight>,
    ) -> Result<TaskSpec, WbcError> {
        Ok(match priority_weight(name, rows, priority, weight)? {
            None => self.hard(name, rows),
            Some(w) => self.soft(name, rows, w),
        })
    }

    /// An inequality task over every variable.
    pub fn inequality(&self, name: &str, rows: usize) -> TaskSpec {
        TaskSpec::inequality(name, &self.ids, rows)
    }
}

/// The weight of a configured equality task with `rows` rows: `None` for a hard task (which must not
/// have one), the configured weight (default 1) for a soft task, checked.
pub(crate) fn priority_weight(
    name: &str,
    rows: usize,
    priority: Priority,
    weight: &Option<Weight>,
) -> Result<Option<Weight>, WbcError> {
    match (priority, weight) {
        (Priority::Hard, Some(_)) => Err(WbcError::InvalidConfig {
            task: name.to_owned(),
            key: "weight",
            reason: "a hard task has no weight: remove `weight` or set `priority = \"soft\"`"
                .into(),
        }),
        (Priority::Hard, None) => Ok(None),
        (Priority::Soft, w) => {
            let w = w.clone().unwrap_or_default();
            check_weight(name, &w, rows)?;
            Ok(Some(w))
        }
    }
}

/// Checks a configured weight: a scalar or `rows` entries, each finite and ≥ 0.
pub(crate) fn check_weight(task: &str, weight: &Weight, rows: usize) -> Result<(), WbcError> {
    weight
        .validate(task, rows)
        .map_err(|e| WbcError::InvalidConfig {
            task: task.to_owned(),
            key: "weight",
            reason: e.to_string(),
        })
}

/// `‖A x − b‖` (equality) or the norm of the side violations (inequality) of a task over the whole
/// decision vector. No allocation.
fn residual(task: &Task, x: &DVector<f64>) -> f64 {
    let a = task.a();
    let mut sum = 0.0;
    for i in 0..a.nrows() {
        let mut ax = 0.0;
        for j in 0..a.ncols() {
            ax += a[(i, j)] * x[j];
        }
        let r = match task.kind() {
            TaskKind::Equality => ax - task.b()[i],
            TaskKind::Inequality => {
                (task.lower()[i] - ax).max(0.0) + (ax - task.upper()[i]).max(0.0)
            }
        };
        sum += r * r;
    }
    sum.sqrt()
}

/// One QP of fixed structure (the task specs given at construction, task `k` has id `TaskId(k)`).
pub(crate) struct QpBridge {
    problem: QpProblem,
    ids: Vec<VarId>,
    /// Whether the last solve wrote its solution to the caller's `x`.
    solved: bool,
    /// Per task: `None` while enabled; `Some((hard, weights))` while disabled: what to restore.
    disabled: Vec<Option<(bool, DVector<f64>)>>,
    /// Per task: a buffer of its row count, so that disabling allocates nothing.
    spare: Vec<Option<DVector<f64>>>,
}

impl QpBridge {
    /// Builds the problem; with `eliminate`, adds stride-qp's null-space solve path.
    pub fn new(
        layout: VariableLayout,
        specs: Vec<TaskSpec>,
        settings: &QpSettings,
        eliminate: bool,
    ) -> Result<Self, WbcError> {
        // `QpProblem::new` sizes every workspace of both backends (nominal and relaxed) and the null-space
        // path sizes its own: no solve allocates, the first included (stride-qp's and this crate's
        // counting-allocator tests), so nothing is solved here. (A priming solve of each QP here cost
        // 34.5 M instructions of the torque walk's start-up: docs/performance.md.)
        let mut problem = QpProblem::new(layout.set, specs, settings.clone())?;
        if eliminate {
            problem.enable_null_space()?;
        }
        let spare = problem
            .tasks()
            .iter()
            .map(|t| Some(DVector::zeros(t.rows())))
            .collect();
        Ok(QpBridge {
            disabled: vec![None; problem.n_tasks()],
            spare,
            problem,
            ids: layout.ids,
            solved: false,
        })
    }

    /// The stride-qp problem solved last: the null-space reduced one (variable
    /// `null_space_coordinates`) or the full one (data, solution, KKT check).
    pub fn problem(&self) -> &QpProblem {
        self.problem.last_solved()
    }

    /// The residual of task `k` at `x` (see [`residual`]): stride-qp's, computed with the solution, when
    /// the last [`QpBridge::solve`] wrote `x`; recomputed when it held `x`.
    pub fn residual(&self, k: usize, x: &DVector<f64>) -> f64 {
        if self.solved {
            self.problem.solution().task_residuals[k]
        } else {
            residual(self.task(k), x)
        }
    }

    /// Task `k`.
    pub fn task(&self, k: usize) -> &Task {
        self.problem.task(TaskId(k))
    }

    /// The rows of task `k`, to be written in place.
    pub fn rows_mut(&mut self, k: usize) -> TaskDataMut<'_> {
        self.problem.task_mut(TaskId(k)).data_mut()
    }

    /// Sets the weights of soft task `k` (one value or one per row). Errors: a disabled task.
    pub fn set_weights(&mut self, k: usize, weights: &[f64]) -> Result<(), WbcError> {
        self.check_enabled(k)?;
        Ok(self.problem.task_mut(TaskId(k)).set_weights(weights)?)
    }

    /// Sets the weight of row `row` of soft task `k`. Errors: a disabled task.
    pub fn set_row_weight(&mut self, k: usize, row: usize, weight: f64) -> Result<(), WbcError> {
        self.check_enabled(k)?;
        Ok(self
            .problem
            .task_mut(TaskId(k))
            .set_row_weight(row, weight)?)
    }

    fn check_enabled(&self, k: usize) -> Result<(), WbcError> {
        match self.disabled[k] {
            None => Ok(()),
            Some(_) => Err(WbcError::InvalidInput(format!(
                "task `{}` is disabled: enable it before changing its weight",
                self.task(k).name()
            ))),
        }
    }

    /// Whether equality task `k` takes part in the problem.
    pub fn is_enabled(&self, k: usize) -> bool {
        self.disabled[k].is_none()
    }

    /// Takes equality task `k` out of the problem (soft with zero weights: its rows cost nothing) or puts
    /// it back with the priority and weights it had. Idempotent, allocation-free. Errors: an inequality.
    pub fn set_enabled(&mut self, k: usize, enabled: bool) -> Result<(), WbcError> {
        let task = self.problem.task_mut(TaskId(k));
        if task.kind() != TaskKind::Equality {
            return Err(WbcError::InvalidInput(format!(
                "task `{}` is a constraint: it cannot be disabled",
                task.name()
            )));
        }
        match (enabled, self.disabled[k].is_some()) {
            (false, false) => {
                let mut saved = self.spare[k].take().unwrap_or_default();
                saved.copy_from(task.weights());
                let hard = task.is_hard();
                task.set_hard(false)?;
                task.set_weight(0.0)?;
                self.disabled[k] = Some((hard, saved));
            }
            (true, true) => {
                if let Some((hard, saved)) = self.disabled[k].take() {
                    task.set_weights(saved.as_slice())?;
                    task.set_hard(hard)?;
                    self.spare[k] = Some(saved);
                }
            }
            _ => {}
        }
        Ok(())
    }

    pub fn reset(&mut self) {
        self.problem.reset_warm_start();
    }

    /// Solves with the variable bounds `lower ≤ x ≤ upper`; on success writes `x`. When the full
    /// problem's nominal and relaxed solves both fail `x` is left untouched and `held` is set.
    pub fn solve(
        &mut self,
        lower: &DVector<f64>,
        upper: &DVector<f64>,
        x: &mut DVector<f64>,
    ) -> SolveReport {
        let start = Instant::now();
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
        self.solved = ok && sol.x.iter().all(|v| v.is_finite());
        if self.solved {
            x.copy_from(&sol.x);
            report.fallback = sol.path == SolvePath::Relaxed;
        } else {
            report.held = true;
        }
        report
    }
}
