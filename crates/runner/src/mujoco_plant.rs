//! [`Robot`] implementation on MuJoCo (`stride-mujoco`, cargo feature `mujoco`).
//!
//! The scenario's `[sim]` section configures it as it configures stride-sim: actuation (`kp`, `kd`, effort
//! limits, friction, delays, torque lag), sensors (`[sim.sensors]`: the same models), pushes, ground
//! height, fall detection, the friction coefficient. The contact model is MuJoCo's own, on the URDF's
//! collision geometry of the soles, with the `[mujoco]` section's parameters (`stride_mujoco::MujocoConfig`
//! documents them). `[sim.model]`'s inertia edits reach MuJoCo as the plant model's body inertias written
//! over the compiled ones.

use std::sync::Arc;

use nalgebra::{DVector, Vector3};
use stride_model::{FrameId, Model, RobotState};
use stride_mujoco::{MujocoRobot, PlantSetup};
use stride_sim::{ActuationMode, SimInput};

use crate::config::{ControlMode, Scenario};
use crate::robot::{JointCommand, Measurement, Robot, RobotError};
use crate::sim_plant::{load_command, load_sensors, SensedOutput};

/// MuJoCo behind the [`Robot`] trait: truth from MuJoCo's state and contacts, sensors from stride-sim's
/// models fed with MuJoCo's motion (see `stride_mujoco`).
pub struct MujocoPlant {
    robot: MujocoRobot,
    model: Arc<Model>,
    input: SimInput,
    meas: Measurement,
}

/// `[sim.model]` changes the inertias (a mass scale or link edits; another URDF alone does not).
pub fn has_inertia_edits(m: &stride_sim::PlantModelConfig) -> bool {
    m.mass_scale != 1.0 || !m.links.is_empty()
}

/// MuJoCo's default `solref` (time constant 20 ms, damping ratio 1), for a floor no geometry touches.
const NO_CONTACT_SOLREF: [f64; 2] = [0.02, 1.0];

/// The MuJoCo plant's contact and solver parameters of `scenario` for the robot `plant` (the plant model):
/// the `[mujoco]` section, its `solref` derived from `sim.contact` when not written
/// ([`crate::config::mujoco::ground_solref`], the soles' area from `sim.contact.surfaces`).
pub fn mujoco_config(scenario: &Scenario, plant: &Model) -> stride_mujoco::MujocoConfig {
    let contact = &scenario.config.sim.contact;
    let sole_area: f64 = contact.surfaces.iter().map(|s| s.length * s.width).sum();
    if sole_area <= 0.0 {
        // no contact surface (a robot on a pole): nothing touches the floor; MuJoCo's default contact
        return scenario.config.mujoco.plant_config(NO_CONTACT_SOLREF);
    }
    let ground = crate::config::mujoco::ground_solref(
        contact.normal_stiffness,
        contact.normal_damping,
        sole_area,
        plant.total_mass(),
        scenario.sim_period().as_secs_f64(),
    );
    scenario.config.mujoco.plant_config(ground)
}

impl MujocoPlant {
    /// Builds the MuJoCo model from `urdf` (the plant's), stepping at `scenario.sim_period()`, with every
    /// joint in `mode`, the plant model's inertias if `[sim.model]` edits them, and stands the robot at
    /// `joint_positions`: left sole level on the ground, the soles' mid-point above the world origin,
    /// heading along +x (as the other plants start), lifted until its collision geometry touches the floor.
    pub fn new(
        scenario: &Scenario,
        model: Arc<Model>,
        urdf: &std::path::Path,
        joint_positions: &DVector<f64>,
        soles: [FrameId; 2],
    ) -> Result<Self, RobotError> {
        let c = &scenario.config;
        let mut sim = c.sim.clone();
        if c.scenario.control_mode == ControlMode::Torque {
            sim.actuation.default.mode = ActuationMode::Torque;
            for j in &mut sim.actuation.joints {
                j.mode = Some(ActuationMode::Torque);
            }
        }
        let names = soles.map(|f| model.frame_name(f).to_string());
        let mut robot = MujocoRobot::new(
            Arc::clone(&model),
            &PlantSetup {
                urdf,
                sim: &sim,
                mujoco: &mujoco_config(scenario, &model),
                soles: [&names[0], &names[1]],
                period: scenario.sim_period(),
                inertias_from_model: has_inertia_edits(&c.sim.model),
            },
        )?;
        let mut state = RobotState::standing(&model, joint_positions, soles[0], soles[1])?;
        state.base_pose.translation.vector += Vector3::new(0.0, 0.0, sim.ground.height);
        robot.set_initial_state(&state)?;
        // The URDF's collision geometry need not end at the sole frames (iCub's sole boxes reach 10.5 mm
        // below them): lift the robot until it touches the floor instead of starting inside it.
        let depth = robot.ground_penetration();
        if depth > 0.0 {
            state.base_pose.translation.vector.z += depth;
            robot.set_initial_state(&state)?;
        }
        let mut plant = Self {
            robot,
            input: SimInput::hold(joint_positions),
            meas: Measurement::new(&model),
            model,
        };
        plant.read_output();
        Ok(plant)
    }

    /// The MuJoCo plant (its model, data and contact details).
    pub fn mujoco(&self) -> &MujocoRobot {
        &self.robot
    }

    fn read_output(&mut self) {
        let out = self.robot.output();
        let m = &mut self.meas;
        m.fallen = out.fallen;
        m.time_ns = load_sensors(
            &mut m.sensors,
            SensedOutput {
                time: out.time,
                joint_positions: &out.joint_positions,
                joint_velocities: &out.joint_velocities,
                imu: &out.imu,
                ft_wrenches: &out.ft_wrenches,
            },
        );
        let truth = &mut m.truth;
        truth.state.copy_from(&out.state);
        truth.joint_torques.copy_from(&out.joint_torques);
        truth.saturated.copy_from_slice(&out.saturated);
        truth.foot_wrenches = out.sole_wrenches;
        truth.feet_in_contact = out.sole_contact;
    }
}

impl Robot for MujocoPlant {
    fn name(&self) -> &str {
        "mujoco"
    }
    fn model(&self) -> &Arc<Model> {
        &self.model
    }
    fn period_ns(&self) -> u64 {
        self.robot.period_ns()
    }
    fn measurement(&self) -> &Measurement {
        &self.meas
    }
    fn command(&mut self, command: &JointCommand) -> Result<(), RobotError> {
        load_command(command, self.model.dof(), &mut self.input)
    }
    fn advance(&mut self) -> Result<(), RobotError> {
        self.robot.step(&self.input)?;
        self.read_output();
        Ok(())
    }
}
