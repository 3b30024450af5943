//! Passive visco-elastic joints: a joint with no motor whose torque is `τ = −k q − b q̇`
//! [Romualdi 2022, eq. (9.1.1)], e.g. the flexible hips of `models/stride_humanoid_flex.urdf`.
//!
//! The simulator makes such a joint a position servo towards `q = 0`, `q̇ = 0` with gains `k`, `b`, no
//! feed-forward and no effort bound, and discards every command the controllers send to it: the servo law
//! is then exactly the spring-damper, and the implicit integrator treats it as stiffly as a servo.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use stride_model::Model;

use crate::actuator::Actuator;
use crate::config::ActuationMode;
use crate::error::SimError;

/// One passive joint of `[sim.passive_joints.<joint>]`.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `stiffness` | N·m/rad (N/m) | – (required) | `k` of `τ = −k q − b q̇`, > 0 |
/// | `damping` | N·m·s/rad (N·s/m) | `2√k` (the thesis's choice, value of `k` in SI units) | `b`, ≥ 0 |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassiveJointConfig {
    /// Stiffness `k`, N·m/rad.
    pub stiffness: f64,
    /// Damping `b`, N·m·s/rad; `None` = `2√k` [Romualdi 2022, §9.4].
    #[serde(default)]
    pub damping: Option<f64>,
}

impl PassiveJointConfig {
    /// The spring `k` with the thesis's damping `b = 2√k` (SI values).
    pub fn with_default_damping(stiffness: f64) -> Self {
        Self {
            stiffness,
            damping: None,
        }
    }

    /// The damping `b` in use, N·m·s/rad: the configured one or `2√k`.
    pub fn damping(&self) -> f64 {
        self.damping.unwrap_or_else(|| 2.0 * self.stiffness.sqrt())
    }

    /// The passive torque `−k q − b q̇` at deflection `q` (rad) and rate `q̇` (rad/s), N·m.
    pub fn torque(&self, position: f64, velocity: f64) -> f64 {
        -self.stiffness * position - self.damping() * velocity
    }

    /// Checks `k > 0` and `b ≥ 0`, both finite; `parameter` names the table in errors.
    pub(crate) fn validate(&self, parameter: &str) -> Result<(), SimError> {
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(SimError::InvalidConfig {
                parameter: format!("{parameter}.stiffness"),
                message: format!("{}: must be finite and > 0", self.stiffness),
            });
        }
        let b = self.damping();
        if !(b.is_finite() && b >= 0.0) {
            return Err(SimError::InvalidConfig {
                parameter: format!("{parameter}.damping"),
                message: format!("{b}: must be finite and ≥ 0"),
            });
        }
        Ok(())
    }
}

/// The model indices of the passive joints, with the actuators in `actuators` (model order) replaced by
/// their spring-dampers. Errors name the joint the model does not have.
pub(crate) fn install_passive_joints(
    model: &Model,
    passive: &BTreeMap<String, PassiveJointConfig>,
    actuators: &mut [Actuator],
) -> Result<Vec<usize>, SimError> {
    let mut indices = Vec::with_capacity(passive.len());
    for (name, p) in passive {
        let parameter = format!("passive_joints.{name}");
        p.validate(&parameter)?;
        let index = model
            .joint_index(name)
            .ok_or_else(|| SimError::UnknownJoint {
                parameter: parameter.clone(),
                joint: name.clone(),
            })?;
        actuators[index] = Actuator::spring_damper(p.stiffness, p.damping());
        indices.push(index);
    }
    Ok(indices)
}

impl Actuator {
    /// A passive joint: a position "servo" to zero with `kp = k`, `kd = b`, no bound, no friction.
    pub(crate) fn spring_damper(stiffness: f64, damping: f64) -> Self {
        Self {
            mode: ActuationMode::Position,
            kp: stiffness,
            kd: damping,
            limit: f64::INFINITY,
            damping: 0.0,
            armature: 0.0,
            coulomb_friction: 0.0,
            torque_bandwidth: 0.0,
        }
    }
}
