//! The plant side of the loop: the [`Robot`] trait and its implementations.
//!
//! The scheduler talks to the robot only through [`Robot`]: read a [`Measurement`], send a
//! [`JointCommand`], advance one plant period. The simulator ([`crate::sim_plant::SimPlant`]) is the first
//! implementation, [`IdealPlant`] the second; a real robot or another simulator plugs in by implementing
//! the trait (its `advance` would wait for the next sample instead of integrating).

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, UnitQuaternion, Vector3, Vector6};
use stride_estimation::EstimatorInput;
use stride_model::{FrameId, KinDyn, Model, RobotState, VelocityRepresentation};

use crate::config::ControlMode;

/// A failure of the robot interface (or of the simulator).
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The simulator failed.
    #[error("simulator: {0}")]
    Sim(#[from] stride_sim::SimError),
    /// The plant's model rejected a state.
    #[error("plant state: {0}")]
    State(#[from] stride_model::ModelError),
    /// A command sized for another robot.
    #[error("command sized for {got} joints, the robot has {expected}")]
    CommandSize {
        /// Joints of the robot.
        expected: usize,
        /// Joints in the command.
        got: usize,
    },
    /// A command with a NaN or infinite joint position.
    #[error("command with a non-finite joint position")]
    NonFiniteCommand,
    /// The plant's period differs from the schedule's.
    #[error("the robot's period {robot_ns} ns differs from rates.sim_hz ({expected_ns} ns)")]
    Period {
        /// The robot's period \[ns\].
        robot_ns: u64,
        /// `1 / rates.sim_hz` \[ns\].
        expected_ns: u64,
    },
    /// The MuJoCo plant failed (build with the `mujoco` feature).
    #[cfg(feature = "mujoco")]
    #[error("MuJoCo plant: {0}")]
    Mujoco(#[from] stride_mujoco::MujocoError),
    /// A robot interface outside stride (a real robot, another simulator) failed; its own words.
    #[error("robot: {0}")]
    Interface(String),
}

/// What the robot reports each plant period: what it senses (the estimation layer's input, the only thing
/// the controllers' path reads) and, for a simulator, the plant's truth (logs, the summary, and the
/// `ground_truth` estimation kind for debugging).
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// Plant time \[ns\].
    pub time_ns: u64,
    /// Encoders, IMU and force/torque sensors, as the robot senses them.
    pub sensors: EstimatorInput,
    /// The plant's truth (a real robot fills it with what it has, e.g. from motion capture, or leaves it
    /// at the last estimate).
    pub truth: PlantTruth,
    /// The plant's own fall detector (the runner also checks base height and tilt).
    pub fallen: bool,
}

/// The plant's true state and contacts.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantTruth {
    /// Base pose, joint positions, base twist (mixed) and joint velocities.
    pub state: RobotState,
    /// Actuator torques applied on the joints [N m].
    pub joint_torques: DVector<f64>,
    /// Per joint, in model order: the motor torque sat at its effort limit during the last period.
    pub saturated: Vec<bool>,
    /// Left and right foot: the wrench `[f; τ]` the ground applies on the foot, world orientation, torque
    /// about the sole frame origin [N; N m].
    pub foot_wrenches: [Vector6<f64>; 2],
    /// Left and right foot touch the ground.
    pub feet_in_contact: [bool; 2],
}

impl Measurement {
    /// A zero measurement sized for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            time_ns: 0,
            sensors: EstimatorInput::new(model),
            truth: PlantTruth {
                state: RobotState::zero(model),
                joint_torques: DVector::zeros(model.dof()),
                saturated: vec![false; model.dof()],
                foot_wrenches: [Vector6::zeros(); 2],
                feet_in_contact: [false; 2],
            },
            fallen: false,
        }
    }
}

/// What the whole-body layer sends to the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct JointCommand {
    /// Which fields the servos use.
    pub mode: ControlMode,
    /// Joint position set-points \[rad\] (position mode).
    pub joint_positions: DVector<f64>,
    /// Joint velocity feed-forward [rad/s] (position mode).
    pub joint_velocities: DVector<f64>,
    /// Joint torques [N m] (torque mode; feed-forward in position mode, usually 0).
    pub joint_torques: DVector<f64>,
    /// Planned contact state of the left and right foot (used by the ideal plant to anchor the base).
    pub contacts: [bool; 2],
}

