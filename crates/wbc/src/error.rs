//! Errors of the whole-body controllers.

use stride_model::ModelError;
use stride_qp::QpError;

/// Everything that can go wrong building or stepping a whole-body controller.
#[derive(Debug, thiserror::Error)]
pub enum WbcError {
    /// A task names a frame the model does not have.
    #[error("task `{task}`: unknown frame `{frame}`")]
    UnknownFrame {
        /// Task name.
        task: String,
        /// Frame name.
        frame: String,
    },
    /// A task names a joint the model does not have.
    #[error("task `{task}`: unknown joint `{joint}`")]
    UnknownJoint {
        /// Task name.
        task: String,
        /// Joint name.
        joint: String,
    },
    /// A config value is invalid.
    #[error("task `{task}`: invalid `{key}`: {reason}")]
    InvalidConfig {
        /// Task name (or `"<controller>"` for controller-level keys).
        task: String,
        /// Offending key.
        key: &'static str,
        /// Why.
        reason: String,
    },
    /// A task type that this controller does not support (e.g. `contact` in the QP-IK).
    #[error("task `{task}`: type `{task_type}` is not supported by the {controller}")]
    UnsupportedTask {
        /// Task name.
        task: String,
        /// Task type.
        task_type: &'static str,
        /// Controller name.
        controller: &'static str,
    },
    /// A name (frame reference, contact, task) that the input or the controller does not have.
    #[error("unknown {what} `{name}` (known: {known})")]
    UnknownName {
        /// What kind of name.
        what: String,
        /// The name.
        name: String,
        /// The names there are, comma-separated.
        known: String,
    },
    /// The input has the wrong size or non-finite values.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// An error from stride-model.
    #[error("model: {0}")]
    Model(#[from] ModelError),
    /// An error from stride-qp (construction).
    #[error("qp: {0}")]
    Qp(#[from] QpError),
}
