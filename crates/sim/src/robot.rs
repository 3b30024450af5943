//! The simulated robot block [`SimRobot`]: what it holds, how it is built, and one time step.
//!
//! The step's parts live in the child modules: the solves of the two schemes ([`integrator`]), setting and
//! placing the state ([`state`]) and the checks of inputs and results ([`checks`]); the contact law, the
//! actuators, the sensors and the pushes in their own crate modules.

mod checks;
mod integrator;
mod state;

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DMatrix, DVector, Vector3};
use stride_block::Block;
use stride_model::{ExternalWrench, FrameId, KinDyn, Model, RobotState, VelocityRepresentation};

use crate::actuator::{resolve_actuators, Actuator};
use crate::config::{IntegratorKind, JointActuatorConfig, PushConfig, SimConfig};
use crate::contact::{build_surfaces, GroundPlane, Point, Surface};
use crate::error::{find_frame, SimError};
use crate::io::{ContactPointState, SimInput, SimOutput};
use crate::linalg::{lin, TreeCholesky};
use crate::push::Push;
use crate::sensors::Sensors;

/// The simulated robot: floating-base dynamics of a [`Model`] on compliant ground, joint servos, sensors and
/// pushes. One [`Block::step`] advances one period (the constructor's `period`); gravity is the model's
/// ([`Model::gravity`]).
///
/// ```no_run
/// use std::sync::Arc;
/// use std::time::Duration;
/// use stride_block::Block;
/// use stride_model::Model;
/// use stride_sim::{SimConfig, SimInput, SimRobot};
///
/// let model = Arc::new(Model::from_urdf_file("models/stride_humanoid.urdf")?);
/// let period = Duration::from_micros(500); // 2 kHz
/// let mut sim = SimRobot::new(Arc::clone(&model), SimConfig::default(), period)?;
/// let mut q = nalgebra::DVector::zeros(model.dof());
/// sim.set_standing_on_ground(&q)?;
/// let input = SimInput::hold(&q);
/// for _ in 0..2000 {
///     let out = sim.step(&input)?;
///     q.copy_from(&out.joint_positions);
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct SimRobot {
    model: Arc<Model>,
    kd: KinDyn,
    config: SimConfig,
    /// Step period, s.
    dt: f64,
    period_ns: u64,
    time_ns: u64,
    /// The model's gravity, m/s² (world).
    gravity: Vector3<f64>,
    ground: GroundPlane,
    actuators: Vec<Actuator>,
    surfaces: Vec<Surface>,
    points: Vec<Point>,
    pushes: Vec<Push>,
    push_jacobian: DMatrix<f64>,
    imu_frame: FrameId,
    /// Velocity of the IMU origin at the end of the last step (world), m/s.
    imu_velocity: Vector3<f64>,
    state: RobotState,
    next_state: RobotState,
    initial_state: RobotState,
    mass: DMatrix<f64>,
    momentum_matrix: DMatrix<f64>,
    factorization: TreeCholesky,
    system: DMatrix<f64>,
    bias: DVector<f64>,
    rhs: DVector<f64>,
    acceleration: DVector<f64>,
    external_forces: DVector<f64>,
    motor_torques: DVector<f64>,
    joint_torque_buffer: DVector<f64>,
    anchor_backup: Vec<Option<Vector3<f64>>>,
    saturated: Vec<bool>,
    wrenches: Vec<ExternalWrench>,
    sensors: Sensors,
    fall_time_ns: Option<u64>,
    /// Largest number of solves of an implicit step ([`SimOutput::MAX_SOLVES`]; lowered by a unit test).
    max_solves: usize,
    /// Accepted steps since the initial state that stopped at `max_solves` with modes still changing.
    solve_cap_hits: u64,
    output: SimOutput,
}

impl std::fmt::Debug for SimRobot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimRobot")
            .field("model", &self.model.name())
            .field("time_ns", &self.time_ns)
            .field("state", &self.state)
            .finish_non_exhaustive()
    }
}

/// `period` in nanoseconds, or [`SimError::InvalidConfig`] (`period`) when it is zero or beyond `u64` ns.
fn period_ns(period: Duration) -> Result<u64, SimError> {
    match u64::try_from(period.as_nanos()) {
        Ok(ns) if ns > 0 => Ok(ns),
        _ => Err(SimError::InvalidConfig {
            parameter: "period".into(),
            message: format!("{period:?}: must be positive and below 2⁶⁴ ns"),
        }),
    }
}