impl JointCommand {
    /// A command holding `q`.
    pub fn hold(mode: ControlMode, q: &DVector<f64>) -> Self {
        let n = q.len();
        Self {
            mode,
            joint_positions: q.clone(),
            joint_velocities: DVector::zeros(n),
            joint_torques: DVector::zeros(n),
            contacts: [true, true],
        }
    }
}

/// The plant interface of the loop.
pub trait Robot {
    /// Short name for logs and the summary (`simulator`, `ideal`, ...).
    fn name(&self) -> &str;
    /// The model the robot is described by.
    fn model(&self) -> &Arc<Model>;
    /// Plant period \[ns\]: how much [`Robot::advance`] moves time.
    fn period_ns(&self) -> u64;
    /// The latest measurement (at the current plant time).
    fn measurement(&self) -> &Measurement;
    /// Sets the command applied from now on.
    fn command(&mut self, command: &JointCommand) -> Result<(), RobotError>;
    /// Advances one period (simulation step; a real robot would wait for the next sample) and refreshes
    /// the measurement.
    fn advance(&mut self) -> Result<(), RobotError>;
    /// The kinematics of the measurement's true state, if the plant keeps them for the runner's model
    /// (the runner copies them instead of running the forward pass again: [`KinDyn::set_state_from`]).
    fn kinematics(&self) -> Option<&KinDyn> {
        None
    }
}

/// The ideal kinematic plant (the first bring-up step of docs/architecture.md): commanded joint positions are applied exactly and the
/// base pose follows from keeping the anchored stance foot where it is (legged odometry). Joint and base
/// velocities are finite differences over the plant period; foot wrenches are the static weight split so
/// that the ZMP is the CoM's ground projection (clamped between the feet in double support). It has
/// encoders but no IMU and no force/torque sensors: the controllers read its truth
/// (`estimation.kind = "ground_truth"`, which the scenario check requires with this plant).
pub struct IdealPlant {
    model: Arc<Model>,
    kd: KinDyn,
    period_ns: u64,
    feet: [FrameId; 2],
    anchor: usize,
    anchor_pose: Isometry3<f64>,
    pending: JointCommand,
    meas: Measurement,
    previous: RobotState,
    gravity: f64,
}

impl IdealPlant {
    /// Builds the plant at `initial` (base pose as given: callers put the soles on the ground first).
    pub fn new(
        model: Arc<Model>,
        period_ns: u64,
        left_sole: FrameId,
        right_sole: FrameId,
        initial: &RobotState,
    ) -> Result<Self, RobotError> {
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        kd.set_state(initial)?;
        let anchor_pose = kd.frame_pose(left_sole);
        let mut meas = Measurement::new(&model);
        meas.truth.state = initial.clone();
        meas.sensors
            .joint_positions
            .copy_from(&initial.joint_positions);
        let pending = JointCommand::hold(ControlMode::Position, &initial.joint_positions);
        let mut plant = Self {
            kd,
            period_ns,
            feet: [left_sole, right_sole],
            anchor: 0,
            anchor_pose,
            pending,
            meas,
            previous: initial.clone(),
            gravity: -model.gravity().z,
            model,
        };
        plant.update_wrenches();
        Ok(plant)
    }

