//! The simulated robot block: state, one time step, sensors.

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Matrix6, UnitQuaternion, Vector3, Vector6};
use stride_block::Block;
use stride_model::{
    ExternalWrench, FrameId, KinDyn, Model, ModelError, RobotState, VelocityRepresentation,
};

use crate::config::{
    ActuationMode, EffortLimitPolicy, IntegratorKind, JointActuatorConfig, PushConfig, SimConfig,
};
use crate::contact::{surface_points, ContactMode, GroundPlane, PointLaw};
use crate::error::SimError;
use crate::linalg::TreeCholesky;
use crate::noise::GaussianNoise;

/// Largest number of re-solves of one implicit step while contact modes and saturations settle.
const MAX_MODE_ITERATIONS: usize = 20;

/// Commands for one step. All vectors have the model's `dof()` entries in model order; which ones a joint uses
/// depends on its [`ActuationMode`].
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
    /// The same wrench as the six-axis sensor reports it: expressed in the sensor frame (the configured
    /// `ft_sensor` frame, else the surface frame), torque about the sensor origin, noise added (N, N·m). The
    /// sensor is ideal in that it measures the contact wrench (the inertia and weight of the part below the
    /// sensor are not subtracted).
    pub sensor_wrench: Vector6<f64>,
    /// Normal force along the ground normal, N (zero without contact).
    pub normal_force: f64,
    /// Centre of pressure on the ground plane (world), m; equals the surface frame origin projected on the
    /// ground when there is no contact.
    pub center_of_pressure: Vector3<f64>,
}

/// Inertial measurement unit reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuMeasurement {
    /// `world_R_imu` (with noise if configured).
    pub orientation: UnitQuaternion<f64>,
    /// Angular velocity of the IMU frame, expressed in the IMU frame, rad/s.
    pub angular_velocity: Vector3<f64>,
    /// Proper acceleration (acceleration minus gravity) of the IMU origin, in the IMU frame, m/s². At rest on
    /// flat ground it reads `[0, 0, +9.81]`.
    pub proper_acceleration: Vector3<f64>,
}

/// Everything the simulator reports after a step (or after its state was set).
#[derive(Clone, Debug, PartialEq)]
pub struct SimOutput {
    /// Simulated time at the end of the step.
    pub time: Duration,
    /// Ground-truth state (base velocity in the mixed representation).
    pub state: RobotState,
    /// Encoder positions (with noise), rad (m).
    pub joint_positions: DVector<f64>,
    /// Encoder velocities (with noise), rad/s (m/s).
    pub joint_velocities: DVector<f64>,
    /// Motor torques applied during the step (after saturation), N·m (N).
    pub joint_torques: DVector<f64>,
    /// `true` for the joints whose motor torque was saturated at the effort limit during the step.
    pub saturated: Vec<bool>,
    /// One entry per configured contact surface.
    pub surfaces: Vec<SurfaceMeasurement>,
    /// All contact points, surface by surface.
    pub contact_points: Vec<ContactPointState>,
    /// IMU reading.
    pub imu: ImuMeasurement,
    /// Total wrench `[f; τ]` of all contacts on the robot, world orientation, torque about the world origin.
    pub total_contact_wrench: Vector6<f64>,
    /// A fall has been detected (latched until reset or a new initial state).
    pub fallen: bool,
    /// When the fall was first detected.
    pub fall_time: Option<Duration>,
    /// Number of linear solves of the last step (1 when no contact mode or saturation changed).
    pub solves: usize,
}

/// A joint actuator with every parameter resolved.
#[derive(Clone, Copy, Debug)]
struct Actuator {
    mode: ActuationMode,
    kp: f64,
    kd: f64,
    limit: f64,
    damping: f64,
    armature: f64,
}

/// A contact surface with its per-step data.
#[derive(Clone, Debug)]
struct Surface {
    frame: FrameId,
    ft_frame: Option<FrameId>,
    first_point: usize,
    point_count: usize,
    pose: Isometry3<f64>,
    twist: Vector6<f64>,
    ft_pose: Isometry3<f64>,
    jacobian: DMatrix<f64>,
    /// Indices of the non-zero columns of `jacobian`.
    columns: Vec<usize>,
    scratch: DMatrix<f64>,
    acceleration: Vector6<f64>,
    wrench: Vector6<f64>,
}

/// A contact point with its memory (the stick anchor) and its per-step data.
#[derive(Clone, Copy, Debug)]
struct Point {
    surface: usize,
    local: Vector3<f64>,
    law: PointLaw,
    /// Where the tangential spring is attached (on the ground), while in contact.
    anchor: Option<Vector3<f64>>,
    position: Vector3<f64>,
    /// `position − surface origin` (world).
    arm: Vector3<f64>,
    velocity: Vector3<f64>,
    penetration: f64,
    mode: ContactMode,
    slide_direction: Vector3<f64>,
    normal_force_estimate: f64,
    /// Force at the start of the step with the current mode (`f0`).
    force_start: Vector3<f64>,
    /// Force applied during the step.
    force: Vector3<f64>,
    /// Velocity at the end of the step.
    velocity_end: Vector3<f64>,
}

#[derive(Clone, Debug)]
struct Push {
    frame: FrameId,
    start_ns: u64,
    end_ns: u64,
    wrench: Vector6<f64>,
}

