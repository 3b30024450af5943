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

use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use stride_block::Block;
use stride_model::{ExternalWrench, FrameId, KinDyn, Model, RobotState, VelocityRepresentation};

use crate::actuator::{resolve_actuators, torque_lag_gain, Actuator, Friction};
use crate::config::{IntegratorKind, JointActuatorConfig, PushConfig, SimConfig};
use crate::contact::{build_surfaces, GroundPlane, Point, Surface};
use crate::error::{find_frame, SimError};
use crate::io::{ContactPointState, SimInput, SimOutput};
use crate::linalg::{join, lin, TreeCholesky, TreeMatrix};
use crate::passive::{install_passive_joints, unmeasured_joints};
use crate::patches::GroundCompliance;
use crate::push::Push;
use crate::sensors::{Sensors, Truth};
use crate::stops::JointStops;

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
    /// The ground's normal densities along the path (its patches).
    compliance: GroundCompliance,
    actuators: Vec<Actuator>,
    /// Model indices of the passive joints (`config.passive_joints`): their commands are discarded.
    passive: Vec<usize>,
    /// The joints' end stops (`config.joint_stops`).
    stops: JointStops,
    /// Model indices of the passive joints without encoders: their encoder readings are 0.
    unmeasured: Vec<usize>,
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
    momentum_matrix: DMatrix<f64>,
    /// The tree factorisation of the implicit system, the mass matrix and the system in its packed pattern,
    /// and what a re-solve must refactorise (the system changed; in which branches of the tree).
    factorization: TreeCholesky,
    mass_packed: TreeMatrix,
    /// Where each entry of [`KinDyn::mass_matrix_lower`] goes in `mass_packed`, in the order it reports
    /// them (the same order at every state).
    mass_slots: Vec<usize>,
    system: TreeMatrix,
    system_changed: bool,
    changed_branches: Vec<bool>,
    bias: DVector<f64>,
    rhs: DVector<f64>,
    acceleration: DVector<f64>,
    external_forces: DVector<f64>,
    motor_torques: DVector<f64>,
    joint_torque_buffer: DVector<f64>,
    anchor_backup: Vec<Option<Vector3<f64>>>,
    saturated: Vec<bool>,
    wrenches: Vec<ExternalWrench>,
    /// Coulomb friction phase of each joint (kept from step to step), its copy for a failed step, and the
    /// number of phase switches of each joint in the current step (at most two).
    friction: Vec<Friction>,
    friction_backup: Vec<Friction>,
    friction_switches: Vec<u8>,
    /// Motor torque of the torque-mode lag at the end of the last step, N·m.
    lagged_torques: DVector<f64>,
    /// Command delay line of `command_delay_steps + 1` inputs; `commands[command_head]` receives the next.
    commands: Vec<SimInput>,
    command_head: usize,
    /// The command applied in the current step (the delayed one, torque lag applied).
    applied: SimInput,
    /// External wrenches of the step for the force/torque sensors (contacts and pushes).
    ft_external: Vec<ExternalWrench>,
    /// Transmitted wrench of each force/torque sensor in the last step (sensor frame), N, N·m.
    ft_truth: Vec<Vector6<f64>>,
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
        let mut actuators = resolve_actuators(&model, &config.actuation)?;
        let passive = install_passive_joints(&model, &config.passive_joints, &mut actuators)?;
        let unmeasured = unmeasured_joints(&model, &config.passive_joints);
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
        let n_ft = model.ft_sensors().len();
        let output = SimOutput::new(
            &state,
            config.contact.surfaces.iter().map(|s| s.name.clone()),
            points.iter().map(|p| p.surface),
            n_ft,
        );
        let dt = period_ns as f64 * 1e-9;
        let wrench_capacity = surfaces.len() + pushes.len() + 8;
        let mut sim = Self {
            kd,
            dt,
            period_ns,
            time_ns: 0,
            gravity: model.gravity(),
            ground: GroundPlane::from_config(&config.ground),
            compliance: GroundCompliance::from_config(&config.ground, &config.contact),
            actuators,
            passive,
            stops: JointStops::new(&model, &config.joint_stops),
            unmeasured,
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
            momentum_matrix: DMatrix::zeros(6, nv),
            mass_packed: factorization.matrix(),
            mass_slots: Vec::new(),
            system: factorization.matrix(),
            system_changed: false,
            changed_branches: vec![false; factorization.branch_count()],
            factorization,
            bias: DVector::zeros(nv),
            rhs: DVector::zeros(nv),
            acceleration: DVector::zeros(nv),
            external_forces: DVector::zeros(nv),
            motor_torques: DVector::zeros(n),
            joint_torque_buffer: DVector::zeros(n),
            saturated: vec![false; n],
            wrenches: Vec::with_capacity(wrench_capacity),
            friction: vec![Friction::Stick; n],
            friction_backup: vec![Friction::Stick; n],
            friction_switches: vec![0; n],
            lagged_torques: DVector::zeros(n),
            commands: vec![SimInput::zeros(n); config.actuation.command_delay_steps + 1],
            command_head: 0,
            applied: SimInput::zeros(n),
            ft_external: Vec::with_capacity(wrench_capacity),
            ft_truth: vec![Vector6::zeros(); n_ft],
            sensors: Sensors::new(&model, &config.sensors, dt),
            fall_time_ns: None,
            max_solves: SimOutput::MAX_SOLVES,
            solve_cap_hits: 0,
            output,
            config,
            model,
        };
        let tree = &sim.factorization;
        let mut slots = Vec::with_capacity(tree.matrix().values().len());
        sim.kd
            .mass_matrix_lower(|row, col, _| slots.push(tree.lower_index(row, col)));
        sim.mass_slots = slots;
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

    /// The dynamics workspace, at the current state after a step or a state change (the kinematics of
    /// [`Self::state`]; its dynamics caches are those of the last step's solve).
    pub fn kinematics(&self) -> &KinDyn {
        &self.kd
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

    /// The force/torque sensors' true offsets and calibration matrices (see
    /// [`crate::SensorModels::ft_offsets`] and [`crate::SensorModels::ft_calibration_matrices`]).
    pub fn ft_calibration_truth(&self) -> (&[nalgebra::Vector6<f64>], Vec<nalgebra::Matrix6<f64>>) {
        (
            self.sensors.ft_offsets(),
            self.sensors.ft_calibration_matrices(),
        )
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
        if self.passive.contains(&index) {
            return Err(SimError::InvalidConfig {
                parameter: "passive_joints".into(),
                message: format!("`{joint}` is passive: it has no actuator to change"),
            });
        }
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
        // The delay line takes the new command; the step applies the one of `command_delay_steps` ago. A failed
        // step does not advance the line (the slot written is the one no longer needed).
        copy_input(&mut self.commands[self.command_head], input);
        let delayed = (self.command_head + 1) % self.commands.len();
        let mut applied = std::mem::replace(&mut self.applied, SimInput::zeros(0));
        copy_input(&mut applied, &self.commands[delayed]);
        self.discard_passive_commands(&mut applied);
        self.lag_torques(&mut applied);
        let result = self.advance(&applied);
        self.applied = applied;
        if result.is_ok() {
            self.command_head = delayed;
        }
        result
    }

    /// Passive joints have no motor: their spring-damper servo ([`crate::passive`]) pulls to `q = 0`,
    /// `q̇ = 0` with no feed-forward, whatever the controllers commanded.
    fn discard_passive_commands(&self, applied: &mut SimInput) {
        for &j in &self.passive {
            applied.joint_positions[j] = 0.0;
            applied.joint_velocities[j] = 0.0;
            applied.joint_torques[j] = 0.0;
        }
    }

    /// Torque-mode joints: the motor torque follows the command through the first-order lag of the joint's
    /// `torque_bandwidth`, `τ = τ_prev + β (τ_cmd − τ_prev)` (written into `applied.joint_torques`).
    fn lag_torques(&self, applied: &mut SimInput) {
        for (j, a) in self.actuators.iter().enumerate() {
            if a.mode == crate::config::ActuationMode::Torque {
                let beta = torque_lag_gain(self.dt, a.torque_bandwidth);
                let previous = self.lagged_torques[j];
                applied.joint_torques[j] = previous + beta * (applied.joint_torques[j] - previous);
            }
        }
    }

    /// One step with the applied command `input`: solve, integrate, commit the contact memory, then measure at
    /// the end-of-step state. On error the state, time, contact anchors and friction phases are those before
    /// the step.
    fn advance(&mut self, input: &SimInput) -> Result<(), SimError> {
        self.wrenches.clear();
        self.apply_pushes()?;
        // Keep the anchors so that a failed step can restore them.
        for (b, p) in self.anchor_backup.iter_mut().zip(&self.points) {
            *b = p.anchor;
        }
        self.friction_backup.copy_from_slice(&self.friction);
        let momentum_start = if self.config.momentum_projection && !self.config.fixed_base {
            Some((self.kd.centroidal_momentum(), self.kd.com_position()))
        } else {
            None
        };
        let solved = match self.config.integrator {
            IntegratorKind::Implicit => self.solve_implicit(input),
            IntegratorKind::Explicit => self.solve_explicit(input),
        };
        let result = solved.and_then(|solve| {
            // The sensors' transmitted wrenches need the start-of-step workspace, which `integrate` may move.
            self.compute_ft_truth()?;
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
        self.lagged_torques.copy_from(&input.joint_torques);
        // Forces were computed at the start-of-step geometry; outputs use the end-of-step geometry.
        self.update_kinematics()?;
        let imu_velocity = lin(&self.kd.frame_velocity(self.imu_frame));
        let imu_acceleration = (imu_velocity - self.imu_velocity) / self.dt;
        self.imu_velocity = imu_velocity;
        self.update_output(&imu_acceleration, solve, false);
        Ok(())
    }

    /// The wrench transmitted through each force/torque sensor during the step
    /// ([`KinDyn::ft_sensor_readings`], the sensors' subtrees only) from the step's acceleration and external wrenches (each touching
    /// surface's point forces about its frame origin, the active pushes), at the start-of-step state the
    /// dynamics used.
    pub(super) fn compute_ft_truth(&mut self) -> Result<(), SimError> {
        if self.ft_truth.is_empty() {
            return Ok(());
        }
        self.ft_external.clear();
        for s in &self.surfaces {
            let o = s.pose.translation.vector;
            let mut w = Vector6::zeros();
            for p in &self.points[s.points()] {
                w += join(&p.force, &(p.position - o).cross(&p.force));
            }
            if w != Vector6::zeros() {
                self.ft_external.push(ExternalWrench {
                    frame: s.frame,
                    wrench: w,
                });
            }
        }
        for p in &self.pushes {
            if p.is_active(self.time_ns) {
                self.ft_external.push(ExternalWrench {
                    frame: p.frame,
                    wrench: p.wrench,
                });
            }
        }
        self.kd
            .ft_sensor_readings(&self.acceleration, &self.ft_external, &mut self.ft_truth)?;
        Ok(())
    }

    /// Fills the output from the committed state and the forces of the last step; `imu_acceleration` is the
    /// world acceleration of the IMU origin over the step (m/s²); `fresh_start` after a state change (the
    /// sensors restart their filters and delay line).
    fn update_output(
        &mut self,
        imu_acceleration: &Vector3<f64>,
        solve: integrator::Solve,
        fresh_start: bool,
    ) {
        let out = &mut self.output;
        out.time = Duration::from_nanos(self.time_ns);
        out.state.copy_from(&self.state);
        out.solves = solve.solves;
        out.solve_cap_hit = solve.cap_hit;
        out.solve_cap_hits = self.solve_cap_hits;
        out.joint_torques.copy_from(&self.motor_torques);
        out.saturated.copy_from_slice(&self.saturated);
        out.total_contact_wrench.fill(0.0);
        for (si, s) in self.surfaces.iter().enumerate() {
            let points = &self.points[s.points()];
            Sensors::measure_surface(si, s, points, &self.ground, out);
        }
        let truth = Truth {
            state: &self.state,
            imu_pose: self.kd.frame_pose(self.imu_frame),
            imu_twist: self.kd.frame_velocity(self.imu_frame),
            imu_acceleration: *imu_acceleration,
            gravity: self.gravity,
            time: self.time_ns as f64 * 1e-9,
            ft_wrenches: &self.ft_truth,
            fresh_start,
        };
        self.sensors.measure(&truth, out);
        for &j in &self.unmeasured {
            out.joint_positions[j] = 0.0;
            out.joint_velocities[j] = 0.0;
        }
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
        self.friction.copy_from_slice(&self.friction_backup);
        // The state was not modified; re-synchronise the kinematics (cannot fail for a state that was accepted).
        let _ = self.update_kinematics();
    }
}

/// Copies `from` into `to` (same sizes; no allocation).
fn copy_input(to: &mut SimInput, from: &SimInput) {
    to.joint_positions.copy_from(&from.joint_positions);
    to.joint_velocities.copy_from(&from.joint_velocities);
    to.joint_torques.copy_from(&from.joint_torques);
}

impl SimRobot {
    /// Advances the simulation by one period. On error the state, time and contact memory are those before
    /// the step.
    ///
    /// Inherent, so a caller need not import [`stride_block::Block`] (the `Block` impl calls it).
    pub fn step(&mut self, input: &SimInput) -> Result<&SimOutput, SimError> {
        self.do_step(input)?;
        Ok(&self.output)
    }
}

impl Block for SimRobot {
    type Input = SimInput;
    type Output = SimOutput;
    type Error = SimError;

    fn step(&mut self, input: &SimInput) -> Result<&SimOutput, SimError> {
        SimRobot::step(self, input)
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
        // Ideal actuators: the saturating command acts in the first step (no command delay, no friction).
        let config = SimConfig {
            actuation: crate::config::ActuationConfig::ideal(),
            ..SimConfig::default()
        };
        let mut sim = SimRobot::new(Arc::clone(&model), config, Duration::from_micros(500))
            .expect("default config");
        sim.set_standing_on_ground(&q).expect("placement");
        let mut input = SimInput::hold(&q);
        let elbow = model.joint_index("l_elbow").expect("l_elbow");
        // kp · 1.5 rad = 1500 N·m: the first solve drives the elbow beyond its 20 N·m limit, which saturates
        // it and needs a second solve.
        input.joint_positions[elbow] = 1.5;
        (sim, input, elbow)
    }

    /// The mass matrix the implicit step packs through its slots is the dense CRBA matrix gathered into
    /// the tree pattern, bit for bit, after a few steps of motion.
    #[test]
    fn the_packed_mass_matrix_is_the_gathered_dense_one() {
        let (mut sim, input, _) = standing_humanoid();
        for _ in 0..5 {
            sim.step(&input).expect("step");
        }
        sim.mass_packed.values_mut().fill(f64::NAN);
        sim.pack_mass_matrix();
        let nv = sim.model.nv();
        let mut dense = DMatrix::zeros(nv, nv);
        sim.kd.mass_matrix(&mut dense).unwrap();
        let mut gathered = sim.factorization.matrix();
        sim.factorization.gather(&dense, &mut gathered);
        let bits = |m: &TreeMatrix| m.values().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&sim.mass_packed), bits(&gathered));
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
