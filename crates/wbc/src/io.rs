//! Plain-data inputs and outputs of the whole-body controllers.

use nalgebra::{DVector, Isometry3, UnitQuaternion, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};
use stride_model::{Model, RobotState};
use stride_qp::QpStatus;

/// Reference of a foot (its sole frame): pose, mixed twist `[ṗ; ω]` and mixed acceleration `[p̈; ω̇]`,
/// all in world coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootReference {
    /// world_H_sole.
    pub pose: Isometry3<f64>,
    /// `[linear velocity (m/s); angular velocity (rad/s)]`.
    pub velocity: Vector6<f64>,
    /// `[linear acceleration (m/s²); angular acceleration (rad/s²)]`.
    pub acceleration: Vector6<f64>,
}

impl Default for FootReference {
    fn default() -> Self {
        FootReference {
            pose: Isometry3::identity(),
            velocity: Vector6::zeros(),
            acceleration: Vector6::zeros(),
        }
    }
}

/// Orientation reference (torso): orientation, angular velocity, angular acceleration (world).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrientationReference {
    /// world_R_frame.
    pub orientation: UnitQuaternion<f64>,
    /// Angular velocity (rad/s).
    pub angular_velocity: Vector3<f64>,
    /// Angular acceleration (rad/s²).
    pub angular_acceleration: Vector3<f64>,
}

impl Default for OrientationReference {
    fn default() -> Self {
        OrientationReference {
            orientation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
            angular_acceleration: Vector3::zeros(),
        }
    }
}

/// Input of one tick of [`crate::QpIk`] or [`crate::Tsid`].
///
/// `state` is the measured robot state in the **mixed** representation. The QP-IK in
/// [`crate::IkFeedback::Integrated`] mode reads it only at its first tick after construction/reset.
#[derive(Debug, Clone, PartialEq)]
pub struct WbcInput {
    /// Measured robot state (mixed velocities).
    pub state: RobotState,
    /// CoM reference position (m).
    pub com_position: Vector3<f64>,
    /// CoM reference velocity (m/s).
    pub com_velocity: Vector3<f64>,
    /// CoM reference acceleration (m/s²; TSID feedforward).
    pub com_acceleration: Vector3<f64>,
    /// Left sole reference.
    pub left_foot: FootReference,
    /// Right sole reference.
    pub right_foot: FootReference,
    /// Whether the left foot is (planned to be) in contact.
    pub left_in_contact: bool,
    /// Whether the right foot is (planned to be) in contact.
    pub right_in_contact: bool,
    /// Desired global ZMP (world x, y), used by a `zmp` task when present.
    pub desired_zmp: Option<Vector2<f64>>,
    /// Desired contact wrenches `[left, right]` (mixed, on the robot), used as the reference of the
    /// `wrench_regularization` task when present.
    pub desired_wrenches: Option<[Vector6<f64>; 2]>,
    /// Torso orientation reference (for tasks with `reference = "torso"`).
    pub torso: OrientationReference,
    /// Posture reference (n joint positions, model order); `None`: the task's configured posture.
    pub posture: Option<DVector<f64>>,
    /// Centroidal angular momentum reference (kg m²/s) for `angular_momentum` tasks.
    pub angular_momentum: Vector3<f64>,
}

impl WbcInput {
    /// An input holding the robot at `state` with every reference zero/identity, both feet in contact.
    /// Meant as a buffer the caller fills each tick.
    pub fn new(model: &Model) -> Self {
        WbcInput {
            state: RobotState::zero(model),
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            com_acceleration: Vector3::zeros(),
            left_foot: FootReference::default(),
            right_foot: FootReference::default(),
            left_in_contact: true,
            right_in_contact: true,
            desired_zmp: None,
            desired_wrenches: None,
            torso: OrientationReference::default(),
            posture: None,
            angular_momentum: Vector3::zeros(),
        }
    }
}

/// Solver report of one tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// Status of the nominal solve.
    pub status: QpStatus,
    /// Status of the relaxed solve (hard tasks made heavily weighted soft), when it ran.
    pub relaxed_status: Option<QpStatus>,
    /// Backend iterations (nominal + relaxed).
    pub iterations: usize,
    /// Wall time of the QP solve(s), seconds.
    pub solve_time: f64,
    /// Wall time of the whole tick (task update + QP build + solve), seconds.
    pub tick_time: f64,
    /// The relaxed problem produced the command (hard tasks may be violated: see residuals).
    pub fallback: bool,
    /// Both solves failed: the command is the last valid one, held.
    pub held: bool,
}

impl Default for SolveReport {
    fn default() -> Self {
        SolveReport {
            status: QpStatus::NotSolved,
            relaxed_status: None,
            iterations: 0,
            solve_time: 0.0,
            tick_time: 0.0,
            fallback: false,
            held: false,
        }
    }
}

/// Residual of one task at the returned solution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskResidual {
    /// Task name (from the config).
    pub name: String,
    /// Whether the task is a hard constraint in the current problem.
    pub hard: bool,
    /// Equality tasks: `‖A x − b‖₂`; inequality tasks: `‖max(l − A x, 0) + max(A x − u, 0)‖₂`
    /// (0 when satisfied); tasks not in the current problem (e.g. an unloaded contact): 0.
    pub residual: f64,
}

/// Output of one tick of [`crate::QpIk`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IkOutput {
    /// Integrated joint positions (rad): the position command.
    pub joint_positions: DVector<f64>,
    /// Joint velocities ṡ (rad/s).
    pub joint_velocities: DVector<f64>,
    /// Base velocity (mixed `[ṗ; ω]`).
    pub base_velocity: Vector6<f64>,
    /// Integrated base pose (world_H_base) of the IK's internal state.
    pub base_pose: Isometry3<f64>,
    /// Solver report.
    pub report: SolveReport,
    /// Per-task residuals, in config order.
    pub residuals: Vec<TaskResidual>,
}

/// Output of one tick of [`crate::Tsid`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TsidOutput {
    /// Joint torques τ (N m): the command.
    pub joint_torques: DVector<f64>,
    /// Generalized acceleration ν̇ (mixed base acceleration, joint accelerations).
    pub accelerations: DVector<f64>,
    /// Planned contact wrenches `[left, right]` (mixed, applied on the robot); zero when unloaded.
    pub contact_wrenches: [Vector6<f64>; 2],
    /// Load factor `[left, right]` in [0, 1] of each foot's normal-force bound (the contact ramp).
    pub contact_load: [f64; 2],
    /// Solver report.
    pub report: SolveReport,
    /// Per-task residuals, in config order.
    pub residuals: Vec<TaskResidual>,
}
