//! The checks of a step's inputs (sizes, finiteness, the effort-limit policy) and of its result (divergence).

use super::SimRobot;
use crate::config::{ActuationMode, EffortLimitPolicy};
use crate::error::SimError;
use crate::io::SimInput;

impl SimRobot {
    /// Rejects commands of the wrong size, non-finite commands a joint's mode uses, and, with
    /// `effort_limit_policy = "error"`, a feed-forward torque beyond a joint's effort limit.
    pub(super) fn check_input(&self, input: &SimInput) -> Result<(), SimError> {
        let n = self.model.dof();
        for (what, len) in [
            ("joint position commands", input.joint_positions.len()),
            ("joint velocity commands", input.joint_velocities.len()),
            ("joint torque commands", input.joint_torques.len()),
        ] {
            if len != n {
                return Err(SimError::Dimension {
                    what,
                    expected: n,
                    actual: len,
                });
            }
        }
        for (j, a) in self.actuators.iter().enumerate() {
            let name = || self.model.joints()[j].name.clone();
            let (qd, vd, tau) = (
                input.joint_positions[j],
                input.joint_velocities[j],
                input.joint_torques[j],
            );
            if a.mode == ActuationMode::Position && !qd.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "position",
                    joint: name(),
                    value: qd,
                });
            }
            if a.mode != ActuationMode::Torque && !vd.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "velocity",
                    joint: name(),
                    value: vd,
                });
            }
            if !tau.is_finite() {
                return Err(SimError::NonFiniteCommand {
                    what: "torque",
                    joint: name(),
                    value: tau,
                });
            }
            if self.config.actuation.effort_limit_policy == EffortLimitPolicy::Error
                && tau.abs() > a.limit
            {
                return Err(SimError::EffortLimit {
                    joint: name(),
                    torque: tau,
                    limit: a.limit,
                });
            }
        }
        Ok(())
    }

    /// Checks the new state; names the first offending joint, base component or contact point.
    pub(super) fn check_divergence(&self) -> Result<(), SimError> {
        let time = self.time_ns as f64 * 1e-9;
        let s = &self.next_state;
        let limits = &self.config.safety;
        for (i, v) in s.base_velocity.iter().enumerate() {
            if !v.is_finite() || v.abs() > limits.max_base_velocity {
                const NAMES: [&str; 6] = ["vx", "vy", "vz", "wx", "wy", "wz"];
                return Err(SimError::Diverged {
                    time,
                    what: "base velocity",
                    name: NAMES[i].to_string(),
                    value: *v,
                    bound: limits.max_base_velocity,
                });
            }
        }
        for (j, v) in s.joint_velocities.iter().enumerate() {
            if !v.is_finite() || v.abs() > limits.max_joint_velocity {
                return Err(SimError::Diverged {
                    time,
                    what: "joint velocity",
                    name: self.model.joints()[j].name.clone(),
                    value: *v,
                    bound: limits.max_joint_velocity,
                });
            }
        }
        for (j, v) in s.joint_positions.iter().enumerate() {
            if !v.is_finite() {
                return Err(SimError::Diverged {
                    time,
                    what: "joint position",
                    name: self.model.joints()[j].name.clone(),
                    value: *v,
                    bound: f64::NAN,
                });
            }
        }
        let pose_ok = s.base_pose.translation.vector.iter().all(|x| x.is_finite())
            && s.base_pose.rotation.coords.iter().all(|x| x.is_finite());
        if !pose_ok {
            return Err(SimError::Diverged {
                time,
                what: "base pose",
                name: "base".into(),
                value: f64::NAN,
                bound: f64::NAN,
            });
        }
        self.check_contact_points(time)
    }

    /// A contact point deeper than `safety.max_penetration`, or with a non-finite force, fails the step.
    fn check_contact_points(&self, time: f64) -> Result<(), SimError> {
        let limits = &self.config.safety;
        for (i, p) in self.points.iter().enumerate() {
            if p.penetration.is_nan()
                || p.penetration > limits.max_penetration
                || !p.force.iter().all(|x| x.is_finite())
            {
                let s = &self.surfaces[p.surface];
                let name = format!(
                    "{}[{}]",
                    self.config.contact.surfaces[p.surface].name,
                    i - s.first_point
                );
                return Err(SimError::Diverged {
                    time,
                    what: "contact penetration",
                    name,
                    value: p.penetration,
                    bound: limits.max_penetration,
                });
            }
        }
        Ok(())
    }
}
