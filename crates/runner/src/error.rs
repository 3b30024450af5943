//! The runner's errors: one enum that wraps each layer's own error, so a caller can match on where a
//! run failed without parsing messages.

use std::path::PathBuf;

use crate::config::ConfigError;
use crate::log::LogError;
use crate::robot::RobotError;

/// Why a run could not start, or why it stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A configuration problem (with its file, line and key).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The model could not be loaded.
    #[error("model {}: {source}", path.display())]
    ModelLoad {
        /// URDF path.
        path: PathBuf,
        /// Loader error.
        source: stride_model::ModelError,
    },
    /// The runner's kinematics rejected a measured state (non-finite, wrong size).
    #[error("measured state: {0}")]
    State(#[from] stride_model::ModelError),
    /// The planner failed.
    #[error("planner: {0}")]
    Planner(#[from] stride_planner::PlannerError),
    /// The simplified layer failed to build (a failed tick is held, not an error).
    #[error("simplified layer: {0}")]
    Simplified(#[from] stride_simplified::SimplifiedError),
    /// The simplified layer's input could not be filled (degenerate support polygon, horizon too small).
    #[error("simplified layer's input: {0}")]
    SimplifiedInput(#[from] stride_walking::SimplifiedInputError),
    /// The whole-body layer failed.
    #[error("whole-body layer: {0}")]
    Wbc(#[from] stride_wbc::WbcError),
    /// The estimation layer failed.
    #[error("estimation layer: {0}")]
    Estimation(#[from] stride_estimation::EstimatorError),
    /// The robot (plant) failed.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// The log could not be written.
    #[error(transparent)]
    Log(#[from] LogError),
    /// A layer asked for the plan before the planner produced one.
    #[error("no plan yet: the planner must run before the {layer} layer")]
    NoPlan {
        /// The layer that needed it.
        layer: &'static str,
    },
}
