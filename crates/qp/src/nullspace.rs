//! Null-space elimination of the hard equality tasks: the fast solve path of a [`QpProblem`] whose hard
//! equalities are few and independent (the whole-body controllers' feet, CoM and dynamics rows).
//!
//! With the hard equality rows `A_e x = b_e` (m rows, full row rank) factor `A_eᵀ = Q R` (Householder,
//! [Golub 2013, §5.2]); then every solution is `x = x_p + N z` with `x_p = Q₁ R⁻ᵀ b_e` and `N = Q₂`
//! (orthonormal, nx × (nx − m)) [Nocedal 2006, §15.3, eq. 15.15]. Soft tasks become `(A N) z = b − A x_p`,
//! inequalities `l − C x_p ≤ (C N) z ≤ u − C x_p`, the variable bounds the rows `lb − x_p ≤ N z ≤ ub − x_p`.
//! The reduced QP has no equality constraint and `nz = nx − m` variables; it is solved by the same backend
//! without fallback (a failure sends the caller to the full problem).
//!
//! Cost per solve (what makes this path cheap; measured in docs/performance.md): only the `nz` columns of
//! `Q` that form `N` are built (the reflectors applied to `[0; I]`, never the `nx × nx` matrix `Q`); each
//! task is projected once as a sum over the nonzero entries of its `A`, and a task whose `A` equals an
//! earlier task's this tick (the TSID's torque limits and torque regularization share `[M_s | −J_sᵀ]`)
//! reuses that projection; the reduced Hessian `ρ I + Σ_soft (A N)ᵀ W (A N)` is accumulated from the stacked
//! weighted soft rows into one triangle, straight into the backend's dense QP (no per-task Hessian, no
//! reduced tasks); only the variables with a finite bound get a bound row. nalgebra's `gemm`
//! (matrixmultiply) was measured faster for the dense products but allocates its packing buffers at every
//! call, so the products here are our own register-tiled loops ([`kernels`]: equal bit for bit to plain
//! rank-one updates, with a fraction of their instructions; docs/performance.md).

use std::time::Instant;

use nalgebra::{DMatrix, DVector};

use crate::error::QpError;
use crate::problem::{QpProblem, QpSettings};
use crate::status::QpStatus;
use crate::task::{Task, TaskKind};
use crate::variables::VariableSet;

pub(crate) mod kernels;
use kernels::{add_lower_gram, apply_reflectors, project_row, Reflectors, SparseColumns};

/// Relative pivot threshold of `R` below which `A_e` is treated as rank deficient (full path instead).
const RANK_TOLERANCE: f64 = 1e-9;

/// The image of one soft or inequality task in the reduced problem.
struct Projected {
    /// `(A N)ᵀ` (nz × rows): column `i` is row `i` of `A N`, contiguous.
    pt: DMatrix<f64>,
    /// `A x_p` (rows).
    shift: DVector<f64>,
    /// Earlier tasks of the same shape: when one's `A` equals this task's, its projection is reused.
    twins: Vec<usize>,
}

/// The reduced problem of a [`QpProblem`] and the workspace of its factorization (all preallocated).
pub(crate) struct NullSpace {
    /// The reduced QP over the variable `null_space_coordinates` (nz scalars): a problem without tasks
    /// whose dense QP is written here every solve.
    pub(crate) problem: QpProblem,
    /// Hard flags of the full tasks when the reduction was built (a change disables the path).
    hard: Vec<bool>,
    m: usize,
    nx: usize,
    nz: usize,
    /// `A_eᵀ` (nx × m), overwritten by the Householder vectors (and the strict upper part of `R`).
    at: DMatrix<f64>,
    tau: DVector<f64>,
    /// `b_e`, then `y = R⁻ᵀ b_e` in place.
    b_e: DVector<f64>,
    /// Diagonal of `R`.
    r_diag: DVector<f64>,
    /// `Nᵀ` (nz × nx): column `j` is row `j` of `N`, so that `A N` is a sum of contiguous columns.
    nt: DMatrix<f64>,
    x_p: DVector<f64>,
    /// Workspace of a projection: the nonzero entries `(j, a_ij)` of one row of a task's `A` (nx).
    nonzeros: Vec<(usize, f64)>,
    /// Per full task: its projection (`None` for the hard equalities).
    proj: Vec<Option<Projected>>,
    /// Per full task, this solve: the task whose projection it uses (itself or an equal twin).
    source: Vec<usize>,
    /// `W^{1/2} (A N)` of every soft row, transposed (nz × soft rows), and `W^{1/2} (b − A x_p)`.
    soft: DMatrix<f64>,
    soft_rhs: DVector<f64>,
}

