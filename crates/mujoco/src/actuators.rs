//! The joint actuators of the scenario (`[sim.actuation]`), resolved per joint, and the control value each
//! MuJoCo actuator receives so that its force equals stride-sim's servo law.

use stride_model::Model;
use stride_sim::{ActuationConfig, ActuationMode};

use crate::MujocoError;

/// One joint's actuator with every parameter resolved (default, overrides, the URDF's effort limit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Servo {
    /// Servo mode.
    pub mode: ActuationMode,
    /// Position gain \[N·m/rad\].
    pub kp: f64,
    /// Velocity gain \[N·m·s/rad\].
    pub kd: f64,
    /// Motor torque bound \[N·m\]; infinite when the joint has none.
    pub limit: f64,
    /// Passive viscous damping \[N·m·s/rad\] (MuJoCo joint `damping`).
    pub damping: f64,
    /// Reflected rotor inertia \[kg·m²\] (MuJoCo joint `armature`).
    pub armature: f64,
    /// Coulomb friction \[N·m\] (MuJoCo joint `frictionloss`).
    pub coulomb_friction: f64,
    /// Torque-mode lag bandwidth \[Hz\] (MuJoCo `filterexact` actuator dynamics); 0 = ideal.
    pub torque_bandwidth: f64,
}

impl Servo {
    /// The control value of the MuJoCo actuator for the command `(q_ref, q̇_ref, τ_ff)`.
    ///
    /// MuJoCo's position actuator applies `kp (u − q) − kv q̇` (`kv = kd`), its velocity actuator
    /// `kv (u − q̇)`, its motor `u`, each clamped at `forcerange` [MuJoCo 3.17 XML reference, "actuator"].
    /// With `u = q_ref + (kd q̇_ref + τ_ff)/kp` (position) or `u = q̇_ref + τ_ff/kd` (velocity) the force is
    /// stride-sim's `kp (q_ref − q) + kd (q̇_ref − q̇) + τ_ff`, with the damping evaluated implicitly by
    /// `implicitfast`, and saturated as a whole at the effort limit on the force the step applies
    /// (`crate::limits`).
    pub fn control(&self, q_ref: f64, qd_ref: f64, tau_ff: f64) -> f64 {
        match self.mode {
            ActuationMode::Position => q_ref + (self.kd * qd_ref + tau_ff) / self.kp,
            ActuationMode::Velocity => qd_ref + tau_ff / self.kd,
            ActuationMode::Torque => tau_ff,
        }
    }
}

/// Every joint's [`Servo`] in model order: `config.default`, then the overrides in order.
pub fn resolve(model: &Model, config: &ActuationConfig) -> Result<Vec<Servo>, MujocoError> {
    let d = &config.default;
    let mut servos: Vec<Servo> = model
        .joints()
        .iter()
        .map(|j| Servo {
            mode: d.mode,
            kp: d.kp,
            kd: d.kd,
            limit: d.effort_limit.unwrap_or(j.effort_limit),
            damping: d.damping,
            armature: d.armature,
            coulomb_friction: d.coulomb_friction,
            torque_bandwidth: d.torque_bandwidth,
        })
        .collect();
    for o in &config.joints {
        let i = model
            .joint_index(&o.name)
            .ok_or_else(|| MujocoError::InvalidConfig {
                parameter: "actuation.joints.name".into(),
                value: o.name.clone(),
                reason: "the model has no such joint".into(),
            })?;
        let s = &mut servos[i];
        s.mode = o.mode.unwrap_or(s.mode);
        s.kp = o.kp.unwrap_or(s.kp);
        s.kd = o.kd.unwrap_or(s.kd);
        s.limit = o.effort_limit.unwrap_or(s.limit);
        s.damping = o.damping.unwrap_or(s.damping);
        s.armature = o.armature.unwrap_or(s.armature);
        s.coulomb_friction = o.coulomb_friction.unwrap_or(s.coulomb_friction);
        s.torque_bandwidth = o.torque_bandwidth.unwrap_or(s.torque_bandwidth);
    }
    for (s, j) in servos.iter().zip(model.joints()) {
        check(s, &j.name)?;
    }
    Ok(servos)
}

/// The gains the MuJoCo actuator divides by must be positive (the rest is stride-sim's validation).
fn check(s: &Servo, joint: &str) -> Result<(), MujocoError> {
    let (name, gain) = match s.mode {
        ActuationMode::Position => ("kp", s.kp),
        ActuationMode::Velocity => ("kd", s.kd),
        ActuationMode::Torque => return Ok(()),
    };
    if gain > 0.0 && gain.is_finite() {
        Ok(())
    } else {
        Err(MujocoError::InvalidConfig {
            parameter: format!("actuation.{name} of joint {joint}"),
            value: gain.to_string(),
            reason: "expected > 0 for this servo mode on the MuJoCo plant".into(),
        })
    }
}
