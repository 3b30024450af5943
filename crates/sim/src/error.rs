//! Error type of the simulator.

use stride_model::{FrameId, Model, ModelError};

/// Everything that can make building or stepping the simulator fail. A failed step leaves the simulator in
/// the state it had before the step.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is out of range.
    #[error("invalid simulator configuration `{parameter}`: {message}")]
    InvalidConfig {
        /// The offending parameter (TOML path).
        parameter: String,
        /// What is wrong.
        message: String,
    },
    /// The configuration names a frame the model does not have.
    #[error("`{parameter}` names the frame `{frame}`, which the model `{model}` does not have")]
    UnknownFrame {
        /// The offending parameter.
        parameter: String,
        /// The frame name.
        frame: String,
        /// The model name.
        model: String,
    },
    /// The configuration names a joint the model does not have.
    #[error("`{parameter}` names the joint `{joint}`, which the model does not have")]
    UnknownJoint {
        /// The offending parameter.
        parameter: String,
        /// The joint name.
        joint: String,
    },
    /// An input vector has the wrong length.
    #[error("{what}: expected {expected} values, got {actual}")]
    Dimension {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        actual: usize,
    },
    /// A command or a state is NaN or infinite.
    #[error("non-finite {what} for joint `{joint}`: {value}")]
    NonFiniteCommand {
        /// Which command (`position`, `velocity`, `torque`).
        what: &'static str,
        /// Joint name.
        joint: String,
        /// The value.
        value: f64,
    },
    /// A state given to the simulator is not finite.
    #[error("non-finite value in the {what} of the state")]
    NonFiniteState {
        /// Which part of the state.
        what: &'static str,
    },
    /// A commanded feed-forward torque beyond the effort limit, with `effort_limit_policy = "error"`.
    #[error("joint `{joint}`: commanded torque {torque} N·m exceeds the effort limit {limit} N·m")]
    EffortLimit {
        /// Joint name.
        joint: String,
        /// The commanded torque.
        torque: f64,
        /// The limit.
        limit: f64,
    },
    /// The step produced a non-finite or out-of-bounds state; the state before the step is kept.
    #[error("simulation diverged at t = {time} s: {what} `{name}` = {value} (bound {bound})")]
    Diverged {
        /// Simulated time at the start of the failed step, s.
        time: f64,
        /// `joint velocity`, `base velocity`, `contact penetration`, `acceleration`.
        what: &'static str,
        /// Joint, base component or contact point (`surface[i]`) name.
        name: String,
        /// The offending value.
        value: f64,
        /// The bound that was exceeded (NaN for non-finite values).
        bound: f64,
    },
    /// The implicit system matrix is not positive definite (should not happen for a valid model).
    #[error("the implicit dynamics matrix is not positive definite at t = {time} s")]
    NotPositiveDefinite {
        /// Simulated time, s.
        time: f64,
    },
    /// An error of the dynamics library.
    #[error("model: {0}")]
    Model(#[from] ModelError),
}

/// The frame `name` of `model`, or [`SimError::UnknownFrame`] naming the config `parameter`.
pub(crate) fn find_frame(model: &Model, parameter: &str, name: &str) -> Result<FrameId, SimError> {
    model.frame_id(name).ok_or_else(|| SimError::UnknownFrame {
        parameter: parameter.to_string(),
        frame: name.to_string(),
        model: model.name().to_string(),
    })
}
