//! From task blocks to stride-qp: every block becomes one [`stride_qp::TaskSpec`] spanning all the
//! controller's variables; each tick copies the numbers in and calls [`QpProblem::solve`], whose relaxed
//! fallback (hard equalities as soft costs with `relaxation_weight`) is used as stride-qp documents it.

use nalgebra::DVector;
use stride_qp::{QpProblem, QpSettings, SolvePath, TaskId, TaskSpec, VarId, VariableSet};

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

/// One QP of fixed structure (the blocks given at construction).
pub(crate) struct QpBridge {
    problem: QpProblem,
    tasks: Vec<TaskId>,
    ids: Vec<VarId>,
}

impl QpBridge {
    pub fn new(
        layout: VariableLayout,
        blocks: &[TaskBlock],
        settings: &QpSettings,
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
        Ok(QpBridge {
            problem,
            tasks,
            ids: layout.ids,
        })
    }

    /// The stride-qp problem (last data, solution, KKT check).
    pub fn problem(&self) -> &QpProblem {
        &self.problem
    }

    pub fn reset(&mut self) {
        self.problem.reset_warm_start();
    }

    /// Residual of block `i` at the last solution (stride-qp's per-task residual).
    pub fn residual(&self, i: usize) -> f64 {
        self.problem.solution().task_residuals[i]
    }

    /// Copies the blocks and bounds in, solves; on success writes `x`. When both the nominal and the
    /// relaxed solve fail `x` is left untouched and `held` is set.
    pub fn solve(
        &mut self,
        blocks: &[TaskBlock],
        lower: &DVector<f64>,
        upper: &DVector<f64>,
        x: &mut DVector<f64>,
    ) -> SolveReport {
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
            solve_time: sol.solve_time.as_secs_f64(),
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
