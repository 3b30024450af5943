//! [`Robot`] implementation on stride-sim.
use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DVector, Vector6};
use stride_estimation::{EstimatorInput, ImuReading};
use stride_model::{FrameId, KinDyn, Model};
use stride_sim::{ActuationMode, ImuMeasurement, SimConfig, SimInput, SimRobot};

use crate::config::ControlMode;
use crate::robot::{JointCommand, Measurement, Robot, RobotError};

/// The simulated robot behind the [`Robot`] trait. The sensors are the simulator's: encoders, IMU and the
/// six-axis force/torque sensors of the model (offsets, noise, delays as configured in `[sim.sensors]`);
/// the truth is its state, actuator torques and the contact wrenches of the two sole surfaces (world
/// orientation, about the sole frame origins).
pub struct SimPlant {
    sim: SimRobot,
    model: Arc<Model>,
    period_ns: u64,
    surfaces: [Option<usize>; 2],
    input: SimInput,
    meas: Measurement,
}

impl SimPlant {
    /// Builds the simulator with `config`, stepping by `period`, places the robot standing on the ground at
    /// `joint_positions`, and sets every joint's actuation to `mode`.
    pub fn new(
        model: Arc<Model>,
        mut config: SimConfig,
        period: Duration,
        mode: ControlMode,
        joint_positions: &DVector<f64>,
        soles: [FrameId; 2],
    ) -> Result<Self, RobotError> {
        let period_ns = u64::try_from(period.as_nanos()).unwrap_or(u64::MAX);
        if mode == ControlMode::Torque {
            config.actuation.default.mode = ActuationMode::Torque;
            for j in &mut config.actuation.joints {
                j.mode = Some(ActuationMode::Torque);
            }
        }
        let mut sim = SimRobot::new(Arc::clone(&model), config, period)?;
        let mut state = sim.set_standing_on_ground(joint_positions)?;
        // Start heading along +x, the heading being the soles' mean yaw (sole frames have x forward by
        // convention, whereas base links differ: iCub's `root_link` points x backward). A rotation about the
        // vertical keeps every contact point's height, so the simulator's placement on the ground holds.
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&state)?;
        let heading =
            crate::stack::soles_heading(&kd.frame_pose(soles[0]), &kd.frame_pose(soles[1]));
        if heading.abs() > 1e-12 {
            let turn = nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, -heading);
            state.base_pose =
                nalgebra::Isometry3::from_parts(nalgebra::Translation3::identity(), turn)
                    * state.base_pose;
            kd.set_state(&state)?;
        }
        // Start with the soles' mid-point above the world origin (as the ideal plant and `stride plan` do),
        // so goals are distances from the start.
        let mid = (kd.frame_pose(soles[0]).translation.vector
            + kd.frame_pose(soles[1]).translation.vector)
            * 0.5;
        state.base_pose.translation.x -= mid.x;
        state.base_pose.translation.y -= mid.y;
        sim.set_initial_state(&state)?;
        let mut surfaces = [None, None];
        for (i, s) in sim.config().contact.surfaces.iter().enumerate() {
            for (k, sole) in soles.iter().enumerate() {
                if s.frame == model.frame_name(*sole) {
                    surfaces[k] = Some(i);
                }
            }
        }
        let mut plant = Self {
            period_ns,

            surfaces,
            input: SimInput::hold(joint_positions),
            meas: Measurement::new(&model),
            sim,
            model,
        };
        plant.meas.truth.state = state;
        plant.read_output()?;
        Ok(plant)
    }

    /// The simulator (for its configuration and contact details).
    pub fn sim(&self) -> &SimRobot {
        &self.sim
    }

    fn read_output(&mut self) -> Result<(), RobotError> {
        let out = self.sim.output();
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
        for k in 0..2 {
            let surface = self.surfaces[k].and_then(|i| out.surfaces.get(i));
            truth.feet_in_contact[k] = surface.is_some_and(|s| s.in_contact);
            truth.foot_wrenches[k] = surface.map_or(nalgebra::Vector6::zeros(), |s| s.wrench);
        }
        Ok(())
    }
}

impl Robot for SimPlant {
    fn name(&self) -> &str {
        "simulator"
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
        load_command(command, self.model.dof(), &mut self.input)
    }
    fn advance(&mut self) -> Result<(), RobotError> {
        self.sim.step(&self.input)?;
        self.read_output()
    }
    fn kinematics(&self) -> Option<&KinDyn> {
        Some(self.sim.kinematics())
    }
}

/// Copies a joint command sized for `dof` joints into a simulator input (positions, velocities, torques);
/// a command sized for another robot is an error that changes nothing. Shared by the simulated plants.
pub(crate) fn load_command(
    command: &JointCommand,
    dof: usize,
    input: &mut SimInput,
) -> Result<(), RobotError> {
    for got in [
        command.joint_positions.len(),
        command.joint_velocities.len(),
        command.joint_torques.len(),
    ] {
        if got != dof {
            return Err(RobotError::CommandSize { expected: dof, got });
        }
    }
    input.joint_positions.copy_from(&command.joint_positions);
    input.joint_velocities.copy_from(&command.joint_velocities);
    input.joint_torques.copy_from(&command.joint_torques);
    Ok(())
}

/// What a simulated plant senses at the end of a step (the sensor part of its output).
pub(crate) struct SensedOutput<'a> {
    /// Plant time.
    pub(crate) time: Duration,
    /// Encoder positions \[rad\].
    pub(crate) joint_positions: &'a DVector<f64>,
    /// Encoder velocities \[rad/s\].
    pub(crate) joint_velocities: &'a DVector<f64>,
    /// The IMU's reading.
    pub(crate) imu: &'a ImuMeasurement,
    /// The FT sensors' readings, in model order.
    pub(crate) ft_wrenches: &'a [Vector6<f64>],
}

/// Copies a simulated plant's sensor readings into the estimation layer's input; returns the time \[ns\].
/// Shared by the simulated plants.
pub(crate) fn load_sensors(sensors: &mut EstimatorInput, out: SensedOutput<'_>) -> u64 {
    let time_ns = u64::try_from(out.time.as_nanos()).unwrap_or(u64::MAX);
    sensors.time_ns = time_ns;
    sensors.joint_positions.copy_from(out.joint_positions);
    sensors.joint_velocities.copy_from(out.joint_velocities);
    sensors.imu = ImuReading {
        orientation: out.imu.orientation,
        angular_velocity: out.imu.angular_velocity,
        proper_acceleration: out.imu.proper_acceleration,
    };
    for (reading, wrench) in sensors.ft_wrenches.iter_mut().zip(out.ft_wrenches) {
        *reading = *wrench;
    }
    time_ns
}
