//! [`MujocoRobot`]: the MuJoCo plant — construction, the initial state, one step.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use mujoco_rs::prelude::*;
use nalgebra::{DVector, UnitQuaternion, Vector3, Vector6};
use stride_model::{ExternalWrench, FrameId, KinDyn, Model, RobotState, VelocityRepresentation};
use stride_sim::{EffortLimitPolicy, ImuMeasurement, SensorModels, SimConfig, SimInput};

use crate::actuators::{resolve, Servo};
use crate::config::MujocoConfig;
use crate::inertia::write_model_inertias;
use crate::limits::Limits;
use crate::scene::{build, SceneSpec};
use crate::MujocoError;

/// MuJoCo's warning kinds (`mjtWarning`, in order): any of them during a step rejects the step.
const WARNINGS: [&str; 7] = [
    "inertia (a body with invalid inertia)",
    "contact buffer full",
    "constraint buffer full",
    "bad qpos (NaN or huge, MuJoCo reset the state)",
    "bad qvel (NaN or huge, MuJoCo reset the state)",
    "bad qacc (NaN or huge, MuJoCo reset the state)",
    "bad ctrl (NaN or huge control)",
];

/// What [`MujocoRobot::new`] needs besides stride's model.
pub struct PlantSetup<'a> {
    /// The URDF MuJoCo compiles (the plant's; its joints must be the stride model's).
    pub urdf: &'a Path,
    /// The scenario's `[sim]` section: actuation, sensors, pushes, ground, fall detection and the friction
    /// coefficient (`contact.friction_coefficient`; the rest of `contact` is stride-sim's).
    pub sim: &'a SimConfig,
    /// MuJoCo's contact and solver parameters.
    pub mujoco: &'a MujocoConfig,
    /// Left and right sole frames: their bodies' collision geometry touches the ground, and the ground
    /// wrench is reported about their origins.
    pub soles: [&'a str; 2],
    /// Plant period, the MuJoCo timestep.
    pub period: Duration,
    /// Write stride's body inertias (mass, centre of mass, rotational inertia) over MuJoCo's own, compiled
    /// from the URDF: how the plant model's `[sim.model]` edits reach MuJoCo. `false` keeps MuJoCo's.
    pub inertias_from_model: bool,
}

/// What the plant reports after a step (or after its state was set).
#[derive(Clone, Debug)]
pub struct MujocoOutput {
    /// Simulated time.
    pub time: Duration,
    /// True state (mixed velocities).
    pub state: RobotState,
    /// Encoders (stride-sim's model: quantised, differenced and filtered, delayed) \[rad, rad/s\].
    pub joint_positions: DVector<f64>,
    /// Encoder velocities \[rad/s\].
    pub joint_velocities: DVector<f64>,
    /// IMU (stride-sim's model, delayed).
    pub imu: ImuMeasurement,
    /// Six-axis force/torque sensors in `Model::ft_sensors()` order, as measured \[N, N·m\].
    pub ft_wrenches: Vec<Vector6<f64>>,
    /// The same, noise-free and undelayed.
    pub ft_wrenches_truth: Vec<Vector6<f64>>,
    /// Actuator torques applied on the joints during the step \[N·m\].
    pub joint_torques: DVector<f64>,
    /// Per joint: the actuator torque sat at its effort limit.
    pub saturated: Vec<bool>,
    /// Left and right sole: the ground wrench on the foot `[f; τ]`, world orientation, torque about the
    /// sole frame origin \[N, N·m\] (the contacts of the step).
    pub sole_wrenches: [Vector6<f64>; 2],
    /// Left and right sole carry a positive normal force.
    pub sole_contact: [bool; 2],
    /// Fall latched (`[sim.fall]`: base height or tilt).
    pub fallen: bool,
}

/// A push resolved against both models.
struct Push {
    frame: FrameId,
    body: usize,
    start_ns: u64,
    end_ns: u64,
    wrench: Vector6<f64>,
}

