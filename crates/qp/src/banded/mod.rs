//! A primal–dual interior-point method (Mehrotra predictor–corrector) for convex QPs whose Hessian is
//! banded and whose constraint rows each touch a few neighbouring variables:
//!
//! `min ½ xᵀPx + qᵀx  s.t.  Cx ≤ d`
//!
//! Each Newton system `(P + Cᵀ diag(λ/s) C) Δx = r` stays banded and is solved by a banded Cholesky in
//! `O(n b²)` [Nocedal 2006, §16.6; Mehrotra 1992]. The rows are grouped by the 2-D point they
//! constrain (for the DCM MPC: the ZMP of one stage and the edges of its support polygon). All memory
//! is allocated in [`BandedQp::new`]; [`BandedQp::solve`] allocates nothing. The same problem can be
//! handed to clarabel for reference ([`BandedQp::solve_with_clarabel`],
//! [`BandedQp::solve_with_sparse_clarabel`]).

mod band;
mod ipm;
mod problem;
mod reference;
mod rows;

/// Test data shared by the unit tests of the banded modules.
#[cfg(test)]
mod test_numbers {
    /// Deterministic pseudo-random numbers in [−1, 1) (a 64-bit linear congruential generator).
    pub(crate) fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }
}

pub use band::BandMatrix;
pub use ipm::{BandedOutcome, BandedSettings};
pub use problem::BandedQp;

/// A banded QP built against its structure (the solve itself reports through [`BandedOutcome`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BandedQpError {
    /// An entry written outside the matrix or outside its band.
    #[error(
        "entry ({row}, {column}) is outside the band of the {n}×{n} matrix (half-bandwidth 5)"
    )]
    OutsideBand {
        /// Row index.
        row: usize,
        /// Column index.
        column: usize,
        /// Size of the matrix.
        n: usize,
    },
    /// More groups or rows than the problem was built for.
    #[error("more constraint {what} than the capacity {capacity}")]
    CapacityExceeded {
        /// `"groups"` or `"rows"`.
        what: &'static str,
        /// The capacity given to [`BandedQp::new`].
        capacity: usize,
    },
    /// The point of a group cannot be used.
    #[error("invalid point of a row group: {reason}")]
    InvalidPoint {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A row was pushed before any group.
    #[error("a constraint row was pushed before any group")]
    NoGroup,
}
