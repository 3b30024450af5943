//! `stride-qp`: the quadratic programs of the whole-body controllers.
//!
//! * [`VariableSet`] names the blocks of the decision vector (`base_velocity`, `joint_velocities`, …).
//! * [`QpProblem`] is assembled once from [`TaskSpec`]s: each task fills `A x = b` (equality) or
//!   `l ≤ A x ≤ u` (inequality) over the variables it names; equalities are hard constraints or soft costs
//!   `½‖W^{1/2}(A x − b)‖²` with run-time weights; a Tikhonov term `½ρ‖x‖²` is added. Every tick the caller
//!   writes numbers into the preallocated task buffers and calls [`QpProblem::solve`] (allocation-free with
//!   the active-set backend).
//! * Backends implement [`QpSolver`] on the dense standard form [`DenseQp`]: [`ActiveSetSolver`] (our
//!   Goldfarb–Idnani dual active-set solver, warm-started, the default) and [`ClarabelSolver`] (interior point,
//!   the reference). [`check_kkt`] verifies any primal–dual answer independently.
//! * [`QpProblem::enable_null_space`] adds the fast path of the whole-body controllers: the hard equality
//!   tasks are eliminated by a null-space parametrization and the smaller equality-free problem is solved
//!   first ([`SolvePath::NullSpace`]).
//! * A soft task's [`Weight`] (scalar or per row) is the same type from a TOML file to the QP.
//! * Failures are explicit ([`QpStatus`], [`QpError::SolveFailed`]); with `fallback` enabled an infeasible
//!   problem is re-solved with its hard equality tasks relaxed into soft ones ([`SolvePath::Relaxed`]).
//! * Large sparse problems (the DCM MPC) go through [`SparseQp`] and [`ClarabelSparseSolver`] without
//!   densification.
#![warn(missing_docs)]

mod active_set;
mod banded;
mod clarabel_backend;
mod dense;
mod error;
mod finite;
mod kkt;
mod nullspace;
mod problem;
mod solver;
mod sparse;
mod status;
mod task;
pub mod testing;
mod variables;
mod weight;

pub use active_set::{ActiveSetSettings, ActiveSetSolver, StartKind};
pub use banded::{BandMatrix, BandedOutcome, BandedQp, BandedQpError, BandedSettings};
pub use clarabel_backend::{ClarabelSettings, ClarabelSolver, ClarabelSparseSolver};
pub use dense::DenseQp;
pub use error::QpError;
pub use kkt::{check_kkt, KktReport};
pub use problem::{Backend, QpProblem, QpSettings, QpSolution, SolvePath};
pub use solver::{QpSolver, SolverOutput};
pub use sparse::{SparseQp, SparseSolution};
pub use status::QpStatus;
pub use task::{Task, TaskDataMut, TaskId, TaskKind, TaskSpec};
pub use variables::{VarId, VariableSet};
pub use weight::Weight;
