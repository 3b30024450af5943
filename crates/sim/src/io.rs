//! What goes into a step ([`SimInput`]) and what comes out of it ([`SimOutput`] and its measurements).

use std::time::Duration;

use nalgebra::{DVector, UnitQuaternion, Vector3, Vector6};
use stride_model::RobotState;

use crate::contact::ContactMode;

/// Commands for one step. All vectors have the model's `dof()` entries in model order; which ones a joint uses
/// depends on its [`ActuationMode`](crate::ActuationMode).
#[derive(Clone, Debug, PartialEq)]
pub struct SimInput {
    /// Position references, rad (m). Used by position servos.
    pub joint_positions: DVector<f64>,
    /// Velocity references, rad/s (m/s). Used by position and velocity servos.
    pub joint_velocities: DVector<f64>,
    /// Feed-forward (torque mode: the whole) motor torques, N·m (N).
    pub joint_torques: DVector<f64>,
}

impl SimInput {
    /// Zero commands for a model with `dof` joints.
    pub fn zeros(dof: usize) -> Self {
        Self {
            joint_positions: DVector::zeros(dof),
            joint_velocities: DVector::zeros(dof),
            joint_torques: DVector::zeros(dof),
        }
    }

    /// Commands that hold the given joint positions (zero velocity and feed-forward).
    pub fn hold(joint_positions: &DVector<f64>) -> Self {
        let n = joint_positions.len();
        Self {
            joint_positions: joint_positions.clone(),
            joint_velocities: DVector::zeros(n),
            joint_torques: DVector::zeros(n),
        }
    }
}

/// One contact point as simulated during the last step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPointState {
    /// Index of its surface in [`SimOutput::surfaces`].
    pub surface: usize,
    /// Position in the world at the end of the step, m.
    pub position: Vector3<f64>,
    /// Force the ground applied on the robot at this point during the step (world), N.
    pub force: Vector3<f64>,
    /// Depth below the ground plane at the start of the step (negative: above), m.
    pub penetration: f64,
    /// What the point did during the step.
    pub mode: ContactMode,
}

/// The measured wrench of one contact surface (e.g. a foot).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMeasurement {
    /// Surface name (from the config).
    pub name: String,
    /// At least one point pushed on the ground during the step.
    pub in_contact: bool,
    /// Ground-truth contact wrench `[f; τ]` the environment applies on the robot through this surface, in world
    /// orientation, torque about the surface frame origin (N, N·m).
    pub wrench: Vector6<f64>,
    /// The same ground-truth wrench expressed in the surface's sensor frame (the configured `ft_sensor` frame,
    /// else the surface frame), torque about its origin (N, N·m): the contact wrench alone, with no noise or
    /// delay. The realistic sensor readings, which also carry the foot's own weight and inertia, are
    /// [`SimOutput::ft_wrenches`].
    pub sensor_wrench: Vector6<f64>,
    /// Normal force along the ground normal, N (zero without contact).
    pub normal_force: f64,
    /// Centre of pressure on the ground plane (world), m; equals the surface frame origin projected on the
    /// ground when there is no contact.
    pub center_of_pressure: Vector3<f64>,
}

impl SurfaceMeasurement {
    /// The measurement of a surface named `name` before any contact.
    fn empty(name: &str) -> Self {
        Self {
            name: name.to_string(),
            in_contact: false,
            wrench: Vector6::zeros(),
            sensor_wrench: Vector6::zeros(),
            normal_force: 0.0,
            center_of_pressure: Vector3::zeros(),
        }
    }
}

/// Inertial measurement unit reading (biased, noisy and delayed as configured in
/// [`ImuConfig`](crate::ImuConfig)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuMeasurement {
    /// `world_R_imu` as an on-board attitude filter reports it (tilt error, yaw drift and noise as configured).
    pub orientation: UnitQuaternion<f64>,
    /// Angular velocity of the IMU frame, expressed in the IMU frame, rad/s.
    pub angular_velocity: Vector3<f64>,
    /// Proper acceleration (acceleration minus gravity) of the IMU origin, in the IMU frame, m/s². At rest on
    /// flat ground it reads `[0, 0, +9.81]`.
    pub proper_acceleration: Vector3<f64>,
}