    fn update_wrenches(&mut self) {
        let com = self.kd.com_position();
        let weight = self.model.total_mass() * self.gravity;
        let pl = self.kd.frame_pose(self.feet[0]).translation.vector;
        let pr = self.kd.frame_pose(self.feet[1]).translation.vector;
        let contacts = self.pending.contacts;
        let (wl, wr) = match contacts {
            [true, true] | [false, false] => {
                // Fraction of the weight on the right foot: CoM projected on the segment left → right.
                let d = (pr - pl).xy();
                let len2 = d.norm_squared();
                let alpha = if len2 > 1e-12 {
                    ((com.xy() - pl.xy()).dot(&d) / len2).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                ((1.0 - alpha) * weight, alpha * weight)
            }
            [true, false] => (weight, 0.0),
            [false, true] => (0.0, weight),
        };
        let single = contacts[0] != contacts[1];
        for (i, (f, p)) in [(wl, pl), (wr, pr)].into_iter().enumerate() {
            let force = Vector3::new(0.0, 0.0, f);
            // Single support: the centre of pressure is the CoM projection; double support: the sole centre.
            let cop = if single && f > 0.0 {
                Vector3::new(com.x, com.y, p.z)
            } else {
                p
            };
            let torque = (cop - p).cross(&force);
            self.meas.truth.foot_wrenches[i] =
                Vector6::new(force.x, force.y, force.z, torque.x, torque.y, torque.z);
            self.meas.truth.feet_in_contact[i] = f > 0.0;
        }
    }
}

impl Robot for IdealPlant {
    fn name(&self) -> &str {
        "ideal"
    }
    fn model(&self) -> &Arc<Model> {
        &self.model
    }
    fn period_ns(&self) -> u64 {
        self.period_ns
    }
    fn measurement(&self) -> &Measurement {
        &self.meas
    }
    fn command(&mut self, command: &JointCommand) -> Result<(), RobotError> {
        if command.joint_positions.len() != self.model.dof() {
            return Err(RobotError::CommandSize {
                expected: self.model.dof(),
                got: command.joint_positions.len(),
            });
        }
        if command.joint_positions.iter().any(|q| !q.is_finite()) {
            return Err(RobotError::NonFiniteCommand);
        }
        self.pending.mode = command.mode;
        self.pending
            .joint_positions
            .copy_from(&command.joint_positions);
        self.pending.contacts = command.contacts;
        Ok(())
    }
    fn advance(&mut self) -> Result<(), RobotError> {
        let dt = self.period_ns as f64 * 1e-9;
        self.previous.copy_from(&self.meas.truth.state);
        // Re-anchor when the anchored foot leaves the ground and the other one is down.
        let contacts = self.pending.contacts;
        if !contacts[self.anchor] && contacts[1 - self.anchor] {
            self.anchor = 1 - self.anchor;
            self.anchor_pose = self.kd.frame_pose(self.feet[self.anchor]);
        }
        let state = &mut self.meas.truth.state;
        state
            .joint_positions
            .copy_from(&self.pending.joint_positions);
        self.kd.set_state(state)?;
        // base_H_anchor with the new joints; world_H_base = world_H_anchor · anchor_H_base.
        let base_to_anchor = self.kd.relative_transform_from_base(self.feet[self.anchor]);
        let mut base = self.anchor_pose * base_to_anchor.inverse();
        // Frame poses come from rotation matrices; renormalize so rounding errors cannot compound.
        base.rotation = UnitQuaternion::new_normalize(base.rotation.into_inner());
        let state = &mut self.meas.truth.state;
        state.base_pose = base;
        // Finite-difference velocities (mixed).
        let prev = &self.previous;
        for i in 0..state.joint_velocities.len() {
            state.joint_velocities[i] = (state.joint_positions[i] - prev.joint_positions[i]) / dt;
        }
        let lin = (base.translation.vector - prev.base_pose.translation.vector) / dt;
        let rot = base.rotation * prev.base_pose.rotation.inverse();
        let ang = rot.scaled_axis() / dt;
        state.base_velocity = Vector6::new(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z);
        self.kd.set_state(state)?;
        self.meas.time_ns += self.period_ns;
        let sensors = &mut self.meas.sensors;
        sensors.time_ns = self.meas.time_ns;
        sensors.joint_positions.copy_from(&state.joint_positions);
        sensors.joint_velocities.copy_from(&state.joint_velocities);
        self.update_wrenches();
        Ok(())
    }
}

/// `base_H_frame` helper on [`KinDyn`] for the plant (pose of a frame relative to the base, from the
/// current world poses).
trait RelativeToBase {
    fn relative_transform_from_base(&self, frame: FrameId) -> Isometry3<f64>;
}

impl RelativeToBase for KinDyn {
    fn relative_transform_from_base(&self, frame: FrameId) -> Isometry3<f64> {
        // world_H_base is the state's base pose; world_H_frame from FK.
        let world_frame = self.frame_pose(frame);
        let base = self
            .model()
            .frame_id(self.model().root_link())
            .map(|b| self.frame_pose(b))
            .unwrap_or_else(Isometry3::identity);
        base.inverse() * world_frame
    }
}
