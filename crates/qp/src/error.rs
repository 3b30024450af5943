//! Error type of the crate.

use crate::status::QpStatus;

/// Everything that can go wrong when building or solving a QP with this crate.
///
/// Construction errors carry the names of the variables / tasks involved; solve failures carry the status
/// of the nominal solve and, when the fallback ran, of the relaxed solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QpError {
    /// Two decision variables were declared with the same name.
    #[error("decision variable `{name}` is declared twice")]
    DuplicateVariable {
        /// The repeated name.
        name: String,
    },
    /// A decision variable was declared with size zero.
    #[error("decision variable `{name}` has size zero")]
    EmptyVariable {
        /// The variable name.
        name: String,
    },
    /// A task refers to a variable id that does not belong to the problem's variable set.
    #[error("task `{task}` refers to unknown variable id {id}")]
    UnknownVariable {
        /// The task name.
        task: String,
        /// The raw variable index.
        id: usize,
    },
    /// A task names the same variable twice.
    #[error("task `{task}` names variable `{variable}` twice")]
    RepeatedVariable {
        /// The task name.
        task: String,
        /// The variable name.
        variable: String,
    },
    /// A task names no variable or has zero rows.
    #[error("task `{task}` is empty (no variables or zero rows)")]
    EmptyTask {
        /// The task name.
        task: String,
    },
    /// Two tasks share a name.
    #[error("task `{name}` is declared twice")]
    DuplicateTask {
        /// The repeated name.
        name: String,
    },
    /// A task name or id was not found.
    #[error("unknown task `{name}`")]
    UnknownTask {
        /// The requested name (or the id printed as text).
        name: String,
    },
    /// Inequality tasks are always hard constraints.
    #[error("task `{task}` is an inequality and cannot be soft (inequalities are always hard)")]
    SoftInequality {
        /// The task name.
        task: String,
    },
    /// A hard task was given a weight (hard tasks are constraints: only soft tasks have weights).
    #[error(
        "task `{task}` is hard and cannot have a weight (remove the weight or make the task soft)"
    )]
    WeightOnHardTask {
        /// The task name.
        task: String,
    },
    /// A weight vector has the wrong length.
    #[error("task `{task}`: weight has {got} entries, the task has {expected} rows")]
    WeightSize {
        /// The task name.
        task: String,
        /// Rows of the task.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A weight is negative, NaN or infinite.
    #[error("task `{task}`: weight {value} at row {row} must be finite and >= 0")]
    InvalidWeight {
        /// The task name.
        task: String,
        /// Row index.
        row: usize,
        /// Offending value.
        value: f64,
    },
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch in {what}: expected {expected}, got {got}")]
    Dimension {
        /// What was being set.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Given size.
        got: usize,
    },
    /// A setting has an invalid value.
    #[error("invalid setting `{name}`: {reason}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A sparse triplet lies outside the matrix or in the wrong triangle.
    #[error("sparse {what} entry ({row}, {col}) is out of range or below the diagonal")]
    BadTriplet {
        /// Which matrix.
        what: &'static str,
        /// Row index.
        row: usize,
        /// Column index.
        col: usize,
    },
    /// Clarabel rejected the problem data at set-up.
    #[error("clarabel set-up failed: {0}")]
    ClarabelSetup(String),
    /// The solve failed: the nominal status and, if the fallback ran, the relaxed status.
    #[error("QP solve failed: nominal solve {nominal:?}, relaxed solve {relaxed:?}")]
    SolveFailed {
        /// Status of the nominal solve.
        nominal: QpStatus,
        /// Status of the relaxed (hard → heavily weighted soft) solve, when it ran.
        relaxed: Option<QpStatus>,
    },
}
