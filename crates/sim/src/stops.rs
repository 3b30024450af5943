//! Joint end stops: a joint past one of its URDF position limits meets a stiff one-sided spring-damper, the
//! mechanical stop of a real joint. Off by default (the URDF limits are then only reported by the model).
//!
//! A joint whose position predicted at the end of the step, `q + dt q̇`, lies beyond its limit `q_l` gets the
//! torque `τ = k (q_l − q⁺) − b q̇⁺` with `q⁺ = q + dt q̇⁺`, pushing it back inside. The damper acts only
//! while the joint moves further into the stop (a leaving joint is not held back). The implicit integrator
//! takes the stop as it takes a servo, linearised at the end of the step: `dt b + dt² k` on the joint's
//! diagonal and `k (q_l − q − dt q̇) − b q̇` in the right-hand side, so a stiff stop stays stable at the
//! simulator's rate. Implicit integrator only: explicitly, `k` = 10⁴ N·m/rad and `b` = 100 N·m·s/rad on a
//! forearm of 10⁻³ kg m² would need steps under `2 I / b` = 20 µs.

use serde::{Deserialize, Serialize};
use stride_model::Model;

use crate::error::SimError;

/// `[sim.joint_stops]`: the joints' mechanical end stops at their URDF position limits.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `enabled` | – | `false` | stops on every joint with finite limits |
/// | `stiffness` | N·m/rad (N/m) | 10 000 | `k` of the stop's spring, > 0 |
/// | `damping` | N·m·s/rad (N·s/m) | 100 | `b` of the stop's damper, ≥ 0 |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JointStopsConfig {
    /// Stop every joint at its URDF position limits (default `false`: the limits are not enforced).
    pub enabled: bool,
    /// Stiffness `k` of the stop (N/m for a prismatic joint; the position servos' order), N·m/rad.
    pub stiffness: f64,
    /// Damping `b` of the stop while the joint moves into it (N·s/m for a prismatic joint), N·m·s/rad.
    pub damping: f64,
}

impl Default for JointStopsConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            stiffness: 1.0e4,
            damping: 100.0,
        }
    }
}

impl JointStopsConfig {
    /// Checks `k > 0` and `b ≥ 0`, both finite.
    pub(crate) fn validate(&self) -> Result<(), SimError> {
        let bad = |parameter: &str, message: &str| SimError::InvalidConfig {
            parameter: parameter.into(),
            message: message.into(),
        };
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(bad("joint_stops.stiffness", "must be finite and > 0"));
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(bad("joint_stops.damping", "must be finite and ≥ 0"));
        }
        Ok(())
    }
}

/// The stops of a model's joints: their limits, and the law.
#[derive(Clone, Debug)]
pub(crate) struct JointStops {
    /// `(lower, upper)` per joint in model order; infinite bounds never stop.
    limits: Vec<(f64, f64)>,
    stiffness: f64,
    damping: f64,
    enabled: bool,
}

impl JointStops {
    /// The stops of `model`'s joints under `config`.
    pub(crate) fn new(model: &Model, config: &JointStopsConfig) -> Self {
        Self {
            limits: model.joints().iter().map(|j| (j.lower, j.upper)).collect(),
            stiffness: config.stiffness,
            damping: config.damping,
            enabled: config.enabled,
        }
    }

    /// The stop joint `j` meets in a step of `dt` from position `q` at rate `qd`: `(k, b, q_l)` (the damper
    /// `b` zero when the joint leaves the stop), or `None` when its predicted position `q + dt qd` is
    /// within its limits.
    pub(crate) fn active(&self, j: usize, q: f64, qd: f64, dt: f64) -> Option<(f64, f64, f64)> {
        if !self.enabled {
            return None;
        }
        let (lower, upper) = self.limits[j];
        let predicted = q + dt * qd;
        let (limit, inward) = if predicted > upper {
            (upper, qd > 0.0)
        } else if predicted < lower {
            (lower, qd < 0.0)
        } else {
            return None;
        };
        let b = if inward { self.damping } else { 0.0 };
        Some((self.stiffness, b, limit))
    }
}
