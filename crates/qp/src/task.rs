//! Tasks: their declaration ([`TaskSpec`]) and their preallocated storage ([`Task`]), which callers write
//! in place every tick (through [`Task::data_mut`] or the single accessors) and [`crate::QpProblem`]
//! assembles into the dense standard form.

use std::ops::Range;

use nalgebra::{DMatrix, DMatrixViewMut, DVector};
use serde::{Deserialize, Serialize};

use crate::error::QpError;
use crate::variables::{VarId, VariableSet};
use crate::weight::{check_weights, Weight};

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
    /// Row weights of a soft task (`None`: 1 on every row). A hard task must have none
    /// ([`QpError::WeightOnHardTask`]).
    pub weight: Option<Weight>,
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
            weight: None,
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
            weight: None,
        }
    }

    /// Makes the task soft with the same weight on every row.
    pub fn soft(self, weight: f64) -> Self {
        self.soft_weight(Weight::Scalar(weight))
    }

    /// Makes the task soft with one weight per row.
    pub fn soft_weights(self, weights: &[f64]) -> Self {
        self.soft_weight(Weight::PerRow(weights.to_vec()))
    }

    /// Makes the task soft with `weight` (the configuration's type: scalar or per row).
    pub fn soft_weight(mut self, weight: Weight) -> Self {
        self.hard = false;
        self.weight = Some(weight);
        self
    }

    /// Makes the task hard (a weight given before is kept, and rejected when the problem is built).
    pub fn hard(mut self) -> Self {
        self.hard = true;
        self
    }
}

/// Handle of a task inside a [`crate::QpProblem`] (index in declaration order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TaskId(pub usize);

/// A task's preallocated data, written every tick through [`crate::QpProblem::task_mut`].
///
/// Its matrix `A` has `rows` rows and one column per scalar of the task's variables, concatenated in the order
/// the spec listed them (use [`Task::var_block_mut`] to address the columns of one variable).
#[derive(Clone, Debug)]
pub struct Task {
    pub(crate) name: String,
    pub(crate) kind: TaskKind,
    pub(crate) vars: Vec<VarId>,
    /// (range in x, offset in the task's columns)
    pub(crate) blocks: Vec<(Range<usize>, usize)>,
    pub(crate) width: usize,
    pub(crate) a: DMatrix<f64>,
    pub(crate) b: DVector<f64>,
    pub(crate) lower: DVector<f64>,
    pub(crate) upper: DVector<f64>,
    pub(crate) hard: bool,
    pub(crate) weight: DVector<f64>,
    pub(crate) aw: DMatrix<f64>,
    pub(crate) bw: DVector<f64>,
    pub(crate) hk: DMatrix<f64>,
    pub(crate) gk: DVector<f64>,
    pub(crate) ax: DVector<f64>,
    pub(crate) nz: Vec<usize>,
}

impl Task {
    pub(crate) fn new(spec: &TaskSpec, vars: &VariableSet) -> Result<Self, QpError> {
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
            ax: DVector::zeros(rows),
            nz: Vec::with_capacity(width),
        };
        match (&spec.weight, spec.hard) {
            (Some(_), true) => {
                return Err(QpError::WeightOnHardTask {
                    task: spec.name.clone(),
                })
            }
            (Some(w), false) => task.set_weights(w.as_slice())?,
            (None, _) => {}
        }
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
        check_weights(&self.name, weights, self.rows())?;
        if weights.len() == 1 {
            self.weight.fill(weights[0]);
        } else {
            self.weight.copy_from_slice(weights);
        }
        Ok(())
    }
    /// Sets the weight of one row (finite, ≥ 0). Allocation-free.
    pub fn set_row_weight(&mut self, row: usize, weight: f64) -> Result<(), QpError> {
        if row >= self.rows() {
            return Err(QpError::WeightSize {
                task: self.name.clone(),
                expected: self.rows(),
                got: row + 1,
            });
        }
        if !(weight >= 0.0 && weight.is_finite()) {
            return Err(QpError::InvalidWeight {
                task: self.name.clone(),
                row,
                value: weight,
            });
        }
        self.weight[row] = weight;
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

    /// Mutable views of the task's rows, for writing them in place every tick: `A` (rows × width, columns
    /// in the order of [`Task::variables`]), `b` (equalities) and `l`, `u` (inequalities). Entries not
    /// written keep their previous value (zero, `−∞`, `+∞` after construction).
    pub fn data_mut(&mut self) -> TaskDataMut<'_> {
        TaskDataMut {
            a: &mut self.a,
            b: &mut self.b,
            lower: &mut self.lower,
            upper: &mut self.upper,
        }
    }

    /// Residual at `x`: `‖A x − b‖₂` for equalities, the 2-norm of the side violations for inequalities;
    /// also returns the ∞-norm.
    pub(crate) fn residual(&mut self, x: &DVector<f64>) -> (f64, f64) {
        // A x as a sum of A's (contiguous) columns
        let rows = self.rows();
        let a = self.a.as_slice();
        let ax = self.ax.as_mut_slice();
        ax.fill(0.0);
        for (range, offset) in &self.blocks {
            for (k, j) in range.clone().enumerate() {
                let xj = x[j];
                let col = &a[(offset + k) * rows..(offset + k + 1) * rows];
                for (o, v) in ax.iter_mut().zip(col) {
                    *o += v * xj;
                }
            }
        }
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
    pub(crate) fn add_cost(
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
    pub(crate) fn write_rows(&self, m: &mut DMatrix<f64>, row0: usize) {
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

/// The rows of one [`Task`], borrowed mutably all at once (see [`Task::data_mut`]).
#[derive(Debug)]
pub struct TaskDataMut<'a> {
    /// `A` (rows × width).
    pub a: &'a mut DMatrix<f64>,
    /// `b` of an equality task (ignored for inequalities).
    pub b: &'a mut DVector<f64>,
    /// Lower sides `l` of an inequality task (−∞ = none; ignored for equalities).
    pub lower: &'a mut DVector<f64>,
    /// Upper sides `u` of an inequality task (+∞ = none; ignored for equalities).
    pub upper: &'a mut DVector<f64>,
}

impl TaskDataMut<'_> {
    /// A shorter-lived copy of the views (to pass them on and keep using them).
    pub fn reborrow(&mut self) -> TaskDataMut<'_> {
        TaskDataMut {
            a: self.a,
            b: self.b,
            lower: self.lower,
            upper: self.upper,
        }
    }
}
