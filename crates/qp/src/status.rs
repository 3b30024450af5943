//! The outcome of a solve, shared by the backends, the errors and the problems.

use serde::{Deserialize, Serialize};

/// Outcome of one backend solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QpStatus {
    /// No solve has run yet.
    #[default]
    NotSolved,
    /// Optimal to the backend's tolerances; `x` is a valid solution.
    Solved,
    /// The backend stopped at reduced accuracy (clarabel `AlmostSolved`); `x` is finite and usable with care.
    SolvedInaccurate,
    /// The constraints admit no solution.
    Infeasible,
    /// The cost is unbounded below on the feasible set (only possible with a singular `H`).
    Unbounded,
    /// The iteration limit was reached.
    MaxIterations,
    /// The Hessian is not positive definite (the active-set backend needs `H ≻ 0`).
    HessianNotPositiveDefinite,
    /// The input contains NaN/∞ where it must be finite, or inconsistent sides (`l > u`).
    InvalidData,
    /// A numerical failure (breakdown, non-finite iterate, stalled progress).
    NumericalError,
}

impl QpStatus {
    /// Whether `x` can be used (`Solved` or `SolvedInaccurate`).
    pub fn is_success(self) -> bool {
        matches!(self, QpStatus::Solved | QpStatus::SolvedInaccurate)
    }
}
