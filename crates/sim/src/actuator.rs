//! Joint actuators: the resolved servo of each joint and its motor torque law.

use stride_model::Model;

use crate::config::{ActuationConfig, ActuationMode, JointActuatorConfig, JointActuatorOverride};
use crate::error::SimError;

/// A joint actuator with every parameter resolved (the default actuator, the overrides, the model's limit).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Actuator {
    pub(crate) mode: ActuationMode,
    /// Position gain, N·m/rad (N/m).
    pub(crate) kp: f64,
    /// Velocity gain, N·m·s/rad (N·s/m).
    pub(crate) kd: f64,
    /// Motor torque bound, N·m (N); infinite when the joint has none.
    pub(crate) limit: f64,
    /// Passive viscous damping, N·m·s/rad.
    pub(crate) damping: f64,
    /// Reflected rotor inertia, kg·m².
    pub(crate) armature: f64,
}

impl Actuator {
    /// The actuator `config` with the model's effort limit `model_limit` (used when the config sets none; a
    /// non-positive or non-finite model limit means unbounded).
    pub(crate) fn resolve(config: &JointActuatorConfig, model_limit: f64) -> Self {
        let model_limit = if model_limit.is_finite() && model_limit > 0.0 {
            model_limit
        } else {
            f64::INFINITY
        };
        Self {
            mode: config.mode,
            kp: config.kp,
            kd: config.kd,
            limit: config.effort_limit.unwrap_or(model_limit),
            damping: config.damping,
            armature: config.armature,
        }
    }

    /// Applies the fields an override sets.
    fn apply(&mut self, o: &JointActuatorOverride) {
        if let Some(m) = o.mode {
            self.mode = m;
        }
        if let Some(v) = o.kp {
            self.kp = v;
        }
        if let Some(v) = o.kd {
            self.kd = v;
        }
        if let Some(v) = o.effort_limit {
            self.limit = v;
        }
        if let Some(v) = o.damping {
            self.damping = v;
        }
        if let Some(v) = o.armature {
            self.armature = v;
        }
    }

    /// Unsaturated motor torque, N·m (N): `τ = τ_ff + kp e_q + kd e_v` in position mode, `τ_ff + kd e_v` in
    /// velocity mode, `τ_ff` in torque mode. The caller evaluates the position error `e_q` and the velocity
    /// error `e_v` where its scheme needs them (start or end of the step).
    pub(crate) fn torque(
        &self,
        feed_forward: f64,
        position_error: f64,
        velocity_error: f64,
    ) -> f64 {
        let mut t = feed_forward;
        if self.mode == ActuationMode::Position {
            t += self.kp * position_error;
        }
        if self.mode != ActuationMode::Torque {
            t += self.kd * velocity_error;
        }
        t
    }

    /// The servo gains `(kp, kd)` that act on the joint in its mode (zero where the mode ignores them).
    pub(crate) fn gains(&self) -> (f64, f64) {
        match self.mode {
            ActuationMode::Position => (self.kp, self.kd),
            ActuationMode::Velocity => (0.0, self.kd),
            ActuationMode::Torque => (0.0, 0.0),
        }
    }
}

/// The actuator of every joint of `model`, in model order: `config.default` with the model's effort limits,
/// then the per-joint overrides in order.
pub(crate) fn resolve_actuators(
    model: &Model,
    config: &ActuationConfig,
) -> Result<Vec<Actuator>, SimError> {
    let mut actuators: Vec<Actuator> = model
        .joints()
        .iter()
        .map(|j| Actuator::resolve(&config.default, j.effort_limit))
        .collect();
    for o in &config.joints {
        let index = model
            .joint_index(&o.name)
            .ok_or_else(|| SimError::UnknownJoint {
                parameter: "actuation.joints".into(),
                joint: o.name.clone(),
            })?;
        actuators[index].apply(o);
    }
    Ok(actuators)
}