/// Armature adds to the mass-matrix diagonal, which only the implicit scheme assembles.
fn check_armature(config: &SimConfig) -> Result<(), SimError> {
    let armature = config.actuation.default.armature > 0.0
        || config
            .actuation
            .joints
            .iter()
            .any(|j| j.armature.unwrap_or(0.0) > 0.0);
    if config.integrator == IntegratorKind::Explicit && armature {
        return Err(SimError::InvalidConfig {
            parameter: "actuation.armature".into(),
            message: "armature needs the implicit integrator".into(),
        });
    }
    Ok(())
}

impl SimRobot {
    /// Builds the simulator for `model` (validating `config` against it), stepping by `period` (a whole,
    /// positive number of nanoseconds; e.g. 500 µs for 2 kHz) under the model's gravity. The robot starts in
    /// the model's zero state (base at the world origin); place it with [`SimRobot::set_standing_on_ground`]
    /// or [`SimRobot::set_initial_state`].
    pub fn new(model: Arc<Model>, config: SimConfig, period: Duration) -> Result<Self, SimError> {
        config.validate()?;
        check_armature(&config)?;
        let period_ns = period_ns(period)?;
        let n = model.dof();
        let nv = model.nv();
        let actuators = resolve_actuators(&model, &config.actuation)?;
        let (surfaces, points) = build_surfaces(&model, &config.contact)?;
        let pushes = config
            .pushes
            .iter()
            .enumerate()
            .map(|(i, p)| Push::new(&model, p, &format!("pushes[{i}].frame")))
            .collect::<Result<Vec<_>, _>>()?;
        let imu_frame = match model.frame_id(&config.sensors.imu_frame) {
            Some(f) => f,
            None => find_frame(&model, "sensors.imu_frame", model.root_link())?,
        };
        let factorization =
            TreeCholesky::floating_base(&model).ok_or_else(|| SimError::InvalidConfig {
                parameter: "model".into(),
                message: "the model's bodies are not in depth-first order".into(),
            })?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let state = RobotState::zero(&model);
        let output = SimOutput::new(
            &state,
            config.contact.surfaces.iter().map(|s| s.name.clone()),
            points.iter().map(|p| p.surface),
        );
        let wrench_capacity = surfaces.len() + pushes.len() + 8;
        let mut sim = Self {
            kd,
            dt: period_ns as f64 * 1e-9,
            period_ns,
            time_ns: 0,
            gravity: model.gravity(),
            ground: GroundPlane::from_config(&config.ground),
            actuators,
            anchor_backup: vec![None; points.len()],
            surfaces,
            points,
            pushes,
            push_jacobian: DMatrix::zeros(6, nv),
            imu_frame,
            imu_velocity: Vector3::zeros(),
            next_state: state.clone(),
            initial_state: state.clone(),
            state,
            mass: DMatrix::zeros(nv, nv),
            momentum_matrix: DMatrix::zeros(6, nv),
            factorization,
            system: DMatrix::zeros(nv, nv),
            bias: DVector::zeros(nv),
            rhs: DVector::zeros(nv),
            acceleration: DVector::zeros(nv),
            external_forces: DVector::zeros(nv),
            motor_torques: DVector::zeros(n),
            joint_torque_buffer: DVector::zeros(n),
            saturated: vec![false; n],
            wrenches: Vec::with_capacity(wrench_capacity),
            sensors: Sensors::new(&config.sensors.noise),
            fall_time_ns: None,
            max_solves: SimOutput::MAX_SOLVES,
            solve_cap_hits: 0,
            output,
            config,
            model,
        };
        let zero = sim.state.clone();
        sim.set_initial_state(&zero)?;
        Ok(sim)
    }

    /// The model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// The step period, s.
    pub fn period(&self) -> f64 {
        self.dt
    }

    /// Simulated time.
    pub fn time(&self) -> Duration {
        Duration::from_nanos(self.time_ns)
    }

    /// Current ground-truth state (mixed velocity representation).
    pub fn state(&self) -> &RobotState {
        &self.state
    }

    /// The last output (after the last step or state change).
    pub fn output(&self) -> &SimOutput {
        &self.output
    }

    /// The ground plane.
    pub fn ground(&self) -> &GroundPlane {
        &self.ground
    }

    /// The contact points as simulated during the last step.
    pub fn contact_points(&self) -> &[ContactPointState] {
        &self.output.contact_points
    }

    /// The dynamics workspace, set to the current state (for tests and logging: CoM, momentum, energy).
    pub fn kin_dyn(&self) -> &KinDyn {
        &self.kd
    }

