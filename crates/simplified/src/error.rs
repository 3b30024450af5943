//! The error type of the simplified-model control layer.

/// Everything that can go wrong in `stride-simplified`. Every variant names the offending parameter,
/// input or quantity so the caller can report it without guessing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimplifiedError {
    /// A configuration or call parameter is out of its admissible range.
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter (as written in the config or the function signature).
        name: &'static str,
        /// The rejected value (NaN when the value is not a single number).
        value: f64,
        /// Why it was rejected.
        reason: &'static str,
    },
    /// An input of a step is NaN or infinite.
    #[error("non-finite input `{name}`")]
    NonFiniteInput {
        /// Name of the input field.
        name: &'static str,
    },
    /// A support polygon cannot be used (too few vertices, zero area, not convex, too many points).
    #[error("invalid support polygon `{name}`: {reason}")]
    InvalidPolygon {
        /// Which polygon (input field name or helper name).
        name: &'static str,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The feet do not push on the ground hard enough for the ZMP to be defined.
    #[error("total normal force {normal_force} N is below the minimum {minimum} N: the ZMP is undefined")]
    InsufficientNormalForce {
        /// Sum of the vertical components of the feet forces \[N\].
        normal_force: f64,
        /// The threshold that was asked for \[N\].
        minimum: f64,
    },
    /// The fixed-capacity MPC horizon buffer is full.
    #[error("MPC horizon buffer is full (capacity {capacity} stages)")]
    HorizonFull {
        /// Number of stages the buffer was built for.
        capacity: usize,
    },
    /// The MPC was stepped with an empty horizon.
    #[error("MPC horizon is empty: the planner provided no stage")]
    EmptyHorizon,
    /// The MPC's QP could not be solved to the requested accuracy.
    #[error("DCM MPC QP failed: {status:?} after {iterations} iterations")]
    SolverFailed {
        /// Final status of the solver.
        status: crate::MpcStatus,
        /// Iterations performed.
        iterations: u32,
    },
    /// The MPC's QP does not fit the structure of its solver (an internal inconsistency: the MPC sizes
    /// its QP for the horizon and the largest polygon).
    #[error("DCM MPC QP structure: {0}")]
    QpStructure(#[from] stride_qp::BandedQpError),
    /// The centroidal MPC was given more contacts than its buffers hold, or more than two active at once.
    #[error("centroidal MPC contacts: {reason} (got {count})")]
    TooManyContacts {
        /// Contacts given (or active at one stage).
        count: usize,
        /// Which limit was exceeded.
        reason: &'static str,
    },
    /// The centroidal MPC's QP failed (the previous output is kept).
    #[error("centroidal MPC QP failed: {status:?} after {iterations} iterations")]
    CentroidalSolverFailed {
        /// Final status of the active-set solver.
        status: stride_qp::QpStatus,
        /// Iterations performed.
        iterations: usize,
    },
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, SimplifiedError>;

/// Returns `NonFiniteInput { name }` unless both components are finite.
pub(crate) fn check_finite2(name: &'static str, v: &nalgebra::Vector2<f64>) -> Result<()> {
    if v.x.is_finite() && v.y.is_finite() {
        Ok(())
    } else {
        Err(SimplifiedError::NonFiniteInput { name })
    }
}

/// Returns `NonFiniteInput { name }` unless the value is finite.
pub(crate) fn check_finite(name: &'static str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SimplifiedError::NonFiniteInput { name })
    }
}

/// Returns `InvalidParameter` unless `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimplifiedError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Returns `InvalidParameter` unless `value` is finite and non-negative.
pub(crate) fn check_non_negative(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SimplifiedError::InvalidParameter {
            name,
            value,
            reason: "must be finite and >= 0",
        })
    }
}

impl From<stride_block::PolygonError> for SimplifiedError {
    fn from(e: stride_block::PolygonError) -> Self {
        SimplifiedError::InvalidPolygon {
            name: e.name,
            reason: e.reason,
        }
    }
}
