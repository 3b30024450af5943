//! Why building or stepping the MuJoCo plant failed.

/// A failure of the MuJoCo plant. A failed step leaves the state, time and sensors as they were before it.
#[derive(Debug, thiserror::Error)]
pub enum MujocoError {
    /// The URDF file could not be read.
    #[error("cannot read the URDF {path}: {source}")]
    Urdf {
        /// The file.
        path: std::path::PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The URDF is not well-formed XML or has no `<robot>` element.
    #[error("cannot prepare the URDF {path} for MuJoCo: {message}")]
    UrdfXml {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A `package://` mesh path of a kept collision element that no ancestor folder of the URDF holds.
    #[error("{uri} (in {path}): no ancestor folder of the URDF holds this package path")]
    Package {
        /// The URDF.
        path: std::path::PathBuf,
        /// The `package://` path.
        uri: String,
    },
    /// MuJoCo rejected the model (parse or compile error, in MuJoCo's words).
    #[error("MuJoCo could not build the model from {path}: {message}")]
    Compile {
        /// The URDF.
        path: std::path::PathBuf,
        /// MuJoCo's message.
        message: String,
    },
    /// A configuration value is out of range or inconsistent with the model.
    #[error("invalid MuJoCo plant parameter `{parameter}` = {value}: {reason}")]
    InvalidConfig {
        /// Dotted name of the parameter.
        parameter: String,
        /// The value as written.
        value: String,
        /// What is expected.
        reason: String,
    },
    /// stride's model and MuJoCo's disagree (a joint or body of one is missing in the other).
    #[error("model mismatch: {0}")]
    Mismatch(String),
    /// The stride-sim configuration (actuation, sensors, pushes) is invalid.
    #[error("simulator configuration: {0}")]
    Sim(#[from] stride_sim::SimError),
    /// stride-model rejected a state or computation.
    #[error("model: {0}")]
    Model(#[from] stride_model::ModelError),
    /// A command sized for another robot.
    #[error("`{what}` has {got} entries, the robot has {expected} joints")]
    Dimension {
        /// Which command field.
        what: &'static str,
        /// Joints of the robot.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A NaN or infinite command.
    #[error("non-finite {what} command for joint `{joint}`")]
    NonFiniteCommand {
        /// Which command field.
        what: &'static str,
        /// The joint.
        joint: String,
    },
    /// A feed-forward torque beyond the effort limit with `effort_limit_policy = "error"`.
    #[error(
        "feed-forward torque {torque} N·m on joint `{joint}` exceeds its effort limit {limit} N·m"
    )]
    EffortLimit {
        /// The joint.
        joint: String,
        /// The commanded torque.
        torque: f64,
        /// The limit.
        limit: f64,
    },
    /// MuJoCo raised a warning during the step (unstable simulation, full contact buffer, ...): the step
    /// is rejected and the state restored.
    #[error("MuJoCo warning during the step at t = {time} s: {warning} (the simulation is unstable or a buffer is full)")]
    Warning {
        /// MuJoCo's warning kind.
        warning: String,
        /// Simulated time at the start of the step \[s\].
        time: f64,
    },
    /// The step produced a non-finite state.
    #[error("non-finite {what} after the step at t = {time} s")]
    NonFiniteState {
        /// Which quantity.
        what: &'static str,
        /// Simulated time at the start of the step \[s\].
        time: f64,
    },
}
