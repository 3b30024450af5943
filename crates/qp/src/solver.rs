//! The backend interface: [`QpSolver`], its output and status.

use crate::dense::DenseQp;
use crate::status::QpStatus;
use nalgebra::{DVector, DVectorView};

/// What a backend writes: the primal solution, the multipliers and diagnostics.
///
/// Multiplier convention (shared by all backends and by [`crate::check_kkt`]): stationarity reads
///
/// ```text
/// H x + g + Eᵀ y + Cᵀ z + w = 0
/// ```
///
/// with `y` free, `z_i > 0` only if the upper side `C_i x = u_i` is active and `z_i < 0` only if the lower side
/// is active, and the same sign rule for the bound multipliers `w_j`.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverOutput {
    /// Primal solution (length n). Always finite; zero when the solve failed before producing an iterate.
    pub x: DVector<f64>,
    pub(crate) y: DVector<f64>,
    pub(crate) z: DVector<f64>,
    /// Multipliers of the variable bounds (length n).
    pub bound_multipliers: DVector<f64>,
    pub(crate) n_eq: usize,
    pub(crate) n_ineq: usize,
    /// Solve status.
    pub status: QpStatus,
    /// Backend iterations (active-set changes for the active-set solver, interior-point iterations for clarabel).
    pub iterations: usize,
    /// Whether the backend started from a previous active set (and kept it).
    pub warm_started: bool,
    /// Objective `½ xᵀHx + gᵀx` at `x`.
    pub objective: f64,
}

impl SolverOutput {
    /// Buffers sized for `qp` (its capacities), status [`QpStatus::NotSolved`].
    pub fn new(qp: &DenseQp) -> Self {
        Self {
            x: DVector::zeros(qp.n()),
            y: DVector::zeros(qp.eq_capacity()),
            z: DVector::zeros(qp.ineq_capacity()),
            bound_multipliers: DVector::zeros(qp.n()),
            n_eq: qp.n_eq(),
            n_ineq: qp.n_ineq(),
            status: QpStatus::NotSolved,
            iterations: 0,
            warm_started: false,
            objective: 0.0,
        }
    }

    /// Equality multipliers `y` (rows in use).
    pub fn eq_multipliers(&self) -> DVectorView<'_, f64> {
        self.y.rows(0, self.n_eq)
    }
    /// Inequality multipliers `z` (rows in use).
    pub fn ineq_multipliers(&self) -> DVectorView<'_, f64> {
        self.z.rows(0, self.n_ineq)
    }

    /// Resizes the buffers for `qp` if needed (allocates only when a capacity grew) and zeroes everything.
    pub(crate) fn prepare(&mut self, qp: &DenseQp) {
        if self.x.len() != qp.n() {
            self.x = DVector::zeros(qp.n());
            self.bound_multipliers = DVector::zeros(qp.n());
        }
        if self.y.len() < qp.n_eq() {
            self.y = DVector::zeros(qp.eq_capacity().max(qp.n_eq()));
        }
        if self.z.len() < qp.n_ineq() {
            self.z = DVector::zeros(qp.ineq_capacity().max(qp.n_ineq()));
        }
        self.n_eq = qp.n_eq();
        self.n_ineq = qp.n_ineq();
        self.x.fill(0.0);
        self.y.fill(0.0);
        self.z.fill(0.0);
        self.bound_multipliers.fill(0.0);
        self.status = QpStatus::NotSolved;
        self.iterations = 0;
        self.warm_started = false;
        self.objective = 0.0;
    }

    /// Replaces a non-finite result by zeros and a [`QpStatus::NumericalError`] (never emit NaN).
    pub(crate) fn sanitize(&mut self) {
        let finite = self.x.iter().all(|v| v.is_finite())
            && self.y.iter().all(|v| v.is_finite())
            && self.z.iter().all(|v| v.is_finite())
            && self.bound_multipliers.iter().all(|v| v.is_finite());
        if !finite {
            self.x.fill(0.0);
            self.y.fill(0.0);
            self.z.fill(0.0);
            self.bound_multipliers.fill(0.0);
            self.objective = 0.0;
            if self.status.is_success() || self.status == QpStatus::NotSolved {
                self.status = QpStatus::NumericalError;
            }
        }
        if !self.objective.is_finite() {
            self.objective = 0.0;
        }
    }
}

/// A QP backend: solves a [`DenseQp`] into a [`SolverOutput`].
///
/// Implementations keep their own workspace (and, if they can, a warm start from the previous call).
pub trait QpSolver: Send {
    /// Short backend name for logs (`"active_set"`, `"clarabel"`).
    fn name(&self) -> &'static str;

    /// Solves `qp`, overwriting `out` (which must come from [`SolverOutput::new`] on a problem of the same
    /// size, or is resized). Never leaves NaN in `out`; failures are reported through `out.status`.
    fn solve(&mut self, qp: &DenseQp, out: &mut SolverOutput);

    /// Forgets any warm-start information.
    fn reset(&mut self) {}

    /// Allocates workspace for problems with up to `n` variables, `n_eq` equality and `n_ineq` inequality
    /// rows, so that even the first solve allocates nothing (where the backend can guarantee it). Default:
    /// no-op.
    fn reserve(&mut self, n: usize, n_eq: usize, n_ineq: usize) {
        let _ = (n, n_eq, n_ineq);
    }
}
