//! `[joint_trajectory]`: a scenario that plays joint sinusoids on the position servos instead of the
//! whole-body layer's command, e.g. to swing the legs of a robot held on a pole (`sim.fixed_base`) through
//! the rotations an in-situ force/torque calibration needs (`configs/identify_ft_legs.toml`,
//! docs/identification.md). The other layers still run and are logged; only the command sent to the robot
//! changes.

use std::collections::BTreeMap;

use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use stride_model::Model;

use crate::config::{ConfigError, ControlMode, Scenario};
use crate::robot::JointCommand;

/// `[joint_trajectory]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct JointTrajectorySection {
    /// Replace the whole-body command by the sinusoids (position control only).
    pub enabled: bool,
    /// Time over which the amplitudes grow from 0 to their value \[s\].
    pub ramp: f64,
    /// Joint name → its sinusoid; joints not listed hold their initial position.
    pub joints: BTreeMap<String, JointSinusoid>,
}

/// One joint of [`JointTrajectorySection::joints`]: `q(t) = q₀ + r(t) A sin(2π t / T + φ)`, `r` the ramp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSinusoid {
    /// Amplitude `A` \[rad or m\].
    pub amplitude: f64,
    /// Period `T` \[s\], > 0.
    pub period: f64,
    /// Phase `φ` \[deg\].
    #[serde(default)]
    pub phase_deg: f64,
}

/// The resolved trajectory: model joint indices, initial positions and joint limits.
#[derive(Debug, Clone)]
pub struct JointTrajectory {
    q0: DVector<f64>,
    ramp: f64,
    /// `(joint index, sinusoid)`.
    joints: Vec<(usize, JointSinusoid)>,
    limits: Vec<(f64, f64)>,
}

impl JointTrajectory {
    /// The scenario's trajectory (`None` when disabled), starting from `q0`. Unknown joints, non-positive
    /// periods, non-finite values and torque control are configuration errors.
    pub fn from_scenario(
        scenario: &Scenario,
        model: &Model,
        q0: &DVector<f64>,
    ) -> Result<Option<Self>, ConfigError> {
        let c = &scenario.config.joint_trajectory;
        if !c.enabled {
            return Ok(None);
        }
        if scenario.config.scenario.control_mode != ControlMode::Position {
            return Err(scenario.invalid(
                "joint_trajectory.enabled",
                "the joint trajectory drives the position servos: needs scenario.control_mode = \"position\"".to_string(),
            ));
        }
        if !(c.ramp.is_finite() && c.ramp >= 0.0) {
            return Err(scenario.invalid(
                "joint_trajectory.ramp",
                format!("{}: expected ≥ 0 [s]", c.ramp),
            ));
        }
        let mut joints = Vec::new();
        for (name, s) in &c.joints {
            let key = format!("joint_trajectory.joints.{name}");
            let j = model.joint_index(name).ok_or_else(|| {
                scenario.invalid(&key, format!("the model has no joint `{name}`"))
            })?;
            let ok = s.amplitude.is_finite()
                && s.phase_deg.is_finite()
                && s.period.is_finite()
                && s.period > 0.0;
            if !ok {
                return Err(scenario.invalid(
                    &key,
                    "expected a finite amplitude [rad or m] and phase_deg [deg], and a period > 0 [s]".to_string(),
                ));
            }
            joints.push((j, *s));
        }
        let limits = model.joints().iter().map(|j| (j.lower, j.upper)).collect();
        Ok(Some(Self {
            q0: q0.clone(),
            ramp: c.ramp,
            joints,
            limits,
        }))
    }

    /// Writes the command at time `t` \[s\] into `command`: every joint at `q₀` plus its sinusoid (clamped
    /// to the joint limits), the velocity feed-forward the sinusoid's derivative, no torque.
    pub fn command(&self, t: f64, command: &mut JointCommand) {
        command.mode = ControlMode::Position;
        command.joint_positions.copy_from(&self.q0);
        command.joint_velocities.fill(0.0);
        command.joint_torques.fill(0.0);
        let (r, r_dot) = if self.ramp > 0.0 && t < self.ramp {
            (t / self.ramp, 1.0 / self.ramp)
        } else {
            (1.0, 0.0)
        };
        for (j, s) in &self.joints {
            let w = std::f64::consts::TAU / s.period;
            let arg = w * t + s.phase_deg.to_radians();
            let (lo, hi) = self.limits[*j];
            let q = self.q0[*j] + r * s.amplitude * arg.sin();
            command.joint_positions[*j] = q.clamp(lo, hi);
            command.joint_velocities[*j] = if q > lo && q < hi {
                s.amplitude * (r_dot * arg.sin() + r * w * arg.cos())
            } else {
                0.0
            };
        }
    }
}