/// The simulated robot: floating-base dynamics of a [`Model`] on compliant ground, joint servos, sensors and
/// pushes. One [`Block::step`] advances one period `1 / rate_hz`.
///
/// ```no_run
/// use std::sync::Arc;
/// use stride_block::Block;
/// use stride_model::Model;
/// use stride_sim::{SimConfig, SimInput, SimRobot};
///
/// let model = Arc::new(Model::from_urdf_file("models/stride_humanoid.urdf")?);
/// let mut sim = SimRobot::new(Arc::clone(&model), SimConfig::default())?;
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
    dt: f64,
    period_ns: u64,
    time_ns: u64,
    gravity: Vector3<f64>,
    ground: GroundPlane,
    actuators: Vec<Actuator>,
    surfaces: Vec<Surface>,
    points: Vec<Point>,
    pushes: Vec<Push>,
    push_jacobian: DMatrix<f64>,
    imu_frame: FrameId,
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
    noise: GaussianNoise,
    fall_time_ns: Option<u64>,
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

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

fn lin(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

fn ang(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}

fn join(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

fn secs_to_ns(s: f64) -> u64 {
    (s * 1e9).round().max(0.0) as u64
}

impl SimRobot {
    /// Builds the simulator for `model` (validating `config` against it). The robot starts in the model's
    /// zero state (base at the world origin); place it with [`SimRobot::set_standing_on_ground`] or
    /// [`SimRobot::set_initial_state`].
    pub fn new(model: Arc<Model>, config: SimConfig) -> Result<Self, SimError> {
        config.validate()?;
        if config.integrator == IntegratorKind::Explicit
            && (config.actuation.default.armature > 0.0
                || config
                    .actuation
                    .joints
                    .iter()
                    .any(|j| j.armature.unwrap_or(0.0) > 0.0))
        {
            return Err(SimError::InvalidConfig {
                parameter: "actuation.armature".into(),
                message: "armature needs the implicit integrator".into(),
            });
        }
        let n = model.dof();
        let nv = model.nv();
        let find_frame = |parameter: &str, name: &str| -> Result<FrameId, SimError> {
            model.frame_id(name).ok_or_else(|| SimError::UnknownFrame {
                parameter: parameter.to_string(),
                frame: name.to_string(),
                model: model.name().to_string(),
            })
        };

        // Actuators.
        let mut actuators: Vec<Actuator> = model
            .joints()
            .iter()
            .map(|j| resolve_actuator(&config.actuation.default, j.effort_limit))
            .collect();
        for o in &config.actuation.joints {
            let index = model
                .joint_index(&o.name)
                .ok_or_else(|| SimError::UnknownJoint {
                    parameter: "actuation.joints".into(),
                    joint: o.name.clone(),
                })?;
            let a = &mut actuators[index];
            if let Some(m) = o.mode {
                a.mode = m;
            }
            if let Some(v) = o.kp {
                a.kp = v;
            }
            if let Some(v) = o.kd {
                a.kd = v;
            }
            if let Some(v) = o.effort_limit {
                a.limit = v;
            }
            if let Some(v) = o.damping {
                a.damping = v;
            }
            if let Some(v) = o.armature {
                a.armature = v;
            }
        }

        // Contact surfaces and points.
        let mut surfaces = Vec::with_capacity(config.contact.surfaces.len());
        let mut points = Vec::new();
        for (si, sc) in config.contact.surfaces.iter().enumerate() {
            let frame = find_frame(&format!("contact.surfaces[{}].frame", sc.name), &sc.frame)?;
            let ft_frame = match &sc.ft_sensor {
                Some(name) => Some(find_frame(
                    &format!("contact.surfaces[{}].ft_sensor", sc.name),
                    name,
                )?),
                None => None,
            };
            let specs = surface_points(sc, &config.contact);
            surfaces.push(Surface {
                frame,
                ft_frame,
                first_point: points.len(),
                point_count: specs.len(),
                pose: Isometry3::identity(),
                twist: Vector6::zeros(),
                ft_pose: Isometry3::identity(),
                jacobian: DMatrix::zeros(6, nv),
                columns: Vec::with_capacity(nv),
                scratch: DMatrix::zeros(6, nv),
                acceleration: Vector6::zeros(),
                wrench: Vector6::zeros(),
            });
            for spec in specs {
                points.push(Point {
                    surface: si,
                    local: spec.local,
                    law: spec.law,
                    anchor: None,
                    position: Vector3::zeros(),
                    arm: Vector3::zeros(),
                    velocity: Vector3::zeros(),
                    penetration: 0.0,
                    mode: ContactMode::Separated,
                    slide_direction: Vector3::zeros(),
                    normal_force_estimate: 0.0,
                    force_start: Vector3::zeros(),
                    force: Vector3::zeros(),
                    velocity_end: Vector3::zeros(),
                });
            }
        }

        let mut pushes = Vec::with_capacity(config.pushes.len());
        for (i, p) in config.pushes.iter().enumerate() {
            pushes.push(make_push(&model, p, &format!("pushes[{i}].frame"))?);
        }

        let imu_frame = match model.frame_id(&config.sensors.imu_frame) {
            Some(f) => f,
            None => find_frame("sensors.imu_frame", model.root_link())?,
        };

        let factorization =
            TreeCholesky::floating_base(&model).ok_or_else(|| SimError::InvalidConfig {
                parameter: "model".into(),
                message: "the model's bodies are not in depth-first order".into(),
            })?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let gravity = Vector3::from(config.gravity);
        kd.set_gravity(gravity);

        let state = RobotState::zero(&model);
        let output = SimOutput {
            time: Duration::ZERO,
            state: state.clone(),
            joint_positions: DVector::zeros(n),
            joint_velocities: DVector::zeros(n),
            joint_torques: DVector::zeros(n),
            saturated: vec![false; n],
            surfaces: config
                .contact
                .surfaces
                .iter()
                .map(|s| SurfaceMeasurement {
                    name: s.name.clone(),
                    in_contact: false,
                    wrench: Vector6::zeros(),
                    sensor_wrench: Vector6::zeros(),
                    normal_force: 0.0,
                    center_of_pressure: Vector3::zeros(),
                })
                .collect(),
            contact_points: points
                .iter()
                .map(|p| ContactPointState {
                    surface: p.surface,
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
            total_contact_wrench: Vector6::zeros(),
            fallen: false,
            fall_time: None,
            solves: 0,
        };
        let wrench_capacity = surfaces.len() + pushes.len() + 8;
        let mut sim = Self {
            kd,
            dt: config.period(),
            period_ns: config.period_ns(),
            time_ns: 0,
            gravity,
            ground: GroundPlane::from_config(&config.ground),
            actuators,
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
            anchor_backup: Vec::new(),
            saturated: vec![false; n],
            wrenches: Vec::with_capacity(wrench_capacity),
            noise: GaussianNoise::new(config.sensors.noise.seed),
            fall_time_ns: None,
            output,
            config,
            model,
        };
        sim.anchor_backup = vec![None; sim.points.len()];
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
        let p = make_push(&self.model, push, "push.frame")?;
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
        self.actuators[index] = resolve_actuator(actuator, limit);
        Ok(())
    }

    /// Replaces the current state (time and contact memory are kept/reinitialised: penetrating points stick
    /// where they are). The base velocity is read in the mixed representation.
    pub fn set_state(&mut self, state: &RobotState) -> Result<(), SimError> {
        self.check_state(state)?;
        self.state.base_pose = state.base_pose;
        self.state.base_velocity = state.base_velocity;
        self.state.joint_positions.copy_from(&state.joint_positions);
        self.state
            .joint_velocities
            .copy_from(&state.joint_velocities);
        for p in &mut self.points {
            p.anchor = None;
        }
        self.refresh_after_state_change()
    }

    /// Sets the state and makes it the one [`Block::reset`] returns to; the time restarts at zero and the fall
    /// flag and the noise sequence are reset.
    pub fn set_initial_state(&mut self, state: &RobotState) -> Result<(), SimError> {
        self.check_state(state)?;
        self.initial_state.clone_from(state);
        self.time_ns = 0;
        self.fall_time_ns = None;
        self.noise.reset();
        self.set_state(state)
    }

    /// Places the robot at rest with the given joint positions and an upright base (identity orientation, base
    /// at x = y = 0) so that its lowest contact points sink into the ground by the static penetration expected
    /// under the robot's weight (`m g / Σ k` over the lowest points, within 0.1 mm of the lowest). Makes this the
    /// initial state and returns it.
    pub fn set_standing_on_ground(
        &mut self,
        joint_positions: &DVector<f64>,
    ) -> Result<RobotState, SimError> {
        let mut state = RobotState::zero(&self.model);
        if joint_positions.len() != state.joint_positions.len() {
            return Err(SimError::Dimension {
                what: "joint_positions",
                expected: state.joint_positions.len(),
                actual: joint_positions.len(),
            });
        }
        state.joint_positions.copy_from(joint_positions);
        self.check_state(&state)?;
        self.kd.set_state(&state)?;
        let mut lowest = f64::INFINITY;
        for p in &self.points {
            let pose = self.kd.frame_pose(self.surfaces[p.surface].frame);
            lowest = lowest.min(
                self.ground
                    .height_of(&(pose * nalgebra::Point3::from(p.local)).coords),
            );
        }
        if lowest.is_finite() {
            let mut stiffness = 0.0;
            for p in &self.points {
                let pose = self.kd.frame_pose(self.surfaces[p.surface].frame);
                let h = self
                    .ground
                    .height_of(&(pose * nalgebra::Point3::from(p.local)).coords);
                if h < lowest + 1e-4 {
                    stiffness += p.law.normal_stiffness;
                }
            }
            let weight =
                self.model.total_mass() * (-self.gravity.dot(&self.ground.normal)).max(0.0);
            let sink = if stiffness > 0.0 {
                weight / stiffness
            } else {
                0.0
            };
            let shift = self.ground.normal * (-(lowest + sink));
            state.base_pose.translation.vector += shift;
        }
        self.set_initial_state(&state)?;
        Ok(state)
    }

    fn check_state(&self, state: &RobotState) -> Result<(), SimError> {
        state.validate(&self.model).map_err(|e| match e {
            ModelError::NonFiniteInput { what } => SimError::NonFiniteState { what },
            ModelError::DimensionMismatch {
                what,
                expected_rows,
                rows,
                ..
            } => SimError::Dimension {
                what,
                expected: expected_rows,
                actual: rows,
            },
            other => SimError::Model(other),
        })
    }

    /// Recomputes the kinematics, initialises contact anchors and the output after a state change.
    fn refresh_after_state_change(&mut self) -> Result<(), SimError> {
        self.update_kinematics()?;
        for p in &mut self.points {
            if p.penetration > 0.0 {
                if p.anchor.is_none() {
                    p.anchor = Some(self.ground.project(&p.position));
                }
            } else {
                p.anchor = None;
            }
            // Explicit estimate of the current forces for the initial output.
            p.mode = if p.penetration > 0.0 {
                ContactMode::Sticking
            } else {
                ContactMode::Separated
            };
            let f = explicit_point_force(p, &self.ground);
            p.force = f.0;
            p.mode = f.1;
        }
        self.imu_velocity = lin(&self.kd.frame_velocity(self.imu_frame));
        self.motor_torques.fill(0.0);
        self.saturated.iter_mut().for_each(|s| *s = false);
        self.update_output(None, 0)
    }

    /// Sets the dynamics workspace to the current state and updates surface poses/twists and point positions,
    /// velocities and penetrations.
    fn update_kinematics(&mut self) -> Result<(), SimError> {
        self.kd.set_state(&self.state)?;
        for s in &mut self.surfaces {
            s.pose = self.kd.frame_pose(s.frame);
            s.twist = self.kd.frame_velocity(s.frame);
            if let Some(f) = s.ft_frame {
                s.ft_pose = self.kd.frame_pose(f);
            } else {
                s.ft_pose = s.pose;
            }
        }
        for p in &mut self.points {
            let s = &self.surfaces[p.surface];
            p.position = (s.pose * nalgebra::Point3::from(p.local)).coords;
            p.arm = p.position - s.pose.translation.vector;
            p.velocity = lin(&s.twist) + ang(&s.twist).cross(&p.arm);
            p.penetration = -self.ground.height_of(&p.position);
        }
        Ok(())
    }

    fn check_input(&self, input: &SimInput) -> Result<(), SimError> {
        let n = self.model.dof();
        for (what, len) in [
            ("joint position commands", input.joint_positions.len()),
            ("joint velocity commands", input.joint_velocities.len()),
            ("joint torque commands", input.joint_torques.len()),
        ] {
            if len != n {
                return Err(SimError::Dimension {
                    what,
                    expected: n,
                    actual: len,
                });
            }
        }
        for (j, a) in self.actuators.iter().enumerate() {
            let name = || self.model.joints()[j].name.clone();
            let (qd, vd, tau) = (
                input.joint_positions[j],
                input.joint_velocities[j],
                input.joint_torques[j],
            );
            if a.mode == ActuationMode::Position && !qd.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "position",
                    joint: name(),
                    value: qd,
                });
            }
            if a.mode != ActuationMode::Torque && !vd.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "velocity",
                    joint: name(),
                    value: vd,
                });
            }
            if !tau.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "torque",
                    joint: name(),
                    value: tau,
                });
            }
            if self.config.actuation.effort_limit_policy == EffortLimitPolicy::Error
                && tau.abs() > a.limit
            {
                return Err(SimError::EffortLimit {
                    joint: name(),
                    torque: tau,
                    limit: a.limit,
                });
            }
        }
        Ok(())
    }

    /// Generalized force of the pushes active at the current time (into `external_forces`), and the list of
    /// external wrenches for the explicit path (into `wrenches`).
    fn apply_pushes(&mut self) -> Result<(), SimError> {
        self.external_forces.fill(0.0);
        let t = self.time_ns;
        for p in &self.pushes {
            if t >= p.start_ns && t < p.end_ns {
                match self.config.integrator {
                    IntegratorKind::Implicit => {
                        self.kd.frame_jacobian(p.frame, &mut self.push_jacobian)?;
                        self.external_forces
                            .gemv_tr(1.0, &self.push_jacobian, &p.wrench, 1.0);
                    }
                    IntegratorKind::Explicit => {
                        self.wrenches.push(ExternalWrench {
                            frame: p.frame,
                            wrench: p.wrench,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// One implicit step: fills `acceleration`, point forces and motor torques. Returns the number of solves.
    fn solve_implicit(&mut self, input: &SimInput) -> Result<usize, SimError> {
        self.kd.mass_matrix(&mut self.mass)?;
        self.kd.bias_forces(&mut self.bias)?;
        for s in &mut self.surfaces {
            self.kd.frame_jacobian(s.frame, &mut s.jacobian)?;
            s.columns.clear();
            for c in 0..s.jacobian.ncols() {
                if s.jacobian
                    .fixed_view::<6, 1>(0, c)
                    .iter()
                    .any(|x| *x != 0.0)
                {
                    s.columns.push(c);
                }
            }
        }
        for p in &mut self.points {
            if p.penetration > 0.0 {
                p.mode = ContactMode::Sticking;
                if p.anchor.is_none() {
                    p.anchor = Some(self.ground.project(&p.position));
                }
            } else {
                p.mode = ContactMode::Separated;
            }
            p.normal_force_estimate = 0.0;
        }
        self.saturated.iter_mut().for_each(|s| *s = false);
        let mut solves = 0;
        loop {
            self.assemble_implicit(input);
            if !self.factorization.factor(&mut self.system) {
                return Err(SimError::NotPositiveDefinite {
                    time: self.time_ns as f64 * 1e-9,
                });
            }
            self.acceleration.copy_from(&self.rhs);
            self.factorization
                .solve(&self.system, &mut self.acceleration);
            solves += 1;
            let changed = self.update_modes(input);
            if !changed || solves >= MAX_MODE_ITERATIONS {
                break;
            }
        }
        Ok(solves)
    }

    /// Builds `(M + dt D + dt² K) ν̇ = rhs` for the current modes.
    fn assemble_implicit(&mut self, input: &SimInput) {
        let dt = self.dt;
        let nb = 6;
        self.system.copy_from(&self.mass);
        self.rhs.copy_from(&self.external_forces);
        self.rhs -= &self.bias;
        let q = &self.state.joint_positions;
        let qd = &self.state.joint_velocities;
        for (j, a) in self.actuators.iter().enumerate() {
            let (mut kp, mut kd) = match a.mode {
                ActuationMode::Position => (a.kp, a.kd),
                ActuationMode::Velocity => (0.0, a.kd),
                ActuationMode::Torque => (0.0, 0.0),
            };
            let motor = if self.saturated[j] {
                kp = 0.0;
                kd = 0.0;
                self.motor_torques[j]
            } else {
                let mut t = input.joint_torques[j];
                if a.mode == ActuationMode::Position {
                    t += a.kp * (input.joint_positions[j] - q[j] - dt * qd[j]);
                }
                if a.mode != ActuationMode::Torque {
                    t += a.kd * (input.joint_velocities[j] - qd[j]);
                }
                t
            };
            let i = nb + j;
            self.system[(i, i)] += a.armature + dt * (kd + a.damping) + dt * dt * kp;
            self.rhs[i] += motor - a.damping * qd[j];
        }
        for s in &mut self.surfaces {
            let mut k6 = Matrix6::zeros();
            let mut d6 = Matrix6::zeros();
            let mut w0 = Vector6::zeros();
            let mut active = false;
            for p in &mut self.points[s.first_point..s.first_point + s.point_count] {
                if p.mode == ContactMode::Separated {
                    continue;
                }
                active = true;
                let n = self.ground.normal;
                let (k, d) = p.law.matrices(p.mode, &n);
                let vn = n.dot(&p.velocity);
                let mut f0 =
                    n * (p.law.normal_stiffness * p.penetration - p.law.normal_damping * vn);
                match p.mode {
                    ContactMode::Sticking => {
                        let anchor = p.anchor.unwrap_or(p.position);
                        f0 -= self.ground.tangential(&(p.position - anchor))
                            * p.law.tangential_stiffness;
                        f0 -= self.ground.tangential(&p.velocity) * p.law.tangential_damping;
                    }
                    ContactMode::Sliding => {
                        f0 += p.slide_direction * (p.law.friction * p.normal_force_estimate);
                    }
                    ContactMode::Separated => {}
                }
                p.force_start = f0;
                let r = skew(&p.arm);
                add_point_matrix(&mut k6, &k, &r);
                add_point_matrix(&mut d6, &d, &r);
                let t = p.arm.cross(&f0);
                w0 += join(&f0, &t);
            }
            if !active {
                continue;
            }
            let g6 = k6 * (dt * dt) + d6 * dt;
            let w = w0 - k6 * s.twist * dt;
            // Jᵀ G J and Jᵀ w over the non-zero columns of J only (the joints that move the surface).
            for &c in &s.columns {
                let col = s.jacobian.fixed_view::<6, 1>(0, c);
                s.scratch
                    .fixed_view_mut::<6, 1>(0, c)
                    .copy_from(&(g6 * col));
                self.rhs[c] += col.dot(&w);
            }
            for &c in &s.columns {
                let gc = s.scratch.fixed_view::<6, 1>(0, c);
                for &r in &s.columns {
                    self.system[(r, c)] += s.jacobian.fixed_view::<6, 1>(0, r).dot(&gc);
                }
            }
        }
    }

    /// After a solve: end-of-step forces, torques; switches contact modes and saturations that the solution
    /// violates. Returns whether anything changed (then the step is solved again).
    fn update_modes(&mut self, input: &SimInput) -> bool {
        let dt = self.dt;
        let mut changed = false;
        let q = &self.state.joint_positions;
        let qd = &self.state.joint_velocities;
        for (j, a) in self.actuators.iter().enumerate() {
            if self.saturated[j] {
                continue;
            }
            let v_end = qd[j] + dt * self.acceleration[6 + j];
            let mut t = input.joint_torques[j];
            if a.mode == ActuationMode::Position {
                t += a.kp * (input.joint_positions[j] - q[j] - dt * v_end);
            }
            if a.mode != ActuationMode::Torque {
                t += a.kd * (input.joint_velocities[j] - v_end);
            }
            if t.abs() > a.limit {
                self.saturated[j] = true;
                self.motor_torques[j] = a.limit.copysign(t);
                changed = true;
            } else {
                self.motor_torques[j] = t;
            }
        }
        let n = self.ground.normal;
        for s in &mut self.surfaces {
            s.acceleration = Vector6::zeros();
            for &c in &s.columns {
                s.acceleration += s.jacobian.fixed_view::<6, 1>(0, c) * self.acceleration[c];
            }
        }
        for p in &mut self.points {
            if p.mode == ContactMode::Separated {
                p.force = Vector3::zeros();
                p.velocity_end = p.velocity;
                continue;
            }
            let s = &self.surfaces[p.surface];
            let acc = lin(&s.acceleration) + ang(&s.acceleration).cross(&p.arm);
            let v_end = p.velocity + acc * dt;
            let (k, d) = p.law.matrices(p.mode, &n);
            let f = p.force_start - k * v_end * dt - d * acc * dt;
            p.force = f;
            p.velocity_end = v_end;
            let fn_end = n.dot(&f);
            if fn_end < 0.0 {
                p.mode = ContactMode::Separated;
                p.force = Vector3::zeros();
                changed = true;
                continue;
            }
            let mu = p.law.friction;
            match p.mode {
                ContactMode::Sticking => {
                    let ft = self.ground.tangential(&f);
                    let ftn = ft.norm();
                    if ftn > mu * fn_end * (1.0 + 1e-12) && ftn > 0.0 {
                        p.mode = ContactMode::Sliding;
                        p.slide_direction = ft / ftn;
                        p.normal_force_estimate = fn_end;
                        changed = true;
                    }
                }
                ContactMode::Sliding => {
                    let vt = self.ground.tangential(&v_end);
                    if vt.dot(&p.slide_direction) > 1e-9 {
                        // Friction would push the point along its motion: the slip stopped within the step.
                        p.mode = ContactMode::Sticking;
                        p.anchor = Some(
                            self.ground.project(&p.position)
                                + p.slide_direction
                                    * (mu * p.normal_force_estimate / p.law.tangential_stiffness),
                        );
                        changed = true;
                    } else if (fn_end - p.normal_force_estimate).abs()
                        > 1e-6 * (1.0 + p.normal_force_estimate)
                    {
                        p.normal_force_estimate = fn_end;
                        changed = true;
                    }
                }
                ContactMode::Separated => {}
            }
        }
        changed
    }

    /// One explicit step: forces at the start of the step, ABA.
    fn solve_explicit(&mut self, input: &SimInput) -> Result<usize, SimError> {
        let q = &self.state.joint_positions;
        let qd = &self.state.joint_velocities;
        for (j, a) in self.actuators.iter().enumerate() {
            let mut t = input.joint_torques[j];
            if a.mode == ActuationMode::Position {
                t += a.kp * (input.joint_positions[j] - q[j]);
            }
            if a.mode != ActuationMode::Torque {
                t += a.kd * (input.joint_velocities[j] - qd[j]);
            }
            self.saturated[j] = t.abs() > a.limit;
            if self.saturated[j] {
                t = a.limit.copysign(t);
            }
            self.motor_torques[j] = t;
        }
        // Joint torques for ABA: motor minus passive damping (reuse `bias` as a scratch of length nv).
        let n = self.model.dof();
        for s in &mut self.surfaces {
            s.wrench = Vector6::zeros();
        }
        for p in &mut self.points {
            if p.penetration > 0.0 {
                if p.anchor.is_none() {
                    p.anchor = Some(self.ground.project(&p.position));
                }
                p.mode = ContactMode::Sticking;
            } else {
                p.mode = ContactMode::Separated;
                p.anchor = None;
            }
            let (f, mode) = explicit_point_force(p, &self.ground);
            p.force = f;
            p.mode = mode;
            p.velocity_end = p.velocity;
            if mode == ContactMode::Sliding {
                p.anchor = Some(
                    self.ground.project(&p.position)
                        + self.ground.tangential(&f) / p.law.tangential_stiffness,
                );
            }
            let s = &mut self.surfaces[p.surface];
            s.wrench += join(&f, &p.arm.cross(&f));
        }
        for s in &self.surfaces {
            if s.wrench != Vector6::zeros() {
                self.wrenches.push(ExternalWrench {
                    frame: s.frame,
                    wrench: s.wrench,
                });
            }
        }
        for j in 0..n {
            self.joint_torque_buffer[j] = self.motor_torques[j] - self.actuators[j].damping * qd[j];
        }
        self.kd.forward_dynamics(
            &self.joint_torque_buffer,
            &self.wrenches,
            &mut self.acceleration,
        )?;
        Ok(1)
    }

    /// Fills the output from the committed state and the forces of the last step.
    fn update_output(
        &mut self,
        imu_acceleration: Option<Vector3<f64>>,
        solves: usize,
    ) -> Result<(), SimError> {
        let noise_cfg = self.config.sensors.noise.clone();
        let out = &mut self.output;
        out.time = Duration::from_nanos(self.time_ns);
        copy_state(&mut out.state, &self.state);
        out.solves = solves;
        for j in 0..self.state.joint_positions.len() {
            out.joint_positions[j] =
                self.state.joint_positions[j] + self.noise.sample(noise_cfg.joint_position);
            out.joint_velocities[j] =
                self.state.joint_velocities[j] + self.noise.sample(noise_cfg.joint_velocity);
            out.joint_torques[j] = self.motor_torques[j];
            out.saturated[j] = self.saturated[j];
        }
        let n = self.ground.normal;
        let mut total = Vector6::zeros();
        for (si, s) in self.surfaces.iter().enumerate() {
            let o = s.pose.translation.vector;
            let o_ft = s.ft_pose.translation.vector;
            let mut w = Vector6::zeros();
            let mut w_ft = Vector6::zeros();
            let mut in_contact = false;
            for (pi, p) in self.points[s.first_point..s.first_point + s.point_count]
                .iter()
                .enumerate()
            {
                let f = p.force;
                if f != Vector3::zeros() {
                    in_contact = true;
                }
                w += join(&f, &(p.position - o).cross(&f));
                w_ft += join(&f, &(p.position - o_ft).cross(&f));
                total += join(&f, &p.position.cross(&f));
                let cp = &mut out.contact_points[s.first_point + pi];
                cp.position = p.position;
                cp.force = f;
                cp.penetration = p.penetration;
                cp.mode = p.mode;
            }
            let r_ft = s.ft_pose.rotation;
            let f_s =
                r_ft.inverse_transform_vector(&lin(&w_ft)) + self.noise.sample3(noise_cfg.force);
            let t_s =
                r_ft.inverse_transform_vector(&ang(&w_ft)) + self.noise.sample3(noise_cfg.torque);
            let m = &mut out.surfaces[si];
            m.in_contact = in_contact;
            m.wrench = w;
            m.sensor_wrench = join(&f_s, &t_s);
            let fz = n.dot(&lin(&w));
            m.normal_force = fz.max(0.0);
            let o_ground = self.ground.project(&o);
            m.center_of_pressure = if fz > 1e-9 {
                // Torque about the projected origin, then the point of the plane where it has no tangential part.
                let t = ang(&w) + (o - o_ground).cross(&lin(&w));
                o_ground + n.cross(&t) / fz
            } else {
                o_ground
            };
        }
        out.total_contact_wrench = total;

        // IMU.
        let pose = self.kd.frame_pose(self.imu_frame);
        let vel = self.kd.frame_velocity(self.imu_frame);
        let acc_world = imu_acceleration.unwrap_or_else(Vector3::zeros);
        let rot = pose.rotation;
        let orientation_noise = self.noise.sample3(noise_cfg.orientation);
        out.imu.orientation = rot * UnitQuaternion::from_scaled_axis(orientation_noise);
        out.imu.angular_velocity =
            rot.inverse_transform_vector(&ang(&vel)) + self.noise.sample3(noise_cfg.gyroscope);
        out.imu.proper_acceleration = rot.inverse_transform_vector(&(acc_world - self.gravity))
            + self.noise.sample3(noise_cfg.accelerometer);

        // Fall detection.
        let base = &self.state.base_pose;
        let height = self.ground.height_of(&base.translation.vector);
        let z_axis = base.rotation * Vector3::z();
        let tilt = z_axis.dot(&n).clamp(-1.0, 1.0).acos();
        if self.fall_time_ns.is_none()
            && (height < self.config.fall.min_base_height || tilt > self.config.fall.max_tilt)
        {
            self.fall_time_ns = Some(self.time_ns);
        }
        out.fallen = self.fall_time_ns.is_some();
        out.fall_time = self.fall_time_ns.map(Duration::from_nanos);
        Ok(())
    }

    /// Checks the new state; names the first offending joint, base component or contact point.
    fn check_divergence(&self) -> Result<(), SimError> {
        let time = self.time_ns as f64 * 1e-9;
        let s = &self.next_state;
        let limits = &self.config.safety;
        for (i, v) in s.base_velocity.iter().enumerate() {
            if !v.is_finite() || v.abs() > limits.max_base_velocity {
                const NAMES: [&str; 6] = ["vx", "vy", "vz", "wx", "wy", "wz"];
                return Err(SimError::Diverged {
                    time,
                    what: "base velocity",
                    name: NAMES[i].to_string(),
                    value: *v,
                    bound: limits.max_base_velocity,
                });
            }
        }
        for (j, v) in s.joint_velocities.iter().enumerate() {
            if !v.is_finite() || v.abs() > limits.max_joint_velocity {
                return Err(SimError::Diverged {
                    time,
                    what: "joint velocity",
                    name: self.model.joints()[j].name.clone(),
                    value: *v,
                    bound: limits.max_joint_velocity,
                });
            }
        }
        for (j, v) in s.joint_positions.iter().enumerate() {
            if !v.is_finite() {
                return Err(SimError::Diverged {
                    time,
                    what: "joint position",
                    name: self.model.joints()[j].name.clone(),
                    value: *v,
                    bound: f64::NAN,
                });
            }
        }
        let pose_ok = s.base_pose.translation.vector.iter().all(|x| x.is_finite())
            && s.base_pose.rotation.coords.iter().all(|x| x.is_finite());
        if !pose_ok {
            return Err(SimError::Diverged {
                time,
                what: "base pose",
                name: "base".into(),
                value: f64::NAN,
                bound: f64::NAN,
            });
        }
        for (i, p) in self.points.iter().enumerate() {
            if p.penetration.is_nan()
                || p.penetration > limits.max_penetration
                || !p.force.iter().all(|x| x.is_finite())
            {
                let s = &self.surfaces[p.surface];
                let name = format!(
                    "{}[{}]",
                    self.config.contact.surfaces[p.surface].name,
                    i - s.first_point
                );
                return Err(SimError::Diverged {
                    time,
                    what: "contact penetration",
                    name,
                    value: p.penetration,
                    bound: limits.max_penetration,
                });
            }
        }
        Ok(())
    }

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
        let solves = match self.config.integrator {
            IntegratorKind::Implicit => self.solve_implicit(input),
            IntegratorKind::Explicit => self.solve_explicit(input),
        };
        let solves = match solves {
            Ok(s) => s,
            Err(e) => {
                self.restore_after_failure();
                return Err(e);
            }
        };
        // New velocities and configuration.
        let dt = self.dt;
        copy_state(&mut self.next_state, &self.state);
        for i in 0..6 {
            self.next_state.base_velocity[i] += dt * self.acceleration[i];
        }
        for j in 0..self.model.dof() {
            self.next_state.joint_velocities[j] += dt * self.acceleration[6 + j];
        }
        let momentum_target = momentum_start.map(|(h, c)| h + dt * self.external_wrench_about(&c));
        let integrated = self
            .next_state
            .integrate(&self.model, VelocityRepresentation::Mixed, dt);
        if let Err(e) = integrated
            .map_err(SimError::from)
            .and_then(|_| match momentum_target {
                Some(h) => self.project_momentum(&h),
                None => Ok(()),
            })
            .and_then(|_| self.check_divergence())
        {
            self.restore_after_failure();
            return Err(e);
        }
        // Commit: anchors of sliding points follow the slip.
        for p in &mut self.points {
            match p.mode {
                ContactMode::Separated => p.anchor = None,
                ContactMode::Sticking => {}
                ContactMode::Sliding => {
                    let end = p.position + p.velocity_end * dt;
                    p.anchor = Some(
                        self.ground.project(&end)
                            + self.ground.tangential(&p.force) / p.law.tangential_stiffness,
                    );
                }
            }
        }
        std::mem::swap(&mut self.state, &mut self.next_state);
        self.time_ns += self.period_ns;
        // Forces were computed at the start-of-step geometry; outputs use the end-of-step geometry.
        let forces_and_modes: usize = solves;
        self.update_kinematics()?;
        let imu_velocity = lin(&self.kd.frame_velocity(self.imu_frame));
        let imu_acceleration = (imu_velocity - self.imu_velocity) / dt;
        self.imu_velocity = imu_velocity;
        self.update_output(Some(imu_acceleration), forces_and_modes)
    }

    /// Total external wrench of the step (gravity, contact forces, active pushes) about the point `c`, world
    /// orientation, with the geometry at the start of the step (the dynamics workspace must still hold it).
    fn external_wrench_about(&self, c: &Vector3<f64>) -> Vector6<f64> {
        let mut force = self.gravity * self.model.total_mass();
        let mut torque = Vector3::zeros();
        for p in &self.points {
            force += p.force;
            torque += (p.position - c).cross(&p.force);
        }
        let t = self.time_ns;
        for p in &self.pushes {
            if t >= p.start_ns && t < p.end_ns {
                let f = lin(&p.wrench);
                let o = self.kd.frame_pose(p.frame).translation.vector;
                force += f;
                torque += ang(&p.wrench) + (o - c).cross(&f);
            }
        }
        join(&force, &torque)
    }

    /// Sets the base velocity of `next_state` so that its centroidal momentum equals `target` (the joint
    /// velocities are kept). Leaves the dynamics workspace at `next_state`.
    fn project_momentum(&mut self, target: &Vector6<f64>) -> Result<(), SimError> {
        self.kd.set_state(&self.next_state)?;
        self.kd
            .centroidal_momentum_matrix(&mut self.momentum_matrix)?;
        let mut rhs = *target;
        for (j, v) in self.next_state.joint_velocities.iter().enumerate() {
            rhs -= self.momentum_matrix.fixed_view::<6, 1>(0, 6 + j) * *v;
        }
        let base: Matrix6<f64> = self.momentum_matrix.fixed_view::<6, 6>(0, 0).into_owned();
        if let Some(v) = base.lu().solve(&rhs) {
            if v.iter().all(|x| x.is_finite()) {
                self.next_state.base_velocity = v;
            }
        }
        Ok(())
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

/// `dst = src` without allocating (the derived `clone_from` of `RobotState` reallocates its vectors).
fn copy_state(dst: &mut RobotState, src: &RobotState) {
    dst.base_pose = src.base_pose;
    dst.base_velocity = src.base_velocity;
    dst.joint_positions.copy_from(&src.joint_positions);
    dst.joint_velocities.copy_from(&src.joint_velocities);
}

fn add_point_matrix(m6: &mut Matrix6<f64>, k: &Matrix3<f64>, r: &Matrix3<f64>) {
    let kr = k * r;
    let rk = r * k;
    let rkr = r * kr;
    for i in 0..3 {
        for j in 0..3 {
            m6[(i, j)] += k[(i, j)];
            m6[(i, j + 3)] -= kr[(i, j)];
            m6[(i + 3, j)] += rk[(i, j)];
            m6[(i + 3, j + 3)] -= rkr[(i, j)];
        }
    }
}

/// Explicit force of a point from its state (anchor, penetration, velocity), clamped to never pull and
/// projected on the friction cone.
fn explicit_point_force(p: &Point, ground: &GroundPlane) -> (Vector3<f64>, ContactMode) {
    if p.penetration <= 0.0 {
        return (Vector3::zeros(), ContactMode::Separated);
    }
    let n = ground.normal;
    let fn_ = p.law.normal_stiffness * p.penetration - p.law.normal_damping * n.dot(&p.velocity);
    if fn_ <= 0.0 {
        return (Vector3::zeros(), ContactMode::Separated);
    }
    let anchor = p.anchor.unwrap_or_else(|| ground.project(&p.position));
    let ft = -ground.tangential(&(p.position - anchor)) * p.law.tangential_stiffness
        - ground.tangential(&p.velocity) * p.law.tangential_damping;
    let ftn = ft.norm();
    let limit = p.law.friction * fn_;
    if ftn > limit {
        (n * fn_ + ft * (limit / ftn), ContactMode::Sliding)
    } else {
        (n * fn_ + ft, ContactMode::Sticking)
    }
}

fn resolve_actuator(c: &JointActuatorConfig, model_limit: f64) -> Actuator {
    let model_limit = if model_limit.is_finite() && model_limit > 0.0 {
        model_limit
    } else {
        f64::INFINITY
    };
    Actuator {
        mode: c.mode,
        kp: c.kp,
        kd: c.kd,
        limit: c.effort_limit.unwrap_or(model_limit),
        damping: c.damping,
        armature: c.armature,
    }
}

fn make_push(model: &Model, p: &PushConfig, parameter: &str) -> Result<Push, SimError> {
    let frame = model
        .frame_id(&p.frame)
        .ok_or_else(|| SimError::UnknownFrame {
            parameter: parameter.to_string(),
            frame: p.frame.clone(),
            model: model.name().to_string(),
        })?;
    let start_ns = secs_to_ns(p.start);
    Ok(Push {
        frame,
        start_ns,
        end_ns: start_ns + secs_to_ns(p.duration),
        wrench: Vector6::from_row_slice(&p.wrench),
    })
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
