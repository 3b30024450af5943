//! The state of passive visco-elastic joints from their estimated torque [Romualdi 2022, §9.3].
//!
//! A flexible joint (no encoder, no motor) obeys `τ^f = −k s^f − d ṡ^f` [Romualdi 2022, eq. (9.1.1)]. Its
//! torque `τ^f` is what the inverse dynamics of the chain below it gives with the measured contact wrench
//! ([`crate::Estimator`]'s step 8, the thesis's Algorithm 2 with β = 1, eq. (9.3.9)); the observer turns it
//! into the deflection and its rate by backward Euler [Romualdi 2022, eq. (9.1.2)]:
//!
//! `s^f[k] = (d s^f[k−1] − τ^f[k] dt) / (k dt + d)`,  `ṡ^f[k] = (s^f[k] − s^f[k−1]) / dt`.
//!
//! The kinematics the torque is computed with use the previous tick's estimate (the thesis's "flexible-joint
//! estimates at t − dt"): [`FlexibleJointObserver::write_state`] puts it into the state before the inverse
//! dynamics of the next tick.

use nalgebra::DVector;
use stride_model::{Model, RobotState};

use crate::error::{EstimatorError, Result};

/// One flexible joint: its model index and spring-damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlexibleJoint {
    /// Index of the joint in model order.
    pub joint: usize,
    /// Stiffness `k`, N·m/rad (> 0).
    pub stiffness: f64,
    /// Damping `d`, N·m·s/rad (≥ 0).
    pub damping: f64,
}

/// Deflection and rate of each flexible joint from its estimated torque, by the backward-Euler law
/// [Romualdi 2022, §9.3, eq. (9.1.2)].
/// Allocation-free after [`FlexibleJointObserver::new`].
#[derive(Debug, Clone)]
pub struct FlexibleJointObserver {
    joints: Vec<FlexibleJoint>,
    /// Period `dt`, s.
    period: f64,
    /// `s^f`, rad, per entry of `joints`.
    positions: Vec<f64>,
    /// `ṡ^f`, rad/s, per entry of `joints`.
    velocities: Vec<f64>,
}

impl FlexibleJointObserver {
    /// The observer of `joints` (name, `k` N·m/rad, `d` N·m·s/rad) of `model`, ticking every `period`
    /// seconds, starting undeflected and at rest.
    ///
    /// # Errors
    /// [`EstimatorError::UnknownJoint`] for a name the model lacks, [`EstimatorError::InvalidParameter`] for
    /// `k ≤ 0`, `d < 0`, a non-finite value or a non-positive period.
    pub fn new(model: &Model, joints: &[(&str, f64, f64)], period: f64) -> Result<Self> {
        if !(period.is_finite() && period > 0.0) {
            return Err(invalid("period", period, "must be finite and > 0"));
        }
        let joints = joints
            .iter()
            .map(|&(name, stiffness, damping)| {
                let joint =
                    model
                        .joint_index(name)
                        .ok_or_else(|| EstimatorError::UnknownJoint {
                            key: "flexible_joints",
                            name: name.to_owned(),
                        })?;
                if !(stiffness.is_finite() && stiffness > 0.0) {
                    return Err(invalid("stiffness", stiffness, "must be finite and > 0"));
                }
                if !(damping.is_finite() && damping >= 0.0) {
                    return Err(invalid("damping", damping, "must be finite and ≥ 0"));
                }
                Ok(FlexibleJoint {
                    joint,
                    stiffness,
                    damping,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let n = joints.len();
        Ok(Self {
            joints,
            period,
            positions: vec![0.0; n],
            velocities: vec![0.0; n],
        })
    }

    /// The flexible joints, in the order given to [`FlexibleJointObserver::new`].
    pub fn joints(&self) -> &[FlexibleJoint] {
        &self.joints
    }

    /// One tick: `torques` are the estimated joint torques of every joint (model order, N·m), of which the
    /// flexible joints' are read; updates the deflections by [Romualdi 2022, eq. (9.1.2)].
    ///
    /// # Errors
    /// [`EstimatorError::InputSize`] when `torques` is too short for a joint index,
    /// [`EstimatorError::NonFiniteInput`] for a non-finite flexible-joint torque (nothing is changed).
    pub fn step(&mut self, torques: &DVector<f64>) -> Result<()> {
        self.step_with_inertia(torques, &[])
    }

    /// [`FlexibleJointObserver::step`] when `torques` were computed with the flexible joints' own
    /// accelerations taken as zero and `inertias[i]` (kg·m², the mass-matrix diagonal entry `M_jj` of
    /// flexible joint `i`; missing entries count as 0) is the torque per unit of that acceleration: the
    /// torque `τ + M_jj s̈` with `s̈ = (ṡ[k] − ṡ[k−1]) / dt` is solved with (9.1.2) for `s[k]` at once,
    ///
    /// `s[k] (k + d/dt + M/dt²) = d s[k−1]/dt + M (s[k−1]/dt + ṡ[k−1])/dt − τ`,
    ///
    /// which stays stable where differencing the estimate into the next torque would not (`d dt < M`).
    pub fn step_with_inertia(&mut self, torques: &DVector<f64>, inertias: &[f64]) -> Result<()> {
        for f in &self.joints {
            let tau = *torques.get(f.joint).ok_or(EstimatorError::InputSize {
                name: "torques",
                expected: f.joint + 1,
                actual: torques.len(),
            })?;
            if !tau.is_finite() {
                return Err(EstimatorError::NonFiniteInput { name: "torques" });
            }
        }
        if !inertias.iter().all(|m| m.is_finite() && *m >= 0.0) {
            return Err(EstimatorError::NonFiniteInput { name: "inertias" });
        }
        let dt = self.period;
        for (i, f) in self.joints.iter().enumerate() {
            let (s1, v1) = (self.positions[i], self.velocities[i]);
            let m = inertias.get(i).copied().unwrap_or(0.0);
            let tau = torques[f.joint];
            let lhs = f.stiffness + f.damping / dt + m / (dt * dt);
            let s = (f.damping * s1 / dt + m * (s1 / dt + v1) / dt - tau) / lhs;
            self.positions[i] = s;
            self.velocities[i] = (s - s1) / dt;
        }
        Ok(())
    }

    /// The estimated deflections `s^f` (rad), in the order of [`FlexibleJointObserver::joints`].
    pub fn positions(&self) -> &[f64] {
        &self.positions
    }

    /// The estimated rates `ṡ^f` (rad/s), in the order of [`FlexibleJointObserver::joints`].
    pub fn velocities(&self) -> &[f64] {
        &self.velocities
    }

    /// Writes the estimated deflections and rates into `state`'s joint positions and velocities.
    pub fn write_state(&self, state: &mut RobotState) {
        for (i, f) in self.joints.iter().enumerate() {
            state.joint_positions[f.joint] = self.positions[i];
            state.joint_velocities[f.joint] = self.velocities[i];
        }
    }

    /// Back to undeflected and at rest.
    pub fn reset(&mut self) {
        self.positions.fill(0.0);
        self.velocities.fill(0.0);
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> EstimatorError {
    EstimatorError::InvalidParameter {
        name,
        value,
        reason,
    }
}
