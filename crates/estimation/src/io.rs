//! The estimation layer's data-only input and output.

use nalgebra::{DVector, UnitQuaternion, Vector3, Vector6};
use stride_model::{Model, RobotState};

/// One IMU sample, in the IMU frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuReading {
    /// Orientation `world_R_imu` from the IMU's on-board filter (roll and pitch from gravity, yaw drifting).
    pub orientation: UnitQuaternion<f64>,
    /// Gyroscope: angular velocity of the IMU frame in the IMU frame, rad/s (bias and noise included).
    pub angular_velocity: Vector3<f64>,
    /// Accelerometer: proper acceleration `Rᵀ (a − g)` of the IMU origin in the IMU frame, m/s².
    pub proper_acceleration: Vector3<f64>,
}

impl Default for ImuReading {
    fn default() -> Self {
        Self {
            orientation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
            proper_acceleration: Vector3::zeros(),
        }
    }
}

/// What the robot senses at one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorInput {
    /// Sample time, ns.
    pub time_ns: u64,
    /// Encoder joint positions, rad (model joint order).
    pub joint_positions: DVector<f64>,
    /// Joint velocities as the robot provides them, rad/s (model joint order).
    pub joint_velocities: DVector<f64>,
    /// The IMU sample.
    pub imu: ImuReading,
    /// Six-axis force/torque sensor readings `[f; τ]` in [`Model::ft_sensors`] order, each in its sensor
    /// frame with its declared measure direction, N and N·m (offsets and noise included).
    pub ft_wrenches: Vec<Vector6<f64>>,
}

impl EstimatorInput {
    /// A zero input sized for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            time_ns: 0,
            joint_positions: DVector::zeros(model.dof()),
            joint_velocities: DVector::zeros(model.dof()),
            imu: ImuReading::default(),
            ft_wrenches: vec![Vector6::zeros(); model.ft_sensors().len()],
        }
    }
}

/// What the estimation layer gives the controllers.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorOutput {
    /// Estimated base pose and mixed twist (`[ṗ_B; ω]`, world), joint positions and velocities.
    pub state: RobotState,
    /// Left and right foot detected in contact with the ground.
    pub contacts: [bool; 2],
    /// Left and right foot: estimated wrench `[f; τ]` the ground applies on the foot, world orientation,
    /// torque about the sole frame origin, N and N·m.
    pub foot_wrenches: [Vector6<f64>; 2],
    /// Estimated joint torques, N·m (model joint order).
    pub joint_torques: DVector<f64>,
    /// Current force/torque sensor offset estimates (subtracted from the readings), [`Model::ft_sensors`] order.
    pub ft_offsets: Vec<Vector6<f64>>,
}

impl EstimatorOutput {
    /// A zero output sized for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            state: RobotState::zero(model),
            contacts: [false; 2],
            foot_wrenches: [Vector6::zeros(); 2],
            joint_torques: DVector::zeros(model.dof()),
            ft_offsets: vec![Vector6::zeros(); model.ft_sensors().len()],
        }
    }
}