/// MuJoCo as the plant: see the crate documentation. A failed step restores the state of before it.
pub struct MujocoRobot {
    model: Arc<Model>,
    pub(crate) kd: KinDyn,
    pub(crate) data: MjData<Box<MjModel>>,
    pub(crate) joint_qpos: Vec<usize>,
    pub(crate) joint_dof: Vec<usize>,
    pub(crate) body: Vec<usize>,
    pub(crate) geom_contact: Vec<Option<usize>>,
    pub(crate) servos: Vec<Servo>,
    pub(crate) limits: Limits,
    pub(crate) servo_saturation: crate::ServoSaturation,
    policy: EffortLimitPolicy,
    pub(crate) soles: [FrameId; 2],
    pub(crate) imu_frame: FrameId,
    pub(crate) sensors: SensorModels,
    pushes: Vec<Push>,
    commands: Vec<SimInput>,
    head: usize,
    pub(crate) period_ns: u64,
    pub(crate) time_ns: u64,
    pub(crate) fall: stride_sim::FallConfig,
    pub(crate) ground: stride_sim::GroundPlane,
    pub(crate) output: MujocoOutput,
    pub(crate) scratch: Scratch,
    /// `sim.fixed_base`: the root is a mocap body held at the initial base pose, no free joint.
    fixed_base: bool,
}

/// Buffers of one step, allocated at construction.
pub(crate) struct Scratch {
    pub(crate) previous: RobotState,
    pub(crate) nu_dot: DVector<f64>,
    pub(crate) external: Vec<ExternalWrench>,
    pub(crate) imu_velocity: Vector3<f64>,
    /// The start-of-step state (`save`).
    pub(crate) qpos: Vec<f64>,
    pub(crate) qvel: Vec<f64>,
    act: Vec<f64>,
    qacc_warmstart: Vec<f64>,
    warnings: [i32; 7],
}

impl MujocoRobot {
    /// Builds the MuJoCo model and the plant (all allocation happens here). The state is the zero state
    /// until [`MujocoRobot::set_initial_state`].
    pub fn new(model: Arc<Model>, setup: &PlantSetup<'_>) -> Result<Self, MujocoError> {
        setup.sim.validate()?;
        let dt = setup.period.as_secs_f64();
        if setup.period.is_zero() {
            return Err(MujocoError::InvalidConfig {
                parameter: "period".into(),
                value: format!("{:?}", setup.period),
                reason: "expected a positive period".into(),
            });
        }
        setup.mujoco.validate(dt)?;
        let servos = resolve(&model, &setup.sim.actuation)?;
        // No contact surface (a robot on a pole): no collision geometry at all, as on stride-sim.
        let contact_frames: Vec<String> = if setup.sim.contact.surfaces.is_empty() {
            Vec::new()
        } else {
            setup.soles.map(String::from).to_vec()
        };
        let mut scene = build(
            &model,
            &SceneSpec {
                urdf: setup.urdf,
                servos: &servos,
                ground: &setup.sim.ground,
                friction: setup.sim.contact.friction_coefficient,
                config: setup.mujoco,
                contact_frames: &contact_frames,
                timestep: dt,
                fixed_base: setup.sim.fixed_base,
            },
        )?;
        let frame = |name: &str| {
            model.frame_id(name).ok_or_else(|| {
                MujocoError::Mismatch(format!("stride's model has no frame `{name}`"))
            })
        };
        let soles = [frame(setup.soles[0])?, frame(setup.soles[1])?];
        let imu_frame =
            frame(&setup.sim.sensors.imu_frame).or_else(|_| frame(model.root_link()))?;
        let pushes = resolve_pushes(&model, &scene.body, setup.sim)?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let n = model.dof();
        let n_ft = model.ft_sensors().len();
        let zero = RobotState::zero(&model);
        if setup.inertias_from_model {
            write_model_inertias(&model, &scene.body, &mut scene.model);
        }
        let mut data = MjData::new(Box::new(scene.model));
        if setup.inertias_from_model {
            data.set_const();
        }
        let (nq, nv, na) = (data.qpos().len(), data.qvel().len(), data.act().len());
        let ground = stride_sim::GroundPlane::from_config(&setup.sim.ground);
        Ok(Self {
            sensors: SensorModels::new(&model, &setup.sim.sensors, dt),
            commands: vec![SimInput::zeros(n); setup.sim.actuation.command_delay_steps + 1],
            head: 0,
            output: MujocoOutput {
                time: Duration::ZERO,
                state: zero.clone(),
                joint_positions: DVector::zeros(n),
                joint_velocities: DVector::zeros(n),
                imu: ImuMeasurement {
                    orientation: UnitQuaternion::identity(),
                    angular_velocity: Vector3::zeros(),
                    proper_acceleration: Vector3::zeros(),
                },
                ft_wrenches: vec![Vector6::zeros(); n_ft],
                ft_wrenches_truth: vec![Vector6::zeros(); n_ft],
                joint_torques: DVector::zeros(n),
                saturated: vec![false; n],
                sole_wrenches: [Vector6::zeros(); 2],
                sole_contact: [false; 2],
                fallen: false,
            },
            scratch: Scratch {
                previous: zero,
                nu_dot: DVector::zeros(model.nv()),
                external: Vec::with_capacity(2 + pushes.len()),
                imu_velocity: Vector3::zeros(),
                qpos: vec![0.0; nq],
                qvel: vec![0.0; nv],
                act: vec![0.0; na],
                qacc_warmstart: vec![0.0; nv],
                warnings: [0; 7],
            },
            joint_qpos: scene.joint_qpos,
            joint_dof: scene.joint_dof,
            body: scene.body,
            geom_contact: scene.geom_contact,
            limits: Limits::new(n),
            servo_saturation: setup.mujoco.servo_saturation,
            servos,
            policy: setup.sim.actuation.effort_limit_policy,
            soles,
            imu_frame,
            pushes,
            period_ns: u64::try_from(setup.period.as_nanos()).unwrap_or(u64::MAX),
            time_ns: 0,
            fall: setup.sim.fall.clone(),
            ground,
            kd,
            data,
            model,
            fixed_base: setup.sim.fixed_base,
        })
    }
}