    /// Schedules an additional push. Allocates (call it between runs, not in a real-time loop).
    pub fn add_push(&mut self, push: &PushConfig) -> Result<(), SimError> {
        let p = Push::new(&self.model, push, "push.frame")?;
        if !push.start.is_finite()
            || !push.duration.is_finite()
            || push.duration < 0.0
            || !push.wrench.iter().all(|w| w.is_finite())
        {
            return Err(SimError::InvalidConfig {
                parameter: "push".into(),
                message: "non-finite or negative values".into(),
            });
        }
        self.pushes.push(p);
        self.config.pushes.push(push.clone());
        Ok(())
    }

    /// Removes every scheduled push.
    pub fn clear_pushes(&mut self) {
        self.pushes.clear();
        self.config.pushes.clear();
    }

    /// Changes one joint's actuator at run time (e.g. switch a joint to torque mode).
    pub fn set_joint_actuator(
        &mut self,
        joint: &str,
        actuator: &JointActuatorConfig,
    ) -> Result<(), SimError> {
        let index = self
            .model
            .joint_index(joint)
            .ok_or_else(|| SimError::UnknownJoint {
                parameter: "set_joint_actuator".into(),
                joint: joint.to_string(),
            })?;
        if self.config.integrator == IntegratorKind::Explicit && actuator.armature > 0.0 {
            return Err(SimError::InvalidConfig {
                parameter: "armature".into(),
                message: "armature needs the implicit integrator".into(),
            });
        }
        let limit = self.model.joints()[index].effort_limit;
        self.actuators[index] = Actuator::resolve(actuator, limit);
        Ok(())
    }

    /// One step: solve, integrate, commit the contact memory, then measure at the end-of-step state. On error
    /// the state, time and contact anchors are those before the step.
    fn do_step(&mut self, input: &SimInput) -> Result<(), SimError> {
        self.check_input(input)?;
        self.wrenches.clear();
        self.apply_pushes()?;
        // Keep the anchors so that a failed step can restore them.
        for (b, p) in self.anchor_backup.iter_mut().zip(&self.points) {
            *b = p.anchor;
        }
        let momentum_start = if self.config.momentum_projection {
            Some((self.kd.centroidal_momentum(), self.kd.com_position()))
        } else {
            None
        };
        let solved = match self.config.integrator {
            IntegratorKind::Implicit => self.solve_implicit(input),
            IntegratorKind::Explicit => self.solve_explicit(input),
        };
        let result = solved.and_then(|solve| {
            self.integrate(momentum_start)?;
            Ok(solve)
        });
        let solve = match result {
            Ok(solve) => solve,
            Err(e) => {
                self.restore_after_failure();
                return Err(e);
            }
        };
        // Commit: anchors of sliding points follow the slip.
        for p in &mut self.points {
            p.commit(&self.ground, self.dt);
        }
        std::mem::swap(&mut self.state, &mut self.next_state);
        self.time_ns += self.period_ns;
        if solve.cap_hit {
            self.solve_cap_hits += 1;
        }
        // Forces were computed at the start-of-step geometry; outputs use the end-of-step geometry.
        self.update_kinematics()?;
        let imu_velocity = lin(&self.kd.frame_velocity(self.imu_frame));
        let imu_acceleration = (imu_velocity - self.imu_velocity) / self.dt;
        self.imu_velocity = imu_velocity;
        self.update_output(&imu_acceleration, solve);
        Ok(())
    }

    /// Fills the output from the committed state and the forces of the last step; `imu_acceleration` is the
    /// world acceleration of the IMU origin over the step (m/s²).
    fn update_output(&mut self, imu_acceleration: &Vector3<f64>, solve: integrator::Solve) {
        let out = &mut self.output;
        out.time = Duration::from_nanos(self.time_ns);
        out.state.copy_from(&self.state);
        out.solves = solve.solves;
        out.solve_cap_hit = solve.cap_hit;
        out.solve_cap_hits = self.solve_cap_hits;
        self.sensors.read_encoders(
            &self.state,
            &mut out.joint_positions,
            &mut out.joint_velocities,
        );
        out.joint_torques.copy_from(&self.motor_torques);
        out.saturated.copy_from_slice(&self.saturated);
        out.total_contact_wrench.fill(0.0);
        for (si, s) in self.surfaces.iter().enumerate() {
            let points = &self.points[s.points()];
            self.sensors
                .measure_surface(si, s, points, &self.ground, out);
        }
        let pose = self.kd.frame_pose(self.imu_frame);
        let twist = self.kd.frame_velocity(self.imu_frame);
        self.sensors
            .measure_imu(&pose, &twist, imu_acceleration, &self.gravity, &mut out.imu);
        self.detect_fall();
    }