impl NullSpace {
    /// The reduction of `tasks` (over `nx` variables), or `None` when there is no hard equality row or
    /// at least `nx` of them.
    pub(crate) fn new(
        tasks: &[Task],
        nx: usize,
        settings: &QpSettings,
    ) -> Result<Option<Self>, QpError> {
        let is_hard_eq = |t: &Task| t.kind == TaskKind::Equality && t.hard;
        let m: usize = tasks
            .iter()
            .filter(|t| is_hard_eq(t))
            .map(|t| t.rows())
            .sum();
        if m == 0 || m >= nx {
            return Ok(None);
        }
        let nz = nx - m;
        let mut vars = VariableSet::new();
        vars.add("null_space_coordinates", nz)?;
        let ineq_rows: usize = tasks
            .iter()
            .filter(|t| t.kind == TaskKind::Inequality)
            .map(|t| t.rows())
            .sum();
        let mut settings = settings.clone();
        // no hard equality is left to relax: failures go to the full problem
        settings.fallback = false;
        // measured: on these equality-free problems the dual active-set solver's cold start (from the
        // unconstrained minimum) is faster than re-imposing the previous active set (IK 7 µs vs 87 µs,
        // TSID 41 µs vs 68 µs on the bundled model), but the previous active set as a guess (the
        // unconstrained minimum when it was empty), checked for optimality and dropped for a cold start
        // when it fails, is cheaper than both: no `J₀ = L⁻ᵀ`, no Givens rotation. `QpProblem::raw`
        // builds the backend so when `active_set.reduced_guess` is on (off by default: its round-off moves
        // closed-loop limits; docs/performance.md, "the reduced QP's warm start").
        settings.active_set.warm_start = settings.active_set.reduced_guess;
        let problem = QpProblem::raw(vars, ineq_rows + nx, settings)?;
        let soft_rows: usize = tasks
            .iter()
            .filter(|t| t.kind == TaskKind::Equality && !t.hard)
            .map(|t| t.rows())
            .sum();
        let proj = tasks
            .iter()
            .enumerate()
            .map(|(k, t)| {
                (!is_hard_eq(t)).then(|| Projected {
                    pt: DMatrix::zeros(nz, t.rows()),
                    shift: DVector::zeros(t.rows()),
                    twins: (0..k)
                        .filter(|&e| {
                            let o = &tasks[e];
                            !is_hard_eq(o) && o.rows() == t.rows() && o.blocks == t.blocks
                        })
                        .collect(),
                })
            })
            .collect();
        Ok(Some(NullSpace {
            problem,
            hard: tasks.iter().map(|t| t.hard).collect(),
            m,
            nx,
            nz,
            at: DMatrix::zeros(nx, m),
            tau: DVector::zeros(m),
            b_e: DVector::zeros(m),
            r_diag: DVector::zeros(m),
            nt: DMatrix::zeros(nz, nx),
            x_p: DVector::zeros(nx),
            nonzeros: vec![(0, 0.0); nx],
            proj,
            source: (0..tasks.len()).collect(),
            soft: DMatrix::zeros(nz, soft_rows),
            soft_rhs: DVector::zeros(soft_rows),
        }))
    }

    /// Copies the hard equality rows into `A_eᵀ` and `b_e` (column by column of each task's `A`).
    #[inline(never)]
    fn gather(&mut self, tasks: &[Task]) {
        let nx = self.nx;
        let at = self.at.as_mut_slice();
        let mut row0 = 0;
        for t in tasks
            .iter()
            .filter(|t| t.kind == TaskKind::Equality && t.hard)
        {
            let rows = t.rows();
            if t.width != nx {
                at[row0 * nx..(row0 + rows) * nx].fill(0.0);
            }
            let a = t.a.as_slice();
            for (range, offset) in &t.blocks {
                for (k, j) in range.clone().enumerate() {
                    let col = &a[(offset + k) * rows..(offset + k + 1) * rows];
                    for (i, v) in col.iter().enumerate() {
                        at[(row0 + i) * nx + j] = *v;
                    }
                }
            }
            self.b_e.as_mut_slice()[row0..row0 + rows].copy_from_slice(t.b.as_slice());
            row0 += rows;
        }
    }

