//! The error type of the estimation layer.

use stride_model::ModelError;

/// Everything that can go wrong in `stride-estimation`. Every variant names the offending parameter, frame,
/// sensor or input so the caller can report it without guessing.
#[derive(Debug, thiserror::Error)]
pub enum EstimatorError {
    /// A configuration parameter is out of its admissible range.
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter as written in the configuration.
        name: &'static str,
        /// The rejected value (NaN when it is not a single number).
        value: f64,
        /// Why it was rejected.
        reason: &'static str,
    },
    /// A frame named in the configuration is not in the model.
    #[error("frame `{name}` (configuration key `{key}`) is not in the model")]
    UnknownFrame {
        /// Configuration key.
        key: &'static str,
        /// The frame name.
        name: String,
    },
    /// A joint named in the configuration is not in the model.
    #[error("joint `{name}` (configuration key `{key}`) is not in the model")]
    UnknownJoint {
        /// Configuration key.
        key: &'static str,
        /// The joint name.
        name: String,
    },
    /// A force/torque sensor named in the configuration is not in the model.
    #[error("force/torque sensor `{name}` (configuration key `{key}`) is not in the model")]
    UnknownFtSensor {
        /// Configuration key.
        key: &'static str,
        /// The sensor name.
        name: String,
    },
    /// No force/torque sensor measures the wrench of a foot (none has the sole on its child side), or the
    /// named one does not.
    #[error("no force/torque sensor measures the wrench on `{sole}`: {reason}")]
    NoFootSensor {
        /// The sole frame.
        sole: String,
        /// Why.
        reason: &'static str,
    },
    /// An input has the wrong size.
    #[error("input `{name}`: expected {expected} entries, got {actual}")]
    InputSize {
        /// Input field.
        name: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        actual: usize,
    },
    /// An input is NaN or infinite.
    #[error("non-finite input `{name}`")]
    NonFiniteInput {
        /// Input field.
        name: &'static str,
    },
    /// The sample time did not increase.
    #[error("sample time {time_ns} ns does not follow the previous sample time {previous_ns} ns")]
    NonIncreasingTime {
        /// This sample's time.
        time_ns: u64,
        /// The previous sample's time.
        previous_ns: u64,
    },
    /// `step` was called before [`crate::Estimator::set_initial_state`] (or after `reset`).
    #[error("the estimator has no initial state: call set_initial_state first")]
    NotInitialized,
    /// The filter's innovation covariance could not be inverted (a σ of zero with a degenerate covariance).
    #[error("EKF update: the innovation covariance of `{what}` is not positive definite")]
    SingularInnovation {
        /// Which measurement.
        what: &'static str,
    },
    /// The map from a foot wrench to its sensor's reading is singular.
    #[error("the wrench map of sensor `{sensor}` to `{sole}` is singular")]
    SingularWrenchMap {
        /// Sensor name.
        sensor: String,
        /// Sole frame.
        sole: String,
    },
    /// A model computation failed.
    #[error("model: {0}")]
    Model(#[from] ModelError),
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, EstimatorError>;

/// `InvalidParameter` unless `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(EstimatorError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// `InvalidParameter` unless `value` is finite and non-negative.
pub(crate) fn check_non_negative(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(EstimatorError::InvalidParameter {
            name,
            value,
            reason: "must be finite and >= 0",
        })
    }
}