    /// Latches a fall when the root link origin is below `fall.min_base_height` above the ground or its z axis
    /// is tilted from the ground normal by more than `fall.max_tilt`.
    fn detect_fall(&mut self) {
        let n = self.ground.normal;
        let base = &self.state.base_pose;
        let height = self.ground.height_of(&base.translation.vector);
        let z_axis = base.rotation * Vector3::z();
        let tilt = z_axis.dot(&n).clamp(-1.0, 1.0).acos();
        if self.fall_time_ns.is_none()
            && (height < self.config.fall.min_base_height || tilt > self.config.fall.max_tilt)
        {
            self.fall_time_ns = Some(self.time_ns);
        }
        self.output.fallen = self.fall_time_ns.is_some();
        self.output.fall_time = self.fall_time_ns.map(Duration::from_nanos);
    }

    /// Undo the partial effects of a failed step (contact anchors set during the step are harmless; the
    /// dynamics workspace is reset to the unchanged state).
    fn restore_after_failure(&mut self) {
        for (b, p) in self.anchor_backup.iter().zip(&mut self.points) {
            p.anchor = *b;
        }
        // The state was not modified; re-synchronise the kinematics (cannot fail for a state that was accepted).
        let _ = self.update_kinematics();
    }
}

impl Block for SimRobot {
    type Input = SimInput;
    type Output = SimOutput;
    type Error = SimError;

    /// Advances the simulation by one period. On error the state, time and contact memory are those before
    /// the step.
    fn step(&mut self, input: &SimInput) -> Result<&SimOutput, SimError> {
        self.do_step(input)?;
        Ok(&self.output)
    }

    /// Returns to the initial state (the zero state, or the last [`SimRobot::set_initial_state`] /
    /// [`SimRobot::set_standing_on_ground`]) at time zero.
    fn reset(&mut self) {
        let initial = self.initial_state.clone();
        // The initial state was validated when it was set, so this cannot fail.
        let _ = self.set_initial_state(&initial);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn standing_humanoid() -> (SimRobot, SimInput, usize) {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/stride_humanoid.urdf"
        );
        let model = Arc::new(Model::from_urdf_file(path).expect("bundled model"));
        let q = DVector::zeros(model.dof());
        let mut sim = SimRobot::new(
            Arc::clone(&model),
            SimConfig::default(),
            Duration::from_micros(500),
        )
        .expect("default config");
        sim.set_standing_on_ground(&q).expect("placement");
        let mut input = SimInput::hold(&q);
        let elbow = model.joint_index("l_elbow").expect("l_elbow");
        // kp · 1.5 rad = 1500 N·m: the first solve drives the elbow beyond its 20 N·m limit, which saturates
        // it and needs a second solve.
        input.joint_positions[elbow] = 1.5;
        (sim, input, elbow)
    }

    #[test]
    fn a_saturation_settles_in_a_second_solve_under_the_default_cap() {
        let (mut sim, input, elbow) = standing_humanoid();
        let out = sim.step(&input).expect("step");
        assert!(out.saturated[elbow]);
        assert!(out.solves >= 2, "{} solves", out.solves);
        assert!(!out.solve_cap_hit);
        assert_eq!(out.solve_cap_hits, 0);
    }

    #[test]
    fn a_step_stopped_by_the_cap_is_flagged_and_counted() {
        let (mut sim, input, elbow) = standing_humanoid();
        // With one solve allowed, the saturation found after it cannot be solved again: the dynamics used the
        // unsaturated servo torque while the output reports the limit.
        sim.max_solves = 1;
        let limit = sim.model().joints()[elbow].effort_limit;
        let out = sim.step(&input).expect("step");
        assert_eq!(out.solves, 1);
        assert!(out.solve_cap_hit);
        assert_eq!(out.solve_cap_hits, 1);
        assert!(out.saturated[elbow]);
        assert_eq!(out.joint_torques[elbow], limit);
        // The elbow accelerated as with the unsaturated torque: far beyond what the limit allows.
        let v = sim.state().joint_velocities[elbow];
        let (mut reference, input_ref, _) = standing_humanoid();
        let v_saturated = reference
            .step(&input_ref)
            .expect("step")
            .state
            .joint_velocities[elbow];
        assert!(v > 10.0 * v_saturated.abs(), "{v} vs {v_saturated} rad/s");
        // The counter accumulates over the steps that hit the cap and restarts with the initial state.
        let mut hits = 1;
        for _ in 0..5 {
            let out = sim.step(&input).expect("step");
            hits += u64::from(out.solve_cap_hit);
            assert_eq!(out.solve_cap_hits, hits);
        }
        sim.reset();
        assert_eq!(sim.output().solve_cap_hits, 0);
        assert!(!sim.output().solve_cap_hit);
    }
}
