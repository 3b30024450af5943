//! Passive visco-elastic joints: a joint with no motor whose torque is `τ = −k q − b q̇`
//! [Romualdi 2022, eq. (9.1.1)], e.g. the flexible hips of `models/stride_humanoid_flex.urdf`.
//!
//! The simulator makes such a joint a position servo towards `q = 0`, `q̇ = 0` with gains `k`, `b`, no
//! feed-forward and no effort bound, and discards every command the controllers send to it: the servo law
//! is then exactly the spring-damper, and the implicit integrator treats it as stiffly as a servo.

use serde::{Deserialize, Serialize};
use stride_model::Model;

use crate::actuator::Actuator;
use crate::config::ActuationMode;
use crate::error::SimError;

/// One entry of `[[sim.passive_joints]]`: joints that share one spring-damper law.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `joints` | – | – (required) | joint names (each in one entry at most) |
/// | `stiffness` | N·m/rad (N/m) | – (required) | `k` of `τ = −k q − b q̇`, > 0 |
/// | `damping` | N·m·s/rad (N·s/m) | `2√k` (the thesis's choice, value of `k` in SI units) | `b`, ≥ 0 |
/// | `encoder` | – | `false` | the joints have encoders; without (the thesis's case) their encoder readings are 0 and the deflection must be estimated ([Romualdi 2022, §9.3]) |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassiveJointConfig {
    /// The joints with this law, by name.
    pub joints: Vec<String>,
    /// Stiffness `k`, N·m/rad.
    pub stiffness: f64,
    /// Damping `b`, N·m·s/rad; `None` = `2√k` [Romualdi 2022, §9.4].
    #[serde(default)]
    pub damping: Option<f64>,
    /// Whether the joints have encoders (default `false`: their readings are 0, the deflection unmeasured).
    #[serde(default)]
    pub encoder: bool,
}

impl PassiveJointConfig {
    /// The joints `joints` with the spring `k` and the thesis's damping `b = 2√k` (SI values).
    pub fn with_default_damping(joints: &[&str], stiffness: f64) -> Self {
        Self {
            joints: joints.iter().map(|j| j.to_string()).collect(),
            stiffness,
            damping: None,
            encoder: false,
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

    /// Checks `k > 0` and `b ≥ 0`, both finite, and a non-empty joint list; `parameter` names the entry.
    pub(crate) fn validate(&self, parameter: &str) -> Result<(), SimError> {
        if self.joints.is_empty() {
            return Err(SimError::InvalidConfig {
                parameter: format!("{parameter}.joints"),
                message: "empty: expected at least one joint name".into(),
            });
        }
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

/// The model indices of the passive joints without encoders in `passive`.
pub(crate) fn unmeasured_joints(model: &Model, passive: &[PassiveJointConfig]) -> Vec<usize> {
    passive
        .iter()
        .filter(|p| !p.encoder)
        .flat_map(|p| p.joints.iter().filter_map(|j| model.joint_index(j)))
        .collect()
}

/// The model indices of the passive joints, with the actuators in `actuators` (model order) replaced by
/// their spring-dampers. Errors name the joint the model does not have, or one listed twice.
pub(crate) fn install_passive_joints(
    model: &Model,
    passive: &[PassiveJointConfig],
    actuators: &mut [Actuator],
) -> Result<Vec<usize>, SimError> {
    let mut indices = Vec::new();
    for (i, p) in passive.iter().enumerate() {
        let parameter = format!("passive_joints[{i}]");
        p.validate(&parameter)?;
        for name in &p.joints {
            let index = model
                .joint_index(name)
                .ok_or_else(|| SimError::UnknownJoint {
                    parameter: format!("{parameter}.joints"),
                    joint: name.clone(),
                })?;
            if indices.contains(&index) {
                return Err(SimError::InvalidConfig {
                    parameter: format!("{parameter}.joints"),
                    message: format!(
                        "`{name}` is already passive; expected each joint in one entry"
                    ),
                });
            }
            actuators[index] = Actuator::spring_damper(p.stiffness, p.damping());
            indices.push(index);
        }
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