/// `input` into `slot` without allocating (`Clone::clone_from` of nalgebra's vectors reallocates).
fn copy_command(slot: &mut SimInput, input: &SimInput) {
    slot.joint_positions.copy_from(&input.joint_positions);
    slot.joint_velocities.copy_from(&input.joint_velocities);
    slot.joint_torques.copy_from(&input.joint_torques);
}

/// `[[sim.pushes]]` against stride's frames and MuJoCo's bodies.
fn resolve_pushes(
    model: &Model,
    body: &[usize],
    sim: &SimConfig,
) -> Result<Vec<Push>, MujocoError> {
    sim.pushes
        .iter()
        .map(|p| {
            let frame = model
                .frame_id(&p.frame)
                .ok_or_else(|| MujocoError::InvalidConfig {
                    parameter: "pushes.frame".into(),
                    value: p.frame.clone(),
                    reason: "the model has no such frame".into(),
                })?;
            let ns = |s: f64| (s * 1e9).round().max(0.0) as u64;
            Ok(Push {
                frame,
                body: body[model.frames()[frame.index()].link],
                start_ns: ns(p.start),
                end_ns: ns(p.start + p.duration),
                wrench: Vector6::from_row_slice(&p.wrench),
            })
        })
        .collect()
}

impl MujocoRobot {
    /// Sets the state (base velocity mixed) as the start of a run: time 0, sensors restarted from their
    /// seed, the command delay line holding the state's joint positions, no fall. The measurement is that
    /// of the robot at rest with no contact force (as stride-sim's first one).
    pub fn set_initial_state(&mut self, state: &RobotState) -> Result<(), MujocoError> {
        state.validate(&self.model)?;
        self.data.reset();
        let s = &mut self.scratch;
        if self.fixed_base {
            // held where it starts: the mocap root's pose, zero base velocity (stride-sim's `fixed_base`)
            crate::state::joints_to_mujoco(
                state,
                &self.joint_qpos,
                &self.joint_dof,
                &mut s.qpos,
                &mut s.qvel,
            );
            let p = state.base_pose.translation.vector;
            let r = state.base_pose.rotation;
            self.data.mocap_pos_mut()[0] = [p.x, p.y, p.z];
            self.data.mocap_quat_mut()[0] = [r.w, r.i, r.j, r.k];
        } else {
            crate::state::state_to_mujoco(
                state,
                &self.joint_qpos,
                &self.joint_dof,
                &mut s.qpos,
                &mut s.qvel,
            );
        }
        self.data.qpos_mut().copy_from_slice(&s.qpos);
        self.data.qvel_mut().copy_from_slice(&s.qvel);
        let hold = SimInput::hold(&state.joint_positions);
        for c in &mut self.commands {
            c.clone_from(&hold);
        }
        self.head = 0;
        self.apply_command_and_pushes(0);
        self.data.forward();
        self.time_ns = 0;
        self.sensors.reset();
        self.output.fallen = false;
        self.output.state.clone_from(state);
        if self.fixed_base {
            self.output.state.base_velocity.fill(0.0);
        }
        self.scratch.previous.clone_from(&self.output.state);
        self.kd.set_state(&self.output.state)?;
        self.scratch.imu_velocity = self.kd.frame_velocity(self.imu_frame).xyz();
        self.measure_at_rest()
    }

