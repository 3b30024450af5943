//! The servos' effort limits decided on the force the step applies, as stride-sim decides them.
//!
//! MuJoCo clamps an actuator's force at `forcerange` on its value at the start of the step, and
//! `implicitfast` leaves a clamped actuator's velocity derivative out of its implicit damping (measured:
//! `tests/mujoco.rs`, a clamped servo on a light link): the damping `−kd q̇` of a clamped position servo
//! becomes explicit. A clamped torque of ±L changes the joint velocity by about
//! `L dt / I` per step, the damping term by `kd L dt / I`; on a light link with `kd dt / I > 2` (kd
//! 200 N·m·s/rad, dt 0.5 ms, the iCub knee's ≈ 0.03 kg·m² effective inertia with its armature: ≈ 3) that is
//! more than the `2 L` between the limits, and the clamped torque flips between +L and −L at every step for as long as
//! the servo is saturated. Nothing physical does that: it is the start-of-step clamp of an explicit step.
//!
//! stride-sim decides a saturation on the end-of-step servo torque and solves the step again with that
//! torque fixed at the limit (its integrator's active set). [`MujocoRobot::step_with_limits`] does the same
//! with MuJoCo: the position and velocity servos step unclamped (their damping implicit); a servo whose
//! applied force `kp (u − q) − kd q̇⁺` (velocity servo: `kd (u − q̇⁺)`) exceeds its limit is pinned at the
//! limit (clamped with a control beyond it, so MuJoCo applies exactly ±L) and the step is taken again from
//! its start; a pinned servo stays pinned for the step, so at most one pass per servo is added. Torque
//! motors keep MuJoCo's clamp: their force does not depend on the state.

use stride_sim::ActuationMode;

use crate::robot::MujocoRobot;
use crate::{MujocoError, ServoSaturation};

/// Per joint, the state of its effort limit during one step (allocated once, at construction).
pub(crate) struct Limits {
    /// The controls of the step as the command gives them.
    controls: Vec<f64>,
    /// 0: free; ±1: pinned at ±limit for this step.
    pinned: Vec<f64>,
    /// The force the step applied \[N·m\]: `kp (u − q) − kd q̇⁺` (free servos), ±limit (pinned), MuJoCo's
    /// actuator force (torque motors).
    pub(crate) applied: Vec<f64>,
}

impl Limits {
    /// Buffers for `n` joints.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            controls: vec![0.0; n],
            pinned: vec![0.0; n],
            applied: vec![0.0; n],
        }
    }

    /// Whether joint `j` was pinned at its limit in the last step.
    pub(crate) fn is_pinned(&self, j: usize) -> bool {
        self.pinned[j] != 0.0
    }
}

impl MujocoRobot {
    /// One MuJoCo step with the controls in `data.ctrl`, the servos saturated on the force the step applies
    /// (module documentation). Expects the start-of-step state saved (`save`); leaves `limits.applied` set.
    ///
    /// # Errors
    /// A MuJoCo warning or a non-finite state in any pass (the caller restores the saved state).
    pub(crate) fn step_with_limits(&mut self) -> Result<(), MujocoError> {
        if self.servo_saturation == ServoSaturation::StartOfStep {
            self.data.step();
            self.check_step()?;
            self.limits
                .applied
                .copy_from_slice(self.data.actuator_force());
            return Ok(());
        }
        self.limits.controls.copy_from_slice(self.data.ctrl());
        self.limits.pinned.fill(0.0);
        for _ in 0..=self.servos.len() {
            self.set_force_limits();
            self.data.step();
            self.check_step()?;
            if !self.saturate_servos() {
                return Ok(());
            }
            self.rewind();
        }
        Ok(())
    }

    /// Whether the limit of joint `j` is decided here (a position or velocity servo with a finite limit).
    fn decided_here(&self, j: usize) -> bool {
        let s = &self.servos[j];
        s.mode != ActuationMode::Torque && s.limit.is_finite()
    }

    /// `forcelimited` off for the free servos, on for the pinned ones, whose control is set beyond the limit
    /// (a start-of-step force of twice the limit, which MuJoCo clamps to it).
    fn set_force_limits(&mut self) {
        for j in 0..self.servos.len() {
            if !self.decided_here(j) {
                continue;
            }
            let sign = self.limits.pinned[j];
            // SAFETY: only the per-actuator flag `forcelimited` changes, a value MuJoCo reads at every step;
            // no size, address or compiled quantity of the model depends on it.
            unsafe { self.data.model_mut() }.actuator_forcelimited_mut()[j] = sign != 0.0;
            let s = self.servos[j];
            let (q, qd) = (
                self.scratch.qpos[self.joint_qpos[j]],
                self.scratch.qvel[self.joint_dof[j]],
            );
            self.data.ctrl_mut()[j] = if sign == 0.0 {
                self.limits.controls[j]
            } else {
                match s.mode {
                    ActuationMode::Position => q + (s.kd * qd + 2.0 * sign * s.limit) / s.kp,
                    _ => qd + 2.0 * sign * s.limit / s.kd,
                }
            };
        }
    }

    /// The force each servo applied in the step just taken; pins the free servos beyond their limit.
    /// Returns whether one was pinned (then the step is taken again).
    fn saturate_servos(&mut self) -> bool {
        let mut changed = false;
        for j in 0..self.servos.len() {
            let s = self.servos[j];
            if !self.decided_here(j) {
                self.limits.applied[j] = self.data.actuator_force()[j];
                continue;
            }
            if self.limits.pinned[j] != 0.0 {
                self.limits.applied[j] = self.limits.pinned[j] * s.limit;
                continue;
            }
            let u = self.limits.controls[j];
            let qd_end = self.data.qvel()[self.joint_dof[j]];
            let force = match s.mode {
                ActuationMode::Position => {
                    s.kp * (u - self.scratch.qpos[self.joint_qpos[j]]) - s.kd * qd_end
                }
                _ => s.kd * (u - qd_end),
            };
            self.limits.applied[j] = force;
            if force.abs() > s.limit {
                self.limits.pinned[j] = force.signum();
                changed = true;
            }
        }
        changed
    }
}