/// Everything the simulator reports after a step (or after its state was set).
///
/// **Re-solve cap.** An implicit step is solved again while contact modes and joint saturations change, at
/// most [`SimOutput::MAX_SOLVES`] times. When the cap is reached with a change still pending
/// ([`SimOutput::solve_cap_hit`]), the step keeps the acceleration of the last solve, but the forces, torques
/// and modes reported for that step are those of the mode update that followed it, so they may differ from
/// what the dynamics used: a point whose normal force came out pulling is reported separated with zero force,
/// a point that left the friction cone is reported sliding with the sticking force, and a joint that reached
/// its effort limit is reported saturated at the limit although the dynamics applied the unsaturated torque.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOutput {
    /// Simulated time at the end of the step.
    pub time: Duration,
    /// Ground-truth state (base velocity in the mixed representation).
    pub state: RobotState,
    /// Encoder positions (quantised, noisy and delayed as configured), rad (m).
    pub joint_positions: DVector<f64>,
    /// Encoder velocities (by default the differenced, low-passed encoder positions; delayed), rad/s (m/s).
    pub joint_velocities: DVector<f64>,
    /// Motor torques applied during the step (after saturation), N·m (N).
    pub joint_torques: DVector<f64>,
    /// `true` for the joints whose motor torque was saturated at the effort limit during the step (in every
    /// actuation mode: a servo's torque or a torque-mode command beyond the limit is clamped to it).
    pub saturated: Vec<bool>,
    /// One entry per configured contact surface.
    pub surfaces: Vec<SurfaceMeasurement>,
    /// All contact points, surface by surface.
    pub contact_points: Vec<ContactPointState>,
    /// IMU reading (delayed as configured).
    pub imu: ImuMeasurement,
    /// Readings of the model's six-axis force/torque sensors, in [`stride_model::Model::ft_sensors`] order:
    /// `[f; τ]` in the sensor frame, torque about its origin, with the sensor's measurement-direction sign, the
    /// wrench transmitted through the sensor's fixed joint (so a foot sensor also carries the weight and
    /// inertia of the foot below it), with offset, drift, noise, saturation and delay (N, N·m).
    pub ft_wrenches: Vec<Vector6<f64>>,
    /// The same wrenches without any sensor error or delay (ground truth, for tests and logs).
    pub ft_wrenches_truth: Vec<Vector6<f64>>,
    /// Total wrench `[f; τ]` of all contacts on the robot, world orientation, torque about the world origin.
    pub total_contact_wrench: Vector6<f64>,
    /// A fall has been detected (latched until reset or a new initial state).
    pub fallen: bool,
    /// When the fall was first detected.
    pub fall_time: Option<Duration>,
    /// Number of linear solves of the last step (1 when no contact mode or saturation changed).
    pub solves: usize,
    /// The last step stopped at [`SimOutput::MAX_SOLVES`] solves with contact modes or saturations still
    /// changing: its reported forces and torques may differ from those the dynamics used (see the type's
    /// documentation).
    pub solve_cap_hit: bool,
    /// Number of steps since the initial state (time zero) that stopped at the re-solve cap.
    pub solve_cap_hits: u64,
}

impl SimOutput {
    /// Largest number of linear solves of one implicit step while contact modes and saturations settle.
    pub const MAX_SOLVES: usize = 20;

    /// The output before the first step: every vector sized (all allocation happens here), everything zero.
    pub(crate) fn new(
        state: &RobotState,
        surface_names: impl Iterator<Item = String>,
        point_surfaces: impl Iterator<Item = usize>,
        ft_sensors: usize,
    ) -> Self {
        let n = state.joint_positions.len();
        Self {
            time: Duration::ZERO,
            state: state.clone(),
            joint_positions: DVector::zeros(n),
            joint_velocities: DVector::zeros(n),
            joint_torques: DVector::zeros(n),
            saturated: vec![false; n],
            surfaces: surface_names
                .map(|name| SurfaceMeasurement::empty(&name))
                .collect(),
            contact_points: point_surfaces
                .map(|surface| ContactPointState {
                    surface,
                    position: Vector3::zeros(),
                    force: Vector3::zeros(),
                    penetration: 0.0,
                    mode: ContactMode::Separated,
                })
                .collect(),
            imu: ImuMeasurement {
                orientation: UnitQuaternion::identity(),
                angular_velocity: Vector3::zeros(),
                proper_acceleration: Vector3::zeros(),
            },
            ft_wrenches: vec![Vector6::zeros(); ft_sensors],
            ft_wrenches_truth: vec![Vector6::zeros(); ft_sensors],
            total_contact_wrench: Vector6::zeros(),
            fallen: false,
            fall_time: None,
            solves: 0,
            solve_cap_hit: false,
            solve_cap_hits: 0,
        }
    }
}