    /// Householder QR of `A_eᵀ` (in place, column slices: contiguous); false when rank deficient.
    #[inline(never)]
    fn householder(&mut self) -> bool {
        let (nx, m) = (self.nx, self.m);
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
            self.r_diag[k] = alpha;
            max_diag = max_diag.max(alpha.abs());
        }
        (0..m).all(|k| self.r_diag[k].abs() > RANK_TOLERANCE * max_diag)
    }

    /// `Nᵀ = (H_0 ⋯ H_{m−1} [0; I])ᵀ`: the last `nz` columns of `Q`, every reflector on them
    /// (`N ← N − τ_k v_k (v_kᵀ N)`, `v_k` on rows `k..nx`, tile by tile of columns); `Q₁` is never formed.
    #[inline(never)]
    fn basis(&mut self) {
        let (nx, m, nz) = (self.nx, self.m, self.nz);
        let nt = self.nt.as_mut_slice();
        nt.fill(0.0);
        for r in 0..nz {
            nt[(m + r) * nz + r] = 1.0;
        }
        let reflectors = Reflectors {
            v: self.at.as_slice(),
            tau: self.tau.as_slice(),
            nx,
        };
        apply_reflectors(&reflectors, nt, nz);
    }

    /// `x_p = Q₁ R⁻ᵀ b_e = H_0 ⋯ H_{m−1} [y; 0]` with `Rᵀ y = b_e` (forward substitution; `R`: diagonal in
    /// `r_diag`, strict upper part in `at`).
    #[inline(never)]
    fn particular(&mut self) {
        let (nx, m) = (self.nx, self.m);
        let at = self.at.as_slice();
        for k in 0..m {
            let mut s = self.b_e[k];
            for j in 0..k {
                s -= at[k * nx + j] * self.b_e[j];
            }
            self.b_e[k] = s / self.r_diag[k];
        }
        let x = self.x_p.as_mut_slice();
        x.fill(0.0);
        x[..m].copy_from_slice(&self.b_e.as_slice()[..m]);
        for k in (0..m).rev() {
            let vk = &at[k * nx + k..(k + 1) * nx];
            let tail = &mut x[k..];
            let dot: f64 = vk.iter().zip(tail.iter()).map(|(a, b)| a * b).sum();
            let f = self.tau[k] * dot;
            for (xv, v) in tail.iter_mut().zip(vk) {
                *xv -= f * v;
            }
        }
    }

    /// `pt = (A N)ᵀ` (nz × rows) and `shift = A x_p` for one task, row by row of `A`, as sums over the
    /// nonzero entries of the row (rows of `N`, contiguous columns of `Nᵀ`, scaled and added): the task
    /// matrices are sparse (posture and wrench rows are selections, Jacobians have zero columns off their
    /// chains, `M_s` zero blocks between branches).
    fn project(
        task: &Task,
        nt: &DMatrix<f64>,
        x_p: &DVector<f64>,
        nonzeros: &mut [(usize, f64)],
        p: &mut Projected,
    ) {
        let nz = nt.nrows();
        let a = SparseColumns {
            a: task.a.as_slice(),
            rows: task.a.nrows(),
            blocks: &task.blocks,
        };
        let rows = p.pt.as_mut_slice().chunks_exact_mut(nz);
        for (i, (row, shift)) in rows.zip(p.shift.iter_mut()).enumerate() {
            *shift = project_row(&a, i, nt.as_slice(), x_p.as_slice(), nonzeros, row);
        }
    }

    /// Projects every soft and inequality task (once per distinct `A`, see [`Projected::twins`]).
    #[inline(never)]
    fn project_all(&mut self, tasks: &[Task]) {
        for k in 0..tasks.len() {
            let Some(p) = &self.proj[k] else { continue };
            let twin = p
                .twins
                .iter()
                .copied()
                .find(|&e| tasks[e].a.as_slice() == tasks[k].a.as_slice());
            self.source[k] = match twin {
                Some(e) => self.source[e],
                None => {
                    let p = self.proj[k].as_mut().expect("checked above");
                    Self::project(&tasks[k], &self.nt, &self.x_p, &mut self.nonzeros, p);
                    k
                }
            };
        }
    }

    /// Stacks the soft rows scaled by the square roots of their weights: column `i` of `soft` is
    /// `√w_i (a_i N)ᵀ`, `soft_rhs[i] = √w_i (b_i − a_i x_p)`, so that the soft cost is
    /// `½‖Sᵀ z − r̃‖²` up to a constant. Returns the number of rows.
    #[inline(never)]
    fn stack_soft_rows(&mut self, tasks: &[Task]) -> usize {
        let nz = self.nz;
        let mut col = 0;
        for (k, t) in tasks.iter().enumerate() {
            if t.kind != TaskKind::Equality || t.hard {
                continue;
            }
            let p = self.proj[self.source[k]]
                .as_ref()
                .expect("soft tasks are projected");
            for i in 0..t.rows() {
                let w = t.weight[i].sqrt();
                let src = &p.pt.as_slice()[i * nz..(i + 1) * nz];
                let dst = &mut self.soft.as_mut_slice()[col * nz..(col + 1) * nz];
                for (d, v) in dst.iter_mut().zip(src) {
                    *d = w * v;
                }
                self.soft_rhs[col] = w * (t.b[i] - p.shift[i]);
                col += 1;
            }
        }
        col
    }

    /// Writes the reduced dense QP: Hessian `ρ I + Σ_soft (A N)ᵀ W (A N)`, gradient
    /// `−Σ_soft (A N)ᵀ W (b − A x_p)`, the projected inequality rows and one bound row per variable with a
    /// finite bound.
    #[inline(never)]
    fn write_reduced(&mut self, tasks: &[Task], lower: &DVector<f64>, upper: &DVector<f64>) {
        let nz = self.nz;
        let rho = self.problem.settings().regularization;
        let soft_rows = self.stack_soft_rows(tasks);
        let qp = self.problem.dense_mut();
        qp.h.fill(0.0);
        qp.h.fill_diagonal(rho);
        qp.g.fill(0.0);
        if soft_rows > 0 {
            // H += S Sᵀ (lower triangle, one soft row at a time), g = −S r̃
            add_lower_gram(
                qp.h.as_mut_slice(),
                &self.soft.as_slice()[..nz * soft_rows],
                nz,
            );
            let s = self.soft.columns(0, soft_rows);
            qp.g.gemv(-1.0, &s, &self.soft_rhs.rows(0, soft_rows), 0.0);
        }
        let mut row = 0;
        for (k, t) in tasks.iter().enumerate() {
            let Some(p) = &self.proj[self.source[k]] else {
                continue;
            };
            match t.kind {
                TaskKind::Equality => {}
                TaskKind::Inequality => {
                    for i in 0..t.rows() {
                        set_row(&mut qp.c, row, &p.pt.as_slice()[i * nz..(i + 1) * nz]);
                        qp.l[row] = t.lower[i] - p.shift[i];
                        qp.u[row] = t.upper[i] - p.shift[i];
                        row += 1;
                    }
                }
            }
        }
        for j in 0..self.nx {
            if lower[j].is_finite() || upper[j].is_finite() {
                set_row(&mut qp.c, row, &self.nt.as_slice()[j * nz..(j + 1) * nz]);
                qp.l[row] = lower[j] - self.x_p[j];
                qp.u[row] = upper[j] - self.x_p[j];
                row += 1;
            }
        }
        // the capacity holds every inequality row and every bound, so this cannot fail
        let _ = qp.set_n_ineq(row);
    }

    /// Factors, fills and solves the reduced problem; on an exact solve writes `x = x_p + N z` and returns
    /// the status and the backend iterations. `None` (and `x` untouched) when the hard rows are rank
    /// deficient, a task changed between hard and soft since construction, or the reduced solve is not
    /// [`QpStatus::Solved`].
    pub(crate) fn solve(
        &mut self,
        tasks: &[Task],
        lower: &DVector<f64>,
        upper: &DVector<f64>,
        x: &mut DVector<f64>,
    ) -> Option<(QpStatus, usize)> {
        let start = Instant::now();
        if tasks.iter().zip(&self.hard).any(|(t, &h)| t.hard != h) {
            return None;
        }
        self.gather(tasks);
        if !self.householder() {
            return None;
        }
        self.basis();
        self.particular();
        self.project_all(tasks);
        self.write_reduced(tasks, lower, upper);
        let sol = self.problem.solve_dense(start);
        // anything short of an exact solve goes to the full problem
        if sol.status != QpStatus::Solved || !sol.x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (z, nz) = (sol.x.as_slice(), self.nz);
        for j in 0..self.nx {
            let row = &self.nt.as_slice()[j * nz..(j + 1) * nz];
            x[j] = self.x_p[j] + row.iter().zip(z).map(|(n, z)| n * z).sum::<f64>();
        }
        Some((sol.status, sol.iterations))
    }
}

/// Writes `values` into row `row` of the column-major matrix `m`.
fn set_row(m: &mut DMatrix<f64>, row: usize, values: &[f64]) {
    let ld = m.nrows();
    for (c, v) in values.iter().enumerate() {
        m.as_mut_slice()[c * ld + row] = *v;
    }
}