    /// One period with the command `input` (it reaches the motors `command_delay_steps` later).
    ///
    /// # Errors
    /// Sizes, non-finite commands, the `error` effort policy (checked before anything changes); a MuJoCo
    /// warning or a non-finite state during the step (the state of before the step is restored).
    pub fn step(&mut self, input: &SimInput) -> Result<&MujocoOutput, MujocoError> {
        self.check_command(input)?;
        let len = self.commands.len();
        copy_command(&mut self.commands[self.head], input);
        self.head = (self.head + 1) % len;
        // The ring holds `delay + 1` commands: the next slot to write is the oldest, written `delay` steps
        // ago (the one just written when there is no delay).
        self.apply_command_and_pushes(self.head);
        self.save();
        if let Err(e) = self.step_with_limits() {
            self.restore();
            // The slot just written held a command already applied: stepping the head back is enough.
            self.head = (self.head + len - 1) % len;
            return Err(e);
        }
        self.time_ns += self.period_ns;
        self.scratch.previous.copy_from(&self.output.state);
        let read = if self.fixed_base {
            crate::state::joints_from_mujoco
        } else {
            crate::state::state_from_mujoco
        };
        read(
            self.data.qpos(),
            self.data.qvel(),
            &self.joint_qpos,
            &self.joint_dof,
            &mut self.output.state,
        );
        self.measure()?;
        Ok(&self.output)
    }

    /// Sizes, finiteness and (with the `error` policy) feed-forward torques within the effort limits.
    fn check_command(&self, input: &SimInput) -> Result<(), MujocoError> {
        let n = self.model.dof();
        for (what, v) in [
            ("joint_positions", &input.joint_positions),
            ("joint_velocities", &input.joint_velocities),
            ("joint_torques", &input.joint_torques),
        ] {
            if v.len() != n {
                return Err(MujocoError::Dimension {
                    what,
                    expected: n,
                    got: v.len(),
                });
            }
            if let Some(j) = v.iter().position(|x| !x.is_finite()) {
                return Err(MujocoError::NonFiniteCommand {
                    what,
                    joint: self.model.joints()[j].name.clone(),
                });
            }
        }
        if self.policy == EffortLimitPolicy::Error {
            for (j, (s, &tau)) in self
                .servos
                .iter()
                .zip(input.joint_torques.iter())
                .enumerate()
            {
                if tau.abs() > s.limit {
                    return Err(MujocoError::EffortLimit {
                        joint: self.model.joints()[j].name.clone(),
                        torque: tau,
                        limit: s.limit,
                    });
                }
            }
        }
        Ok(())
    }

    /// Controls from the command in ring slot `slot`; `xfrc_applied` from the pushes active at the current
    /// time (a wrench about a frame origin becomes one about the body's centre of mass: `τ + (p − c) × f`).
    fn apply_command_and_pushes(&mut self, slot: usize) {
        let c = &self.commands[slot];
        let ctrl = self.data.ctrl_mut();
        for (j, s) in self.servos.iter().enumerate() {
            ctrl[j] = s.control(
                c.joint_positions[j],
                c.joint_velocities[j],
                c.joint_torques[j],
            );
        }
        for b in self.data.xfrc_applied_mut() {
            *b = [0.0; 6];
        }
        for p in &self.pushes {
            if self.time_ns < p.start_ns || self.time_ns >= p.end_ns {
                continue;
            }
            let origin = self.kd.frame_pose(p.frame).translation.vector;
            let com = Vector3::from(self.data.xipos()[p.body]);
            let f = p.wrench.fixed_rows::<3>(0).into_owned();
            let tau = p.wrench.fixed_rows::<3>(3) + (origin - com).cross(&f);
            let x = &mut self.data.xfrc_applied_mut()[p.body];
            for k in 0..3 {
                x[k] += f[k];
                x[3 + k] += tau[k];
            }
        }
    }

