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
    /// Coulomb friction torque, N·m (N).
    pub(crate) coulomb_friction: f64,
    /// Torque-mode tracking bandwidth, Hz (0 = ideal).
    pub(crate) torque_bandwidth: f64,
}

/// Speed below which the implicit Coulomb law holds a sticking joint, rad/s: the stick phase is a viscous
/// damper `b = τ_c / STICK_SPEED` evaluated at the end of the step, so a joint loaded below `τ_c` creeps at
/// most at this speed (in practice far less: the servo and gravity torques are balanced before).
pub(crate) const STICK_SPEED: f64 = 1e-7;

/// Speed at which the explicit scheme's regularised Coulomb law `τ = −τ_c sat(q̇ / v_s)` reaches `τ_c`, rad/s.
pub(crate) const EXPLICIT_FRICTION_SPEED: f64 = 0.05;

/// The Coulomb friction phase of a joint during an implicit step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Friction {
    /// Held: friction is the damper `−(τ_c / STICK_SPEED) q̇⁺`, valid while it stays within `±τ_c`.
    Stick,
    /// Sliding: friction is this constant torque (`±τ_c`, opposing the motion), N·m.
    Slide(f64),
}

impl Friction {
    /// The phase after a solve that gave the end-of-step velocity `velocity` (rad/s) to a joint with Coulomb
    /// friction `tau_c`: a sticking joint whose holding torque exceeds `τ_c` slides against it; a sliding joint
    /// whose velocity crossed zero (friction would now drive it) sticks. `None` when the phase holds.
    pub(crate) fn switch(self, tau_c: f64, velocity: f64) -> Option<Friction> {
        match self {
            Friction::Stick => {
                let holding = -tau_c / STICK_SPEED * velocity;
                (holding.abs() > tau_c).then(|| Friction::Slide(tau_c.copysign(holding)))
            }
            Friction::Slide(t) => (t * velocity > 0.0).then_some(Friction::Stick),
        }
    }

    /// `(damping, torque)` the phase adds to the joint: the stick damper, or the constant sliding torque.
    pub(crate) fn terms(self, tau_c: f64) -> (f64, f64) {
        match self {
            Friction::Stick if tau_c > 0.0 => (tau_c / STICK_SPEED, 0.0),
            Friction::Stick => (0.0, 0.0),
            Friction::Slide(t) => (0.0, t),
        }
    }
}

/// The explicit scheme's regularised Coulomb friction torque `−τ_c sat(q̇ / v_s)`, N·m.
pub(crate) fn explicit_friction(tau_c: f64, velocity: f64) -> f64 {
    -tau_c * (velocity / EXPLICIT_FRICTION_SPEED).clamp(-1.0, 1.0)
}

/// Gain `β = 1 − exp(−2π f dt)` of the torque-tracking lag `τ ← τ + β (τ_cmd − τ)` with bandwidth `f` Hz at the
/// period `dt` s: the exact discretisation of `τ̇ = 2π f (τ_cmd − τ)`, so a step reaches 63 % after
/// `1/(2π f)`. 1 (ideal) when `f == 0`.
pub(crate) fn torque_lag_gain(dt: f64, bandwidth: f64) -> f64 {
    if bandwidth > 0.0 {
        1.0 - (-std::f64::consts::TAU * bandwidth * dt).exp()
    } else {
        1.0
    }
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
            coulomb_friction: config.coulomb_friction,
            torque_bandwidth: config.torque_bandwidth,
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
        if let Some(v) = o.coulomb_friction {
            self.coulomb_friction = v;
        }
        if let Some(v) = o.torque_bandwidth {
            self.torque_bandwidth = v;
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