    /// The pushes active at `time_ns` as external wrenches on stride's frames (for the FT model).
    pub(crate) fn active_pushes(&self, time_ns: u64, out: &mut Vec<ExternalWrench>) {
        for p in &self.pushes {
            if time_ns >= p.start_ns && time_ns < p.end_ns {
                out.push(ExternalWrench {
                    frame: p.frame,
                    wrench: p.wrench,
                });
            }
        }
    }

    fn save(&mut self) {
        let s = &mut self.scratch;
        s.qpos.copy_from_slice(self.data.qpos());
        s.qvel.copy_from_slice(self.data.qvel());
        s.act.copy_from_slice(self.data.act());
        s.qacc_warmstart.copy_from_slice(self.data.qacc_warmstart());
        for (n, w) in s.warnings.iter_mut().zip(self.data.warning().iter()) {
            *n = w.number;
        }
    }

    fn restore(&mut self) {
        self.rewind();
        self.data.forward();
    }

    /// The state saved at the start of the step (`save`), MuJoCo's solver warm start included, without
    /// recomputing what depends on it (the next `mj_step` does).
    pub(crate) fn rewind(&mut self) {
        let s = &self.scratch;
        self.data.qpos_mut().copy_from_slice(&s.qpos);
        self.data.qvel_mut().copy_from_slice(&s.qvel);
        self.data.act_mut().copy_from_slice(&s.act);
        self.data
            .qacc_warmstart_mut()
            .copy_from_slice(&s.qacc_warmstart);
        self.data.set_time(self.time_ns as f64 * 1e-9);
    }

    /// A new MuJoCo warning or a non-finite state fails the step.
    pub(crate) fn check_step(&self) -> Result<(), MujocoError> {
        let time = self.time_ns as f64 * 1e-9;
        for (k, w) in self.data.warning().iter().enumerate().take(WARNINGS.len()) {
            if w.number > self.scratch.warnings[k] {
                return Err(MujocoError::Warning {
                    warning: WARNINGS[k].into(),
                    time,
                });
            }
        }
        if !self.data.qpos().iter().all(|x| x.is_finite()) {
            return Err(MujocoError::NonFiniteState { what: "qpos", time });
        }
        if !self.data.qvel().iter().all(|x| x.is_finite()) {
            return Err(MujocoError::NonFiniteState { what: "qvel", time });
        }
        Ok(())
    }

    /// The deepest penetration of the robot's collision geometry into the floor \[m\] (0 when none), from
    /// MuJoCo's contacts at the current state (`-dist`). The official iCub standing with its sole frames on
    /// the floor: 10.5 mm (its sole boxes' bottom faces lie that far below the frames).
    pub fn ground_penetration(&self) -> f64 {
        self.data
            .contact()
            .iter()
            .map(|c| -c.dist)
            .fold(0.0, f64::max)
    }

    /// The latest output.
    pub fn output(&self) -> &MujocoOutput {
        &self.output
    }

    /// The true state (mixed velocities).
    pub fn state(&self) -> &RobotState {
        &self.output.state
    }

    /// stride's model of the plant.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The MuJoCo model.
    pub fn mj_model(&self) -> &MjModel {
        self.data.model()
    }

    /// The MuJoCo data (positions of bodies, contacts, ...), as of the last step.
    pub fn mj_data(&self) -> &MjData<Box<MjModel>> {
        &self.data
    }

    /// MuJoCo body of each stride body (`Model::bodies` order).
    pub fn body_ids(&self) -> &[usize] {
        &self.body
    }

    /// `qpos` address of each stride joint.
    pub fn joint_qpos_addresses(&self) -> &[usize] {
        &self.joint_qpos
    }

    /// The resolved servo of each joint.
    pub fn servos(&self) -> &[Servo] {
        &self.servos
    }

    /// Plant period \[ns\].
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }
}
